//! Ray queries over the scene's surfaces: a compressed wide BVH (obvhs's CWBVH) over
//! primitives, with object instances as BVHs of their own.

mod build;
mod hull;
mod tie;

pub use hull::{Hulls, gather_hulls, lone_spheres};

use glam::{Affine3A, Vec2, Vec3, Vec3A};
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray as BvhRay, RayHit};

use crate::geometry::{Bounds3, MotionTransform, Ray};
use crate::shapes::{
    BilinearMesh, Curve, CurveCommon, Cylinder, Disk, Mesh, Sphere, SurfaceDerivatives, SurfaceHit, barycentrics,
    transform_normal, triangle_derivatives, triangle_hit,
};
use crate::textures::{Tex, TexContext, Textures};
use tie::{slack, tie};

/// Marks an absent index (no area light, no medium interface, not instanced).
pub const NONE: u32 = u32::MAX;

/// What a primitive is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Geometry {
    /// Triangle `tri` of mesh `mesh`.
    Triangle {
        /// Mesh index.
        mesh: u32,
        /// Triangle index within the mesh.
        tri: u32,
    },
    /// A sphere.
    Sphere(u32),
    /// A disk.
    Disk(u32),
    /// A cylinder.
    Cylinder(u32),
    /// A piece of a curve.
    Curve(u32),
    /// Patch `patch` of bilinear mesh `mesh`.
    Bilinear {
        /// Bilinear mesh index.
        mesh: u32,
        /// Patch index within the mesh.
        patch: u32,
    },
    /// An object instance (only in the top-level BVH).
    Instance(u32),
    /// A closed convex mesh's triangles, as one primitive of the top-level BVH (`hull.rs`);
    /// hits name the triangle.
    Hull(u32),
}

/// A piece of geometry with what is attached to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Primitive {
    /// The geometry.
    pub geometry: Geometry,
    /// Material index.
    pub material: u32,
    /// Area light index or [`NONE`].
    pub area_light: u32,
    /// Medium interface index or [`NONE`] (not a boundary between media).
    pub interface: u32,
    /// Index of the shape's alpha texture in [`Surfaces::alphas`], or [`NONE`] (opaque).
    pub alpha: u32,
}

impl Primitive {
    /// The top-level primitive of instance `k` (its BVH's primitives carry the attachments).
    pub fn instance(k: u32) -> Primitive {
        Primitive { geometry: Geometry::Instance(k), material: 0, area_light: NONE, interface: NONE, alpha: NONE }
    }
}

/// All shapes, referenced by index from primitives.
#[derive(Default)]
pub struct ShapeStore {
    /// Triangle meshes (world space, or instance space for instanced ones).
    pub meshes: Vec<Mesh>,
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// Disks.
    pub disks: Vec<Disk>,
    /// Cylinders.
    pub cylinders: Vec<Cylinder>,
    /// Curve pieces.
    pub curves: Vec<Curve>,
    /// What the pieces of each curve segment share.
    pub curve_segments: Vec<CurveCommon>,
    /// Bilinear patch meshes (world space, or instance space for instanced ones).
    pub bilinear_meshes: Vec<BilinearMesh>,
}

impl ShapeStore {
    /// Primitive `g`'s Ptex face id (pbrt-v4's `faceIndex`: the mesh's `faceIndices` entry,
    /// else 0).
    #[inline]
    pub fn face_index(&self, g: Geometry) -> i32 {
        match g {
            Geometry::Triangle { mesh, tri } => self.meshes[mesh as usize].face_index(tri),
            Geometry::Bilinear { mesh, patch } => self.bilinear_meshes[mesh as usize].face_index(patch),
            _ => 0,
        }
    }

