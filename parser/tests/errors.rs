//! Each class of error, with its exact message and `file:line:col`.

use nimbus_parser::{Error, SceneBuilder, load_str, parse_bytes};

use crate::common::{load, load_err, load_err_string, parse_err_string, scene};

#[test]
fn unknown_directive() {
    assert_eq!(load_err_string("WorldBegin\n  Shpe \"sphere\""), "t.pbrt:2:3: unknown directive \"Shpe\"");
    // Directive names are case-sensitive.
    assert_eq!(parse_err_string("worldbegin"), "t.pbrt:1:1: unknown directive \"worldbegin\"");
    assert_eq!(
        parse_err_string("WorldBegin\nWorldEnd\n"),
        "t.pbrt:2:1: unknown directive \"WorldEnd\" (a pbrt-v3 directive; pbrt-v4 scenes end without it)"
    );
    // Long words are shortened in the message.
    let long = "X".repeat(70);
    assert_eq!(parse_err_string(&long), format!("t.pbrt:1:1: unknown directive \"{}...\"", "X".repeat(60)));
}

#[test]
fn options_directives_after_world_begin() {
    for (directive, keyword) in [
        ("Camera \"perspective\"", "Camera"),
        ("Film \"rgb\"", "Film"),
        ("Sampler \"halton\"", "Sampler"),
        ("Integrator \"path\"", "Integrator"),
        ("PixelFilter \"box\"", "PixelFilter"),
        ("Accelerator \"bvh\"", "Accelerator"),
        ("TransformTimes 0 1", "TransformTimes"),
        ("WorldBegin", "WorldBegin"),
    ] {
        assert_eq!(
            load_err_string(&format!("WorldBegin\nShape \"sphere\"\n  {directive}")),
            format!("t.pbrt:3:3: {keyword} is not allowed after WorldBegin (options block only)")
        );
    }
}

#[test]
fn world_directives_before_world_begin() {
    for (directive, keyword) in [
        ("Shape \"sphere\"", "Shape"),
        ("LightSource \"point\"", "LightSource"),
        ("AreaLightSource \"diffuse\"", "AreaLightSource"),
        ("Material \"diffuse\"", "Material"),
        ("MakeNamedMaterial \"m\" \"string type\" \"diffuse\"", "MakeNamedMaterial"),
        ("NamedMaterial \"m\"", "NamedMaterial"),
        ("Texture \"t\" \"float\" \"constant\"", "Texture"),
        ("AttributeBegin", "AttributeBegin"),
        ("AttributeEnd", "AttributeEnd"),
        ("TransformBegin", "TransformBegin"),
        ("TransformEnd", "TransformEnd"),
        ("ObjectBegin \"o\"", "ObjectBegin"),
        ("ObjectEnd", "ObjectEnd"),
        ("ObjectInstance \"o\"", "ObjectInstance"),
        ("ReverseOrientation", "ReverseOrientation"),
    ] {
        assert_eq!(
            load_err_string(&format!("Camera \"perspective\"\n {directive}\nWorldBegin")),
            format!("t.pbrt:2:2: {keyword} is not allowed before WorldBegin (world block only)")
        );
    }
}

#[test]
fn directives_allowed_in_both_blocks() {
    // Transforms, media, attributes, color spaces, options and coordinate systems may appear
    // on either side of WorldBegin.
    let both = "Translate 1 0 0\nScale 1 1 1\nRotate 10 0 1 0\nIdentity\n\
                Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]\n\
                ConcatTransform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]\n\
                LookAt 0 0 0 0 0 1 0 1 0\nCoordinateSystem \"c\"\nCoordSysTransform \"c\"\n\
                ActiveTransform All\nColorSpace \"srgb\"\nOption \"seed\" 3\n\
                MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n\
                MediumInterface \"\" \"\"\nAttribute \"shape\" \"float radius\" 1";
    let both_world = both.replace("MakeNamedMedium \"m\"", "MakeNamedMedium \"m2\"");
    load(&scene(both, &both_world));
}

#[test]
fn missing_world_begin() {
    let e = load_err("Camera \"perspective\"\n");
    assert_eq!(
        e,
        Error { loc: None, message: "end of scene before WorldBegin: a pbrt-v4 scene needs a WorldBegin".into() }
    );
    assert_eq!(e.to_string(), "end of scene before WorldBegin: a pbrt-v4 scene needs a WorldBegin");
    assert_eq!(
        load_str("", "empty.pbrt").unwrap_err().to_string(),
        "end of scene before WorldBegin: a pbrt-v4 scene needs a WorldBegin"
    );
}

