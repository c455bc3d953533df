//! The picture: the render shown 1:1 or fitted, zoom and pan, the pixel
//! under the cursor and the pick of an object by a click.

use super::{RayOfLightApp, navigate};
use crate::gui::panel::Selection;
use crate::gui::texture::WHOLE;
use crate::session::preview::RenderState;
use egui::{Color32, Pos2, Rect, Sense, TextureOptions, Vec2};

/// The picture's part of the window: its textures, how it is viewed, the
/// pixel under the cursor and what the mouse is doing on it.
#[derive(Default)]
pub(super) struct Screen {
    pub(super) texture: crate::gui::texture::PictureTexture,
    /// The coarse pass's picture at its own size (see
    /// [`crate::session::preview::Preview::coarse`]).
    pub(super) coarse_texture: Option<egui::TextureHandle>,
    /// The coarse picture is on screen (until the finer one is uploaded).
    pub(super) showing_coarse: bool,
    pub(super) view: View,
    /// The pixel under the cursor and its colour.
    pub(super) hovered: Option<(u32, u32, [u8; 3])>,
    /// What the mouse is doing on the picture: one thing at a time.
    pub(super) interaction: super::Interaction,
    /// When the wheel last moved the camera, while its undo step is open.
    pub(super) wheel_at: Option<std::time::Instant>,
    /// Where the picture was drawn in the last frame.
    pub(super) shown_at: Option<Rect>,
}

/// How the picture is placed in the central area.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct View {
    /// Screen pixels per image pixel (1 = 1:1, crisp).
    zoom: f32,
    /// Offset of the picture's centre from the area's centre, in points.
    pan: Vec2,
    /// Keep the whole picture in view as the window changes.
    fit: bool,
}

impl View {
    /// Keep the whole picture in view.
    pub(super) fn fit() -> View {
        View::default()
    }

    /// One image pixel per screen pixel, centred.
    pub(super) fn one_to_one() -> View {
        View {
            fit: false,
            ..View::default()
        }
    }

    /// Zooms by `factor`, within 1/64 to 64 screen pixels per image pixel.
    pub(super) fn zoom_by(&mut self, factor: f32) {
        self.zoom = (self.zoom * factor).clamp(1.0 / 64.0, 64.0);
        self.fit = false;
    }
}

impl Default for View {
    fn default() -> Self {
        View {
            zoom: 1.0,
            pan: Vec2::ZERO,
            fit: true,
        }
    }
}

