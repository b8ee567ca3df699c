//! The scene builder's graphics state: media, area lights, instancing, color spaces, options,
//! materials, textures, attributes and the scene's defaults.

use nimbus_parser::{ColorSpace, MaterialRef, MediumInterface, SceneOptions, TextureValue};

use crate::common::{load, scene};

#[test]
fn defaults_are_pbrt_v4s() {
    let s = load("WorldBegin");
    assert_eq!(s.camera.entity.name, "perspective");
    assert_eq!(s.camera.medium, None);
    assert!(!s.camera.world_from_camera.is_animated());
    assert_eq!(s.camera.world_from_camera.start, glam::DMat4::IDENTITY);
    assert_eq!(s.film.name, "rgb");
    assert_eq!(s.sampler.name, "zsobol");
    assert_eq!(s.filter.name, "gaussian");
    assert_eq!(s.integrator.name, "volpath");
    assert_eq!(s.accelerator.name, "bvh");
    assert_eq!(s.options, SceneOptions::default());
    assert_eq!(s.materials.len(), 1);
    assert_eq!(s.materials[0].name, "diffuse");
    assert!(s.shapes.is_empty() && s.lights.is_empty() && s.media.is_empty());
    assert!(s.warnings.is_empty());
    assert_eq!(s.files, ["t.pbrt"]);
}

#[test]
fn options_block_entities_keep_name_parameters_and_location() {
    let s = load(
        "Film \"gbuffer\" \"integer xresolution\" 32\nSampler \"halton\"\n\
         PixelFilter \"box\"\nIntegrator \"path\" \"integer maxdepth\" 3\n\
         Accelerator \"kdtree\"\nCamera \"orthographic\"\nWorldBegin",
    );
    assert_eq!(s.film.name, "gbuffer");
    assert_eq!(s.film.params.get_one_int("xresolution", 0), Ok(32));
    assert_eq!(s.film.loc.to_string(), "t.pbrt:1:1");
    assert_eq!(s.sampler.name, "halton");
    assert_eq!(s.filter.name, "box");
    assert_eq!(s.integrator.name, "path");
    assert_eq!(s.integrator.params.get_one_int("maxdepth", 5), Ok(3));
    assert_eq!(s.accelerator.name, "kdtree");
    assert_eq!(s.camera.entity.name, "orthographic");
    assert_eq!(s.camera.entity.loc.to_string(), "t.pbrt:6:1");
}

#[test]
fn the_last_of_each_options_directive_wins() {
    let s = load("Film \"rgb\"\nFilm \"spectral\"\nCamera \"perspective\"\nCamera \"realistic\"\nWorldBegin");
    assert_eq!(s.film.name, "spectral");
    assert_eq!(s.camera.entity.name, "realistic");
}

#[test]
fn camera_and_lights_sit_in_the_outside_medium() {
    let s = load(&scene(
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n\
         MakeNamedMedium \"air\" \"string type\" \"homogeneous\"\n\
         MediumInterface \"fog\" \"air\"\nCamera \"perspective\"",
        "LightSource \"point\"\nMediumInterface \"fog\"\nLightSource \"spot\"\n\
         MediumInterface \"air\" \"\"\nLightSource \"distant\"",
    ));
    assert_eq!(s.camera.medium, Some("air".into()));
    let media: Vec<Option<&str>> = s.lights.iter().map(|l| l.medium.as_deref()).collect();
    // WorldBegin does not reset the current media: the first light is still in "air".
    assert_eq!(media, [Some("air"), Some("fog"), None]);
}

