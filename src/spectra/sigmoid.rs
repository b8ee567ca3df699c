//! Smooth spectra for RGB values: the sigmoid-polynomial model of Jakob and Hanika, "A
//! Low-Dimensional Function Space for Efficient Spectral Upsampling" (2019), which pbrt-v4
//! uses for every RGB reflectance, coefficient and light. A spectrum is
//! s(λ) = S(c₀λ² + c₁λ + c₂) with the sigmoid S(x) = ½ + x / (2√(1 + x²)); the three
//! coefficients of an RGB are found by Gauss–Newton so that the spectrum, seen under the
//! color space's illuminant, has that RGB (their Eq. 6, residual measured in CIELAB as
//! pbrt-v4's `rgb2spec_opt` does).
//!
//! pbrt-v4 precomputes a 3 × 64³ coefficient table per color space at build time. nimbus
//! solves scene constants exactly with `rgb2spec_opt`'s own objective ([`fit_sigmoid`],
//! about 0.25 ms each, cached: on a 7³ grid of sRGB colours their spectra are within 2e-4 on
//! average, 5e-3 at worst, of `rgb2spec_opt`'s exact solutions, checked against pbrt-v4's
//! generated table), and builds a coarser table of the same layout lazily, on the first
//! per-texel lookup of a spectral render ([`SigmoidTable`], 10 nm objective).

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use glam::{DMat3, DVec3, Vec4};
use nimbus_parser::ColorSpace;

use super::cie::{LAMBDA_MAX, LAMBDA_MIN, cie_xyz_bar};
use super::colorspace::rgb_color_space;

/// pbrt-v4's `RGBSigmoidPolynomial`: s(λ) = S(c₀λ² + c₁λ + c₂), λ in nm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SigmoidPolynomial {
    /// λ² coefficient.
    pub c0: f32,
    /// λ coefficient.
    pub c1: f32,
    /// Constant term.
    pub c2: f32,
}

#[inline]
fn sigmoid(x: f32) -> f32 {
    if x.is_infinite() {
        return if x > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + x / (2.0 * (1.0 + x * x).sqrt())
}

impl SigmoidPolynomial {
    /// The constant spectrum `v` ∈ [0, 1] (exact: c₀ = c₁ = 0; 0 and 1 give ∓∞).
    pub fn constant(v: f32) -> SigmoidPolynomial {
        SigmoidPolynomial { c0: 0.0, c1: 0.0, c2: (v - 0.5) / (v * (1.0 - v)).sqrt() }
    }

    /// The value at `lambda` nm.
    #[inline]
    pub fn eval(&self, lambda: f32) -> f32 {
        sigmoid((self.c0 * lambda + self.c1) * lambda + self.c2)
    }

    /// The values at four wavelengths, lane-parallel (this runs in the path loop).
    #[inline]
    pub fn eval4(&self, lambda: Vec4) -> Vec4 {
        let x = (Vec4::splat(self.c0) * lambda + Vec4::splat(self.c1)) * lambda + Vec4::splat(self.c2);
        // Clamped so x² stays finite: ±∞ (the constants 0 and 1) then give exactly 0 and 1,
        // and no lane needs a branch.
        let x = x.clamp(Vec4::splat(-1e18), Vec4::splat(1e18));
        Vec4::splat(0.5) + x / (Vec4::splat(2.0) * (Vec4::ONE + x * x).sqrt())
    }

    /// The largest value over 360–830 nm (pbrt-v4's `MaxValue`).
    pub fn max_value(&self) -> f32 {
        let mut m = self.eval(360.0).max(self.eval(830.0));
        let lambda = -self.c1 / (2.0 * self.c0);
        if (360.0..=830.0).contains(&lambda) {
            m = m.max(self.eval(lambda));
        }
        m
    }

    /// True when the spectrum is constant.
    pub fn is_constant(&self) -> bool {
        self.c0 == 0.0 && self.c1 == 0.0
    }
}

/// The quadrature a fit integrates the spectrum's RGB with.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Quadrature {
    /// `rgb2spec_opt`'s: 283 points over 360–830 nm, the 5 nm CIE and illuminant tables
    /// interpolated linearly between them, Simpson's 3/8 rule. Scene constants are few and
    /// cached, so they get pbrt-v4's own objective (and so pbrt-v4's spectra).
    Pbrt,
    /// Trapezoid at 10 nm: 6× cheaper, for building [`SigmoidTable`] on first use (its
    /// round trip against pbrt-v4's 1 nm sums stays within 2e-3; its spectra differ from
    /// [`Quadrature::Pbrt`]'s by a few 1e-3 on average).
    Coarse,
}

