//! Parameter values as entities use them, checked where they are read so that an error names
//! the parameter's place: floats and integers within their ranges, floats that may come from
//! a texture.

use nimbus_parser::{Error, FloatOrTexture, ParameterDictionary};

/// A float that may come from a texture.
#[derive(Clone, Debug, PartialEq)]
pub enum FloatInput {
    /// A constant.
    Value(f32),
    /// The named float texture.
    Texture(String),
}

/// Reads an optional float-or-texture parameter.
pub fn float_input(params: &ParameterDictionary, name: &str) -> Result<Option<FloatInput>, Error> {
    Ok(params.get_float_or_texture(name)?.map(|f| match f {
        FloatOrTexture::Value(v) => FloatInput::Value(v),
        FloatOrTexture::Texture(t, _) => FloatInput::Texture(t.to_string()),
    }))
}

/// A float parameter that must satisfy `ok`, reported with `what` otherwise.
pub fn checked_float(
    params: &ParameterDictionary,
    name: &str,
    default: f32,
    ok: impl Fn(f32) -> bool,
    what: &str,
) -> Result<f32, Error> {
    let v = params.get_one_float(name, default)?;
    if !ok(v) {
        let loc = params.loc(name).cloned();
        return Err(Error { loc, message: format!("\"{name}\" = {v}: {what}") });
    }
    Ok(v)
}

/// An integer parameter that must satisfy `ok`.
pub fn checked_int(
    params: &ParameterDictionary,
    name: &str,
    default: i32,
    ok: impl Fn(i32) -> bool,
    what: &str,
) -> Result<i32, Error> {
    let v = params.get_one_int(name, default)?;
    if !ok(v) {
        let loc = params.loc(name).cloned();
        return Err(Error { loc, message: format!("\"{name}\" = {v}: {what}") });
    }
    Ok(v)
}