#[test]
fn wrong_parameter_value_type() {
    assert_eq!(
        load_err_string("WorldBegin\nShape \"sphere\" \"float radius\" \"big\""),
        "t.pbrt:2:31: string \"big\": expected a number for \"float radius\""
    );
    assert_eq!(
        load_err_string("WorldBegin\nShape \"sphere\" \"floot radius\" 1"),
        "t.pbrt:2:16: \"floot\": unknown parameter type"
    );
}

#[test]
fn wrong_parameter_value_count() {
    assert_eq!(
        load_err_string("WorldBegin\nShape \"trianglemesh\"\n  \"point3 P\" [ 0 0 0 1 0 ]"),
        "t.pbrt:3:3: \"point3 P\": 5 values given, but a point3 takes 3: the count must be a multiple of 3"
    );
}

#[test]
fn undefined_named_material() {
    assert_eq!(
        load_err_string(&scene("", "AttributeBegin\n  NamedMaterial \"gold\"\n  Shape \"sphere\"\nAttributeEnd")),
        "t.pbrt:4:3: named material \"gold\" is not defined"
    );
    // A name nothing uses is not checked; a name defined later is fine.
    load(&scene("", "NamedMaterial \"unused\""));
    load(&scene(
        "",
        "NamedMaterial \"late\"\nShape \"sphere\"\nMakeNamedMaterial \"late\" \"string type\" \"diffuse\"",
    ));
}

#[test]
fn undefined_medium() {
    // Used by a shape.
    assert_eq!(
        load_err_string(&scene(
            "",
            "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\nMediumInterface \"fog\" \"smoke\"\nShape \"sphere\""
        )),
        "t.pbrt:4:1: medium \"smoke\" is not defined"
    );
    // Used by the camera.
    assert_eq!(
        load_err_string(&scene("MediumInterface \"fog\"\nCamera \"perspective\"", "")),
        "t.pbrt:1:1: medium \"fog\" is not defined"
    );
    // Used by a light.
    assert_eq!(
        load_err_string(&scene("", "MediumInterface \"\" \"air\"\nLightSource \"point\"")),
        "t.pbrt:3:1: medium \"air\" is not defined"
    );
    // Set but used by nothing: not checked.
    load(&scene("", "MediumInterface \"nothing\""));
}

#[test]
fn undefined_texture() {
    assert_eq!(
        load_err_string(&scene("", "Material \"diffuse\"\n    \"texture reflectance\" \"checks\"\nShape \"sphere\"")),
        "t.pbrt:4:5: texture \"checks\" is not defined"
    );
    assert_eq!(
        load_err_string(&scene("", "Shape \"sphere\" \"texture alpha\" \"mask\"")),
        "t.pbrt:3:16: texture \"mask\" is not defined"
    );
    assert_eq!(
        load_err_string(&scene("", "Texture \"mix\" \"float\" \"mix\" \"texture tex1\" \"a\"")),
        "t.pbrt:3:29: texture \"a\" is not defined"
    );
    assert_eq!(
        load_err_string(&scene(
            "",
            "MakeNamedMaterial \"m\" \"string type\" \"diffuse\" \"texture reflectance\" \"t\""
        )),
        "t.pbrt:3:47: texture \"t\" is not defined"
    );
    assert_eq!(
        load_err_string(&scene("", "LightSource \"projection\" \"texture image\" \"slide\"")),
        "t.pbrt:3:26: texture \"slide\" is not defined"
    );
    // Float and spectrum textures of those names are both fine.
    load(&scene(
        "",
        "Texture \"a\" \"float\" \"constant\"\nTexture \"b\" \"spectrum\" \"constant\"\n\
         Material \"diffuse\" \"texture reflectance\" \"b\" \"texture displacement\" \"a\"",
    ));
}

#[test]
fn undefined_object() {
    assert_eq!(
        load_err_string(&scene("", "Translate 1 0 0\n  ObjectInstance \"tree\"")),
        "t.pbrt:4:3: object \"tree\" is not defined (ObjectInstance needs an ObjectBegin of that name)"
    );
}

#[test]
fn unterminated_string() {
    assert_eq!(
        parse_err_string("WorldBegin\nShape \"sphere\n\"float radius\" 1"),
        "t.pbrt:2:7: unterminated string: newline before the closing '\"'"
    );
    // An escaped newline does not continue the string either.
    assert_eq!(
        parse_err_string("Shape \"sph\\\nere\""),
        "t.pbrt:1:7: unterminated string: newline before the closing '\"'"
    );
    assert_eq!(parse_err_string("Shape \"sphere"), "t.pbrt:1:7: premature end of file inside a quoted string");
    assert_eq!(parse_err_string("Shape \"sphere\\"), "t.pbrt:1:7: premature end of file inside a quoted string");
}

