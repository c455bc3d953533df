//! The application: window layout and the glue between the document, the
//! file watcher, the render worker and the picture on screen.
//!
//! The work is the model's ([`crate::session`]): the worker renders, the
//! watcher reads files, [`Document`] keeps the text, the edits and their
//! undo, [`Preview`] assembles tiles. `RayOfLightApp` holds the model's
//! parts and one struct per part of the window, each defined in the
//! module that draws it (`picture::Screen`, `overlay::Overlay`,
//! `explain::ExplainState`, `passes::Passes`, `dialogs::Dialogs`,
//! `status::Status`, `events::Files`, `hot_exit::Ending`); this module
//! holds the frame ([`RayOfLightApp::draw`]); its children hold the rest:
//! - [`command`]: the [`Command`] enum of menus and keys, and the one
//!   binding table that gives each its label, keys and help line;
//! - `menus`: the menu bar, the keys and the help window read from that
//!   table, and the one place that carries a command out (`run`);
//! - `dialogs`: open (a large file on a thread of its own), save (on a
//!   thread of its own), export, and the modal questions;
//! - `hot_exit`: the journal of unsaved edits kept as they are made,
//!   restored when a scene opens; the clean end on SIGTERM, SIGINT, SIGHUP;
//! - `events`: render requests and their schedule (`RenderSchedule`),
//!   and what the worker, the watcher and the dialogs send back;
//! - `picture`: the picture, its zoom and pan, the pick;
//! - `navigate`: orbit, pan and dolly the camera, move the selected object
//!   (G) with the mouse;
//! - `overlay`: the selection's outline and the light markers (dragged to
//!   move lights), hidden with View › Overlays (O);
//! - `explain`: the explained pixel's window and its path over the
//!   picture (E, Alt+click);
//! - `passes`: View › Pass, a render pass shown in place of the picture;
//! - `status`: the status bar, the error banner, notices, frame counts
//!   (`FrameStats`).
//!
//! What the mouse is doing on the picture is one `Interaction` at a
//! time.

pub mod command;
mod dialogs;
mod events;
mod explain;
mod hot_exit;
mod menus;
mod navigate;
mod overlay;
mod passes;
mod picture;
mod status;

pub use command::Command;
use dialogs::DialogKind;
use picture::View;

use super::panel::{self, Selection};
use super::study::{PreviewMethods, StudyWindow};
use crate::render;
use crate::session::document::{Document, SaveJob, SaveOutcome};
use crate::session::preview::{Preview, RenderState};
use crate::session::settings::{Persisted, Recent, Settings};
use crate::session::watcher::{FileEvent, SceneWatcher};
use crate::session::worker::Worker;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, Sender};
use std::time::{Duration, Instant};

/// What background threads send to the UI thread.
enum Background {
    /// A file event from the watcher of this generation.
    File(u64, FileEvent),
    /// The object-id buffer for the outline of (object, render generation).
    Ids((u32, u64), crate::render::ObjectIds),
    /// An export ended: written, failed, or (`Ok(false)`) cancelled.
    Exported(PathBuf, Result<bool, String>),
    Dialog(DialogKind, Option<PathBuf>, Duration),
    /// A save ran (on a thread of its own).
    Saved(Box<SaveJob>, SaveOutcome),
    /// A render pass for (pass, render generation).
    Pass((render::Pass, u64), Box<render::PassImage>),
    /// A file opened in the background (the load's number, the document).
    Opened(u64, Box<Result<Document, crate::scene::LoadError>>),
    /// The pixel explained for this request number (`None`: outside the
    /// picture).
    Explained(u64, Option<Box<crate::render::Explanation>>),
    /// What the user's editor said over the editor link
    /// ([`crate::desktop::editor_link`]), on the connection numbered so:
    /// its unsaved text of a file, or that it let go of it.
    Editor(u64, crate::desktop::editor_link::Message),
    /// The editor on that connection is gone.
    EditorGone(u64),
}

/// What the mouse is doing on the picture, or will do at the next click:
/// one thing at a time.
#[derive(Debug, Clone, Default)]
enum Interaction {
    #[default]
    Idle,
    /// A drag of the camera (orbit or pan) under way.
    Navigating(navigate::Navigation),
    /// The selected object follows the pointer (G, Alt+drag).
    Grabbing(navigate::Grab),
    /// A light's marker is being dragged.
    DraggingLight(overlay::LightDrag),
    /// The next click on the picture explains its pixel (E).
    ExplainArmed,
}