    /// Texture coordinates of the point `p` of primitive `g` (a point on it, e.g. a light
    /// sample), with `from` a point it is seen from (for bilinear patches, whose parameters
    /// are found along the ray between them); `None` where they cannot be found.
    pub fn uv_at(&self, g: Geometry, p: Vec3, from: Vec3) -> Option<Vec2> {
        Some(match g {
            Geometry::Sphere(i) => self.spheres[i as usize].uv_at(p),
            Geometry::Disk(i) => self.disks[i as usize].uv_at(p),
            Geometry::Cylinder(i) => self.cylinders[i as usize].uv_at(p),
            Geometry::Triangle { mesh, tri } => {
                let m = &self.meshes[mesh as usize];
                let (b1, b2) = barycentrics(m.vertices(tri), p)?;
                triangle_hit(m, tri, 0.0, b1, b2).uv
            }
            Geometry::Bilinear { mesh, patch } => {
                let m = &self.bilinear_meshes[mesh as usize];
                let d = p - from;
                let (u, v) = m.param(patch, &Ray::new(from, d.normalize_or_zero()))?;
                m.hit(patch, 0.0, u, v).uv
            }
            Geometry::Curve(_) | Geometry::Instance(_) | Geometry::Hull(_) => return None,
        })
    }

    // Kept out of line: curves are rare and their intersection is long, and inlining it would
    // keep the triangle test out of the traversal loop.
    #[inline(never)]
    fn curve_hit(&self, i: u32, ray: &Ray, t_max: f32) -> Option<(f32, Detail)> {
        let c = &self.curves[i as usize];
        c.intersect(&self.curve_segments[c.common as usize], ray, t_max).map(|(t, _)| (t, Detail::Curve))
    }

    // Out of line like curves: patches are rarer than triangles and their test longer.
    #[inline(never)]
    fn patch_hit(&self, mesh: u32, patch: u32, ray: &Ray, t_max: f32) -> Option<(f32, Detail)> {
        self.bilinear_meshes[mesh as usize].intersect(patch, ray, t_max).map(|(t, u, v)| (t, Detail::Patch(u, v)))
    }

    /// Where a non-instance primitive is hit, for the alpha test.
    #[inline(never)]
    fn detail(&self, g: Geometry, ray: &Ray, t_max: f32) -> Option<(f32, Detail)> {
        match g {
            Geometry::Triangle { mesh, tri } => self.meshes[mesh as usize]
                .intersect(tri, ray, t_max)
                .map(|(t, b1, b2)| (t, Detail::Barycentric(b1, b2))),
            Geometry::Sphere(i) => {
                self.spheres[i as usize].intersect(ray, t_max).map(|(t, p)| (t, Detail::ObjectPoint(p)))
            }
            Geometry::Disk(i) => self.disks[i as usize].intersect(ray, t_max).map(|(t, p)| (t, Detail::ObjectPoint(p))),
            Geometry::Cylinder(i) => {
                self.cylinders[i as usize].intersect(ray, t_max).map(|(t, p)| (t, Detail::ObjectPoint(p)))
            }
            Geometry::Curve(i) => self.curve_hit(i, ray, t_max),
            Geometry::Bilinear { mesh, patch } => self.patch_hit(mesh, patch, ray, t_max),
            Geometry::Instance(_) | Geometry::Hull(_) => None,
        }
    }

    /// Bounds of a non-instance geometry.
    pub fn bounds(&self, g: Geometry) -> Bounds3 {
        match g {
            Geometry::Triangle { mesh, tri } => self.meshes[mesh as usize].triangle_bounds(tri),
            Geometry::Sphere(i) => self.spheres[i as usize].bounds(),
            Geometry::Disk(i) => self.disks[i as usize].bounds(),
            Geometry::Cylinder(i) => self.cylinders[i as usize].bounds(),
            Geometry::Curve(i) => {
                let c = &self.curves[i as usize];
                c.bounds(&self.curve_segments[c.common as usize])
            }
            Geometry::Bilinear { mesh, patch } => self.bilinear_meshes[mesh as usize].bounds(patch),
            Geometry::Instance(_) | Geometry::Hull(_) => Bounds3::EMPTY,
        }
    }
}

/// Where along a ray a primitive was hit, before computing surface details.
#[derive(Clone, Copy, Debug)]
enum Detail {
    Barycentric(f32, f32),
    ObjectPoint(Vec3),
    /// A curve piece: its details are recomputed for the closest hit only, which keeps
    /// candidates small for every other shape's traversal.
    Curve,
    /// Bilinear patch parameters (u, v).
    Patch(f32, f32),
    /// The face (of the hull the primitive is) through which a ray from inside leaves; its
    /// triangle is found only if the hit is resolved.
    HullExit(u32),
}

