//! Transform directives, checked numerically against matrices worked out by hand (written row
//! by row), and the animated transforms of `ActiveTransform` / `TransformTimes`.

use glam::DMat4;
use nimbus_parser::SceneDescription;

use crate::common::{assert_mat_close, load, rows, scene};

/// world_from_object of the first shape of a scene whose world block is `world`.
fn object_transform(world: &str) -> DMat4 {
    let s = load(&scene("", &format!("{world}\nShape \"sphere\"")));
    let t = s.shapes[0].world_from_object;
    assert!(!t.is_animated(), "{world}");
    t.start
}

fn translation(x: f64, y: f64, z: f64) -> DMat4 {
    rows([[1.0, 0.0, 0.0, x], [0.0, 1.0, 0.0, y], [0.0, 0.0, 1.0, z], [0.0, 0.0, 0.0, 1.0]])
}

#[test]
fn translate() {
    assert_mat_close(object_transform("Translate 1 -2 3.5"), translation(1.0, -2.0, 3.5));
}

#[test]
fn scale() {
    assert_mat_close(
        object_transform("Scale 2 3 -4"),
        rows([[2.0, 0.0, 0.0, 0.0], [0.0, 3.0, 0.0, 0.0], [0.0, 0.0, -4.0, 0.0], [0.0, 0.0, 0.0, 1.0]]),
    );
}

