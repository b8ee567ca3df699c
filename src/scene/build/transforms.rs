//! Transforms as the scene gives them, checked: fixed, moving, and affine only.

use super::*;

pub(super) fn fixed_transform(t: &AnimatedTransform, loc: &FileLoc, what: &str) -> Result<Affine3A, Error> {
    if t.is_animated() {
        return Err(err(
            loc,
            format!(
                "animated transforms ({what} with ActiveTransform/TransformTimes motion) are not supported by nimbus"
            ),
        ));
    }
    affine(&t.start, loc)
}

/// An animated transform's motion, both keyframes checked as [`affine`] checks them.
pub(super) fn motion_transform(t: &AnimatedTransform, loc: &FileLoc) -> Result<MotionTransform, Error> {
    affine(&t.start, loc)?;
    affine(&t.end, loc)?;
    Ok(MotionTransform::new(&t.start, &t.end, t.start_time as f32, t.end_time as f32))
}

pub(super) fn affine(m: &DMat4, loc: &FileLoc) -> Result<Affine3A, Error> {
    let row3 = m.row(3);
    if (row3.x, row3.y, row3.z, row3.w) != (0.0, 0.0, 0.0, 1.0) {
        return Err(err(loc, "projective transforms are not supported (the last row must be 0 0 0 1)"));
    }
    let a = Affine3A::from_mat4(m.as_mat4());
    if !a.is_finite() || a.matrix3.determinant() == 0.0 {
        return Err(err(loc, "the transform is singular or not finite"));
    }
    Ok(a)
}

/// The frame of an infinite light: pbrt-v4 transforms only directions by it, through the
/// upper 3×3 of the matrix and of its inverse, so translation does not matter and neither does
/// a projective last row while the translation column is zero (the inverse's 3×3 is then the
/// 3×3's inverse). Published scenes rotate environment maps this way (sssdragon).
pub(super) fn direction_frame(m: &DMat4, loc: &FileLoc) -> Result<Affine3A, Error> {
    let row3 = m.row(3);
    let projective = (row3.x, row3.y, row3.z) != (0.0, 0.0, 0.0) || row3.w != 1.0;
    let col3 = m.col(3);
    if projective && (col3.x, col3.y, col3.z) != (0.0, 0.0, 0.0) {
        return Err(err(
            loc,
            "infinite light under a projective transform with a translation: its directions would not be those \
             of a linear map (pbrt-v4 would bend them through the inverse's 3x3), which nimbus does not follow",
        ));
    }
    if projective && row3.w <= 0.0 {
        return Err(err(loc, "infinite light under a projective transform whose last entry is not positive"));
    }
    let a = Affine3A::from_mat3(glam::DMat3::from_mat4(*m).as_mat3());
    if !a.is_finite() || a.matrix3.determinant() == 0.0 {
        return Err(err(loc, "the infinite light's transform is singular or not finite"));
    }
    Ok(a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn infinite_lights_take_the_3x3_of_a_projective_rotation() {
        let loc = FileLoc::new("t.pbrt".into(), 1, 1);
        // sssdragon's environment frame: a rotation with (0, 0, 8.87, 1) as its last row.
        let m = DMat4::from_cols_array(&[
            -0.224951, 0.0, -0.97437, 0.0, -0.97437, 0.0, 0.224951, 0.0, 0.0, 1.0, 0.0, 8.87, 0.0, 0.0, 0.0, 1.0,
        ]);
        assert!(affine(&m, &loc).is_err());
        let a = direction_frame(&m, &loc).unwrap();
        let d = a.transform_vector3(glam::Vec3::Z);
        assert!((d - glam::Vec3::Y).length() < 1e-6, "{d}");
        assert_eq!(a.translation, glam::Vec3A::ZERO);
        // Translation alone is dropped; translation with a projective row is refused.
        let moved = DMat4::from_translation(glam::DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(direction_frame(&moved, &loc).unwrap(), Affine3A::IDENTITY);
        let mut both = moved;
        both.x_axis.w = 0.5;
        assert!(direction_frame(&both, &loc).unwrap_err().to_string().contains("with a translation"));
        assert!(direction_frame(&DMat4::ZERO, &loc).is_err());
    }
}
