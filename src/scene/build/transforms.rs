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
