//! The scene as the file describes it, graphics state resolved: typed entities, each with its
//! parameters, transform and source location. Nothing here is created for rendering yet.

use glam::DMat4;

use crate::error::Warning;
use crate::loc::FileLoc;
use crate::params::ParameterDictionary;

/// The RGB color spaces pbrt-v4 knows (`ColorSpace "name"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum ColorSpace {
    /// `srgb` (the default)
    #[default]
    Srgb,
    /// `rec2020`
    Rec2020,
    /// `aces2065-1`
    Aces2065_1,
    /// `dci-p3`
    DciP3,
}

impl ColorSpace {
    /// The color space called `name` in scene files.
    pub fn from_name(name: &str) -> Option<ColorSpace> {
        match name {
            "srgb" => Some(ColorSpace::Srgb),
            "rec2020" => Some(ColorSpace::Rec2020),
            "aces2065-1" => Some(ColorSpace::Aces2065_1),
            "dci-p3" => Some(ColorSpace::DciP3),
            _ => None,
        }
    }

    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            ColorSpace::Srgb => "srgb",
            ColorSpace::Rec2020 => "rec2020",
            ColorSpace::Aces2065_1 => "aces2065-1",
            ColorSpace::DciP3 => "dci-p3",
        }
    }
}

/// A transform that may change over the shutter interval (`ActiveTransform`,
/// `TransformTimes`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnimatedTransform {
    /// The transform at `start_time`.
    pub start: DMat4,
    /// The transform at `end_time`.
    pub end: DMat4,
    /// Time of `start`.
    pub start_time: f64,
    /// Time of `end`.
    pub end_time: f64,
}

impl AnimatedTransform {
    /// A transform that does not move.
    pub fn fixed(m: DMat4) -> AnimatedTransform {
        AnimatedTransform { start: m, end: m, start_time: 0.0, end_time: 1.0 }
    }

    /// True when the start and end transforms differ.
    pub fn is_animated(&self) -> bool {
        self.start != self.end
    }
}

/// What every entity has: its type name (`"sphere"`, `"perspective"`, ...), parameters,
/// location and the color space its RGB values are in.
#[derive(Clone, Debug, PartialEq)]
pub struct Entity {
    /// The type name given in the directive.
    pub name: String,
    /// Its parameters (including applicable `Attribute` defaults).
    pub params: ParameterDictionary,
    /// Where the directive is.
    pub loc: FileLoc,
    /// Color space of the entity's RGB parameters.
    pub color_space: ColorSpace,
}

impl Entity {
    /// An entity with default parameters and no real location (the scene's defaults).
    pub fn default_named(name: &str) -> Entity {
        Entity {
            name: name.to_string(),
            params: ParameterDictionary::default(),
            loc: FileLoc::new(std::sync::Arc::from("<default>"), 0, 0),
            color_space: ColorSpace::Srgb,
        }
    }
}

/// The camera.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraEntity {
    /// Type and parameters.
    pub entity: Entity,
    /// World-from-camera (pbrt-v4's camera space: +z forward, +y up, left-handed).
    pub world_from_camera: AnimatedTransform,
    /// The medium the camera sits in (the *outside* of the current `MediumInterface`).
    pub medium: Option<String>,
}

/// The two media a surface separates. Only surfaces whose inside and outside differ are
/// boundaries; the description holds `None` for the rest.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MediumInterface {
    /// Medium on the side the normal points away from (`None`: vacuum).
    pub inside: Option<String>,
    /// Medium on the side the normal points to (`None`: vacuum).
    pub outside: Option<String>,
}

/// Which material a shape uses.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MaterialRef {
    /// An anonymous `Material`: index into [`SceneDescription::materials`].
    Index(usize),
    /// A `NamedMaterial`: key into [`SceneDescription::named_materials`].
    Named(String),
}

/// A shape with everything the graphics state attached to it.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeEntity {
    /// Type and parameters.
    pub entity: Entity,
    /// World-from-object (object-space-of-the-instance for shapes inside `ObjectBegin`).
    pub world_from_object: AnimatedTransform,
    /// `ReverseOrientation` was in effect.
    pub reverse_orientation: bool,
    /// The material.
    pub material: MaterialRef,
    /// Index into [`SceneDescription::area_lights`] when the shape emits.
    pub area_light: Option<usize>,
    /// Media on either side, when the shape is a boundary between different media.
    pub medium_interface: Option<MediumInterface>,
    /// The medium around the shape (the `MediumInterface`'s outside) even when it is not a
    /// boundary: area lights emit into it.
    pub outside_medium: Option<String>,
}

/// A light source (not an area light: those hang off shapes).
#[derive(Clone, Debug, PartialEq)]
pub struct LightEntity {
    /// Type and parameters.
    pub entity: Entity,
    /// World-from-light.
    pub world_from_light: AnimatedTransform,
    /// The medium the light sits in (outside of the current `MediumInterface`).
    pub medium: Option<String>,
}

