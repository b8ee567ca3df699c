//! Typed parameter lists (`"float fov" [ 45 ]`) and the dictionary consumers read them from.
//!
//! Consumers look parameters up by name and type; each lookup marks the parameter as used, so
//! [`ParameterDictionary::report_unused`] can name every parameter nothing read (pbrt-v4 makes
//! those fatal). A name given with a type the consumer does not accept is an error, not a
//! silent default.

use std::fmt;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::{Error, Result, Warning};
use crate::loc::FileLoc;

/// The type written before a parameter's name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParamType {
    /// `integer`
    Integer,
    /// `float`
    Float,
    /// `point2`
    Point2,
    /// `vector2`
    Vector2,
    /// `point3`
    Point3,
    /// `vector3`
    Vector3,
    /// `normal`
    Normal,
    /// `bool`
    Bool,
    /// `string`
    String,
    /// `texture`: the name of a texture
    Texture,
    /// `rgb`: RGB triples in the current color space
    Rgb,
    /// `spectrum`: wavelength/value pairs, a named spectrum, or a `.spd` file
    Spectrum,
    /// `blackbody`: a temperature in Kelvin
    Blackbody,
}

impl ParamType {
    /// Every type, in the order pbrt-v4's documentation lists them.
    pub const ALL: [ParamType; 13] = [
        ParamType::Integer,
        ParamType::Float,
        ParamType::Point2,
        ParamType::Vector2,
        ParamType::Point3,
        ParamType::Vector3,
        ParamType::Normal,
        ParamType::Bool,
        ParamType::String,
        ParamType::Texture,
        ParamType::Rgb,
        ParamType::Spectrum,
        ParamType::Blackbody,
    ];

    /// The spelling in scene files.
    pub fn name(self) -> &'static str {
        match self {
            ParamType::Integer => "integer",
            ParamType::Float => "float",
            ParamType::Point2 => "point2",
            ParamType::Vector2 => "vector2",
            ParamType::Point3 => "point3",
            ParamType::Vector3 => "vector3",
            ParamType::Normal => "normal",
            ParamType::Bool => "bool",
            ParamType::String => "string",
            ParamType::Texture => "texture",
            ParamType::Rgb => "rgb",
            ParamType::Spectrum => "spectrum",
            ParamType::Blackbody => "blackbody",
        }
    }

    /// The type spelled `name`, if pbrt-v4 knows it.
    pub fn from_name(name: &str) -> Option<ParamType> {
        ParamType::ALL.into_iter().find(|t| t.name() == name)
    }

    /// How many numbers make one item (3 for a `point3`); 1 for non-numeric types.
    pub fn per_item(self) -> usize {
        match self {
            ParamType::Point2 | ParamType::Vector2 => 2,
            ParamType::Point3 | ParamType::Vector3 | ParamType::Normal | ParamType::Rgb => 3,
            _ => 1,
        }
    }
}

impl fmt::Display for ParamType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The values of one parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValues {
    /// `integer` values.
    Ints(Vec<i32>),
    /// Numeric values of every other numeric type (flattened: a `point3` list holds 3n).
    Floats(Vec<f32>),
    /// `string` and `texture` values, and named or file `spectrum` values.
    Strings(Vec<String>),
    /// `bool` values.
    Bools(Vec<bool>),
}

impl ParamValues {
    /// Number of scalar values (a `point3` counts 3).
    pub fn len(&self) -> usize {
        match self {
            ParamValues::Ints(v) => v.len(),
            ParamValues::Floats(v) => v.len(),
            ParamValues::Strings(v) => v.len(),
            ParamValues::Bools(v) => v.len(),
        }
    }