impl Interaction {
    fn is_grabbing(&self) -> bool {
        matches!(self, Interaction::Grabbing(_))
    }

    fn is_navigating(&self) -> bool {
        matches!(self, Interaction::Navigating(_))
    }

    fn is_explain_armed(&self) -> bool {
        matches!(self, Interaction::ExplainArmed)
    }

    /// Nothing under way: a new drag or move may start (an armed explain
    /// gives way to it).
    fn is_free(&self) -> bool {
        matches!(self, Interaction::Idle | Interaction::ExplainArmed)
    }
}

/// The window. Each part of it owns its state (the picture, the
/// overlay, explain, passes, dialogs, the status bar, …) in a struct of its
/// own module; what it shows and changes is the model's
/// ([`crate::session`]): the document, the worker, the preview.
pub struct RayOfLightApp {
    doc: Document,
    worker: Worker,
    preview: Preview,
    selection: Selection,
    /// When to render, how coarse, and what is in flight.
    schedule: events::RenderSchedule,
    choice: events::RenderChoice,
    study: StudyWindow,
    files: events::Files,
    background: Channel,
    screen: picture::Screen,
    overlay: overlay::Overlay,
    explain: explain::ExplainState,
    passes: passes::Passes,
    dialogs: dialogs::Dialogs,
    status: status::Status,
    editors: EditorLink,
    kept: Kept,
    /// The journal of unsaved edits, when the app keeps one.
    hot_exit: Option<hot_exit::HotExit>,
    ending: hot_exit::Ending,
    ctx: egui::Context,
}

/// What background threads send to the UI thread, and the sender they
/// are given.
struct Channel {
    rx: Receiver<Background>,
    tx: Sender<Background>,
}

/// The link to the user's editors: what an editor the app started said
/// when it failed (its thread sends it, for the status bar), the socket
/// `rayoflight lsp` reaches the app by (removed when the app ends,
/// [`RayOfLightApp::listen_to_editors`]), and the editors connected over
/// it, for a click on an object to ask them to show its element.
struct EditorLink {
    failed: (Sender<String>, Receiver<String>),
    socket: Option<PathBuf>,
    peers: crate::desktop::editor_link::Peers,
    /// The editors (by connection) that hold unsaved text of the open
    /// file, the one on screen last, each with its newest text (but the
    /// one on screen, whose text the document holds: `None`): when it
    /// lets go, the one before is shown again, and the file only when none
    /// holds any.
    holding: Vec<(u64, Option<String>)>,
    /// The editors whose text is off screen and not unsaved: the file's,
    /// or the text they saved, kept whole. A change of it is applied
    /// there, not asked for whole again.
    bases: Vec<(u64, crate::session::document::EditorBase)>,
}

impl EditorLink {
    /// What editor `connection`'s text is now known as (`None`: not
    /// known, or held).
    fn know(&mut self, connection: u64, base: Option<crate::session::document::EditorBase>) {
        self.bases.retain(|(c, _)| *c != connection);
        if let Some(base) = base {
            self.bases.push((connection, base));
        }
    }

    /// What editor `connection`'s text is known as, taken (for a change
    /// to be applied to it).
    fn take(&mut self, connection: u64) -> Option<crate::session::document::EditorBase> {
        let i = self.bases.iter().position(|(c, _)| *c == connection)?;
        Some(self.bases.swap_remove(i).1)
    }
}

/// What the app remembers between runs: the recent files, and the window
/// size, anti-aliasing and study runs (saved on exit).
struct Kept {
    recent: Recent,
    settings: Settings,
}

