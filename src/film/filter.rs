//! Pixel reconstruction filters, with pbrt-v4's definitions and its way of sampling them
//! (`filters.h`, `filters.cpp`; PBR 4th ed. §8.8).
//!
//! pbrt-v4 does not splat a sample onto neighbouring pixels: it importance-samples an offset
//! from the pixel centre with density proportional to |f| and carries the ratio f/pdf as the
//! sample's weight; the film divides the weighted sum of radiance by the sum of weights.

use std::f64::consts::PI;

use glam::Vec2;

use crate::film::filter_settings::FilterSettings;
use crate::sampling::warp::ONE_MINUS_EPSILON;

/// A filter offset and its weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterSample {
    /// Offset from the pixel centre, within the filter's radius.
    pub offset: Vec2,
    /// f(offset)/pdf(offset), up to a constant factor (see [`Filter::sample`]).
    pub weight: f32,
}

/// The filter function, each a product of two 1D factors as in pbrt-v4.
#[derive(Clone, Debug)]
enum Kernel {
    Box {
        radius: Vec2,
    },
    Gaussian {
        radius: Vec2,
        sigma: f32,
        /// The Gaussian at the radius, subtracted so the filter reaches 0 there.
        exp: Vec2,
    },
    Triangle {
        radius: Vec2,
    },
    Mitchell {
        radius: Vec2,
        b: f32,
        c: f32,
    },
    LanczosSinc {
        radius: Vec2,
        tau: f32,
    },
}

/// Normal density with mean 0 and deviation `sigma` (pbrt-v4's `Gaussian`).
fn gaussian(x: f32, sigma: f32) -> f32 {
    (-(x * x) / (2.0 * sigma * sigma)).exp() / (2.0 * std::f32::consts::PI * sigma * sigma).sqrt()
}

/// The Mitchell-Netravali cubic on [-2, 2] ("Reconstruction Filters in Computer Graphics",
/// SIGGRAPH 1988), as pbrt-v4 writes it.
fn mitchell_1d(x: f32, b: f32, c: f32) -> f32 {
    let x = x.abs();
    if x <= 1.0 {
        ((12.0 - 9.0 * b - 6.0 * c) * x * x * x + (-18.0 + 12.0 * b + 6.0 * c) * x * x + (6.0 - 2.0 * b)) * (1.0 / 6.0)
    } else if x <= 2.0 {
        ((-b - 6.0 * c) * x * x * x + (6.0 * b + 30.0 * c) * x * x + (-12.0 * b - 48.0 * c) * x + (8.0 * b + 24.0 * c))
            * (1.0 / 6.0)
    } else {
        0.0
    }
}

/// sin(πx)/(πx), with pbrt-v4's guard near 0.
fn sinc(x: f32) -> f32 {
    let px = std::f32::consts::PI * x;
    if 1.0 + px * px == 1.0 { 1.0 } else { px.sin() / px }
}

/// Sinc windowed by a wider sinc (Lanczos), zero past `radius`.
fn windowed_sinc(x: f32, radius: f32, tau: f32) -> f32 {
    if x.abs() > radius { 0.0 } else { sinc(x) * sinc(x / tau) }
}

/// pbrt-v4's `SampleLinear`: x in [0, 1) with density proportional to lerp(x, a, b).
fn sample_linear(u: f32, a: f32, b: f32) -> f32 {
    if u == 0.0 && a == 0.0 {
        return 0.0;
    }
    let x = u * (a + b) / (a + ((1.0 - u) * a * a + u * b * b).sqrt());
    x.min(ONE_MINUS_EPSILON)
}

/// pbrt-v4's `SampleTent`: x in [-radius, radius] with density proportional to radius - |x|;
/// the first half of u picks the side.
fn sample_tent(u: f32, radius: f32) -> f32 {
    if u < 0.5 {
        let u = (u / 0.5).min(ONE_MINUS_EPSILON);
        -radius + radius * sample_linear(u, 0.0, 1.0)
    } else {
        let u = ((u - 0.5) / 0.5).min(ONE_MINUS_EPSILON);
        radius * sample_linear(u, 1.0, 0.0)
    }
}