    /// True when no values were given (`[ ]`).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One parameter as written: `"type name" values`.
#[derive(Debug)]
pub struct Param {
    /// Declared type.
    pub ty: ParamType,
    /// Name (`fov`, `reflectance`, ...).
    pub name: String,
    /// The values.
    pub values: ParamValues,
    /// Where the `"type name"` declaration is.
    pub loc: FileLoc,
    /// Set by any lookup that returned this parameter.
    looked_up: AtomicBool,
    /// Defaults from `Attribute` need not be used by every entity that inherits them.
    may_be_unused: bool,
}

impl Clone for Param {
    fn clone(&self) -> Param {
        Param {
            ty: self.ty,
            name: self.name.clone(),
            values: self.values.clone(),
            loc: self.loc.clone(),
            looked_up: AtomicBool::new(self.looked_up.load(Ordering::Relaxed)),
            may_be_unused: self.may_be_unused,
        }
    }
}

impl PartialEq for Param {
    /// Parameters are equal when type, name and values are; location and use are ignored.
    fn eq(&self, other: &Param) -> bool {
        self.ty == other.ty && self.name == other.name && self.values == other.values
    }
}

impl Param {
    /// A parameter as parsed at `loc`.
    pub fn new(ty: ParamType, name: impl Into<String>, values: ParamValues, loc: FileLoc) -> Param {
        Param { ty, name: name.into(), values, loc, looked_up: AtomicBool::new(false), may_be_unused: false }
    }

    /// Marks the parameter as an `Attribute` default, which entities may ignore.
    pub(crate) fn into_attribute_default(mut self) -> Param {
        self.may_be_unused = true;
        self
    }

    fn mark_used(&self) {
        self.looked_up.store(true, Ordering::Relaxed);
    }

    /// True once a lookup has returned this parameter.
    pub fn is_used(&self) -> bool {
        self.looked_up.load(Ordering::Relaxed)
    }

    fn floats(&self) -> &[f32] {
        match &self.values {
            ParamValues::Floats(v) => v,
            _ => &[],
        }
    }
}

/// A spectral quantity as the scene gave it; the renderer turns it into its color space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpectrumValue<'a> {
    /// `"rgb name" [r g b]`, in the entity's color space.
    Rgb([f32; 3]),
    /// `"blackbody name" [T]`: a normalised blackbody emitter at T Kelvin.
    Blackbody(f32),
    /// `"spectrum name" [λ0 v0 λ1 v1 ...]`: piecewise-linear samples, λ in nm, increasing.
    Samples(&'a [f32]),
    /// `"spectrum name" "metal-Au-eta"` or `"spectrum name" "file.spd"`: a named spectrum or
    /// a file of samples (resolve with the parameter's location).
    Named(&'a str),
}

/// A spectrum parameter with where it was written.
#[derive(Clone, Copy, Debug)]
pub struct SpectrumParam<'a> {
    /// The value.
    pub value: SpectrumValue<'a>,
    /// Where the parameter is declared (files resolve relative to it).
    pub loc: &'a FileLoc,
}

/// A value that may be given directly or as the name of a texture.
#[derive(Clone, Copy, Debug)]
pub enum FloatOrTexture<'a> {
    /// `"float name" v`
    Value(f32),
    /// `"texture name" "texname"`
    Texture(&'a str, &'a FileLoc),
}

/// A spectrum that may be given directly or as the name of a texture.
#[derive(Clone, Copy, Debug)]
pub enum SpectrumOrTexture<'a> {
    /// An `rgb`, `spectrum` or `blackbody` value.
    Value(SpectrumParam<'a>),
    /// `"texture name" "texname"`
    Texture(&'a str, &'a FileLoc),
}

/// The parameters of one entity, in lookup order: within a directive the last occurrence of a
/// name wins, and the directive's own parameters win over `Attribute` defaults.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParameterDictionary {
    params: Vec<Param>,
}

impl ParameterDictionary {
    /// A dictionary from a directive's parameters (in file order) and the `Attribute` defaults
    /// that apply (in file order).
    pub fn new(own: Vec<Param>, defaults: &[Param]) -> ParameterDictionary {
        let mut params = own;
        params.reverse();
        params.extend(defaults.iter().rev().map(|p| p.clone().into_attribute_default()));
        ParameterDictionary { params }
    }

    /// All parameters in lookup order.
    pub fn iter(&self) -> impl Iterator<Item = &Param> {
        self.params.iter()
    }

    /// True when there are no parameters at all.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The first parameter called `name` (of any type), without marking it used.
    pub fn peek(&self, name: &str) -> Option<&Param> {
        self.params.iter().find(|p| p.name == name)
    }

