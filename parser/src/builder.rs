//! The graphics state machine: follows transforms, attributes, materials, media and area lights
//! through the directives and emits the typed entities of a [`SceneDescription`]. Checks, as
//! pbrt-v4 does, that each directive is in the right block and that every name used is
//! defined.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use glam::DMat4;

use crate::description::*;
use crate::directive::{ActiveTransform, Directive};
use crate::error::{Error, Result, Warning};
use crate::loc::FileLoc;
use crate::params::{Param, ParamType, ParamValues, ParameterDictionary};
use crate::parser::ParserTarget;
use crate::transform;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Block {
    Options,
    World,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Push {
    Attribute,
    Object,
}

/// The area light that shapes take until the attribute block ends.
#[derive(Clone, Debug)]
struct AreaLight {
    name: String,
    params: Vec<Param>,
    loc: FileLoc,
    color_space: ColorSpace,
}

/// Attribute-scoped state.
#[derive(Clone, Debug)]
struct GraphicsState {
    /// Current transform matrix at start and end time (object-to-world in the world block,
    /// world-to-camera before it).
    ctm: [DMat4; 2],
    active: ActiveTransform,
    reverse_orientation: bool,
    color_space: ColorSpace,
    material: MaterialRef,
    /// Where `NamedMaterial` was given, to report an undefined name there.
    material_loc: Option<FileLoc>,
    area_light: Option<AreaLight>,
    inside: String,
    outside: String,
    medium_loc: Option<FileLoc>,
    shape_attributes: Vec<Param>,
    light_attributes: Vec<Param>,
    material_attributes: Vec<Param>,
    medium_attributes: Vec<Param>,
    texture_attributes: Vec<Param>,
    start_time: f64,
    end_time: f64,
}

impl GraphicsState {
    fn new() -> GraphicsState {
        GraphicsState {
            ctm: [DMat4::IDENTITY; 2],
            active: ActiveTransform::All,
            reverse_orientation: false,
            color_space: ColorSpace::Srgb,
            material: MaterialRef::Index(0),
            material_loc: None,
            area_light: None,
            inside: String::new(),
            outside: String::new(),
            medium_loc: None,
            shape_attributes: Vec::new(),
            light_attributes: Vec::new(),
            material_attributes: Vec::new(),
            medium_attributes: Vec::new(),
            texture_attributes: Vec::new(),
            start_time: 0.0,
            end_time: 1.0,
        }
    }

    fn apply(&mut self, f: impl Fn(DMat4) -> DMat4) {
        if self.active != ActiveTransform::EndTime {
            self.ctm[0] = f(self.ctm[0]);
        }
        if self.active != ActiveTransform::StartTime {
            self.ctm[1] = f(self.ctm[1]);
        }
    }

    fn transform(&self) -> AnimatedTransform {
        AnimatedTransform { start: self.ctm[0], end: self.ctm[1], start_time: self.start_time, end_time: self.end_time }
    }

    fn entity(&self, name: String, own: Vec<Param>, defaults: &[Param], loc: FileLoc) -> Entity {
        Entity { name, params: ParameterDictionary::new(own, defaults), loc, color_space: self.color_space }
    }
}

/// Adds every texture name `params` refers to, for checking once all textures are known.
fn texture_references(params: &ParameterDictionary, out: &mut Vec<(&'static str, String, FileLoc)>) {
    for p in params.iter() {
        if p.ty == ParamType::Texture
            && let ParamValues::Strings(names) = &p.values
        {
            out.extend(names.iter().map(|n| ("texture", n.clone(), p.loc.clone())));
        }
    }
}

fn medium_name(name: &str) -> Option<String> {
    (!name.is_empty()).then(|| name.to_string())
}

/// Builds a [`SceneDescription`] from directives.
pub struct SceneBuilder {
    block: Block,
    gs: GraphicsState,
    pushed: Vec<(GraphicsState, Push, FileLoc)>,
    named_coordinate_systems: HashMap<String, [DMat4; 2]>,
    imports: Vec<(GraphicsState, usize, HashMap<String, [DMat4; 2]>)>,
    active_instance: Option<InstanceDefinition>,
    instance_names: HashSet<String>,
    float_texture_names: HashSet<String>,
    spectrum_texture_names: HashSet<String>,
    /// Names used before they may be defined, checked at the end: (kind, name, where used).
    pending_names: Vec<(&'static str, String, FileLoc)>,
    warned_transform_begin: bool,
    scene: SceneDescription,
}

impl Default for SceneBuilder {
    fn default() -> Self {
        SceneBuilder::new()
    }
}

impl SceneBuilder {
    /// A builder with pbrt-v4's defaults.
    pub fn new() -> SceneBuilder {
        let mut diffuse = Entity::default_named("diffuse");
        diffuse.loc = FileLoc::new(Arc::from("<default material>"), 0, 0);
        SceneBuilder {
            block: Block::Options,
            gs: GraphicsState::new(),
            pushed: Vec::new(),
            named_coordinate_systems: HashMap::new(),
            imports: Vec::new(),
            active_instance: None,
            instance_names: HashSet::new(),
            float_texture_names: HashSet::new(),
            spectrum_texture_names: HashSet::new(),
            pending_names: Vec::new(),
            warned_transform_begin: false,
            scene: SceneDescription {
                camera: CameraEntity {
                    entity: Entity::default_named("perspective"),
                    world_from_camera: AnimatedTransform::fixed(DMat4::IDENTITY),
                    medium: None,
                },
                film: Entity::default_named("rgb"),
                sampler: Entity::default_named("zsobol"),
                filter: Entity::default_named("gaussian"),
                integrator: Entity::default_named("volpath"),
                accelerator: Entity::default_named("bvh"),
                options: SceneOptions::default(),
                shapes: Vec::new(),
                lights: Vec::new(),
                area_lights: Vec::new(),
                materials: vec![diffuse],
                named_materials: Vec::new(),
                media: Vec::new(),
                textures: Vec::new(),
                instance_definitions: Vec::new(),
                instances: Vec::new(),
                files: Vec::new(),
                warnings: Vec::new(),
            },
        }
    }

    fn options_only(&self, what: &str, loc: &FileLoc) -> Result<()> {
        if self.block == Block::World {
            return Err(Error::new(loc, format!("{what} is not allowed after WorldBegin (options block only)")));
        }
        Ok(())
    }

    fn world_only(&self, what: &str, loc: &FileLoc) -> Result<()> {
        if self.block == Block::Options {
            return Err(Error::new(loc, format!("{what} is not allowed before WorldBegin (world block only)")));
        }
        Ok(())
    }

    fn warn(&mut self, loc: &FileLoc, message: impl Into<String>) {
        self.scene.warnings.push(Warning::new(loc, message));
    }

    fn use_media(&mut self) {
        let loc = self.gs.medium_loc.clone();
        if let Some(loc) = loc {
            for name in [self.gs.inside.clone(), self.gs.outside.clone()] {
                if !name.is_empty() {
                    self.pending_names.push(("medium", name, loc.clone()));
                }
            }
        }
    }

    fn attribute_end(&mut self, loc: &FileLoc, expected: Push) -> Result<()> {
        let floor = self.imports.last().map_or(0, |i| i.1);
        if self.pushed.len() <= floor {
            let what = if expected == Push::Object {
                "ObjectEnd without ObjectBegin"
            } else {
                "AttributeEnd without matching AttributeBegin"
            };
            return Err(Error::new(loc, what));
        }
        let (gs, kind, begin) = self.pushed.pop().expect("checked non-empty");
        if kind != expected {
            let (open, close) = match kind {
                Push::Attribute => ("AttributeBegin", "ObjectEnd"),
                Push::Object => ("ObjectBegin", "AttributeEnd"),
            };
            return Err(Error::new(loc, format!("mismatched nesting: {close} closes the {open} at {begin}")));
        }
        self.gs = gs;
        Ok(())
    }

    fn check_texture_references(&mut self, params: &ParameterDictionary) {
        texture_references(params, &mut self.pending_names);
    }

    fn shape(&mut self, name: String, params: Vec<Param>, loc: FileLoc) -> Result<()> {
        self.world_only("Shape", &loc)?;
        let entity = self.gs.entity(name, params, &self.gs.shape_attributes, loc.clone());
        self.check_texture_references(&entity.params);
        self.use_media();
        if let (MaterialRef::Named(n), Some(at)) = (&self.gs.material, &self.gs.material_loc) {
            self.pending_names.push(("named material", n.clone(), at.clone()));
        }
        let mut area_light = None;
        if let Some(al) = &self.gs.area_light {
            if self.active_instance.is_some() {
                self.warn(&loc, "area lights are not supported with object instancing; this shape will not emit");
            } else {
                let params = ParameterDictionary::new(al.params.clone(), &self.gs.light_attributes);
                self.scene.area_lights.push(Entity {
                    name: al.name.clone(),
                    params,
                    loc: al.loc.clone(),
                    color_space: al.color_space,
                });
                area_light = Some(self.scene.area_lights.len() - 1);
            }
        }
        let medium_interface = (self.gs.inside != self.gs.outside)
            .then(|| MediumInterface { inside: medium_name(&self.gs.inside), outside: medium_name(&self.gs.outside) });
        let shape = ShapeEntity {
            entity,
            world_from_object: self.gs.transform(),
            reverse_orientation: self.gs.reverse_orientation,
            material: self.gs.material.clone(),
            area_light,
            medium_interface,
            outside_medium: medium_name(&self.gs.outside),
        };
        match &mut self.active_instance {
            Some(def) => def.shapes.push(shape),
            None => self.scene.shapes.push(shape),
        }
        Ok(())
    }

    fn option(&mut self, name: &str, value: &str, loc: &FileLoc) -> Result<()> {
        // Accept both `Option "seed" 5` and pbrt-v4's documented `Option "integer seed" 5`.
        let key: String = name
            .rsplit(' ')
            .next()
            .unwrap_or(name)
            .chars()
            .filter(|c| *c != '_' && *c != '-')
            .collect::<String>()
            .to_lowercase();
        let flag = |v: &str| -> Result<bool> {
            match v.trim_matches('"') {
                "true" => Ok(true),
                "false" => Ok(false),
                _ => Err(Error::new(loc, format!("Option \"{name}\": expected true or false, found {v}"))),
            }
        };
        let quoted = |v: &str| -> Result<String> {
            if v.len() >= 2 && v.starts_with('"') && v.ends_with('"') {
                Ok(v[1..v.len() - 1].to_string())
            } else {
                Err(Error::new(loc, format!("Option \"{name}\": expected a quoted string, found {v}")))
            }
        };
        let o = &mut self.scene.options;
        match key.as_str() {
            "disablepixeljitter" => o.disable_pixel_jitter = flag(value)?,
            "disabletexturefiltering" => o.disable_texture_filtering = flag(value)?,
            "disablewavelengthjitter" => o.disable_wavelength_jitter = flag(value)?,
            "forcediffuse" => o.force_diffuse = flag(value)?,
            "pixelstats" => o.pixel_stats = flag(value)?,
            "wavefront" => o.wavefront = flag(value)?,
            "displacementedgescale" => {
                o.displacement_edge_scale = Some(
                    value
                        .parse()
                        .map_err(|_| Error::new(loc, format!("Option \"{name}\": expected a number, found {value}")))?,
                )
            }
            "seed" => {
                o.seed =
                    Some(value.trim_matches('"').parse().map_err(|_| {
                        Error::new(loc, format!("Option \"{name}\": expected an integer, found {value}"))
                    })?)
            }
            "spectral" => {
                let v = quoted(value)?;
                if !matches!(v.as_str(), "auto" | "on" | "off") {
                    return Err(Error::new(
                        loc,
                        format!("Option \"{name}\": unknown transport \"{v}\" (auto, on or off)"),
                    ));
                }
                o.spectral = Some(v);
            }
            "msereferenceimage" => o.mse_reference_image = Some(quoted(value)?),
            "msereferenceout" => o.mse_reference_out = Some(quoted(value)?),
            "rendercoordsys" => {
                let v = quoted(value)?;
                if !matches!(v.as_str(), "camera" | "cameraworld" | "world") {
                    return Err(Error::new(
                        loc,
                        format!(
                            "Option \"{name}\": unknown rendering coordinate system \"{v}\" (camera, cameraworld or world)"
                        ),
                    ));
                }
                o.render_coord_sys = Some(v);
            }
            _ => {
                return Err(Error::new(loc, format!("Option \"{name}\": unknown option")));
            }
        }
        Ok(())
    }

    /// Checks that the scene is complete and every name it uses is defined, and returns it.
    pub fn finish(mut self) -> Result<SceneDescription> {
        if self.block != Block::World {
            return Err(Error::general("end of scene before WorldBegin: a pbrt-v4 scene needs a WorldBegin"));
        }
        if let Some((_, kind, loc)) = self.pushed.last() {
            let what = if *kind == Push::Object {
                "ObjectBegin has no matching ObjectEnd"
            } else {
                "AttributeBegin has no matching AttributeEnd"
            };
            return Err(Error::new(loc, what));
        }
        let scene = &self.scene;
        let entities = scene.materials.iter().chain(scene.named_materials.iter().map(|m| &m.entity));
        let entities =
            entities.chain(scene.textures.iter().map(|t| &t.entity)).chain(scene.lights.iter().map(|l| &l.entity));
        for e in entities {
            texture_references(&e.params, &mut self.pending_names);
        }
        let media: HashSet<&str> = self.scene.media.iter().map(|m| m.name.as_str()).collect();
        let materials: HashSet<&str> = self.scene.named_materials.iter().map(|m| m.name.as_str()).collect();
        for (kind, name, loc) in &self.pending_names {
            let defined = match *kind {
                "medium" => media.contains(name.as_str()),
                "named material" => materials.contains(name.as_str()),
                "texture" => self.float_texture_names.contains(name) || self.spectrum_texture_names.contains(name),
                _ => true,
            };
            if !defined {
                return Err(Error::new(loc, format!("{kind} \"{name}\" is not defined")));
            }
        }
        let objects: HashSet<&str> = self.scene.instance_definitions.iter().map(|d| d.name.as_str()).collect();
        for u in &self.scene.instances {
            if !objects.contains(u.name.as_str()) {
                return Err(Error::new(
                    &u.loc,
                    format!("object \"{}\" is not defined (ObjectInstance needs an ObjectBegin of that name)", u.name),
                ));
            }
        }
        Ok(self.scene)
    }
}

impl ParserTarget for SceneBuilder {
    fn directive(&mut self, directive: Directive, loc: FileLoc) -> Result<()> {
        match directive {
            Directive::Accelerator(name, params) => {
                self.options_only("Accelerator", &loc)?;
                self.scene.accelerator = self.gs.entity(name, params, &[], loc);
            }
            Directive::ActiveTransform(a) => self.gs.active = a,
            Directive::AreaLightSource(name, params) => {
                self.world_only("AreaLightSource", &loc)?;
                self.gs.area_light = Some(AreaLight { name, params, loc, color_space: self.gs.color_space });
            }
            Directive::Attribute(target, params) => {
                let list = match target.as_str() {
                    "shape" => &mut self.gs.shape_attributes,
                    "light" => &mut self.gs.light_attributes,
                    "material" => &mut self.gs.material_attributes,
                    "medium" => &mut self.gs.medium_attributes,
                    "texture" => &mut self.gs.texture_attributes,
                    _ => {
                        return Err(Error::new(
                            &loc,
                            format!(
                                "unknown Attribute target \"{target}\": must be \"shape\", \"light\", \"material\", \"medium\" or \"texture\""
                            ),
                        ));
                    }
                };
                list.extend(params);
            }
            Directive::AttributeBegin | Directive::TransformBegin => {
                if matches!(directive, Directive::TransformBegin) && !self.warned_transform_begin {
                    self.warned_transform_begin = true;
                    self.warn(&loc, "TransformBegin/TransformEnd are deprecated: use AttributeBegin/AttributeEnd");
                }
                self.world_only(directive.keyword(), &loc)?;
                self.pushed.push((self.gs.clone(), Push::Attribute, loc));
            }
            Directive::AttributeEnd | Directive::TransformEnd => {
                self.world_only(directive.keyword(), &loc)?;
                self.attribute_end(&loc, Push::Attribute)?;
            }
            Directive::Camera(name, params) => {
                self.options_only("Camera", &loc)?;
                let camera_from_world = self.gs.ctm;
                let inv = |m: &DMat4| {
                    transform::try_inverse(m)
                        .ok_or_else(|| Error::new(&loc, "the camera transform is singular (cannot be inverted)"))
                };
                let world_from_camera = [inv(&camera_from_world[0])?, inv(&camera_from_world[1])?];
                self.named_coordinate_systems.insert("camera".into(), world_from_camera);
                if !self.gs.outside.is_empty() {
                    self.pending_names.push((
                        "medium",
                        self.gs.outside.clone(),
                        self.gs.medium_loc.clone().unwrap_or(loc.clone()),
                    ));
                }
                self.scene.camera = CameraEntity {
                    world_from_camera: AnimatedTransform {
                        start: world_from_camera[0],
                        end: world_from_camera[1],
                        start_time: self.gs.start_time,
                        end_time: self.gs.end_time,
                    },
                    medium: medium_name(&self.gs.outside),
                    entity: self.gs.entity(name, params, &[], loc),
                };
            }
            Directive::ColorSpace(name) => {
                self.gs.color_space = ColorSpace::from_name(&name).ok_or_else(|| {
                    Error::new(&loc, format!("unknown color space \"{name}\" (srgb, rec2020, aces2065-1 or dci-p3)"))
                })?;
            }
            Directive::ConcatTransform(m) => self.gs.apply(|t| t * transform::from_pbrt_array(&m)),
            Directive::CoordinateSystem(name) => {
                self.named_coordinate_systems.insert(name, self.gs.ctm);
            }
            Directive::CoordSysTransform(name) => match self.named_coordinate_systems.get(&name) {
                Some(m) => self.gs.ctm = *m,
                None => self.warn(&loc, format!("couldn't find named coordinate system \"{name}\"")),
            },
            Directive::Film(name, params) => {
                self.options_only("Film", &loc)?;
                self.scene.film = self.gs.entity(name, params, &[], loc);
            }
            Directive::Identity => self.gs.apply(|_| DMat4::IDENTITY),
            Directive::Import(_) | Directive::Include(_) => {
                // The parser reads these files itself when building a scene.
                return Err(Error::new(&loc, "internal: Include/Import reached the scene builder"));
            }
            Directive::Integrator(name, params) => {
                self.options_only("Integrator", &loc)?;
                self.scene.integrator = self.gs.entity(name, params, &[], loc);
            }
            Directive::LightSource(name, params) => {
                self.world_only("LightSource", &loc)?;
                if !self.gs.outside.is_empty() {
                    self.pending_names.push((
                        "medium",
                        self.gs.outside.clone(),
                        self.gs.medium_loc.clone().unwrap_or(loc.clone()),
                    ));
                }
                let entity = self.gs.entity(name, params, &self.gs.light_attributes, loc);
                self.scene.lights.push(LightEntity {
                    entity,
                    world_from_light: self.gs.transform(),
                    medium: medium_name(&self.gs.outside),
                });
            }
            Directive::LookAt(v) => {
                let m = transform::look_at([v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]).ok_or_else(
                    || Error::new(&loc, "LookAt: the view direction is zero or parallel to the up vector"),
                )?;
                self.gs.apply(|t| t * m);
            }
            Directive::MakeNamedMaterial(name, params) => {
                self.world_only("MakeNamedMaterial", &loc)?;
                if self.scene.named_material(&name).is_some() {
                    return Err(Error::new(&loc, format!("named material \"{name}\" redefined")));
                }
                let entity = self.gs.entity(String::new(), params, &self.gs.material_attributes, loc.clone());
                let ty = entity.params.get_opt_string("type")?.map(str::to_string);
                let Some(ty) = ty else {
                    return Err(Error::new(
                        &loc,
                        format!("MakeNamedMaterial \"{name}\": missing \"string type\" parameter"),
                    ));
                };
                self.scene.named_materials.push(NamedMaterialEntity { name, entity: Entity { name: ty, ..entity } });
            }
            Directive::MakeNamedMedium(name, params) => {
                if self.scene.medium(&name).is_some() {
                    return Err(Error::new(&loc, format!("named medium \"{name}\" redefined")));
                }
                let entity = self.gs.entity(String::new(), params, &self.gs.medium_attributes, loc.clone());
                let ty = entity.params.get_opt_string("type")?.map(str::to_string);
                let Some(ty) = ty else {
                    return Err(Error::new(
                        &loc,
                        format!("MakeNamedMedium \"{name}\": missing \"string type\" parameter"),
                    ));
                };
                self.scene.media.push(MediumEntity {
                    name,
                    entity: Entity { name: ty, ..entity },
                    world_from_medium: self.gs.transform(),
                });
            }
            Directive::Material(name, params) => {
                self.world_only("Material", &loc)?;
                let entity = self.gs.entity(name, params, &self.gs.material_attributes, loc);
                self.scene.materials.push(entity);
                self.gs.material = MaterialRef::Index(self.scene.materials.len() - 1);
                self.gs.material_loc = None;
            }
            Directive::MediumInterface { inside, outside } => {
                self.gs.inside = inside;
                self.gs.outside = outside;
                self.gs.medium_loc = Some(loc);
            }
            Directive::NamedMaterial(name) => {
                self.world_only("NamedMaterial", &loc)?;
                self.gs.material = MaterialRef::Named(name);
                self.gs.material_loc = Some(loc);
            }
            Directive::ObjectBegin(name) => {
                self.world_only("ObjectBegin", &loc)?;
                if self.active_instance.is_some() {
                    return Err(Error::new(&loc, "ObjectBegin inside another object definition"));
                }
                if !self.instance_names.insert(name.clone()) {
                    return Err(Error::new(&loc, format!("object \"{name}\" redefined")));
                }
                self.pushed.push((self.gs.clone(), Push::Object, loc.clone()));
                self.active_instance = Some(InstanceDefinition { name, shapes: Vec::new(), loc });
            }
            Directive::ObjectEnd => {
                self.world_only("ObjectEnd", &loc)?;
                if self.active_instance.is_none() {
                    return Err(Error::new(&loc, "ObjectEnd without ObjectBegin"));
                }
                self.attribute_end(&loc, Push::Object)?;
                let def = self.active_instance.take().expect("checked above");
                self.scene.instance_definitions.push(def);
            }
            Directive::ObjectInstance(name) => {
                self.world_only("ObjectInstance", &loc)?;
                if self.active_instance.is_some() {
                    return Err(Error::new(&loc, "ObjectInstance inside an object definition"));
                }
                self.scene.instances.push(InstanceUse { name, world_from_instance: self.gs.transform(), loc });
            }
            Directive::Option(name, value) => self.option(&name, &value, &loc)?,
            Directive::PixelFilter(name, params) => {
                self.options_only("PixelFilter", &loc)?;
                self.scene.filter = self.gs.entity(name, params, &[], loc);
            }
            Directive::ReverseOrientation => {
                self.world_only("ReverseOrientation", &loc)?;
                self.gs.reverse_orientation = !self.gs.reverse_orientation;
            }
            Directive::Rotate(v) => {
                let r = transform::rotate(v[0], [v[1], v[2], v[3]])
                    .ok_or_else(|| Error::new(&loc, "Rotate: the rotation axis is zero"))?;
                self.gs.apply(|t| t * r);
            }
            Directive::Sampler(name, params) => {
                self.options_only("Sampler", &loc)?;
                self.scene.sampler = self.gs.entity(name, params, &[], loc);
            }
            Directive::Scale(s) => self.gs.apply(|t| t * transform::scale(s)),
            Directive::Shape(name, params) => self.shape(name, params, loc)?,
            Directive::Texture { name, value_type, class, params } => {
                self.world_only("Texture", &loc)?;
                let (value, names) = match value_type.as_str() {
                    "float" => (TextureValue::Float, &mut self.float_texture_names),
                    "spectrum" => (TextureValue::Spectrum, &mut self.spectrum_texture_names),
                    _ => {
                        return Err(Error::new(
                            &loc,
                            format!("texture type \"{value_type}\" unknown: must be \"float\" or \"spectrum\""),
                        ));
                    }
                };
                if !names.insert(name.clone()) {
                    return Err(Error::new(&loc, format!("texture \"{name}\" redefined")));
                }
                let entity = self.gs.entity(class, params, &self.gs.texture_attributes, loc);
                self.scene.textures.push(TextureEntity {
                    name,
                    value,
                    entity,
                    world_from_texture: self.gs.transform(),
                });
            }
            Directive::Transform(m) => self.gs.apply(|_| transform::from_pbrt_array(&m)),
            Directive::TransformTimes(start, end) => {
                self.options_only("TransformTimes", &loc)?;
                self.gs.start_time = start;
                self.gs.end_time = end;
            }
            Directive::Translate(d) => self.gs.apply(|t| t * transform::translate(d)),
            Directive::WorldBegin => {
                self.options_only("WorldBegin", &loc)?;
                self.block = Block::World;
                self.gs.ctm = [DMat4::IDENTITY; 2];
                self.gs.active = ActiveTransform::All;
                self.named_coordinate_systems.insert("world".into(), self.gs.ctm);
            }
        }
        Ok(())
    }

    fn file_read(&mut self, name: &str) {
        self.scene.files.push(name.to_string());
    }

    fn import_begin(&mut self, loc: &FileLoc) -> Result<()> {
        self.world_only("Import", loc)?;
        self.imports.push((self.gs.clone(), self.pushed.len(), self.named_coordinate_systems.clone()));
        Ok(())
    }

    fn import_end(&mut self, loc: &FileLoc) -> Result<()> {
        let (gs, depth, names) = self.imports.pop().expect("import_end follows import_begin");
        if self.pushed.len() != depth {
            let (_, _, open) = self.pushed.last().expect("deeper than at import");
            return Err(Error::new(
                open,
                format!("AttributeBegin has no matching AttributeEnd in the file imported at {loc}"),
            ));
        }
        self.gs = gs;
        self.named_coordinate_systems = names;
        Ok(())
    }
}
