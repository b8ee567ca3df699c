//! pbrt-v4's `PiecewiseLinear2D` (after Mitsuba 2's `Marginal2D`, Dupuy and Jakob 2018): a
//! density on [0, 1]² given at the nodes of a regular grid and interpolated bilinearly,
//! optionally depending on up to three further parameters through a regular table of such
//! grids that is interpolated multilinearly. It can be evaluated, sampled (inverting the
//! marginal CDF along y, then the conditional one along x, each exactly: the CDFs of linear
//! pieces are quadratics) and inverted (the map from a point back to the uniform sample that
//! produces it). The measured BSDF's tables are of this kind.

use glam::Vec2;

use crate::sampling::warp::ONE_MINUS_EPSILON;

/// Most extra parameters a table has (the measured BSDF's spectra: φ, θ, λ).
const MAX_PARAMS: usize = 3;

/// A sampled point and its density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlSample {
    /// The point (sampled, or the uniform sample when inverting).
    pub p: Vec2,
    /// The density at the point.
    pub pdf: f32,
}

/// A bilinearly interpolated 2D density with optional parameters.
#[derive(Clone, Debug, Default)]
pub struct PiecewiseLinear2D {
    /// Grid resolution (x, y).
    size: [usize; 2],
    /// Cells per unit along x and y: size − 1.
    inv_patch: Vec2,
    /// Per parameter: its node count, its stride in grids (0 when it has one node) and its
    /// node values.
    param_size: Vec<usize>,
    param_strides: Vec<usize>,
    param_values: Vec<Vec<f32>>,
    /// Density values, one grid per parameter combination (the first parameter slowest).
    data: Vec<f32>,
    /// Per grid: the marginal CDF over rows and the conditional CDFs along each row.
    marginal_cdf: Vec<f32>,
    conditional_cdf: Vec<f32>,
}

/// Weights of the two nodes around each parameter value, and the grid offset of the lower.
struct ParamWeights {
    w: [[f32; 2]; MAX_PARAMS],
    slice: usize,
}

/// pbrt-v4's `FindInterval`: the largest i in [0, size − 2] with `pred(i)`, for a predicate
/// that holds up to some index and fails after it (0 when it never holds).
fn find_interval(size: usize, pred: impl Fn(usize) -> bool) -> usize {
    let (mut first, mut len) = (1usize, size as isize - 2);
    while len > 0 {
        let half = (len as usize) >> 1;
        let middle = first + half;
        if pred(middle) {
            first = middle + 1;
            len -= half as isize + 1;
        } else {
            len = half as isize;
        }
    }
    (first as isize - 1).clamp(0, (size as isize - 2).max(0)) as usize
}

impl PiecewiseLinear2D {
    /// The density `data` of `x_size` × `y_size` nodes (rows of x) for every combination of
    /// the parameters' nodes `params` (the first parameter slowest in `data`). With
    /// `build_cdf` the density is normalised to integrate to 1 and can be sampled; without,
    /// it is only evaluated, normalised when `normalize` is set. `None` when the sizes do not
    /// fit or the density is zero everywhere it must be sampled.
    pub fn new(
        data: &[f32],
        x_size: usize,
        y_size: usize,
        params: &[&[f32]],
        normalize: bool,
        build_cdf: bool,
    ) -> Option<PiecewiseLinear2D> {
        if x_size < 2 || y_size < 2 || params.len() > MAX_PARAMS || params.iter().any(|p| p.is_empty()) {
            return None;
        }
        let mut slices = 1usize;
        let mut param_strides = vec![0; params.len()];
        for i in (0..params.len()).rev() {
            param_strides[i] = if params[i].len() > 1 { slices } else { 0 };
            slices *= params[i].len();
        }
        let n = x_size * y_size;
        if data.len() != slices * n || data.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let mut t = PiecewiseLinear2D {
            size: [x_size, y_size],
            inv_patch: Vec2::new((x_size - 1) as f32, (y_size - 1) as f32),
            param_size: params.iter().map(|p| p.len()).collect(),
            param_strides,
            param_values: params.iter().map(|p| p.to_vec()).collect(),
            data: vec![0.0; slices * n],
            marginal_cdf: Vec::new(),
            conditional_cdf: Vec::new(),
        };
        if build_cdf {
            t.marginal_cdf = vec![0.0; slices * y_size];
            t.conditional_cdf = vec![0.0; slices * n];
            for s in 0..slices {
                let d = &data[s * n..(s + 1) * n];
                let cond = &mut t.conditional_cdf[s * n..(s + 1) * n];
                for y in 0..y_size {
                    let mut sum = 0.0f64;
                    let i = y * x_size;
                    cond[i] = 0.0;
                    for x in 0..x_size - 1 {
                        sum += 0.5 * (d[i + x] as f64 + d[i + x + 1] as f64);
                        cond[i + x + 1] = sum as f32;
                    }
                }
                let marg = &mut t.marginal_cdf[s * y_size..(s + 1) * y_size];
                marg[0] = 0.0;
                let mut sum = 0.0f64;
                for y in 0..y_size - 1 {
                    sum += 0.5 * (cond[(y + 1) * x_size - 1] as f64 + cond[(y + 2) * x_size - 1] as f64);
                    marg[y + 1] = sum as f32;
                }
                let total = marg[y_size - 1];
                if total <= 0.0 || !total.is_finite() {
                    return None;
                }
                let norm = 1.0 / total;
                cond.iter_mut().for_each(|v| *v *= norm);
                marg.iter_mut().for_each(|v| *v *= norm);
                for (o, v) in t.data[s * n..(s + 1) * n].iter_mut().zip(d) {
                    *o = v * norm;
                }
            }
        } else {
            for s in 0..slices {
                let d = &data[s * n..(s + 1) * n];
                let mut norm = 1.0 / (t.inv_patch.x * t.inv_patch.y);
                if normalize {
                    let mut sum = 0.0f64;
                    for y in 0..y_size - 1 {
                        for x in 0..x_size - 1 {
                            let i = y * x_size + x;
                            sum += 0.25 * (d[i] + d[i + 1] + d[i + x_size] + d[i + 1 + x_size]) as f64;
                        }
                    }
                    norm = (1.0 / sum) as f32;
                }
                for (o, v) in t.data[s * n..(s + 1) * n].iter_mut().zip(d) {
                    *o = v * norm;
                }
            }
        }
        Some(t)
    }

