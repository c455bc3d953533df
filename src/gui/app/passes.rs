//! View › Pass: one render pass (a term of the formula, or the normal,
//! depth or object of the camera ray's hit) shown in place of the
//! picture. The pass is rendered by the worker
//! ([`Worker::render_pass`](crate::session::worker::Worker::render_pass): the
//! library's [`render_pass`](crate::render::render_pass), the image's tile
//! loop) once the
//! picture's scene and camera settle, the newest request cancelling the
//! older; the pixel inspector shows its values.

use super::{Background, RayOfLightApp};
use crate::render::{Cancel, Pass, PassImage};
use egui::TextureOptions;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// View › Pass: the pass shown, its picture once rendered, and the
/// renders asked for.
#[derive(Default)]
pub(super) struct Passes {
    pub(super) pass: Pass,
    pub(super) view: Option<PassView>,
    pub(super) requests: PassRequests,
}

/// A pass on screen.
pub(super) struct PassView {
    /// The pass and the render generation it shows.
    key: (Pass, u64),
    pub(super) image: PassImage,
    pub(super) texture: egui::TextureHandle,
}

/// The pass requests: the newest wanted, and a counter that cancels the
/// older ones.
#[derive(Default)]
pub(super) struct PassRequests {
    wanted: Option<(Pass, u64)>,
    newest: Arc<AtomicU64>,
}

impl RayOfLightApp {
    /// Shows `pass` in place of the picture (`Pass::Final`: the picture).
    pub fn show_pass(&mut self, pass: Pass) {
        self.passes.pass = pass;
        if pass == Pass::Final {
            self.passes.view = None;
            self.passes.requests.wanted = None;
            self.passes.requests.newest.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// The pass shown, and its image once rendered for the scene and
    /// camera of the newest picture (until then, and while the camera
    /// moves, the picture shows instead).
    pub fn pass_shown(&self) -> (Pass, Option<&PassImage>) {
        let image = self
            .passes
            .view
            .as_ref()
            .filter(|v| v.key == (self.passes.pass, self.worker.newest()))
            .map(|v| &v.image);
        (self.passes.pass, image)
    }

    /// Renders the pass shown when the scene or camera changed and
    /// nothing is being dragged.
    pub(super) fn refresh_pass(&mut self) {
        if self.passes.pass == Pass::Final {
            return;
        }
        let key = (self.passes.pass, self.worker.newest());
        if self.passes.requests.wanted == Some(key) || self.interacting() {
            return;
        }
        self.passes.requests.wanted = Some(key);
        let generation = self.passes.requests.newest.fetch_add(1, Ordering::Relaxed) + 1;
        let cancel = Cancel::new(Arc::clone(&self.passes.requests.newest), generation);
        let scene = Arc::new(self.doc.scene().clone());
        let request = self.choice.methods.request(false, self.choice.aa);
        let tx = self.background.tx.clone();
        let ctx = self.ctx.clone();
        self.worker
            .render_pass(scene, request, key.0, cancel, move |image| {
                let _ = tx.send(Background::Pass(key, Box::new(image)));
                ctx.request_repaint();
            });
    }

    /// A pass arrived: on screen if it is still the one wanted.
    pub(super) fn pass_ready(&mut self, key: (Pass, u64), image: PassImage) {
        if self.passes.requests.wanted != Some(key) {
            return;
        }
        let shown = image.to_rgb8();
        let (w, h) = shown.dimensions();
        let picture = egui::ColorImage::from_rgb([w as usize, h as usize], shown.as_raw());
        let texture = self
            .ctx
            .load_texture("render-pass", picture, TextureOptions::NEAREST);
        self.passes.view = Some(PassView {
            key,
            image,
            texture,
        });
    }

    /// The texture of the pass shown, when it is rendered for this
    /// picture's size.
    pub(super) fn pass_texture(&self, width: u32, height: u32) -> Option<egui::TextureId> {
        let image = self.pass_shown().1?;
        let view = self.passes.view.as_ref()?;
        ((image.width, image.height) == (width, height)).then(|| view.texture.id())
    }

    /// The inspector's words for pixel (x, y) of the pass shown.
    pub(super) fn pass_value(&self, x: u32, y: u32) -> Option<String> {
        let (pass, Some(image)) = self.pass_shown() else {
            return None;
        };
        let v = image.at(x, y)?;
        let vector = crate::render::explain::vector;
        Some(match pass {
            Pass::Depth if v.x.is_finite() => {
                format!("t = {}", crate::render::explain::number(v.x))
            }
            Pass::Depth => "t = ∞ (nothing hit)".to_owned(),
            Pass::Object if v.x >= 1.0 => self.doc.object_label(v.x as usize - 1),
            Pass::Object => "no object".to_owned(),
            Pass::Normal => format!("N = {}", vector(v)),
            _ => format!("{} {}", pass.name(), vector(v)),
        })
    }

    /// The depth pass's range, for the status bar.
    pub(super) fn depth_range(&self) -> Option<(f64, f64)> {
        self.pass_shown().1?.depth_range()
    }
}
