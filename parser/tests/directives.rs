//! Every directive parses into its `Directive` value, with its location.

use nimbus_parser::{ActiveTransform, Directive, DirectiveRecorder, ParamType, ParamValues, parse_str};

use crate::common::{directive, directives, parse_err_string};

/// Every directive keyword, each with one example.
const EXAMPLES: [(&str, &str); 40] = [
    ("Accelerator", "Accelerator \"bvh\" \"integer maxnodeprims\" 4"),
    ("ActiveTransform", "ActiveTransform StartTime"),
    ("AreaLightSource", "AreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ]"),
    ("Attribute", "Attribute \"shape\" \"float radius\" 0.5"),
    ("AttributeBegin", "AttributeBegin"),
    ("AttributeEnd", "AttributeEnd"),
    ("Camera", "Camera \"perspective\" \"float fov\" 45"),
    ("ColorSpace", "ColorSpace \"rec2020\""),
    ("ConcatTransform", "ConcatTransform [ 1 0 0 0 0 1 0 0 0 0 1 0 1 2 3 1 ]"),
    ("CoordinateSystem", "CoordinateSystem \"mine\""),
    ("CoordSysTransform", "CoordSysTransform \"camera\""),
    ("Film", "Film \"rgb\" \"integer xresolution\" 64"),
    ("Identity", "Identity"),
    ("Import", "Import \"geometry.pbrt\""),
    ("Include", "Include \"materials.pbrt\""),
    ("Integrator", "Integrator \"volpath\" \"integer maxdepth\" 5"),
    ("LightSource", "LightSource \"point\" \"rgb I\" [ 1 2 3 ]"),
    ("LookAt", "LookAt 0 1 2  3 4 5  0 1 0"),
    ("MakeNamedMaterial", "MakeNamedMaterial \"gold\" \"string type\" \"conductor\""),
    ("MakeNamedMedium", "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\""),
    ("Material", "Material \"diffuse\""),
    ("MediumInterface", "MediumInterface \"in\" \"out\""),
    ("NamedMaterial", "NamedMaterial \"gold\""),
    ("ObjectBegin", "ObjectBegin \"tree\""),
    ("ObjectEnd", "ObjectEnd"),
    ("ObjectInstance", "ObjectInstance \"tree\""),
    ("Option", "Option \"bool disablepixeljitter\" true"),
    ("PixelFilter", "PixelFilter \"box\""),
    ("ReverseOrientation", "ReverseOrientation"),
    ("Rotate", "Rotate 90 0 0 1"),
    ("Sampler", "Sampler \"zsobol\" \"integer pixelsamples\" 16"),
    ("Scale", "Scale 1 2 -3"),
    ("Shape", "Shape \"sphere\" \"float radius\" 2"),
    ("Texture", "Texture \"checks\" \"spectrum\" \"checkerboard\" \"float uscale\" 4"),
    ("Transform", "Transform [ 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 ]"),
    ("TransformBegin", "TransformBegin"),
    ("TransformEnd", "TransformEnd"),
    ("TransformTimes", "TransformTimes 0.25 0.75"),
    ("Translate", "Translate 1 -2 3.5"),
    ("WorldBegin", "WorldBegin"),
];

#[test]
fn every_directive_parses_to_its_keyword() {
    for (keyword, text) in EXAMPLES {
        assert_eq!(directive(text).keyword(), keyword, "{text}");
    }
}