#[derive(Clone, Copy, Debug)]
struct Candidate {
    t: f32,
    prim: Primitive,
    instance: u32,
    detail: Detail,
}

/// The BVH library's ray. Negative zeros in the direction become positive: obvhs picks the
/// traversal octant from the sign bits and its slab test misses with -0.0 components.
#[inline]
fn bvh_ray(ray: &Ray, t_max: f32) -> BvhRay {
    BvhRay::new(Vec3A::from(ray.o), Vec3A::from(ray.d) + Vec3A::ZERO, 0.0, t_max)
}

/// pbrt-v4's stochastic alpha test: a hit where alpha < 1 counts when a uniform number hashed
/// from the ray is at most alpha (never when alpha ≤ 0). pbrt-v4 hashes the ray, then retraces
/// from the skipped hit, so the surfaces behind get their own numbers; nimbus tests every
/// candidate of one traversal, so it hashes the hit distance in as well.
#[inline]
fn alpha_passes(alpha: f32, ray: &Ray, t: f32) -> bool {
    if alpha >= 1.0 {
        return true;
    }
    if alpha <= 0.0 {
        return false;
    }
    let mut bytes = [0u8; 28];
    for (i, v) in [ray.o.x, ray.o.y, ray.o.z, ray.d.x, ray.d.y, ray.d.z, t].iter().enumerate() {
        bytes[4 * i..4 * i + 4].copy_from_slice(&v.to_le_bytes());
    }
    let u = (crate::sampling::rng::murmur_hash64a(&bytes, 0) as u32) as f32 * (1.0 / 4_294_967_296.0);
    u <= alpha
}

/// A BVH over primitives (stored in BVH leaf order), or over parts that are BVHs of their own
/// over consecutive primitives (a large set built a part at a time: `build.rs`).
pub struct Accel {
    bvh: CwBvh,
    prims: Vec<Primitive>,
    /// Empty, or the parts the top BVH's leaves name.
    parts: Vec<Part>,
    bounds: Bounds3,
}

/// A BVH over `prims[start..]` (leaf positions count from `start`).
struct Part {
    bvh: CwBvh,
    start: u32,
}

/// Up to this many primitives are tested one by one, without the BVH: on the Disney cloud
/// (a bounding sphere and the ground) traversing their BVH took as long as the tests. Not
/// more: grid-cloud's 14 triangles tested one by one rendered 20–50 % slower.
const DIRECT: usize = 4;

impl Accel {
    /// World bounds of everything in the BVH.
    pub fn bounds(&self) -> Bounds3 {
        self.bounds
    }

    /// The primitives, in BVH leaf order.
    pub fn primitives(&self) -> &[Primitive] {
        &self.prims
    }

    fn closest(&self, scene: &Surfaces, ray: &Ray, t_max: f32, instance: u32, best: &mut Option<Candidate>) {
        if self.prims.len() <= DIRECT {
            let mut t_max = t_max;
            for &prim in &self.prims {
                t_max = t_max.min(self.test_closest(prim, scene, ray, t_max, instance, best));
            }
            return;
        }
        if self.parts.is_empty() {
            return self.closest_in(&self.bvh, 0, scene, ray, t_max, instance, best);
        }
        let mut hit = RayHit::none();
        self.bvh.ray_traverse(bvh_ray(ray, t_max), &mut hit, |r, id| {
            let part = &self.parts[id];
            self.closest_in(&part.bvh, part.start as usize, scene, ray, r.tmax, instance, best);
            best.map_or(f32::INFINITY, |b| slack(b.t))
        });
    }