/// Composite Simpson's rule in f64 over `n` (even) intervals.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let inner: f64 = (1..n).map(|i| f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 }).sum();
    (f(a) + f(b) + inner) * h / 3.0
}

impl Kernel {
    fn radius(&self) -> Vec2 {
        match *self {
            Kernel::Box { radius }
            | Kernel::Gaussian { radius, .. }
            | Kernel::Triangle { radius }
            | Kernel::Mitchell { radius, .. }
            | Kernel::LanczosSinc { radius, .. } => radius,
        }
    }

    fn evaluate(&self, p: Vec2) -> f32 {
        match *self {
            Kernel::Box { radius } => {
                if p.x.abs() <= radius.x && p.y.abs() <= radius.y {
                    1.0
                } else {
                    0.0
                }
            }
            Kernel::Triangle { radius } => (radius.x - p.x.abs()).max(0.0) * (radius.y - p.y.abs()).max(0.0),
            Kernel::Gaussian { .. } | Kernel::Mitchell { .. } | Kernel::LanczosSinc { .. } => {
                let f = self.factors(p);
                f.x * f.y
            }
        }
    }

    /// The 1D factors along x and y of a tabulated filter (every such filter of pbrt-v4's is
    /// a product of two); `evaluate` is their product.
    fn factors(&self, p: Vec2) -> Vec2 {
        match *self {
            Kernel::Gaussian { sigma, exp, .. } => {
                Vec2::new((gaussian(p.x, sigma) - exp.x).max(0.0), (gaussian(p.y, sigma) - exp.y).max(0.0))
            }
            Kernel::Mitchell { radius, b, c } => {
                Vec2::new(mitchell_1d(2.0 * p.x / radius.x, b, c), mitchell_1d(2.0 * p.y / radius.y, b, c))
            }
            Kernel::LanczosSinc { radius, tau } => {
                Vec2::new(windowed_sinc(p.x, radius.x, tau), windowed_sinc(p.y, radius.y, tau))
            }
            Kernel::Box { .. } | Kernel::Triangle { .. } => unreachable!("box and triangle are sampled in closed form"),
        }
    }

    /// ∫ f over the filter's support.
    fn integral(&self) -> f32 {
        match *self {
            Kernel::Box { radius } => 4.0 * radius.x * radius.y,
            Kernel::Triangle { radius } => radius.x * radius.x * radius.y * radius.y,
            // Mitchell-Netravali cubics integrate to 1 over [-2, 2] for every B and C.
            Kernel::Mitchell { radius, .. } => radius.x * radius.y / 4.0,
            // pbrt-v4 integrates the Gaussian with erf and the sinc by Monte Carlo; both are
            // products of smooth 1D factors, so Simpson's rule is exact to f32 precision.
            Kernel::Gaussian { radius, sigma, exp } => {
                let axis = |r: f32, e: f32| {
                    simpson(|x| gaussian(x as f32, sigma) as f64, -r as f64, r as f64, 4096) - 2.0 * r as f64 * e as f64
                };
                (axis(radius.x, exp.x) * axis(radius.y, exp.y)) as f32
            }
            Kernel::LanczosSinc { radius, tau } => {
                let axis = |r: f32| {
                    simpson(
                        |x| {
                            let px = PI * x;
                            let s = |t: f64| if t == 0.0 { 1.0 } else { t.sin() / t };
                            s(px) * s(px / tau as f64)
                        },
                        -r as f64,
                        r as f64,
                        4096,
                    )
                };
                (axis(radius.x) * axis(radius.y)) as f32
            }
        }
    }
}

/// pbrt-v4's `FilterSampler`: |f| tabulated at cell centres, 32 cells per unit of radius
/// (cells 1/16 pixel wide), sampled as a piecewise-constant 2D distribution. pbrt-v4 samples
/// its 2D table by a marginal and a conditional search; every filter it tabulates is a
/// product f(x) f(y), so the table is the product of two 1D tables and the same distribution
/// is sampled one axis at a time, each cell found by counting the CDF entries at or below u
/// (branch-free, where the binary searches' mispredicted branches made the Gaussian filter
/// cost 8 % of an emissive-grid render).
#[derive(Clone, Debug)]
struct TabulatedSampler {
    x: AxisTable,
    y: AxisTable,
}

