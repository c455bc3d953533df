//! Looking around the scene with the mouse: gestures on the picture orbit,
//! pan and dolly the camera ([`crate::render::navigate`]). Each gesture is
//! an edit of the camera's transformation through the document, so it is
//! shown as unsaved, saved with Ctrl+S and undone with Ctrl+Z: a whole drag
//! is one step, and so is a burst of wheel steps with no pause over
//! [`WHEEL_PAUSE`].

use super::*;
use crate::render::navigate::{Pose, pixel_size};
use crate::scene::edit::Edit;
use glam::DVec3;

/// Radians the camera turns per screen point dragged.
const ORBIT_PER_POINT: f64 = 0.01;

/// Wheel steps closer together than this are one undo step.
pub(super) const WHEEL_PAUSE: Duration = Duration::from_millis(500);

/// What a drag on the picture does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Gesture {
    /// Turn the camera around the point under the cursor.
    Orbit,
    /// Move the camera in its view plane.
    Pan,
}

/// A drag of the camera under way.
#[derive(Debug, Clone, Copy)]
pub(super) struct Navigation {
    gesture: Gesture,
    /// The camera when the drag started: each frame moves it from there by
    /// the whole drag, so nothing drifts.
    start: Pose,
    pivot: DVec3,
    /// World size of one image pixel at the pivot's depth.
    pixel: f64,
}

impl RayOfLightApp {
    /// The point seen at image position `at` and its distance from the
    /// eye; where the ray hits nothing, the centre of the spheres (or a
    /// point ahead) at its own distance.
    fn pivot_at(&self, pose: &Pose, at: (f64, f64)) -> (DVec3, f64) {
        let scene = self.doc.scene();
        let eye = pose.eye(scene.camera.eye_distance);
        let prepared = render::prepare(scene, &RenderOptions::default());
        let ray = render::CameraRays::new(&scene.camera).ray(at.0, at.1);
        if let Some(hit) = prepared.nearest_hit(&ray) {
            return (ray.at(hit.t), hit.t);
        }
        let centres: Vec<DVec3> = scene
            .objects
            .iter()
            .filter(|o| o.shape == crate::scene::Shape::Sphere)
            .map(|o| o.transform.to_world().translation)
            .collect();
        let centre = if centres.is_empty() {
            pose.position + pose.forward() * (10.0 * pose.scale)
        } else {
            centres.iter().sum::<DVec3>() / centres.len() as f64
        };
        (centre, (centre - eye).length())
    }

    /// Starts a camera drag at image position `at`. A camera whose
    /// transformation cannot be navigated says why and is left alone.
    pub(super) fn navigation_start(&mut self, gesture: Gesture, at: (f64, f64)) {
        let camera = &self.doc.scene().camera;
        match Pose::of(camera) {
            Ok(start) => {
                let (pivot, distance) = self.pivot_at(&start, at);
                let pixel = pixel_size(camera, distance);
                self.navigation = Some(Navigation {
                    gesture,
                    start,
                    pivot,
                    pixel,
                });
            }
            Err(e) => self.notify(e.to_string()),
        }
    }

    /// The drag has moved `total` screen points since it started; an image
    /// pixel is `image_per_point` of them.
    pub(super) fn navigation_drag(&mut self, total: Vec2, image_per_point: f64) {
        let Some(nav) = self.navigation else {
            return;
        };
        let (dx, dy) = (f64::from(total.x), f64::from(total.y));
        let pose = match nav.gesture {
            // Right turns the scene to the right (the camera goes left);
            // down shows it from higher up.
            Gesture::Orbit => {
                nav.start
                    .orbit(nav.pivot, dx * ORBIT_PER_POINT, -dy * ORBIT_PER_POINT)
            }
            // The point under the cursor follows it.
            Gesture::Pan => {
                let (x, y) = (dx * image_per_point, dy * image_per_point);
                nav.start.pan(-x * nav.pixel, -y * nav.pixel)
            }
        };
        self.set_camera(&pose, true);
    }

    pub(super) fn navigation_end(&mut self) {
        if self.navigation.take().is_some() {
            self.doc.end_drag();
        }
    }

    /// Moves the camera toward the point at image position `at` by a part
    /// of its distance that grows with `scroll` (points; negative moves
    /// away).
    pub(super) fn dolly(&mut self, at: (f64, f64), scroll: f32) {
        let camera = &self.doc.scene().camera;
        let pose = match Pose::of(camera) {
            Ok(pose) => pose,
            Err(e) => return self.notify(e.to_string()),
        };
        let (target, distance) = self.pivot_at(&pose, at);
        let eye = pose.eye(camera.eye_distance);
        let direction = (target - eye).normalize_or_zero();
        let step = distance * (1.0 - (-f64::from(scroll) / 200.0).exp());
        self.set_camera(&pose.dolly(direction, step), true);
        self.wheel_at = Some(Instant::now());
    }

    /// A pause in the wheel ends its undo step.
    pub(super) fn end_wheel_burst(&mut self) {
        if self.wheel_at.is_some_and(|t| t.elapsed() >= WHEEL_PAUSE) {
            self.wheel_at = None;
            self.doc.end_drag();
        }
    }

    /// Back to the camera the file has (Home).
    pub(super) fn camera_from_file(&mut self) {
        let steps = self.doc.file_scene().camera.transform.steps().to_vec();
        if steps.as_slice() != self.doc.scene().camera.transform.steps() {
            self.apply_camera(Edit::CameraTransform(steps), false);
        }
    }

    fn set_camera(&mut self, pose: &Pose, dragging: bool) {
        self.apply_camera(Edit::CameraTransform(pose.steps()), dragging);
    }

    fn apply_camera(&mut self, edit: Edit, dragging: bool) {
        match self.doc.apply_step(vec![edit], dragging) {
            Ok(()) => self.after_edit(),
            Err(e) => self.notify(e.to_string()),
        }
    }
}