/// What the fit of one color space needs: at each quadrature node, λ normalised to [0, 1]
/// and the weights giving the space's RGB of a reflectance under its illuminant.
struct Fitter {
    t: Vec<f64>,
    weights: Vec<DVec3>,
    xyz_from_rgb: DMat3,
    white: DVec3,
}

impl Fitter {
    fn new(space: ColorSpace, quadrature: Quadrature) -> Fitter {
        let cs = rgb_color_space(space);
        // The tables at 5 nm, interpolated linearly as rgb2spec_opt's `cie_interp` does (the
        // matching functions and the illuminant separately).
        let at5 = |f: &dyn Fn(f64) -> DVec3, lambda: f64| {
            let x = ((lambda - LAMBDA_MIN) / 5.0).clamp(0.0, 93.999_999);
            let (i, w) = (x.floor(), x.fract());
            let l0 = LAMBDA_MIN + 5.0 * i;
            f(l0) * (1.0 - w) + f(l0 + 5.0) * w
        };
        let illuminant = |l: f64| DVec3::splat(cs.illuminant.eval(l));
        let (nodes, step): (usize, f64) = match quadrature {
            Quadrature::Pbrt => (283, (LAMBDA_MAX - LAMBDA_MIN) / 282.0),
            Quadrature::Coarse => (48, 10.0),
        };
        let mut t = Vec::with_capacity(nodes);
        let mut xyz = Vec::with_capacity(nodes);
        for i in 0..nodes {
            let lambda = (LAMBDA_MIN + step * i as f64).min(LAMBDA_MAX);
            t.push((lambda - LAMBDA_MIN) / (LAMBDA_MAX - LAMBDA_MIN));
            let (w, v) = match quadrature {
                // Simpson's 3/8: 1, 3, 3, 2, 3, 3, 2, …, 3, 3, 1.
                Quadrature::Pbrt => {
                    let w = if i == 0 || i == nodes - 1 {
                        1.0
                    } else if (i - 1) % 3 == 2 {
                        2.0
                    } else {
                        3.0
                    };
                    (w, at5(&cie_xyz_bar, lambda) * at5(&illuminant, lambda).x)
                }
                Quadrature::Coarse => {
                    let w = if i == 0 || i == nodes - 1 { 0.5 } else { 1.0 };
                    (w, cie_xyz_bar(lambda) * cs.illuminant.eval(lambda))
                }
            };
            xyz.push(v * w);
        }
        let white: DVec3 = xyz.iter().sum();
        // Normalise so the constant spectrum 1 has the illuminant's Y = 1.
        let norm = 1.0 / white.y;
        let weights = xyz.iter().map(|x| cs.rgb_from_xyz * (*x * norm)).collect();
        Fitter { t, weights, xyz_from_rgb: cs.xyz_from_rgb, white: white * norm }
    }

