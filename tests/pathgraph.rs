//! Volume path graphs: a cluster of one is volpath, in either representation; the image does
//! not depend on the thread count; the method's energy against volpath, with its bias measured.

use crate::common::{Estimate, assert_agree, channel_stats, load_scene, render_scene, render_with, transport};
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
        let graph = load_scene(
            &scene_text(
                "pathgraph",
                r#""integer clustersize" 1 "integer iterations" 4 "integer linesamples" 0"#,
                "2 2 2",
            ),
            &opts,
        );
        let volpath = load_scene(&scene_text("volpath", "", "2 2 2"), &opts);
        let line = VolPath::with_config(PathConfig { camera_line: true, ..PathConfig::volpath(20, false) });
        let (g, v) = (render_scene(&graph), render_with(&volpath, &line));
        let peak = v.pixels.iter().map(|p| p.max_element()).fold(0.0, f32::max);
        let d = max_abs_diff(&g, &v);
        assert!(peak > 0.05 && d <= 1e-4 * peak, "spectral {spectral}: max difference {d} (peak {peak})");
    }
}

/// K = 1 against the volpath users get (light seen through the medium found by delta
/// tracking, not along the camera line): two unbiased estimators of the same image, so every
/// channel's mean agrees within four standard errors (two independent seeds each, 16 spp).
#[test]
fn cluster_size_one_agrees_with_users_volpath() {
    for spectral in [false, true] {
        let render = |integrator: &str, params: &str, seed| {
            let opts = BuildOptions { spp: Some(16), seed: Some(seed), ..transport(spectral) };
            render_scene(&load_scene(&scene_text(integrator, params, "2 2 2"), &opts))
        };
        let k1 = r#""integer clustersize" 1"#;
        let graph = Estimate::from_seeds(&[render("pathgraph", k1, 1), render("pathgraph", k1, 2)]);
        let volpath = Estimate::from_seeds(&[render("volpath", "", 3), render("volpath", "", 4)]);
        assert_agree(&format!("K = 1 against volpath, spectral {spectral}"), &graph, &volpath, 0.0, "none: unbiased");
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

/// The MSE ratio at equal spp the README states for this test's cube (measured 4.4×).
const NOISE_RATIO: f64 = 3.0;

/// pathgraph's stated bias bound on media scenes (README: within 1 % on the media scenes).
const GRAPH_BIAS: f64 = 0.01;

/// Against a volpath reference (two seeds at 512 spp) on this scene: pathgraph's image mean
/// (two seeds at 32 spp) agrees in every channel within four standard errors plus
/// GRAPH_BIAS, and its per-pixel MSE at 32 spp is lower than volpath's at 32 spp (two seeds
/// each) by the factor the README states for this scene.
#[test]
fn energy_and_noise_against_volpath() {
    let render = |integrator: &str, spp, seed| {
        let opts = BuildOptions { spp: Some(spp), seed: Some(seed), ..Default::default() };
        render_scene(&load_scene(&scene_text(integrator, "", "2 2 2"), &opts))
    };
    let reference = [render("volpath", 512, 9), render("volpath", 512, 10)];
    let graph = [render("pathgraph", 32, 1), render("pathgraph", 32, 2)];
    let volpath = [render("volpath", 32, 3), render("volpath", 32, 4)];
    let bias = assert_agree(
        "pathgraph against volpath at 1024 spp",
        &Estimate::from_seeds(&graph),
        &Estimate::from_seeds(&reference),
        GRAPH_BIAS,
        "pathgraph's bias on media scenes, README",
    );
    let r: Vec<_> = reference[0].pixels.iter().zip(&reference[1].pixels).map(|(a, b)| 0.5 * (*a + *b)).collect();
    let mse = |imgs: &[Image]| {
        imgs.iter()
            .map(|a| a.pixels.iter().zip(&r).map(|(p, q)| f64::from((*p - *q).length_squared())).sum::<f64>())
            .sum::<f64>()
            / (imgs.len() * r.len()) as f64
    };
    let ratio = mse(&volpath) / mse(&graph);
    eprintln!("pathgraph on the cube: mean {:+.2} %, MSE {ratio:.2}x lower than volpath's at 32 spp", 100.0 * bias);
    assert!(ratio > NOISE_RATIO, "volpath MSE / pathgraph MSE at 32 spp: {ratio:.2} (README: at least {NOISE_RATIO})");
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
        let render = |integrator: &str, params: &str, seed| {
            let opts = BuildOptions { spp: Some(16), seed: Some(seed), ..transport(spectral) };
            render_scene(&load_scene(&scene_text(integrator, params, "2 2 2"), &opts))
        };
        let params = r#""integer clustersize" 1 "integer extradirect" 4"#;
        let graph = Estimate::from_seeds(&[render("pathgraph", params, 6), render("pathgraph", params, 7)]);
        let volpath = Estimate::from_seeds(&[render("volpath", "", 8), render("volpath", "", 9)]);
        let what = format!("extradirect 4 against volpath, spectral {spectral}");
        assert_agree(&what, &graph, &volpath, 0.0, "none: unbiased");
    }
}

/// Extra first vertices along the camera ray (`linesamples`) make the pixel's direct light the
/// mean of several independent estimates, the path's own among them: with K = 1 the image mean
/// matches volpath's within noise, in a gray and a chromatic medium (whose collisions weigh
/// the channels as the path's own do), in RGB and in spectral transport.
#[test]
fn line_samples_keep_the_mean() {
    for spectral in [false, true] {
        for sigma_s in ["2 2 2", "1 2 4"] {
            let render = |integrator: &str, params: &str, seed| {
                let opts = BuildOptions { spp: Some(16), seed: Some(seed), ..transport(spectral) };
                render_scene(&load_scene(&scene_text(integrator, params, sigma_s), &opts))
            };
            let params = r#""integer clustersize" 1 "integer linesamples" 4"#;
            let graph = Estimate::from_seeds(&[render("pathgraph", params, 12), render("pathgraph", params, 13)]);
            let volpath = Estimate::from_seeds(&[render("volpath", "", 14), render("volpath", "", 15)]);
            let what = format!("linesamples 4 against volpath, sigma_s {sigma_s}, spectral {spectral}");
            assert_agree(&what, &graph, &volpath, 0.0, "none: unbiased");
        }
    }
}

/// In a chromatic medium the graph's paths draw a hero wavelength per segment (so that each
/// edge factor is unbiased when aggregation splices paths): with K = 1 (path tracing with the
/// per-segment MIS) the image mean matches volpath's within noise, and with K = 64 within the
/// method's bias measured on the gray version of this scene (+1.1 to +1.5 %; bound 2 %), in
/// RGB and spectral transport. Splicing whole-path hero estimates measured +5 % (red) here
/// and +10.8 % on the rgbgrid-smoke parity scene.
#[test]
fn chromatic_media_keep_the_mean() {
    for spectral in [false, true] {
        let render = |integrator: &str, params: &str, seed| {
            let opts = BuildOptions { spp: Some(16), seed: Some(seed), ..transport(spectral) };
            render_scene(&load_scene(&scene_text(integrator, params, "1 2 4"), &opts))
        };
        let volpath = Estimate::from_seeds(&[render("volpath", "", 8), render("volpath", "", 9)]);
        for (k, bias, source) in [
            (1, 0.0, "none: K = 1 is unbiased"),
            (64, 0.02, "aggregation at K = 64 on this cube, measured +1.1 to +1.5 %"),
        ] {
            let params = format!(r#""integer clustersize" {k}"#);
            let graph = Estimate::from_seeds(&[render("pathgraph", &params, 10), render("pathgraph", &params, 11)]);
            assert_agree(&format!("chromatic, K {k}, spectral {spectral}"), &graph, &volpath, bias, source);
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

/// The README's per-sample claim on its headline scenes (the results' first table: the cloud,
/// the wax in glass, the fog with an emitter, 128×96 against their 2048/4096-spp volpath
/// references): at 1 spp pathgraph's relMSE is lower than volpath's by at least the factor
/// the README states for each (measured over seeds 1–2 here, 18×, 14× and 4.4× in the
/// results at seed 1).
#[test]
fn per_sample_noise_on_the_headline_scenes() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("pbrt-scenes");
    for (name, at_least) in
        [("cloud-sun-sky", PER_SAMPLE[0]), ("wax-small-light", PER_SAMPLE[1]), ("fog-emitter", PER_SAMPLE[2])]
    {
        let desc = nimbus::parser::load_file(&dir.join(format!("{name}.pbrt"))).unwrap();
        let reference = nimbus::imageio::read_exr(&dir.join(format!("references/{name}.exr"))).unwrap();
        let rel_mse = |integrator: &str| {
            [1, 2]
                .map(|seed| {
                    let opts = BuildOptions {
                        integrator: Some(integrator.into()),
                        spp: Some(1),
                        seed: Some(seed),
                        ..Default::default()
                    };
                    let img = render_scene(&nimbus::setup::build(&desc, &opts).unwrap());
                    nimbus::metrics::error_metrics(&img, &reference).unwrap().rel_mse
                })
                .iter()
                .sum::<f64>()
                / 2.0
        };
        let (v, g) = (rel_mse("volpath"), rel_mse("pathgraph"));
        eprintln!("{name}: relMSE at 1 spp volpath {v:.4}, pathgraph {g:.4}: {:.1}x", v / g);
        assert!(
            v / g >= at_least,
            "{name}: relMSE at 1 spp {v:.4} -> {g:.4}, {:.1}x (README: at least {at_least}x)",
            v / g
        );
    }
}

/// The per-sample factors the README states as lower bounds: cloud-sun-sky, wax-small-light,
/// fog-emitter.
const PER_SAMPLE: [f64; 3] = [10.0, 8.0, 3.0];

/// The reference scenes' grid cloud made dense and forward-scattering (σs 24, g 0.85), lit
/// from behind (the light reaches the camera through its rim), at 32², rendered by
/// `integrator` with `params`: where the graph alone (K 64) is dark (README: consistency).
fn backlit_cloud(integrator: &str, params: &str) -> String {
    backlit_cloud_at(integrator, params, 32)
}

/// [`backlit_cloud`] at `side`² pixels.
fn backlit_cloud_at(integrator: &str, params: &str, side: u32) -> String {
    let path = crate::common::reference_scenes_dir().join("grid-cloud.pbrt");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let subs = [
        ("LookAt 0 0.3 4.2", "LookAt 0 0.2 4.2".to_string()),
        (
            "\"integer xresolution\" [ 128 ] \"integer yresolution\" [ 128 ]",
            format!("\"integer xresolution\" [ {side} ] \"integer yresolution\" [ {side} ]"),
        ),
        (
            "Integrator \"volpath\" \"integer maxdepth\" [ 100 ]",
            format!("Integrator \"{integrator}\" \"integer maxdepth\" [ 100 ] {params}"),
        ),
        ("\"point3 from\" [ -1 3 2 ]", "\"point3 from\" [ 0.3 0.6 -4 ]".to_string()),
        (
            "\"rgb sigma_a\" [ 0.2 0.2 0.2 ] \"rgb sigma_s\" [ 12 12 12 ] \"float g\" [ 0.6 ]",
            "\"rgb sigma_a\" [ 0.05 0.05 0.05 ] \"rgb sigma_s\" [ 24 24 24 ] \"float g\" [ 0.85 ]".to_string(),
        ),
    ];
    subs.iter().fold(text, |t, (a, b)| {
        assert!(t.contains(a), "grid-cloud.pbrt no longer has {a}");
        t.replace(a, b)
    })
}

/// The combination converges where the graph alone does not (README: consistency): on the
/// back-lit cloud at 256 spp the graph alone's mean is off by more than four standard errors
/// plus the 1 % the README allows (−5.4 %), and the combined image's mean agrees with
/// volpath's within them (−0.1 %), graph samples having stopped paying within the render.
#[test]
fn the_combination_removes_the_graphs_bias() {
    let render = |integrator: &str, params: &str, spp, seed| {
        let opts = BuildOptions { spp: Some(spp), seed: Some(seed), ..Default::default() };
        render_scene(&load_scene(&backlit_cloud(integrator, params), &opts))
    };
    let reference = Estimate::from_seeds(&[render("volpath", "", 1024, 9), render("volpath", "", 1024, 10)]);
    let graph = "\"integer clustersize\" 64";
    let alone = format!("{graph} \"bool combine\" false");
    let alone = Estimate::from_seeds(&[render("pathgraph", &alone, 256, 1), render("pathgraph", &alone, 256, 2)]);
    // The combined renders, with what the method says about them.
    let (combined, reports): (Vec<Image>, Vec<Vec<String>>) = [1, 2]
        .iter()
        .map(|&seed| {
            let opts = BuildOptions { spp: Some(256), seed: Some(seed), ..Default::default() };
            let setup = load_scene(&backlit_cloud("pathgraph", graph), &opts);
            let method = setup.prepare().unwrap().integrator;
            let image = render_with(&setup.scene, method.as_ref());
            (image, method.report())
        })
        .unzip();
    let combined = Estimate::from_seeds(&combined);
    assert_combined_removes_the_bias("back-lit cloud at 256 spp", &reference, &alone, &combined);
    // Here the graph's weight falls fast enough that graph samples stop paying within the
    // render: from then on one in `unpaired::THIN` builds a graph, the rest are the paths' own
    // estimate alone, pooled with the paired ones'.
    for r in &reports {
        assert!(r.iter().any(|l| l.contains("graph samples thinned after")), "{r:#?}");
    }
}

/// The neighbours' estimate of the graph's bias (README: consistency, `render/correction.rs`)
/// takes it off long before the weights can: on the back-lit cloud at 64², 32 spp (K 64) the
/// graph alone's mean is off by more than four standard errors plus the 1 % the README
/// allows, and the combined image's agrees with volpath's within them (without the
/// correction it did not).
#[test]
fn the_neighbours_take_the_graphs_bias_off_at_few_samples() {
    let render = |integrator: &str, params: &str, spp, seed| {
        let opts = BuildOptions { spp: Some(spp), seed: Some(seed), ..Default::default() };
        render_scene(&load_scene(&backlit_cloud_at(integrator, params, 64), &opts))
    };
    let reference = Estimate::from_seeds(&[render("volpath", "", 1024, 9), render("volpath", "", 1024, 10)]);
    let graph = "\"integer clustersize\" 64";
    let alone = format!("{graph} \"bool combine\" false");
    let seeds = [1, 2, 3, 4];
    let alone = Estimate::from_seeds(&seeds.map(|s| render("pathgraph", &alone, 32, s)));
    let combined = Estimate::from_seeds(&seeds.map(|s| render("pathgraph", graph, 32, s)));
    assert_combined_removes_the_bias("back-lit cloud at 64², 32 spp", &reference, &alone, &combined);
}

/// The graph alone's image mean off volpath's `reference` by more than four standard errors
/// plus GRAPH_BIAS (else the case shows nothing), and the `combined` image's within them;
/// `case` names the renders in the output.
fn assert_combined_removes_the_bias(case: &str, reference: &Estimate, alone: &Estimate, combined: &Estimate) {
    let green = |e: &Estimate| e.mean[1] / reference.mean[1] - 1.0;
    let se = |e: &Estimate| (e.se[1].powi(2) + reference.se[1].powi(2)).sqrt() / reference.mean[1];
    eprintln!(
        "{case}: graph alone {:+.2} % (se {:.2} %), combined {:+.2} % (se {:.2} %)",
        100.0 * green(alone),
        100.0 * se(alone),
        100.0 * green(combined),
        100.0 * se(combined)
    );
    assert!(
        green(alone).abs() > 4.0 * se(alone) + GRAPH_BIAS,
        "the graph alone is not biased here beyond its noise: the test shows nothing"
    );
    assert_agree("the combined image against volpath", combined, reference, GRAPH_BIAS, "pathgraph README");
}