#[test]
fn shapes_get_a_medium_interface_only_where_the_media_differ() {
    let s = load(&scene(
        "",
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n\
         MakeNamedMedium \"smoke\" \"string type\" \"homogeneous\"\n\
         Shape \"sphere\"\n\
         AttributeBegin\n\
           MediumInterface \"fog\"\n Shape \"sphere\"\n\
           MediumInterface \"fog\" \"fog\"\n Shape \"sphere\"\n\
           MediumInterface \"fog\" \"\"\n Shape \"sphere\"\n\
           MediumInterface \"\" \"smoke\"\n Shape \"sphere\"\n\
           MediumInterface \"fog\" \"smoke\"\n Shape \"sphere\"\n\
         AttributeEnd\n\
         Shape \"sphere\"",
    ));
    let got: Vec<(Option<MediumInterface>, Option<&str>)> =
        s.shapes.iter().map(|sh| (sh.medium_interface.clone(), sh.outside_medium.as_deref())).collect();
    let mi = |inside: Option<&str>, outside: Option<&str>| {
        Some(MediumInterface { inside: inside.map(str::to_string), outside: outside.map(str::to_string) })
    };
    assert_eq!(
        got,
        [
            (None, None),
            (None, Some("fog")),
            (None, Some("fog")),
            (mi(Some("fog"), None), None),
            (mi(None, Some("smoke")), Some("smoke")),
            (mi(Some("fog"), Some("smoke")), Some("smoke")),
            // AttributeEnd restored the empty interface.
            (None, None),
        ]
    );
}

#[test]
fn media_keep_type_parameters_and_transform() {
    let s = load(&scene(
        "",
        "Translate 0 2 0\nAttribute \"medium\" \"float g\" 0.5\n\
         MakeNamedMedium \"cloud\" \"string type\" \"uniformgrid\" \"integer nx\" 2",
    ));
    let m = s.medium("cloud").unwrap();
    assert_eq!(m.entity.name, "uniformgrid");
    assert_eq!(m.entity.params.get_one_int("nx", 1), Ok(2));
    assert_eq!(m.entity.params.get_one_float("g", 0.0), Ok(0.5));
    assert_eq!(m.entity.loc.to_string(), "t.pbrt:5:1");
    assert_eq!(m.world_from_medium.start.transform_point3(glam::DVec3::ZERO), glam::DVec3::new(0.0, 2.0, 0.0));
    assert!(s.medium("other").is_none());
}

#[test]
fn area_lights_attach_to_the_shapes_that_follow_in_their_block() {
    let s = load(&scene(
        "",
        "Shape \"sphere\"\n\
         AttributeBegin\n\
           Attribute \"light\" \"float scale\" 2\n\
           ColorSpace \"rec2020\"\n\
           AreaLightSource \"diffuse\" \"rgb L\" [ 4 4 4 ]\n\
           ColorSpace \"srgb\"\n\
           Shape \"sphere\"\n\
           Shape \"disk\"\n\
         AttributeEnd\n\
         Shape \"sphere\"",
    ));
    let lights: Vec<Option<usize>> = s.shapes.iter().map(|sh| sh.area_light).collect();
    assert_eq!(lights, [None, Some(0), Some(1), None]);
    assert_eq!(s.area_lights.len(), 2);
    for al in &s.area_lights {
        assert_eq!(al.name, "diffuse");
        assert_eq!(al.loc.to_string(), "t.pbrt:7:1");
        assert_eq!(al.params.get_rgbs("L"), Ok(&[[4.0, 4.0, 4.0]][..]));
        // Light attributes apply to area lights.
        assert_eq!(al.params.get_one_float("scale", 1.0), Ok(2.0));
        // The color space is the one in effect at AreaLightSource.
        assert_eq!(al.color_space, ColorSpace::Rec2020);
    }
    assert_eq!(s.shapes[1].entity.color_space, ColorSpace::Srgb);
    assert!(s.lights.is_empty());
}