    fn get(space: ColorSpace, quadrature: Quadrature) -> &'static Fitter {
        static FITTERS: OnceLock<[[Fitter; 4]; 2]> = OnceLock::new();
        let f = FITTERS.get_or_init(|| {
            [Quadrature::Pbrt, Quadrature::Coarse].map(|q| {
                [ColorSpace::Srgb, ColorSpace::Rec2020, ColorSpace::Aces2065_1, ColorSpace::DciP3]
                    .map(|s| Fitter::new(s, q))
            })
        });
        let f = &f[usize::from(quadrature == Quadrature::Coarse)];
        match space {
            ColorSpace::Srgb => &f[0],
            ColorSpace::Rec2020 => &f[1],
            ColorSpace::Aces2065_1 => &f[2],
            ColorSpace::DciP3 => &f[3],
        }
    }

    /// CIELAB of `rgb` (relative to the illuminant's white) and its derivative d Lab / d rgb.
    fn lab(&self, rgb: DVec3) -> (DVec3, DMat3) {
        let xyz = self.xyz_from_rgb * rgb / self.white;
        let delta: f64 = 6.0 / 29.0;
        let f = |t: f64| if t > delta.powi(3) { t.cbrt() } else { t / (3.0 * delta * delta) + 4.0 / 29.0 };
        let df = |t: f64| if t > delta.powi(3) { 1.0 / (3.0 * t.cbrt().powi(2)) } else { 1.0 / (3.0 * delta * delta) };
        let (fx, fy, fz) = (f(xyz.x), f(xyz.y), f(xyz.z));
        let lab = DVec3::new(116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz));
        // d Lab / d(xyz / white), then through the normalisation and the matrix.
        let (dx, dy, dz) = (df(xyz.x), df(xyz.y), df(xyz.z));
        let d_lab_d_xyz = DMat3::from_cols(
            DVec3::new(0.0, 500.0 * dx, 0.0),
            DVec3::new(116.0 * dy, -500.0 * dy, 200.0 * dy),
            DVec3::new(0.0, 0.0, -200.0 * dz),
        );
        let d_xyz_d_rgb = DMat3::from_diagonal(1.0 / self.white) * self.xyz_from_rgb;
        (lab, d_lab_d_xyz * d_xyz_d_rgb)
    }

    /// RGB of the spectrum with normalised-λ coefficients `c`, and its derivative d rgb / d c.
    fn rgb(&self, c: DVec3) -> (DVec3, DMat3) {
        let (mut out, mut d) = (DVec3::ZERO, [DVec3::ZERO; 3]);
        for (t, w) in self.t.iter().zip(&self.weights) {
            let x = (c.x * t + c.y) * t + c.z;
            let q = 1.0 + x * x;
            out += *w * (0.5 + x / (2.0 * q.sqrt()));
            // S'(x) = 1 / (2 (1 + x²)^{3/2}); dx/dc = (t², t, 1).
            let ds = *w * (0.5 / (q * q.sqrt()));
            d[0] += ds * (t * t);
            d[1] += ds * *t;
            d[2] += ds;
        }
        (out, DMat3::from_cols(d[0], d[1], d[2]))
    }

    /// Gauss–Newton on the CIELAB residual from coefficients `c`, as `rgb2spec_opt` runs it
    /// (at most 15 steps, coefficients kept below 200; its central-difference Jacobian here
    /// analytic), with a step-halving line search so a step never increases the residual (the
    /// optimiser's table walk takes small enough steps not to need one; single colours may
    /// not).
    fn gauss_newton(&self, target: DVec3, mut c: DVec3) -> DVec3 {
        let (goal, _) = self.lab(target);
        let eval = |c: DVec3| {
            let (rgb, d_rgb) = self.rgb(c);
            let (lab, d_lab) = self.lab(rgb);
            // The residual is goal − lab, so its Jacobian is −d lab / d c.
            (goal - lab, d_lab * d_rgb * -1.0)
        };
        let (mut r, mut j) = eval(c);
        for _ in 0..15 {
            if r.length_squared() < 1e-6 || j.determinant().abs() < 1e-15 {
                break;
            }
            let step = j.inverse() * r;
            let mut t = 1.0;
            loop {
                let mut next = c - step * t;
                let m = next.max_element();
                if m > 200.0 {
                    next *= 200.0 / m;
                }
                let (r_next, j_next) = eval(next);
                if r_next.length_squared() < r.length_squared() || t < 1e-3 {
                    (c, r, j) = (next, r_next, j_next);
                    break;
                }
                t *= 0.5;
            }
        }
        c
    }

    /// Coefficients (normalised λ) for `rgb` ∈ [0, 1]³ with distinct components: pbrt-v4's
    /// table walk, done for one colour — start from zero at a dim level of the same
    /// chromaticity, then raise the brightness to the target over pbrt-v4's smoothstep² levels,
    /// each solve starting from the last (Gauss–Newton alone does not reach saturated colours
    /// from zero).
    fn solve(&self, rgb: DVec3) -> DVec3 {
        let b = rgb.max_element();
        let smooth = |x: f64| x * x * (3.0 - 2.0 * x);
        let levels = 64;
        let start = levels / 5;
        let mut c = DVec3::ZERO;
        for k in start..levels {
            let level = smooth(smooth(k as f64 / (levels - 1) as f64));
            if level >= b {
                break;
            }
            c = self.gauss_newton(rgb * (level / b), c);
        }
        self.gauss_newton(rgb, c)
    }
}

