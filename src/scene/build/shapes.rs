//! Shapes of a scene: meshes, curves and analytic shapes, with their materials and media.

use super::*;

/// A shape's boundary index from its `MediumInterface` and its material.
pub(super) type InterfaceIds<'a> = dyn Fn(Option<&nimbus_parser::MediumInterface>, u32) -> Result<u32, Error> + 'a;

pub(super) struct ShapeBuilder<'a> {
    pub(super) store: ShapeStore,
    pub(super) textures: &'a TextureBuilder<'a>,
    pub(super) alphas: Vec<Tex>,
    pub(super) spectra: SpectrumResolver<'a>,
    pub(super) material_ids: &'a dyn Fn(&MaterialRef) -> u32,
    pub(super) interface_ids: &'a InterfaceIds<'a>,
    pub(super) lights: Vec<Light>,
    pub(super) triangles: usize,
    pub(super) mesh_bytes: usize,
    /// The render's transport is RGB (emission images are converted to film RGB once).
    pub(super) rgb_transport: bool,
}

impl ShapeBuilder<'_> {
    /// Adds a shape's primitives (and their area lights) to `prims`/`bounds`.
    pub(super) fn add(
        &mut self,
        shape: &ShapeEntity,
        area_lights: &[nimbus_parser::Entity],
        instanced: bool,
        world: Affine3A,
        prims: &mut Vec<Primitive>,
        bounds: &mut Vec<Bounds3>,
    ) -> Result<(), Error> {
        let e = &shape.entity;
        let settings = ShapeSettings::from_entity(shape)?;
        let shape_settings = &settings;
        let rev = shape.reverse_orientation;
        let material = (self.material_ids)(&shape.material);
        let interface = (self.interface_ids)(shape.medium_interface.as_ref(), material)?;
        // pbrt-v4 alpha-tests a shape whose "alpha" is a texture or a constant below 1.
        let alpha = match &settings.alpha {
            FloatInput::Value(a) if *a >= 1.0 => NONE,
            a => {
                self.alphas.push(self.textures.float(a, &e.loc)?);
                self.alphas.len() as u32 - 1
            }
        };
        let first = prims.len();
        let mut push = |g: Geometry, store: &ShapeStore| {
            bounds.push(store.bounds(g));
            prims.push(Primitive { geometry: g, material, area_light: NONE, interface, alpha });
        };
        match &settings.kind {
            ShapeKind::Sphere { radius, zmin, zmax, phimax } => {
                self.store.spheres.push(Sphere::new(world, rev, *radius, *zmin, *zmax, *phimax));
                push(Geometry::Sphere(self.store.spheres.len() as u32 - 1), &self.store);
            }
            ShapeKind::Disk { height, radius, inner_radius, phimax } => {
                self.store.disks.push(Disk::new(world, rev, *height, *radius, *inner_radius, *phimax));
                push(Geometry::Disk(self.store.disks.len() as u32 - 1), &self.store);
            }
            ShapeKind::Cylinder { radius, zmin, zmax, phimax } => {
                self.store.cylinders.push(Cylinder::new(world, rev, *radius, *zmin, *zmax, *phimax));
                push(Geometry::Cylinder(self.store.cylinders.len() as u32 - 1), &self.store);
            }
            ShapeKind::TriangleMesh(m) => {
                let mesh = Mesh::new(&world, rev, m.positions, m.normals, m.uvs, m.indices.clone())
                    .with_face_indices(m.face_indices.clone());
                self.add_mesh(mesh, [material, interface, alpha], prims, bounds);
            }
            ShapeKind::BilinearMesh(m) => {
                let mesh = BilinearMesh::new(&world, rev, m.positions, m.normals, m.uvs, m.indices.clone())
                    .with_face_indices(m.face_indices.clone());
                self.add_bilinear(mesh, [material, interface, alpha], prims, bounds);
            }
            ShapeKind::Curve { segments, widths, normals, kind, split_depth } => {
                if shape.area_light.is_some() {
                    return Err(err(&e.loc, "curves cannot be area lights (pbrt-v4 cannot sample them either)"));
                }
                let pieces = 1u32 << split_depth;
                for (k, (cp, w)) in segments.iter().zip(widths).enumerate() {
                    let n = normals.get(k).map(|n| n.map(Vec3::from));
                    let common = self.store.curve_segments.len() as u32;
                    self.store.curve_segments.push(CurveCommon::new(cp.map(Vec3::from), *w, *kind, n, world, rev));
                    for i in 0..pieces {
                        let (u0, u1) = (i as f32 / pieces as f32, (i + 1) as f32 / pieces as f32);
                        self.store.curves.push(Curve::new(common, u0, u1));
                        push(Geometry::Curve(self.store.curves.len() as u32 - 1), &self.store);
                    }
                }
            }
            ShapeKind::LoopSubdiv { mesh: m, levels } => {
                let sub = crate::geometry::loop_subdiv::loop_subdivide(m.positions, &m.indices, *levels)
                    .map_err(|m| err(&e.loc, format!("loopsubdiv: {m}")))?;
                let mesh = Mesh::new(&world, rev, &sub.positions, &sub.normals, &[], sub.indices);
                self.add_mesh(mesh, [material, interface, alpha], prims, bounds);
            }
            ShapeKind::PlyMesh(path, displacement) => {
                let mut ply = read_ply(path).map_err(|m| err(&e.loc, format!("plymesh: {m}")))?;
                if let Some((name, edge)) = displacement {
                    // pbrt-v4 evaluates the texture at the mesh's own (p, uv), nothing else.
                    let tex = self.textures.float(&FloatInput::Texture(name.clone()), &e.loc)?;
                    let textures = &self.textures.textures;
                    ply = crate::geometry::displace::displace(&ply, &world, *edge, |p, uv| {
                        textures.eval_float(tex, &TexContext::at(p, uv, Vec3::ZERO))
                    })
                    .map_err(|m| err(&e.loc, format!("plymesh \"{}\": {m}", path.display())))?;
                }
                if !ply.quads.is_empty() {
                    let quads = BilinearMesh::new(&world, rev, &ply.positions, &ply.normals, &ply.uvs, ply.quads)
                        .with_face_indices(ply.quad_faces);
                    self.add_bilinear(quads, [material, interface, alpha], prims, bounds);
                }
                if !ply.indices.is_empty() {
                    let mesh = Mesh::new(&world, rev, &ply.positions, &ply.normals, &ply.uvs, ply.indices)
                        .with_face_indices(ply.triangle_faces);
                    self.add_mesh(mesh, [material, interface, alpha], prims, bounds);
                }
            }
            ShapeKind::ObjMesh(path) | ShapeKind::GltfMesh(path) => {
                let meshes = if matches!(settings.kind, ShapeKind::ObjMesh(_)) {
                    crate::geometry::obj::read_obj(path)
                } else {
                    crate::geometry::gltf::read_gltf(path)
                }
                .map_err(|m| err(&e.loc, m))?;
                for m in meshes {
                    let mesh = Mesh::new(&world, rev, &m.positions, &m.normals, &m.uvs, m.indices);
                    self.add_mesh(mesh, [material, interface, alpha], prims, bounds);
                }
            }
        }
        if let Some(al) = shape.area_light {
            if instanced {
                return Ok(());
            }
            let al_entity = &area_lights[al];
            let settings = AreaLightSettings::from_entity(al_entity)?;
            let image = emission_image(&settings, al_entity, &self.spectra, self.rgb_transport)?;
            // pbrt-v4's invisible area light: a shape of constant alpha 0 is never hit, but its
            // light drops the alpha and emits everywhere (DiffuseAreaLight's constructor).
            let invisible = self.alpha_is_zero(&shape_settings.alpha);
            for prim in &mut prims[first..] {
                let area = match prim.geometry {
                    Geometry::Triangle { mesh, tri } => self.store.meshes[mesh as usize].triangle_area(tri),
                    Geometry::Sphere(i) => {
                        let s = &self.store.spheres[i as usize];
                        let scale = uniform_scale(&world)
                            .ok_or_else(|| err(&e.loc, "an emitting sphere must not be scaled non-uniformly"))?;
                        s.area() * scale * scale
                    }
                    Geometry::Disk(i) => self.store.disks[i as usize]
                        .world_area()
                        .ok_or_else(|| err(&e.loc, "an emitting disk must not be scaled non-uniformly"))?,
                    Geometry::Cylinder(i) => self.store.cylinders[i as usize]
                        .world_area()
                        .ok_or_else(|| err(&e.loc, "an emitting cylinder must not be scaled non-uniformly"))?,
                    Geometry::Bilinear { mesh, patch } => self.store.bilinear_meshes[mesh as usize].area(patch),
                    Geometry::Curve(_) | Geometry::Instance(_) | Geometry::Hull(_) => continue,
                };
                let l = area_light_radiance(&settings, image.as_deref(), al_entity, area, &self.spectra)?;
                prim.area_light = self.lights.len() as u32;
                self.lights.push(Light {
                    kind: LightKind::Area {
                        geometry: prim.geometry,
                        l,
                        image: image.clone(),
                        two_sided: settings.two_sided,
                        area,
                        interface: prim.interface,
                        alpha: if invisible { NONE } else { prim.alpha },
                        invisible,
                    },
                    medium: NONE,
                });
            }
        }
        Ok(())
    }

    /// Whether a shape's alpha is the constant 0 (a value, or a `constant` texture of 0), the
    /// case pbrt-v4 turns into an invisible light.
    fn alpha_is_zero(&self, alpha: &FloatInput) -> bool {
        match alpha {
            FloatInput::Value(a) => *a == 0.0,
            FloatInput::Texture(name) => self.textures.constant_float(name) == Some(0.0),
        }
    }

    pub(super) fn add_bilinear(
        &mut self,
        mesh: BilinearMesh,
        attrs: [u32; 3],
        prims: &mut Vec<Primitive>,
        bounds: &mut Vec<Bounds3>,
    ) {
        let id = self.store.bilinear_meshes.len() as u32;
        self.mesh_bytes += mesh_bytes(mesh.positions.len(), mesh.normals.len(), mesh.uvs.len(), mesh.indices.len());
        let piece = |patch| (Geometry::Bilinear { mesh: id, patch }, mesh.bounds(patch));
        push_pieces(mesh.patch_count(), piece, attrs, prims, bounds);
        self.store.bilinear_meshes.push(mesh);
    }

    pub(super) fn add_mesh(
        &mut self,
        mesh: Mesh,
        attrs: [u32; 3],
        prims: &mut Vec<Primitive>,
        bounds: &mut Vec<Bounds3>,
    ) {
        let id = self.store.meshes.len() as u32;
        self.triangles += mesh.triangle_count();
        self.mesh_bytes += mesh_bytes(mesh.positions.len(), mesh.normals.len(), mesh.uvs.len(), mesh.indices.len());
        let piece = |tri| (Geometry::Triangle { mesh: id, tri }, mesh.triangle_bounds(tri));
        push_pieces(mesh.triangle_count(), piece, attrs, prims, bounds);
        self.store.meshes.push(mesh);
    }
}

