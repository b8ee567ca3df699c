//! Sums of Henyey-Greenstein phase functions over a cluster, laid out so that they vectorise:
//! the aggregation's inner loops (Eqs. 17 and 22) evaluate O(K) phase functions per vertex,
//! which is most of the solve. Arrays are padded to [`LANES`] with entries that contribute 0,
//! and the sums run over fixed-size blocks (one accumulator per lane), which the compiler
//! turns into SIMD without reassociating anything itself.

use glam::Vec3;

use crate::color::Rgb;

/// Block width of the sums.
pub const LANES: usize = 8;

/// The Henyey-Greenstein phase function of one vertex as a / (b + c·(ωo·ω))^{3/2}, the same
/// expression as [`crate::media::phase::henyey_greenstein`] with ωo folded in.
#[derive(Clone, Copy, Debug)]
pub struct Hg {
    /// ωo.
    pub wo: Vec3,
    /// (1 − g²)/4π.
    pub a: f32,
    /// 1 + g².
    pub b: f32,
    /// 2g.
    pub c: f32,
}

impl Hg {
    /// The phase function of asymmetry `g` (clamped as pbrt-v4 does) seen from `wo`.
    #[inline]
    pub fn new(g: f32, wo: Vec3) -> Hg {
        let g = g.clamp(-0.99, 0.99);
        Hg { wo, a: (1.0 - g * g) / (4.0 * std::f32::consts::PI), b: 1.0 + g * g, c: 2.0 * g }
    }

    /// p(ωo, w).
    #[inline]
    pub fn eval(&self, w: Vec3) -> f32 {
        hg(self.a, self.b, self.c, self.wo.dot(w))
    }
}

#[inline(always)]
fn hg(a: f32, b: f32, c: f32, cos: f32) -> f32 {
    let d = (b + c * cos).max(1e-12);
    a / (d * d.sqrt())
}

/// Directions with RGB weights: Σⱼ p(ωⱼ) qⱼ for one phase function.
#[derive(Debug, Default)]
pub struct Samples {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    r: Vec<f32>,
    g: Vec<f32>,
    b: Vec<f32>,
}

impl Samples {
    /// Empties the arrays (keeping their memory).
    pub fn clear(&mut self) {
        for v in [&mut self.x, &mut self.y, &mut self.z, &mut self.r, &mut self.g, &mut self.b] {
            v.clear();
        }
    }

    /// Adds direction `w` with weight `q` (zero weights are skipped).
    #[inline]
    pub fn push(&mut self, w: Vec3, q: Rgb) {
        if q != Rgb::ZERO {
            self.x.push(w.x);
            self.y.push(w.y);
            self.z.push(w.z);
            self.r.push(q.x);
            self.g.push(q.y);
            self.b.push(q.z);
        }
    }

    /// Pads to a whole number of blocks; call after the last push.
    pub fn seal(&mut self) {
        while !self.x.len().is_multiple_of(LANES) {
            self.push_padding();
        }
    }

    fn push_padding(&mut self) {
        for v in [&mut self.x, &mut self.y, &mut self.z, &mut self.r, &mut self.g, &mut self.b] {
            v.push(0.0);
        }
    }

    /// Σⱼ p(ωⱼ) qⱼ.
    #[inline]
    pub fn weighted_sum(&self, p: &Hg) -> Rgb {
        let (mut sr, mut sg, mut sb) = ([0.0f32; LANES], [0.0f32; LANES], [0.0f32; LANES]);
        let blocks = self
            .x
            .chunks_exact(LANES)
            .zip(self.y.chunks_exact(LANES))
            .zip(self.z.chunks_exact(LANES))
            .zip(self.r.chunks_exact(LANES).zip(self.g.chunks_exact(LANES)).zip(self.b.chunks_exact(LANES)));
        for (((x, y), z), ((r, g), b)) in blocks {
            for l in 0..LANES {
                let f = hg(p.a, p.b, p.c, p.wo.x * x[l] + p.wo.y * y[l] + p.wo.z * z[l]);
                sr[l] += f * r[l];
                sg[l] += f * g[l];
                sb[l] += f * b[l];
            }
        }
        Rgb::new(sr.iter().sum(), sg.iter().sum(), sb.iter().sum())
    }
}

/// Directions with their marginal densities M and RGB values L, for a vertex that stands in
/// for another technique e: Σⱼ p(ωⱼ) Lⱼ / (Mⱼ − pₑ(ωⱼ) + p(ωⱼ)).
#[derive(Debug, Default)]
pub struct SwapSamples {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    m: Vec<f32>,
    r: Vec<f32>,
    g: Vec<f32>,
    b: Vec<f32>,
}

impl SwapSamples {
    /// Empties the arrays (keeping their memory).
    pub fn clear(&mut self) {
        for v in [&mut self.x, &mut self.y, &mut self.z, &mut self.m, &mut self.r, &mut self.g, &mut self.b] {
            v.clear();
        }
    }

    /// Adds direction `w` with marginal `m` and value `l` (zero values are skipped).
    #[inline]
    pub fn push(&mut self, w: Vec3, m: f32, l: Rgb) {
        if l != Rgb::ZERO {
            self.x.push(w.x);
            self.y.push(w.y);
            self.z.push(w.z);
            self.m.push(m);
            self.r.push(l.x);
            self.g.push(l.y);
            self.b.push(l.z);
        }
    }

