//! Explain a pixel: `E` (View › Explain pixel) then a click, or Alt+click,
//! opens a window with the pixel's ray tree from the library
//! ([`crate::render::Prepared::explain`]: the render's own numbers), and
//! draws the path over the picture. Clicking a term selects the object
//! and the coefficient it comes from in the panel. The worker traces the
//! tree ([`crate::session::worker::Worker::explain`]); the window goes on
//! drawing meanwhile, and the newest explain asked for wins.

use super::{Interaction, RayOfLightApp, picture};
use crate::gui::panel::Selection;
use crate::render::explain::{Bounce, Sample, describe_ray, number, vector};
use crate::render::{Explanation, navigate};
use crate::scene::edit::{Coef, Field};
use crate::session::preview::RenderState;
use egui::{Color32, Pos2, Vec2};
use glam::DVec3;
use std::collections::BTreeMap;

/// The explain part: the pixel explained in its window, the one the worker
/// is tracing, and a pick or explain waiting for the scene to be prepared.
#[derive(Default)]
pub(super) struct ExplainState {
    pub(super) explained: Option<Shown>,
    pub(super) explaining: Option<Explaining>,
    pub(super) waiting: Option<picture::Waiting>,
}

/// The explained pixel on screen.
pub(super) struct Shown {
    pub(super) explanation: Explanation,
    /// The panel's names of the objects its rays hit (only those: a
    /// scene may hold a million).
    labels: BTreeMap<usize, String>,
    /// Which ray's tree is shown (supersampled pixels have several).
    sample: usize,
    /// The render generation it explains.
    generation: u64,
}

/// An explain the worker is tracing.
pub(super) struct Explaining {
    /// Which request it is: an answer to an older one is dropped.
    id: u64,
    /// The render generation it explains.
    generation: u64,
}

/// Which coefficient a term comes from.
fn term_field(object: usize, term: usize) -> Field {
    let coef = match term {
        0 => Coef::Ka,
        1 => Coef::Kd,
        _ => Coef::Ks,
    };
    Field::Material { object, coef }
}

impl RayOfLightApp {
    /// Explains pixel (x, y) of the picture: its tree in the window, its
    /// path over the picture.
    pub fn explain_pixel(&mut self, x: u32, y: u32) {
        if self.screen.interaction.is_explain_armed() {
            self.screen.interaction = Interaction::Idle;
        }
        let scene = self.doc.scene();
        // The worker's prepared scene (the method of the picture, its
        // rays per pixel); until it has prepared this scene (it is
        // rendering it), the explain waits for it.
        let Some(prepared) = self.worker.prepared(scene) else {
            self.explain.waiting = Some(picture::Waiting::Explain(x, y));
            return;
        };
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        let id = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.explain.explaining = Some(Explaining {
            id,
            generation: self.worker.newest(),
        });
        let (tx, ctx) = (self.background.tx.clone(), self.ctx.clone());
        self.worker.explain(prepared, (x, y), move |explanation| {
            let _ = tx.send(super::Background::Explained(id, explanation.map(Box::new)));
            ctx.request_repaint();
        });
    }

    /// The worker's answer to explain request `id`: shown if it is the
    /// newest asked for.
    pub(super) fn explained(&mut self, id: u64, explanation: Option<Box<Explanation>>) {
        let Some(explaining) = self.explain.explaining.take_if(|e| e.id == id) else {
            return;
        };
        let Some(explanation) = explanation else {
            // Outside the picture (it shrank).
            self.explain.explained = None;
            return;
        };
        let explanation = *explanation;
        let sample = self.explain.explained.as_ref().map_or(0, |s| s.sample);
        let sample = sample.min(explanation.samples.len() - 1);
        let labels = explanation
            .samples
            .iter()
            .flat_map(|s| &s.bounces)
            .map(|b| (b.object, self.doc.object_label(b.object)))
            .collect();
        self.explain.explained = Some(Shown {
            explanation,
            labels,
            sample,
            generation: explaining.generation,
        });
    }

    /// Whether the worker is tracing a pixel to explain (for tests and
    /// tools driving the app).
    pub fn is_explaining(&self) -> bool {
        self.explain.explaining.is_some()
    }

