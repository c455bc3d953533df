//! Moving the camera as a viewport does: orbit around a pivot, pan in the
//! view plane, dolly toward a point (the camera of docs/scene-format.md,
//! Coordinates).
//!
//! A [`Pose`] is the camera's transformation read as a uniform scale, a
//! rotation and a position. Each move gives a new pose, which
//! [`Pose::steps`] writes back as the short sequence of steps a scene file
//! holds: `scale`, `rotate-z` (roll), `rotate-x` (pitch), `rotate-y` (yaw),
//! `translate`, applied in that order. Yaw turns about the world's y axis
//! (which points down), pitch about the camera's right axis, so an orbit
//! keeps the horizon level.
//!
//! A camera whose transformation has a non-uniform scale or a shear has no
//! such pose: [`Pose::of`] refuses it rather than change the picture.

use glam::{DMat3, DVec3};

use crate::math::TransformStep;
use crate::scene::Camera;

/// The most the camera pitches up or down: short of straight, where yaw
/// and roll would be one and the same.
pub const MAX_PITCH: f64 = 89.0 * std::f64::consts::PI / 180.0;

/// Why a camera cannot be navigated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error(
    "orbit, pan and dolly keep a camera's shape, and this one has a shear or an uneven scale: edit its steps in the panel"
)]
pub struct NotRigid;

/// Where the camera is and how it is turned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Camera units to world units (the `scale factor`), > 0.
    pub scale: f64,
    /// Camera axes to world axes: a rotation.
    pub rotation: DMat3,
    /// The camera's origin, the centre of its screen, in world space.
    pub position: DVec3,
}