    /// Pads to a whole number of blocks; call after the last push.
    pub fn seal(&mut self) {
        while !self.x.len().is_multiple_of(LANES) {
            for v in [&mut self.x, &mut self.y, &mut self.z, &mut self.r, &mut self.g, &mut self.b] {
                v.push(0.0);
            }
            self.m.push(1.0);
        }
    }

    /// Σⱼ p(ωⱼ) Lⱼ / (Mⱼ − pₑ(ωⱼ) + p(ωⱼ)), terms with a non-positive denominator left out.
    #[inline]
    pub fn swapped_sum(&self, p: &Hg, e: &Hg) -> Rgb {
        let (mut sr, mut sg, mut sb) = ([0.0f32; LANES], [0.0f32; LANES], [0.0f32; LANES]);
        let blocks = self
            .x
            .chunks_exact(LANES)
            .zip(self.y.chunks_exact(LANES))
            .zip(self.z.chunks_exact(LANES).zip(self.m.chunks_exact(LANES)))
            .zip(self.r.chunks_exact(LANES).zip(self.g.chunks_exact(LANES)).zip(self.b.chunks_exact(LANES)));
        for (((x, y), (z, m)), ((r, g), b)) in blocks {
            for l in 0..LANES {
                let f = hg(p.a, p.b, p.c, p.wo.x * x[l] + p.wo.y * y[l] + p.wo.z * z[l]);
                let fe = hg(e.a, e.b, e.c, e.wo.x * x[l] + e.wo.y * y[l] + e.wo.z * z[l]);
                let d = m[l] - fe + f;
                let w = if d > 0.0 { f / d } else { 0.0 };
                sr[l] += w * r[l];
                sg[l] += w * g[l];
                sb[l] += w * b[l];
            }
        }
        Rgb::new(sr.iter().sum(), sg.iter().sum(), sb.iter().sum())
    }
}

/// Phase functions (one per technique): Σₗ pₗ(ω) for a direction.
#[derive(Debug, Default)]
pub struct Phases {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    a: Vec<f32>,
    b: Vec<f32>,
    c: Vec<f32>,
}

impl Phases {
    /// Empties the arrays (keeping their memory).
    pub fn clear(&mut self) {
        for v in [&mut self.x, &mut self.y, &mut self.z, &mut self.a, &mut self.b, &mut self.c] {
            v.clear();
        }
    }

    /// Adds a phase function.
    #[inline]
    pub fn push(&mut self, p: &Hg) {
        self.x.push(p.wo.x);
        self.y.push(p.wo.y);
        self.z.push(p.wo.z);
        self.a.push(p.a);
        self.b.push(p.b);
        self.c.push(p.c);
    }

    /// Pads to a whole number of blocks with phase functions that are 0; call after the last
    /// push.
    pub fn seal(&mut self) {
        while !self.a.len().is_multiple_of(LANES) {
            self.push(&Hg { wo: Vec3::ZERO, a: 0.0, b: 1.0, c: 0.0 });
        }
    }

    /// Σₗ pₗ(w).
    #[inline]
    pub fn sum(&self, w: Vec3) -> f32 {
        let mut acc = [0.0f32; LANES];
        let blocks = self
            .x
            .chunks_exact(LANES)
            .zip(self.y.chunks_exact(LANES))
            .zip(self.z.chunks_exact(LANES))
            .zip(self.a.chunks_exact(LANES).zip(self.b.chunks_exact(LANES)).zip(self.c.chunks_exact(LANES)));
        for (((x, y), z), ((a, b), c)) in blocks {
            for l in 0..LANES {
                acc[l] += hg(a[l], b[l], c[l], x[l] * w.x + y[l] * w.y + z[l] * w.z);
            }
        }
        acc.iter().sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::media::phase::henyey_greenstein;

    #[test]
    fn folded_hg_is_the_phase_function() {
        for g in [-0.7, 0.0, 0.3, 0.95] {
            let wo = Vec3::new(0.3, -0.4, 0.866).normalize();
            let w = Vec3::new(-0.2, 0.9, 0.1).normalize();
            let a = Hg::new(g, wo).eval(w);
            let b = henyey_greenstein(wo.dot(w), g);
            assert!((a - b).abs() <= 1e-6 * b, "g={g}: {a} vs {b}");
        }
    }

    #[test]
    fn blocked_sums_match_plain_sums() {
        let dirs: Vec<Vec3> =
            (0..13).map(|k| Vec3::new((k as f32).sin(), (k as f32 * 1.7).cos(), 0.3).normalize()).collect();
        let phases: Vec<Hg> = dirs.iter().enumerate().map(|(k, &w)| Hg::new(0.1 * k as f32 - 0.5, w)).collect();
        let (mut s, mut p) = (Samples::default(), Phases::default());
        for (k, &w) in dirs.iter().enumerate() {
            s.push(w, Rgb::new(k as f32, 1.0, 0.5));
            p.push(&phases[k]);
        }
        s.seal();
        p.seal();
        let plain: Rgb = dirs.iter().enumerate().map(|(k, &w)| phases[3].eval(w) * Rgb::new(k as f32, 1.0, 0.5)).sum();
        assert!((s.weighted_sum(&phases[3]) - plain).abs().max_element() < 1e-4 * plain.max_element());
        let w = Vec3::new(0.1, 0.2, 0.97).normalize();
        let plain: f32 = phases.iter().map(|h| h.eval(w)).sum();
        assert!((p.sum(w) - plain).abs() < 1e-5 * plain);
    }
}