    fn weights(&self, params: &[f32]) -> ParamWeights {
        debug_assert_eq!(params.len(), self.param_size.len());
        let mut pw = ParamWeights { w: [[1.0, 0.0]; MAX_PARAMS], slice: 0 };
        for (dim, &p) in params.iter().enumerate() {
            if self.param_size[dim] == 1 {
                continue;
            }
            let values = &self.param_values[dim];
            let i = find_interval(values.len(), |k| values[k] <= p);
            let (p0, p1) = (values[i], values[i + 1]);
            let w1 = ((p - p0) / (p1 - p0)).clamp(0.0, 1.0);
            pw.w[dim] = [1.0 - w1, w1];
            pw.slice += self.param_strides[dim] * i;
        }
        pw
    }

    /// `table[index]` interpolated over the parameters: `index` addresses the lower corner's
    /// grid and `size` is one grid's length in `table`.
    #[inline]
    fn lookup(&self, table: &[f32], index: usize, size: usize, pw: &ParamWeights) -> f32 {
        let dims = self.param_size.len();
        let mut v = 0.0;
        for corner in 0..1usize << dims {
            let (mut i, mut w) = (index, 1.0);
            for d in 0..dims {
                let bit = (corner >> d) & 1;
                i += bit * self.param_strides[d] * size;
                w *= pw.w[d][bit];
            }
            if w != 0.0 {
                v += w * table[i];
            }
        }
        v
    }

    /// A point distributed by the density for `params`, from a uniform sample `u`.
    pub fn sample(&self, mut u: Vec2, params: &[f32]) -> PlSample {
        let pw = self.weights(params);
        let [sx, sy] = self.size;
        let one_minus = ONE_MINUS_EPSILON;
        u = u.clamp(Vec2::splat(1.0 - one_minus), Vec2::splat(one_minus));
        // The row, from the marginal CDF.
        let moff = pw.slice * sy;
        let marginal = |i: usize| self.lookup(&self.marginal_cdf, moff + i, sy, &pw);
        let row = find_interval(sy, |i| marginal(i) < u.y);
        u.y -= marginal(row);
        let slice_size = sx * sy;
        let offset = row * sx + pw.slice * slice_size;
        let r0 = self.lookup(&self.conditional_cdf, offset + sx - 1, slice_size, &pw);
        let r1 = self.lookup(&self.conditional_cdf, offset + 2 * sx - 1, slice_size, &pw);
        let is_const = (r0 - r1).abs() < 1e-4 * (r0 + r1);
        u.y = if is_const { 2.0 * u.y } else { r0 - (r0 * r0 - 2.0 * u.y * (r0 - r1)).max(0.0).sqrt() };
        u.y /= if is_const { r0 + r1 } else { r0 - r1 };
        // The column, from the conditional CDF interpolated between the two rows.
        u.x *= (1.0 - u.y) * r0 + u.y * r1;
        let conditional = |i: usize| {
            let v0 = self.lookup(&self.conditional_cdf, offset + i, slice_size, &pw);
            let v1 = self.lookup(&self.conditional_cdf, offset + sx + i, slice_size, &pw);
            (1.0 - u.y) * v0 + u.y * v1
        };
        let col = find_interval(sx, |i| conditional(i) < u.x);
        u.x -= conditional(col);
        let o = offset + col;
        let v00 = self.lookup(&self.data, o, slice_size, &pw);
        let v10 = self.lookup(&self.data, o + 1, slice_size, &pw);
        let v01 = self.lookup(&self.data, o + sx, slice_size, &pw);
        let v11 = self.lookup(&self.data, o + sx + 1, slice_size, &pw);
        let c0 = (1.0 - u.y) * v00 + u.y * v01;
        let c1 = (1.0 - u.y) * v10 + u.y * v11;
        let is_const = (c0 - c1).abs() < 1e-4 * (c0 + c1);
        u.x = if is_const { 2.0 * u.x } else { c0 - (c0 * c0 - 2.0 * u.x * (c0 - c1)).max(0.0).sqrt() };
        u.x /= if is_const { c0 + c1 } else { c0 - c1 };
        PlSample {
            p: Vec2::new((col as f32 + u.x) / self.inv_patch.x, (row as f32 + u.y) / self.inv_patch.y),
            pdf: ((1.0 - u.x) * c0 + u.x * c1) * self.inv_patch.x * self.inv_patch.y,
        }
    }

