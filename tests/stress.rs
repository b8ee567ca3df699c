//! `nimbus stress`: a tiny matrix (two conditions × every integrator) runs cell by cell in
//! child processes, judges every cell against volpath, reuses its cached references, and
//! reports a cell that does not finish as a failure with a non-zero exit.

use crate::common::{nimbus, scratch_dir};

/// A 16×16 homogeneous sphere behind an `interface` boundary lit by `light`; the sampler's
/// 64 spp is the reference's.
fn condition(what: &str, light: &str) -> String {
    format!(
        "# nimbus stress matrix, condition test: {what}.\n\
         LookAt 0 0 4.5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 32\n\
         Sampler \"zsobol\" \"integer pixelsamples\" 64\nIntegrator \"volpath\" \"integer maxdepth\" 100\n\
         Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n\
         MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.2 0.2 0.2] \"rgb sigma_s\" [1.8 1.8 1.8]\n\
         WorldBegin\n{light}\nAttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\n\
         Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n"
    )
}

/// The bias bound each method's README states for this matrix's homogeneous sphere, and
/// where it is stated.
fn stated_bias(integrator: &str) -> (f64, &'static str) {
    match integrator {
        "pathgraph" => (0.01, "pathgraph README: within 1 % on media scenes"),
        "radiancegraph" => (0.025, "radiancegraph README: node averaging, within 2.5 % on the scenes of its tests"),
        _ => (0.0, "unbiased"),
    }
}

fn csv_rows(text: &str) -> Vec<std::collections::HashMap<String, String>> {
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            // The last field (the reason) may be quoted and hold commas.
            let fields: Vec<&str> = l.splitn(header.len(), ',').collect();
            header.iter().cloned().zip(fields.iter().map(|f| f.trim_matches('"').to_string())).collect()
        })
        .collect()
}

