//! Turns tokens into [`Directive`]s and hands each to a [`ParserTarget`]. `Include` splices the
//! included file's tokens into the stream; `Import` parses a file as a unit between
//! [`ParserTarget::import_begin`] and [`ParserTarget::import_end`].

use std::path::Path;
use std::sync::Arc;

use crate::directive::{ActiveTransform, Directive};
use crate::error::{Error, Result};
use crate::loc::FileLoc;
use crate::number::{IntError, parse_f64, parse_i32};
use crate::params::{Param, ParamType, ParamValues};
use crate::tokenizer::{Token, TokenKind, TokenStream, read_source};

/// How deep `Import` may nest before we assume a file imports itself.
const MAX_IMPORT_DEPTH: usize = 32;

/// Receives the directives of a scene in file order.
pub trait ParserTarget {
    /// Handles one directive found at `loc`.
    fn directive(&mut self, directive: Directive, loc: FileLoc) -> Result<()>;

    /// Whether `Include` and `Import` are read (true, the default) or handed to
    /// [`ParserTarget::directive`] unread, as a formatter wants.
    fn follow_files(&self) -> bool {
        true
    }

    /// Called before the directives of an imported file.
    fn import_begin(&mut self, _loc: &FileLoc) -> Result<()> {
        Ok(())
    }

    /// Called after the directives of an imported file.
    fn import_end(&mut self, _loc: &FileLoc) -> Result<()> {
        Ok(())
    }

    /// Called with the name of every file read: the main file, then each included or
    /// imported one.
    fn file_read(&mut self, _name: &str) {}
}

/// A target that records every directive with its location.
#[derive(Debug, Default)]
pub struct DirectiveRecorder {
    /// The directives, in order.
    pub directives: Vec<(Directive, FileLoc)>,
}

impl ParserTarget for DirectiveRecorder {
    fn directive(&mut self, directive: Directive, loc: FileLoc) -> Result<()> {
        self.directives.push((directive, loc));
        Ok(())
    }

    fn follow_files(&self) -> bool {
        false
    }
}

/// Reads a file into `target`. `.gz` files are decompressed; `-` is standard input.
pub fn parse_file(path: &Path, target: &mut dyn ParserTarget) -> Result<()> {
    let name: Arc<str> = if path.as_os_str() == "-" { Arc::from("<stdin>") } else { Arc::from(path.to_string_lossy()) };
    let data = read_source(path).map_err(|e| Error::general(format!("{name}: cannot read scene file: {e}")))?;
    target.file_read(&name);
    parse_stream(TokenStream::new(name, data)?, target, 0)
}

/// Reads scene text into `target`; `name` stands for the file in locations, and relative paths
/// resolve against its directory.
pub fn parse_str(text: &str, name: &str, target: &mut dyn ParserTarget) -> Result<()> {
    target.file_read(name);
    parse_stream(TokenStream::new(Arc::from(name), text.as_bytes().to_vec())?, target, 0)
}

/// Reads scene bytes (which need not be UTF-8: errors say so) into `target`.
pub fn parse_bytes(data: &[u8], name: &str, target: &mut dyn ParserTarget) -> Result<()> {
    target.file_read(name);
    parse_stream(TokenStream::new(Arc::from(name), data.to_vec())?, target, 0)
}