#[test]
fn object_instancing() {
    let s = load(&scene(
        "",
        "Translate 0 0 1\n\
         ObjectBegin \"tree\"\n\
           Material \"conductor\"\n\
           Translate 1 0 0\n\
           Shape \"sphere\"\n\
           Shape \"cylinder\"\n\
         ObjectEnd\n\
         Shape \"disk\"\n\
         Translate 0 5 0\n\
         ObjectInstance \"tree\"\n\
         Translate 0 5 0\n\
         ObjectInstance \"tree\"",
    ));
    // The definition's shapes are not scene shapes; each has its transform at definition.
    assert_eq!(s.shapes.len(), 1);
    assert_eq!(s.shapes[0].entity.name, "disk");
    let def = &s.instance_definitions[0];
    assert_eq!(def.name, "tree");
    assert_eq!(def.loc.to_string(), "t.pbrt:4:1");
    let names: Vec<&str> = def.shapes.iter().map(|sh| sh.entity.name.as_str()).collect();
    assert_eq!(names, ["sphere", "cylinder"]);
    let origin = glam::DVec3::ZERO;
    for sh in &def.shapes {
        assert_eq!(sh.world_from_object.start.transform_point3(origin), glam::DVec3::new(1.0, 0.0, 1.0));
        assert_eq!(sh.material, MaterialRef::Index(1));
    }
    // ObjectEnd restores the graphics state: the disk has the default material and the
    // transform from before ObjectBegin.
    assert_eq!(s.shapes[0].material, MaterialRef::Index(0));
    assert_eq!(s.shapes[0].world_from_object.start.transform_point3(origin), glam::DVec3::new(0.0, 0.0, 1.0));
    let uses: Vec<(&str, glam::DVec3, String)> = s
        .instances
        .iter()
        .map(|u| (u.name.as_str(), u.world_from_instance.start.transform_point3(origin), u.loc.to_string()))
        .collect();
    assert_eq!(
        uses,
        [
            ("tree", glam::DVec3::new(0.0, 5.0, 1.0), "t.pbrt:12:1".to_string()),
            ("tree", glam::DVec3::new(0.0, 10.0, 1.0), "t.pbrt:14:1".to_string()),
        ]
    );
}

#[test]
fn an_instance_may_be_used_before_its_definition() {
    let s = load(&scene("", "ObjectInstance \"later\"\nObjectBegin \"later\"\nShape \"sphere\"\nObjectEnd"));
    assert_eq!(s.instances.len(), 1);
    assert_eq!(s.instance_definitions[0].shapes.len(), 1);
}

#[test]
fn area_lights_inside_object_definitions_are_dropped_with_a_warning() {
    let s = load(&scene("", "ObjectBegin \"lamp\"\nAreaLightSource \"diffuse\"\n  Shape \"sphere\"\nObjectEnd"));
    assert_eq!(s.instance_definitions[0].shapes[0].area_light, None);
    assert!(s.area_lights.is_empty());
    let warnings: Vec<String> = s.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(
        warnings,
        ["t.pbrt:5:3: area lights are not supported with object instancing; this shape will not emit"]
    );
}

#[test]
fn color_space_is_graphics_state() {
    let s = load(&scene(
        "ColorSpace \"aces2065-1\"\nFilm \"rgb\"\nCamera \"perspective\"",
        "Shape \"sphere\"\n\
         AttributeBegin\nColorSpace \"dci-p3\"\nShape \"sphere\"\n\
         ColorSpace \"rec2020\"\nLightSource \"point\"\nMaterial \"diffuse\"\n\
         Texture \"t\" \"spectrum\" \"constant\"\nAttributeEnd\n\
         Shape \"sphere\"\nColorSpace \"srgb\"\nShape \"sphere\"",
    ));
    assert_eq!(s.film.color_space, ColorSpace::Aces2065_1);
    assert_eq!(s.camera.entity.color_space, ColorSpace::Aces2065_1);
    let spaces: Vec<ColorSpace> = s.shapes.iter().map(|sh| sh.entity.color_space).collect();
    // WorldBegin keeps the color space; AttributeEnd restores it.
    assert_eq!(spaces, [ColorSpace::Aces2065_1, ColorSpace::DciP3, ColorSpace::Aces2065_1, ColorSpace::Srgb]);
    assert_eq!(s.lights[0].entity.color_space, ColorSpace::Rec2020);
    assert_eq!(s.materials[1].color_space, ColorSpace::Rec2020);
    assert_eq!(s.textures[0].entity.color_space, ColorSpace::Rec2020);
    for cs in [ColorSpace::Srgb, ColorSpace::Rec2020, ColorSpace::Aces2065_1, ColorSpace::DciP3] {
        assert_eq!(ColorSpace::from_name(cs.name()), Some(cs));
    }
}

