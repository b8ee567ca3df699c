//! Parameter lists: every type, bracketed and bare values, repeated names, and the typed
//! lookups of `ParameterDictionary`.

use nimbus_parser::{Directive, FloatOrTexture, Param, ParamType, ParamValues, SpectrumOrTexture, SpectrumValue};

use crate::common::{directive, load, load_err_string, parse_err_string, scene};

/// The parameters of the single `Shape` in `params`.
#[track_caller]
fn shape_params(params: &str) -> Vec<Param> {
    match directive(&format!("Shape \"test\" {params}")) {
        Directive::Shape(name, params) => {
            assert_eq!(name, "test");
            params
        }
        other => panic!("not a shape: {other:?}"),
    }
}

/// The one parameter of `Shape "test" {param}`.
#[track_caller]
fn one_param(param: &str) -> Param {
    let mut p = shape_params(param);
    assert_eq!(p.len(), 1, "{p:?}");
    p.remove(0)
}

#[test]
fn every_parameter_type_parses_with_its_values() {
    let cases: [(&str, ParamType, ParamValues); 16] = [
        (
            "\"integer n\" [ -3 0 2147483647 -2147483648 +5 ]",
            ParamType::Integer,
            ParamValues::Ints(vec![-3, 0, i32::MAX, i32::MIN, 5]),
        ),
        (
            "\"float n\" [ 1 -2.5 .5 5. 1e3 -1E-2 +4 ]",
            ParamType::Float,
            ParamValues::Floats(vec![1.0, -2.5, 0.5, 5.0, 1000.0, -0.01, 4.0]),
        ),
        ("\"point2 n\" [ 1 2 3 4 ]", ParamType::Point2, ParamValues::Floats(vec![1.0, 2.0, 3.0, 4.0])),
        ("\"vector2 n\" [ 0.5 -0.5 ]", ParamType::Vector2, ParamValues::Floats(vec![0.5, -0.5])),
        ("\"point3 n\" [ 1 2 3 4 5 6 ]", ParamType::Point3, ParamValues::Floats(vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0])),
        ("\"vector3 n\" [ 0 0 1 ]", ParamType::Vector3, ParamValues::Floats(vec![0.0, 0.0, 1.0])),
        ("\"normal n\" [ 0 1 0 ]", ParamType::Normal, ParamValues::Floats(vec![0.0, 1.0, 0.0])),
        ("\"bool n\" [ true false true ]", ParamType::Bool, ParamValues::Bools(vec![true, false, true])),
        (
            "\"string n\" [ \"a\" \"b c\" \"\" ]",
            ParamType::String,
            ParamValues::Strings(vec!["a".into(), "b c".into(), String::new()]),
        ),
        ("\"texture n\" \"checks\"", ParamType::Texture, ParamValues::Strings(vec!["checks".into()])),
        ("\"rgb n\" [ 0.25 0.5 1 ]", ParamType::Rgb, ParamValues::Floats(vec![0.25, 0.5, 1.0])),
        (
            "\"spectrum n\" [ 300 0.5 400 1 800.5 0 ]",
            ParamType::Spectrum,
            ParamValues::Floats(vec![300.0, 0.5, 400.0, 1.0, 800.5, 0.0]),
        ),
        ("\"spectrum n\" \"metal-Au-eta\"", ParamType::Spectrum, ParamValues::Strings(vec!["metal-Au-eta".into()])),
        ("\"blackbody n\" 6500", ParamType::Blackbody, ParamValues::Floats(vec![6500.0])),
        // Declarations may carry extra spaces.
        ("\"  float   n \" 1", ParamType::Float, ParamValues::Floats(vec![1.0])),
        // Numbers and brackets need no spaces around them.
        ("\"float n\"[1 2]", ParamType::Float, ParamValues::Floats(vec![1.0, 2.0])),
    ];
    for (text, ty, values) in cases {
        let p = one_param(text);
        assert_eq!((p.ty, p.name.as_str(), &p.values), (ty, "n", &values), "{text}");
    }
}

#[test]
fn every_type_is_covered_above() {
    // ParamType::ALL lists each type once, each with the spelling scene files use.
    let names: Vec<&str> = ParamType::ALL.iter().map(|t| t.name()).collect();
    assert_eq!(
        names,
        [
            "integer",
            "float",
            "point2",
            "vector2",
            "point3",
            "vector3",
            "normal",
            "bool",
            "string",
            "texture",
            "rgb",
            "spectrum",
            "blackbody"
        ]
    );
    for t in ParamType::ALL {
        assert_eq!(ParamType::from_name(t.name()), Some(t));
    }
    assert_eq!(ParamType::from_name("point"), None);
}

