//! What is drawn over the picture: the selected object's outline (from the
//! core's object-id buffer, computed by the worker whenever the selection
//! or the scene changes and the mouse is still), and a marker at
//! each light's projected position, which a drag moves in the view plane
//! (an undoable edit of the light's x, y, z, one step per drag).

use super::{Background, Interaction, RayOfLightApp};
use crate::gui::texture::WHOLE;
use crate::render;
use crate::render::navigate::{GESTURE_PRECISION, moved_on_screen, pixel_at, project, settle_vec};
use crate::scene::edit::{Axis, Edit, Field, Value};
use egui::{Color32, Pos2, Rect, Sense, TextureOptions, Vec2};
use glam::DVec3;
use std::sync::Arc;

/// What is drawn over the picture: the light markers and the selection's
/// outline, shown or hidden (O).
pub(super) struct Overlay {
    /// The light markers drawn in the last frame: light and position.
    pub(super) markers: Vec<(usize, Pos2)>,
    /// The selected object's outline, and what the newest one asked for is.
    pub(super) outline: Option<Outline>,
    pub(super) outline_wanted: Option<(u32, u64)>,
    /// Light markers, the outline and the explained path are drawn (O).
    pub(super) shown: bool,
}

impl Default for Overlay {
    fn default() -> Overlay {
        Overlay {
            markers: Vec::new(),
            outline: None,
            outline_wanted: None,
            shown: true,
        }
    }
}

/// Radius of a light's marker, in points.
const MARKER: f32 = 7.0;

/// The longest side of the object-id buffer behind the outline.
const OUTLINE_SIDE: u32 = 800;

/// The outline of the selected object, ready to draw.
pub(super) struct Outline {
    /// What it was computed for: the object and the render generation of
    /// the scene it was computed on.
    key: (u32, u64),
    texture: egui::TextureHandle,
    /// Outline pixels (for tests).
    pixels: usize,
}

/// A light being dragged.
#[derive(Debug, Clone, Copy)]
pub(super) struct LightDrag {
    light: usize,
    start: DVec3,
    /// World size of one image pixel at the light's depth.
    pixel: f64,
}

impl RayOfLightApp {
    /// The number of outline pixels drawn for the selected object, once
    /// computed (for tests).
    pub fn outline_pixels(&self) -> Option<usize> {
        self.overlay.outline.as_ref().map(|o| o.pixels)
    }

    /// Starts computing the outline when the selection or the scene
    /// changed and nothing is being dragged; drops it when nothing is
    /// selected.
    pub(super) fn refresh_outline(&mut self) {
        let Some(object) = self.selection.object.and_then(|o| u32::try_from(o).ok()) else {
            self.overlay.outline = None;
            self.overlay.outline_wanted = None;
            return;
        };
        let key = (object, self.worker.newest());
        if self.overlay.outline_wanted == Some(key) || self.interacting() {
            return;
        }
        self.overlay.outline_wanted = Some(key);
        let scene = Arc::new(self.doc.scene().clone());
        let longest = scene.camera.width.max(scene.camera.height);
        let scale = longest.div_ceil(OUTLINE_SIDE).max(1);
        let tx = self.background.tx.clone();
        let ctx = self.ctx.clone();
        self.worker.object_ids(scene, scale, move |ids| {
            let _ = tx.send(Background::Ids(key, ids));
            ctx.request_repaint();
        });
    }

    /// The object-id buffer for `key` arrived: its outline becomes a
    /// texture (transparent but for the outline pixels).
    pub(super) fn outline_ready(&mut self, key: (u32, u64), ids: render::ObjectIds) {
        if self.overlay.outline_wanted != Some(key) {
            return;
        }
        let (w, h) = (ids.width, ids.height);
        let mut pixels = 0;
        let mut image = egui::ColorImage::new(
            [w as usize, h as usize],
            vec![Color32::TRANSPARENT; (w * h) as usize],
        );
        for y in 0..h {
            for x in 0..w {
                if ids.is_outline(x, y, key.0) {
                    image.pixels[(y * w + x) as usize] = Color32::from_rgb(255, 140, 0);
                    pixels += 1;
                }
            }
        }
        let texture = self
            .ctx
            .load_texture("selection-outline", image, TextureOptions::NEAREST);
        self.overlay.outline = Some(Outline {
            key,
            texture,
            pixels,
        });
    }