    /// The closest hit among the primitives of `bvh`, whose leaf positions count from `start`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn closest_in(
        &self,
        bvh: &CwBvh,
        start: usize,
        scene: &Surfaces,
        ray: &Ray,
        t_max: f32,
        instance: u32,
        best: &mut Option<Candidate>,
    ) {
        let mut hit = RayHit::none();
        bvh.ray_traverse(bvh_ray(ray, t_max), &mut hit, |r, id| {
            self.test_closest(self.prims[start + id], scene, ray, r.tmax, instance, best)
        });
    }

    /// Tests `prim` for a hit closer than `best` before `t_max`; returns the distance to
    /// traverse up to from now on (infinity: unchanged).
    #[inline(always)]
    fn test_closest(
        &self,
        mut prim: Primitive,
        scene: &Surfaces,
        ray: &Ray,
        t_max: f32,
        instance: u32,
        best: &mut Option<Candidate>,
    ) -> f32 {
        let found = match prim.geometry {
            Geometry::Triangle { mesh, tri } => scene.shapes.meshes[mesh as usize]
                .intersect(tri, ray, t_max)
                .map(|(t, b1, b2)| (t, Detail::Barycentric(b1, b2))),
            Geometry::Sphere(i) => {
                scene.shapes.spheres[i as usize].intersect(ray, t_max).map(|(t, p)| (t, Detail::ObjectPoint(p)))
            }
            Geometry::Disk(i) => {
                scene.shapes.disks[i as usize].intersect(ray, t_max).map(|(t, p)| (t, Detail::ObjectPoint(p)))
            }
            Geometry::Cylinder(i) => {
                scene.shapes.cylinders[i as usize].intersect(ray, t_max).map(|(t, p)| (t, Detail::ObjectPoint(p)))
            }
            Geometry::Curve(i) => scene.shapes.curve_hit(i, ray, t_max),
            Geometry::Bilinear { mesh, patch } => scene.shapes.patch_hit(mesh, patch, ray, t_max),
            Geometry::Instance(k) => {
                let inst = &scene.instances[k as usize];
                let local = inst.local_ray(ray);
                let before = best.map(|c| c.t);
                scene.blas[inst.accel as usize].closest(scene, &local, t_max, k, best);
                let after = best.map(|c| c.t);
                return match after {
                    Some(t) if after != before => t,
                    _ => f32::INFINITY,
                };
            }
            Geometry::Hull(k) => scene.hulls.all[k as usize].closest(ray, t_max).map(|(tri, t, b1, b2)| {
                prim = tri;
                (t, Detail::Barycentric(b1, b2))
            }),
        };
        // Coplanar pass-through (`interface`) and opaque surfaces — a medium's box sitting on
        // a ground plane — tie. pbrt-v4 resolves such ties by floating-point rounding, which
        // `tie::pass_through_wins` reproduces. Hits are reported to the BVH slightly
        // long so that a coplanar partner is still visited.
        let Some((t, detail)) = found else {
            return f32::INFINITY;
        };
        if prim.alpha != NONE && !scene.alpha_passes(prim, instance, detail, ray, t) {
            return f32::INFINITY;
        }
        match *best {
            Some(b) if tie(t, b.t) => {
                let (new_pass, old_pass) = (scene.is_pass_through(prim), scene.is_pass_through(b.prim));
                if new_pass != old_pass
                    && tie::pass_through_wins(scene, ray, instance, b.prim, prim, new_pass) == new_pass
                {
                    *best = Some(Candidate { t: b.t, prim, instance, detail });
                }
                slack(b.t)
            }
            Some(b) if t >= b.t => f32::INFINITY,
            _ => {
                *best = Some(Candidate { t, prim, instance, detail });
                slack(t)
            }
        }
    }

    fn any(&self, scene: &Surfaces, ray: &Ray, t_max: f32, instance: u32) -> bool {
        if self.prims.len() <= DIRECT {
            return self.prims.iter().any(|&prim| self.test_any(prim, scene, ray, t_max, instance));
        }
        if self.parts.is_empty() {
            return self.any_in(&self.bvh, 0, scene, ray, t_max, instance);
        }
        !self.bvh.ray_traverse_miss(bvh_ray(ray, t_max), |r, id| {
            let part = &self.parts[id];
            if self.any_in(&part.bvh, part.start as usize, scene, ray, r.tmax, instance) { 0.0 } else { f32::INFINITY }
        })
    }

    /// True when a primitive of `bvh` (leaf positions counting from `start`) blocks the ray.
    #[inline(always)]
    fn any_in(&self, bvh: &CwBvh, start: usize, scene: &Surfaces, ray: &Ray, t_max: f32, instance: u32) -> bool {
        !bvh.ray_traverse_miss(bvh_ray(ray, t_max), |r, id| {
            if self.test_any(self.prims[start + id], scene, ray, r.tmax, instance) { 0.0 } else { f32::INFINITY }
        })
    }

    /// True when `prim` blocks the ray before `t_max`.
    #[inline(always)]
    fn test_any(&self, prim: Primitive, scene: &Surfaces, ray: &Ray, t_max: f32, instance: u32) -> bool {
        if prim.alpha != NONE {
            // Alpha-tested shapes need the hit to test.
            return match scene.shapes.detail(prim.geometry, ray, t_max) {
                Some((t, detail)) => scene.alpha_passes(prim, instance, detail, ray, t),
                None => false,
            };
        }
        match prim.geometry {
            Geometry::Triangle { mesh, tri } => scene.shapes.meshes[mesh as usize].intersect(tri, ray, t_max).is_some(),
            Geometry::Sphere(i) => scene.shapes.spheres[i as usize].intersect(ray, t_max).is_some(),
            Geometry::Disk(i) => scene.shapes.disks[i as usize].intersect(ray, t_max).is_some(),
            Geometry::Cylinder(i) => scene.shapes.cylinders[i as usize].intersect(ray, t_max).is_some(),
            Geometry::Curve(i) => scene.shapes.curve_hit(i, ray, t_max).is_some(),
            Geometry::Bilinear { mesh, patch } => scene.shapes.patch_hit(mesh, patch, ray, t_max).is_some(),
            Geometry::Instance(k) => {
                let inst = &scene.instances[k as usize];
                let local = inst.local_ray(ray);
                scene.blas[inst.accel as usize].any(scene, &local, t_max, k)
            }
            Geometry::Hull(k) => scene.hulls.all[k as usize].closest(ray, t_max).is_some(),
        }
    }
}