#[test]
fn booleans_may_be_quoted() {
    assert_eq!(
        one_param("\"bool b\" [ \"true\" false \"false\" ]").values,
        ParamValues::Bools(vec![true, false, false])
    );
}

#[test]
fn a_single_value_needs_no_brackets() {
    assert_eq!(one_param("\"float r\" 2").values, ParamValues::Floats(vec![2.0]));
    assert_eq!(one_param("\"integer r\" 7").values, ParamValues::Ints(vec![7]));
    assert_eq!(one_param("\"bool r\" false").values, ParamValues::Bools(vec![false]));
    assert_eq!(one_param("\"string r\" \"x\"").values, ParamValues::Strings(vec!["x".into()]));
    // Without brackets only the first value belongs to the parameter: a second number is
    // taken as the next directive, which is an error.
    assert_eq!(parse_err_string("Shape \"s\" \"float r\" 1 2"), "t.pbrt:1:23: unknown directive \"2\"");
}

#[test]
fn empty_brackets_give_empty_values_of_the_types_kind() {
    for (decl, values) in [
        ("integer", ParamValues::Ints(vec![])),
        ("bool", ParamValues::Bools(vec![])),
        ("string", ParamValues::Strings(vec![])),
        ("texture", ParamValues::Strings(vec![])),
        ("float", ParamValues::Floats(vec![])),
        ("point3", ParamValues::Floats(vec![])),
        ("spectrum", ParamValues::Floats(vec![])),
    ] {
        assert_eq!(one_param(&format!("\"{decl} x\" [ ]")).values, values, "{decl}");
    }
}

#[test]
fn parameters_keep_file_order_and_their_locations() {
    let p = shape_params("\"float a\" 1\n  \"integer b\" [ 2 ]\n\t\"string c\" \"x\"");
    let names: Vec<&str> = p.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["a", "b", "c"]);
    let locs: Vec<String> = p.iter().map(|p| p.loc.to_string()).collect();
    assert_eq!(locs, ["t.pbrt:1:14", "t.pbrt:2:3", "t.pbrt:3:2"]);
}