    /// Where the parameter `name` is declared, if it is.
    pub fn loc(&self, name: &str) -> Option<&FileLoc> {
        self.peek(name).map(|p| &p.loc)
    }

    /// Finds `name` among the types in `accepted`. A parameter with that name but another
    /// type (not an `Attribute` default) is an error: it would otherwise be silently ignored.
    fn find(&self, name: &str, accepted: &[ParamType]) -> Result<Option<&Param>> {
        for p in &self.params {
            if p.name != name {
                continue;
            }
            if accepted.contains(&p.ty) {
                p.mark_used();
                return Ok(Some(p));
            }
            if !p.may_be_unused {
                let list: Vec<&str> = accepted.iter().map(|t| t.name()).collect();
                return Err(Error::new(
                    &p.loc,
                    format!("parameter \"{}\" has type \"{}\" but must be {}", name, p.ty, quoted_alternatives(&list)),
                ));
            }
        }
        Ok(None)
    }

    fn one_float_item(&self, name: &str, ty: ParamType) -> Result<Option<&[f32]>> {
        let Some(p) = self.find(name, &[ty])? else {
            return Ok(None);
        };
        let v = p.floats();
        check_single(p, v.len(), ty.per_item())?;
        Ok(Some(v))
    }

    /// A single `float`, or `default`.
    pub fn get_one_float(&self, name: &str, default: f32) -> Result<f32> {
        Ok(self.one_float_item(name, ParamType::Float)?.map_or(default, |v| v[0]))
    }

    /// A single `float` if given.
    pub fn get_opt_float(&self, name: &str) -> Result<Option<f32>> {
        Ok(self.one_float_item(name, ParamType::Float)?.map(|v| v[0]))
    }

    /// A single `integer`, or `default`.
    pub fn get_one_int(&self, name: &str, default: i32) -> Result<i32> {
        let Some(p) = self.find(name, &[ParamType::Integer])? else {
            return Ok(default);
        };
        match &p.values {
            ParamValues::Ints(v) => {
                check_single(p, v.len(), 1)?;
                Ok(v[0])
            }
            _ => Err(Error::new(&p.loc, format!("parameter \"{name}\" holds no integers"))),
        }
    }

    /// A single `bool`, or `default`.
    pub fn get_one_bool(&self, name: &str, default: bool) -> Result<bool> {
        let Some(p) = self.find(name, &[ParamType::Bool])? else {
            return Ok(default);
        };
        match &p.values {
            ParamValues::Bools(v) => {
                check_single(p, v.len(), 1)?;
                Ok(v[0])
            }
            _ => Err(Error::new(&p.loc, format!("parameter \"{name}\" holds no Boolean values"))),
        }
    }

    /// A single `string`, if given.
    pub fn get_opt_string(&self, name: &str) -> Result<Option<&str>> {
        let Some(p) = self.find(name, &[ParamType::String])? else {
            return Ok(None);
        };
        match &p.values {
            ParamValues::Strings(v) => {
                check_single(p, v.len(), 1)?;
                Ok(Some(&v[0]))
            }
            _ => Err(Error::new(&p.loc, format!("parameter \"{name}\" holds no strings"))),
        }
    }

    /// A single `string`, or `default`.
    pub fn get_one_string<'a>(&'a self, name: &str, default: &'a str) -> Result<&'a str> {
        Ok(self.get_opt_string(name)?.unwrap_or(default))
    }

    /// A single `point2`, or `default`.
    pub fn get_one_point2(&self, name: &str, default: [f32; 2]) -> Result<[f32; 2]> {
        Ok(self.one_float_item(name, ParamType::Point2)?.map_or(default, |v| [v[0], v[1]]))
    }

    /// A single `vector2`, or `default`.
    pub fn get_one_vector2(&self, name: &str, default: [f32; 2]) -> Result<[f32; 2]> {
        Ok(self.one_float_item(name, ParamType::Vector2)?.map_or(default, |v| [v[0], v[1]]))
    }