impl RayOfLightApp {
    /// The app on `doc`, with what it remembers between runs
    /// ([`Persisted::user`] in the app, [`Persisted::in_memory`] in tests).
    pub fn new(ctx: &egui::Context, doc: Document, persisted: Persisted) -> RayOfLightApp {
        let Persisted {
            settings,
            recent,
            journal,
            refused,
        } = persisted;
        let wake_ctx = ctx.clone();
        let worker = Worker::spawn(Worker::default_threads(), move || {
            wake_ctx.request_repaint()
        });
        let (tx, rx) = mpsc::channel();
        let mut app = RayOfLightApp {
            doc,
            worker,
            preview: Preview::default(),
            selection: Selection::default(),
            schedule: events::RenderSchedule::default(),
            choice: events::RenderChoice {
                aa: settings.aa,
                methods: PreviewMethods::default(),
            },
            study: StudyWindow::with_runs(settings.study_runs),
            files: events::Files::default(),
            background: Channel { rx, tx },
            screen: picture::Screen::default(),
            overlay: overlay::Overlay::default(),
            explain: explain::ExplainState::default(),
            passes: passes::Passes::default(),
            dialogs: dialogs::Dialogs::default(),
            status: status::Status {
                notice: None,
                frame_stats: status::FrameStats::new(stats_wanted(
                    std::env::var_os("RAYOFLIGHT_STATS").as_deref(),
                )),
                title: String::new(),
            },
            editors: EditorLink {
                failed: mpsc::channel(),
                socket: None,
                peers: crate::desktop::editor_link::Peers::default(),
                holding: Vec::new(),
                bases: Vec::new(),
            },
            kept: Kept { recent, settings },
            hot_exit: journal.map(hot_exit::HotExit::new),
            ending: hot_exit::Ending::default(),
            ctx: ctx.clone(),
        };
        app.restore_journal();
        // A folder of the user's state that is not safe to use, said once
        // (after what a restored journal says, if anything).
        if !refused.is_empty() {
            let mut text = refused.join("; ");
            if let Some((restored, _)) = app.status.notice.take() {
                text = format!("{restored}; {text}");
            }
            app.notify(text);
        }
        // The first screen says where the keys are, and the two things
        // the mouse does that a newcomer would not guess.
        if app.status.notice.is_none() {
            app.notify(
                "F1: keys and mouse (Help menu). Drag the picture to orbit; click an object \
                 to select it"
                    .to_owned(),
            );
        }
        app.watch();
        app.request_render();
        app
    }

    /// SIGTERM, SIGINT and SIGHUP (a logout, Ctrl+C, a closed terminal)
    /// end the app cleanly from now on, with the unsaved edits in the
    /// journal and nothing asked.
    pub fn end_on_signals(&mut self) {
        // A save or export under way stops at its next write, its
        // temporary file removed, before the app ends.
        let _ = crate::system::interrupt::record_only();
        self.ending.signalled = hot_exit::watch_signals(&self.ctx);
    }

    /// Listens to `rayoflight lsp` in the user's editors from now on
    /// (their unsaved text of the open file is shown as it is typed, their
    /// cursor selects objects, a click asks them to show one), on threads
    /// of their own: one that accepts, one that reads a connection.
    pub fn listen_to_editors(&mut self, listener: crate::desktop::editor_link::Listener) {
        self.editors.socket = Some(listener.path().to_owned());
        let (tx, ctx) = (self.background.tx.clone(), self.ctx.clone());
        let editors = self.editors.peers.clone();
        // Without the thread the app runs, only without the link.
        let _ = std::thread::Builder::new()
            .name("editor link".into())
            .spawn(move || {
                let mut unanswered = u64::MAX;
                while let Ok(stream) = listener.accept() {
                    let (tx, ctx, editors) = (tx.clone(), ctx.clone(), editors.clone());
                    // An editor this app cannot answer is still followed
                    // (under a number of its own).
                    let peer = editors.add(&stream).ok();
                    let connection = peer.unwrap_or_else(|| {
                        unanswered -= 1;
                        unanswered
                    });
                    let _ = std::thread::Builder::new()
                        .name("editor".into())
                        .spawn(move || {
                            use crate::desktop::editor_link::{Message, receive};
                            let mut r = std::io::BufReader::new(stream);
                            // An editor that goes away (quit, crashed)
                            // lets go of what it sent.
                            let mut sent: Vec<PathBuf> = Vec::new();
                            while let Ok(Some(message)) = receive(&mut r) {
                                if let Message::Buffer { path, .. } = &message
                                    && !sent.contains(path)
                                {
                                    sent.push(path.clone());
                                }
                                if tx.send(Background::Editor(connection, message)).is_err() {
                                    return;
                                }
                                ctx.request_repaint();
                            }
                            if let Some(peer) = peer {
                                editors.remove(peer);
                            }
                            for path in sent {
                                let _ = tx.send(Background::Editor(
                                    connection,
                                    Message::Released { path },
                                ));
                            }
                            let _ = tx.send(Background::EditorGone(connection));
                            ctx.request_repaint();
                        });
                }
            });
    }

