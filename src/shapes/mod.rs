//! Shapes with pbrt-v4's geometry and orientation conventions: intersection, surface
//! details at a hit, and area sampling for shapes that emit.

mod bilinear;
mod curve;
mod cylinder;
mod disk;
mod mesh;
mod sphere;

pub use bilinear::BilinearMesh;
pub use curve::{
    Curve, CurveCommon, CurveType, cubic_bspline_to_bezier, elevate_quadratic, quadratic_bspline_to_bezier,
};
pub use cylinder::Cylinder;
pub use disk::Disk;
pub use mesh::{
    Mesh, PbrtTriangleHit, barycentrics, intersect_triangle, pbrt_intersect_triangle, triangle_derivatives,
    triangle_hit, triangle_sample,
};
pub use sphere::Sphere;

use glam::{Affine3A, Vec2, Vec3};

/// Geometry at a ray hit, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Distance along the ray.
    pub t: f32,
    /// Hit point.
    pub p: Vec3,
    /// Geometric normal, oriented as pbrt-v4 orients it (outward for closed quadrics,
    /// counter-clockwise for triangles, flipped by ReverseOrientation and by transforms
    /// that swap handedness; towards the shading normal when a mesh has normals).
    pub n: Vec3,
    /// Shading normal (same side as `n`).
    pub ns: Vec3,
    /// Surface parameterisation (texture coordinates).
    pub uv: Vec2,
    /// ∂p/∂u: the shading frame's first tangent.
    pub dpdu: Vec3,
    /// A bound on the hit point's distance from the surface beyond the usual rounding
    /// (pbrt-v4's per-shape `pError`; curves: twice their width), for offsetting rays.
    pub p_error: f32,
}

/// The shading geometry's derivatives at a hit, which only bump and normal mapping need:
/// computed on demand (the accelerator's `Surfaces::derivatives`) so that hits stay cheap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceDerivatives {
    /// Shading ∂p/∂u (for meshes with normals made perpendicular to ns, as pbrt-v4 does).
    pub dpdu: Vec3,
    /// Shading ∂p/∂v (for meshes with normals ns × ∂p/∂u).
    pub dpdv: Vec3,
    /// ∂n/∂u of the shading normal (bump mapping's curvature term).
    pub dndu: Vec3,
    /// ∂n/∂v of the shading normal.
    pub dndv: Vec3,
}

impl SurfaceDerivatives {
    /// The derivatives in world space, for a hit on an instance.
    pub fn transformed(&self, world_from_instance: &Affine3A, instance_from_world: &Affine3A) -> SurfaceDerivatives {
        SurfaceDerivatives {
            dpdu: world_from_instance.transform_vector3(self.dpdu),
            dpdv: world_from_instance.transform_vector3(self.dpdv),
            dndu: transform_normal_unnormalized(instance_from_world, self.dndu),
            dndv: transform_normal_unnormalized(instance_from_world, self.dndv),
        }
    }
}

impl SurfaceHit {
    /// A ray leaving the hit in direction `d`, offset off the surface.
    #[inline]
    pub fn spawn_ray(&self, d: Vec3) -> crate::geometry::Ray {
        crate::geometry::Ray::new(self.offset_origin(d), d)
    }

    /// The hit point moved off the surface towards the side `w` points to.
    #[inline]
    pub fn offset_origin(&self, w: Vec3) -> Vec3 {
        crate::geometry::offset_origin_by(self.p, self.n, w, self.p_error)
    }
}

/// A point sampled on a shape's surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeSample {
    /// The point.
    pub p: Vec3,
    /// Oriented geometric normal there.
    pub n: Vec3,
    /// Density of the sample: per unit area, or per solid angle when `solid_angle`.
    pub pdf: f32,
    /// True when `pdf` is already per solid angle as seen from the reference point.
    pub solid_angle: bool,
}

/// Mesh vertex data taken to world space, shared by triangle and bilinear-patch meshes:
/// positions, unit normals (transformed as normals, and flipped with ReverseOrientation as
/// pbrt-v4 flips stored normals), texture coordinates, and whether geometric normals flip
/// (ReverseOrientation xor a handedness-swapping transform).
pub(crate) struct WorldVertices {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub flip_normals: bool,
}