#[test]
fn stress_judges_every_cell_and_reports_failures() {
    let dir = scratch_dir("stress");
    let scenes = dir.join("scenes");
    std::fs::create_dir_all(&scenes).unwrap();
    let sun = "LightSource \"distant\" \"point3 from\" [-1 1.5 1] \"point3 to\" [0 0 0] \"rgb L\" [3 3 3]";
    std::fs::write(scenes.join("a-sun.pbrt"), condition("a distant sun", sun)).unwrap();
    let spot = "LightSource \"spot\" \"point3 from\" [-2 2.5 2] \"point3 to\" [0 0 0] \"rgb I\" [5 5 5]";
    std::fs::write(scenes.join("b-spot.pbrt"), condition("a spot light", spot)).unwrap();
    // A coarse, quick graph for the radiance graph (its config beside the scene).
    let graph = r#"{"graphBuilder": {"radiusModifier": 60, "dimensionSteps": 50, "iterationsPerStep": 4}}"#;
    std::fs::write(scenes.join("a-sun.json"), graph).unwrap();
    let out = dir.join("out");
    let args = |time: &str, extra: &[&str]| {
        let mut v: Vec<String> =
            ["stress", "--scenes", scenes.to_str().unwrap(), "--out", out.to_str().unwrap()].map(String::from).to_vec();
        v.extend(["--time".into(), time.into()]);
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let run = |a: Vec<String>| nimbus(&a.iter().map(String::as_str).collect::<Vec<_>>());

    let first = run(args("0.3", &[]));
    let err = String::from_utf8_lossy(&first.stderr);
    assert!(first.status.success(), "{err}");
    assert!(err.contains("reference: rendering volpath at 64 spp"), "{err}");
    assert!(scenes.join("a-sun.volpath-64spp-seed2.exr").exists());
    let rows = csv_rows(&std::fs::read_to_string(out.join("stress.csv")).unwrap());
    let methods = nimbus::integrators::INTEGRATOR_NAMES.len();
    assert_eq!(rows.len(), 2 * methods, "two conditions x every method nimbus has");
    for r in &rows {
        let (cond, name, verdict) = (&r["condition"], &r["integrator"], r["verdict"].as_str());
        match (name.as_str(), cond.as_str()) {
            ("volpath", _) => assert!(verdict == "baseline" || (verdict == "biased" && r["biased"] == "true")),
            ("radiancegraph", "b-spot") => {
                assert_eq!(verdict, "refused");
                assert!(
                    r["reason"].contains("diffuse area lights only (the scene has spot lights)"),
                    "{}",
                    r["reason"]
                );
            }
            _ => {
                // The verdict follows from the ratio and its standard error as documented:
                // beyond twice the standard error of its logarithm and beyond 1.25x.
                let ratio: f64 = r["relmse_ratio"].parse().unwrap();
                let se: f64 = r["relmse_se"].parse::<f64>().unwrap() / r["relmse"].parse::<f64>().unwrap();
                let base = rows.iter().find(|b| &b["condition"] == cond && b["integrator"] == "volpath").unwrap();
                let base_se: f64 = base["relmse_se"].parse::<f64>().unwrap() / base["relmse"].parse::<f64>().unwrap();
                let band = (2.0 * (se * se + base_se * base_se).sqrt()).max(1.25f64.ln());
                let biased = r["biased"] == "true";
                let expected = if biased {
                    "biased"
                } else if ratio.ln() < -band {
                    "better"
                } else if ratio.ln() > band {
                    "worse"
                } else {
                    "same"
                };
                assert_eq!(verdict, expected, "{cond}/{name}: relMSE ratio {ratio} (band ±{band} in log)");
            }
        }
        if verdict != "refused" {
            let relmse: f64 = r["relmse"].parse().unwrap();
            assert!(relmse.is_finite() && relmse > 0.0, "{cond}/{name}");
            assert_eq!(r["nonfinite_samples"], "0");
            assert!(r["peak_rss_bytes"].parse::<u64>().unwrap() > 0);
            // Quality: every method's image mean within 4 standard errors of the reference's
            // plus the bias its README states, and the `biased` column saying so.
            let (bias, z): (f64, f64) = (r["bias"].parse().unwrap(), r["bias_z"].parse().unwrap());
            let se = if z != 0.0 { (bias / z).abs() } else { 0.0 };
            let (bound, source) = stated_bias(name);
            eprintln!("{cond}/{name}: mean {:+.2} % ± {:.2} %", 100.0 * bias, 100.0 * se);
            assert!(
                bias.abs() <= 4.0 * se + bound,
                "{cond}/{name}: mean {:+.2} % off the reference, more than 4 standard errors ({:.2} %) plus \
                 the stated bias bound {:.1} % ({source})",
                100.0 * bias,
                100.0 * se,
                100.0 * bound
            );
            // The `biased` column and verdict follow from the documented rule: more than 3
            // standard errors and more than 1 % off.
            let rule = z.abs() > 3.0 && bias.abs() > 0.01;
            assert_eq!(r["biased"] == "true", rule, "{cond}/{name}: bias {bias}, z {z}");
        }
    }
    for file in ["stress.md", "heatmap.svg", "heatmap.png", "cells/a-sun/guided.exr", "cells/b-spot/radiancegraph.log"]
    {
        assert!(out.join(file).exists(), "{file}");
    }
    let md = std::fs::read_to_string(out.join("stress.md")).unwrap();
    assert!(md.contains("| a-sun | 1x |") && md.contains("radiancegraph on b-spot: refused"), "{md}");

    // The references are reused; a cell stopped at the timeout is a failure, and the run
    // says so with its exit code.
    let second = run(args("0.3", &["--integrators", "volpath", "--conditions", "a-sun", "--timeout", "0.001"]));
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(!second.status.success());
    assert!(err.contains("(cached)") && err.contains("1 cell(s) failed"), "{err}");
    let md = std::fs::read_to_string(out.join("stress.md")).unwrap();
    assert!(md.contains("volpath on a-sun: FAILED: still running after 0 s"), "{md}");

    let bad = run(args("0.3", &["--integrators", "nosuch"]));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("unknown integrator \"nosuch\""));
    let none = run(args("0.3", &["--conditions", "zzz"]));
    assert!(String::from_utf8_lossy(&none.stderr).contains("no condition scenes"));
}