#[test]
fn options_set_scene_options() {
    let s = load(
        "Option \"bool disablepixeljitter\" true\n\
         Option \"bool disabletexturefiltering\" \"true\"\n\
         Option \"disablewavelengthjitter\" true\n\
         Option \"bool forcediffuse\" true\n\
         Option \"bool pixelstats\" true\n\
         Option \"bool wavefront\" true\n\
         Option \"float displacementedgescale\" 0.5\n\
         Option \"integer seed\" -7\n\
         Option \"string msereferenceimage\" \"ref.exr\"\n\
         Option \"string msereferenceout\" \"mse.txt\"\n\
         Option \"string rendercoordsys\" \"world\"\n\
         Option \"string spectral\" \"on\"\n\
         WorldBegin\n\
         Option \"bool wavefront\" false",
    );
    assert_eq!(
        s.options,
        SceneOptions {
            seed: Some(-7),
            disable_pixel_jitter: true,
            disable_texture_filtering: true,
            disable_wavelength_jitter: true,
            displacement_edge_scale: Some(0.5),
            mse_reference_image: Some("ref.exr".into()),
            mse_reference_out: Some("mse.txt".into()),
            render_coord_sys: Some("world".into()),
            force_diffuse: true,
            pixel_stats: true,
            wavefront: false,
            spectral: Some("on".into()),
        }
    );
}

#[test]
fn materials_named_and_anonymous() {
    let s = load(&scene(
        "",
        "Shape \"sphere\"\n\
         Material \"conductor\" \"float roughness\" 0.1\nShape \"sphere\"\n\
         MakeNamedMaterial \"glass\" \"string type\" \"dielectric\" \"float eta\" 1.5\n\
         NamedMaterial \"glass\"\nShape \"sphere\"\n\
         Material \"diffuse\"\nShape \"sphere\"",
    ));
    let refs: Vec<&MaterialRef> = s.shapes.iter().map(|sh| &sh.material).collect();
    assert_eq!(
        refs,
        [&MaterialRef::Index(0), &MaterialRef::Index(1), &MaterialRef::Named("glass".into()), &MaterialRef::Index(2),]
    );
    let types: Vec<&str> = s.shapes.iter().map(|sh| s.material_of(&sh.material).unwrap().name.as_str()).collect();
    assert_eq!(types, ["diffuse", "conductor", "dielectric", "diffuse"]);
    let glass = s.named_material("glass").unwrap();
    assert_eq!(glass.entity.params.get_one_float("eta", 1.0), Ok(1.5));
    assert_eq!(glass.entity.loc.to_string(), "t.pbrt:6:1");
    // "string type" picks the type and counts as used.
    assert_eq!(glass.entity.params.report_unused(), []);
}

#[test]
fn textures_keep_value_type_class_and_transform() {
    let s = load(&scene(
        "",
        "Scale 2 2 2\nTexture \"checks\" \"spectrum\" \"checkerboard\" \"float uscale\" 8\n\
         Texture \"bump\" \"float\" \"imagemap\" \"string filename\" \"b.png\"",
    ));
    let t = s.texture("checks", TextureValue::Spectrum).unwrap();
    assert_eq!(t.entity.name, "checkerboard");
    assert_eq!(t.entity.params.get_one_float("uscale", 1.0), Ok(8.0));
    assert_eq!(t.world_from_texture.start.transform_point3(glam::DVec3::ONE), glam::DVec3::splat(2.0));
    assert!(s.texture("checks", TextureValue::Float).is_none());
    let b = s.texture("bump", TextureValue::Float).unwrap();
    assert_eq!(b.entity.name, "imagemap");
    assert_eq!(b.entity.loc.to_string(), "t.pbrt:5:1");
}

#[test]
fn reverse_orientation_toggles_within_its_block() {
    let s = load(&scene(
        "",
        "Shape \"sphere\"\nAttributeBegin\nReverseOrientation\nShape \"sphere\"\n\
         ReverseOrientation\nShape \"sphere\"\nReverseOrientation\nAttributeEnd\nShape \"sphere\"",
    ));
    let flags: Vec<bool> = s.shapes.iter().map(|sh| sh.reverse_orientation).collect();
    assert_eq!(flags, [false, true, false, false]);
}