/// Coefficients in normalised λ ∈ [0, 1] turned into coefficients in nm.
fn to_nm(c: DVec3) -> SigmoidPolynomial {
    let (c0, c1) = (LAMBDA_MIN, 1.0 / (LAMBDA_MAX - LAMBDA_MIN));
    let (a, b, cc) = (c.x, c.y, c.z);
    SigmoidPolynomial {
        c0: (a * c1 * c1) as f32,
        c1: (b * c1 - 2.0 * a * c0 * c1 * c1) as f32,
        c2: (cc - b * c0 * c1 + a * (c0 * c1) * (c0 * c1)) as f32,
    }
}

/// The sigmoid polynomial whose spectrum has RGB `rgb` (components clamped to [0, 1]) in
/// color space `space`, solved exactly and cached (scene constants).
pub fn fit_sigmoid(space: ColorSpace, rgb: [f32; 3]) -> SigmoidPolynomial {
    let rgb = rgb.map(|v| v.clamp(0.0, 1.0));
    if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
        return SigmoidPolynomial::constant(rgb[0]);
    }
    type Cache = Mutex<HashMap<(ColorSpace, [u32; 3]), SigmoidPolynomial>>;
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let key = (space, rgb.map(f32::to_bits));
    let cache = CACHE.get_or_init(Default::default);
    if let Some(p) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return *p;
    }
    let p = to_nm(Fitter::get(space, Quadrature::Pbrt).solve(DVec3::new(rgb[0] as f64, rgb[1] as f64, rgb[2] as f64)));
    cache.lock().unwrap_or_else(|e| e.into_inner()).insert(key, p);
    p
}

/// pbrt-v4's `RGBToSpectrumTable` layout: for each largest component (3), brightness z (on
/// pbrt-v4's smoothstep² nodes) and the other two components relative to it (x, y), the
/// coefficients, trilinearly interpolated. pbrt-v4 computes its table when it is built;
/// nimbus fits a column (one largest component, x and y, every z) the first time a lookup
/// needs it, so a render pays for the colours its scene has: a chromatic smoke of a few
/// hues fits a few dozen of the 3 × 32² columns (the whole table took 0.17 s of a 2-core
/// render's start-up).
pub struct SigmoidTable {
    space: ColorSpace,
    res: usize,
    z_nodes: Vec<f32>,
    /// Per column, `(maxc · res + y) · res + x`: the coefficients at each z node.
    columns: Vec<OnceLock<Box<[[f32; 3]]>>>,
}

/// Resolution of [`SigmoidTable`]: 3 × 32³ fits take about a second of one core (for scenes
/// of every colour); pbrt-v4's 64³ would take eight. The round-trip error it adds is measured
/// in the tests.
const TABLE_RES: usize = 32;

impl SigmoidTable {
    fn new(space: ColorSpace, res: usize) -> SigmoidTable {
        let smooth = |x: f64| x * x * (3.0 - 2.0 * x);
        let z_nodes = (0..res).map(|k| smooth(smooth(k as f64 / (res - 1) as f64)) as f32).collect();
        SigmoidTable { space, res, z_nodes, columns: (0..3 * res * res).map(|_| OnceLock::new()).collect() }
    }

