//! The Study window: the study of the current scene, run by the worker.
//!
//! It owns the window's state (the study's progress and rows, the failure
//! pictures), takes the worker's study events, and draws the progress, the
//! table and the choice of method; the interactive chart and its legend are
//! in [`plot`]. A failing row opens its side-by-side picture. It also
//! holds the choice of method for the live preview: `auto` by default, any
//! method of the study, and optionally a cheaper one while a value is being
//! dragged (the exact one renders again on release). The window only keeps state and reports
//! what the user asked for as [`Action`]s; the app talks to the worker.

mod plot;

use crate::render::request::RenderRequest;
use crate::render::{self, Decision, Method};
use crate::scene::Scene;
use crate::session::worker::Event;
use crate::study::{self, Row, Stage, StudyProgress};
use egui::{Color32, RichText, TextureHandle, TextureOptions};
use image::RgbImage;
use std::sync::Arc;
use std::time::Duration;

/// The progress bar's share and words while a study runs, `done` of
/// `total` methods measured: the references first (a minute on a large
/// scene, before any method), then each method, run after run, with the
/// pixels of the render under way (`(done, all)`).
fn running(stage: Stage, pixels: (u64, u64), done: usize, total: usize) -> (f32, String) {
    let within = match pixels {
        (_, 0) => 0.0,
        (done, all) => done as f32 / all as f32,
    };
    let percent = (within * 100.0).floor();
    match stage {
        Stage::Waiting => (0.0, "starting".to_owned()),
        Stage::Reference { supersampled } => (
            within,
            format!(
                "the reference{}: {percent} %",
                if supersampled { ", 16×16 samples" } else { "" }
            ),
        ),
        Stage::Method {
            index,
            of,
            name,
            run,
            runs,
        } => {
            // Each run of a method its share of the method's.
            let method = (run as f32 + within) / runs.max(1) as f32;
            let which = match runs {
                0 | 1 => String::new(),
                runs => format!(", run {} of {runs}", run + 1),
            };
            (
                (index as f32 + method) / of.max(1) as f32,
                format!("{done} of {total} methods; {name}{which}: {percent} %"),
            )
        }
    }
}

