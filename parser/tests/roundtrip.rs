//! Printing directives and parsing them back gives the same directives; and no input, however
//! broken, makes the parser panic.

use std::sync::Arc;

use nimbus_parser::{
    ActiveTransform, Directive, FileLoc, Param, ParamType, ParamValues, SceneBuilder, directive_to_string,
    directives_of_str, load_str, parse_bytes, to_pbrt,
};
use proptest::collection::vec;
use proptest::prelude::*;

use crate::common::directives;

fn loc() -> FileLoc {
    FileLoc::new(Arc::from("generated"), 1, 1)
}

/// Strings that stress the quoting: quotes, backslashes, newlines, tabs, carriage returns,
/// comment and bracket characters, and arbitrary Unicode.
fn any_string() -> impl Strategy<Value = String> {
    prop_oneof![
        "[a-z]{0,8}",
        "[ -~\n\t\r\u{8}\u{c}\"\\\\]{0,16}",
        "[\"\\\\#\\[\\] \n]{0,6}",
        any::<String>().prop_map(|s| s.chars().take(12).collect()),
    ]
}

/// Parameter names: no whitespace (the declaration splits on it), but quotes and backslashes
/// are fine.
fn param_name() -> impl Strategy<Value = String> {
    prop_oneof!["[a-zA-Z_][a-zA-Z0-9_]{0,10}", "[a-z\"\\\\#é]{1,6}",]
}

/// Finite f32 values of every magnitude: normals, subnormals, zeros, small integers.
fn any_f32() -> impl Strategy<Value = f32> {
    use proptest::num::f32 as f;
    prop_oneof![
        f::POSITIVE | f::NEGATIVE | f::NORMAL | f::SUBNORMAL | f::ZERO,
        (-1000i32..1000).prop_map(|i| i as f32),
        -1.0f32..1.0,
        -1e6f32..1e6,
    ]
}

/// Finite f64 values of every magnitude.
fn any_f64() -> impl Strategy<Value = f64> {
    use proptest::num::f64 as f;
    prop_oneof![
        f::POSITIVE | f::NEGATIVE | f::NORMAL | f::SUBNORMAL | f::ZERO,
        (-1000i32..1000).prop_map(f64::from),
        -1.0f64..1.0,
        -1e9f64..1e9,
    ]
}

fn floats(per_item: usize) -> impl Strategy<Value = ParamValues> {
    (0usize..5).prop_flat_map(move |n| vec(any_f32(), n * per_item)).prop_map(ParamValues::Floats)
}

/// Values valid for a parameter of type `ty`.
fn values_for(ty: ParamType) -> BoxedStrategy<ParamValues> {
    match ty {
        ParamType::Integer => vec(any::<i32>(), 0..6).prop_map(ParamValues::Ints).boxed(),
        ParamType::Bool => vec(any::<bool>(), 0..4).prop_map(ParamValues::Bools).boxed(),
        ParamType::String | ParamType::Texture => vec(any_string(), 0..4).prop_map(ParamValues::Strings).boxed(),
        ParamType::Spectrum => prop_oneof![
            // Wavelength/value pairs with strictly increasing wavelengths.
            (vec(any_f32(), 0..6), vec(any_f32(), 6)).prop_map(|(mut lambdas, values)| {
                lambdas.sort_by(f32::total_cmp);
                lambdas.dedup_by(|a, b| a == b);
                let pairs = lambdas.iter().zip(&values).flat_map(|(&l, &v)| [l, v]);
                ParamValues::Floats(pairs.collect())
            }),
            // Named spectra or files.
            vec(any_string(), 1..3).prop_map(ParamValues::Strings),
        ]
        .boxed(),
        other => floats(other.per_item()).boxed(),
    }
}

fn param() -> impl Strategy<Value = Param> {
    (proptest::sample::select(ParamType::ALL.to_vec()), param_name())
        .prop_flat_map(|(ty, name)| values_for(ty).prop_map(move |values| Param::new(ty, name.clone(), values, loc())))
}

fn params() -> impl Strategy<Value = Vec<Param>> {
    vec(param(), 0..4)
}