fn parse_stream(mut s: TokenStream, target: &mut dyn ParserTarget, import_depth: usize) -> Result<()> {
    while let Some(tok) = s.next()? {
        let loc = s.loc(&tok);
        if tok.kind != TokenKind::Word {
            return Err(Error::new(&loc, format!("expected a directive, found {}", describe(&s, &tok))));
        }
        let directive = match s.bytes(&tok) {
            b"Accelerator" => named(&mut s, Directive::Accelerator)?,
            b"ActiveTransform" => {
                let t = s.expect("All, StartTime or EndTime after ActiveTransform")?;
                Directive::ActiveTransform(match s.bytes(&t) {
                    b"All" => ActiveTransform::All,
                    b"StartTime" => ActiveTransform::StartTime,
                    b"EndTime" => ActiveTransform::EndTime,
                    _ => {
                        return Err(Error::new(
                            &s.loc(&t),
                            format!("ActiveTransform takes All, StartTime or EndTime, not {}", describe(&s, &t)),
                        ));
                    }
                })
            }
            b"AreaLightSource" => named(&mut s, Directive::AreaLightSource)?,
            b"Attribute" => named(&mut s, Directive::Attribute)?,
            b"AttributeBegin" => Directive::AttributeBegin,
            b"AttributeEnd" => Directive::AttributeEnd,
            b"Camera" => named(&mut s, Directive::Camera)?,
            b"ColorSpace" => Directive::ColorSpace(string(&mut s, "a color space name")?),
            b"ConcatTransform" => Directive::ConcatTransform(matrix(&mut s, "ConcatTransform")?),
            b"CoordinateSystem" => Directive::CoordinateSystem(string(&mut s, "a coordinate system name")?),
            b"CoordSysTransform" => Directive::CoordSysTransform(string(&mut s, "a coordinate system name")?),
            b"Film" => named(&mut s, Directive::Film)?,
            b"Identity" => Directive::Identity,
            b"Include" => {
                let file = string(&mut s, "a file name after Include")?;
                if target.follow_files() {
                    let path = loc.resolve(&file);
                    let data = read_source(&path).map_err(|e| {
                        Error::new(
                            &loc,
                            format!("Include \"{file}\": cannot read it (tried {}): {e}", crate::loc::shown(&path)),
                        )
                    })?;
                    let name: Arc<str> = Arc::from(path.to_string_lossy());
                    target.file_read(&name);
                    s.push(name, data)?;
                    continue;
                }
                Directive::Include(file)
            }
            b"Import" => {
                let file = string(&mut s, "a file name after Import")?;
                if target.follow_files() {
                    if import_depth >= MAX_IMPORT_DEPTH {
                        return Err(Error::new(&loc, "Import nested too deeply (does a file import itself?)"));
                    }
                    let path = loc.resolve(&file);
                    let data = read_source(&path).map_err(|e| {
                        Error::new(
                            &loc,
                            format!("Import \"{file}\": cannot read it (tried {}): {e}", crate::loc::shown(&path)),
                        )
                    })?;
                    let name: Arc<str> = Arc::from(path.to_string_lossy());
                    target.file_read(&name);
                    target.import_begin(&loc)?;
                    // An imported file's paths resolve from the scene's directory too.
                    let stream = TokenStream::with_search_dir(name, data, s.search_dir().clone())?;
                    parse_stream(stream, target, import_depth + 1)?;
                    target.import_end(&loc)?;
                    continue;
                }
                Directive::Import(file)
            }
            b"Integrator" => named(&mut s, Directive::Integrator)?,
            b"LightSource" => named(&mut s, Directive::LightSource)?,
            b"LookAt" => Directive::LookAt(numbers::<9>(&mut s, "LookAt")?),
            b"MakeNamedMaterial" => named(&mut s, Directive::MakeNamedMaterial)?,
            b"MakeNamedMedium" => named(&mut s, Directive::MakeNamedMedium)?,
            b"Material" => named(&mut s, Directive::Material)?,
            b"MediumInterface" => {
                let inside = string(&mut s, "a medium name after MediumInterface")?;
                let outside = match s.next()? {
                    Some(t) if matches!(t.kind, TokenKind::Str { .. }) => s.text(&t)?,
                    Some(t) => {
                        s.unget(t);
                        inside.clone()
                    }
                    None => inside.clone(),
                };
                Directive::MediumInterface { inside, outside }
            }
            b"NamedMaterial" => Directive::NamedMaterial(string(&mut s, "a material name")?),
            b"ObjectBegin" => Directive::ObjectBegin(string(&mut s, "an object name")?),
            b"ObjectEnd" => Directive::ObjectEnd,
            b"ObjectInstance" => Directive::ObjectInstance(string(&mut s, "an object name")?),
            b"Option" => {
                let name = string(&mut s, "an option name")?;
                let t = s.expect("an option value")?;
                let value = match t.kind {
                    TokenKind::Str { .. } => format!("\"{}\"", s.text(&t)?),
                    TokenKind::Word => s.text(&t)?,
                    _ => {
                        return Err(Error::new(
                            &s.loc(&t),
                            format!("expected an option value, found {}", describe(&s, &t)),
                        ));
                    }
                };
                Directive::Option(name, value)
            }
            b"PixelFilter" => named(&mut s, Directive::PixelFilter)?,
            b"ReverseOrientation" => Directive::ReverseOrientation,
            b"Rotate" => Directive::Rotate(numbers::<4>(&mut s, "Rotate")?),
            b"Sampler" => named(&mut s, Directive::Sampler)?,
            b"Scale" => Directive::Scale(numbers::<3>(&mut s, "Scale")?),
            b"Shape" => named(&mut s, Directive::Shape)?,
            b"Texture" => {
                let name = string(&mut s, "a texture name")?;
                let value_type = string(&mut s, "the texture type (\"float\" or \"spectrum\")")?;
                let class = string(&mut s, "the texture class")?;
                let params = parameters(&mut s)?;
                Directive::Texture { name, value_type, class, params }
            }
            b"Transform" => Directive::Transform(matrix(&mut s, "Transform")?),
            b"TransformBegin" => Directive::TransformBegin,
            b"TransformEnd" => Directive::TransformEnd,
            b"TransformTimes" => {
                let [a, b] = numbers::<2>(&mut s, "TransformTimes")?;
                Directive::TransformTimes(a, b)
            }
            b"Translate" => Directive::Translate(numbers::<3>(&mut s, "Translate")?),
            b"WorldBegin" => Directive::WorldBegin,
            b"WorldEnd" => {
                return Err(Error::new(
                    &loc,
                    "unknown directive \"WorldEnd\" (a pbrt-v3 directive; pbrt-v4 scenes end without it)",
                ));
            }
            _ => {
                return Err(Error::new(&loc, format!("unknown directive {}", describe(&s, &tok))));
            }
        };
        target.directive(directive, loc)?;
    }
    Ok(())
}