#[test]
fn strings_decode_escapes() {
    let p = one_param(r#""string s" [ "q\"b\\n\nt\tr\rb\bf\f'\'" ]"#);
    assert_eq!(p.values, ParamValues::Strings(vec!["q\"b\\n\nt\tr\rb\u{8}f\u{c}''".into()]));
}

#[test]
fn comments_and_brackets_inside_strings_are_text() {
    let p = one_param("\"string s\" [ \"a # b [c]\" ] # a comment \"string t\" \"x\"");
    assert_eq!(p.values, ParamValues::Strings(vec!["a # b [c]".into()]));
}

#[test]
fn repeated_parameter_last_one_wins() {
    let s = load(&scene(
        "Camera \"perspective\" \"float fov\" 30 \"float fov\" [ 45 ]",
        "Shape \"sphere\" \"float radius\" 1 \"float radius\" 2 \"float radius\" 3",
    ));
    assert_eq!(s.camera.entity.params.get_one_float("fov", 90.0), Ok(45.0));
    let shape = &s.shapes[0].entity.params;
    assert_eq!(shape.get_one_float("radius", 1.0), Ok(3.0));
    // The shadowed occurrences are not "unused".
    assert_eq!(shape.report_unused(), []);
    // The parsed directive keeps all three, in order.
    let Directive::Shape(_, p) = directive("Shape \"s\" \"float r\" 1 \"float r\" 2") else { panic!() };
    assert_eq!(p.len(), 2);
}

#[test]
fn repeated_name_with_another_type_is_reported_on_lookup() {
    // The last occurrence wins even when its type is not the one asked for.
    let s = load(&scene("", "Shape \"sphere\" \"float radius\" 1\n  \"integer radius\" 2"));
    assert_eq!(
        s.shapes[0].entity.params.get_one_float("radius", 1.0).unwrap_err().to_string(),
        "t.pbrt:4:3: parameter \"radius\" has type \"integer\" but must be \"float\""
    );
}

#[test]
fn typed_lookups_return_values_and_defaults() {
    let s = load(&scene(
        "",
        r#"Shape "trianglemesh"
    "integer indices" [ 0 1 2 ]
    "point3 P" [ 0 0 0  1 0 0  0 1 0 ]
    "normal N" [ 0 0 1  0 0 1  0 0 1 ]
    "point2 uv" [ 0 0  1 0  0 1 ]
    "vector3 S" [ 1 0 0  1 0 0  1 0 0 ]
    "vector2 v" [ 3 4 ]
    "bool flag" true
    "string alphamode" "cutout"
    "string names" [ "a" "b" ]
    "float alpha" 0.5
    "float arr" [ 1 2 3 ]
    "texture tex" "t"
    "rgb c" [ 0.1 0.2 0.3 ]
    "blackbody b" 3000
    "spectrum s" [ 400 1 500 2 ]
    "spectrum named" "metal-Cu-k"
    "float extra" 1
Texture "t" "float" "constant" "float value" 1"#,
    ));
    let p = &s.shapes[0].entity.params;
    assert_eq!(p.get_ints("indices"), Ok(&[0, 1, 2][..]));
    assert_eq!(p.get_point3s("P"), Ok(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]][..]));
    assert_eq!(p.get_normals("N").unwrap().len(), 3);
    assert_eq!(p.get_point2s("uv"), Ok(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]][..]));
    assert_eq!(p.get_vector3s("S").unwrap()[2], [1.0, 0.0, 0.0]);
    assert_eq!(p.get_one_vector2("v", [0.0; 2]), Ok([3.0, 4.0]));
    assert_eq!(p.get_one_bool("flag", false), Ok(true));
    assert_eq!(p.get_one_string("alphamode", "none"), Ok("cutout"));
    assert_eq!(p.get_strings("names"), Ok(&["a".to_string(), "b".to_string()][..]));
    assert_eq!(p.get_one_float("alpha", 1.0), Ok(0.5));
    assert_eq!(p.get_floats("arr"), Ok(&[1.0, 2.0, 3.0][..]));
    assert_eq!(p.get_texture("tex"), Ok(Some("t")));
    assert_eq!(p.get_rgbs("c"), Ok(&[[0.1, 0.2, 0.3]][..]));
    match p.get_one_spectrum("b").unwrap().unwrap().value {
        SpectrumValue::Blackbody(t) => assert_eq!(t, 3000.0),
        other => panic!("{other:?}"),
    }
    match p.get_one_spectrum("s").unwrap().unwrap().value {
        SpectrumValue::Samples(v) => assert_eq!(v, [400.0, 1.0, 500.0, 2.0]),
        other => panic!("{other:?}"),
    }
    match p.get_spectrum_or_texture("named").unwrap().unwrap() {
        SpectrumOrTexture::Value(v) => {
            assert_eq!(v.value, SpectrumValue::Named("metal-Cu-k"));
            assert_eq!(v.loc.to_string(), "t.pbrt:19:5");
        }
        other => panic!("{other:?}"),
    }
    match p.get_spectrum_or_texture("c").unwrap().unwrap() {
        SpectrumOrTexture::Value(v) => assert_eq!(v.value, SpectrumValue::Rgb([0.1, 0.2, 0.3])),
        other => panic!("{other:?}"),
    }
    match p.get_float_or_texture("tex").unwrap().unwrap() {
        FloatOrTexture::Texture(name, loc) => {
            assert_eq!(name, "t");
            assert_eq!(loc.to_string(), "t.pbrt:15:5");
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(p.get_float_or_texture("alpha"), Ok(Some(FloatOrTexture::Value(0.5)))));
    // Absent names give defaults / nothing.
    assert_eq!(p.get_one_float("missing", 7.0), Ok(7.0));
    assert_eq!(p.get_one_int("missing", 3), Ok(3));
    assert_eq!(p.get_opt_string("missing"), Ok(None));
    assert_eq!(p.get_floats("missing"), Ok(&[][..]));
    assert_eq!(p.get_one_spectrum("missing").unwrap().map(|s| s.value), None);
    // Every lookup above marked its parameter used; only "extra" was never asked for.
    let unused: Vec<String> = p.report_unused().iter().map(|w| w.to_string()).collect();
    assert_eq!(unused, ["t.pbrt:20:5: \"float extra\": unused parameter"]);
}