#[test]
fn every_directive_parses_to_its_value() {
    let parsed: Vec<Directive> = EXAMPLES.iter().map(|(_, text)| directive(text)).collect();
    let float = |name: &str, v: &[f32]| (ParamType::Float, name.to_string(), ParamValues::Floats(v.to_vec()));
    let int = |name: &str, v: i32| (ParamType::Integer, name.to_string(), ParamValues::Ints(vec![v]));
    let string = |name: &str, v: &str| (ParamType::String, name.to_string(), ParamValues::Strings(vec![v.to_string()]));
    let rgb = |name: &str, v: [f32; 3]| (ParamType::Rgb, name.to_string(), ParamValues::Floats(v.to_vec()));
    // (keyword, name, parameters) for the directives that take a name and parameters.
    let with_params = |d: &Directive| -> (String, Vec<(ParamType, String, ParamValues)>) {
        let (name, params) = match d {
            Directive::Accelerator(n, p)
            | Directive::AreaLightSource(n, p)
            | Directive::Attribute(n, p)
            | Directive::Camera(n, p)
            | Directive::Film(n, p)
            | Directive::Integrator(n, p)
            | Directive::LightSource(n, p)
            | Directive::MakeNamedMaterial(n, p)
            | Directive::MakeNamedMedium(n, p)
            | Directive::Material(n, p)
            | Directive::PixelFilter(n, p)
            | Directive::Sampler(n, p)
            | Directive::Shape(n, p) => (n, p),
            other => panic!("{other:?} takes no parameters"),
        };
        let params = params.iter().map(|p| (p.ty, p.name.clone(), p.values.clone())).collect();
        (name.clone(), params)
    };
    assert_eq!(with_params(&parsed[0]), ("bvh".into(), vec![int("maxnodeprims", 4)]));
    assert_eq!(parsed[1], Directive::ActiveTransform(ActiveTransform::StartTime));
    assert_eq!(with_params(&parsed[2]), ("diffuse".into(), vec![rgb("L", [1.0; 3])]));
    assert_eq!(with_params(&parsed[3]), ("shape".into(), vec![float("radius", &[0.5])]));
    assert_eq!(parsed[4], Directive::AttributeBegin);
    assert_eq!(parsed[5], Directive::AttributeEnd);
    assert_eq!(with_params(&parsed[6]), ("perspective".into(), vec![float("fov", &[45.0])]));
    assert_eq!(parsed[7], Directive::ColorSpace("rec2020".into()));
    assert_eq!(
        parsed[8],
        Directive::ConcatTransform([1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 2.0, 3.0, 1.0])
    );
    assert_eq!(parsed[9], Directive::CoordinateSystem("mine".into()));
    assert_eq!(parsed[10], Directive::CoordSysTransform("camera".into()));
    assert_eq!(with_params(&parsed[11]), ("rgb".into(), vec![int("xresolution", 64)]));
    assert_eq!(parsed[12], Directive::Identity);
    assert_eq!(parsed[13], Directive::Import("geometry.pbrt".into()));
    assert_eq!(parsed[14], Directive::Include("materials.pbrt".into()));
    assert_eq!(with_params(&parsed[15]), ("volpath".into(), vec![int("maxdepth", 5)]));
    assert_eq!(with_params(&parsed[16]), ("point".into(), vec![rgb("I", [1.0, 2.0, 3.0])]));
    assert_eq!(parsed[17], Directive::LookAt([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 0.0, 1.0, 0.0]));
    assert_eq!(with_params(&parsed[18]), ("gold".into(), vec![string("type", "conductor")]));
    assert_eq!(with_params(&parsed[19]), ("fog".into(), vec![string("type", "homogeneous")]));
    assert_eq!(with_params(&parsed[20]), ("diffuse".into(), vec![]));
    assert_eq!(parsed[21], Directive::MediumInterface { inside: "in".into(), outside: "out".into() });
    assert_eq!(parsed[22], Directive::NamedMaterial("gold".into()));
    assert_eq!(parsed[23], Directive::ObjectBegin("tree".into()));
    assert_eq!(parsed[24], Directive::ObjectEnd);
    assert_eq!(parsed[25], Directive::ObjectInstance("tree".into()));
    assert_eq!(parsed[26], Directive::Option("bool disablepixeljitter".into(), "true".into()));
    assert_eq!(with_params(&parsed[27]), ("box".into(), vec![]));
    assert_eq!(parsed[28], Directive::ReverseOrientation);
    assert_eq!(parsed[29], Directive::Rotate([90.0, 0.0, 0.0, 1.0]));
    assert_eq!(with_params(&parsed[30]), ("zsobol".into(), vec![int("pixelsamples", 16)]));
    assert_eq!(parsed[31], Directive::Scale([1.0, 2.0, -3.0]));
    assert_eq!(with_params(&parsed[32]), ("sphere".into(), vec![float("radius", &[2.0])]));
    let Directive::Texture { name, value_type, class, params } = &parsed[33] else {
        panic!("{:?}", parsed[33]);
    };
    assert_eq!((name.as_str(), value_type.as_str(), class.as_str()), ("checks", "spectrum", "checkerboard"));
    assert_eq!(params.len(), 1);
    assert_eq!(
        (params[0].ty, params[0].name.as_str(), &params[0].values),
        (ParamType::Float, "uscale", &ParamValues::Floats(vec![4.0]))
    );
    assert_eq!(
        parsed[34],
        Directive::Transform([1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0])
    );
    assert_eq!(parsed[35], Directive::TransformBegin);
    assert_eq!(parsed[36], Directive::TransformEnd);
    assert_eq!(parsed[37], Directive::TransformTimes(0.25, 0.75));
    assert_eq!(parsed[38], Directive::Translate([1.0, -2.0, 3.5]));
    assert_eq!(parsed[39], Directive::WorldBegin);
}