#[test]
fn attribute_defaults_apply_to_their_kind_within_their_block() {
    let s = load(&scene(
        "",
        "AttributeBegin\n\
           Attribute \"shape\" \"float radius\" 0.5 \"float zmax\" 0.25\n\
           Attribute \"light\" \"rgb L\" [ 1 2 3 ]\n\
           Attribute \"material\" \"float roughness\" 0.3\n\
           Attribute \"texture\" \"float scale\" 4\n\
           Attribute \"medium\" \"float g\" 0.7\n\
           Shape \"sphere\"\n\
           Shape \"sphere\" \"float radius\" 2\n\
           LightSource \"point\" \"float power\" 10\n\
           Material \"conductor\"\n\
           MakeNamedMaterial \"m\" \"string type\" \"diffuse\"\n\
           Texture \"t\" \"float\" \"constant\"\n\
           MakeNamedMedium \"f\" \"string type\" \"homogeneous\"\n\
           Attribute \"shape\" \"float radius\" 0.75\n\
           Shape \"sphere\"\n\
         AttributeEnd\n\
         Shape \"sphere\"\nMaterial \"diffuse\"",
    ));
    let radius = |i: usize| s.shapes[i].entity.params.get_one_float("radius", 1.0).unwrap();
    // Defaults apply; the shape's own parameter wins; later Attributes win over earlier ones;
    // AttributeEnd drops them.
    assert_eq!([radius(0), radius(1), radius(2), radius(3)], [0.5, 2.0, 0.75, 1.0]);
    assert_eq!(s.shapes[0].entity.params.get_one_float("zmax", 1.0), Ok(0.25));
    assert_eq!(s.lights[0].entity.params.get_rgbs("L"), Ok(&[[1.0, 2.0, 3.0]][..]));
    assert_eq!(s.materials[1].params.get_one_float("roughness", 0.0), Ok(0.3));
    assert_eq!(s.named_material("m").unwrap().entity.params.get_one_float("roughness", 0.0), Ok(0.3));
    assert_eq!(s.textures[0].entity.params.get_one_float("scale", 1.0), Ok(4.0));
    assert_eq!(s.medium("f").unwrap().entity.params.get_one_float("g", 0.0), Ok(0.7));
    // Defaults go only to their own kind...
    assert_eq!(s.lights[0].entity.params.peek("radius"), None);
    assert_eq!(s.materials[1].params.peek("L"), None);
    assert_eq!(s.materials[2].params.peek("roughness"), None);
    // ...and an entity need not use them: only its own parameters are reported unused.
    assert_eq!(s.shapes[1].entity.params.report_unused(), []);
    let light_unused: Vec<String> = s.lights[0].entity.params.report_unused().iter().map(|w| w.to_string()).collect();
    assert_eq!(light_unused, ["t.pbrt:11:21: \"float power\": unused parameter"]);
}

#[test]
fn an_attribute_default_of_another_type_does_not_hide_the_real_parameter() {
    let s = load(&scene("", "Attribute \"shape\" \"integer radius\" 3\nShape \"sphere\""));
    // The default has the wrong type for this lookup, but being a default it is skipped
    // rather than reported.
    assert_eq!(s.shapes[0].entity.params.get_one_float("radius", 1.0), Ok(1.0));
}

#[test]
fn transform_begin_is_a_deprecated_attribute_begin() {
    let s = load(&scene(
        "",
        "TransformBegin\nTranslate 1 0 0\nMaterial \"conductor\"\nTransformEnd\nShape \"sphere\"\n\
         TransformBegin\nTransformEnd",
    ));
    assert_eq!(s.shapes[0].material, MaterialRef::Index(0));
    assert_eq!(s.shapes[0].world_from_object.start.transform_point3(glam::DVec3::ZERO), glam::DVec3::ZERO);
    // Warned once.
    let warnings: Vec<String> = s.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(warnings, ["t.pbrt:3:1: TransformBegin/TransformEnd are deprecated: use AttributeBegin/AttributeEnd"]);
}