/// A named medium.
#[derive(Clone, Debug, PartialEq)]
pub struct MediumEntity {
    /// The name shapes and the camera refer to it by.
    pub name: String,
    /// `entity.name` is the medium type (`"string type"`: homogeneous, uniformgrid, ...).
    pub entity: Entity,
    /// World-from-medium (the transform in effect at `MakeNamedMedium`).
    pub world_from_medium: AnimatedTransform,
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedMaterialEntity {
    /// The name `NamedMaterial` refers to it by.
    pub name: String,
    /// `entity.name` is the material type (`"string type"`).
    pub entity: Entity,
}

/// Whether a texture yields floats or spectra.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureValue {
    /// `Texture "name" "float" ...`
    Float,
    /// `Texture "name" "spectrum" ...`
    Spectrum,
}

/// A named texture.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureEntity {
    /// The name parameters refer to it by.
    pub name: String,
    /// Float or spectrum.
    pub value: TextureValue,
    /// `entity.name` is the texture class (`imagemap`, `checkerboard`, ...).
    pub entity: Entity,
    /// World-from-texture.
    pub world_from_texture: AnimatedTransform,
}

/// The shapes between `ObjectBegin` and `ObjectEnd`.
#[derive(Clone, Debug, PartialEq)]
pub struct InstanceDefinition {
    /// The object's name.
    pub name: String,
    /// Its shapes, in object space.
    pub shapes: Vec<ShapeEntity>,
    /// Where `ObjectBegin` is.
    pub loc: FileLoc,
}

/// One `ObjectInstance`.
#[derive(Clone, Debug, PartialEq)]
pub struct InstanceUse {
    /// The object it places.
    pub name: String,
    /// World-from-instance.
    pub world_from_instance: AnimatedTransform,
    /// Where `ObjectInstance` is.
    pub loc: FileLoc,
}

/// pbrt-v4's `Option` settings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneOptions {
    /// `Option "seed"`
    pub seed: Option<i32>,
    /// `Option "disablepixeljitter"`
    pub disable_pixel_jitter: bool,
    /// `Option "disabletexturefiltering"`
    pub disable_texture_filtering: bool,
    /// `Option "disablewavelengthjitter"`
    pub disable_wavelength_jitter: bool,
    /// `Option "displacementedgescale"`
    pub displacement_edge_scale: Option<f32>,
    /// `Option "msereferenceimage"`
    pub mse_reference_image: Option<String>,
    /// `Option "msereferenceout"`
    pub mse_reference_out: Option<String>,
    /// `Option "rendercoordsys"` (`camera`, `cameraworld` or `world`)
    pub render_coord_sys: Option<String>,
    /// `Option "forcediffuse"`
    pub force_diffuse: bool,
    /// `Option "pixelstats"`
    pub pixel_stats: bool,
    /// `Option "wavefront"`
    pub wavefront: bool,
    /// `Option "string spectral"`: nimbus's choice of light transport, `auto` (RGB when it
    /// gives the same answer, sampled spectra otherwise), `on` or `off`.
    pub spectral: Option<String>,
}

/// Everything a scene file describes.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneDescription {
    /// The camera (pbrt-v4's default: `perspective` at the origin).
    pub camera: CameraEntity,
    /// The film (default `rgb`).
    pub film: Entity,
    /// The sampler (default `zsobol`).
    pub sampler: Entity,
    /// The pixel filter (default `gaussian`).
    pub filter: Entity,
    /// The integrator (default `volpath`).
    pub integrator: Entity,
    /// The accelerator (default `bvh`).
    pub accelerator: Entity,
    /// `Option` settings.
    pub options: SceneOptions,
    /// Shapes outside object definitions.
    pub shapes: Vec<ShapeEntity>,
    /// Light sources.
    pub lights: Vec<LightEntity>,
    /// Area light definitions; shapes index into this.
    pub area_lights: Vec<Entity>,
    /// Anonymous materials; shapes index into this. Index 0 is pbrt-v4's default `diffuse`.
    pub materials: Vec<Entity>,
    /// Named materials in definition order.
    pub named_materials: Vec<NamedMaterialEntity>,
    /// Named media in definition order.
    pub media: Vec<MediumEntity>,
    /// Named textures in definition order.
    pub textures: Vec<TextureEntity>,
    /// Object definitions.
    pub instance_definitions: Vec<InstanceDefinition>,
    /// Object uses.
    pub instances: Vec<InstanceUse>,
    /// Files read (the main file first, then included and imported ones).
    pub files: Vec<String>,
    /// Non-fatal problems found while reading.
    pub warnings: Vec<Warning>,
}

impl SceneDescription {
    /// The named medium `name`.
    pub fn medium(&self, name: &str) -> Option<&MediumEntity> {
        self.media.iter().find(|m| m.name == name)
    }

    /// The named material `name`.
    pub fn named_material(&self, name: &str) -> Option<&NamedMaterialEntity> {
        self.named_materials.iter().find(|m| m.name == name)
    }

    /// The texture `name` of the given value type.
    pub fn texture(&self, name: &str, value: TextureValue) -> Option<&TextureEntity> {
        self.textures.iter().find(|t| t.name == name && t.value == value)
    }

    /// The material entity a shape refers to.
    pub fn material_of<'a>(&'a self, r: &MaterialRef) -> Option<&'a Entity> {
        match r {
            MaterialRef::Index(i) => self.materials.get(*i),
            MaterialRef::Named(n) => self.named_material(n).map(|m| &m.entity),
        }
    }
}
