//! Dense voxel grids over the unit cube, as pbrt-v4's `SampledGrid` stores `uniformgrid` and
//! `rgbgrid` data: sample (i, j, k) sits at ((i + ½)/nx, (j + ½)/ny, (k + ½)/nz), lookups
//! interpolate trilinearly and are zero outside the samples.

use glam::{IVec3, UVec3, Vec3};

/// A dense grid of `T` values, x fastest.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseGrid<T> {
    n: UVec3,
    values: Vec<T>,
}

/// Values a grid can hold: floats or RGB triples.
pub trait GridValue: Copy + Default + std::ops::Add<Output = Self> + std::ops::Mul<f32, Output = Self> {
    /// The largest component (for majorants).
    fn max_component(self) -> f32;
    /// The smallest component (for minorants).
    fn min_component(self) -> f32;
}

impl GridValue for f32 {
    fn max_component(self) -> f32 {
        self
    }
    fn min_component(self) -> f32 {
        self
    }
}

impl GridValue for Vec3 {
    fn max_component(self) -> f32 {
        self.max_element()
    }
    fn min_component(self) -> f32 {
        self.min_element()
    }
}

impl GridValue for glam::Vec4 {
    /// The largest of the first three components (an RGB with a spare lane).
    fn max_component(self) -> f32 {
        self.truncate().max_element()
    }
    /// The smallest of the first three components.
    fn min_component(self) -> f32 {
        self.truncate().min_element()
    }
}

impl<T: GridValue> DenseGrid<T> {
    /// A grid of `n.x * n.y * n.z` values (x fastest). Returns `None` on a size mismatch.
    pub fn new(n: UVec3, values: Vec<T>) -> Option<DenseGrid<T>> {
        (values.len() == (n.x as usize) * (n.y as usize) * (n.z as usize) && n.min_element() > 0)
            .then_some(DenseGrid { n, values })
    }

    /// The samples, x fastest.
    pub fn values(&self) -> &[T] {
        &self.values
    }

    /// Resolution.
    pub fn resolution(&self) -> UVec3 {
        self.n
    }