/// A statement of a generated world block.
#[derive(Clone, Debug)]
enum Item {
    Translate([i8; 3]),
    ReverseOrientation,
    Material,
    AreaLight,
    Shape,
    Block(Vec<Item>),
}

fn items() -> impl proptest::strategy::Strategy<Value = Vec<Item>> {
    use proptest::prelude::*;
    let leaf = prop_oneof![
        any::<[i8; 3]>().prop_map(Item::Translate),
        Just(Item::ReverseOrientation),
        Just(Item::Material),
        Just(Item::AreaLight),
        Just(Item::Shape),
        Just(Item::Shape),
    ];
    let item = leaf.prop_recursive(4, 48, 6, |inner| proptest::collection::vec(inner, 0..6).prop_map(Item::Block));
    proptest::collection::vec(item, 0..10)
}

/// What the graphics state should give each shape.
#[derive(Clone, Debug, PartialEq)]
struct Expected {
    translation: [f64; 3],
    reverse: bool,
    material: usize,
    area_light: Option<usize>,
}

#[derive(Clone)]
struct State {
    translation: [f64; 3],
    reverse: bool,
    material: usize,
    area_light: bool,
}

/// Writes `items` as pbrt text and works out, independently of the builder, what each shape
/// should get.
fn model(
    items: &[Item],
    state: &mut State,
    text: &mut String,
    materials: &mut usize,
    area_lights: &mut usize,
    shapes: &mut Vec<Expected>,
) {
    for item in items {
        match item {
            Item::Translate(d) => {
                text.push_str(&format!("Translate {} {} {}\n", d[0], d[1], d[2]));
                for (t, d) in state.translation.iter_mut().zip(d) {
                    *t += f64::from(*d);
                }
            }
            Item::ReverseOrientation => {
                text.push_str("ReverseOrientation\n");
                state.reverse = !state.reverse;
            }
            Item::Material => {
                text.push_str("Material \"conductor\"\n");
                state.material = *materials;
                *materials += 1;
            }
            Item::AreaLight => {
                text.push_str("AreaLightSource \"diffuse\"\n");
                state.area_light = true;
            }
            Item::Shape => {
                text.push_str("Shape \"sphere\"\n");
                let area_light = state.area_light.then(|| {
                    *area_lights += 1;
                    *area_lights - 1
                });
                shapes.push(Expected {
                    translation: state.translation,
                    reverse: state.reverse,
                    material: state.material,
                    area_light,
                });
            }
            Item::Block(inner) => {
                text.push_str("AttributeBegin\n");
                let mut inner_state = state.clone();
                model(inner, &mut inner_state, text, materials, area_lights, shapes);
                text.push_str("AttributeEnd\n");
            }
        }
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 128, ..Default::default() })]

    #[test]
    fn attribute_blocks_save_and_restore_the_graphics_state(items in items()) {
        let mut text = String::from("Camera \"perspective\"\nWorldBegin\n");
        let mut expected = Vec::new();
        let mut state = State {
            translation: [0.0; 3],
            reverse: false,
            material: 0,
            area_light: false,
        };
        model(&items, &mut state, &mut text, &mut 1, &mut 0, &mut expected);
        let s = nimbus_parser::load_str(&text, "generated.pbrt");
        proptest::prop_assert!(s.is_ok(), "{:?}\n{}", s, text);
        let s = s.unwrap();
        let got: Vec<Expected> = s
            .shapes
            .iter()
            .map(|sh| {
                let MaterialRef::Index(material) = sh.material else {
                    panic!("{:?}", sh.material)
                };
                Expected {
                    translation: sh
                        .world_from_object
                        .start
                        .transform_point3(glam::DVec3::ZERO)
                        .to_array(),
                    reverse: sh.reverse_orientation,
                    material,
                    area_light: sh.area_light,
                }
            })
            .collect();
        proptest::prop_assert_eq!(got, expected, "{}", text);
    }
}
