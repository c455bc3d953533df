//! Moving the camera as a viewport does: orbit around a pivot, pan in the
//! view plane, dolly toward a point (contract section 1's camera).
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
    "the camera's transformation has a non-uniform scale or a shear, which a viewport move would lose: edit its steps in the panel"
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

/// The world size of one pixel at `depth` world units in front of the eye.
///
/// A pixel is s = 2 / min(width, height) camera units on the screen, which
/// is eyeDistance from the eye; by similar triangles (the camera's scale
/// cancels) it is s · depth / eyeDistance at that depth.
pub fn pixel_size(camera: &Camera, depth: f64) -> f64 {
    let s = 2.0 / f64::from(camera.width.min(camera.height));
    s * depth / camera.eye_distance
}

/// Where a world point shows in the picture, in pixels from its top-left
/// corner (the inverse of [`super::CameraRays::ray`]); `None` for a point
/// at or behind the eye.
///
/// In camera space the eye is at (0, 0, −e) and the screen is z = 0: the
/// line from the eye to q meets the screen at q.xy · e / (q.z + e), which is
/// (x − width/2) · s in pixels x.
pub fn project(camera: &Camera, point: DVec3) -> Option<(f64, f64)> {
    let q = camera.transform.to_object().transform_point3(point);
    let e = camera.eye_distance;
    let depth = q.z + e;
    if depth.is_nan() || depth <= 0.0 {
        return None;
    }
    let s = 2.0 / f64::from(camera.width.min(camera.height));
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