/// One axis of a [`TabulatedSampler`]: f at the cell centres over [−radius, radius].
#[derive(Clone, Debug)]
struct AxisTable {
    f: Vec<f32>,
    /// CDF of |f| at the cells' inner boundaries (1..n; 0 and 1 are implied).
    cdf: Vec<f32>,
    /// ∫|f| of the table.
    integral: f32,
    radius: f32,
}

impl AxisTable {
    fn new(radius: f32, f: impl Fn(f32) -> f32) -> AxisTable {
        let n = ((32.0 * radius) as usize).max(1);
        let f: Vec<f32> = (0..n).map(|i| f(-radius + 2.0 * radius * ((i as f32 + 0.5) / n as f32))).collect();
        let sum: f64 = f.iter().map(|v| v.abs() as f64).sum();
        let mut acc = 0.0f64;
        let cdf = f[..n - 1]
            .iter()
            .map(|v| {
                acc += v.abs() as f64;
                if sum > 0.0 { (acc / sum) as f32 } else { 0.0 }
            })
            .collect();
        AxisTable { f, cdf, integral: (sum * 2.0 * radius as f64 / n as f64) as f32, radius }
    }

    /// A position in [−radius, radius] with density proportional to |f|, its cell's f, and
    /// its density.
    #[inline]
    fn sample(&self, u: f32) -> (f32, f32, f32) {
        let u = if u >= 0.0 { u.min(ONE_MINUS_EPSILON) } else { 0.0 };
        let n = self.f.len();
        // The cell whose CDF interval holds u (a zero cell's interval is empty and is passed).
        let o = self.cdf.iter().map(|&c| (c <= u) as u32).sum::<u32>() as usize;
        let lo = if o == 0 { 0.0 } else { self.cdf[o - 1] };
        let hi = if o + 1 == n { 1.0 } else { self.cdf[o] };
        let du = if hi > lo { ((u - lo) / (hi - lo)).clamp(0.0, ONE_MINUS_EPSILON) } else { 0.0 };
        let t = (o as f32 + du) / n as f32;
        let x = (-self.radius + 2.0 * self.radius * t).min(self.radius);
        let f = self.f[o];
        let pdf = if self.integral > 0.0 { f.abs() / self.integral } else { 1.0 / (2.0 * self.radius) };
        (x, f, pdf)
    }
}

impl TabulatedSampler {
    fn new(kernel: &Kernel) -> TabulatedSampler {
        let r = kernel.radius();
        TabulatedSampler {
            x: AxisTable::new(r.x, |x| kernel.factors(Vec2::new(x, 0.0)).x),
            y: AxisTable::new(r.y, |y| kernel.factors(Vec2::new(0.0, y)).y),
        }
    }

    fn sample(&self, u: Vec2) -> FilterSample {
        let (x, fx, pdf_x) = self.x.sample(u.x);
        let (y, fy, pdf_y) = self.y.sample(u.y);
        let pdf = pdf_x * pdf_y;
        FilterSample { offset: Vec2::new(x, y), weight: if pdf > 0.0 { fx * fy / pdf } else { 0.0 } }
    }
}

/// A pixel reconstruction filter: box, Gaussian, triangle, Mitchell-Netravali or
/// Lanczos-windowed sinc, each defined exactly as in pbrt-v4.
#[derive(Clone, Debug)]
pub struct Filter {
    kernel: Kernel,
    /// For the filters not sampled in closed form.
    table: Option<TabulatedSampler>,
}

