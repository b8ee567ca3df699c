//! Volume path graphs: a cluster of one is volpath, in either representation; the image does
//! not depend on the thread count; the method's energy against volpath, with its bias measured.

use crate::common::{channel_stats, load_scene, render_scene, render_with, transport};
use nimbus::imageio::Image;
use nimbus::integrators::common::PathConfig;
use nimbus::integrators::volpath::VolPath;
use nimbus::scene::BuildOptions;

/// A cube (side 2) of a forward-scattering medium with a `sigma_s` spectrum, over a diffuse
/// floor, lit by a distant light, a sky and a small emitter seen through the cube, rendered
/// by `integrator` with `params`.
fn scene_text(integrator: &str, params: &str, sigma_s: &str) -> String {
    format!(
        r#"LookAt 0 1 6  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Sampler "zsobol" "integer pixelsamples" 4
Integrator "{integrator}" "integer maxdepth" 20 {params}
WorldBegin
LightSource "distant" "point3 from" [0.3 1 0.2] "point3 to" [0 0 0] "rgb L" [2 2 2]
LightSource "infinite" "rgb L" [0.2 0.25 0.4]
MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_s" [{sigma_s}] "rgb sigma_a" [0.05 0.05 0.05]
  "float g" 0.5
AttributeBegin
  Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
  Shape "trianglemesh" "point3 P" [-4 -1 -4  4 -1 -4  4 -1 4  -4 -1 4] "integer indices" [0 2 1 0 3 2]
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [3 3 3]
  Material "diffuse" "rgb reflectance" [0 0 0]
  Shape "trianglemesh" "point3 P" [-0.4 0 -1.5  0.4 0 -1.5  0.4 0.8 -1.5  -0.4 0.8 -1.5] "integer indices" [0 1 2 0 2 3]
AttributeEnd
AttributeBegin
  MediumInterface "m" ""
  Material "interface"
  Shape "trianglemesh"
    "point3 P" [-1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1]
    "integer indices" [0 2 1 0 3 2  4 5 6 4 6 7  0 1 5 0 5 4  3 7 6 3 6 2  0 4 7 0 7 3  1 2 6 1 6 5]
AttributeEnd
"#
    )
}

fn max_abs_diff(a: &Image, b: &Image) -> f32 {
    a.pixels.iter().zip(&b.pixels).map(|(p, q)| (*p - *q).abs().max_element()).fold(0.0, f32::max)
}

/// K = 1 makes every shading point its own cluster: aggregation then gives back each path's
/// own estimates, so the image is volpath's at the same seed (to float rounding), in RGB and
/// in spectral transport, with surfaces (diffuse floor) and media vertices; volpath here
/// estimates the light seen through the medium as the graph's paths do
/// (`PathConfig::camera_line`). (In chromatic media
/// the graph's paths apply spectral MIS per segment, a different unbiased estimator: see
/// `chromatic_media_keep_the_mean`.)
#[test]
fn cluster_size_one_is_volpath() {
    for spectral in [false, true] {
        let opts = BuildOptions { seed: Some(3), ..transport(spectral) };
        let graph =
            load_scene(&scene_text("pathgraph", r#""integer clustersize" 1 "integer iterations" 4"#, "2 2 2"), &opts);
        let volpath = load_scene(&scene_text("volpath", "", "2 2 2"), &opts);
        let line = VolPath::with_config(PathConfig { camera_line: true, ..PathConfig::volpath(20, false) });
        let (g, v) = (render_scene(&graph), render_with(&volpath, &line));
        let peak = v.pixels.iter().map(|p| p.max_element()).fold(0.0, f32::max);
        let d = max_abs_diff(&g, &v);
        assert!(peak > 0.05 && d <= 1e-4 * peak, "spectral {spectral}: max difference {d} (peak {peak})");
    }
}

/// Centres, clusters and the solve are fixed by the seed: one thread and two give the same
/// image, bit for bit.
#[test]
fn same_image_at_any_thread_count() {
    let scene =
        load_scene(&scene_text("pathgraph", "", "2 2 2"), &BuildOptions { seed: Some(5), ..Default::default() });
    let render = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| render_scene(&scene))
    };
    let (one, two) = (render(1), render(2));
    assert_eq!(one.pixels, two.pixels);
}

/// The recording arrays a sample leaves behind are reused by the next (README: memory):
/// an integrator rendering the image a second time, on stores full of the first render's
/// vertices, gives it again bit for bit.
#[test]
fn reused_stores_leave_no_trace() {
    let scene = load_scene(
        &scene_text("pathgraph", "", "2 2 2"),
        &BuildOptions { spp: Some(3), seed: Some(2), ..Default::default() },
    );
    let method = scene.integrator.create(&scene).unwrap();
    let first = render_with(&scene, method.as_ref());
    let again = render_with(&scene, method.as_ref());
    assert!(first.pixels.iter().any(|p| p.max_element() > 0.0));
    assert_eq!(first.pixels, again.pixels);
}