    /// Column `(l, j, i)`'s coefficients, fitted as `rgb2spec_opt` fits a column: z marched up
    /// from a fifth and down from there, each solve warm-started from its neighbour (the
    /// same fits whichever lookup asks first, so renders do not depend on thread timing).
    fn column(&self, l: usize, j: usize, i: usize) -> &[[f32; 3]] {
        let res = self.res;
        self.columns[(l * res + j) * res + i].get_or_init(|| {
            let fitter = Fitter::get(self.space, Quadrature::Coarse);
            let (x, y) = (i as f64 / (res - 1) as f64, j as f64 / (res - 1) as f64);
            let rgb_at = |b: f64| {
                let mut v = DVec3::ZERO;
                v[l] = b;
                v[(l + 1) % 3] = x * b;
                v[(l + 2) % 3] = y * b;
                v
            };
            let z = |k: usize| {
                let smooth = |x: f64| x * x * (3.0 - 2.0 * x);
                smooth(smooth(k as f64 / (res - 1) as f64))
            };
            let mut out = vec![[0.0; 3]; res];
            let start = res / 5;
            // Both marches start from zero at `start`, so both give it the same value.
            for ks in [(start..res).collect::<Vec<_>>(), (0..=start).rev().collect()] {
                let mut c = DVec3::ZERO;
                for k in ks {
                    c = fitter.gauss_newton(rgb_at(z(k)), c);
                    let p = to_nm(c);
                    out[k] = [p.c0, p.c1, p.c2];
                }
            }
            out.into_boxed_slice()
        })
    }

