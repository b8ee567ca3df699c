//! Sums over square windows of pixels, by a summed-area table: built once per image, then any
//! window's sum in four lookups, whatever its radius. The tables are built from the values as
//! they are computed (no image-sized list of them first), and read per pixel by the callers in
//! parallel: at 1920×1080 the page faults of the film's image-sized temporaries were two fifths
//! of its combination.

/// The summed-area table of a K-channel image (row-major, `width` wide; a missing value counts
/// as nothing).
pub(super) struct Table<const K: usize> {
    width: usize,
    height: usize,
    /// (width + 1) × (height + 1) prefix sums, the first row and column zero.
    sums: Vec<[f64; K]>,
}

impl<const K: usize> Table<K> {
    /// The table of `values`, a `width`-wide image.
    pub fn new(width: usize, values: &[Option<[f64; K]>]) -> Table<K> {
        Table::from_fn(width, values.len(), |i| values[i])
    }

    /// The table of a `width`-wide image of `len` pixels whose pixel i is `value(i)`.
    pub fn from_fn(width: usize, len: usize, value: impl Fn(usize) -> Option<[f64; K]>) -> Table<K> {
        let height = len.checked_div(width).unwrap_or(0);
        let stride = width + 1;
        let mut sums = vec![[0.0f64; K]; stride * (height + 1)];
        for y in 0..height {
            let mut row = [0.0f64; K];
            for x in 0..width {
                if let Some(v) = &value(y * width + x) {
                    for k in 0..K {
                        row[k] += v[k];
                    }
                }
                let above = sums[y * stride + x + 1];
                sums[(y + 1) * stride + x + 1] = std::array::from_fn(|k| above[k] + row[k]);
            }
        }
        Table { width, height, sums }
    }

    /// Σ over the (2r + 1)² window around pixel `i`, clipped to the image.
    #[inline]
    pub fn window(&self, i: usize, r: usize) -> [f64; K] {
        let (x, y) = (i % self.width, i / self.width);
        let (x0, x1) = (x.saturating_sub(r), (x + r + 1).min(self.width));
        let (y0, y1) = (y.saturating_sub(r), (y + r + 1).min(self.height));
        let stride = self.width + 1;
        let s = &self.sums;
        std::array::from_fn(|k| {
            s[y1 * stride + x1][k] - s[y0 * stride + x1][k] - s[y1 * stride + x0][k] + s[y0 * stride + x0][k]
        })
    }
}

/// The means over rings of pixels of one image: each pixel's (2r + 1)² window without the
/// pixel itself, over the pixels that have a value.
pub(super) struct Rings<const K: usize> {
    values: Table<K>,
    counts: Table<1>,
}

impl<const K: usize> Rings<K> {
    /// The rings of `values`, a `width`-wide image.
    pub fn new(width: usize, values: &[Option<[f64; K]>]) -> Rings<K> {
        let counts = Table::from_fn(width, values.len(), |i| values[i].map(|_| [1.0]));
        Rings { values: Table::new(width, values), counts }
    }

    /// The mean over pixel `i`'s ring of radius `r`, `own` being its own value (left out);
    /// None where no other pixel of the window has one.
    #[inline]
    pub fn mean(&self, i: usize, r: usize, own: Option<&[f64; K]>) -> Option<[f64; K]> {
        let [count] = self.counts.window(i, r);
        let sum = self.values.window(i, r);
        let (n, own) = match own {
            Some(v) => (count - 1.0, *v),
            None => (count, [0.0; K]),
        };
        (n > 0.5).then(|| std::array::from_fn(|k| (sum[k] - own[k]) / n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_are_clipped_sums() {
        // 3×2: 1 2 3 / 4 5 6, pixel 5 missing.
        let v: Vec<Option<[f64; 1]>> = vec![Some([1.0]), Some([2.0]), Some([3.0]), Some([4.0]), None, Some([6.0])];
        let t = Table::new(3, &v);
        assert_eq!(t.window(0, 1), [1.0 + 2.0 + 4.0]);
        assert_eq!(t.window(4, 1), [1.0 + 2.0 + 3.0 + 4.0 + 6.0]);
        assert_eq!(t.window(2, 0), [3.0]);
        assert!((0..6).all(|i| t.window(i, 5) == [16.0]));
    }

    #[test]
    fn a_ring_leaves_out_its_centre_and_the_missing() {
        // 3×3: the centre's ring is the mean of the other eight, one of them missing.
        let mut v: Vec<Option<[f64; 1]>> = (0..9).map(|i| Some([i as f64])).collect();
        v[0] = None;
        let rings = Rings::new(3, &v);
        assert_eq!(rings.mean(4, 1, v[4].as_ref()), Some([(1.0 + 2.0 + 3.0 + 5.0 + 6.0 + 7.0 + 8.0) / 7.0]));
        // The corner (0, 0) has no value of its own: its ring is its three neighbours.
        assert_eq!(rings.mean(0, 1, v[0].as_ref()), Some([(1.0 + 3.0 + 4.0) / 3.0]));
        // A lone pixel has no ring.
        let lone = [Some([1.0])];
        assert_eq!(Rings::new(1, &lone).mean(0, 1, lone[0].as_ref()), None);
    }
}
