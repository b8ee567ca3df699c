//! Helpers shared by the end-to-end tests.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use nimbus::imageio::Image;

/// The pbrt-v4 parity scenes shipped beside the repository.
pub fn reference_scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes/pbrt-v4-references/scenes")
}

/// All `.pbrt` files of the parity suite, sorted.
pub fn reference_scenes() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(reference_scenes_dir())
        .expect("pbrt-scenes/pbrt-v4-references/scenes is in the repository")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "pbrt"))
        .collect();
    v.sort();
    v
}

/// Runs the `nimbus` binary.
pub fn nimbus(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_nimbus")).args(args).output().expect("nimbus runs")
}

/// A test's scratch directory, removed with everything in it when the test ends (also when
/// it fails).
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A fresh directory for one test's files.
pub fn scratch_dir(test: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("nimbus-test-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Scratch(dir)
}

/// A cube [-1, 1]³ bounding medium `name` through an `interface` surface, in its own attribute
/// block: the media tests' standard volume.
pub fn medium_cube(name: &str) -> String {
    format!(
        r#"AttributeBegin
  MediumInterface "{name}" ""
  Material "interface"
  Shape "trianglemesh" "integer indices" [ 0 2 1 0 3 2  4 5 6 4 6 7  0 1 5 0 5 4  3 7 6 3 6 2  0 4 7 0 7 3  1 2 6 1 6 5 ]
    "point3 P" [ -1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1 ]
AttributeEnd"#
    )
}

/// Camera, sampler and 16×16 film looking down −z at the unit cube's centre (the central ray
/// sees through [-1, 1]³), rendered by `integrator` with `maxdepth` `depth`.
pub fn media_header(integrator: &str, spp: u32, depth: u32) -> String {
    format!(
        r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "orthographic" "float screenwindow" [-0.5 0.5 -0.5 0.5]
Sampler "sobol" "integer pixelsamples" {spp}
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Integrator "{integrator}" "integer maxdepth" {depth}
"#
    )
}

/// `n`³ copies of the voxel value(s) `v`, as a grid parameter's text.
pub fn grid_values(n: usize, v: &str) -> String {
    vec![v; n * n * n].join(" ")
}

/// Parses `text` and builds its scene and method; a failure panics with the located error.
pub fn load_scene(text: &str, opts: &nimbus::scene::BuildOptions) -> nimbus::setup::Setup {
    let desc = nimbus::parser::load_str(text, "test.pbrt").unwrap_or_else(|e| panic!("{e}"));
    nimbus::setup::build(&desc, opts).unwrap_or_else(|e| panic!("{e}"))
}

/// Renders `scene` with `integrator` at the scene's spp.
pub fn render_with(scene: &nimbus::scene::Scene, integrator: &dyn nimbus::integrators::Integrator) -> Image {
    let options = nimbus::render::RenderOptions { time_budget: None, quiet: true };
    nimbus::render::render(scene, integrator, &options).image
}

/// Renders the set-up scene with its own method.
pub fn render_scene(setup: &nimbus::setup::Setup) -> Image {
    render_with(&setup.scene, setup.prepare().unwrap().integrator.as_ref())
}

/// Per-channel image mean and its standard error from the pixel spread. The spread is noise
/// only where every pixel has the same expected value (a white furnace, a uniform slab): use
/// it for analytic uniform images, and [`Estimate`] to compare images with structure.
pub fn channel_stats(img: &Image) -> [(f64, f64); 3] {
    let n = img.pixels.len() as f64;
    let mut out = [(0.0, 0.0); 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mean = img.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / n;
        let var = img.pixels.iter().map(|p| (p[c] as f64 - mean).powi(2)).sum::<f64>() / (n - 1.0);
        *o = (mean, (var / n).sqrt());
    }
    out
}

/// Every channel's image mean within 4 standard errors of `expected`, plus 0.2 % for the
/// answer's own rounding (film RGB of a spectrum integrated at 1-nm steps, f32 accumulation).
/// For analytic images whose every pixel expects the same value (see [`channel_stats`]).
pub fn assert_channels(img: &Image, expected: [f64; 3], what: &str) {
    for (c, (mean, se)) in channel_stats(img).iter().enumerate() {
        assert!(
            (mean - expected[c]).abs() < 4.0 * se + 2e-3 * expected[c].max(1e-3),
            "{what}: channel {c} mean {mean} ± {se}, expected {} (4 standard errors + 0.2 % rounding of the answer)",
            expected[c]
        );
    }
}

/// An estimate of an image's mean per channel with its standard error, from renders of one
/// estimator with independent seeds: how each 8×8 block's mean differs between the seeds is
/// the estimator's noise alone (the image's structure is the same in every render and
/// cancels), and blocks rather than pixels count the noise that neighbouring pixels share
/// (a graph method's clusters span pixels).
#[derive(Clone, Copy, Debug)]
pub struct Estimate {
    /// Image mean per channel over the renders.
    pub mean: [f64; 3],
    /// Its standard error per channel.
    pub se: [f64; 3],
}

impl Estimate {
    /// From `images`, renders of the same estimator with independent seeds (at least two).
    pub fn from_seeds(images: &[Image]) -> Estimate {
        let k = images.len();
        assert!(k >= 2, "a noise estimate needs renders with two seeds or more");
        let (w, h) = (images[0].width, images[0].height);
        assert!(images.iter().all(|i| (i.width, i.height) == (w, h)), "renders of different sizes");
        let n = (w * h) as f64;
        let mut out = Estimate { mean: [0.0; 3], se: [0.0; 3] };
        for c in 0..3 {
            let mut var = 0.0;
            for by in (0..h).step_by(8) {
                for bx in (0..w).step_by(8) {
                    let (x1, y1) = ((bx + 8).min(w), (by + 8).min(h));
                    // Each render's block sum, as a share of the image mean.
                    let sums: Vec<f64> = images
                        .iter()
                        .map(|img| {
                            (by..y1)
                                .flat_map(|y| (bx..x1).map(move |x| (x, y)))
                                .map(|(x, y)| img.get(x, y)[c] as f64)
                                .sum::<f64>()
                                / n
                        })
                        .collect();
                    let m = sums.iter().sum::<f64>() / k as f64;
                    out.mean[c] += m;
                    var += sums.iter().map(|s| (s - m).powi(2)).sum::<f64>() / (k - 1) as f64 / k as f64;
                }
            }
            out.se[c] = var.sqrt();
        }
        out
    }

    /// A reference image rendered by an estimator with `noise` per sample as `test`'s, at
    /// `spp` where `test` took `test_spp` per render: its standard error is `test`'s scaled to
    /// the reference's sample count.
    pub fn reference(img: &Image, spp: f64, test: &Estimate, renders: usize, test_spp: f64) -> Estimate {
        let mean = img.mean();
        let scale = (renders as f64 * test_spp / spp).sqrt();
        Estimate { mean: [0, 1, 2].map(|c| mean[c] as f64), se: test.se.map(|s| s * scale) }
    }
}

/// The film's f32 accumulation of thousands of samples rounds a pixel by up to this share of
/// its value: a noiseless region (sky seen directly) of a render and of a reference rendered
/// at another sample count differ by that much.
pub const F32_ROUNDING: f64 = 1e-5;

/// `test` against `reference`, every channel: the means within 4 standard errors of their
/// difference plus `bias` (relative to the reference's mean), the method's stated bias bound,
/// which `bias_source` names, and F32_ROUNDING. Returns the worst channel's relative
/// difference.
pub fn assert_agree(what: &str, test: &Estimate, reference: &Estimate, bias: f64, bias_source: &str) -> f64 {
    let mut worst = 0.0f64;
    for c in 0..3 {
        let (t, r) = (test.mean[c], reference.mean[c]);
        let se = (test.se[c].powi(2) + reference.se[c].powi(2)).sqrt();
        let tol = 4.0 * se + (bias + F32_ROUNDING) * r.abs();
        assert!(
            (t - r).abs() <= tol,
            "{what}: channel {c} mean {t:.6} against {r:.6} ({:+.2} %): more than 4 standard errors ({se:.2e}) \
             plus the stated bias bound {:.2} % ({bias_source})",
            100.0 * (t / r - 1.0),
            100.0 * bias
        );
        if r != 0.0 {
            worst = if (t / r - 1.0).abs() > worst.abs() { t / r - 1.0 } else { worst };
        }
    }
    worst
}

/// The film RGB (pbrt-v4's default `cie1931` sensor, sRGB output) of radiance spectrum `f`:
/// the analytic answer for spectral transport where a light's spectrum reaches the camera
/// through known spectral factors.
pub fn film_rgb(f: impl Fn(f32) -> f32) -> [f64; 3] {
    let sensor = nimbus::spectra::PixelSensor::new("cie1931", 0.0, 100.0, 1.0, nimbus::parser::ColorSpace::Srgb)
        .expect("the default sensor exists");
    sensor.film_rgb(|l| f64::from(f(l as f32))).as_dvec3().to_array()
}

/// Build options forcing RGB (`false`) or spectral (`true`) transport.
pub fn transport(spectral: bool) -> nimbus::scene::BuildOptions {
    use nimbus::scene::transport::SpectralMode;
    nimbus::scene::BuildOptions {
        spectral: Some(if spectral { SpectralMode::On } else { SpectralMode::Off }),
        ..Default::default()
    }
}

/// pbrt-v4's samplers nimbus has, at 16 spp.
pub const SAMPLERS: [&str; 7] = [
    r#"Sampler "independent" "integer pixelsamples" 16"#,
    r#"Sampler "stratified" "integer xsamples" 4 "integer ysamples" 4"#,
    r#"Sampler "sobol" "integer pixelsamples" 16"#,
    r#"Sampler "zsobol" "integer pixelsamples" 16"#,
    r#"Sampler "halton" "integer pixelsamples" 16"#,
    r#"Sampler "paddedsobol" "integer pixelsamples" 16"#,
    r#"Sampler "pmj02bn" "integer pixelsamples" 16"#,
];

/// pbrt-v4's analytic scene: the inside of a reversed unit sphere of diffuse albedo 0.5 with
/// `light`, seen through a 32×32 film by `integrator` (maxdepth 30), once per sampler.
pub fn reversed_sphere_images(integrator: &str, light: &str) -> Vec<(&'static str, Image)> {
    SAMPLERS
        .iter()
        .map(|sampler| {
            let text = format!(
                r#"LookAt 0 0 0  0 0 1  0 1 0
Camera "perspective" "float fov" 45
{sampler}
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Integrator "{integrator}" "integer maxdepth" 30
WorldBegin
{light}
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
ReverseOrientation
Shape "sphere" "float radius" 1"#
            );
            (*sampler, render_scene(&load_scene(&text, &nimbus::scene::BuildOptions::default())))
        })
        .collect()
}

/// The per-pixel difference a − b: its mean over pixels and channels and the standard error
/// of that mean. Both images estimate the same pixels, so the mean difference is 0 in
/// expectation and the spread of the differences is its noise.
pub fn mean_difference(a: &Image, b: &Image) -> (f64, f64) {
    let diff: Vec<f64> =
        a.pixels.iter().zip(&b.pixels).map(|(x, y)| ((*x - *y).x + (*x - *y).y + (*x - *y).z) as f64 / 3.0).collect();
    let n = diff.len() as f64;
    let md = diff.iter().sum::<f64>() / n;
    let sd = (diff.iter().map(|d| (d - md) * (d - md)).sum::<f64>() / (n - 1.0) / n).sqrt();
    (md, sd)
}