    /// Bytes of voxel data.
    pub fn memory_bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<T>()
    }

    #[inline]
    fn at(&self, x: i32, y: i32, z: i32) -> T {
        if x < 0 || y < 0 || z < 0 || x >= self.n.x as i32 || y >= self.n.y as i32 || z >= self.n.z as i32 {
            return T::default();
        }
        self.values[(z as usize * self.n.y as usize + y as usize) * self.n.x as usize + x as usize]
    }

    /// The cell of samples around `p` ∈ [0, 1]³: the index of its lowest corner and `p`'s
    /// position inside it (the trilinear weights).
    #[inline]
    pub fn cell(&self, p: Vec3) -> (IVec3, Vec3) {
        let ps = p * self.n.as_vec3() - Vec3::splat(0.5);
        let i = crate::math::floor_ivec3(ps);
        (i, ps - i.as_vec3())
    }

    /// The indices into [`DenseGrid::values`] of the eight samples of the cell whose lowest
    /// corner is `c`, x fastest, then y, then z; `None` for a cell with a corner outside the
    /// grid (those samples are zero).
    #[inline]
    pub fn corner_indices(&self, c: IVec3) -> Option<[usize; 8]> {
        let n = self.n.as_ivec3();
        if !(c.cmpge(IVec3::ZERO).all() && (c + IVec3::ONE).cmplt(n).all()) {
            return None;
        }
        let (dx, dy) = (1, n.x as usize);
        let dz = dy * n.y as usize;
        let b = (c.z as usize * n.y as usize + c.y as usize) * n.x as usize + c.x as usize;
        Some([b, b + dx, b + dy, b + dx + dy, b + dz, b + dx + dz, b + dy + dz, b + dx + dy + dz])
    }

    /// The eight samples of the cell whose lowest corner is `c` (zero outside), mapped by `f`,
    /// x fastest, then y, then z.
    #[inline]
    pub fn corners<U>(&self, c: IVec3, f: impl Fn(T) -> U) -> [U; 8] {
        // Written out rather than through `array::from_fn`, whose per-element closure the
        // compiler left uninlined here: a spectral rgbgrid lookup converts 8 corners per grid.
        if let Some(i) = self.corner_indices(c) {
            // A cell inside the grid (nearly every lookup).
            // SAFETY: as in `lookup`, the indices of a cell inside the grid are below
            // `values.len()`.
            let v = |k: usize| f(unsafe { *self.values.get_unchecked(i[k]) });
            [v(0), v(1), v(2), v(3), v(4), v(5), v(6), v(7)]
        } else {
            let at = |x: i32, y: i32, z: i32| f(self.at(c.x + x, c.y + y, c.z + z));
            [at(0, 0, 0), at(1, 0, 0), at(0, 1, 0), at(1, 1, 0), at(0, 0, 1), at(1, 0, 1), at(0, 1, 1), at(1, 1, 1)]
        }
    }

    /// Trilinear interpolation at `p` in [0, 1]³ of the samples mapped by `f` (zero outside):
    /// pbrt-v4's `SampledGrid::Lookup` with a conversion, which interpolates the converted
    /// values (e.g. sampled spectra of RGB voxels), not the raw samples.
    #[inline]
    pub fn lookup_map<U>(&self, p: Vec3, f: impl Fn(T) -> U) -> U
    where
        U: Copy + std::ops::Add<Output = U> + std::ops::Mul<f32, Output = U>,
    {
        let (c, d) = self.cell(p);
        trilinear(&self.corners(c, f), d)
    }

    /// Trilinear interpolation at `p` in [0, 1]³.
    #[inline]
    pub fn lookup(&self, p: Vec3) -> T {
        let ps = p * self.n.as_vec3() - Vec3::splat(0.5);
        let i = crate::math::floor_ivec3(ps);
        let d = ps - i.as_vec3();
        let (x, y, z) = (i.x, i.y, i.z);
        let lerp = |t: f32, a: T, b: T| a * (1.0 - t) + b * t;
        if let Some(c) = self.corner_indices(i) {
            // Inside: the eight samples without a bounds test each (the same values, the same
            // arithmetic).
            let v = |k: usize| {
                debug_assert!(c[k] < self.values.len());
                // SAFETY: `corner_indices` returns indices only for a cell whose corners all
                // lie inside the grid (0 ≤ c and c + 1 < n per axis), so each is below
                // n.x·n.y·n.z = `values.len()` (`new` checks that length). Eight bounds
                // checks per lookup were a quarter of its instructions (callgrind, graph-cloud).
                unsafe { *self.values.get_unchecked(c[k]) }
            };
            let d00 = lerp(d.x, v(0), v(1));
            let d10 = lerp(d.x, v(2), v(3));
            let d01 = lerp(d.x, v(4), v(5));
            let d11 = lerp(d.x, v(6), v(7));
            return lerp(d.z, lerp(d.y, d00, d10), lerp(d.y, d01, d11));
        }
        let d00 = lerp(d.x, self.at(x, y, z), self.at(x + 1, y, z));
        let d10 = lerp(d.x, self.at(x, y + 1, z), self.at(x + 1, y + 1, z));
        let d01 = lerp(d.x, self.at(x, y, z + 1), self.at(x + 1, y, z + 1));
        let d11 = lerp(d.x, self.at(x, y + 1, z + 1), self.at(x + 1, y + 1, z + 1));
        lerp(d.z, lerp(d.y, d00, d10), lerp(d.y, d01, d11))
    }

    /// The largest component of any sample that can influence lookups inside the box
    /// [lo, hi] ⊂ [0, 1]³ (pbrt-v4's SampledGrid::MaxValue).
    pub fn max_value(&self, lo: Vec3, hi: Vec3) -> f32 {
        self.max_value_by(lo, hi, T::max_component)
    }

    /// [`DenseGrid::max_value`] of the samples mapped by `f` (e.g. the maximum over
    /// wavelengths of a voxel's spectrum).
    pub fn max_value_by(&self, lo: Vec3, hi: Vec3, f: impl Fn(T) -> f32) -> f32 {
        let n = self.n.as_vec3();
        let p0 = (lo * n - Vec3::splat(0.5)).floor();
        let p1 = (hi * n - Vec3::splat(0.5)).floor() + Vec3::ONE;
        let max_i = self.n.as_ivec3() - glam::IVec3::ONE;
        let i0 = p0.as_ivec3().max(glam::IVec3::ZERO);
        let i1 = p1.as_ivec3().min(max_i);
        let mut m = f32::NEG_INFINITY;
        for z in i0.z..=i1.z {
            for y in i0.y..=i1.y {
                for x in i0.x..=i1.x {
                    m = m.max(f(self.at(x, y, z)));
                }
            }
        }
        if m == f32::NEG_INFINITY { 0.0 } else { m }
    }

    /// The smallest component of any sample that can influence lookups inside the box
    /// [lo, hi] ⊂ [0, 1]³, zero where the box's lookups reach past the samples (they read
    /// zero there): a lower bound on every lookup in the box, since trilinear interpolation
    /// is a convex combination of the corners.
    pub fn min_value(&self, lo: Vec3, hi: Vec3) -> f32 {
        let n = self.n.as_vec3();
        let p0 = (lo * n - Vec3::splat(0.5)).floor().as_ivec3();
        let p1 = ((hi * n - Vec3::splat(0.5)).floor() + Vec3::ONE).as_ivec3();
        let max_i = self.n.as_ivec3() - glam::IVec3::ONE;
        if p0.cmplt(glam::IVec3::ZERO).any() || p1.cmpgt(max_i).any() {
            return 0.0;
        }
        let mut m = f32::INFINITY;
        for z in p0.z..=p1.z {
            for y in p0.y..=p1.y {
                for x in p0.x..=p1.x {
                    m = m.min(self.at(x, y, z).min_component());
                }
            }
        }
        m
    }
}