/// A short quotation of a token for messages.
fn describe(s: &TokenStream, t: &Token) -> String {
    let raw = s.bytes(t);
    let shown: String = String::from_utf8_lossy(&raw[..raw.len().min(60)]).into_owned();
    let more = if raw.len() > 60 { "..." } else { "" };
    match t.kind {
        TokenKind::Str { .. } => format!("string \"{shown}{more}\""),
        _ => format!("\"{shown}{more}\""),
    }
}

fn string(s: &mut TokenStream, what: &str) -> Result<String> {
    let t = s.expect(what)?;
    match t.kind {
        TokenKind::Str { .. } => s.text(&t),
        _ => Err(Error::new(&s.loc(&t), format!("expected {what} as a quoted string, found {}", describe(s, &t)))),
    }
}

fn number(s: &mut TokenStream, what: &str) -> Result<f64> {
    let t = s.expect_with(|| format!("a number for {what}"))?;
    if t.kind == TokenKind::Word
        && let Some(v) = parse_f64(s.bytes(&t))
    {
        if v.is_finite() {
            return Ok(v);
        }
        return Err(Error::new(&s.loc(&t), format!("{}: number out of range", describe(s, &t))));
    }
    Err(Error::new(&s.loc(&t), format!("expected a number for {what}, found {}", describe(s, &t))))
}

fn numbers<const N: usize>(s: &mut TokenStream, what: &str) -> Result<[f64; N]> {
    let mut out = [0.0; N];
    for v in &mut out {
        *v = number(s, what)?;
    }
    Ok(out)
}

fn matrix(s: &mut TokenStream, what: &str) -> Result<[f64; 16]> {
    let open = s.expect("'[' and 16 numbers")?;
    if open.kind != TokenKind::Open {
        return Err(Error::new(
            &s.loc(&open),
            format!("{what} expects '[' and 16 numbers, found {}", describe(s, &open)),
        ));
    }
    let m = numbers::<16>(s, what)?;
    let close = s.expect("']' after 16 numbers")?;
    if close.kind != TokenKind::Close {
        return Err(Error::new(
            &s.loc(&close),
            format!("{what} takes exactly 16 numbers; found {} where ']' should be", describe(s, &close)),
        ));
    }
    Ok(m)
}

fn named(s: &mut TokenStream, make: fn(String, Vec<Param>) -> Directive) -> Result<Directive> {
    let name = string(s, "a type name")?;
    let params = parameters(s)?;
    Ok(make(name, params))
}

