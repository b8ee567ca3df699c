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

/// The frames of an infinite light. pbrt-v4 transforms only its directions: it looks a
/// direction up through the upper 3×3 of R⁻¹, R its render-from-light matrix (render space
/// being world space moved to the camera by default, as `render_from_world` says), and places
/// light samples through the upper 3×3 of R without normalising them. For an affine transform these are a rotation
/// and its inverse, translation playing no part. A projective last row (published scenes
/// rotate environment maps with one: sssdragon) leaves the lookup a rotation but bends and
/// scales pbrt-v4's samples (unless the camera is at the origin), so its light samples and its
/// camera rays see two different skies. nimbus renders the sky its lookup sees, sampling it
/// consistently, and `bent` says when pbrt-v4's samples would differ.
pub(super) struct DirectionFrames {
    /// World from light, for placing samples (the inverse of `inverse`).
    pub forward: Affine3A,
    /// Light from world, for looking directions up (pbrt-v4's).
    pub inverse: Affine3A,
    /// pbrt-v4 places this light's samples through another frame than `forward`.
    pub bent: bool,
}

pub(super) fn direction_frames(
    m: &DMat4,
    render_from_world: &Affine3A,
    loc: &FileLoc,
) -> Result<DirectionFrames, Error> {
    let row3 = m.row(3);
    if (row3.x, row3.y, row3.z, row3.w) == (0.0, 0.0, 0.0, 1.0) {
        // Affine: the rotation and its inverse, exactly as every other light's frame is made.
        let a = Affine3A::from_mat3(glam::DMat3::from_mat4(*m).as_mat3());
        if !a.is_finite() || a.matrix3.determinant() == 0.0 {
            return Err(err(loc, "the infinite light's transform is singular or not finite"));
        }
        return Ok(DirectionFrames { forward: a, inverse: a.inverse(), bent: false });
    }
    let render = DMat4::from(glam::DAffine3::from_cols_array(&render_from_world.to_cols_array().map(f64::from)));
    let r = render * *m;
    // Directions go between world and render space through the render frame's rotation (the
    // identity unless render space is camera space).
    let rotation = glam::DMat3::from_mat4(render);
    let lookup = glam::DMat3::from_mat4(r.inverse());
    if !lookup.is_finite() || lookup.determinant() == 0.0 || m.determinant() == 0.0 {
        return Err(err(loc, "the infinite light's transform is singular or not finite"));
    }
    let inverse = lookup * rotation;
    let forward = inverse.inverse();
    let pbrt_forward = rotation.inverse() * glam::DMat3::from_mat4(r);
    let bent =
        (0..3).any(|c| (forward.col(c) - pbrt_forward.col(c)).length() > 1e-6 * forward.col(c).length().max(1.0));
    Ok(DirectionFrames {
        forward: Affine3A::from_mat3(forward.as_mat3()),
        inverse: Affine3A::from_mat3(inverse.as_mat3()),
        bent,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn infinite_lights_look_up_as_pbrt_v4_and_sample_consistently() {
        let loc = FileLoc::new("t.pbrt".into(), 1, 1);
        let v = glam::Vec3::new(0.3, -0.5, 0.8);
        // An affine transform: its rotation and the inverse, translation and camera aside.
        let rot = DMat4::from_rotation_translation(glam::DQuat::from_rotation_y(0.7), glam::DVec3::new(1.0, 2.0, 3.0));
        let f = direction_frames(&rot, &Affine3A::from_translation(-glam::Vec3::new(4.0, 5.0, 6.0)), &loc).unwrap();
        let expected = glam::Quat::from_rotation_y(0.7) * v;
        assert!((f.forward.transform_vector3(v) - expected).length() < 1e-5);
        assert!((f.inverse.transform_vector3(expected) - v).length() < 1e-5);
        // sssdragon's environment frame: a rotation with (0, 0, 8.87, 1) as its last row. The
        // lookup is the rotation wherever the camera is; pbrt-v4's samples bend unless it is at
        // the origin.
        let m = DMat4::from_cols_array(&[
            -0.224951, 0.0, -0.97437, 0.0, -0.97437, 0.0, 0.224951, 0.0, 0.0, 1.0, 0.0, 8.87, 0.0, 0.0, 0.0, 1.0,
        ]);
        assert!(affine(&m, &loc).is_err());
        let at_origin = direction_frames(&m, &Affine3A::IDENTITY, &loc).unwrap();
        assert!((at_origin.forward.transform_vector3(glam::Vec3::Z) - glam::Vec3::Y).length() < 1e-6);
        assert!((at_origin.inverse.transform_vector3(glam::Vec3::Y) - glam::Vec3::Z).length() < 1e-5);
        assert!(!at_origin.bent && !f.bent);
        let moved = direction_frames(&m, &Affine3A::from_translation(-glam::Vec3::new(0.0, 1.0, -4.0)), &loc).unwrap();
        assert!((moved.inverse.transform_vector3(glam::Vec3::Y) - glam::Vec3::Z).length() < 1e-5);
        assert!((moved.forward.transform_vector3(glam::Vec3::Z) - glam::Vec3::Y).length() < 1e-5);
        assert!(moved.bent, "pbrt-v4 bends this one's samples");
        // Render space = camera space (`rendercoordsys "camera"`): rotated as well as moved.
        // World directions still look up through the rotation; pbrt-v4's samples, taken in
        // render space and rotated back to the world, bend as they do for the moved camera.
        let camera_from_world =
            Affine3A::from_rotation_y(1.1) * Affine3A::from_translation(-glam::Vec3::new(0.0, 1.0, -4.0));
        let rotated = direction_frames(&m, &camera_from_world, &loc).unwrap();
        assert!((rotated.inverse.transform_vector3(glam::Vec3::Y) - glam::Vec3::Z).length() < 1e-5);
        assert!((rotated.forward.transform_vector3(glam::Vec3::Z) - glam::Vec3::Y).length() < 1e-5);
        assert!(rotated.bent);
        assert!(direction_frames(&DMat4::ZERO, &Affine3A::IDENTITY, &loc).is_err());
    }
}