#[test]
fn unused_parameters_are_reported_with_their_location() {
    let s = load(&scene("", "Shape \"sphere\" \"float radius\" 1\n    \"float radiuss\" 2"));
    let p = &s.shapes[0].entity.params;
    assert_eq!(p.get_one_float("radius", 1.0), Ok(1.0));
    let unused: Vec<String> = p.report_unused().iter().map(|w| w.to_string()).collect();
    assert_eq!(unused, ["t.pbrt:4:5: \"float radiuss\": unused parameter"]);
}

#[test]
fn lookup_errors_name_the_parameter_and_its_location() {
    let s = load(&scene(
        "",
        r#"Shape "sphere"
    "integer radius" 2
    "float zmin" [ 1 2 ]
    "float zmax" [ ]
    "point3 p" [ 1 2 3 4 5 6 ]
    "texture t" [ "a" "b" ]
    "rgb c" [ 1 2 3 4 5 6 ]
Texture "a" "float" "constant"
Texture "b" "float" "constant""#,
    ));
    let p = &s.shapes[0].entity.params;
    let err = |r: Result<(), nimbus_parser::Error>| r.unwrap_err().to_string();
    assert_eq!(
        err(p.get_one_float("radius", 1.0).map(drop)),
        "t.pbrt:4:5: parameter \"radius\" has type \"integer\" but must be \"float\""
    );
    assert_eq!(
        err(p.get_float_or_texture("radius").map(drop)),
        "t.pbrt:4:5: parameter \"radius\" has type \"integer\" but must be \"float\" or \"texture\""
    );
    assert_eq!(
        err(p.get_spectrum_or_texture("radius").map(drop)),
        "t.pbrt:4:5: parameter \"radius\" has type \"integer\" but must be \"rgb\", \"blackbody\", \"spectrum\" or \"texture\""
    );
    assert_eq!(
        err(p.get_one_float("zmin", 0.0).map(drop)),
        "t.pbrt:5:5: more than one value provided for parameter \"zmin\" (expected one float)"
    );
    assert_eq!(err(p.get_one_float("zmax", 0.0).map(drop)), "t.pbrt:6:5: no values provided for parameter \"zmax\"");
    assert_eq!(err(p.get_floats("zmax").map(drop)), "t.pbrt:6:5: no values provided for \"zmax\"");
    assert_eq!(
        err(p.get_one_point3("p", [0.0; 3]).map(drop)),
        "t.pbrt:7:5: more than one value provided for parameter \"p\" (expected one point3)"
    );
    assert_eq!(err(p.get_texture("t").map(drop)), "t.pbrt:8:5: more than one texture name provided for \"t\"");
    assert_eq!(
        err(p.get_one_spectrum("c").map(drop)),
        "t.pbrt:9:5: more than one value provided for parameter \"c\" (expected one rgb)"
    );
}

#[test]
fn wrong_value_kind_is_a_parse_error_at_the_value() {
    let cases = [
        ("\"float r\" \"two\"", "t.pbrt:1:21: string \"two\": expected a number for \"float r\""),
        ("\"float r\" [ 1 x ]", "t.pbrt:1:25: \"x\": expected a number for \"float r\""),
        ("\"float r\" true", "t.pbrt:1:21: \"true\": expected a number for \"float r\""),
        ("\"integer n\" 1.5", "t.pbrt:1:23: \"1.5\": expected an integer for \"integer n\""),
        ("\"integer n\" \"1\"", "t.pbrt:1:23: string \"1\": expected an integer for \"integer n\""),
        ("\"integer n\" 2147483648", "t.pbrt:1:23: \"2147483648\": too large for a 32-bit integer"),
        ("\"bool b\" 1", "t.pbrt:1:20: \"1\": expected true or false for \"bool b\""),
        ("\"bool b\" \"yes\"", "t.pbrt:1:20: string \"yes\": expected true or false for \"bool b\""),
        ("\"string s\" s", "t.pbrt:1:22: \"s\": expected a quoted string for \"string s\""),
        ("\"texture t\" [ 1 ]", "t.pbrt:1:25: \"1\": expected a quoted string for \"texture t\""),
        ("\"rgb c\" [ 1 \"x\" 2 ]", "t.pbrt:1:23: string \"x\": expected a number for \"rgb c\""),
        (
            "\"spectrum s\" [ \"a\" 400 ]",
            "t.pbrt:1:30: \"400\": expected a quoted spectrum name (values cannot mix names and numbers) for \"spectrum s\"",
        ),
        (
            "\"spectrum s\" [ 400 \"a\" ]",
            "t.pbrt:1:30: string \"a\": expected a number (values cannot mix names and numbers) for \"spectrum s\"",
        ),
        ("\"float r\" 1e39", "t.pbrt:1:21: \"1e39\": out of range for a 32-bit float"),
        ("\"float r\" [ 1 [ 2 ] ]", "t.pbrt:1:25: unexpected \"[\" inside the values of \"r\""),
    ];
    for (params, expected) in cases {
        assert_eq!(parse_err_string(&format!("Shape \"s\" {params}")), expected, "{params}");
    }
}