    /// A single `point3`, or `default`.
    pub fn get_one_point3(&self, name: &str, default: [f32; 3]) -> Result<[f32; 3]> {
        Ok(self.one_float_item(name, ParamType::Point3)?.map_or(default, |v| [v[0], v[1], v[2]]))
    }

    /// A single `vector3`, or `default`.
    pub fn get_one_vector3(&self, name: &str, default: [f32; 3]) -> Result<[f32; 3]> {
        Ok(self.one_float_item(name, ParamType::Vector3)?.map_or(default, |v| [v[0], v[1], v[2]]))
    }

    /// A single `normal`, or `default`.
    pub fn get_one_normal(&self, name: &str, default: [f32; 3]) -> Result<[f32; 3]> {
        Ok(self.one_float_item(name, ParamType::Normal)?.map_or(default, |v| [v[0], v[1], v[2]]))
    }

    fn float_array(&self, name: &str, ty: ParamType) -> Result<&[f32]> {
        let Some(p) = self.find(name, &[ty])? else {
            return Ok(&[]);
        };
        let v = p.floats();
        if v.is_empty() {
            return Err(Error::new(&p.loc, format!("no values provided for \"{name}\"")));
        }
        // The parser already checked that the count is a multiple of the item size.
        Ok(v)
    }

    /// All values of a `float` array (empty when absent).
    pub fn get_floats(&self, name: &str) -> Result<&[f32]> {
        self.float_array(name, ParamType::Float)
    }

    /// All values of an `integer` array (empty when absent).
    pub fn get_ints(&self, name: &str) -> Result<&[i32]> {
        let Some(p) = self.find(name, &[ParamType::Integer])? else {
            return Ok(&[]);
        };
        match &p.values {
            ParamValues::Ints(v) if !v.is_empty() => Ok(v),
            _ => Err(Error::new(&p.loc, format!("no values provided for \"{name}\""))),
        }
    }

    /// All values of a `string` array (empty when absent).
    pub fn get_strings(&self, name: &str) -> Result<&[String]> {
        let Some(p) = self.find(name, &[ParamType::String])? else {
            return Ok(&[]);
        };
        match &p.values {
            ParamValues::Strings(v) if !v.is_empty() => Ok(v),
            _ => Err(Error::new(&p.loc, format!("no values provided for \"{name}\""))),
        }
    }

    /// All items of a `point2` array.
    pub fn get_point2s(&self, name: &str) -> Result<&[[f32; 2]]> {
        Ok(self.float_array(name, ParamType::Point2)?.as_chunks::<2>().0)
    }

    /// All items of a `vector2` array.
    pub fn get_vector2s(&self, name: &str) -> Result<&[[f32; 2]]> {
        Ok(self.float_array(name, ParamType::Vector2)?.as_chunks::<2>().0)
    }

    /// All items of a `point3` array.
    pub fn get_point3s(&self, name: &str) -> Result<&[[f32; 3]]> {
        Ok(self.float_array(name, ParamType::Point3)?.as_chunks::<3>().0)
    }

    /// All items of a `vector3` array.
    pub fn get_vector3s(&self, name: &str) -> Result<&[[f32; 3]]> {
        Ok(self.float_array(name, ParamType::Vector3)?.as_chunks::<3>().0)
    }

    /// All items of a `normal` array.
    pub fn get_normals(&self, name: &str) -> Result<&[[f32; 3]]> {
        Ok(self.float_array(name, ParamType::Normal)?.as_chunks::<3>().0)
    }

    /// All items of an `rgb` array.
    pub fn get_rgbs(&self, name: &str) -> Result<&[[f32; 3]]> {
        Ok(self.float_array(name, ParamType::Rgb)?.as_chunks::<3>().0)
    }

