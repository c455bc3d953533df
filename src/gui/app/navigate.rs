//! Looking around the scene and moving things with the mouse: gestures on
//! the picture orbit, pan and dolly the camera ([`crate::render::navigate`]),
//! and `G` (or Alt+drag) moves the selected object in the view plane. Each
//! gesture is an edit of a transformation through the document, so it is
//! shown as unsaved, saved with Ctrl+S and undone with Ctrl+Z: a whole drag
//! is one step, and so is a burst of wheel steps with no pause over
//! [`WHEEL_PAUSE`].

use super::{Interaction, RayOfLightApp};
use crate::math::TransformStep;
use crate::render;
use crate::render::navigate::{
    GESTURE_PRECISION, Pose, moved_on_screen, pixel_angle, pixel_at, pixel_size, settle_steps,
};
use crate::scene::edit::{Edit, Owner};
use egui::{Pos2, Vec2};
use glam::DVec3;
use std::time::{Duration, Instant};

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
#[derive(Debug, Clone)]
pub(super) struct Navigation {
    gesture: Gesture,
    /// The camera when the drag started: each frame moves it from there by
    /// the whole drag, so nothing drifts.
    start: Pose,
    /// Its steps then: values the drag leaves within a fraction of a pixel
    /// keep their text.
    start_steps: Vec<TransformStep>,
    pivot: DVec3,
    /// World size of one image pixel at the pivot's depth.
    pixel: f64,
}

/// The selected object being moved (`G`, or Alt+drag), as in Blender: the
/// mouse moves it in the view plane, a click confirms, Esc or a right
/// click puts it back.
#[derive(Debug, Clone)]
pub(super) struct Grab {
    object: usize,
    /// Its steps when the move started.
    start: Vec<TransformStep>,
    /// Where the pointer was when the move started (set at its first
    /// position over the picture).
    pointer: Option<Pos2>,
    /// Its centre in world space when the move started.
    centre: DVec3,
    /// World size of one image pixel at the object's depth.
    pixel: f64,
}

impl RayOfLightApp {
    /// Starts moving the selected object; `pointer` is where the mouse is,
    /// if over the picture.
    pub(super) fn grab_start(&mut self, pointer: Option<Pos2>) {
        if !self.screen.interaction.is_free() {
            return;
        }
        let Some(object) = self.selection.object else {
            return self.notify("select an object first (click it), then G moves it".into());
        };
        let scene = self.doc.scene();
        let Some(o) = scene.objects.get(object) else {
            return;
        };
        let centre = o.transform.to_world().translation;
        // Through the camera's projection: any camera, sheared too.
        let Some(pixel) = pixel_at(&scene.camera, centre) else {
            return self.notify("the object is behind the eye: it cannot follow the mouse".into());
        };
        self.screen.interaction = Interaction::Grabbing(Grab {
            object,
            start: o.transform.steps().to_vec(),
            pointer,
            centre,
            pixel,
        });
        self.notify("moving: click to place, Esc or right click to cancel".into());
    }

    /// The pointer is at `pointer`: the object follows it. An image pixel
    /// is `image_per_point` screen points.
    pub(super) fn grab_move(&mut self, pointer: Pos2, image_per_point: f64) {
        let Interaction::Grabbing(grab) = &mut self.screen.interaction else {
            return;
        };
        let start = *grab.pointer.get_or_insert(pointer);
        let total = pointer - start;
        let camera = &self.doc.scene().camera;
        let Some(moved) = moved_on_screen(
            camera,
            grab.centre,
            f64::from(total.x) * image_per_point,
            f64::from(total.y) * image_per_point,
        ) else {
            return;
        };
        let delta = moved - grab.centre;
        let mut steps = grab.start.clone();
        // World moves come last: a trailing translate takes them, or one is
        // added.
        match steps.last_mut() {
            Some(TransformStep::Translate(t)) => *t += delta,
            _ => steps.push(TransformStep::Translate(delta)),
        }
        if total == Vec2::ZERO {
            return;
        }
        // Rounded to a fraction of a pixel there: no float noise written.
        let camera = &self.doc.scene().camera;
        let steps = settle_steps(
            &steps,
            &grab.start,
            grab.pixel * GESTURE_PRECISION,
            pixel_angle(camera) * GESTURE_PRECISION,
        );
        let edit = Edit::Transform(Owner::Object(grab.object), steps);
        match self.doc.apply_step(vec![edit], true) {
            Ok(()) => self.after_edit(),
            Err(e) => self.notify(e.to_string()),
        }
    }

