//! The status bar, the error banner, transient notices and the frame
//! counter (`RAYOFLIGHT_STATS`).

use super::RayOfLightApp;
use crate::render;
use crate::session::document::FileState;
use crate::session::preview::RenderState;
use egui::Color32;
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// The status bar's part: a transient notice, the frame counts, the
/// window title last sent.
pub(super) struct Status {
    /// A transient message (export done, save failed) and when it came.
    pub(super) notice: Option<(String, Instant)>,
    /// Frames and pictures a second, for the status bar and
    /// `RAYOFLIGHT_STATS`.
    pub(super) frame_stats: FrameStats,
    pub(super) title: String,
}

/// Frames and pictures a second: the status bar's figures, printed once a
/// second with `RAYOFLIGHT_STATS`.
#[derive(Debug)]
pub(super) struct FrameStats {
    /// When the pictures (finished passes) of the last second were done:
    /// pictures a second while the mouse moves.
    pub(super) pictures: VecDeque<Instant>,
    /// Frame times of the last second, for the frames-per-second readout.
    pub(super) frames: VecDeque<Instant>,
    /// Frames drawn since the start.
    pub(super) frames_drawn: u64,
    /// Print the figures to stderr once a second (`RAYOFLIGHT_STATS`, see
    /// [`super::stats_wanted`]).
    pub(super) stats: bool,
    pub(super) last_stats: Instant,
    /// The longest time `draw` took since the last stats line.
    pub(super) slowest_frame: Duration,
}

impl FrameStats {
    pub(super) fn new(stats: bool) -> FrameStats {
        FrameStats {
            pictures: VecDeque::new(),
            frames: VecDeque::new(),
            frames_drawn: 0,
            stats,
            last_stats: Instant::now(),
            slowest_frame: Duration::ZERO,
        }
    }
}

impl RayOfLightApp {
    /// The error banner, over the top of the picture's `area` (a layer
    /// above it, not a panel that pushes it down): the picture never moves
    /// while the text in the editor is broken and fixed again.
    pub(super) fn error_banner(&mut self, ctx: &egui::Context, area: egui::Rect) {
        let Some(error) = self.doc.error().map(str::to_owned) else {
            return;
        };
        let what = if self.doc.is_following() {
            "Your editor's unsaved text does not load; showing the last good scene."
        } else if self.doc.is_placeholder() {
            "The file does not load yet; it will show as soon as it does."
        } else {
            "The last save does not load; showing the last good scene."
        };
        egui::Area::new(egui::Id::unique("error-banner"))
            .order(egui::Order::Foreground)
            .fixed_pos(area.min)
            .interactable(false)
            .show(ctx, |ui| {
                ui.set_width(area.width());
                egui::Frame::new()
                    .fill(Color32::from_rgb(120, 20, 20))
                    .inner_margin(6.0)
                    .show(ui, |ui| {
                        ui.set_width(area.width() - 12.0);
                        ui.colored_label(Color32::WHITE, format!("{what}\n{error}"));
                    });
            });
    }