/// `Option` values: a bare word or a quoted string (kept with its quotes).
fn option_value() -> impl Strategy<Value = String> {
    prop_oneof!["[A-Za-z0-9_.+-][A-Za-z0-9_.+#-]{0,8}", any_string().prop_map(|s| format!("\"{s}\"")),]
}

fn f64s<const N: usize>() -> impl Strategy<Value = [f64; N]> {
    proptest::array::uniform::<_, N>(any_f64())
}

/// Any directive, with valid arguments.
fn any_directive() -> impl Strategy<Value = Directive> {
    type Named = fn(String, Vec<Param>) -> Directive;
    let named: Vec<Named> = vec![
        Directive::Accelerator,
        Directive::AreaLightSource,
        Directive::Attribute,
        Directive::Camera,
        Directive::Film,
        Directive::Integrator,
        Directive::LightSource,
        Directive::MakeNamedMaterial,
        Directive::MakeNamedMedium,
        Directive::Material,
        Directive::PixelFilter,
        Directive::Sampler,
        Directive::Shape,
    ];
    type OneString = fn(String) -> Directive;
    let one_string: Vec<OneString> = vec![
        Directive::ColorSpace,
        Directive::CoordinateSystem,
        Directive::CoordSysTransform,
        Directive::Import,
        Directive::Include,
        Directive::NamedMaterial,
        Directive::ObjectBegin,
        Directive::ObjectInstance,
    ];
    prop_oneof![
        (proptest::sample::select(named), any_string(), params()).prop_map(|(make, name, params)| make(name, params)),
        (proptest::sample::select(one_string), any_string()).prop_map(|(make, s)| make(s)),
        proptest::sample::select(vec![
            Directive::AttributeBegin,
            Directive::AttributeEnd,
            Directive::Identity,
            Directive::ObjectEnd,
            Directive::ReverseOrientation,
            Directive::TransformBegin,
            Directive::TransformEnd,
            Directive::WorldBegin,
            Directive::ActiveTransform(ActiveTransform::All),
            Directive::ActiveTransform(ActiveTransform::StartTime),
            Directive::ActiveTransform(ActiveTransform::EndTime),
        ]),
        f64s::<16>().prop_map(Directive::ConcatTransform),
        f64s::<16>().prop_map(Directive::Transform),
        f64s::<9>().prop_map(Directive::LookAt),
        f64s::<4>().prop_map(Directive::Rotate),
        f64s::<3>().prop_map(Directive::Scale),
        f64s::<3>().prop_map(Directive::Translate),
        (any_f64(), any_f64()).prop_map(|(a, b)| Directive::TransformTimes(a, b)),
        (any_string(), any_string()).prop_map(|(inside, outside)| Directive::MediumInterface { inside, outside }),
        (any_string(), option_value()).prop_map(|(n, v)| Directive::Option(n, v)),
        (any_string(), any_string(), any_string(), params())
            .prop_map(|(name, value_type, class, params)| Directive::Texture { name, value_type, class, params }),
    ]
}