/// Reads `"type name" value-or-[values]` pairs until a token that is not a quoted string.
fn parameters(s: &mut TokenStream) -> Result<Vec<Param>> {
    let mut params = Vec::new();
    loop {
        let Some(decl) = s.next()? else {
            return Ok(params);
        };
        if !matches!(decl.kind, TokenKind::Str { .. }) {
            s.unget(decl);
            return Ok(params);
        }
        let loc = s.loc(&decl);
        let text = s.text(&decl)?;
        let mut words = text.split_ascii_whitespace();
        let (Some(type_name), Some(name), None) = (words.next(), words.next(), words.next()) else {
            return Err(Error::new(
                &loc,
                format!("\"{text}\": a parameter declaration is \"type name\" (e.g. \"float radius\")"),
            ));
        };
        let ty = ParamType::from_name(type_name).ok_or_else(|| {
            let hint = match type_name {
                "point" => " (pbrt-v3 spelling: use \"point3\")",
                "vector" => " (pbrt-v3 spelling: use \"vector3\")",
                "color" => " (pbrt-v3 spelling: use \"rgb\")",
                "normal3" => " (use \"normal\")",
                _ => "",
            };
            Error::new(&loc, format!("\"{type_name}\": unknown parameter type{hint}"))
        })?;
        let values = parameter_values(s, ty, name, &loc)?;
        params.push(Param::new(ty, name, values, loc));
    }
}

/// Values accumulated while reading one parameter.
enum Acc {
    Empty,
    Ints(Vec<i32>),
    Floats(Vec<f32>),
    Strings(Vec<String>),
    Bools(Vec<bool>),
}

fn parameter_values(s: &mut TokenStream, ty: ParamType, name: &str, loc: &FileLoc) -> Result<ParamValues> {
    let first = s.expect_with(|| format!("a value for parameter \"{name}\""))?;
    let mut acc = Acc::Empty;
    if first.kind == TokenKind::Open {
        loop {
            let t = s.expect_with(|| format!("']' to close the values of \"{name}\""))?;
            if t.kind == TokenKind::Close {
                break;
            }
            add_value(s, &t, ty, name, &mut acc)?;
        }
    } else {
        add_value(s, &first, ty, name, &mut acc)?;
    }
    let values = match acc {
        Acc::Empty => match ty {
            ParamType::Integer => ParamValues::Ints(Vec::new()),
            ParamType::Bool => ParamValues::Bools(Vec::new()),
            ParamType::String | ParamType::Texture => ParamValues::Strings(Vec::new()),
            _ => ParamValues::Floats(Vec::new()),
        },
        Acc::Ints(v) => ParamValues::Ints(v),
        Acc::Floats(v) => ParamValues::Floats(v),
        Acc::Strings(v) => ParamValues::Strings(v),
        Acc::Bools(v) => ParamValues::Bools(v),
    };
    let n = values.len();
    let per = ty.per_item();
    if n % per != 0 {
        return Err(Error::new(
            loc,
            format!("\"{ty} {name}\": {n} values given, but a {ty} takes {per}: the count must be a multiple of {per}"),
        ));
    }
    if ty == ParamType::Spectrum && matches!(values, ParamValues::Floats(_)) {
        if n % 2 != 0 {
            return Err(Error::new(
                loc,
                format!("\"spectrum {name}\": odd number of values; expected wavelength/value pairs"),
            ));
        }
        if let ParamValues::Floats(v) = &values {
            for i in 1..n / 2 {
                if v[2 * i] <= v[2 * (i - 1)] {
                    return Err(Error::new(
                        loc,
                        format!(
                            "\"spectrum {name}\": wavelengths must increase, but {} follows {}",
                            v[2 * i],
                            v[2 * (i - 1)]
                        ),
                    ));
                }
            }
        }
    }
    Ok(values)
}