    /// The uniform sample [`PiecewiseLinear2D::sample`] maps to `p`, and the density at `p`.
    pub fn invert(&self, p: Vec2, params: &[f32]) -> PlSample {
        let pw = self.weights(params);
        let [sx, sy] = self.size;
        let mut s = p * self.inv_patch;
        let pos = [(s.x as usize).min(sx - 2), (s.y as usize).min(sy - 2)];
        s -= Vec2::new(pos[0] as f32, pos[1] as f32);
        let slice_size = sx * sy;
        let offset = pos[0] + pos[1] * sx + pw.slice * slice_size;
        let v00 = self.lookup(&self.data, offset, slice_size, &pw);
        let v10 = self.lookup(&self.data, offset + 1, slice_size, &pw);
        let v01 = self.lookup(&self.data, offset + sx, slice_size, &pw);
        let v11 = self.lookup(&self.data, offset + sx + 1, slice_size, &pw);
        let (w1, w0) = (s, Vec2::ONE - s);
        let c0 = w0.y * v00 + w1.y * v01;
        let c1 = w0.y * v10 + w1.y * v11;
        let pdf = w0.x * c0 + w1.x * c1;
        s.x *= c0 + 0.5 * s.x * (c1 - c0);
        let v0 = self.lookup(&self.conditional_cdf, offset, slice_size, &pw);
        let v1 = self.lookup(&self.conditional_cdf, offset + sx, slice_size, &pw);
        s.x += (1.0 - s.y) * v0 + s.y * v1;
        let row = pos[1] * sx + pw.slice * slice_size;
        let r0 = self.lookup(&self.conditional_cdf, row + sx - 1, slice_size, &pw);
        let r1 = self.lookup(&self.conditional_cdf, row + 2 * sx - 1, slice_size, &pw);
        s.x /= (1.0 - s.y) * r0 + s.y * r1;
        s.y *= r0 + 0.5 * s.y * (r1 - r0);
        s.y += self.lookup(&self.marginal_cdf, pos[1] + pw.slice * sy, sy, &pw);
        PlSample { p: s, pdf: pdf * self.inv_patch.x * self.inv_patch.y }
    }

    /// The density at `p` for `params`.
    pub fn evaluate(&self, p: Vec2, params: &[f32]) -> f32 {
        let pw = self.weights(params);
        let [sx, sy] = self.size;
        let q = p * self.inv_patch;
        let pos = [(q.x.max(0.0) as usize).min(sx - 2), (q.y.max(0.0) as usize).min(sy - 2)];
        let w1 = q - Vec2::new(pos[0] as f32, pos[1] as f32);
        let w0 = Vec2::ONE - w1;
        let size = sx * sy;
        let index = pos[0] + pos[1] * sx + pw.slice * size;
        let v00 = self.lookup(&self.data, index, size, &pw);
        let v10 = self.lookup(&self.data, index + 1, size, &pw);
        let v01 = self.lookup(&self.data, index + sx, size, &pw);
        let v11 = self.lookup(&self.data, index + sx + 1, size, &pw);
        (w0.y * (w0.x * v00 + w1.x * v10) + w1.y * (w0.x * v01 + w1.x * v11)) * self.inv_patch.x * self.inv_patch.y
    }