    pub(super) fn status_bar(&mut self, ui: &mut egui::Ui) {
        egui::Panel::bottom("status").show(ui, |ui| {
            ui.horizontal(|ui| {
                match self.preview.state() {
                    RenderState::Idle => ui.label("idle"),
                    RenderState::Waiting => ui.label("rendering…"),
                    RenderState::Rendering { scale, .. } => {
                        let (fraction, left) = self.preview.progress().unwrap_or((0.0, None));
                        let what = if *scale == 1 {
                            "rendering".to_owned()
                        } else {
                            format!("preview 1/{scale}")
                        };
                        // Long passes say how far they are and how long
                        // they have left.
                        let text = match left {
                            Some(left) => format!(
                                "{what} {:.0} % · {:.0} s left",
                                fraction * 100.0,
                                left.as_secs_f64().ceil()
                            ),
                            None => what,
                        };
                        ui.add(
                            egui::ProgressBar::new(fraction)
                                .desired_width(200.0)
                                .text(text),
                        )
                    }
                    RenderState::Done { .. } => ui.label("done"),
                    RenderState::Failed(message) => ui.colored_label(Color32::RED, message),
                    RenderState::Cancelled => ui.label(
                        "cancelled (Esc): the picture may be of an older scene — F5 renders again",
                    ),
                };
                ui.label(if self.schedule.rendered_dragging {
                    self.choice.methods.dragging.as_ref().map_or("", |m| m.name)
                } else {
                    self.choice.methods.preview.name
                })
                .on_hover_text("the live preview's method (View › Study…)");
                if let Some((elapsed, rays)) = self.preview.last_render() {
                    let secs = elapsed.as_secs_f64().max(1e-9);
                    ui.separator();
                    ui.label(format!("{:.1} ms", secs * 1e3));
                    ui.label(format!("{:.2} Mrays/s", rays as f64 / secs / 1e6));
                }
                ui.separator();
                let camera = &self.doc.scene().camera;
                ui.label(format!("{}×{}", camera.width, camera.height));
                ui.separator();
                ui.label(match self.doc.state() {
                    _ if self.doc.is_following() && self.doc.error().is_some() => {
                        "following your editor's unsaved text: it has errors".to_owned()
                    }
                    _ if self.doc.is_following() => {
                        "following your editor's unsaved text".to_owned()
                    }
                    FileState::Builtin if self.doc.is_placeholder() => "no scene yet".to_owned(),
                    FileState::Builtin => "built-in example".to_owned(),
                    FileState::Missing => "file missing: waiting for it to come back".to_owned(),
                    FileState::Watching if self.doc.error().is_some() => {
                        if self.doc.has_unsaved_edits() {
                            "file has errors · unsaved edits".to_owned()
                        } else {
                            "file has errors".to_owned()
                        }
                    }
                    FileState::Watching if self.files.reading => {
                        "the file changed: reading it…".to_owned()
                    }
                    FileState::Watching if self.doc.has_unsaved_edits() => {
                        "unsaved edits (Ctrl+S saves)".to_owned()
                    }
                    FileState::Watching => "watching, saved".to_owned(),
                });
                if let Some((x, y, rgb)) = self.screen.hovered {
                    ui.separator();
                    // The pass shown's value, else the picture's colour.
                    ui.label(match self.pass_value(x, y) {
                        Some(value) => format!("({x}, {y}) {value}"),
                        None => format!("({x}, {y}) rgb({}, {}, {})", rgb[0], rgb[1], rgb[2]),
                    });
                }
                if self.passes.pass != render::Pass::Final {
                    ui.separator();
                    ui.label(match (self.pass_shown().1, self.depth_range()) {
                        (None, _) => format!("rendering the {} pass…", self.passes.pass.name()),
                        (Some(_), Some((near, far))) => format!(
                            "depth pass: t {} (light) to {} (dark)",
                            render::explain::number(near),
                            render::explain::number(far)
                        ),
                        (Some(_), None) => format!("{} pass", self.passes.pass.name()),
                    });
                }
                if self.screen.interaction.is_explain_armed() {
                    ui.separator();
                    ui.label("click a pixel to explain it (Esc: cancel)");
                }
                ui.separator();
                // The frames of the last second, this one included; with
                // no other, the window is idle (and draws nothing more).
                if self.status.frame_stats.frames.len() <= 1 {
                    ui.label("idle");
                } else {
                    ui.label(format!("{} fps", self.status.frame_stats.frames.len()));
                    // One more frame once this second is over, to say so.
                    ui.ctx().request_repaint_after(Duration::from_millis(1100));
                }
                self.export_progress(ui);
                if let Some(saving) = &self.dialogs.saving {
                    // No spinner: it would draw every frame it can while
                    // the save runs; the seconds go up four times a second.
                    ui.separator();
                    ui.label(format!(
                        "saving… {:.0} s",
                        saving.started.elapsed().as_secs_f64().floor()
                    ));
                    ui.ctx().request_repaint_after(Duration::from_millis(250));
                }
                if let Some((fraction, loading)) = self.loading_status() {
                    ui.separator();
                    ui.add(
                        egui::ProgressBar::new(fraction)
                            .desired_width(120.0)
                            .show_percentage(),
                    );
                    ui.label(loading);
                    ui.ctx().request_repaint_after(Duration::from_millis(250));
                }
                if let Some((notice, _)) = &self.status.notice {
                    ui.separator();
                    // Cut to the bar's width with "…"; egui shows all of it
                    // on hover (a tooltip of our own drew it twice).
                    ui.add(egui::Label::new(notice.as_str()).truncate());
                }
            });
        });
    }

    /// The export under way: its percentage, the time left once a second
    /// has passed, and a button that stops it.
    fn export_progress(&mut self, ui: &mut egui::Ui) {
        let Some(export) = &self.dialogs.export else {
            return;
        };
        ui.separator();
        let name = export.path.file_name().map_or_else(
            || export.path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        let fraction = export.progress.fraction();
        let mut text = format!("exporting {name} {:.0} %", fraction * 100.0);
        if let Some(left) = export.progress.left(export.started.elapsed()) {
            text += &format!(" · {:.0} s left", left.as_secs_f64().ceil());
        }
        ui.add(
            egui::ProgressBar::new(fraction as f32)
                .desired_width(220.0)
                .text(text),
        );
        if ui
            .small_button("Cancel")
            .on_hover_text("stop the export")
            .clicked()
        {
            export.cancel();
        }
        ui.ctx().request_repaint_after(Duration::from_millis(100));
    }

    pub(super) fn count_frame(&mut self) {
        let now = Instant::now();
        // Once a second, with RAYOFLIGHT_STATS set: the figures the status
        // bar shows, on stderr, for measuring the app from outside.
        if self.status.frame_stats.stats
            && now.duration_since(self.status.frame_stats.last_stats) >= Duration::from_secs(1)
        {
            self.status.frame_stats.last_stats = now;
            eprintln!(
                "stats: fps={} slowest_frame_ms={:.1} pictures={} state={:?} first_pass_ms={:?} last_render_ms={:?}",
                self.status.frame_stats.frames.len(),
                std::mem::take(&mut self.status.frame_stats.slowest_frame).as_secs_f64() * 1e3,
                self.status.frame_stats.pictures.len(),
                self.preview.state(),
                self.preview.first_pass().map(|d| d.as_secs_f64() * 1e3),
                self.preview
                    .last_render()
                    .map(|(d, _)| d.as_secs_f64() * 1e3),
            );
        }
        while self
            .status
            .frame_stats
            .pictures
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
        {
            self.status.frame_stats.pictures.pop_front();
        }
        self.status.frame_stats.frames.push_back(now);
        self.status.frame_stats.frames_drawn += 1;
        while self
            .status
            .frame_stats
            .frames
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
        {
            self.status.frame_stats.frames.pop_front();
        }
        if self
            .status
            .notice
            .as_ref()
            .is_some_and(|(_, t)| t.elapsed() > Duration::from_secs(8))
        {
            self.status.notice = None;
        }
        if let Ok(said) = self.editors.failed.1.try_recv() {
            self.notify(said);
        }
    }

    pub(super) fn notify(&mut self, message: String) {
        self.status.notice = Some((message, Instant::now()));
    }
}