impl Pose {
    /// The pose of `camera`'s transformation.
    pub fn of(camera: &Camera) -> Result<Pose, NotRigid> {
        let m = camera.transform.to_world();
        let a = m.matrix3;
        let scale = a.x_axis.length();
        if !(scale.is_finite() && scale > 0.0) {
            return Err(NotRigid);
        }
        let rotation = a * (1.0 / scale);
        // A rotation: orthonormal columns and a positive determinant.
        let tolerance = 1e-9;
        let orthonormal = (rotation.transpose() * rotation - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .all(|v| v.abs() < tolerance);
        if !orthonormal || rotation.determinant() <= 0.0 {
            return Err(NotRigid);
        }
        Ok(Pose {
            scale,
            rotation,
            position: m.translation,
        })
    }

    /// The camera's right (x), down (y) and forward (z) axes in world space.
    pub fn right(&self) -> DVec3 {
        self.rotation.x_axis
    }

    pub fn down(&self) -> DVec3 {
        self.rotation.y_axis
    }

    pub fn forward(&self) -> DVec3 {
        self.rotation.z_axis
    }

    /// The eye: `eye_distance` camera units behind the screen's centre.
    pub fn eye(&self, eye_distance: f64) -> DVec3 {
        self.position - self.forward() * (eye_distance * self.scale)
    }

    /// Turned about `pivot`: `yaw` radians about the world's y axis, then
    /// `pitch` about the camera's right axis (positive looks up), the
    /// pitch kept within [`MAX_PITCH`].
    pub fn orbit(&self, pivot: DVec3, yaw: f64, pitch: f64) -> Pose {
        let (_, current_pitch, _) = angles(&self.rotation);
        let pitch = (current_pitch + pitch).clamp(-MAX_PITCH, MAX_PITCH) - current_pitch;
        let turn = DMat3::from_rotation_y(yaw) * DMat3::from_axis_angle(self.right(), pitch);
        Pose {
            scale: self.scale,
            rotation: turn * self.rotation,
            position: pivot + turn * (self.position - pivot),
        }
    }

    /// Moved by `right` and `down` world units along the camera's axes.
    pub fn pan(&self, right: f64, down: f64) -> Pose {
        Pose {
            position: self.position + self.right() * right + self.down() * down,
            ..*self
        }
    }

    /// Moved `distance` world units along `direction` (a unit vector).
    pub fn dolly(&self, direction: DVec3, distance: f64) -> Pose {
        Pose {
            position: self.position + direction * distance,
            ..*self
        }
    }

    /// The pose as transformation steps: `scale`, `rotate-z`, `rotate-x`,
    /// `rotate-y`, `translate`, each only when it does something (a camera
    /// dollied straight ahead is saved as one `translate`, not with
    /// `rotate-x angle="-0"` beside it).
    pub fn steps(&self) -> Vec<TransformStep> {
        let (yaw, pitch, roll) = angles(&self.rotation);
        let mut steps = Vec::new();
        if self.scale != 1.0 {
            steps.push(TransformStep::UniformScale(self.scale));
        }
        if roll != 0.0 {
            steps.push(TransformStep::RotateZ(roll));
        }
        if pitch != 0.0 {
            steps.push(TransformStep::RotateX(pitch));
        }
        if yaw != 0.0 {
            steps.push(TransformStep::RotateY(yaw));
        }
        if self.position != DVec3::ZERO {
            steps.push(TransformStep::Translate(self.position));
        }
        steps
    }
}

/// (yaw, pitch, roll) of a rotation R = Ry(yaw) · Rx(pitch) · Rz(roll).
///
/// The forward axis R·z = (cos p sin y, −sin p, cos p cos y) gives pitch
/// and yaw; the right axis taken back through Ry and Rx is
/// (cos r, sin r, 0), which gives roll.
fn angles(rotation: &DMat3) -> (f64, f64, f64) {
    let f = rotation.z_axis;
    let pitch = (-f.y).clamp(-1.0, 1.0).asin();
    let yaw = f.x.atan2(f.z);
    let back = (DMat3::from_rotation_y(yaw) * DMat3::from_rotation_x(pitch)).transpose();
    let u = back * rotation.x_axis;
    let roll = u.y.atan2(u.x);
    (yaw, pitch, roll)
}

/// What part of a pixel a value set by a gesture (a drag of the camera, a
/// light, an object) may move when it is rounded: well under what shows.
pub const GESTURE_PRECISION: f64 = 1.0 / 16.0;

/// The shortest decimal within `tolerance` of `v` (0 within `tolerance`
/// of 0; `v` itself when the tolerance is not positive): the value a
/// gesture means, without the float noise of the arithmetic that got it
/// (`-1.2000000000000002` is `-1.2`).
pub fn shortest_within(v: f64, tolerance: f64) -> f64 {
    if !(tolerance > 0.0 && v.is_finite()) {
        return v;
    }
    if v.abs() <= tolerance {
        return 0.0;
    }
    for digits in 0..17 {
        let r: f64 = format!("{v:.digits$}").parse().unwrap_or(v);
        if (r - v).abs() <= tolerance {
            return r;
        }
    }
    v
}

/// `new` (a gesture's value) rounded to `tolerance`, or `old` (the value
/// before the gesture) itself when the gesture left it within that: a
/// value brought back, or one the gesture did not move, keeps its text.
pub fn settle(new: f64, old: f64, tolerance: f64) -> f64 {
    if (new - old).abs() <= tolerance {
        old
    } else {
        shortest_within(new, tolerance)
    }
}

/// [`settle`] for each coordinate.
pub fn settle_vec(new: DVec3, old: DVec3, tolerance: f64) -> DVec3 {
    DVec3::new(
        settle(new.x, old.x, tolerance),
        settle(new.y, old.y, tolerance),
        settle(new.z, old.z, tolerance),
    )
}

/// `steps` (a gesture's transformation) with each value settled against
/// the step of the same kind at the same place in `old` ([`settle`]):
/// lengths and positions within `distance`, angles within `angle`, scale
/// factors within a relative 1e-9. Steps that do nothing once settled
/// (`rotate-z angle="0"`, `scale factor="1"`) are left out.
pub fn settle_steps(
    steps: &[TransformStep],
    old: &[TransformStep],
    distance: f64,
    angle: f64,
) -> Vec<TransformStep> {
    use TransformStep as S;
    let factor = |f: f64, o: Option<f64>| {
        let tolerance = f.abs() * 1e-9;
        match o {
            Some(o) => settle(f, o, tolerance),
            None if (f - 1.0).abs() <= tolerance => 1.0,
            None => shortest_within(f, tolerance),
        }
    };
    // The n-th step of a kind pairs with the n-th of that kind in `old`.
    let same_kind = |a: &TransformStep, b: &TransformStep| {
        std::mem::discriminant(a) == std::mem::discriminant(b)
    };
    steps
        .iter()
        .enumerate()
        .filter_map(|(k, step)| {
            let nth = steps[..k].iter().filter(|s| same_kind(s, step)).count();
            let before = old.iter().filter(|s| same_kind(s, step)).nth(nth);
            let settled = match (*step, before.copied()) {
                (S::Translate(v), Some(S::Translate(o))) => {
                    S::Translate(settle_vec(v, o, distance))
                }
                (S::Translate(v), _) => S::Translate(settle_vec(v, DVec3::ZERO, distance)),
                (S::Scale(v), Some(S::Scale(o))) => {
                    S::Scale(settle_vec(v, o, 1e-9 * v.abs().max_element()))
                }
                (S::Scale(v), _) => S::Scale(v),
                (S::RotateX(a), Some(S::RotateX(o))) => S::RotateX(settle(a, o, angle)),
                (S::RotateY(a), Some(S::RotateY(o))) => S::RotateY(settle(a, o, angle)),
                (S::RotateZ(a), Some(S::RotateZ(o))) => S::RotateZ(settle(a, o, angle)),
                (S::RotateX(a), _) => S::RotateX(settle(a, 0.0, angle)),
                (S::RotateY(a), _) => S::RotateY(settle(a, 0.0, angle)),
                (S::RotateZ(a), _) => S::RotateZ(settle(a, 0.0, angle)),
                (S::UniformScale(f), Some(S::UniformScale(o))) => {
                    S::UniformScale(factor(f, Some(o)))
                }
                (S::UniformScale(f), _) => S::UniformScale(factor(f, None)),
            };
            // A step the text had stays, whatever it does.
            let identity = match settled {
                S::Translate(v) => v == DVec3::ZERO,
                S::RotateX(a) | S::RotateY(a) | S::RotateZ(a) => a == 0.0,
                S::UniformScale(f) => f == 1.0,
                S::Scale(v) => v == DVec3::ONE,
            };
            (!identity || before.is_some_and(|b| *b == settled)).then_some(settled)
        })
        .collect()
}

/// The angle one pixel spans at the centre of the picture: 2 / min(width,
/// height) camera units seen from eyeDistance.
pub fn pixel_angle(camera: &Camera) -> f64 {
    2.0 / f64::from(camera.width.min(camera.height)) / camera.eye_distance
}

/// The world size of one pixel at `depth` world units in front of the eye.
///
/// A pixel is s = 2 / min(width, height) camera units on the screen, which
/// is eyeDistance from the eye; by similar triangles (the camera's scale
/// cancels) it is s · depth / eyeDistance at that depth.
pub fn pixel_size(camera: &Camera, depth: f64) -> f64 {
    let s = 2.0 / f64::from(camera.width.min(camera.height));
    s * depth / camera.eye_distance
}

/// `point` moved by (`dx`, `dy`) pixels across the picture at its own
/// depth in camera space: what dragging it on screen means. It needs only
/// the camera's projection, so it works for any camera transformation (a
/// sheared or non-uniformly scaled one too, which cannot be orbited).
/// `None` for a point at or behind the eye.
///
/// In camera space a pixel at depth q.z + e from the eye spans
/// s · (q.z + e) / e camera units (by similar triangles, as in
/// [`project`]).
pub fn moved_on_screen(camera: &Camera, point: DVec3, dx: f64, dy: f64) -> Option<DVec3> {
    let (q, depth, s) = in_camera_space(camera, point)?;
    let k = s * depth / camera.eye_distance;
    let moved = camera
        .transform
        .to_world()
        .transform_point3(q + DVec3::new(dx * k, dy * k, 0.0));
    moved.is_finite().then_some(moved)
}

/// `point` in camera space (q), its depth in front of the eye (q.z + e),
/// and a pixel's size on the screen (s = 2 / min(width, height) camera
/// units); `None` for a point at or behind the eye.
fn in_camera_space(camera: &Camera, point: DVec3) -> Option<(DVec3, f64, f64)> {
    let q = camera.transform.to_object().transform_point3(point);
    let depth = q.z + camera.eye_distance;
    if depth.is_nan() || depth <= 0.0 {
        return None;
    }
    let s = 2.0 / f64::from(camera.width.min(camera.height));
    Some((q, depth, s))
}

/// The world size of one pixel at `point` (the smaller of a step across
/// and a step down, which differ for a non-uniformly scaled camera);
/// `None` for a point at or behind the eye.
pub fn pixel_at(camera: &Camera, point: DVec3) -> Option<f64> {
    let across = moved_on_screen(camera, point, 1.0, 0.0)?;
    let down = moved_on_screen(camera, point, 0.0, 1.0)?;
    Some((across - point).length().min((down - point).length()))
}

/// Where a world point shows in the picture, in pixels from its top-left
/// corner (the inverse of [`super::CameraRays::ray`]); `None` for a point
/// at or behind the eye.
///
/// In camera space the eye is at (0, 0, −e) and the screen is z = 0: the
/// line from the eye to q meets the screen at q.xy · e / (q.z + e), which is
/// (x − width/2) · s in pixels x.
pub fn project(camera: &Camera, point: DVec3) -> Option<(f64, f64)> {
    let (q, depth, s) = in_camera_space(camera, point)?;
    let e = camera.eye_distance;
    let x = q.x * e / depth / s + f64::from(camera.width) / 2.0;
    let y = q.y * e / depth / s + f64::from(camera.height) / 2.0;
    (x.is_finite() && y.is_finite()).then_some((x, y))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Transform;
    use std::path::Path;

    fn camera(steps: Vec<TransformStep>) -> Camera {
        let mut c = crate::scene::parse(crate::EXAMPLE_SCENE, Path::new("e.xml"))
            .unwrap()
            .camera;
        c.transform = Transform::from_steps(steps).unwrap();
        c
    }

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-12 * (1.0 + a.length())
    }