/// Against volpath at 64 spp: the image means agree within four standard errors of the
/// difference plus the method's bias allowance (the issue's 1 %), and the graph's per-pixel
/// noise is lower. Returns the relative mean difference (the bias measured).
#[test]
fn energy_and_noise_against_volpath() {
    let opts = BuildOptions { spp: Some(64), seed: Some(1), ..Default::default() };
    let graph = load_scene(&scene_text("pathgraph", "", "2 2 2"), &opts);
    let volpath = load_scene(&scene_text("volpath", "", "2 2 2"), &opts);
    let reference = load_scene(
        &scene_text("volpath", "", "2 2 2"),
        &BuildOptions { spp: Some(1024), seed: Some(9), ..Default::default() },
    );
    let r = render_scene(&reference);
    let g = render_with(&graph, graph.integrator.create(&graph).unwrap().as_ref());
    let v = render_scene(&volpath);
    let (gs, rs) = (channel_stats(&g), channel_stats(&r));
    for c in 0..3 {
        let se = (gs[c].1 * gs[c].1 + rs[c].1 * rs[c].1).sqrt();
        assert!(
            (gs[c].0 - rs[c].0).abs() <= 4.0 * se + 0.01 * rs[c].0,
            "channel {c}: graph {:?} reference {:?}",
            gs[c],
            rs[c]
        );
    }
    let mse = |a: &Image| {
        a.pixels.iter().zip(&r.pixels).map(|(p, q)| f64::from((*p - *q).length_squared())).sum::<f64>()
            / a.pixels.len() as f64
    };
    assert!(mse(&g) < mse(&v), "graph MSE {} volpath MSE {}", mse(&g), mse(&v));
}

/// A white furnace: a non-absorbing sphere of medium under a uniform sky of radiance 1, where
/// the radiance is 1 everywhere. Returns the image mean (the pixels outside the sphere see the
/// sky: 1 exactly).
fn furnace_mean(g: f32, k: u32, iterations: u32) -> f64 {
    let text = format!(
        r#"LookAt 0 0 4  0 0 0  0 1 0
Camera "perspective" "float fov" 32
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Sampler "zsobol" "integer pixelsamples" 4
Integrator "pathgraph" "integer maxdepth" 1000 "integer clustersize" {k} "integer iterations" {iterations}
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_s" [5 5 5] "rgb sigma_a" [0 0 0] "float g" {g}
AttributeBegin
  MediumInterface "m" ""
  Material "interface"
  Shape "sphere" "float radius" 1
AttributeEnd
"#
    );
    let scene = load_scene(&text, &BuildOptions { seed: Some(2), ..Default::default() });
    channel_stats(&render_scene(&scene))[1].0
}

/// The white furnace keeps its energy: with isotropic and forward scattering, small and large
/// clusters, one aggregation (iterations 0) and the default 2. Counting a path's later
/// vertices as techniques of their own made this −14 % at K = 4 (README: deviations); many
/// iterations reuse the same samples until the bias turns positive (+3 % at 8 iterations),
/// which the README's iteration study records.
#[test]
fn white_furnace_keeps_its_energy() {
    for (g, k, iterations) in [(0.0, 64, 2), (0.7, 4, 0), (0.7, 64, 0), (0.7, 64, 2)] {
        let mean = furnace_mean(g, k, iterations);
        assert!((mean - 1.0).abs() < 0.01, "g {g}, K {k}, {iterations} iterations: mean {mean}");
    }
}

/// Without media there is nothing to cluster (surface vertices are clusters of one): the
/// method path-traces, so the image is volpath's and costs no recording.
#[test]
fn surfaces_only_scene_is_volpath() {
    let text = |integrator: &str| {
        format!(
            r#"LookAt 0 1 6  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
Sampler "zsobol" "integer pixelsamples" 4
Integrator "{integrator}"
WorldBegin
LightSource "infinite" "rgb L" [0.5 0.6 0.8]
Material "diffuse" "rgb reflectance" [0.7 0.3 0.2]
Shape "sphere" "float radius" 1
"#
        )
    };
    let opts = BuildOptions { seed: Some(4), ..Default::default() };
    let graph = load_scene(&text("pathgraph"), &opts);
    let volpath = load_scene(&text("volpath"), &opts);
    let integrator = graph.integrator.create(&graph).unwrap();
    assert_eq!(render_with(&graph, integrator.as_ref()).pixels, render_scene(&volpath).pixels);
    assert!(integrator.report()[0].contains("no media"), "{:?}", integrator.report());
}