#[inline]
fn add_value(s: &TokenStream, t: &Token, ty: ParamType, name: &str, acc: &mut Acc) -> Result<()> {
    let is_str = matches!(t.kind, TokenKind::Str { .. });
    let bad = |what: &str| Error::new(&s.loc(t), format!("{}: expected {what} for \"{ty} {name}\"", describe(s, t)));
    if !is_str && t.kind != TokenKind::Word {
        return Err(Error::new(&s.loc(t), format!("unexpected \"[\" inside the values of \"{name}\"")));
    }
    match ty {
        ParamType::Integer => {
            if is_str {
                return Err(bad("an integer"));
            }
            let v = match parse_i32(s.bytes(t)) {
                Ok(v) => v,
                Err(IntError::Overflow) => {
                    return Err(Error::new(&s.loc(t), format!("{}: too large for a 32-bit integer", describe(s, t))));
                }
                Err(IntError::NotInteger) => return Err(bad("an integer")),
            };
            match acc {
                Acc::Ints(vs) => vs.push(v),
                _ => *acc = Acc::Ints(vec![v]),
            }
        }
        ParamType::Bool => {
            let v = match s.bytes(t) {
                b"true" => true,
                b"false" => false,
                _ => return Err(bad("true or false")),
            };
            match acc {
                Acc::Bools(vs) => vs.push(v),
                _ => *acc = Acc::Bools(vec![v]),
            }
        }
        ParamType::String | ParamType::Texture => {
            if !is_str {
                return Err(bad("a quoted string"));
            }
            let v = s.text(t)?;
            match acc {
                Acc::Strings(vs) => vs.push(v),
                _ => *acc = Acc::Strings(vec![v]),
            }
        }
        ParamType::Spectrum if is_str || matches!(acc, Acc::Strings(_)) => {
            if !is_str {
                return Err(bad("a quoted spectrum name (values cannot mix names and numbers)"));
            }
            let v = s.text(t)?;
            match acc {
                Acc::Strings(vs) => vs.push(v),
                Acc::Empty => *acc = Acc::Strings(vec![v]),
                _ => return Err(bad("a number (values cannot mix names and numbers)")),
            }
        }
        _ => {
            if is_str {
                return Err(bad("a number"));
            }
            let v = parse_f64(s.bytes(t)).ok_or_else(|| bad("a number"))?;
            let f = v as f32;
            if !f.is_finite() {
                return Err(Error::new(&s.loc(t), format!("{}: out of range for a 32-bit float", describe(s, t))));
            }
            match acc {
                Acc::Floats(vs) => vs.push(f),
                _ => *acc = Acc::Floats(vec![f]),
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<Directive>> {
        let mut r = DirectiveRecorder::default();
        parse_str(text, "t.pbrt", &mut r)?;
        Ok(r.directives.into_iter().map(|(d, _)| d).collect())
    }

    #[test]
    fn parameter_lists() {
        let d =
            parse(r#"Shape "sphere" "float radius" 2 "integer indices" [0 1 2] "bool b" true "string s" "x""#).unwrap();
        let Directive::Shape(name, params) = &d[0] else { panic!() };
        assert_eq!(name, "sphere");
        assert_eq!(params[0].values, ParamValues::Floats(vec![2.0]));
        assert_eq!(params[1].values, ParamValues::Ints(vec![0, 1, 2]));
        assert_eq!(params[2].values, ParamValues::Bools(vec![true]));
        assert_eq!(params[3].values, ParamValues::Strings(vec!["x".into()]));
    }

    #[test]
    fn medium_interface_with_one_or_two_names() {
        let d = parse(r#"MediumInterface "a" MediumInterface "b" "c""#).unwrap();
        assert_eq!(d[0], Directive::MediumInterface { inside: "a".into(), outside: "a".into() });
        assert_eq!(d[1], Directive::MediumInterface { inside: "b".into(), outside: "c".into() });
    }

    #[test]
    fn errors_name_the_offending_text_and_place() {
        let e = parse("WorldBegin\n  Shpe \"sphere\"").unwrap_err();
        assert_eq!(e.to_string(), "t.pbrt:2:3: unknown directive \"Shpe\"");
        let e = parse("Shape \"sphere\" \"float radius\" [ 1 x ]").unwrap_err();
        assert_eq!(e.to_string(), "t.pbrt:1:35: \"x\": expected a number for \"float radius\"");
        let e = parse("Shape \"sphere\" \"integer n\" 1.5").unwrap_err();
        assert!(e.to_string().starts_with("t.pbrt:1:28: \"1.5\": expected an integer"), "{e}");
        let e = parse("Shape \"trianglemesh\" \"point3 P\" [ 1 2 ]").unwrap_err();
        assert!(e.message.contains("multiple of 3"), "{e}");
        let e = parse("Shape \"sphere\" \"colour c\" [ 1 2 3 ]").unwrap_err();
        assert_eq!(e.to_string(), "t.pbrt:1:16: \"colour\": unknown parameter type");
        let e = parse("Translate 1 2").unwrap_err();
        assert!(e.message.contains("premature end of file"), "{e}");
        let e = parse("Shape \"sphere\" \"float radius\" [ 1 ").unwrap_err();
        assert!(e.message.contains("premature end of file"), "{e}");
    }
}