    #[test]
    fn a_gestures_values_are_the_shortest_decimals_within_its_precision() {
        assert_eq!(shortest_within(-1.2000000000000002, 1e-3), -1.2);
        assert_eq!(shortest_within(0.123456, 1e-3), 0.123);
        assert_eq!(shortest_within(1.27e-14, 1e-6), 0.0);
        assert_eq!(shortest_within(2.5, 0.0), 2.5, "no precision, no rounding");
        // Unmoved, or brought back: the value before, exactly.
        assert_eq!(settle(-2.0000000001, -2.0, 1e-3), -2.0);
        assert_eq!(settle(1.23456789, 1.23456789, 1e-3), 1.23456789);
        assert_eq!(settle(1.9, 1.23456789, 1e-3), 1.9);
    }

    #[test]
    fn orbits_leave_no_float_noise_and_no_identity_steps() {
        let c = camera(vec![TransformStep::Translate(DVec3::new(0.0, -3.0, -8.0))]);
        let start = Pose::of(&c).unwrap();
        // Many small orbits there and back, as a user's drags.
        let mut pose = start;
        let pivot = DVec3::new(1.0, 0.5, 2.0);
        for k in 0..50 {
            pose = pose.orbit(pivot, 0.3, 0.0).orbit(pivot, 0.0, 0.2);
            pose = pose.orbit(pivot, 0.0, -0.2).orbit(pivot, -0.3, 0.0);
            if k % 7 == 0 {
                pose = pose.dolly(DVec3::Z, 0.1).dolly(DVec3::Z, -0.1);
            }
        }
        let raw = pose.steps();
        assert!(raw.len() > 1, "noise there to clean: {raw:?}");
        let settled = settle_steps(&raw, c.transform.steps(), 1e-3, 1e-4);
        assert_eq!(settled, c.transform.steps(), "back where it was: {raw:?}");
        // A real turn: short values, no scale or roll of noise.
        let turned = start.orbit(DVec3::ZERO, 0.5, 0.0);
        let settled = settle_steps(&turned.steps(), c.transform.steps(), 1e-3, 1e-4);
        let text = format!("{settled:?}");
        assert!(
            !settled.iter().any(|s| matches!(
                s,
                TransformStep::UniformScale(_)
                    | TransformStep::RotateZ(_)
                    | TransformStep::RotateX(_)
            )),
            "{text}"
        );
        for step in &settled {
            let values: Vec<f64> = match *step {
                TransformStep::Translate(v) => v.to_array().to_vec(),
                TransformStep::RotateY(a) => vec![a],
                _ => unreachable!(),
            };
            for v in values {
                assert!(crate::scene::edit::number_text(v).len() <= 8, "{text}");
            }
        }
    }