#[test]
fn bad_escape_in_string() {
    assert_eq!(parse_err_string("Shape \"s\\qx\""), "t.pbrt:1:7: unexpected escaped character '\\q' in string");
}

#[test]
fn premature_end_of_file() {
    // The location is the end of the file.
    let cases = [
        ("Translate 1 2", "1:14", "a number for Translate"),
        ("Rotate 1 0 0\n", "2:1", "a number for Rotate"),
        ("Transform [ 1 2", "1:16", "a number for Transform"),
        ("Transform", "1:10", "'[' and 16 numbers"),
        ("Transform [ 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1", "1:44", "']' after 16 numbers"),
        ("Shape", "1:6", "a type name"),
        ("Shape \"s\" \"float r\"", "1:20", "a value for parameter \"r\""),
        ("Shape \"s\" \"float r\" [ 1 2 ", "1:27", "']' to close the values of \"r\""),
        ("Texture \"t\" \"float\"", "1:20", "the texture class"),
        ("Option \"seed\"", "1:14", "an option value"),
        ("ActiveTransform", "1:16", "All, StartTime or EndTime after ActiveTransform"),
        ("Include", "1:8", "a file name after Include"),
        ("Import", "1:7", "a file name after Import"),
        ("MediumInterface", "1:16", "a medium name after MediumInterface"),
        ("ColorSpace", "1:11", "a color space name"),
    ];
    for (text, at, what) in cases {
        assert_eq!(parse_err_string(text), format!("t.pbrt:{at}: premature end of file: expected {what}"), "{text}");
    }
}

#[test]
fn unbalanced_attribute_blocks() {
    assert_eq!(load_err_string(&scene("", "AttributeEnd")), "t.pbrt:3:1: AttributeEnd without matching AttributeBegin");
    assert_eq!(
        load_err_string(&scene("", "AttributeBegin\n  AttributeBegin\n  AttributeEnd")),
        "t.pbrt:3:1: AttributeBegin has no matching AttributeEnd"
    );
    assert_eq!(
        load_err_string(&scene("", "TransformBegin")),
        "t.pbrt:3:1: AttributeBegin has no matching AttributeEnd"
    );
    assert_eq!(load_err_string(&scene("", "ObjectBegin \"o\"")), "t.pbrt:3:1: ObjectBegin has no matching ObjectEnd");
    assert_eq!(load_err_string(&scene("", "ObjectEnd")), "t.pbrt:3:1: ObjectEnd without ObjectBegin");
    assert_eq!(
        load_err_string(&scene("", "ObjectBegin \"o\"\nAttributeBegin\nObjectEnd")),
        "t.pbrt:5:1: mismatched nesting: ObjectEnd closes the AttributeBegin at t.pbrt:4:1"
    );
    assert_eq!(
        load_err_string(&scene("", "AttributeBegin\nObjectBegin \"o\"\nAttributeEnd")),
        "t.pbrt:5:1: mismatched nesting: AttributeEnd closes the ObjectBegin at t.pbrt:4:1"
    );
}

#[test]
fn object_definition_errors() {
    assert_eq!(
        load_err_string(&scene("", "ObjectBegin \"a\"\nObjectBegin \"b\"")),
        "t.pbrt:4:1: ObjectBegin inside another object definition"
    );
    assert_eq!(
        load_err_string(&scene("", "ObjectBegin \"a\"\nObjectInstance \"a\"")),
        "t.pbrt:4:1: ObjectInstance inside an object definition"
    );
    assert_eq!(
        load_err_string(&scene("", "ObjectBegin \"a\"\nObjectEnd\nObjectBegin \"a\"\nObjectEnd")),
        "t.pbrt:5:1: object \"a\" redefined"
    );
}

#[test]
fn redefinitions() {
    assert_eq!(
        load_err_string(&scene(
            "",
            "MakeNamedMaterial \"m\" \"string type\" \"diffuse\"\nMakeNamedMaterial \"m\" \"string type\" \"diffuse\""
        )),
        "t.pbrt:4:1: named material \"m\" redefined"
    );
    assert_eq!(
        load_err_string(&scene(
            "MakeNamedMedium \"f\" \"string type\" \"homogeneous\"",
            "MakeNamedMedium \"f\" \"string type\" \"homogeneous\""
        )),
        "t.pbrt:3:1: named medium \"f\" redefined"
    );
    assert_eq!(
        load_err_string(&scene("", "Texture \"t\" \"float\" \"constant\"\nTexture \"t\" \"float\" \"constant\"")),
        "t.pbrt:4:1: texture \"t\" redefined"
    );
    // A float and a spectrum texture may share a name.
    load(&scene("", "Texture \"t\" \"float\" \"constant\"\nTexture \"t\" \"spectrum\" \"constant\""));
}

