//! Orthonormal frames: local shading space has the normal along +z.

use glam::Vec3;

/// An orthonormal basis (x, y, z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub x: Vec3,
    /// Second tangent.
    pub y: Vec3,
    /// Normal.
    pub z: Vec3,
}

impl Frame {
    /// A frame whose z axis is the unit vector `n` (Duff et al. 2017, "Building an
    /// Orthonormal Basis, Revisited").
    #[inline]
    pub fn from_z(n: Vec3) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let x = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let y = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { x, y, z: n }
    }

    /// A frame with z = `n` and x as close to `tangent` as orthogonality allows; falls back
    /// to [`Frame::from_z`] when the tangent is parallel to `n`.
    #[inline]
    pub fn from_z_x(n: Vec3, tangent: Vec3) -> Frame {
        let x = tangent - n * n.dot(tangent);
        let len2 = x.length_squared();
        if len2 < 1e-12 {
            return Frame::from_z(n);
        }
        let x = x / len2.sqrt();
        Frame { x, y: n.cross(x), z: n }
    }

    /// World to local coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }

    /// Local to world coordinates.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal_and_round_trip() {
        for n in [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::new(0.3, -0.5, 0.81).normalize(), Vec3::new(0.0, 0.0, -1.0)] {
            let f = Frame::from_z(n);
            assert!((f.x.length() - 1.0).abs() < 1e-5 && (f.y.length() - 1.0).abs() < 1e-5);
            assert!(f.x.dot(f.y).abs() < 1e-5 && f.x.dot(f.z).abs() < 1e-5 && f.y.dot(f.z).abs() < 1e-5);
            assert!(f.x.cross(f.y).dot(f.z) > 0.99, "right-handed");
            let v = Vec3::new(0.2, 0.7, -0.4);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }
}