/// Extra light samples at the first vertex replace the path's own direct light there by light
/// sampling alone: a different estimator of the same pixel, so with K = 1 (no aggregation)
/// the image mean matches volpath's within noise, in RGB and in spectral transport.
#[test]
fn extra_direct_samples_keep_the_mean() {
    for spectral in [false, true] {
        let opts = BuildOptions { spp: Some(32), seed: Some(6), ..transport(spectral) };
        let graph =
            load_scene(&scene_text("pathgraph", r#""integer clustersize" 1 "integer extradirect" 4"#, "2 2 2"), &opts);
        // Another seed, so the two estimators' noise is independent.
        let volpath = load_scene(&scene_text("volpath", "", "2 2 2"), &BuildOptions { seed: Some(7), ..opts.clone() });
        let (g, v) = (render_scene(&graph), render_scene(&volpath));
        for c in 0..3 {
            let (mean, se) = paired_difference(&g, &v, c);
            let level = channel_stats(&v)[c].0;
            assert!(mean.abs() <= 4.0 * se + 1e-3 * level, "spectral {spectral} channel {c}: difference {mean} ± {se}");
        }
    }
}

/// Mean per-pixel difference a − b in channel `c` and its standard error: the images' shared
/// structure cancels, so the tolerance is the noise of the two estimators alone.
fn paired_difference(a: &Image, b: &Image, c: usize) -> (f64, f64) {
    let d: Vec<f64> = a.pixels.iter().zip(&b.pixels).map(|(p, q)| f64::from(p[c] - q[c])).collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// In a chromatic medium the graph's paths draw a hero wavelength per segment (so that each
/// edge factor is unbiased when aggregation splices paths): with K = 1 (path tracing with the
/// per-segment MIS) the image mean matches volpath's within noise, and with the default K
/// within the method's bias measured on the gray version of this scene (+1.1 to +1.5 % in
/// this paired comparison), in RGB and spectral transport. Splicing whole-path hero
/// estimates measured +5 % (red) here and +10.8 % on the rgbgrid-smoke parity scene.
#[test]
fn chromatic_media_keep_the_mean() {
    for spectral in [false, true] {
        let opts = BuildOptions { spp: Some(32), seed: Some(8), ..transport(spectral) };
        let volpath = load_scene(&scene_text("volpath", "", "1 2 4"), &BuildOptions { seed: Some(9), ..opts.clone() });
        let v = render_scene(&volpath);
        for (k, bias) in [(1, 0.0), (64, 0.02)] {
            let graph = load_scene(&scene_text("pathgraph", &format!(r#""integer clustersize" {k}"#), "1 2 4"), &opts);
            let g = render_scene(&graph);
            for c in 0..3 {
                let (mean, se) = paired_difference(&g, &v, c);
                let level = channel_stats(&v)[c].0;
                assert!(
                    mean.abs() <= 4.0 * se + bias * level,
                    "spectral {spectral} K {k} channel {c}: difference {mean} ± {se} (level {level})"
                );
            }
        }
    }
}

/// A small `maxdepth` in a bright medium: a vertex's estimate depends on how many bounces its
/// path has left, so vertices cluster with vertices at the same place along their paths
/// (README: depth classes). The white furnace's sphere at maxdepth 4 against volpath's at the
/// same maxdepth (not 1: the cut paths' light is missing); mixing depths made the first
/// vertices take the more truncated estimates of deeper ones (−2.3 % here).
#[test]
fn a_small_maxdepth_keeps_the_mean() {
    let text = |integrator: &str, spp: u32| {
        format!(
            r#"LookAt 0 0 2.2  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Sampler "zsobol" "integer pixelsamples" {spp}
Integrator "{integrator}" "integer maxdepth" 4
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
MakeNamedMedium "m" "string type" "homogeneous" "rgb sigma_s" [5 5 5] "rgb sigma_a" [0 0 0]
AttributeBegin
  MediumInterface "m" ""
  Material "interface"
  Shape "sphere" "float radius" 1
AttributeEnd
"#
        )
    };
    let opts = BuildOptions { seed: Some(2), ..Default::default() };
    let mean = |integrator: &str, spp: u32| {
        let img = render_scene(&load_scene(&text(integrator, spp), &opts));
        img.pixels.iter().map(|p| f64::from(p.y)).sum::<f64>() / img.pixels.len() as f64
    };
    let (graph, reference) = (mean("pathgraph", 16), mean("volpath", 256));
    assert!(reference < 0.9, "maxdepth 4 cuts the furnace's light: {reference}");
    assert!((graph / reference - 1.0).abs() < 0.01, "graph {graph} against volpath {reference}");
}