impl Filter {
    /// The filter `settings` describe (radii default as in pbrt-v4: box 0.5, Gaussian 1.5,
    /// triangle 2, Mitchell 2, sinc 4).
    pub fn new(settings: &FilterSettings) -> Filter {
        let v = |r: [f32; 2]| Vec2::from(r);
        let kernel = match *settings {
            FilterSettings::Box { radius } => Kernel::Box { radius: v(radius) },
            FilterSettings::Gaussian { radius, sigma } => Kernel::Gaussian {
                radius: v(radius),
                sigma,
                exp: Vec2::new(gaussian(radius[0], sigma), gaussian(radius[1], sigma)),
            },
            FilterSettings::Triangle { radius } => Kernel::Triangle { radius: v(radius) },
            FilterSettings::Mitchell { radius, b, c } => Kernel::Mitchell { radius: v(radius), b, c },
            FilterSettings::LanczosSinc { radius, tau } => Kernel::LanczosSinc { radius: v(radius), tau },
        };
        let table = match kernel {
            Kernel::Box { .. } | Kernel::Triangle { .. } => None,
            _ => Some(TabulatedSampler::new(&kernel)),
        };
        Filter { kernel, table }
    }

    /// Half-width of the support along x and y, in pixels.
    pub fn radius(&self) -> Vec2 {
        self.kernel.radius()
    }

    /// The filter's value at offset `p` from the pixel centre (0 outside the radius; the
    /// Mitchell and sinc filters go negative).
    pub fn evaluate(&self, p: Vec2) -> f32 {
        self.kernel.evaluate(p)
    }

    /// ∫ f over the support (pbrt-v4's `Integral`).
    pub fn integral(&self) -> f32 {
        self.kernel.integral()
    }