#[test]
fn directives_are_recorded_with_their_locations() {
    let text = "# a comment\nLookAt 0 0 1  0 0 0  0 1 0\n   Camera \"perspective\"\nWorldBegin\n\tShape \"sphere\" AttributeBegin";
    let mut r = DirectiveRecorder::default();
    parse_str(text, "dir/scene.pbrt", &mut r).unwrap();
    let locs: Vec<(&str, String)> = r.directives.iter().map(|(d, loc)| (d.keyword(), loc.to_string())).collect();
    assert_eq!(
        locs,
        [
            ("LookAt", "dir/scene.pbrt:2:1".to_string()),
            ("Camera", "dir/scene.pbrt:3:4".to_string()),
            ("WorldBegin", "dir/scene.pbrt:4:1".to_string()),
            ("Shape", "dir/scene.pbrt:5:2".to_string()),
            ("AttributeBegin", "dir/scene.pbrt:5:17".to_string()),
        ]
    );
}

#[test]
fn active_transform_takes_each_of_its_three_words() {
    assert_eq!(
        directives("ActiveTransform All ActiveTransform StartTime ActiveTransform EndTime"),
        [
            Directive::ActiveTransform(ActiveTransform::All),
            Directive::ActiveTransform(ActiveTransform::StartTime),
            Directive::ActiveTransform(ActiveTransform::EndTime),
        ]
    );
    assert_eq!(
        parse_err_string("ActiveTransform Sometimes"),
        "t.pbrt:1:17: ActiveTransform takes All, StartTime or EndTime, not \"Sometimes\""
    );
    // A quoted word is accepted too.
    assert_eq!(directive("ActiveTransform \"EndTime\""), Directive::ActiveTransform(ActiveTransform::EndTime));
    assert_eq!(
        parse_err_string("ActiveTransform \"all\""),
        "t.pbrt:1:17: ActiveTransform takes All, StartTime or EndTime, not string \"all\""
    );
}

#[test]
fn medium_interface_takes_one_or_two_names() {
    assert_eq!(
        directives("MediumInterface \"fog\"\nMediumInterface \"\" \"air\"\nMediumInterface \"a\" Shape \"sphere\""),
        [
            Directive::MediumInterface { inside: "fog".into(), outside: "fog".into() },
            Directive::MediumInterface { inside: String::new(), outside: "air".into() },
            Directive::MediumInterface { inside: "a".into(), outside: "a".into() },
            Directive::Shape("sphere".into(), vec![]),
        ]
    );
    // One name at the very end of the file.
    assert_eq!(
        directive("MediumInterface \"fog\""),
        Directive::MediumInterface { inside: "fog".into(), outside: "fog".into() }
    );
}

#[test]
fn option_keeps_its_value_token_as_written() {
    assert_eq!(
        directives("Option \"seed\" 5\nOption \"string rendercoordsys\" \"world\"\nOption \"bool wavefront\" false"),
        [
            Directive::Option("seed".into(), "5".into()),
            Directive::Option("string rendercoordsys".into(), "\"world\"".into()),
            Directive::Option("bool wavefront".into(), "false".into()),
        ]
    );
    assert_eq!(parse_err_string("Option \"seed\" [ 5 ]"), "t.pbrt:1:15: expected an option value, found \"[\"");
}