    /// The scene changed (an edit, undo, redo, a reload): drop a selection
    /// that no longer exists and render.
    fn after_edit(&mut self) {
        if self
            .selection
            .object
            .is_some_and(|n| n >= self.doc.scene().objects.len())
        {
            self.selection = Selection::default();
        }
        self.request_render();
    }

    /// Runs `change`, which takes a version of the scene from outside (the
    /// file another program wrote, the editor's text), and keeps the
    /// selection on the object it named: found again in the new list by
    /// its identity (`scene::identity`, as a merge finds an edit's
    /// element), or let go where that object is gone — never left on
    /// whatever object now has its number.
    fn keeping_selection<R>(&mut self, change: impl FnOnce(&mut Self) -> R) -> R {
        let before = self
            .selection
            .object
            .map(|n| (n, self.doc.scene().objects.clone()));
        let result = change(self);
        let Some((n, old)) = before else {
            return result;
        };
        let new = &self.doc.scene().objects;
        if !old.same_list(new) {
            let now = crate::scene::identity::objects(&old, new)
                .get(n)
                .copied()
                .flatten();
            if now != Some(n) {
                self.selection = match now {
                    Some(now) => Selection {
                        object: Some(now),
                        ..Selection::default()
                    },
                    None => Selection::default(),
                };
            }
        }
        result
    }

    fn replace_document(&mut self, doc: Document) {
        self.doc = doc;
        // Editors' texts were of the other file.
        self.editors.holding.clear();
        self.editors.bases.clear();
        self.selection = Selection::default();
        self.screen.view = View::default();
        self.restore_journal();
        self.watch();
        self.request_render();
    }

    /// (Re)starts watching the document's file, if it has one.
    fn watch(&mut self) {
        self.files.watcher = None;
        self.files.generation += 1;
        let Some(path) = self.doc.path().map(Path::to_owned) else {
            return;
        };
        let tx = self.background.tx.clone();
        let ctx = self.ctx.clone();
        let generation = self.files.generation;
        match SceneWatcher::new(&path, self.doc.disk_fingerprint(), move |event| {
            let _ = tx.send(Background::File(generation, event));
            ctx.request_repaint();
        }) {
            Ok(w) => {
                w.share(&self.doc.scene().objects);
                self.files.watcher = Some(w);
            }
            Err(e) => self.notify(format!("{e}; saves from other editors will not show")),
        }
        self.kept.recent.push(&path);
    }

    /// The settings as they stand now, to save on exit.
    pub fn settings(&self) -> Settings {
        let window = self
            .ctx
            .input(|i| i.viewport().inner_rect)
            .map(|r| [r.width(), r.height()]);
        let mut settings = self.kept.settings.clone();
        settings.window = window.or(settings.window);
        settings.aa = self.choice.aa;
        settings.study_runs = self.study.runs;
        settings.last_file = self.doc.path().map(crate::system::files::absolute);
        settings
    }

    pub fn document(&self) -> &Document {
        &self.doc
    }

    /// A file is being opened in the background.
    pub fn is_loading(&self) -> bool {
        self.files.loading.is_some()
    }

    /// A save is running (on its own thread).
    pub fn is_saving(&self) -> bool {
        self.dialogs.saving.is_some()
    }

    /// The object selected in the picture or the panel.
    /// The light selected (the editor's cursor in its element), if any.
    pub fn selected_light(&self) -> Option<usize> {
        self.selection.light
    }

    pub fn selected_object(&self) -> Option<usize> {
        self.selection.object
    }

    /// Whether the overlays are drawn (View › Overlays, O).
    pub fn overlays_shown(&self) -> bool {
        self.overlay.shown
    }

    /// The field marked in the panel (a term of an explained pixel).
    pub fn marked_field(&self) -> Option<crate::scene::edit::Field> {
        self.selection.field
    }