#[test]
fn bad_directive_arguments() {
    let cases = [
        ("ColorSpace \"adobe\"", "t.pbrt:3:1: unknown color space \"adobe\" (srgb, rec2020, aces2065-1 or dci-p3)"),
        (
            "Attribute \"camera\" \"float fov\" 30",
            "t.pbrt:3:1: unknown Attribute target \"camera\": must be \"shape\", \"light\", \"material\", \"medium\" or \"texture\"",
        ),
        (
            "MakeNamedMaterial \"m\" \"rgb reflectance\" [ 1 1 1 ]",
            "t.pbrt:3:1: MakeNamedMaterial \"m\": missing \"string type\" parameter",
        ),
        ("MakeNamedMedium \"m\" \"float g\" 0", "t.pbrt:3:1: MakeNamedMedium \"m\": missing \"string type\" parameter"),
        (
            "Texture \"t\" \"color\" \"constant\"",
            "t.pbrt:3:1: texture type \"color\" unknown: must be \"float\" or \"spectrum\"",
        ),
        ("Rotate 45 0 0 0", "t.pbrt:3:1: Rotate: the rotation axis is zero"),
        ("LookAt 0 0 0  0 0 0  0 1 0", "t.pbrt:3:1: LookAt: the view direction is zero or parallel to the up vector"),
        ("LookAt 0 0 0  0 2 0  0 1 0", "t.pbrt:3:1: LookAt: the view direction is zero or parallel to the up vector"),
    ];
    for (world, expected) in cases {
        assert_eq!(load_err_string(&scene("", world)), expected, "{world}");
    }
    assert_eq!(
        load_err_string("Scale 1 0 1\nCamera \"perspective\"\nWorldBegin"),
        "t.pbrt:2:1: the camera transform is singular (cannot be inverted)"
    );
}

#[test]
fn option_errors() {
    let cases = [
        ("Option \"bogus\" 1", "Option \"bogus\": unknown option"),
        ("Option \"bool wavefront\" 1", "Option \"bool wavefront\": expected true or false, found 1"),
        ("Option \"integer seed\" 1.5", "Option \"integer seed\": expected an integer, found 1.5"),
        (
            "Option \"float displacementedgescale\" x",
            "Option \"float displacementedgescale\": expected a number, found x",
        ),
        (
            "Option \"string msereferenceimage\" ref.exr",
            "Option \"string msereferenceimage\": expected a quoted string, found ref.exr",
        ),
        (
            "Option \"string rendercoordsys\" \"screen\"",
            "Option \"string rendercoordsys\": unknown rendering coordinate system \"screen\" (camera, cameraworld or world)",
        ),
        (
            "Option \"string spectral\" \"yes\"",
            "Option \"string spectral\": unknown transport \"yes\" (auto, on or off)",
        ),
    ];
    for (text, expected) in cases {
        assert_eq!(load_err_string(&format!("{text}\nWorldBegin")), format!("t.pbrt:1:1: {expected}"), "{text}");
    }
}

#[test]
fn encoding_errors() {
    let mut b = SceneBuilder::new();
    assert_eq!(
        parse_bytes(&[0xff, 0xfe, b'W', 0], "utf16.pbrt", &mut b).unwrap_err().to_string(),
        "utf16.pbrt:1:1: file is UTF-16 encoded; pbrt scene files must be UTF-8"
    );
    let mut b = SceneBuilder::new();
    assert_eq!(
        parse_bytes(b"WorldBegin\nShape \"sph\xffere\"", "bytes.pbrt", &mut b).unwrap_err().to_string(),
        "bytes.pbrt:2:7: text is not valid UTF-8"
    );
    let mut b = SceneBuilder::new();
    assert_eq!(
        parse_bytes(b"Wor\xc3ldBegin", "bytes.pbrt", &mut b).unwrap_err().to_string(),
        "bytes.pbrt:1:1: unknown directive \"Wor\u{fffd}ldBegin\""
    );
}

#[test]
fn the_first_error_is_the_one_reported() {
    // Two problems: the earlier one in the file wins, and parsing stops there.
    assert_eq!(
        load_err_string("WorldBegin\nCamera \"perspective\"\nShpe"),
        "t.pbrt:2:1: Camera is not allowed after WorldBegin (options block only)"
    );
}