impl RayOfLightApp {
    pub(super) fn picture(&mut self, ui: &mut egui::Ui) {
        egui::CentralPanel::default().show(ui, |ui| {
            self.error_banner(ui.ctx(), ui.available_rect_before_wrap());
            let (cleared, dirty) = self.preview.take_dirty();
            // At the zoom of the last frame (one frame late when it
            // changes).
            self.screen.texture.update(
                ui.ctx(),
                self.preview.image(),
                cleared,
                dirty,
                self.screen.view.zoom,
            );
            // A coarse pass shows at its own size, stretched, and stays on
            // screen until the finer picture is wholly uploaded.
            let coarse_dirty = self.preview.take_coarse_dirty();
            if let Some(coarse) = self.preview.coarse() {
                if coarse_dirty || self.screen.coarse_texture.is_none() {
                    let (w, h) = coarse.image.dimensions();
                    let image =
                        egui::ColorImage::from_rgb([w as usize, h as usize], coarse.image.as_raw());
                    match &mut self.screen.coarse_texture {
                        Some(t) => t.set(image, TextureOptions::NEAREST),
                        None => {
                            self.screen.coarse_texture = Some(ui.ctx().load_texture(
                                "render-coarse",
                                image,
                                TextureOptions::NEAREST,
                            ))
                        }
                    }
                }
                self.screen.showing_coarse = true;
            } else if self.screen.texture.complete() {
                self.screen.showing_coarse = false;
            }
            let (w, h) = self.preview.image().dimensions();
            // A render pass (View › Pass) in place of the picture, once
            // rendered at the picture's size.
            let (texture, uv) = match (&self.screen.coarse_texture, self.pass_texture(w, h)) {
                (_, Some(pass)) => (pass, WHOLE),
                (Some(t), None) if self.screen.showing_coarse => (t.id(), WHOLE),
                _ => match self.screen.texture.shown() {
                    Some(shown) => shown,
                    None => return,
                },
            };
            let area = ui.available_rect_before_wrap();
            let response = ui.allocate_rect(area, Sense::click_and_drag());
            let image_size = Vec2::new(w as f32, h as f32);
            let ppp = ui.ctx().pixels_per_point();
            if self.screen.view.fit {
                let fit = (area.width() / image_size.x).min(area.height() / image_size.y) * ppp;
                // Whole steps when enlarging keep pixels square and crisp.
                self.screen.view.zoom = if fit >= 1.0 { fit.floor() } else { fit };
                self.screen.view.pan = Vec2::ZERO;
            }
            let size = image_size * self.screen.view.zoom / ppp;
            let rect = Rect::from_center_size(area.center() + self.screen.view.pan, size);
            // Snap to physical pixels so 1:1 stays crisp.
            let rect = Rect::from_min_size(
                Pos2::new(
                    (rect.min.x * ppp).round() / ppp,
                    (rect.min.y * ppp).round() / ppp,
                ),
                size,
            );
            self.screen.shown_at = Some(rect);
            // Image pixels (x, y) under a screen position.
            let to_image = |pos: Pos2| {
                let rel = (pos - rect.min) / size * image_size;
                (f64::from(rel.x), f64::from(rel.y))
            };
            let image_per_point = f64::from(image_size.x / size.x);
            // A click that places a moved object selects nothing.
            let grabbing = self.screen.interaction.is_grabbing();
            self.gestures(ui, &response, to_image, image_per_point);
            let painter = ui.painter_at(area);
            painter.image(texture, rect, uv, Color32::WHITE);
            if self.overlay.shown {
                self.draw_outline(&painter, rect);
            }
            // Pixel inspector, pick and explain (E then a click, or
            // Alt+click).
            self.screen.hovered = None;
            let alt = ui.input(|i| i.modifiers.alt);
            if let Some(pos) = response.hover_pos() {
                let rel = (pos - rect.min) / size * image_size;
                if rel.x >= 0.0 && rel.y >= 0.0 && rel.x < image_size.x && rel.y < image_size.y {
                    let (x, y) = (rel.x as u32, rel.y as u32);
                    let rgb = self.preview.image().get_pixel(x, y).0;
                    self.screen.hovered = Some((x, y, rgb));
                    if self.screen.interaction.is_explain_armed() {
                        ui.ctx().set_cursor_icon(egui::CursorIcon::Crosshair);
                    }
                    if response.clicked() && !grabbing {
                        if self.screen.interaction.is_explain_armed() || alt {
                            self.explain_pixel(x, y);
                        } else {
                            self.pick(f64::from(rel.x), f64::from(rel.y));
                        }
                    }
                }
            }
            let to_screen =
                |x: f64, y: f64| rect.min + Vec2::new(x as f32, y as f32) / image_size * size;
            if self.overlay.shown {
                self.draw_explained_path(&painter.with_clip_rect(rect.intersect(area)), to_screen);
            }
            // Markers belong on a picture of the camera's size (not the
            // blank one shown before the first render, nor an old size).
            let camera = &self.doc.scene().camera;
            if self.overlay.shown && (w, h) == (camera.width, camera.height) {
                self.light_markers(ui, area, to_screen, image_per_point);
            } else {
                self.overlay.markers.clear();
            }
        });
    }