    /// The table of `space`, built on first use.
    pub fn get(space: ColorSpace) -> &'static SigmoidTable {
        static TABLES: [OnceLock<SigmoidTable>; 4] =
            [OnceLock::new(), OnceLock::new(), OnceLock::new(), OnceLock::new()];
        let i = match space {
            ColorSpace::Srgb => 0,
            ColorSpace::Rec2020 => 1,
            ColorSpace::Aces2065_1 => 2,
            ColorSpace::DciP3 => 3,
        };
        TABLES[i].get_or_init(|| SigmoidTable::new(space, TABLE_RES))
    }

    /// The coefficients for `rgb` ∈ [0, 1]³ (pbrt-v4's `RGBToSpectrumTable::operator()`).
    pub fn lookup(&self, rgb: [f32; 3]) -> SigmoidPolynomial {
        let rgb = rgb.map(|v| v.clamp(0.0, 1.0));
        if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
            return SigmoidPolynomial::constant(rgb[0]);
        }
        let maxc = if rgb[0] > rgb[1] {
            if rgb[0] > rgb[2] { 0 } else { 2 }
        } else if rgb[1] > rgb[2] {
            1
        } else {
            2
        };
        let res = self.res;
        let z = rgb[maxc];
        let x = rgb[(maxc + 1) % 3] * (res - 1) as f32 / z;
        let y = rgb[(maxc + 2) % 3] * (res - 1) as f32 / z;
        let xi = (x as usize).min(res - 2);
        let yi = (y as usize).min(res - 2);
        let zi = self.z_nodes.partition_point(|n| *n < z).saturating_sub(1).min(res - 2);
        let (dx, dy) = (x - xi as f32, y - yi as f32);
        let dz = (z - self.z_nodes[zi]) / (self.z_nodes[zi + 1] - self.z_nodes[zi]);
        let columns = [
            [self.column(maxc, yi, xi), self.column(maxc, yi, xi + 1)],
            [self.column(maxc, yi + 1, xi), self.column(maxc, yi + 1, xi + 1)],
        ];
        let co = |ox: usize, oy: usize, oz: usize| columns[oy][ox][zi + oz];
        let lerp = |t: f32, a: [f32; 3], b: [f32; 3]| [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t);
        let c = lerp(
            dz,
            lerp(dy, lerp(dx, co(0, 0, 0), co(1, 0, 0)), lerp(dx, co(0, 1, 0), co(1, 1, 0))),
            lerp(dy, lerp(dx, co(0, 0, 1), co(1, 0, 1)), lerp(dx, co(0, 1, 1), co(1, 1, 1))),
        );
        SigmoidPolynomial { c0: c[0], c1: c[1], c2: c[2] }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectra::cie::integrate_xyz;

    /// The RGB of the reflectance spectrum `p` under the space's illuminant, by pbrt-v4's
    /// 1 nm sums (independent of the fit's 5 nm quadrature).
    fn round_trip(space: ColorSpace, p: &SigmoidPolynomial) -> DVec3 {
        let cs = rgb_color_space(space);
        let illum = |l: f64| cs.illuminant.eval(l);
        let xyz = integrate_xyz(|l| p.eval(l as f32) as f64 * illum(l)) / integrate_xyz(illum).y;
        cs.rgb_from_xyz(xyz)
    }

    const COLORS: [[f32; 3]; 8] = [
        [0.65, 0.1, 0.1],
        [0.1, 0.6, 0.15],
        [0.2, 0.3, 0.9],
        [0.9, 0.8, 0.05],
        [0.5, 0.45, 0.4],
        [0.02, 0.03, 0.01],
        [0.95, 0.2, 0.6],
        [0.3, 0.9, 0.95],
    ];

    #[test]
    fn gray_is_an_exact_constant() {
        let p = fit_sigmoid(ColorSpace::Srgb, [0.4; 3]);
        assert!(p.is_constant());
        assert!((p.eval(500.0) - 0.4).abs() < 1e-6);
        assert_eq!(fit_sigmoid(ColorSpace::Srgb, [0.0; 3]).eval(600.0), 0.0);
        assert_eq!(fit_sigmoid(ColorSpace::Srgb, [1.0; 3]).eval4(Vec4::splat(600.0)), Vec4::ONE);
    }

    #[test]
    fn exact_fits_round_trip_in_every_space() {
        for space in [ColorSpace::Srgb, ColorSpace::Rec2020, ColorSpace::Aces2065_1, ColorSpace::DciP3] {
            for rgb in COLORS {
                // The wider spaces' saturated colours have no reflectance spectrum at all (a
                // spectrum within [0, 1] cannot reach them): test those halfway to gray.
                let rgb = if space == ColorSpace::Srgb { rgb } else { rgb.map(|v| 0.5 * v + 0.25) };
                let p = fit_sigmoid(space, rgb);
                let back = round_trip(space, &p);
                let err = (back - DVec3::new(rgb[0] as f64, rgb[1] as f64, rgb[2] as f64)).abs().max_element();
                assert!(err < 2e-3, "{space:?} {rgb:?} -> {back} ({err})");
                // Reflectances stay within [0, 1].
                for l in (360..=830).step_by(10) {
                    let v = p.eval(l as f32);
                    assert!((0.0..=1.0).contains(&v), "{rgb:?} at {l}: {v}");
                }
            }
        }
    }

    #[test]
    fn eval4_matches_eval() {
        let p = fit_sigmoid(ColorSpace::Srgb, [0.65, 0.1, 0.1]);
        let l = Vec4::new(380.0, 455.5, 610.0, 800.0);
        let v = p.eval4(l);
        for i in 0..4 {
            assert!((v[i] - p.eval(l[i])).abs() < 1e-6);
        }
        assert!(p.max_value() >= v.max_element());
    }

    /// The four-lane evaluation keeps the exact constants 0 and 1 (±∞ polynomials).
    #[test]
    fn eval4_keeps_the_constants_exact() {
        let l = Vec4::new(360.0, 500.0, 700.0, 830.0);
        assert_eq!(SigmoidPolynomial::constant(0.0).eval4(l), Vec4::ZERO);
        assert_eq!(SigmoidPolynomial::constant(1.0).eval4(l), Vec4::ONE);
        assert_eq!(SigmoidPolynomial::constant(0.5).eval4(l), Vec4::splat(0.5));
    }

    #[test]
    fn table_lookups_match_exact_fits() {
        let table = SigmoidTable::get(ColorSpace::Srgb);
        let mut worst = 0.0f64;
        for r in 0..9 {
            for g in 0..9 {
                for b in 0..9 {
                    let rgb =
                        [r as f32 / 8.0 * 0.98 + 0.01, g as f32 / 8.0 * 0.98 + 0.01, b as f32 / 8.0 * 0.98 + 0.01];
                    let back = round_trip(ColorSpace::Srgb, &table.lookup(rgb));
                    let err = (back - DVec3::new(rgb[0] as f64, rgb[1] as f64, rgb[2] as f64)).abs().max_element();
                    worst = worst.max(err);
                }
            }
        }
        // Trilinear interpolation of the 32³ table costs at most 0.0065 near the gamut's corners
        // (components of 0.01); pbrt-v4's 64³ table, 0.002 (measured against exact fits).
        assert!(worst < 0.01, "worst table round trip {worst}");
    }
}