/// What the user asked for in the window.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Action {
    Run,
    Cancel,
    /// Render the live preview with this method.
    Preview(&'static str),
    /// While dragging a value, render with this method (`None`: the
    /// preview's own).
    WhileDragging(Option<&'static str>),
}

#[derive(Debug, Clone, PartialEq)]
pub enum StudyState {
    Idle,
    Running { done: usize, total: usize },
    Done(Duration),
    Stopped(String),
}

/// The live preview's methods: its own, and the one while a value is
/// dragged (`None`: its own).
#[derive(Debug, Clone, PartialEq)]
pub struct PreviewMethods {
    /// The method of the live preview (auto unless chosen).
    pub preview: Method,
    pub dragging: Option<Method>,
}

impl Default for PreviewMethods {
    fn default() -> Self {
        PreviewMethods {
            preview: render::method("auto").expect("the study has an auto method"),
            dragging: None,
        }
    }
}

impl PreviewMethods {
    /// What to render with, `dragging` or not, at the preview's
    /// anti-aliasing `aa` (View › Anti-aliasing: above 1×1 it is asked for
    /// and wins over the method's, see [`crate::render::request`]).
    pub fn request(&self, dragging: bool, aa: u32) -> RenderRequest {
        let method = match (&self.dragging, dragging) {
            (Some(fast), true) => fast,
            _ => &self.preview,
        };
        RenderRequest {
            method: Some(method.clone()),
            aa: (aa > 1).then_some(aa),
            threads: None,
            region: None,
        }
    }
}

pub struct StudyWindow {
    pub open: bool,
    /// Generation of the study request this window shows.
    generation: Option<u64>,
    state: StudyState,
    /// The scene studied (its name in the table).
    scene_name: String,
    rows: Vec<Row>,
    /// Side-by-side pictures of the failing methods.
    failures: Vec<(&'static str, RgbImage)>,
    /// The failure picture shown, and its texture.
    shown: Option<(&'static str, TextureHandle)>,
    /// auto's decisions for the current scene.
    plan: Vec<Decision>,
    pub runs: usize,
    /// Which render the running study is at, and its pixels.
    progress: Arc<StudyProgress>,
}

impl Default for StudyWindow {
    fn default() -> Self {
        StudyWindow {
            open: false,
            generation: None,
            state: StudyState::Idle,
            scene_name: String::new(),
            rows: Vec::new(),
            failures: Vec::new(),
            shown: None,
            plan: Vec::new(),
            runs: 3,
            progress: Arc::default(),
        }
    }
}

impl StudyWindow {
    /// A closed window whose study renders each method `runs` times.
    pub fn with_runs(runs: usize) -> StudyWindow {
        StudyWindow {
            runs,
            ..StudyWindow::default()
        }
    }

    pub fn state(&self) -> &StudyState {
        &self.state
    }

    pub fn rows(&self) -> &[Row] {
        &self.rows
    }

    pub fn is_done(&self) -> bool {
        matches!(self.state, StudyState::Done(_))
    }

    pub fn is_running(&self) -> bool {
        matches!(self.state, StudyState::Running { .. })
    }

    /// A study of `scene_name` was requested as `generation`, reporting
    /// where it is in `progress`: forget the previous results.
    pub fn started(&mut self, generation: u64, scene_name: String, progress: Arc<StudyProgress>) {
        *self = StudyWindow {
            open: true,
            generation: Some(generation),
            state: StudyState::Running { done: 0, total: 0 },
            scene_name,
            progress,
            plan: std::mem::take(&mut self.plan),
            runs: self.runs,
            ..StudyWindow::default()
        };
    }

    /// The plan `auto` makes for the current scene (shown in the window).
    pub fn set_plan(&mut self, scene: &Scene) {
        self.plan = render::auto(scene).decisions;
    }

    /// Takes a study event of this window's request. Returns whether the
    /// study has ended (finished or stopped).
    pub fn apply(&mut self, event: Event) -> bool {
        if Some(event.generation()) != self.generation {
            return false;
        }
        match event {
            Event::StudyStarted { total, .. } => {
                self.state = StudyState::Running { done: 0, total };
                false
            }
            Event::StudyRow { row, failure, .. } => {
                if let Some(picture) = failure {
                    self.failures.push((row.method, picture));
                }
                self.rows.push(row);
                if let StudyState::Running { done, .. } = &mut self.state {
                    *done += 1;
                }
                false
            }
            Event::StudyFinished { elapsed, .. } => {
                self.state = StudyState::Done(elapsed);
                true
            }
            Event::StudyStopped { message, .. } => {
                // A newer request already said why (the scene changed).
                if !matches!(self.state, StudyState::Stopped(_)) {
                    self.state = StudyState::Stopped(message);
                }
                true
            }
            _ => false,
        }
    }

    /// The request was cancelled by a newer one that is not a study (a
    /// render after an edit): the study says so.
    pub fn superseded(&mut self, newest: u64) {
        if self.is_running() && self.generation.is_some_and(|g| g < newest) {
            self.state = StudyState::Stopped("cancelled: the scene changed".into());
        }
    }

    /// Draws the window; returns what the user asked for.
    pub fn show(&mut self, ctx: &egui::Context, live: &PreviewMethods) -> Vec<Action> {
        let mut actions = Vec::new();
        let mut open = self.open;
        egui::Window::new("Study")
            .open(&mut open)
            .default_size([720.0, 640.0])
            .vscroll(true)
            .show(ctx, |ui| self.contents(ui, live, &mut actions));
        self.open = open;
        actions
    }

    fn contents(&mut self, ui: &mut egui::Ui, live: &PreviewMethods, actions: &mut Vec<Action>) {
        ui.label(
            "Every method renders the current scene; each is timed (median of the runs) and \
             compared with the default image (anti-aliasing: with the default supersampled \
             16×16). A method fails when fewer than 99 % of the pixels are within one level.",
        );
        ui.horizontal(|ui| {
            if self.is_running() {
                if ui.button("Cancel").clicked() {
                    actions.push(Action::Cancel);
                }
            } else if ui.button("Run the study").clicked() {
                actions.push(Action::Run);
            }
            ui.add_enabled(
                !self.is_running(),
                egui::DragValue::new(&mut self.runs)
                    .range(1..=9)
                    .prefix("runs: "),
            );
            match &self.state {
                StudyState::Idle => {
                    ui.label("not run yet");
                }
                StudyState::Running { done, total } => {
                    let (share, text) = running(
                        self.progress.stage(),
                        self.progress.render.pixels(),
                        *done,
                        *total,
                    );
                    ui.add(
                        egui::ProgressBar::new(share)
                            .desired_width(260.0)
                            .text(text),
                    );
                    // The render's pixels move between the rows' events.
                    ui.ctx().request_repaint_after(Duration::from_millis(200));
                }
                StudyState::Done(elapsed) => {
                    ui.label(format!(
                        "{}: {} methods in {:.1} s",
                        self.scene_name,
                        self.rows.len(),
                        elapsed.as_secs_f64()
                    ));
                }
                StudyState::Stopped(message) => {
                    ui.colored_label(Color32::from_rgb(220, 120, 60), message);
                }
            }
        });
        ui.separator();
        self.preview_choice(ui, live, actions);
        if !self.plan.is_empty() {
            egui::CollapsingHeader::new("auto's plan for this scene").show(ui, |ui| {
                for d in &self.plan {
                    ui.label(RichText::new(format!("{}: {}", d.topic, d.choice)).strong());
                    ui.label(&d.reason);
                }
            });
        }
        ui.separator();
        self.table(ui, live, actions);
        self.failure_picture(ui);
        plot::plot(ui, &self.rows);
    }

    fn preview_choice(
        &mut self,
        ui: &mut egui::Ui,
        live: &PreviewMethods,
        actions: &mut Vec<Action>,
    ) {
        let methods = render::methods();
        egui::Grid::new("preview-methods").show(ui, |ui| {
            ui.label("Live preview");
            egui::ComboBox::from_id_salt("preview-method")
                .selected_text(live.preview.name)
                .show_ui(ui, |ui| {
                    for m in &methods {
                        if ui
                            .selectable_label(live.preview.name == m.name, m.name)
                            .clicked()
                        {
                            actions.push(Action::Preview(m.name));
                        }
                    }
                });
            ui.end_row();
            ui.label("While dragging");
            let current = live.dragging.as_ref().map_or("the same", |m| m.name);
            egui::ComboBox::from_id_salt("dragging-method")
                .selected_text(current)
                .show_ui(ui, |ui| {
                    if ui
                        .selectable_label(live.dragging.is_none(), "the same")
                        .clicked()
                    {
                        actions.push(Action::WhileDragging(None));
                    }
                    for m in &methods {
                        if ui.selectable_label(current == m.name, m.name).clicked() {
                            actions.push(Action::WhileDragging(Some(m.name)));
                        }
                    }
                });
            ui.end_row();
        });
    }

    fn table(&mut self, ui: &mut egui::Ui, live: &PreviewMethods, actions: &mut Vec<Action>) {
        if self.rows.is_empty() {
            return;
        }
        let best = study::chart::fastest_accurate(&self.rows)
            .first()
            .map(|r| r.method);
        let mut show = None;
        egui::Grid::new("study-table")
            .striped(true)
            .num_columns(8)
            .show(ui, |ui| {
                for title in [
                    "method", "time ms", "rays", "max", "mean", "within 1", "", "",
                ] {
                    ui.label(RichText::new(title).strong());
                }
                ui.end_row();
                for row in &self.rows {
                    let name = if Some(row.method) == best {
                        RichText::new(format!("{} (fastest)", row.method)).strong()
                    } else {
                        RichText::new(row.method)
                    };
                    ui.label(name);
                    ui.label(format!("{:.2}", row.time.as_secs_f64() * 1e3));
                    ui.label(row.rays.to_string());
                    ui.label(row.max_diff.to_string());
                    ui.label(format!("{:.4}", row.mean_diff));
                    ui.label(format!("{:.4}", row.within1));
                    if row.failed {
                        let selected = self.shown.as_ref().is_some_and(|s| s.0 == row.method);
                        if ui
                            .selectable_label(
                                selected,
                                RichText::new("FAILED").color(Color32::from_rgb(230, 90, 70)),
                            )
                            .on_hover_text("show method | reference | difference ×8")
                            .clicked()
                        {
                            show = Some(row.method);
                        }
                    } else {
                        ui.label("");
                    }
                    if live.preview.name == row.method {
                        ui.label("previewing");
                    } else if ui.button("preview with it").clicked() {
                        actions.push(Action::Preview(row.method));
                    }
                    ui.end_row();
                }
            });
        if best.is_some() {
            ui.label("(fastest): the fastest method that did not fail");
        }
        if let Some(method) = show
            && let Some((_, picture)) = self.failures.iter().find(|(m, _)| *m == method)
        {
            let texture = ui.ctx().load_texture(
                format!("study-failure-{method}"),
                color_image(picture),
                TextureOptions::NEAREST,
            );
            self.shown = Some((method, texture));
        }
    }

    fn failure_picture(&mut self, ui: &mut egui::Ui) {
        let Some((method, texture)) = &self.shown else {
            return;
        };
        ui.separator();
        ui.label(format!("{method} | default | difference ×8"));
        let size = texture.size_vec2();
        let scale = (ui.available_width() / size.x).min(2.0);
        ui.image((texture.id(), size * scale));
    }
}

fn color_image(image: &RgbImage) -> egui::ColorImage {
    let (w, h) = image.dimensions();
    egui::ColorImage::from_rgb([w as usize, h as usize], image.as_raw())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bar_moves_within_a_reference_and_within_a_method() {
        let (share, text) = running(Stage::Reference { supersampled: true }, (25, 100), 0, 12);
        assert_eq!(
            (share, text.as_str()),
            (0.25, "the reference, 16×16 samples: 25 %")
        );
        let name = "phong";
        let stage = |run, runs| Stage::Method {
            index: 3,
            of: 12,
            name,
            run,
            runs,
        };
        let (share, text) = running(stage(0, 1), (50, 100), 3, 12);
        assert_eq!(share, 3.5 / 12.0);
        assert_eq!(text, "3 of 12 methods; phong: 50 %");
        // The second of four runs half done: the method 3/8 done, the bar
        // not back to the method's start.
        let (share, text) = running(stage(1, 4), (50, 100), 3, 12);
        assert_eq!(share, (3.0 + 1.5 / 4.0) / 12.0);
        assert_eq!(text, "3 of 12 methods; phong, run 2 of 4: 50 %");
        assert_eq!(running(Stage::Waiting, (0, 0), 0, 12).0, 0.0);
    }
}