    /// A single spectrum given as `rgb`, `blackbody` or `spectrum`, if present.
    pub fn get_one_spectrum(&self, name: &str) -> Result<Option<SpectrumParam<'_>>> {
        let Some(p) = self.find(name, &[ParamType::Rgb, ParamType::Blackbody, ParamType::Spectrum])? else {
            return Ok(None);
        };
        spectrum_of(p).map(Some)
    }

    /// A `texture` name, if present.
    pub fn get_texture(&self, name: &str) -> Result<Option<&str>> {
        let Some(p) = self.find(name, &[ParamType::Texture])? else {
            return Ok(None);
        };
        texture_name(p).map(Some)
    }

    /// A float given as a `float` or as a `texture` name, if present.
    pub fn get_float_or_texture(&self, name: &str) -> Result<Option<FloatOrTexture<'_>>> {
        let Some(p) = self.find(name, &[ParamType::Float, ParamType::Texture])? else {
            return Ok(None);
        };
        if p.ty == ParamType::Texture {
            return Ok(Some(FloatOrTexture::Texture(texture_name(p)?, &p.loc)));
        }
        let v = p.floats();
        check_single(p, v.len(), 1)?;
        Ok(Some(FloatOrTexture::Value(v[0])))
    }

    /// A spectrum given as `rgb`, `blackbody`, `spectrum` or a `texture` name, if present.
    pub fn get_spectrum_or_texture(&self, name: &str) -> Result<Option<SpectrumOrTexture<'_>>> {
        let Some(p) =
            self.find(name, &[ParamType::Rgb, ParamType::Blackbody, ParamType::Spectrum, ParamType::Texture])?
        else {
            return Ok(None);
        };
        if p.ty == ParamType::Texture {
            return Ok(Some(SpectrumOrTexture::Texture(texture_name(p)?, &p.loc)));
        }
        spectrum_of(p).map(|s| Some(SpectrumOrTexture::Value(s)))
    }

    /// Warnings naming every parameter no lookup used (pbrt-v4: "unused parameter"). A name
    /// given twice counts as used when its winning occurrence was used.
    pub fn report_unused(&self) -> Vec<Warning> {
        let mut seen: Vec<(ParamType, &str)> = Vec::new();
        let mut out = Vec::new();
        for p in &self.params {
            if p.may_be_unused {
                continue;
            }
            let shadowed = seen.iter().any(|&(t, n)| t == p.ty && n == p.name);
            if p.is_used() {
                if !shadowed {
                    seen.push((p.ty, &p.name));
                }
            } else if !shadowed {
                out.push(Warning::new(&p.loc, format!("\"{} {}\": unused parameter", p.ty, p.name)));
            }
        }
        out
    }
}

fn quoted_alternatives(list: &[&str]) -> String {
    match list {
        [one] => format!("\"{one}\""),
        _ => {
            let (last, rest) = list.split_last().expect("non-empty");
            let rest: Vec<String> = rest.iter().map(|s| format!("\"{s}\"")).collect();
            format!("{} or \"{last}\"", rest.join(", "))
        }
    }
}

fn check_single(p: &Param, len: usize, per_item: usize) -> Result<()> {
    if len == 0 {
        return Err(Error::new(&p.loc, format!("no values provided for parameter \"{}\"", p.name)));
    }
    if len > per_item {
        return Err(Error::new(
            &p.loc,
            format!("more than one value provided for parameter \"{}\" (expected one {})", p.name, p.ty),
        ));
    }
    Ok(())
}

fn texture_name(p: &Param) -> Result<&str> {
    match &p.values {
        ParamValues::Strings(v) if v.len() == 1 => Ok(&v[0]),
        ParamValues::Strings(v) if v.len() > 1 => {
            Err(Error::new(&p.loc, format!("more than one texture name provided for \"{}\"", p.name)))
        }
        _ => Err(Error::new(&p.loc, format!("no texture name provided for \"{}\"", p.name))),
    }
}