    /// Draws the selected object's outline over the picture at `rect`.
    pub(super) fn draw_outline(&self, painter: &egui::Painter, rect: Rect) {
        if let Some(outline) = &self.overlay.outline
            && self.selection.object.map(|o| o as u32) == Some(outline.key.0)
        {
            painter.image(outline.texture.id(), rect, WHOLE, Color32::WHITE);
        }
    }

    /// Where light `n`'s marker was drawn last, in screen points (for
    /// tests and tools driving the app).
    pub fn light_marker(&self, n: usize) -> Option<Pos2> {
        self.overlay
            .markers
            .iter()
            .find(|(m, _)| *m == n)
            .map(|&(_, pos)| pos)
    }

    /// Draws the light markers and moves a light its marker is dragged.
    /// `to_screen` maps image pixels to screen points; an image pixel is
    /// `image_per_point` screen points.
    pub(super) fn light_markers(
        &mut self,
        ui: &mut egui::Ui,
        area: Rect,
        to_screen: impl Fn(f64, f64) -> Pos2,
        image_per_point: f64,
    ) {
        let scene = self.doc.scene();
        let camera = scene.camera.clone();
        let lights: Vec<(usize, DVec3, Pos2)> = scene
            .lights
            .iter()
            .enumerate()
            .filter_map(|(n, l)| {
                let (x, y) = project(&camera, l.position)?;
                let pos = to_screen(x, y);
                area.contains(pos).then_some((n, l.position, pos))
            })
            .collect();
        let painter = ui.painter_at(area);
        self.overlay.markers = lights.iter().map(|&(n, _, pos)| (n, pos)).collect();
        for (n, position, pos) in lights {
            let id = ui.scope_id().with(("light-marker", n));
            let hit = Rect::from_center_size(pos, Vec2::splat(MARKER * 2.5));
            let response = ui
                .interact(hit, id, Sense::drag())
                .on_hover_text(format!("light {}: drag to move it", n + 1));
            let strong = response.hovered() || response.dragged();
            painter.circle(
                pos,
                MARKER,
                Color32::from_rgb(255, 220, 60),
                egui::Stroke::new(if strong { 2.5 } else { 1.5 }, Color32::BLACK),
            );
            // Selected (the editor's cursor in its element): a ring.
            if self.selection.light == Some(n) {
                painter.circle_stroke(pos, MARKER + 4.0, egui::Stroke::new(2.0, Color32::WHITE));
            }
            painter.text(
                pos + Vec2::new(MARKER + 2.0, -MARKER),
                egui::Align2::LEFT_BOTTOM,
                format!("L{}", n + 1),
                egui::FontId::proportional(12.0),
                Color32::WHITE,
            );
            if response.drag_started() && self.screen.interaction.is_free() {
                self.screen.interaction = Interaction::DraggingLight(LightDrag {
                    light: n,
                    start: position,
                    pixel: pixel_at(&camera, position).unwrap_or(0.0),
                });
            }
            // The light follows the pointer across the view, at its depth
            // (through the camera's projection: any camera, sheared too).
            if response.dragged()
                && let Interaction::DraggingLight(drag) = self.screen.interaction
                && drag.light == n
                && let Some(moved) = {
                    let total = response.total_drag_delta().unwrap_or_default();
                    moved_on_screen(
                        &camera,
                        drag.start,
                        f64::from(total.x) * image_per_point,
                        f64::from(total.y) * image_per_point,
                    )
                }
            {
                // Rounded to a fraction of a pixel there (no float noise in
                // the file); a coordinate the drag left alone keeps its text.
                let moved = settle_vec(moved, drag.start, drag.pixel * GESTURE_PRECISION);
                let edits = [Axis::X, Axis::Y, Axis::Z]
                    .into_iter()
                    .map(|axis| {
                        let value = match axis {
                            Axis::X => moved.x,
                            Axis::Y => moved.y,
                            Axis::Z => moved.z,
                        };
                        Edit::Set(
                            Field::LightPosition { light: n, axis },
                            Value::Number(value),
                        )
                    })
                    .collect();
                match self.doc.apply_step(edits, true) {
                    Ok(()) => self.after_edit(),
                    Err(e) => self.notify(e.to_string()),
                }
            }
            if response.drag_stopped() {
                if matches!(self.screen.interaction, Interaction::DraggingLight(_)) {
                    self.screen.interaction = Interaction::Idle;
                }
                self.doc.end_drag();
            }
        }
    }
}