    /// Once the picture of an edited scene (or a moved camera) is done,
    /// the same pixel is explained again: the numbers follow the edits.
    pub(super) fn refresh_explained(&mut self) {
        let Some(shown) = &self.explain.explained else {
            return;
        };
        let newest = self.worker.newest();
        let done = matches!(self.preview.state(), RenderState::Done { .. })
            && self.preview.generation() == newest;
        if shown.generation != newest
            && done
            && !self.interacting()
            && self.explain.explaining.is_none()
        {
            let (x, y) = (shown.explanation.x, shown.explanation.y);
            let armed = self.screen.interaction.is_explain_armed();
            self.explain_pixel(x, y);
            if armed {
                self.screen.interaction = Interaction::ExplainArmed;
            }
        }
    }

    /// The pixel explained in the window, if any.
    pub fn explanation(&self) -> Option<&Explanation> {
        self.explain.explained.as_ref().map(|s| &s.explanation)
    }

    /// The window of the explained pixel.
    pub(super) fn explain_window(&mut self, ctx: &egui::Context) {
        // The pixel of the finished picture of the scene explained.
        let on_screen = self.explain.explained.as_ref().and_then(|shown| {
            let done = matches!(self.preview.state(), RenderState::Done { .. })
                && self.preview.generation() == shown.generation;
            let (x, y) = (shown.explanation.x, shown.explanation.y);
            let image = self.preview.image();
            (done && x < image.width() && y < image.height()).then(|| image.get_pixel(x, y).0)
        });
        let Some(shown) = &mut self.explain.explained else {
            return;
        };
        let mut open = true;
        let mut select = None;
        let e = &shown.explanation;
        // At the right, clear of the panel.
        let right = ctx.content_rect().right_top() + Vec2::new(-420.0, 40.0);
        egui::Window::new("Explain pixel")
            .open(&mut open)
            .default_pos(right)
            .default_width(400.0)
            .default_height(560.0)
            .show(ctx, |ui| {
                let [r, g, b] = e.rgb8;
                ui.strong(format!("Pixel ({}, {}): ({r}, {g}, {b})", e.x, e.y));
                ui.label(format!(
                    "{} model · unclamped {}",
                    e.illumination.name(),
                    vector(e.rgb)
                ));
                if let Some(note) = e.draft_note() {
                    ui.label(note);
                }
                if let Some(pixel) = on_screen
                    && pixel != e.rgb8
                {
                    // Not expected: the explained value is the render's.
                    ui.colored_label(Color32::YELLOW, format!("on screen: {pixel:?}"));
                }
                if e.samples.len() > 1 {
                    ui.horizontal(|ui| {
                        ui.label("ray");
                        let count = e.samples.len();
                        ui.add(
                            egui::DragValue::new(&mut shown.sample)
                                .range(0..=count - 1)
                                .custom_formatter(|v, _| format!("{} of {count}", v as usize + 1)),
                        );
                        ui.label("(the pixel is the mean of its rays, each clamped)");
                    });
                }
                let sample = &e.samples[shown.sample.min(e.samples.len() - 1)];
                egui::ScrollArea::vertical()
                    .max_height(480.0)
                    .show(ui, |ui| {
                        select = sample_ui(ui, sample, &shown.labels);
                    });
            });
        if let Some((object, field)) = select {
            self.selection = Selection {
                field,
                ..Selection::revealed(Some(object))
            };
        }
        if !open {
            self.explain.explained = None;
        }
    }