    #[test]
    fn steps_that_do_nothing_are_left_out() {
        let c = camera(vec![TransformStep::Translate(DVec3::new(0.0, 0.0, -20.0))]);
        let pose = Pose::of(&c).unwrap().dolly(DVec3::Z, 5.0);
        assert_eq!(
            pose.steps(),
            vec![TransformStep::Translate(DVec3::new(0.0, 0.0, -15.0))]
        );
        let home = Pose::of(&camera(Vec::new())).unwrap();
        assert_eq!(home.steps(), Vec::new());
    }

    #[test]
    fn steps_give_back_the_pose() {
        for steps in [
            vec![TransformStep::Translate(DVec3::new(0.0, 0.0, -20.0))],
            vec![
                TransformStep::UniformScale(2.5),
                TransformStep::RotateZ(0.3),
                TransformStep::RotateX(-0.4),
                TransformStep::RotateY(2.0),
                TransformStep::Translate(DVec3::new(1.0, -2.0, 3.0)),
            ],
            vec![
                TransformStep::RotateY(0.7),
                TransformStep::RotateX(0.2),
                TransformStep::Translate(DVec3::new(5.0, 0.0, 0.0)),
            ],
        ] {
            let c = camera(steps);
            let pose = Pose::of(&c).unwrap();
            let again = Pose::of(&camera(pose.steps())).unwrap();
            assert!((again.scale - pose.scale).abs() < 1e-12);
            assert!(close(again.position, pose.position));
            for (a, b) in [
                (again.right(), pose.right()),
                (again.down(), pose.down()),
                (again.forward(), pose.forward()),
            ] {
                assert!(close(a, b), "{a} vs {b}");
            }
        }
    }