/// One placement of an object definition, or a moving shape (pbrt-v4's `AnimatedPrimitive`:
/// a shape under an animated transform is a BVH of its own placed by that motion).
pub struct Instance {
    /// Index of the object's BVH in [`Surfaces::blas`].
    pub accel: u32,
    /// World-from-instance (at the start of the motion for moving ones).
    pub world_from_instance: Affine3A,
    /// Instance-from-world (likewise).
    pub instance_from_world: Affine3A,
    /// The motion over the shutter interval, for moving placements.
    pub motion: Option<Box<MotionTransform>>,
}

impl Instance {
    /// A placement that does not move.
    pub fn fixed(accel: u32, world_from_instance: Affine3A) -> Instance {
        Instance { accel, world_from_instance, instance_from_world: world_from_instance.inverse(), motion: None }
    }

    /// A placement moving with `motion`.
    pub fn moving(accel: u32, motion: MotionTransform) -> Instance {
        let w = motion.start();
        Instance { accel, world_from_instance: w, instance_from_world: w.inverse(), motion: Some(Box::new(motion)) }
    }

    /// (world-from-instance, instance-from-world) at `time`.
    #[inline]
    pub fn transforms_at(&self, time: f32) -> (Affine3A, Affine3A) {
        match &self.motion {
            None => (self.world_from_instance, self.instance_from_world),
            Some(m) => {
                let w = m.at(time);
                (w, w.inverse())
            }
        }
    }

    /// A world-space ray in the instance's space.
    #[inline]
    fn local_ray(&self, ray: &Ray) -> Ray {
        let (_, f) = self.transforms_at(ray.time);
        Ray::timed(f.transform_point3(ray.o), f.transform_vector3(ray.d), ray.time)
    }
}

/// The closest hit along a ray before its geometry is computed: its distance is all that
/// delta tracking needs, and most segments through a dense medium end before it (on the
/// Disney cloud the sphere's uv, normal and frame at boundary hits were 5 % of the time).
#[derive(Clone, Copy, Debug)]
pub struct Found {
    c: Candidate,
    ray: Ray,
}