    /// The explained pixel's path over the picture: its hit points, and
    /// the segments between them that are in front of the eye.
    pub(super) fn draw_explained_path(
        &self,
        painter: &egui::Painter,
        to_screen: impl Fn(f64, f64) -> Pos2,
    ) {
        let Some(shown) = &self.explain.explained else {
            return;
        };
        let e = &shown.explanation;
        let sample = &e.samples[shown.sample.min(e.samples.len() - 1)];
        let camera = &self.doc.scene().camera;
        let on_screen = |p: DVec3| navigate::project(camera, p).map(|(x, y)| to_screen(x, y));
        let stroke = egui::Stroke::new(2.0, Color32::from_rgb(255, 200, 0));
        let mut points: Vec<DVec3> = sample.bounces.iter().map(|b| b.point).collect();
        if let Some(ray) = &sample.missed {
            // Off to the sky: far along the ray.
            let far = 1e3
                * (ray.origin - sample.bounces.first().map_or(ray.origin, |b| b.ray.origin))
                    .length()
                    .max(1.0);
            points.push(ray.at(far));
        }
        for pair in points.windows(2) {
            if let Some((a, b)) = clip_in_front(camera, pair[0], pair[1])
                && let (Some(a), Some(b)) = (on_screen(a), on_screen(b))
            {
                painter.line_segment([a, b], stroke);
            }
        }
        let pixel = to_screen(sample.at.0, sample.at.1);
        painter.circle_stroke(pixel, 5.0, stroke);
        for (k, b) in sample.bounces.iter().enumerate() {
            if let Some(p) = on_screen(b.point) {
                painter.circle_filled(p, 3.5, stroke.color);
                painter.text(
                    p + Vec2::new(6.0, -6.0),
                    egui::Align2::LEFT_BOTTOM,
                    format!("{}", k + 1),
                    egui::FontId::proportional(12.0),
                    stroke.color,
                );
            }
        }
    }
}

/// The part of segment a–b in front of the camera's eye (both ends
/// project), if any.
fn clip_in_front(camera: &crate::scene::Camera, a: DVec3, b: DVec3) -> Option<(DVec3, DVec3)> {
    let sees = |p: DVec3| navigate::project(camera, p).is_some();
    match (sees(a), sees(b)) {
        (true, true) => Some((a, b)),
        (false, false) => None,
        (seen_a, _) => {
            // Halve toward the last point still in front.
            let (mut inside, mut outside) = if seen_a { (a, b) } else { (b, a) };
            for _ in 0..40 {
                let mid = (inside + outside) * 0.5;
                if sees(mid) {
                    inside = mid;
                } else {
                    outside = mid;
                }
            }
            Some(if seen_a { (a, inside) } else { (inside, b) })
        }
    }
}

/// One ray's tree; returns the object (and field) a click chose.
fn sample_ui(
    ui: &mut egui::Ui,
    sample: &Sample,
    labels: &BTreeMap<usize, String>,
) -> Option<(usize, Option<Field>)> {
    let mut chosen = None;
    for (k, bounce) in sample.bounces.iter().enumerate() {
        ui.separator();
        ui.strong(describe_ray(k, &bounce.ray));
        if let Some(c) = bounce_ui(ui, bounce, labels) {
            chosen = Some(c);
        }
    }
    if let Some(ray) = &sample.missed {
        ui.separator();
        let ray = describe_ray(sample.bounces.len(), ray);
        ui.strong(format!("{ray}: hits nothing (black)"));
    }
    ui.separator();
    ui.label(format!("Chain ended: {}", sample.ended.describe()));
    chosen
}

fn bounce_ui(
    ui: &mut egui::Ui,
    b: &Bounce,
    labels: &BTreeMap<usize, String>,
) -> Option<(usize, Option<Field>)> {
    let mut chosen = None;
    let label = labels.get(&b.object).cloned().unwrap_or_default();
    ui.horizontal(|ui| {
        ui.label("hits");
        if ui
            .link(&label)
            .on_hover_text("select it in the panel")
            .clicked()
        {
            chosen = Some((b.object, None));
        }
        ui.label(format!("at t = {}", number(b.t)));
    });
    ui.label(format!("M = {}  N = {}", vector(b.point), vector(b.normal)));
    for l in &b.lights {
        ui.label(l.describe());
    }
    egui::Grid::new(("terms", b.object, b.t.to_bits()))
        .num_columns(2)
        .show(ui, |ui| {
            let terms = [
                ("ambient  ka·C", b.terms.ambient),
                ("diffuse  Σ I·kd·cos θ", b.terms.diffuse),
                ("specular  Σ I·ks·cos^m α", b.terms.specular),
                ("reflection  ks·Ir", b.reflection),
            ];
            for (term, (name, value)) in terms.into_iter().enumerate() {
                let hint = ["ka", "kd", "ks", "ks"][term];
                if ui
                    .link(name)
                    .on_hover_text(format!("select {hint} of {label} in the panel"))
                    .clicked()
                {
                    chosen = Some((b.object, Some(term_field(b.object, term))));
                }
                ui.monospace(vector(value));
                ui.end_row();
            }
            ui.strong("colour");
            ui.monospace(vector(b.color));
            ui.end_row();
        });
    chosen
}