#[test]
fn numbers_take_every_decimal_spelling() {
    assert_eq!(directive("Translate -1.5e2 +.25 7."), Directive::Translate([-150.0, 0.25, 7.0]));
    assert_eq!(directive("Scale 1E-3 00012.5000 -0"), Directive::Scale([0.001, 12.5, -0.0]));
    // Long mantissas and large exponents are rounded correctly.
    assert_eq!(
        directive("Translate 3.14159265358979323846264338327950288 1e-400 1.7976931348623157e308"),
        Directive::Translate([std::f64::consts::PI, 0.0, f64::MAX])
    );
}

#[test]
fn transform_takes_exactly_sixteen_numbers_in_brackets() {
    assert_eq!(
        parse_err_string("Transform 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"),
        "t.pbrt:1:11: Transform expects '[' and 16 numbers, found \"1\""
    );
    assert_eq!(
        parse_err_string("ConcatTransform [ 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 ]"),
        "t.pbrt:1:49: expected a number for ConcatTransform, found \"]\""
    );
    assert_eq!(
        parse_err_string("Transform [ 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 0 ]"),
        "t.pbrt:1:45: Transform takes exactly 16 numbers; found \"0\" where ']' should be"
    );
}

#[test]
fn numeric_directives_reject_non_numbers_and_overflow() {
    assert_eq!(parse_err_string("Translate 1 two 3"), "t.pbrt:1:13: expected a number for Translate, found \"two\"");
    assert_eq!(parse_err_string("Scale 1 \"2\" 3"), "t.pbrt:1:9: expected a number for Scale, found string \"2\"");
    assert_eq!(parse_err_string("Rotate 1e999 0 0 1"), "t.pbrt:1:8: \"1e999\": number out of range");
    assert_eq!(
        parse_err_string("LookAt 0 0 0 0 0 1 0 1 nan"),
        "t.pbrt:1:24: expected a number for LookAt, found \"nan\""
    );
}

#[test]
fn names_must_be_quoted_strings() {
    assert_eq!(
        parse_err_string("Shape sphere"),
        "t.pbrt:1:7: expected a type name as a quoted string, found \"sphere\""
    );
    assert_eq!(
        parse_err_string("NamedMaterial [ \"gold\" ]"),
        "t.pbrt:1:15: expected a material name as a quoted string, found \"[\""
    );
    assert_eq!(
        parse_err_string("Texture \"t\" float \"constant\""),
        "t.pbrt:1:13: expected the texture type (\"float\" or \"spectrum\") as a quoted string, found \"float\""
    );
    assert_eq!(
        parse_err_string("Include scene.pbrt"),
        "t.pbrt:1:9: expected a file name after Include as a quoted string, found \"scene.pbrt\""
    );
}

#[test]
fn a_directive_must_start_with_a_word() {
    assert_eq!(
        parse_err_string("WorldBegin\n\"float radius\" 1"),
        "t.pbrt:2:1: expected a directive, found string \"float radius\""
    );
    assert_eq!(parse_err_string("WorldBegin ]"), "t.pbrt:1:12: expected a directive, found \"]\"");
}

#[test]
fn byte_order_mark_and_crlf_line_ends_are_accepted() {
    let text = "\u{feff}WorldBegin\r\nShape \"sphere\" # comment\r\n  \"float radius\" 2\r\n";
    let mut r = DirectiveRecorder::default();
    parse_str(text, "t.pbrt", &mut r).unwrap();
    assert_eq!(r.directives.len(), 2);
    assert_eq!(r.directives[1].1.to_string(), "t.pbrt:2:1");
    let Directive::Shape(_, p) = &r.directives[1].0 else { panic!() };
    assert_eq!(p[0].loc.to_string(), "t.pbrt:3:3");
}

#[test]
fn empty_and_comment_only_input_has_no_directives() {
    assert_eq!(directives(""), []);
    assert_eq!(directives("  \n\t# only a comment\n# and another"), []);
}

#[test]
fn byte_order_mark_does_not_count_as_a_column() {
    // Regression: the UTF-8 byte order mark was counted, so the first line's columns were
    // off by three.
    let mut r = DirectiveRecorder::default();
    parse_str("\u{feff}WorldBegin Shape \"sphere\"", "t.pbrt", &mut r).unwrap();
    let locs: Vec<String> = r.directives.iter().map(|(_, l)| l.to_string()).collect();
    assert_eq!(locs, ["t.pbrt:1:1", "t.pbrt:1:12"]);
}