impl Found {
    /// Distance along the ray.
    #[inline]
    pub fn t(&self) -> f32 {
        self.c.t
    }

    /// The primitive hit.
    #[inline]
    pub fn prim(&self) -> Primitive {
        self.c.prim
    }
}

/// A surface hit: geometry plus the primitive's attachments.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// World-space geometry.
    pub surface: SurfaceHit,
    /// The primitive hit.
    pub prim: Primitive,
    /// The instance it belongs to, or [`NONE`].
    pub instance: u32,
    /// The time of the ray that found it.
    pub time: f32,
}

impl Hit {
    /// A ray leaving the hit in direction `d`, offset off the surface, at the hit's time.
    #[inline]
    pub fn spawn_ray(&self, d: Vec3) -> Ray {
        Ray { time: self.time, ..self.surface.spawn_ray(d) }
    }
}

/// Every surface in the scene and the BVHs over them. A scene without surfaces has no BVH.
#[derive(Default)]
pub struct Surfaces {
    /// Shape data.
    pub shapes: ShapeStore,
    /// The top-level BVH (primitives and instances), if there are any surfaces.
    pub top: Option<Accel>,
    /// One BVH per object definition.
    pub blas: Vec<Accel>,
    /// Object placements.
    pub instances: Vec<Instance>,
    /// Per material index: true for surfaces rays pass through (`interface`).
    pub pass_through: Vec<bool>,
    /// Alpha textures of alpha-tested shapes (float), indexed by [`Primitive::alpha`].
    pub alphas: Vec<Tex>,
    /// The scene's textures, for the alpha test.
    pub textures: Textures,
    /// Closed convex meshes the top-level BVH holds as one primitive each, and the convex
    /// shapes (hulls, full spheres) a ray from inside meets nothing before leaving.
    pub hulls: Hulls,
    /// pbrt-v4's render space (for deciding ties as its rounding does there).
    pub render_from_world: Affine3A,
}

impl Surfaces {
    #[inline]
    fn is_pass_through(&self, prim: Primitive) -> bool {
        self.pass_through.get(prim.material as usize).copied().unwrap_or(false)
    }

    /// The stochastic alpha test of a candidate hit on an alpha-tested primitive (out of
    /// line for the same reason as curves).
    #[inline(never)]
    fn alpha_passes(&self, prim: Primitive, instance: u32, detail: Detail, ray: &Ray, t: f32) -> bool {
        let s = self.surface(&Candidate { t, prim, instance, detail }, ray, instance != NONE);
        let ctx = TexContext { face: self.shapes.face_index(prim.geometry), ..TexContext::at(s.p, s.uv, s.n) };
        let alpha = self.textures.eval_float(self.alphas[prim.alpha as usize], &ctx);
        alpha_passes(alpha, ray, t)
    }