    #[test]
    fn orbit_keeps_the_distance_to_the_pivot_and_looks_at_it_still() {
        let c = camera(vec![TransformStep::Translate(DVec3::new(0.0, 0.0, -20.0))]);
        let pose = Pose::of(&c).unwrap();
        let pivot = DVec3::ZERO;
        let turned = pose.orbit(pivot, 0.5, 0.2);
        assert!(((turned.position - pivot).length() - 20.0).abs() < 1e-12);
        // The pivot was straight ahead and still is.
        let ahead = (pivot - turned.position).normalize();
        assert!(close(ahead, turned.forward()));
        // A quarter turn of yaw looks along -x... from +x.
        let quarter = pose.orbit(pivot, std::f64::consts::FRAC_PI_2, 0.0);
        assert!(close(quarter.position, DVec3::new(-20.0, 0.0, 0.0)));
    }

    #[test]
    fn pitch_stops_short_of_straight_up_or_down() {
        let c = camera(vec![TransformStep::Translate(DVec3::new(0.0, 0.0, -20.0))]);
        let pose = Pose::of(&c).unwrap().orbit(DVec3::ZERO, 0.0, 3.0);
        let (_, pitch, _) = angles(&pose.rotation);
        assert!((pitch - MAX_PITCH).abs() < 1e-12);
    }

    #[test]
    fn projecting_a_point_of_a_pixels_ray_gives_the_pixel() {
        let c = camera(vec![
            TransformStep::RotateX(-0.3),
            TransformStep::RotateY(0.8),
            TransformStep::Translate(DVec3::new(1.0, -2.0, -15.0)),
        ]);
        let rays = crate::render::CameraRays::new(&c);
        for (x, y) in [(0.5, 0.5), (300.0, 300.0), (599.5, 17.25)] {
            let p = rays.ray(x, y).at(7.5);
            let (u, v) = project(&c, p).unwrap();
            assert!((u - x).abs() < 1e-9 && (v - y).abs() < 1e-9, "{u} {v}");
        }
        // Behind the eye: nowhere.
        let behind = rays.ray(300.0, 300.0).at(-50.0);
        assert_eq!(project(&c, behind), None);
    }

    #[test]
    fn a_sheared_or_squashed_camera_is_refused() {
        let c = camera(vec![TransformStep::Scale(DVec3::new(1.0, 2.0, 1.0))]);
        assert_eq!(Pose::of(&c), Err(NotRigid));
        let c = camera(vec![TransformStep::UniformScale(-1.0)]);
        assert_eq!(Pose::of(&c), Err(NotRigid));
    }
}
