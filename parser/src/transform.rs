//! The transform directives in pbrt-v4's conventions (left-handed camera space, angles in
//! degrees, `Transform` matrices given column by column), computed in double precision.

use glam::{DMat4, DVec3, DVec4};

/// `Translate x y z`
pub fn translate(d: [f64; 3]) -> DMat4 {
    DMat4::from_translation(DVec3::from(d))
}

/// `Scale x y z`
pub fn scale(s: [f64; 3]) -> DMat4 {
    DMat4::from_scale(DVec3::from(s))
}

/// `Rotate angle x y z`: a rotation by `angle` degrees about the axis (x, y, z). `None` for a
/// zero axis.
pub fn rotate(angle_deg: f64, axis: [f64; 3]) -> Option<DMat4> {
    let a = DVec3::from(axis);
    if a.length_squared() == 0.0 {
        return None;
    }
    let a = a.normalize();
    let (s, c) = angle_deg.to_radians().sin_cos();
    // Rows of the rotation matrix (Rodrigues' formula), as pbrt-v4 writes them.
    let r0 = DVec4::new(
        a.x * a.x + (1.0 - a.x * a.x) * c,
        a.x * a.y * (1.0 - c) - a.z * s,
        a.x * a.z * (1.0 - c) + a.y * s,
        0.0,
    );
    let r1 = DVec4::new(
        a.x * a.y * (1.0 - c) + a.z * s,
        a.y * a.y + (1.0 - a.y * a.y) * c,
        a.y * a.z * (1.0 - c) - a.x * s,
        0.0,
    );
    let r2 = DVec4::new(
        a.x * a.z * (1.0 - c) - a.y * s,
        a.y * a.z * (1.0 - c) + a.x * s,
        a.z * a.z + (1.0 - a.z * a.z) * c,
        0.0,
    );
    Some(DMat4::from_cols(r0, r1, r2, DVec4::W).transpose())
}

/// `LookAt eye look up`: the camera-from-world transform. `None` when the view direction is
/// zero or parallel to `up`.
pub fn look_at(eye: [f64; 3], look: [f64; 3], up: [f64; 3]) -> Option<DMat4> {
    let pos = DVec3::from(eye);
    let dir = DVec3::from(look) - pos;
    let up = DVec3::from(up);
    if dir.length_squared() == 0.0 || up.length_squared() == 0.0 {
        return None;
    }
    let dir = dir.normalize();
    let right = up.normalize().cross(dir);
    if right.length() < 1e-12 {
        return None;
    }
    let right = right.normalize();
    let new_up = dir.cross(right);
    let world_from_camera = DMat4::from_cols(right.extend(0.0), new_up.extend(0.0), dir.extend(0.0), pos.extend(1.0));
    Some(world_from_camera.inverse())
}

/// `Transform [16 numbers]`: pbrt-v4 reads the numbers column by column.
pub fn from_pbrt_array(m: &[f64; 16]) -> DMat4 {
    DMat4::from_cols_array(m)
}

/// The inverse, or `None` when `m` is singular (or not finite).
pub fn try_inverse(m: &DMat4) -> Option<DMat4> {
    let det = m.determinant();
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = m.inverse();
    inv.is_finite().then_some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-9
    }

    #[test]
    fn rotate_is_counterclockwise_about_the_axis() {
        let r = rotate(90.0, [0.0, 0.0, 1.0]).unwrap();
        assert!(close(r.transform_point3(DVec3::X), DVec3::Y));
        assert!(rotate(10.0, [0.0, 0.0, 0.0]).is_none());
    }

    #[test]
    fn look_at_maps_the_eye_to_the_origin_and_the_target_to_plus_z() {
        let m = look_at([0.0, 1.0, 3.4], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]).unwrap();
        assert!(close(m.transform_point3(DVec3::new(0.0, 1.0, 3.4)), DVec3::ZERO));
        assert!(close(m.transform_point3(DVec3::new(0.0, 1.0, 0.0)), DVec3::new(0.0, 0.0, 3.4)));
        // pbrt's camera space is left-handed: +x is to the left of the view seen from behind
        // when up is +y and the camera looks down -z in world space.
        assert!(close(m.transform_vector3(DVec3::new(-1.0, 0.0, 0.0)), DVec3::new(1.0, 0.0, 0.0)));
        assert!(look_at([0.0; 3], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]).is_none());
    }

    #[test]
    fn transform_array_is_column_major() {
        let mut a = [0.0; 16];
        a[0] = 1.0;
        a[5] = 1.0;
        a[10] = 1.0;
        a[15] = 1.0;
        a[12] = 5.0; // translation x in pbrt's layout
        let m = from_pbrt_array(&a);
        assert!(close(m.transform_point3(DVec3::ZERO), DVec3::new(5.0, 0.0, 0.0)));
    }
}