fn spectrum_of(p: &Param) -> Result<SpectrumParam<'_>> {
    let value = match (p.ty, &p.values) {
        (ParamType::Rgb, ParamValues::Floats(v)) => {
            check_single(p, v.len(), 3)?;
            SpectrumValue::Rgb([v[0], v[1], v[2]])
        }
        (ParamType::Blackbody, ParamValues::Floats(v)) => {
            check_single(p, v.len(), 1)?;
            SpectrumValue::Blackbody(v[0])
        }
        (ParamType::Spectrum, ParamValues::Floats(v)) => {
            if v.is_empty() {
                return Err(Error::new(&p.loc, format!("no values provided for \"{}\"", p.name)));
            }
            SpectrumValue::Samples(v)
        }
        (ParamType::Spectrum, ParamValues::Strings(v)) => {
            check_single(p, v.len(), 1)?;
            SpectrumValue::Named(&v[0])
        }
        _ => {
            return Err(Error::new(&p.loc, format!("no values provided for \"{}\"", p.name)));
        }
    };
    Ok(SpectrumParam { value, loc: &p.loc })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn loc(line: u32) -> FileLoc {
        FileLoc::new(Arc::from("t.pbrt"), line, 1)
    }

    fn float(name: &str, v: &[f32], line: u32) -> Param {
        Param::new(ParamType::Float, name, ParamValues::Floats(v.to_vec()), loc(line))
    }

    #[test]
    fn last_occurrence_wins_and_shadowed_is_not_unused() {
        let d = ParameterDictionary::new(vec![float("fov", &[30.0], 1), float("fov", &[45.0], 2)], &[]);
        assert_eq!(d.get_one_float("fov", 90.0).unwrap(), 45.0);
        assert!(d.report_unused().is_empty());
    }

    #[test]
    fn unused_parameters_are_named() {
        let d = ParameterDictionary::new(vec![float("fov", &[30.0], 1), float("lensradius", &[0.1], 2)], &[]);
        d.get_one_float("fov", 90.0).unwrap();
        let w = d.report_unused();
        assert_eq!(w.len(), 1);
        assert_eq!(w[0].to_string(), "t.pbrt:2:1: \"float lensradius\": unused parameter");
    }

    #[test]
    fn wrong_type_is_an_error() {
        let p = Param::new(ParamType::Integer, "fov", ParamValues::Ints(vec![30]), loc(3));
        let d = ParameterDictionary::new(vec![p], &[]);
        let e = d.get_one_float("fov", 90.0).unwrap_err();
        assert_eq!(e.to_string(), "t.pbrt:3:1: parameter \"fov\" has type \"integer\" but must be \"float\"");
    }

    #[test]
    fn too_many_values_is_an_error() {
        let d = ParameterDictionary::new(vec![float("fov", &[30.0, 40.0], 4)], &[]);
        assert!(d.get_one_float("fov", 90.0).unwrap_err().message.contains("more than one value"));
    }

    #[test]
    fn attribute_defaults_apply_and_may_go_unused() {
        let d = ParameterDictionary::new(vec![], &[float("radius", &[2.0], 1), float("other", &[1.0], 2)]);
        assert_eq!(d.get_one_float("radius", 1.0).unwrap(), 2.0);
        assert!(d.report_unused().is_empty());
        let own = ParameterDictionary::new(vec![float("radius", &[3.0], 5)], &[float("radius", &[2.0], 1)]);
        assert_eq!(own.get_one_float("radius", 1.0).unwrap(), 3.0);
    }

    #[test]
    fn arrays_come_back_as_items() {
        let p = Param::new(ParamType::Point3, "P", ParamValues::Floats(vec![0., 1., 2., 3., 4., 5.]), loc(1));
        let d = ParameterDictionary::new(vec![p], &[]);
        assert_eq!(d.get_point3s("P").unwrap(), &[[0., 1., 2.], [3., 4., 5.]]);
        assert!(d.get_point3s("missing").unwrap().is_empty());
    }

    #[test]
    fn spectra_and_textures() {
        let rgb = Param::new(ParamType::Rgb, "reflectance", ParamValues::Floats(vec![0.5, 0.25, 0.125]), loc(1));
        let tex = Param::new(ParamType::Texture, "roughness", ParamValues::Strings(vec!["r".into()]), loc(2));
        let d = ParameterDictionary::new(vec![rgb, tex], &[]);
        match d.get_spectrum_or_texture("reflectance").unwrap() {
            Some(SpectrumOrTexture::Value(s)) => {
                assert_eq!(s.value, SpectrumValue::Rgb([0.5, 0.25, 0.125]))
            }
            other => panic!("{other:?}"),
        }
        match d.get_float_or_texture("roughness").unwrap() {
            Some(FloatOrTexture::Texture(n, _)) => assert_eq!(n, "r"),
            other => panic!("{other:?}"),
        }
    }
}