#[test]
fn rotate_is_counterclockwise_in_degrees_about_any_axis() {
    // 90 degrees about z takes x to y.
    assert_mat_close(
        object_transform("Rotate 90 0 0 1"),
        rows([[0.0, -1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]),
    );
    // 90 degrees about x takes y to z; the axis need not be normalised.
    assert_mat_close(
        object_transform("Rotate 90 3 0 0"),
        rows([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]),
    );
    // 120 degrees about (1,1,1) cycles the axes: x to y, y to z, z to x.
    assert_mat_close(
        object_transform("Rotate 120 1 1 1"),
        rows([[0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]),
    );
    // -90 about y takes x to z.
    assert_mat_close(
        object_transform("Rotate -90 0 1 0"),
        rows([[0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]),
    );
}

#[test]
fn transforms_compose_right_to_left_on_points() {
    // Each directive multiplies on the right: the last one acts on the object first.
    assert_mat_close(
        object_transform("Translate 1 0 0\nScale 2 2 2"),
        rows([[2.0, 0.0, 0.0, 1.0], [0.0, 2.0, 0.0, 0.0], [0.0, 0.0, 2.0, 0.0], [0.0, 0.0, 0.0, 1.0]]),
    );
    assert_mat_close(
        object_transform("Rotate 90 0 0 1\nTranslate 1 0 0"),
        rows([[0.0, -1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]),
    );
}

#[test]
fn transform_replaces_the_matrix_given_column_by_column() {
    assert_mat_close(
        object_transform("Translate 9 9 9\nTransform [ 1 2 3 4  5 6 7 8  9 10 11 12  13 14 15 16 ]"),
        rows([[1.0, 5.0, 9.0, 13.0], [2.0, 6.0, 10.0, 14.0], [3.0, 7.0, 11.0, 15.0], [4.0, 8.0, 12.0, 16.0]]),
    );
    assert_mat_close(object_transform("Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1 ]"), translation(5.0, 6.0, 7.0));
}

#[test]
fn concat_transform_multiplies_on_the_right() {
    assert_mat_close(
        object_transform("Translate 1 0 0\nConcatTransform [ 1 2 3 4  5 6 7 8  9 10 11 12  13 14 15 16 ]"),
        rows([[5.0, 13.0, 21.0, 29.0], [2.0, 6.0, 10.0, 14.0], [3.0, 7.0, 11.0, 15.0], [4.0, 8.0, 12.0, 16.0]]),
    );
}

#[test]
fn look_at_in_the_world_block() {
    // Eye (1,2,3) looking down +z with +y up: camera-from-world is a translation by -eye.
    assert_mat_close(object_transform("LookAt 1 2 3  1 2 10  0 1 0"), translation(-1.0, -2.0, -3.0));
    // Eye at the origin looking down +x with +z up: camera x is world y, camera y is world
    // z, camera z is world x.
    assert_mat_close(
        object_transform("LookAt 0 0 0  1 0 0  0 0 1"),
        rows([[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]),
    );
}

/// The world-from-camera of `LookAt 0 0 5  0 0 0  0 1 0`: pbrt's camera space is left-handed,
/// so looking down -z with +y up puts camera +x at world -x.
fn look_at_z5() -> DMat4 {
    rows([[-1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, -1.0, 5.0], [0.0, 0.0, 0.0, 1.0]])
}

#[test]
fn camera_transform_is_the_inverse_of_the_options_block_ctm() {
    let s = load("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin");
    assert_mat_close(s.camera.world_from_camera.start, look_at_z5());
    assert!(!s.camera.world_from_camera.is_animated());
    let s = load("Scale -1 1 1\nTranslate 0 0 -4\nCamera \"perspective\"\nWorldBegin");
    assert_mat_close(
        s.camera.world_from_camera.start,
        rows([[-1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 4.0], [0.0, 0.0, 0.0, 1.0]]),
    );
}

#[test]
fn world_begin_resets_the_transform() {
    assert_mat_close(
        load("Translate 1 2 3\nWorldBegin\nShape \"sphere\"").shapes[0].world_from_object.start,
        DMat4::IDENTITY,
    );
}

#[test]
fn identity_resets_the_transform() {
    assert_mat_close(object_transform("Translate 1 2 3\nRotate 30 1 0 0\nIdentity"), DMat4::IDENTITY);
}

#[test]
fn attribute_blocks_restore_the_transform() {
    let s = load(&scene(
        "",
        "Translate 1 0 0\nAttributeBegin\nTranslate 0 1 0\nShape \"sphere\"\nAttributeEnd\nShape \"sphere\"",
    ));
    assert_mat_close(s.shapes[0].world_from_object.start, translation(1.0, 1.0, 0.0));
    assert_mat_close(s.shapes[1].world_from_object.start, translation(1.0, 0.0, 0.0));
}

#[test]
fn lights_take_the_current_transform() {
    let s = load(&scene("", "Translate 0 4 0\nLightSource \"point\""));
    assert_mat_close(s.lights[0].world_from_light.start, translation(0.0, 4.0, 0.0));
}

#[test]
fn named_coordinate_systems() {
    let s = load(&scene(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"",
        "Translate 0 3 0\nCoordinateSystem \"up3\"\nIdentity\nShape \"sphere\"\n\
         CoordSysTransform \"up3\"\nShape \"sphere\"\n\
         CoordSysTransform \"camera\"\nShape \"sphere\"\n\
         Translate 7 7 7\nCoordSysTransform \"world\"\nShape \"sphere\"\n\
         CoordSysTransform \"nowhere\"\nShape \"sphere\"",
    ));
    let t: Vec<DMat4> = s.shapes.iter().map(|sh| sh.world_from_object.start).collect();
    assert_mat_close(t[0], DMat4::IDENTITY);
    assert_mat_close(t[1], translation(0.0, 3.0, 0.0));
    // "camera" places objects in camera space.
    assert_mat_close(t[2], look_at_z5());
    assert_mat_close(t[3], DMat4::IDENTITY);
    // An unknown name leaves the transform alone, with a warning.
    assert_mat_close(t[4], DMat4::IDENTITY);
    let warnings: Vec<String> = s.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(warnings, ["t.pbrt:15:1: couldn't find named coordinate system \"nowhere\""]);
}

#[test]
fn named_coordinate_systems_from_the_options_block_carry_into_the_world() {
    let s = load(&scene(
        "Translate 2 0 0\nCoordinateSystem \"opt\"\nCamera \"perspective\"",
        "CoordSysTransform \"opt\"\nShape \"sphere\"",
    ));
    assert_mat_close(s.shapes[0].world_from_object.start, translation(2.0, 0.0, 0.0));
}

/// A scene with the camera and a shape animated through ActiveTransform.
fn animated() -> SceneDescription {
    load(
        "TransformTimes 0.5 2\n\
         Translate 0 0 -1\n\
         ActiveTransform EndTime\n\
         Translate 0 0 -2\n\
         ActiveTransform StartTime\n\
         Scale 2 2 2\n\
         ActiveTransform All\n\
         Camera \"perspective\"\n\
         ActiveTransform EndTime\n\
         WorldBegin\n\
         Translate 0 1 0\n\
         AttributeBegin\n\
           ActiveTransform StartTime\n\
           Translate 1 0 0\n\
           Shape \"sphere\"\n\
         AttributeEnd\n\
         Translate 0 0 1\n\
         Shape \"sphere\"",
    )
}

#[test]
fn active_transform_and_transform_times_keep_start_and_end() {
    let s = animated();
    let cam = s.camera.world_from_camera;
    assert!(cam.is_animated());
    assert_eq!((cam.start_time, cam.end_time), (0.5, 2.0));
    // camera-from-world: start = T(0,0,-1) S(2), end = T(0,0,-1) T(0,0,-2).
    assert_mat_close(
        cam.start,
        rows([[0.5, 0.0, 0.0, 0.0], [0.0, 0.5, 0.0, 0.0], [0.0, 0.0, 0.5, 0.5], [0.0, 0.0, 0.0, 1.0]]),
    );
    assert_mat_close(cam.end, translation(0.0, 0.0, 3.0));

    // WorldBegin makes both transforms active again and keeps the times.
    let moving = s.shapes[0].world_from_object;
    assert_eq!((moving.start_time, moving.end_time), (0.5, 2.0));
    assert_mat_close(moving.start, translation(1.0, 1.0, 0.0));
    assert_mat_close(moving.end, translation(0.0, 1.0, 0.0));
    // AttributeEnd restored ActiveTransform All.
    let still = s.shapes[1].world_from_object;
    assert!(!still.is_animated());
    assert_mat_close(still.start, translation(0.0, 1.0, 1.0));
}

#[test]
fn default_shutter_times_are_zero_and_one() {
    let t = load("WorldBegin\nShape \"sphere\"").shapes[0].world_from_object;
    assert_eq!((t.start_time, t.end_time), (0.0, 1.0));
}