    /// An offset for a camera ray, from `u` in [0, 1)², with density proportional to |f|.
    ///
    /// As in pbrt-v4: the box and triangle filters are sampled exactly and weigh 1. The
    /// others are sampled from the table, and weigh the tabulated f of the chosen cell over
    /// the table's density, i.e. ±∫|f|: constant for the positive Gaussian, negative where
    /// Mitchell and sinc lobes are. Either way the mean weight is proportional to ∫f, and the
    /// film's division by the summed weights removes the constant.
    pub fn sample(&self, u: Vec2) -> FilterSample {
        match (&self.kernel, &self.table) {
            (_, Some(table)) => table.sample(u),
            (Kernel::Triangle { radius }, None) => {
                FilterSample { offset: Vec2::new(sample_tent(u.x, radius.x), sample_tent(u.y, radius.y)), weight: 1.0 }
            }
            (kernel, None) => {
                let r = kernel.radius();
                FilterSample { offset: -r + 2.0 * r * u, weight: 1.0 }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::chi_square::TestRng;

    fn filter(directive: &str) -> Filter {
        let scene = nimbus_parser::load_str(&format!("{directive}\nWorldBegin\n"), "t.pbrt").expect("scene parses");
        Filter::new(&FilterSettings::from_entity(&scene.filter).expect("filter reads"))
    }

    fn close(a: f32, b: f64) -> bool {
        (a as f64 - b).abs() <= 1e-5 * (1.0 + b.abs())
    }

    #[test]
    fn default_radii_match_pbrt() {
        for (name, r) in [("box", 0.5), ("gaussian", 1.5), ("triangle", 2.0), ("mitchell", 2.0), ("sinc", 4.0)] {
            assert_eq!(filter(&format!("PixelFilter \"{name}\"")).radius(), Vec2::splat(r));
        }
        // The scene default is pbrt's Gaussian.
        assert_eq!(filter("").radius(), Vec2::splat(1.5));
        let f = filter("PixelFilter \"box\" \"float xradius\" 1 \"float yradius\" 2");
        assert_eq!(f.radius(), Vec2::new(1.0, 2.0));
    }

    #[test]
    fn evaluate_matches_closed_forms() {
        let b = filter("PixelFilter \"box\"");
        assert_eq!(b.evaluate(Vec2::new(0.5, -0.5)), 1.0);
        assert_eq!(b.evaluate(Vec2::new(0.51, 0.0)), 0.0);

        // Gaussian, sigma 1/2, radius 3/2: (g(x) - g(3/2)) (g(y) - g(3/2)).
        let g = |x: f64| (-2.0 * x * x).exp() * (2.0 / PI).sqrt();
        let f = filter("PixelFilter \"gaussian\"");
        assert!(close(f.evaluate(Vec2::ZERO), (g(0.0) - g(1.5)).powi(2)));
        assert!(close(f.evaluate(Vec2::new(1.0, 0.0)), (g(1.0) - g(1.5)) * (g(0.0) - g(1.5))));
        assert_eq!(f.evaluate(Vec2::new(1.6, 0.0)), 0.0);

        let t = filter("PixelFilter \"triangle\"");
        assert!(close(t.evaluate(Vec2::new(0.5, -1.0)), 1.5));
        assert_eq!(t.evaluate(Vec2::new(2.5, 0.0)), 0.0);

        // Mitchell with B = C = 1/3 and radius 2: k(0) = 8/9, k(1) = 1/18, k(3/2) = -5/144.
        let m = filter("PixelFilter \"mitchell\"");
        assert!(close(m.evaluate(Vec2::ZERO), 64.0 / 81.0));
        assert!(close(m.evaluate(Vec2::new(1.0, 0.0)), 8.0 / 9.0 / 18.0));
        assert!(close(m.evaluate(Vec2::new(0.0, 1.5)), -8.0 / 9.0 * 5.0 / 144.0));
        assert_eq!(m.evaluate(Vec2::new(0.0, 2.1)), 0.0);

        // Lanczos: sinc(x) sinc(x / 3) on radius 4.
        let s = filter("PixelFilter \"sinc\"");
        let sinc = |x: f64| (PI * x).sin() / (PI * x);
        assert!(close(s.evaluate(Vec2::ZERO), 1.0));
        assert!(close(s.evaluate(Vec2::new(0.5, 0.0)), sinc(0.5) * sinc(0.5 / 3.0)));
        assert!(close(s.evaluate(Vec2::new(1.5, 2.5)), sinc(1.5) * sinc(0.5) * sinc(2.5) * sinc(2.5 / 3.0)));
        assert_eq!(s.evaluate(Vec2::new(4.5, 0.0)), 0.0);
    }

    /// ∫ f g over the support by the midpoint rule in f64, on a fine grid.
    fn quadrature(f: &Filter, g: impl Fn(Vec2) -> f64) -> f64 {
        let r = f.radius();
        let n = 800;
        let cell = Vec2::new(2.0 * r.x / n as f32, 2.0 * r.y / n as f32);
        let mut sum = 0.0;
        for j in 0..n {
            for i in 0..n {
                let p = -r + cell * Vec2::new(i as f32 + 0.5, j as f32 + 0.5);
                sum += f.evaluate(p) as f64 * g(p);
            }
        }
        sum * (cell.x * cell.y) as f64
    }

    #[test]
    fn sampled_weights_average_to_the_integral() {
        let scenes = [
            "PixelFilter \"box\"",
            "PixelFilter \"triangle\" \"float xradius\" 1.5",
            "PixelFilter \"gaussian\"",
            "PixelFilter \"gaussian\" \"float sigma\" 0.7 \"float yradius\" 2",
            "PixelFilter \"mitchell\"",
            "PixelFilter \"mitchell\" \"float B\" 0 \"float C\" 0.5 \"float xradius\" 1",
            "PixelFilter \"sinc\"",
            "PixelFilter \"sinc\" \"float tau\" 2 \"float xradius\" 3",
        ];
        let n = 100_000;
        for (k, scene) in scenes.iter().enumerate() {
            let f = filter(scene);
            let r = f.radius();
            let exact = f.table.is_none();
            // The integral pbrt reports agrees with quadrature.
            let integral = quadrature(&f, |_| 1.0);
            assert!((f.integral() as f64 - integral).abs() < 1e-3 * integral, "{scene}");
            // A test function to check where samples go, not only their total weight.
            let g = |p: Vec2| 1.0 + (p.x * p.x) as f64 + 0.3 * p.y as f64;
            let fg = quadrature(&f, g);
            let abs_integral =
                quadrature(&Filter::new(&FilterSettings::Box { radius: r.into() }), |p| f.evaluate(p).abs() as f64);
            let mut rng = TestRng::new(k as u64 + 10);
            let (mut sum_w, mut sum_w2, mut sum_wg, mut sum_wg2) = (0.0, 0.0, 0.0, 0.0);
            for _ in 0..n {
                let s = f.sample(Vec2::new(rng.uniform(), rng.uniform()));
                assert!(s.offset.abs().cmple(r).all(), "{scene}: {:?}", s.offset);
                assert!(s.weight.is_finite());
                if exact {
                    assert_eq!(s.weight, 1.0);
                } else {
                    // pbrt's weights are ±∫|f| (of the table).
                    assert!((s.weight.abs() as f64 - abs_integral).abs() < 2e-3 * abs_integral);
                }
                let (w, wg) = (s.weight as f64, s.weight as f64 * g(s.offset));
                sum_w += w;
                sum_w2 += w * w;
                sum_wg += wg;
                sum_wg2 += wg * wg;
            }
            let nf = n as f64;
            // Box and triangle weigh 1: the mean weight is ∫f/∫f.
            let scale = if exact { 1.0 / integral } else { 1.0 };
            let sigma = |s: f64, s2: f64| ((s2 / nf - (s / nf).powi(2)).max(0.0) / nf).sqrt();
            // 3σ, plus the table's midpoint-rule error (cells 1/16 pixel wide).
            let tol = |expected: f64, sigma: f64| 3.0 * sigma + 2e-3 * expected.abs();
            let mean_w = sum_w / nf;
            assert!(
                (mean_w - integral * scale).abs() <= tol(integral * scale, sigma(sum_w, sum_w2)),
                "{scene}: mean weight {mean_w} vs {}",
                integral * scale
            );
            let mean_wg = sum_wg / nf;
            assert!(
                (mean_wg - fg * scale).abs() <= tol(fg * scale, sigma(sum_wg, sum_wg2)),
                "{scene}: mean weighted g {mean_wg} vs {}",
                fg * scale
            );
        }
    }

    /// Sampled one axis at a time, the table gives the offsets pbrt-v4's 2D table search
    /// gives (a marginal over rows from u.y, then the row's conditional from u.x), and the
    /// same weights.
    #[test]
    fn axis_tables_sample_as_the_2d_table() {
        use crate::sampling::distribution::PiecewiseConstant2D;
        for scene in
            ["PixelFilter \"gaussian\" \"float yradius\" 1", "PixelFilter \"mitchell\"", "PixelFilter \"sinc\""]
        {
            let f = filter(scene);
            let r = f.radius();
            let (nx, ny) = ((32.0 * r.x) as usize, (32.0 * r.y) as usize);
            let cells: Vec<f32> = (0..nx * ny)
                .map(|i| {
                    let t = Vec2::new(((i % nx) as f32 + 0.5) / nx as f32, ((i / nx) as f32 + 0.5) / ny as f32);
                    f.evaluate(-r + 2.0 * r * t)
                })
                .collect();
            let table = PiecewiseConstant2D::new(&cells, nx, ny, -r, r);
            let mut rng = TestRng::new(5);
            for _ in 0..20000 {
                let u = Vec2::new(rng.uniform(), rng.uniform());
                let (a, b) = (f.sample(u), table.sample(u));
                let weight = cells[b.cell.y as usize * nx + b.cell.x as usize] / b.pdf;
                assert!((a.offset - b.point).abs().max_element() < 1e-4, "{scene}: {a:?} vs {:?} at {u}", b.point);
                assert!((a.weight - weight).abs() < 1e-4 * weight.abs(), "{scene}: weight {} vs {weight}", a.weight);
            }
        }
    }

    #[test]
    fn tent_sampling_is_monotone_and_in_range() {
        let mut last = -3.0;
        for i in 0..1000 {
            let x = sample_tent(i as f32 / 1000.0, 2.0);
            assert!((-2.0..=2.0).contains(&x) && x >= last);
            last = x;
        }
    }
}