/// Words, strings, numbers and brackets in random order: mostly invalid scenes that still get
/// past the tokenizer.
fn token_soup() -> impl Strategy<Value = String> {
    let token = prop_oneof![
        proptest::sample::select(vec![
            "WorldBegin",
            "AttributeBegin",
            "AttributeEnd",
            "ObjectBegin",
            "ObjectEnd",
            "ObjectInstance",
            "Shape",
            "Camera",
            "LookAt",
            "Translate",
            "Rotate",
            "Scale",
            "Transform",
            "ConcatTransform",
            "CoordinateSystem",
            "CoordSysTransform",
            "MediumInterface",
            "MakeNamedMedium",
            "MakeNamedMaterial",
            "NamedMaterial",
            "Material",
            "Texture",
            "AreaLightSource",
            "LightSource",
            "Attribute",
            "ActiveTransform",
            "TransformTimes",
            "StartTime",
            "EndTime",
            "All",
            "Option",
            "ColorSpace",
            "ReverseOrientation",
            "Identity",
            "TransformBegin",
            "TransformEnd",
            "Film",
            "Sampler",
            "Integrator",
            "PixelFilter",
            "Accelerator",
            "WorldEnd",
            "[",
            "]",
            "[ ]",
            "true",
            "false",
            "\"float radius\"",
            "\"integer indices\"",
            "\"point3 P\"",
            "\"rgb L\"",
            "\"spectrum eta\"",
            "\"blackbody L\"",
            "\"texture reflectance\"",
            "\"string type\"",
            "\"bool b\"",
            "\"colour c\"",
            "\"float\"",
            "\"sphere\"",
            "\"fog\"",
            "\"\"",
            "\"homogeneous\"",
            "\"camera\"",
            "\"world\"",
            "\"float\"",
            "\"spectrum\"",
            "\"seed\"",
            "\"unterminated",
            "\"a\\\"b\"",
            "\"bad\\q\"",
            "# comment\n",
            "\n",
            "1e40",
            "1e400",
            "2147483648",
            "-0",
            ".5",
        ])
        .prop_map(str::to_string),
        any::<i32>().prop_map(|i| i.to_string()),
        any_f64().prop_map(|f| f.to_string()),
    ];
    vec(token, 0..40).prop_map(|tokens| tokens.join(" "))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn printed_directives_parse_back_to_themselves(ds in vec(any_directive(), 0..12)) {
        let text = to_pbrt(&ds);
        let parsed = directives_of_str(&text, "printed.pbrt");
        prop_assert!(parsed.is_ok(), "{:?}\n--- printed ---\n{}", parsed, text);
        prop_assert_eq!(parsed.unwrap(), ds, "printed:\n{}", text);
    }

    #[test]
    fn random_bytes_never_panic(data in vec(any::<u8>(), 0..256)) {
        let mut builder = SceneBuilder::new();
        if parse_bytes(&data, "random.pbrt", &mut builder).is_ok() {
            let _ = builder.finish();
        }
        if let Ok(text) = std::str::from_utf8(&data) {
            let _ = directives_of_str(text, "random.pbrt");
        }
    }

    #[test]
    fn token_soup_never_panics(text in token_soup()) {
        let _ = load_str(&text, "soup.pbrt");
        let mut builder = SceneBuilder::new();
        if parse_bytes(text.as_bytes(), "soup.pbrt", &mut builder).is_ok() {
            let _ = builder.finish();
        }
        // Whatever parses must also survive printing.
        if let Ok(ds) = directives_of_str(&text, "soup.pbrt") {
            let printed = to_pbrt(&ds);
            prop_assert_eq!(directives_of_str(&printed, "printed.pbrt"), Ok(ds));
        }
    }

    #[test]
    fn soup_inside_a_world_block_never_panics(text in token_soup()) {
        let _ = load_str(&format!("WorldBegin\n{text}"), "soup.pbrt");
    }
}

#[test]
fn option_string_values_with_quotes_and_backslashes_round_trip() {
    // Regression: the printer wrote the decoded value between quotes without escaping it, so
    // `Option "x" "a\"b"` printed as `Option "x" "a"b"`, which does not parse back.
    let d = directives(r#"Option "string msereferenceimage" "a\"b\\c""#);
    assert_eq!(d, [Directive::Option("string msereferenceimage".into(), "\"a\"b\\c\"".into())]);
    let printed = directive_to_string(&d[0]);
    assert_eq!(printed, r#"Option "string msereferenceimage" "a\"b\\c""#);
    assert_eq!(directives(&printed), d);
}

#[test]
fn printer_output_is_what_the_format_documents() {
    let d = directives(
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n\
         \"bool flip\" false \"string name\" \"tab\\there\"\n\
         Translate 1 -2.5 1e-3\n\
         MediumInterface \"fog\"",
    );
    assert_eq!(
        to_pbrt(&d),
        "Shape \"trianglemesh\"\n    \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n    \
         \"integer indices\" [ 0 1 2 ]\n    \"bool flip\" [ false ]\n    \
         \"string name\" [ \"tab\\there\" ]\nTranslate 1 -2.5 0.001\n\
         MediumInterface \"fog\" \"fog\"\n"
    );
}