    /// Where the picture was drawn in the last frame (points), if it was.
    pub fn picture_rect(&self) -> Option<egui::Rect> {
        self.screen.shown_at
    }

    pub fn preview(&self) -> &Preview {
        &self.preview
    }

    /// The newest render generation requested from the worker.
    pub fn newest_generation(&self) -> u64 {
        self.worker.newest()
    }

    /// The live preview's methods (for tests).
    pub fn preview_methods(&self) -> &PreviewMethods {
        &self.choice.methods
    }

    pub fn study_window(&self) -> &StudyWindow {
        &self.study
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        egui::Panel::left("scene-panel")
            .resizable(true)
            .default_size(320.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    let out = panel::scene_panel(ui, &self.doc, &mut self.selection);
                    if !out.edits.is_empty() {
                        match self.doc.apply_step(out.edits, out.dragging) {
                            Ok(()) => self.after_edit(),
                            Err(e) => self.notify(e.to_string()),
                        }
                    }
                    if out.drag_ended {
                        self.doc.end_drag();
                    }
                });
            });
    }
}

impl eframe::App for RayOfLightApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let start = Instant::now();
        self.draw(ui);
        self.status.frame_stats.slowest_frame =
            self.status.frame_stats.slowest_frame.max(start.elapsed());
    }

    fn on_exit(&mut self, _gl: Option<&eframe::glow::Context>) {
        self.settings().save();
        if let Some(socket) = &self.editors.socket {
            let _ = std::fs::remove_file(socket);
        }
    }
}

impl RayOfLightApp {
    /// The whole window's content for one frame.
    pub fn draw(&mut self, ui: &mut egui::Ui) {
        self.count_frame();
        self.drain_events();
        let ctx = ui.ctx().clone();
        self.keep_journal(&ctx);
        self.guard_close(&ctx);
        self.shortcuts(&ctx);
        let title = format!(
            "RayOfLight — {}{}",
            match &self.files.loading {
                Some(loading) => format!("loading {}…", loading.path.display()),
                None => self.doc.title(),
            },
            if self.doc.has_unsaved_edits() {
                " •"
            } else {
                ""
            }
        );
        if title != self.status.title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.status.title = title;
        }
        egui::Panel::top("menu").show(ui, |ui| self.menu_bar(ui));
        self.status_bar(ui);
        self.side_panel(ui);
        self.picture(ui);
        self.modals(ui);
        self.help_window(&ctx);
        self.retry_waiting(&ctx);
        self.refresh_explained();
        self.explain_window(&ctx);
        self.refresh_outline();
        self.refresh_pass();
        if self.study.open {
            for action in self.study.show(&ctx, &self.choice.methods) {
                self.study_action(action);
            }
        }
        if self.screen.wheel_at.is_some() {
            self.end_wheel_burst();
            ctx.request_repaint_after(navigate::WHEEL_PAUSE);
        }
        // The mouse stopped: refine the coarse picture, exact again if a
        // value was dragged with a cheaper method.
        if (self.schedule.rendered_dragging
            || self.schedule.interactive.is_some()
            || self.schedule.render_pending)
            && !self.interacting()
        {
            self.request_render();
        }
        if self.study.is_running() {
            ctx.request_repaint_after(Duration::from_millis(100));
        }
        if matches!(self.preview.state(), RenderState::Rendering { .. }) {
            // Tiles wake the window (at most once a worker::FRAME); this
            // keeps the progress bar and its time left moving when they
            // are slow to come.
            ctx.request_repaint_after(Duration::from_millis(250));
        }
    }
}

/// Whether `RAYOFLIGHT_STATS` asks for the figures on stderr: set to
/// anything but empty, `0`, `false`, `no` or `off` (as such switches read).
pub fn stats_wanted(value: Option<&std::ffi::OsStr>) -> bool {
    value
        .and_then(std::ffi::OsStr::to_str)
        .map(|v| v.trim().to_ascii_lowercase())
        .is_some_and(|v| !matches!(v.as_str(), "" | "0" | "false" | "no" | "off"))
        // A value that is not UTF-8 is still set.
        || value.is_some_and(|v| v.to_str().is_none())
}