impl WorldVertices {
    pub(crate) fn new(
        world_from_object: &Affine3A,
        reverse_orientation: bool,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        uvs: &[[f32; 2]],
    ) -> WorldVertices {
        let m = world_from_object.inverse().matrix3;
        WorldVertices {
            positions: positions.iter().map(|p| world_from_object.transform_point3(Vec3::from(*p))).collect(),
            normals: normals
                .iter()
                .map(|n| {
                    let n = Vec3::from(*n);
                    let w = Vec3::new(m.x_axis.dot(n.into()), m.y_axis.dot(n.into()), m.z_axis.dot(n.into()))
                        .normalize_or_zero();
                    if reverse_orientation { -w } else { w }
                })
                .collect(),
            uvs: uvs.iter().map(|t| Vec2::from(*t)).collect(),
            flip_normals: reverse_orientation ^ swaps_handedness(world_from_object),
        }
    }
}

/// Whether a transform flips handedness (negative determinant): pbrt-v4 then flips normals.
pub fn swaps_handedness(m: &Affine3A) -> bool {
    m.matrix3.determinant() < 0.0
}

/// If `m` scales uniformly (a similarity), its scale factor.
pub fn uniform_scale(m: &Affine3A) -> Option<f32> {
    let sx = Vec3::from(m.matrix3.x_axis).length();
    let sy = Vec3::from(m.matrix3.y_axis).length();
    let sz = Vec3::from(m.matrix3.z_axis).length();
    let orthogonal = m.matrix3.x_axis.dot(m.matrix3.y_axis).abs() < 1e-4 * sx * sy
        && m.matrix3.x_axis.dot(m.matrix3.z_axis).abs() < 1e-4 * sx * sz
        && m.matrix3.y_axis.dot(m.matrix3.z_axis).abs() < 1e-4 * sy * sz;
    (orthogonal && (sx - sy).abs() < 1e-4 * sx && (sx - sz).abs() < 1e-4 * sx).then_some(sx)
}

/// Transforms an object-space normal to world space with the inverse transpose of the
/// world-from-object transform, given as its inverse.
#[inline]
pub fn transform_normal(object_from_world: &Affine3A, n: Vec3) -> Vec3 {
    transform_normal_unnormalized(object_from_world, n).normalize_or_zero()
}

/// (M⁻¹)ᵀ n without normalising: how pbrt-v4 transforms ∂n/∂u and ∂n/∂v.
pub fn transform_normal_unnormalized(object_from_world: &Affine3A, n: Vec3) -> Vec3 {
    // Component i is column i of M^-1 dotted with n.
    let m = object_from_world.matrix3;
    Vec3::new(m.x_axis.dot(n.into()), m.y_axis.dot(n.into()), m.z_axis.dot(n.into()))
}

/// ∂n/∂u and ∂n/∂v of a parametric surface from its first and second derivatives: the
/// Weingarten equations (pbrt-v4 §6.2.3, with n = normalize(∂p/∂u × ∂p/∂v)).
pub fn weingarten(dpdu: Vec3, dpdv: Vec3, d2pduu: Vec3, d2pduv: Vec3, d2pdvv: Vec3) -> (Vec3, Vec3) {
    let (e1, f1, g1) = (dpdu.dot(dpdu), dpdu.dot(dpdv), dpdv.dot(dpdv));
    let n = dpdu.cross(dpdv).normalize_or_zero();
    let (e, f, g) = (n.dot(d2pduu), n.dot(d2pduv), n.dot(d2pdvv));
    let egf2 = e1 * g1 - f1 * f1;
    let inv = if egf2 == 0.0 { 0.0 } else { 1.0 / egf2 };
    let dndu = (f * f1 - e * g1) * inv * dpdu + (e * f1 - f * e1) * inv * dpdv;
    let dndv = (g * f1 - f * g1) * inv * dpdu + (f * f1 - g * e1) * inv * dpdv;
    (dndu, dndv)
}