/// Bytes of a mesh's vertex arrays (positions, normals, uvs) and indices.
pub(super) fn mesh_bytes(positions: usize, normals: usize, uvs: usize, indices: usize) -> usize {
    positions * 12 + normals * 12 + uvs * 8 + indices * 4
}

/// Adds `n` primitives of one mesh, piece k's geometry and bounds from `piece(k)`, all with
/// the shape's [material, interface, alpha].
pub(super) fn push_pieces(
    n: usize,
    piece: impl Fn(u32) -> (Geometry, Bounds3),
    [material, interface, alpha]: [u32; 3],
    prims: &mut Vec<Primitive>,
    bounds: &mut Vec<Bounds3>,
) {
    for k in 0..n as u32 {
        let (geometry, b) = piece(k);
        bounds.push(b);
        prims.push(Primitive { geometry, material, area_light: NONE, interface, alpha });
    }
}

/// The scene's surfaces placed: the top-level BVH over shapes and instances, the BVHs of
/// moving shapes and object definitions, and the instances that place them.
pub(super) struct Placed {
    pub(super) top: Option<Accel>,
    pub(super) blas: Vec<Accel>,
    pub(super) instances: Vec<Instance>,
    pub(super) primitives: usize,
    /// The closed convex meshes among the top-level shapes, each one primitive of `top`.
    pub(super) hulls: Hulls,
}