    /// Bytes of table data.
    pub fn bytes(&self) -> usize {
        4 * (self.data.len() + self.marginal_cdf.len() + self.conditional_cdf.len())
            + self.param_values.iter().map(|v| 4 * v.len()).sum::<usize>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Pcg32;

    /// A smooth positive density on a 7 × 5 grid for each of 3 × 2 parameter nodes.
    fn table() -> (Vec<f32>, Vec<f32>, Vec<f32>) {
        let (p0, p1) = (vec![0.0, 0.5, 2.0], vec![-1.0, 1.0]);
        let mut data = Vec::new();
        for a in &p0 {
            for b in &p1 {
                for y in 0..5 {
                    for x in 0..7 {
                        let (fx, fy) = (x as f32 / 6.0, y as f32 / 4.0);
                        data.push(0.2 + (fx * 3.0 + a).sin().abs() + fy * (1.5 + b) + fx * fy);
                    }
                }
            }
        }
        (data, p0, p1)
    }

    #[test]
    fn find_interval_matches_pbrt() {
        let v = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(find_interval(4, |i| v[i] <= -1.0), 0);
        assert_eq!(find_interval(4, |i| v[i] <= 0.5), 0);
        assert_eq!(find_interval(4, |i| v[i] <= 1.5), 1);
        assert_eq!(find_interval(4, |i| v[i] <= 2.5), 2);
        assert_eq!(find_interval(4, |i| v[i] <= 9.0), 2);
    }

    #[test]
    fn sampling_inverts_and_densities_agree() {
        let (data, p0, p1) = table();
        let t = PiecewiseLinear2D::new(&data, 7, 5, &[&p0, &p1], true, true).unwrap();
        let mut rng = Pcg32::new(1, 2);
        for _ in 0..2000 {
            let params = [rng.uniform() * 2.5 - 0.25, rng.uniform() * 2.0 - 1.0];
            let u = Vec2::new(rng.uniform(), rng.uniform());
            let s = t.sample(u, &params);
            assert!(s.p.cmpge(Vec2::ZERO).all() && s.p.cmple(Vec2::ONE).all(), "{:?}", s.p);
            let e = t.evaluate(s.p, &params);
            assert!((s.pdf - e).abs() <= 1e-3 * e, "pdf {} vs evaluate {e}", s.pdf);
            let inv = t.invert(s.p, &params);
            assert!((inv.p - u).length() < 1e-3, "invert {:?} vs {u:?}", inv.p);
            assert!((inv.pdf - e).abs() <= 1e-3 * e);
        }
    }

    #[test]
    fn the_density_integrates_to_one_for_any_parameter() {
        let (data, p0, p1) = table();
        let t = PiecewiseLinear2D::new(&data, 7, 5, &[&p0, &p1], true, true).unwrap();
        for params in [[0.0, -1.0], [0.3, 0.2], [2.0, 1.0], [1.1, -0.4]] {
            let n = 400;
            let mut sum = 0.0f64;
            for j in 0..n {
                for i in 0..n {
                    let p = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    sum += t.evaluate(p, &params) as f64;
                }
            }
            let integral = sum / (n * n) as f64;
            // Interpolating normalised grids between parameter nodes keeps the integral 1.
            assert!((integral - 1.0).abs() < 1e-3, "{params:?}: {integral}");
        }
        // Sampled points follow the density: a histogram over 4 × 4 cells.
        let params = [0.7, 0.3];
        let mut counts = [[0usize; 4]; 4];
        let mut rng = Pcg32::new(5, 6);
        let n = 200_000;
        for _ in 0..n {
            let s = t.sample(Vec2::new(rng.uniform(), rng.uniform()), &params);
            counts[((s.p.y * 4.0) as usize).min(3)][((s.p.x * 4.0) as usize).min(3)] += 1;
        }
        for (cy, row) in counts.iter().enumerate() {
            for (cx, &c) in row.iter().enumerate() {
                let m = 40;
                let mut expected = 0.0f64;
                for j in 0..m {
                    for i in 0..m {
                        let p = Vec2::new(
                            (cx as f32 + (i as f32 + 0.5) / m as f32) / 4.0,
                            (cy as f32 + (j as f32 + 0.5) / m as f32) / 4.0,
                        );
                        expected += t.evaluate(p, &params) as f64;
                    }
                }
                expected *= n as f64 / (16.0 * (m * m) as f64);
                assert!(
                    (c as f64 - expected).abs() < 5.0 * expected.sqrt() + 1e-3 * expected,
                    "cell ({cx},{cy}): {c} vs {expected}"
                );
            }
        }
    }

    #[test]
    fn unnormalised_tables_interpolate_the_data() {
        let data = [1.0, 2.0, 3.0, 4.0];
        let t = PiecewiseLinear2D::new(&data, 2, 2, &[], false, false).unwrap();
        assert!((t.evaluate(Vec2::new(0.5, 0.5), &[]) - 2.5).abs() < 1e-6);
        assert!((t.evaluate(Vec2::new(1.0, 0.0), &[]) - 2.0).abs() < 1e-6);
        assert!(PiecewiseLinear2D::new(&[1.0, 2.0, 3.0], 2, 2, &[], false, false).is_none());
    }
}
