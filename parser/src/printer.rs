//! Writes directives back as pbrt-v4 text. Numbers print in their shortest exact form, so
//! printing and re-parsing gives back the same directives.

use std::fmt::Write;

use crate::directive::{ActiveTransform, Directive};
use crate::params::{Param, ParamValues};

/// Quotes a string with pbrt-v4's escapes.
pub fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            '\u{8}' => out.push_str("\\b"),
            '\u{c}' => out.push_str("\\f"),
            _ => out.push(c),
        }
    }
    out.push('"');
    out
}

fn params(out: &mut String, params: &[Param]) {
    for p in params {
        let _ = write!(out, "\n    {} [", quote(&format!("{} {}", p.ty, p.name)));
        match &p.values {
            ParamValues::Ints(v) => v.iter().for_each(|x| {
                let _ = write!(out, " {x}");
            }),
            ParamValues::Floats(v) => v.iter().for_each(|x| {
                let _ = write!(out, " {x}");
            }),
            ParamValues::Strings(v) => v.iter().for_each(|x| {
                let _ = write!(out, " {}", quote(x));
            }),
            ParamValues::Bools(v) => v.iter().for_each(|x| {
                let _ = write!(out, " {x}");
            }),
        }
        out.push_str(" ]");
    }
}

fn numbers(out: &mut String, v: &[f64]) {
    for x in v {
        let _ = write!(out, " {x}");
    }
}

/// One directive as text (no trailing newline).
pub fn directive_to_string(d: &Directive) -> String {
    let mut out = String::from(d.keyword());
    match d {
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
        | Directive::Shape(n, p) => {
            let _ = write!(out, " {}", quote(n));
            params(&mut out, p);
        }
        Directive::ActiveTransform(a) => out.push_str(match a {
            ActiveTransform::All => " All",
            ActiveTransform::StartTime => " StartTime",
            ActiveTransform::EndTime => " EndTime",
        }),
        Directive::ColorSpace(n)
        | Directive::CoordinateSystem(n)
        | Directive::CoordSysTransform(n)
        | Directive::Import(n)
        | Directive::Include(n)
        | Directive::NamedMaterial(n)
        | Directive::ObjectBegin(n)
        | Directive::ObjectInstance(n) => {
            let _ = write!(out, " {}", quote(n));
        }
        Directive::ConcatTransform(m) | Directive::Transform(m) => {
            out.push_str(" [");
            numbers(&mut out, m);
            out.push_str(" ]");
        }
        Directive::LookAt(v) => numbers(&mut out, v),
        Directive::Rotate(v) => numbers(&mut out, v),
        Directive::Scale(v) | Directive::Translate(v) => numbers(&mut out, v),
        Directive::TransformTimes(a, b) => numbers(&mut out, &[*a, *b]),
        Directive::MediumInterface { inside, outside } => {
            let _ = write!(out, " {} {}", quote(inside), quote(outside));
        }
        Directive::Option(n, v) => {
            // A string value is kept decoded between quotes (no bare word contains '"'):
            // quote its contents again so escapes survive.
            let value = match v.strip_prefix('"').and_then(|s| s.strip_suffix('"')) {
                Some(inner) => quote(inner),
                None => v.clone(),
            };
            let _ = write!(out, " {} {value}", quote(n));
        }
        Directive::Texture { name, value_type, class, params: p } => {
            let _ = write!(out, " {} {} {}", quote(name), quote(value_type), quote(class));
            params(&mut out, p);
        }
        Directive::AttributeBegin
        | Directive::AttributeEnd
        | Directive::Identity
        | Directive::ObjectEnd
        | Directive::ReverseOrientation
        | Directive::TransformBegin
        | Directive::TransformEnd
        | Directive::WorldBegin => {}
    }
    out
}

/// A whole list of directives as a scene file.
pub fn to_pbrt(directives: &[Directive]) -> String {
    let mut out = String::new();
    for d in directives {
        out.push_str(&directive_to_string(d));
        out.push('\n');
    }
    out
}