    /// What the mouse does on the picture: a drag orbits the camera
    /// (Shift or the middle button: pans it), the wheel dollies it toward
    /// the point under the cursor; with Ctrl, the drag and the wheel pan and
    /// zoom the picture instead. A click without a drag selects.
    fn gestures(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        to_image: impl Fn(Pos2) -> (f64, f64),
        image_per_point: f64,
    ) {
        let (modifiers, scroll, zoom, middle, press) = ui.input(|i| {
            (
                i.modifiers,
                i.smooth_scroll_delta.y,
                i.zoom_delta(),
                i.pointer.middle_down(),
                i.pointer.press_origin(),
            )
        });
        if response.hovered() {
            if modifiers.command || zoom != 1.0 {
                let factor = zoom * (scroll / 200.0).exp();
                if factor != 1.0 {
                    self.screen.view.zoom_by(factor);
                }
            } else if scroll != 0.0
                && let Some(pos) = response.hover_pos()
            {
                self.dolly(to_image(pos), scroll);
            }
        }
        // An object being moved follows the pointer; a click places it, a
        // right click puts it back.
        if self.screen.interaction.is_grabbing() {
            if let Some(pos) = response.hover_pos().or(response.interact_pointer_pos()) {
                self.grab_move(pos, image_per_point);
            }
            if response.secondary_clicked() {
                self.grab_end(false);
            } else if response.clicked() || response.drag_stopped() {
                self.grab_end(true);
            }
            return;
        }
        if response.drag_started() && modifiers.alt {
            self.grab_start(press);
            return;
        }
        if response.drag_started() && !modifiers.command {
            let gesture = if modifiers.shift || middle {
                navigate::Gesture::Pan
            } else {
                navigate::Gesture::Orbit
            };
            let at = press.or(response.interact_pointer_pos()).map(&to_image);
            if let Some(at) = at {
                self.navigation_start(gesture, at);
            }
        }
        if response.dragged() {
            if self.screen.interaction.is_navigating() {
                let total = response
                    .interact_pointer_pos()
                    .zip(press)
                    .map_or(Vec2::ZERO, |(now, start)| now - start);
                self.navigation_drag(total, image_per_point);
            } else if modifiers.command {
                self.screen.view.pan += response.drag_delta();
                self.screen.view.fit = false;
            }
        }
        if response.drag_stopped() {
            self.navigation_end();
        }
    }

    /// Selects the object seen at image position (`x`, `y`) and opens it
    /// in the panel, once (a click in the picture), and asks the user's
    /// editors to show its element. The pick is made in the scene the
    /// worker prepared for the picture; until it has prepared this one (it
    /// is rendering it), the pick waits for it.
    pub fn pick(&mut self, x: f64, y: f64) {
        match self.worker.prepared(self.doc.scene()) {
            Some(prepared) => {
                let object = prepared.pick(x, y);
                self.selection = Selection::revealed(object);
                if let Some(n) = object {
                    self.show_in_editors(n);
                }
            }
            None => self.explain.waiting = Some(Waiting::Pick(x, y)),
        }
    }

    /// Asks the editors linked to this app to show object `n`'s element,
    /// without taking the focus from the window; an object added in the
    /// panel since the file was read is not in their text.
    fn show_in_editors(&mut self, n: usize) {
        let (Some(path), Some(object)) = (self.doc.path(), self.doc.object_in_text(n)) else {
            return;
        };
        self.editors
            .peers
            .tell(&crate::desktop::editor_link::Message::Show {
                path: path.to_owned(),
                object,
            });
    }

    /// A pick or an explain that waited for the worker to prepare the
    /// scene: made once it has, else it waits a frame more, unless no
    /// render will prepare it (the newest was cancelled or failed): then
    /// it is dropped, and a notice says why.
    pub(super) fn retry_waiting(&mut self, ctx: &egui::Context) {
        let Some(waiting) = self.explain.waiting.take() else {
            return;
        };
        match waiting {
            Waiting::Pick(x, y) => self.pick(x, y),
            Waiting::Explain(x, y) => self.explain_pixel(x, y),
        }
        if self.explain.waiting.is_none() {
            return;
        }
        let why = match self.preview.state() {
            RenderState::Cancelled => "the render was cancelled (Esc); F5 renders again",
            RenderState::Failed(_) => "the render failed",
            _ => {
                ctx.request_repaint_after(crate::session::worker::FRAME);
                return;
            }
        };
        self.explain.waiting = None;
        let what = match waiting {
            Waiting::Pick(..) => "nothing picked",
            Waiting::Explain(..) => "nothing explained",
        };
        self.notify(format!("{what}: {why}"));
    }

    /// Whether a pick or an explain waits for the worker to prepare the
    /// scene on screen (for tests and tools driving the app).
    pub fn waits_for_the_worker(&self) -> bool {
        self.explain.waiting.is_some()
    }
}

/// What waits for the worker to prepare the scene on screen: the UI
/// thread never prepares one (a million objects take a second).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Waiting {
    /// A pick at this image position.
    Pick(f64, f64),
    /// Explaining this pixel.
    Explain(u32, u32),
}