impl ShapeBuilder<'_> {
    /// Builds every shape, object definition and instance of `desc`: fixed shapes into the
    /// top level, each moving shape as a BVH of its own placed by its motion at each ray's
    /// time (pbrt-v4's AnimatedPrimitive), each object definition once.
    pub(super) fn place_all(&mut self, desc: &SceneDescription) -> Result<Placed, Error> {
        let mut prims = Vec::new();
        let mut bounds = Vec::new();
        let mut blas = Vec::new();
        let mut instances = Vec::new();
        for shape in &desc.shapes {
            let t = &shape.world_from_object;
            if !t.is_animated() {
                self.add(
                    shape,
                    &desc.area_lights,
                    false,
                    affine(&t.start, &shape.entity.loc)?,
                    &mut prims,
                    &mut bounds,
                )?;
                continue;
            }
            // A moving shape: built in its own space as a BVH of its own, placed by its motion at
            // each ray's time (pbrt-v4's AnimatedPrimitive).
            if shape.area_light.is_some() {
                return Err(err(&shape.entity.loc, "animated area lights are not supported (nor are they by pbrt-v4)"));
            }
            let motion = motion_transform(t, &shape.entity.loc)?;
            let (mut p, mut b) = (Vec::new(), Vec::new());
            self.add(shape, &desc.area_lights, false, Affine3A::IDENTITY, &mut p, &mut b)?;
            if let Some(accel) = Accel::build(p, b) {
                bounds.push(motion.bounds(&accel.bounds()));
                blas.push(accel);
                instances.push(Instance::moving(blas.len() as u32 - 1, motion));
                prims.push(Primitive::instance(instances.len() as u32 - 1));
            }
        }
        let mut blas_of: HashMap<&str, Option<u32>> = HashMap::new();
        for def in &desc.instance_definitions {
            let mut p = Vec::new();
            let mut b = Vec::new();
            for shape in &def.shapes {
                let world = fixed_transform(&shape.world_from_object, &shape.entity.loc, "a shape inside ObjectBegin")?;
                self.add(shape, &desc.area_lights, true, world, &mut p, &mut b)?;
            }
            let accel = Accel::build(p, b);
            blas_of.insert(def.name.as_str(), accel.as_ref().map(|_| blas.len() as u32));
            if let Some(a) = accel {
                blas.push(a);
            }
        }
        for u in &desc.instances {
            let Some(Some(accel)) = blas_of.get(u.name.as_str()).copied() else {
                continue;
            };
            let object_bounds = blas[accel as usize].bounds();
            let t = &u.world_from_instance;
            if t.is_animated() {
                let motion = motion_transform(t, &u.loc)?;
                bounds.push(motion.bounds(&object_bounds));
                instances.push(Instance::moving(accel, motion));
            } else {
                let world = affine(&t.start, &u.loc)?;
                bounds.push(object_bounds.transformed(&world));
                instances.push(Instance::fixed(accel, world));
            }
            prims.push(Primitive::instance(instances.len() as u32 - 1));
        }
        let primitives = prims.len();
        let mut hulls = gather_hulls(&mut prims, &mut bounds, &self.store.meshes);
        hulls.spheres = lone_spheres(&prims, &bounds, &self.store.spheres);
        Ok(Placed { top: Accel::build(prims, bounds), blas, instances, primitives, hulls })
    }
}