    /// Ends the move: kept, or put back as it was.
    pub(super) fn grab_end(&mut self, keep: bool) {
        let grab = match std::mem::take(&mut self.screen.interaction) {
            Interaction::Grabbing(grab) => grab,
            other => return self.screen.interaction = other,
        };
        let moved = self
            .doc
            .scene()
            .objects
            .get(grab.object)
            .map(|o| o.transform.steps())
            != Some(grab.start.as_slice());
        if moved && !keep {
            self.doc.undo();
            self.after_edit();
        }
        self.doc.end_drag();
        self.notify(if keep { "moved" } else { "move cancelled" }.into());
    }

    /// The point seen at image position `at` and its distance from the
    /// eye (in the scene the worker prepared); where the ray hits nothing,
    /// or the worker has not prepared this scene yet, the centre of the
    /// spheres (or a point ahead) at its own distance.
    fn pivot_at(&self, pose: &Pose, at: (f64, f64)) -> (DVec3, f64) {
        let scene = self.doc.scene();
        let eye = pose.eye(scene.camera.eye_distance);
        let ray = render::CameraRays::new(&scene.camera).ray(at.0, at.1);
        if let Some(prepared) = self.worker.prepared(scene)
            && let Some(hit) = prepared.nearest_hit(&ray)
        {
            return (ray.at(hit.t), hit.t);
        }
        let centres: Vec<DVec3> = scene
            .objects
            .iter()
            .filter(|o| o.shape.is_bounded())
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
                self.screen.interaction = Interaction::Navigating(Navigation {
                    gesture,
                    start,
                    start_steps: camera.transform.steps().to_vec(),
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
        let Interaction::Navigating(nav) = self.screen.interaction.clone() else {
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
        self.set_camera(&pose, &nav.start_steps, nav.pixel, true);
    }

    pub(super) fn navigation_end(&mut self) {
        if self.screen.interaction.is_navigating() {
            self.screen.interaction = Interaction::Idle;
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
        let (before, pixel) = (
            camera.transform.steps().to_vec(),
            pixel_size(camera, (distance - step).abs()),
        );
        self.set_camera(&pose.dolly(direction, step), &before, pixel, true);
        self.screen.wheel_at = Some(Instant::now());
    }

    /// A pause in the wheel ends its undo step.
    pub(super) fn end_wheel_burst(&mut self) {
        if self
            .screen
            .wheel_at
            .is_some_and(|t| t.elapsed() >= WHEEL_PAUSE)
        {
            self.screen.wheel_at = None;
            self.doc.end_drag();
        }
    }

    /// Back to the camera the file has (Home).
    pub(super) fn camera_from_file(&mut self) {
        let steps = self.doc.file_scene().camera.transform.steps().to_vec();
        if steps.as_slice() != self.doc.scene().camera.transform.steps() {
            self.apply_camera(Edit::Transform(Owner::Camera, steps), false);
        }
    }

    /// Moves the camera to `pose`, from the steps `before` the gesture:
    /// rounded to a fraction of a `pixel` (the world size of one at the
    /// point the gesture holds) and of a pixel's angle, values left within
    /// that keeping their text ([`settle_steps`]). The rounded camera is
    /// the one applied, so the saved file renders what is shown.
    fn set_camera(&mut self, pose: &Pose, before: &[TransformStep], pixel: f64, dragging: bool) {
        let camera = &self.doc.scene().camera;
        let steps = settle_steps(
            &pose.steps(),
            before,
            pixel * GESTURE_PRECISION,
            pixel_angle(camera) * GESTURE_PRECISION,
        );
        self.apply_camera(Edit::Transform(Owner::Camera, steps), dragging);
    }

    fn apply_camera(&mut self, edit: Edit, dragging: bool) {
        match self.doc.apply_step(vec![edit], dragging) {
            Ok(()) => self.after_edit(),
            Err(e) => self.notify(e.to_string()),
        }
    }
}