#[test]
fn wrong_value_count_is_a_parse_error_at_the_declaration() {
    let cases = [
        (
            "\"point3 P\" [ 1 2 3 4 ]",
            "t.pbrt:1:11: \"point3 P\": 4 values given, but a point3 takes 3: the count must be a multiple of 3",
        ),
        (
            "\"point2 uv\" [ 1 ]",
            "t.pbrt:1:11: \"point2 uv\": 1 values given, but a point2 takes 2: the count must be a multiple of 2",
        ),
        ("\"rgb c\" 1", "t.pbrt:1:11: \"rgb c\": 1 values given, but a rgb takes 3: the count must be a multiple of 3"),
        (
            "\"normal N\" [ 0 0 ]",
            "t.pbrt:1:11: \"normal N\": 2 values given, but a normal takes 3: the count must be a multiple of 3",
        ),
        (
            "\"vector2 v\" [ 1 2 3 ]",
            "t.pbrt:1:11: \"vector2 v\": 3 values given, but a vector2 takes 2: the count must be a multiple of 2",
        ),
        (
            "\"vector3 v\" [ 1 ]",
            "t.pbrt:1:11: \"vector3 v\": 1 values given, but a vector3 takes 3: the count must be a multiple of 3",
        ),
        (
            "\"spectrum s\" [ 400 1 500 ]",
            "t.pbrt:1:11: \"spectrum s\": odd number of values; expected wavelength/value pairs",
        ),
        (
            "\"spectrum s\" [ 500 1 400 2 ]",
            "t.pbrt:1:11: \"spectrum s\": wavelengths must increase, but 400 follows 500",
        ),
        (
            "\"spectrum s\" [ 400 1 400 2 ]",
            "t.pbrt:1:11: \"spectrum s\": wavelengths must increase, but 400 follows 400",
        ),
    ];
    for (params, expected) in cases {
        assert_eq!(parse_err_string(&format!("Shape \"s\" {params}")), expected, "{params}");
    }
}

#[test]
fn malformed_declarations_are_errors_at_the_declaration() {
    let cases = [
        ("\"colour c\" [ 1 2 3 ]", "t.pbrt:1:11: \"colour\": unknown parameter type"),
        ("\"point P\" [ 1 2 3 ]", "t.pbrt:1:11: \"point\": unknown parameter type (pbrt-v3 spelling: use \"point3\")"),
        (
            "\"vector v\" [ 1 2 3 ]",
            "t.pbrt:1:11: \"vector\": unknown parameter type (pbrt-v3 spelling: use \"vector3\")",
        ),
        ("\"color c\" [ 1 2 3 ]", "t.pbrt:1:11: \"color\": unknown parameter type (pbrt-v3 spelling: use \"rgb\")"),
        ("\"normal3 n\" [ 1 2 3 ]", "t.pbrt:1:11: \"normal3\": unknown parameter type (use \"normal\")"),
        ("\"radius\" 1", "t.pbrt:1:11: \"radius\": a parameter declaration is \"type name\" (e.g. \"float radius\")"),
        (
            "\"float the radius\" 1",
            "t.pbrt:1:11: \"float the radius\": a parameter declaration is \"type name\" (e.g. \"float radius\")",
        ),
        ("\"\" 1", "t.pbrt:1:11: \"\": a parameter declaration is \"type name\" (e.g. \"float radius\")"),
    ];
    for (params, expected) in cases {
        assert_eq!(parse_err_string(&format!("Shape \"s\" {params}")), expected, "{params}");
    }
}

#[test]
fn builder_errors_from_parameters_use_the_parameter_location() {
    assert_eq!(
        load_err_string(&scene("", "MakeNamedMaterial \"m\"\n  \"integer type\" 1")),
        "t.pbrt:4:3: parameter \"type\" has type \"integer\" but must be \"string\""
    );
}
