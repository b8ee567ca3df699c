//! The directives of the pbrt-v4 format, as parsed: one value per statement in the file.

use crate::params::Param;

/// Which transforms of the start/end pair later transform directives change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ActiveTransform {
    /// Both (the default).
    All,
    /// Only the transform at shutter open.
    StartTime,
    /// Only the transform at shutter close.
    EndTime,
}

/// One statement of a scene file. Parameter lists keep file order.
#[derive(Clone, Debug, PartialEq)]
pub enum Directive {
    /// `Accelerator "name" params`
    Accelerator(String, Vec<Param>),
    /// `ActiveTransform All|StartTime|EndTime`
    ActiveTransform(ActiveTransform),
    /// `AreaLightSource "name" params`
    AreaLightSource(String, Vec<Param>),
    /// `Attribute "shape|light|material|medium|texture" params`
    Attribute(String, Vec<Param>),
    /// `AttributeBegin`
    AttributeBegin,
    /// `AttributeEnd`
    AttributeEnd,
    /// `Camera "name" params`
    Camera(String, Vec<Param>),
    /// `ColorSpace "name"`
    ColorSpace(String),
    /// `ConcatTransform [m00 .. m33]`
    ConcatTransform([f64; 16]),
    /// `CoordinateSystem "name"`
    CoordinateSystem(String),
    /// `CoordSysTransform "name"`
    CoordSysTransform(String),
    /// `Film "name" params`
    Film(String, Vec<Param>),
    /// `Identity`
    Identity,
    /// `Import "file"` (world block only; its graphics state does not leak out)
    Import(String),
    /// `Include "file"` (its tokens are spliced in place)
    Include(String),
    /// `Integrator "name" params`
    Integrator(String, Vec<Param>),
    /// `LightSource "name" params`
    LightSource(String, Vec<Param>),
    /// `LookAt ex ey ez  lx ly lz  ux uy uz`
    LookAt([f64; 9]),
    /// `MakeNamedMaterial "name" params` (with `"string type"`)
    MakeNamedMaterial(String, Vec<Param>),
    /// `MakeNamedMedium "name" params` (with `"string type"`)
    MakeNamedMedium(String, Vec<Param>),
    /// `Material "type" params`
    Material(String, Vec<Param>),
    /// `MediumInterface "inside" ["outside"]`: one name means inside and outside alike.
    MediumInterface {
        /// Medium inside the shapes that follow.
        inside: String,
        /// Medium outside them (and the medium of cameras and lights).
        outside: String,
    },
    /// `NamedMaterial "name"`
    NamedMaterial(String),
    /// `ObjectBegin "name"`
    ObjectBegin(String),
    /// `ObjectEnd`
    ObjectEnd,
    /// `ObjectInstance "name"`
    ObjectInstance(String),
    /// `Option "name" value`: the value token as written (quotes kept for strings).
    Option(String, String),
    /// `PixelFilter "name" params`
    PixelFilter(String, Vec<Param>),
    /// `ReverseOrientation`
    ReverseOrientation,
    /// `Rotate angle x y z` (degrees)
    Rotate([f64; 4]),
    /// `Sampler "name" params`
    Sampler(String, Vec<Param>),
    /// `Scale x y z`
    Scale([f64; 3]),
    /// `Shape "name" params`
    Shape(String, Vec<Param>),
    /// `Texture "name" "float|spectrum" "class" params`
    Texture {
        /// Name materials refer to it by.
        name: String,
        /// `float` or `spectrum`.
        value_type: String,
        /// Texture class (`imagemap`, `checkerboard`, ...).
        class: String,
        /// Parameters.
        params: Vec<Param>,
    },
    /// `Transform [m00 .. m33]`
    Transform([f64; 16]),
    /// `TransformBegin` (deprecated: treated as `AttributeBegin`)
    TransformBegin,
    /// `TransformEnd` (deprecated: treated as `AttributeEnd`)
    TransformEnd,
    /// `TransformTimes start end`
    TransformTimes(f64, f64),
    /// `Translate x y z`
    Translate([f64; 3]),
    /// `WorldBegin`
    WorldBegin,
}

impl Directive {
    /// The keyword that starts this directive in a file.
    pub fn keyword(&self) -> &'static str {
        match self {
            Directive::Accelerator(..) => "Accelerator",
            Directive::ActiveTransform(_) => "ActiveTransform",
            Directive::AreaLightSource(..) => "AreaLightSource",
            Directive::Attribute(..) => "Attribute",
            Directive::AttributeBegin => "AttributeBegin",
            Directive::AttributeEnd => "AttributeEnd",
            Directive::Camera(..) => "Camera",
            Directive::ColorSpace(_) => "ColorSpace",
            Directive::ConcatTransform(_) => "ConcatTransform",
            Directive::CoordinateSystem(_) => "CoordinateSystem",
            Directive::CoordSysTransform(_) => "CoordSysTransform",
            Directive::Film(..) => "Film",
            Directive::Identity => "Identity",
            Directive::Import(_) => "Import",
            Directive::Include(_) => "Include",
            Directive::Integrator(..) => "Integrator",
            Directive::LightSource(..) => "LightSource",
            Directive::LookAt(_) => "LookAt",
            Directive::MakeNamedMaterial(..) => "MakeNamedMaterial",
            Directive::MakeNamedMedium(..) => "MakeNamedMedium",
            Directive::Material(..) => "Material",
            Directive::MediumInterface { .. } => "MediumInterface",
            Directive::NamedMaterial(_) => "NamedMaterial",
            Directive::ObjectBegin(_) => "ObjectBegin",
            Directive::ObjectEnd => "ObjectEnd",
            Directive::ObjectInstance(_) => "ObjectInstance",
            Directive::Option(..) => "Option",
            Directive::PixelFilter(..) => "PixelFilter",
            Directive::ReverseOrientation => "ReverseOrientation",
            Directive::Rotate(_) => "Rotate",
            Directive::Sampler(..) => "Sampler",
            Directive::Scale(_) => "Scale",
            Directive::Shape(..) => "Shape",
            Directive::Texture { .. } => "Texture",
            Directive::Transform(_) => "Transform",
            Directive::TransformBegin => "TransformBegin",
            Directive::TransformEnd => "TransformEnd",
            Directive::TransformTimes(..) => "TransformTimes",
            Directive::Translate(_) => "Translate",
            Directive::WorldBegin => "WorldBegin",
        }
    }
}