    /// The closest surface the ray hits before `t_max`.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.find(ray, t_max).map(|f| self.resolve(&f))
    }

    /// The closest surface the ray hits before `t_max`, its geometry not computed yet.
    pub fn find(&self, ray: &Ray, t_max: f32) -> Option<Found> {
        let top = self.top.as_ref()?;
        if let Some(c) = self.hulls.exit(ray) {
            return (c.t < t_max).then_some(Found { c, ray: *ray });
        }
        for &prim in &self.hulls.spheres {
            let Geometry::Sphere(i) = prim.geometry else { continue };
            let sphere = &self.shapes.spheres[i as usize];
            if sphere.contains(ray.o) {
                let (t, p) = sphere.intersect(ray, t_max)?;
                let c = Candidate { t, prim, instance: NONE, detail: Detail::ObjectPoint(p) };
                return Some(Found { c, ray: *ray });
            }
        }
        let mut best = None;
        top.closest(self, ray, t_max, NONE, &mut best);
        best.map(|c| Found { c, ray: *ray })
    }

    /// The hit `found` with its geometry.
    pub fn resolve(&self, found: &Found) -> Hit {
        let (c, ray) = (&self.hulls.resolve(&found.c, &found.ray), &found.ray);
        Hit { surface: self.surface(c, ray, false), prim: c.prim, instance: c.instance, time: ray.time }
    }

    /// The shading derivatives at a hit, for bump and normal mapping (computed on demand so
    /// that the hits every ray finds stay small and cheap).
    pub fn derivatives(&self, hit: &Hit) -> SurfaceDerivatives {
        let s = &hit.surface;
        // Shapes compute in their own space: an instance's hit is taken back there and the
        // result forth.
        let (local, inst) = if hit.instance == NONE {
            (*s, None)
        } else {
            let (w, f) = self.instances[hit.instance as usize].transforms_at(hit.time);
            let local = SurfaceHit {
                p: f.transform_point3(s.p),
                n: transform_normal(&w, s.n),
                ns: transform_normal(&w, s.ns),
                dpdu: f.transform_vector3(s.dpdu),
                ..*s
            };
            (local, Some((w, f)))
        };
        let d = match hit.prim.geometry {
            Geometry::Triangle { mesh, tri } => triangle_derivatives(&self.shapes.meshes[mesh as usize], tri, &local),
            Geometry::Sphere(i) => self.shapes.spheres[i as usize].derivatives(&local),
            Geometry::Disk(i) => self.shapes.disks[i as usize].derivatives(&local),
            Geometry::Cylinder(i) => self.shapes.cylinders[i as usize].derivatives(&local),
            Geometry::Bilinear { mesh, patch } => {
                // The patch parameters of the hit point: where a ray back along the normal meets it.
                let m = &self.shapes.bilinear_meshes[mesh as usize];
                let size = m.bounds(patch).bounding_sphere().1.max(1e-6);
                let probe = Ray::new(local.p + local.n * (1e-3 * size), -local.n);
                let uv = m.param(patch, &probe).map_or(local.uv.clamp(Vec2::ZERO, Vec2::ONE), |(u, v)| Vec2::new(u, v));
                m.derivatives(patch, &local, uv)
            }
            // Across a curve, ∂p/∂v spans its width (its p_error, as pbrt-v4 bounds it); it does
            // not bend.
            Geometry::Hull(_) => unreachable!("hits name the hull's triangle"),
            Geometry::Curve(_) | Geometry::Instance(_) => SurfaceDerivatives {
                dpdu: local.dpdu,
                dpdv: local.ns.cross(local.dpdu).normalize_or_zero() * local.p_error,
                dndu: Vec3::ZERO,
                dndv: Vec3::ZERO,
            },
        };
        match inst {
            None => d,
            Some((w, f)) => d.transformed(&w, &f),
        }
    }

    /// World-space geometry at a candidate hit found along `ray` (in the candidate's
    /// instance space when `ray_is_local`, else in world space).
    #[inline]
    fn surface(&self, c: &Candidate, ray: &Ray, ray_is_local: bool) -> SurfaceHit {
        let local = match c.detail {
            Detail::Barycentric(b1, b2) => {
                let Geometry::Triangle { mesh, tri } = c.prim.geometry else {
                    unreachable!("barycentrics come from triangles")
                };
                triangle_hit(&self.shapes.meshes[mesh as usize], tri, c.t, b1, b2)
            }
            Detail::Patch(u, v) => {
                let Geometry::Bilinear { mesh, patch } = c.prim.geometry else {
                    unreachable!("patch parameters come from bilinear patches")
                };
                self.shapes.bilinear_meshes[mesh as usize].hit(patch, c.t, u, v)
            }
            Detail::ObjectPoint(p) => match c.prim.geometry {
                Geometry::Sphere(i) => self.shapes.spheres[i as usize].hit(c.t, p),
                Geometry::Disk(i) => self.shapes.disks[i as usize].hit(c.t, p),
                Geometry::Cylinder(i) => self.shapes.cylinders[i as usize].hit(c.t, p),
                _ => unreachable!("object points come from quadrics"),
            },
            Detail::HullExit(_) => unreachable!("resolved to its triangle first"),
            Detail::Curve => {
                let Geometry::Curve(i) = c.prim.geometry else { unreachable!("only curves leave Detail::Curve") };
                let local_ray = if c.instance == NONE || ray_is_local {
                    *ray
                } else {
                    self.instances[c.instance as usize].local_ray(ray)
                };
                let curve = &self.shapes.curves[i as usize];
                // The same computation as the traversal's, so the same (closest) hit; should
                // rounding ever lose it, the ray's own frame stands in rather than a panic.
                match curve.intersect(&self.shapes.curve_segments[curve.common as usize], &local_ray, f32::INFINITY) {
                    Some((_, s)) => s,
                    None => SurfaceHit {
                        t: c.t,
                        p: local_ray.o + local_ray.d * c.t,
                        n: -local_ray.d,
                        ns: -local_ray.d,
                        uv: glam::Vec2::ZERO,
                        dpdu: local_ray.d.any_orthonormal_vector(),
                        p_error: 0.0,
                    },
                }
            }
        };
        if c.instance == NONE {
            local
        } else {
            let (w, f) = self.instances[c.instance as usize].transforms_at(ray.time);
            SurfaceHit {
                t: c.t,
                p: w.transform_point3(local.p),
                n: transform_normal(&f, local.n),
                ns: transform_normal(&f, local.ns),
                uv: local.uv,
                dpdu: w.transform_vector3(local.dpdu),
                p_error: local.p_error * w.matrix3.determinant().abs().cbrt(),
            }
        }
    }

    /// True when anything blocks the ray before `t_max`.
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.top.as_ref().is_some_and(|top| top.any(self, ray, t_max, NONE))
    }

    /// Bounds of all surfaces (empty without surfaces).
    pub fn bounds(&self) -> Bounds3 {
        self.top.as_ref().map_or(Bounds3::EMPTY, |t| t.bounds())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_scene() -> Surfaces {
        let mut s = Surfaces::default();
        s.shapes.meshes.push(Mesh::new(
            &Affine3A::IDENTITY,
            false,
            &[[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]],
            &[],
            &[],
            vec![0, 1, 2, 0, 2, 3],
        ));
        s.shapes.spheres.push(Sphere::new(
            Affine3A::from_translation(Vec3::new(0.0, 0.0, 2.0)),
            false,
            0.5,
            -0.5,
            0.5,
            360.0,
        ));
        let prims = vec![
            Primitive {
                geometry: Geometry::Triangle { mesh: 0, tri: 0 },
                material: 0,
                area_light: NONE,
                interface: NONE,
                alpha: NONE,
            },
            Primitive {
                geometry: Geometry::Triangle { mesh: 0, tri: 1 },
                material: 0,
                area_light: NONE,
                interface: NONE,
                alpha: NONE,
            },
            Primitive { geometry: Geometry::Sphere(0), material: 1, area_light: NONE, interface: NONE, alpha: NONE },
        ];
        let bounds: Vec<Bounds3> = prims.iter().map(|p| s.shapes.bounds(p.geometry)).collect();
        s.top = Accel::build(prims, bounds);
        s
    }

    #[test]
    fn closest_hit_and_occlusion() {
        let s = quad_scene();
        let down = Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
        let h = s.intersect(&down, f32::INFINITY).unwrap();
        assert_eq!(h.prim.material, 1, "the sphere is in front of the quad");
        assert!((h.surface.t - 2.5).abs() < 1e-4);
        let side = Ray::new(Vec3::new(0.9, 0.9, 5.0), -Vec3::Z);
        let h = s.intersect(&side, f32::INFINITY).unwrap();
        assert_eq!(h.prim.material, 0);
        assert!((h.surface.t - 5.0).abs() < 1e-4);
        assert!(s.occluded(&side, 10.0));
        assert!(!s.occluded(&side, 4.0));
        assert!(s.intersect(&Ray::new(Vec3::new(3.0, 0.0, 5.0), -Vec3::Z), f32::INFINITY).is_none());
    }

    #[test]
    fn no_surfaces_means_no_bvh() {
        let s = Surfaces::default();
        assert!(s.top.is_none());
        assert!(s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z), f32::INFINITY).is_none());
        assert!(!s.occluded(&Ray::new(Vec3::ZERO, Vec3::Z), 1.0));
    }
}
