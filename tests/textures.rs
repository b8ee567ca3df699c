//! Textures end to end: pbrt-v4's `ptex` (its filtering is checked against the Ptex library
//! in `src/textures/ptex/filter.rs`, its rendering against pbrt-v4 in `pbrt_v4_parity`).

use nimbus::scene::BuildOptions;

use crate::common::scratch_dir;

const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/ptex/grid-rgb8.ptx");

/// A quad (a bilinear patch) with the ptex texture `texture` as its reflectance and
/// `faces` as its `faceIndices`.
fn scene(texture: &str, faces: &str) -> String {
    format!(
        "LookAt 0 0 3  0 0 0  0 1 0\nCamera \"orthographic\"\nSampler \"independent\" \"integer pixelsamples\" 4\n\
         Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n\
         LightSource \"infinite\" \"rgb L\" [1 1 1]\n{texture}\n\
         Material \"diffuse\" \"texture reflectance\" \"t\"\n\
         Shape \"bilinearmesh\" \"point3 P\" [-1 -1 0  1 -1 0  -1 1 0  1 1 0] \"point2 uv\" [0 0 1 0 0 1 1 1] {faces}\n"
    )
}

/// Errors name the directive's place and say what is wrong: a missing file, a file that is
/// not Ptex, an unknown encoding, a face id the file does not have is a lookup of zero (as
/// in the Ptex library), never a panic.
#[test]
fn ptex_errors_name_the_file_and_place() {
    let dir = scratch_dir("ptex-errors");
    let not_ptex = dir.as_ref().join("not.ptx");
    std::fs::write(&not_ptex, "hello").unwrap();
    let opts = BuildOptions { spp: Some(1), ..Default::default() };
    let cases = [
        (
            format!(
                "Texture \"t\" \"spectrum\" \"ptex\" \"string filename\" \"{}/missing.ptx\"",
                dir.as_ref().display()
            ),
            "ptex: cannot find file",
        ),
        (
            format!("Texture \"t\" \"spectrum\" \"ptex\" \"string filename\" \"{}\"", not_ptex.display()),
            "not a Ptex file",
        ),
        (
            format!(
                "Texture \"t\" \"spectrum\" \"ptex\" \"string filename\" \"{FIXTURE}\" \"string encoding\" \"gamma\""
            ),
            "unknown encoding",
        ),
        ("Texture \"t\" \"spectrum\" \"ptexx\"".to_string(), "texture type \"ptexx\" is unknown"),
    ];
    for (texture, message) in cases {
        let text = scene(&texture, "");
        let desc = nimbus::parser::load_str(&text, "ptex.pbrt").unwrap();
        let err = nimbus::setup::build(&desc, &opts).err().unwrap_or_else(|| panic!("{texture}: built")).to_string();
        assert!(err.contains(message) && err.starts_with("ptex.pbrt:7:"), "{texture}: {err}");
    }
    let text = scene(
        &format!("Texture \"t\" \"spectrum\" \"ptex\" \"string filename\" \"{FIXTURE}\""),
        "\"integer faceIndices\" [99]",
    );
    let desc = nimbus::parser::load_str(&text, "ptex.pbrt").unwrap();
    let image = crate::common::render_scene(&nimbus::setup::build(&desc, &opts).unwrap());
    assert!(image.pixels.iter().all(|p| p.is_finite()));
}

/// `faceIndices` picks the face: face 4 of the fixture is constant, so a quad showing it
/// under a uniform white sky (orthographic camera filling the frame with it, diffuse, no
/// occlusion) has radiance equal to the face's value, decoded by pbrt-v4's default
/// `gamma 2.2`, wherever the filter stays inside the face (the middle half; nearer the edges
/// it blends in the neighbours, as Ptex does): the mean there matches it within 4 standard
/// errors. Face 0 (the default face id) is another colour.
#[test]
fn ptex_face_indices_pick_the_face() {
    let file =
        nimbus::textures::PtexTexture::open(FIXTURE.as_ref(), nimbus::textures::PtexEncoding::Gamma(2.2), 1.0).unwrap();
    let want = file.lookup(4, glam::Vec2::splat(0.5), glam::Vec2::ZERO, glam::Vec2::ZERO);
    let texture = format!("Texture \"t\" \"spectrum\" \"ptex\" \"string filename\" \"{FIXTURE}\"");
    let opts = BuildOptions { spp: Some(16), seed: Some(3), ..Default::default() };
    let render = |faces: &str| {
        let text = scene(&texture, faces)
            .replace("xresolution\" 8 \"integer yresolution\" 8", "xresolution\" 32 \"integer yresolution\" 32");
        let desc = nimbus::parser::load_str(&text, "ptex.pbrt").unwrap();
        crate::common::render_scene(&nimbus::setup::build(&desc, &opts).unwrap())
    };
    // Per channel, the mean of the middle 16×16 pixels and its standard error.
    let middle = |img: nimbus::imageio::Image| -> [(f64, f64); 3] {
        std::array::from_fn(|c| {
            let v: Vec<f64> =
                (8..24).flat_map(|y| (8..24).map(move |x| (x, y))).map(|(x, y)| img.get(x, y)[c] as f64).collect();
            let n = v.len() as f64;
            let m = v.iter().sum::<f64>() / n;
            (m, (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt())
        })
    };
    let face4 = middle(render("\"integer faceIndices\" [4]"));
    let face0 = middle(render(""));
    let mut differs = false;
    for c in 0..3 {
        let (mean, se) = face4[c];
        assert!((mean - want[c] as f64).abs() < 4.0 * se, "channel {c}: {mean} ± {se} for {}", want[c]);
        differs |= (face0[c].0 - mean).abs() > 10.0 * se.max(face0[c].1);
    }
    assert!(differs, "face 0 {face0:?}, face 4 {face4:?}");
}

/// A texture declared under a singular transform: pbrt-v4 goes on when the texture maps by
/// (u, v) and never inverts the transform (published scenes have such chains), so nimbus
/// renders it; one that maps points through the transform (spherical) is refused at its place.
#[test]
fn textures_under_singular_transforms_need_it_only_to_map_points() {
    let text = |mapping: &str| {
        format!(
            r#"LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective"
Film "rgb" "integer xresolution" 8 "integer yresolution" 8
Sampler "independent" "integer pixelsamples" 1
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
AttributeBegin
  Scale 0 1 1
  Texture "t" "spectrum" "checkerboard" "string mapping" "{mapping}"
AttributeEnd
Material "diffuse" "texture reflectance" "t"
Shape "sphere"
"#
        )
    };
    let uv = nimbus::parser::load_str(&text("uv"), "s.pbrt").unwrap();
    let setup = nimbus::setup::build(&uv, &BuildOptions::default()).expect("a (u, v) texture needs no inverse");
    assert!(crate::common::render_scene(&setup).mean().x > 0.0);
    let spherical = nimbus::parser::load_str(&text("spherical"), "s.pbrt").unwrap();
    let e = nimbus::setup::build(&spherical, &BuildOptions::default()).err().expect("refused");
    assert!(e.to_string().starts_with("s.pbrt:9:") && e.to_string().contains("singular"), "{e}");
}