/// Trilinear interpolation of a cell's corners ([`DenseGrid::corners`] order) at `d` ∈ [0, 1]³.
#[inline]
pub fn trilinear<U>(v: &[U; 8], d: Vec3) -> U
where
    U: Copy + std::ops::Add<Output = U> + std::ops::Mul<f32, Output = U>,
{
    let lerp = |t: f32, a: U, b: U| a * (1.0 - t) + b * t;
    let d00 = lerp(d.x, v[0], v[1]);
    let d10 = lerp(d.x, v[2], v[3]);
    let d01 = lerp(d.x, v[4], v[5]);
    let d11 = lerp(d.x, v[6], v[7]);
    lerp(d.z, lerp(d.y, d00, d10), lerp(d.y, d01, d11))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookups_interpolate_between_sample_centres_and_vanish_outside() {
        let g = DenseGrid::new(UVec3::new(2, 1, 1), vec![1.0f32, 3.0]).unwrap();
        // Sample centres at x = 0.25 and 0.75 (y, z at the centre).
        assert!((g.lookup(Vec3::new(0.25, 0.5, 0.5)) - 1.0).abs() < 1e-6);
        assert!((g.lookup(Vec3::new(0.5, 0.5, 0.5)) - 2.0).abs() < 1e-6);
        assert!((g.lookup(Vec3::new(0.75, 0.5, 0.5)) - 3.0).abs() < 1e-6);
        // Half a voxel from the edge the value falls towards zero.
        assert!((g.lookup(Vec3::new(0.0, 0.5, 0.5)) - 0.5).abs() < 1e-6);
        assert_eq!(g.max_value(Vec3::ZERO, Vec3::splat(0.2)), 1.0);
        assert_eq!(g.max_value(Vec3::ZERO, Vec3::ONE), 3.0);
        assert!(DenseGrid::new(UVec3::new(2, 2, 1), vec![1.0f32]).is_none());
    }
}
