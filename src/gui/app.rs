//! The application: window layout and the glue between the document, the
//! file watcher, the render worker and the picture on screen.
//!
//! State is small and owned here; the work is elsewhere: the worker renders,
//! the watcher reads files, [`Document`] keeps the text, the edits and
//! their undo, [`Preview`] assembles tiles. Every menu item and key is a
//! [`Command`], carried out in one place ([`RayOfLightApp::run`]), which
//! also asks before anything drops unsaved edits or replaces a file.

use super::document::{Document, FileState, Reload, SaveError};
use super::panel::{self, Selection};
use super::preview::{Preview, RenderState};
use super::recent::Recent;
use super::study::{self, PreviewMethods, StudyWindow};
use super::watcher::{FileEvent, SceneWatcher};
use super::worker::{Event, Worker};
use crate::render::{self, RenderOptions};
use crate::scene::merge::Choice;
use egui::{Color32, Key, KeyboardShortcut, Modifiers, Pos2, Rect, Sense, TextureOptions, Vec2};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, Sender};
use std::time::{Duration, Instant};

const OPEN: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::O);
const SAVE: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::S);
const EXPORT: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::E);
const QUIT: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Q);
const UNDO: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Z);
const REDO: KeyboardShortcut =
    KeyboardShortcut::new(Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::Z);
const REDO_Y: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::Y);

/// Everything the menus and keys can ask for.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// The Open dialog.
    Open,
    /// The plain path field for opening.
    OpenPath,
    /// Open this file (Recent, a drop, a dialog's or field's answer).
    OpenFile(PathBuf),
    OpenBuiltin,
    /// Read the file again, dropping unsaved edits.
    Reload,
    Save,
    /// The Save as dialog.
    SaveAs,
    /// The plain path field for Save as.
    SaveAsPath,
    /// Save to this file (asks first if it is another existing file).
    SaveTo(PathBuf),
    Export,
    ExportPath,
    RevertEdits,
    Undo,
    Redo,
    Quit,
    Fit,
    OneToOne,
    ZoomIn,
    ZoomOut,
    CancelRender,
    Study,
}

impl Command {
    /// Whether carrying it out drops unsaved edits.
    fn drops_edits(&self) -> bool {
        matches!(
            self,
            Command::OpenFile(_) | Command::OpenBuiltin | Command::Reload | Command::Quit
        )
    }
}

/// A question the app is waiting on.
#[derive(Debug, Clone, PartialEq)]
enum Confirm {
    /// `Command` would drop unsaved edits.
    Discard(Command),
    /// Save as would replace this existing file.
    Replace(PathBuf),
}

/// How the picture is placed in the central area.
#[derive(Debug, Clone, Copy, PartialEq)]
struct View {
    /// Screen pixels per image pixel (1 = 1:1, crisp).
    zoom: f32,
    /// Offset of the picture's centre from the area's centre, in points.
    pan: Vec2,
    /// Keep the whole picture in view as the window changes.
    fit: bool,
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

/// A file dialog running on its own thread, so the window keeps painting.
enum DialogKind {
    Open,
    SaveAs,
    Export,
}

/// What background threads send to the UI thread.
enum Background {
    /// A file event from the watcher of this generation.
    File(u64, FileEvent),
    Exported(PathBuf, Result<(), String>),
    Dialog(DialogKind, Option<PathBuf>, Duration),
}

/// An answer to a [`Confirm`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Answer {
    Go,
    SaveThen,
    Cancel,
}

/// Whether two paths name the same file (through links).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// A plain path field, offered where no file dialog can open.
struct PathPrompt {
    kind: DialogKind,
    text: String,
    /// Keyboard focus was given to the field (once, when it opened).
    focused: bool,
}

impl PathPrompt {
    fn new(kind: DialogKind) -> PathPrompt {
        PathPrompt {
            kind,
            text: String::new(),
            focused: false,
        }
    }
}

pub struct RayOfLightApp {
    doc: Document,
    worker: Worker,
    preview: Preview,
    texture: Option<egui::TextureHandle>,
    watcher: Option<SceneWatcher>,
    background: Receiver<Background>,
    background_tx: Sender<Background>,
    path_prompt: Option<PathPrompt>,
    view: View,
    selection: Selection,
    /// A question waiting for an answer.
    confirm: Option<Confirm>,
    /// The user's choice for each conflict of the pending merge.
    conflict_choices: Vec<Choice>,
    /// Anti-aliasing of the preview and of exports.
    aa: u32,
    /// The live preview's method (auto unless chosen in the Study window)
    /// and the one while a value is dragged.
    methods: PreviewMethods,
    /// The newest render used the while-dragging method: render again
    /// with the exact one on release.
    rendered_dragging: bool,
    study: StudyWindow,
    /// A transient message for the status bar (export done, save failed).
    notice: Option<(String, Instant)>,
    recent: Recent,
    /// Which watcher is the current one: events of an older one (for a
    /// file no longer open) still in the channel are dropped.
    watch_generation: u64,
    /// Frame times of the last second, for the frames-per-second readout.
    frames: VecDeque<Instant>,
    /// The pixel under the cursor and its colour.
    hovered: Option<(u32, u32, [u8; 3])>,
    /// The window title last sent.
    title: String,
    /// The user chose to quit without saving.
    allow_close: bool,
    /// Print the status figures to stderr once a second (RAYOFLIGHT_STATS).
    stats: bool,
    last_stats: Instant,
    ctx: egui::Context,
}

impl RayOfLightApp {
    /// The app on `doc`, with the recent-files list `recent`
    /// ([`Recent::user`] in the app, [`Recent::in_memory`] in tests).
    pub fn new(ctx: &egui::Context, doc: Document, recent: Recent) -> RayOfLightApp {
        let wake_ctx = ctx.clone();
        let worker = Worker::spawn(Worker::default_threads(), move || {
            wake_ctx.request_repaint()
        });
        let (background_tx, background) = mpsc::channel();
        let mut app = RayOfLightApp {
            doc,
            worker,
            preview: Preview::default(),
            texture: None,
            watcher: None,
            background,
            background_tx,
            title: String::new(),
            allow_close: false,
            stats: std::env::var_os("RAYOFLIGHT_STATS").is_some(),
            last_stats: Instant::now(),
            path_prompt: None,
            view: View::default(),
            selection: Selection::default(),
            confirm: None,
            conflict_choices: Vec::new(),
            aa: 1,
            methods: PreviewMethods::default(),
            rendered_dragging: false,
            study: StudyWindow::default(),
            notice: None,
            recent,
            watch_generation: 0,
            frames: VecDeque::new(),
            hovered: None,
            ctx: ctx.clone(),
        };
        app.watch();
        app.request_render();
        app
    }

    /// Carries out a command from a menu or a key. Commands that would drop
    /// unsaved edits ask first.
    pub fn run(&mut self, command: Command) {
        if command.drops_edits() && self.doc.has_unsaved_edits() {
            self.confirm = Some(Confirm::Discard(command));
            return;
        }
        self.execute(command);
    }

    fn execute(&mut self, command: Command) {
        match command {
            Command::Open => self.start_dialog(DialogKind::Open),
            Command::OpenPath => self.path_prompt = Some(PathPrompt::new(DialogKind::Open)),
            Command::OpenFile(path) => self.open(&path),
            Command::OpenBuiltin => self.replace_document(Document::builtin()),
            Command::Reload => match self.doc.path().map(Path::to_owned) {
                Some(path) => self.open(&path),
                None => self.replace_document(Document::builtin()),
            },
            Command::Save => self.save(),
            Command::SaveAs => self.start_dialog(DialogKind::SaveAs),
            Command::SaveAsPath => {
                let mut prompt = PathPrompt::new(DialogKind::SaveAs);
                if let Some(path) = self.doc.path() {
                    prompt.text = path.display().to_string();
                }
                self.path_prompt = Some(prompt);
            }
            Command::SaveTo(path) => {
                let other_file = path.exists()
                    && self
                        .doc
                        .path()
                        .is_none_or(|current| !same_file(current, &path));
                if other_file {
                    self.confirm = Some(Confirm::Replace(path));
                } else {
                    self.save_as(&path);
                }
            }
            Command::Export => self.start_dialog(DialogKind::Export),
            Command::ExportPath => self.path_prompt = Some(PathPrompt::new(DialogKind::Export)),
            Command::RevertEdits => {
                self.doc.revert();
                self.after_edit();
            }
            Command::Undo => {
                if let Some(label) = self.doc.undo() {
                    self.notify(format!("undid {label}"));
                    self.after_edit();
                }
            }
            Command::Redo => {
                if let Some(label) = self.doc.redo() {
                    self.notify(format!("redid {label}"));
                    self.after_edit();
                }
            }
            Command::Quit => {
                self.allow_close = true;
                self.ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
            Command::Fit => self.view.fit = true,
            Command::OneToOne => {
                self.view = View {
                    fit: false,
                    ..View::default()
                }
            }
            Command::ZoomIn => {
                self.view.zoom = (self.view.zoom * 1.25).min(64.0);
                self.view.fit = false;
            }
            Command::ZoomOut => {
                self.view.zoom = (self.view.zoom / 1.25).max(1.0 / 64.0);
                self.view.fit = false;
            }
            Command::CancelRender => self.worker.cancel(),
            Command::Study => {
                self.study.open = true;
                self.study.set_plan(self.doc.scene());
            }
        }
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

    fn replace_document(&mut self, doc: Document) {
        self.doc = doc;
        self.selection = Selection::default();
        self.view = View::default();
        self.watch();
        self.request_render();
    }

    /// (Re)starts watching the document's file, if it has one.
    fn watch(&mut self) {
        self.watcher = None;
        self.watch_generation += 1;
        let Some(path) = self.doc.path().map(Path::to_owned) else {
            return;
        };
        let tx = self.background_tx.clone();
        let ctx = self.ctx.clone();
        let generation = self.watch_generation;
        match SceneWatcher::new(&path, move |event| {
            let _ = tx.send(Background::File(generation, event));
            ctx.request_repaint();
        }) {
            Ok(w) => self.watcher = Some(w),
            Err(e) => self.notify(format!("{e}; saves from other editors will not show")),
        }
        self.recent.push(&path);
    }

    pub fn document(&self) -> &Document {
        &self.doc
    }

    pub fn preview(&self) -> &Preview {
        &self.preview
    }

    /// The newest render generation requested from the worker.
    pub fn newest_generation(&self) -> u64 {
        self.worker.newest()
    }

    fn notify(&mut self, message: String) {
        self.notice = Some((message, Instant::now()));
    }

    /// Asks the worker for the preview of the current scene, with the
    /// while-dragging method when one is set and a button is held.
    fn request_render(&mut self) {
        let dragging = self.methods.dragging.is_some() && self.ctx.input(|i| i.pointer.any_down());
        let options = self.methods.options(self.doc.scene(), dragging, self.aa);
        self.rendered_dragging = dragging;
        let generation = self
            .worker
            .request(Arc::new(self.doc.scene().clone()), options);
        self.study.superseded(generation);
        if self.study.open {
            self.study.set_plan(self.doc.scene());
        }
    }

    /// Selects the object seen at image position (`x`, `y`) and opens it
    /// in the panel, once (a click in the picture).
    pub fn pick(&mut self, x: f64, y: f64) {
        let prepared = render::prepare(self.doc.scene(), &RenderOptions::default());
        self.selection = Selection {
            object: prepared.pick(x, y),
            reveal: true,
        };
    }

    /// The live preview's methods (for tests).
    pub fn preview_methods(&self) -> &PreviewMethods {
        &self.methods
    }

    pub fn study_window(&self) -> &StudyWindow {
        &self.study
    }

    /// Runs the study of the current scene in the worker.
    pub fn run_study(&mut self) {
        let name = self.doc.path().and_then(Path::file_stem).map_or_else(
            || "example".to_owned(),
            |s| s.to_string_lossy().into_owned(),
        );
        let scene = crate::study::StudyScene {
            name: name.clone(),
            scene: self.doc.scene().clone(),
        };
        let generation = self.worker.study(scene, self.study.runs);
        self.study.started(generation, name);
        self.study.set_plan(self.doc.scene());
    }

    /// Does what the Study window asked.
    pub fn study_action(&mut self, action: study::Action) {
        match action {
            study::Action::Run => self.run_study(),
            study::Action::Cancel => self.worker.cancel(),
            study::Action::Preview(name) => {
                if let Some(method) = crate::study::method(name) {
                    self.methods.preview = method;
                    self.request_render();
                }
            }
            study::Action::WhileDragging(name) => {
                self.methods.dragging = name.and_then(crate::study::method);
            }
        }
    }

    /// Replaces the document by the file at `path` (the caller asked about
    /// unsaved edits). A file that does not load opens with its error shown.
    fn open(&mut self, path: &Path) {
        match Document::open(path) {
            Ok(doc) => self.replace_document(doc),
            Err(e) => self.notify(e.to_string()),
        }
    }

    fn save(&mut self) {
        match self.doc.save() {
            Ok(Reload::Merged) => {
                self.notify("merged the file's changes and saved".into());
                self.after_edit();
            }
            Ok(Reload::Replaced) => {
                self.notify(
                    "the file changed on disk and nothing here was unsaved: showing it".into(),
                );
                self.after_edit();
            }
            Ok(_) => self.notify("saved".into()),
            Err(SaveError::NoPath) => self.start_dialog(DialogKind::SaveAs),
            Err(SaveError::Conflict) => {
                self.notify("the file changed on disk: choose between the versions".into());
                self.conflict_choices.clear();
            }
            Err(e) => self.notify(format!("not saved: {e}")),
        }
    }

    fn save_as(&mut self, path: &Path) {
        match self.doc.save_as(path) {
            Ok(()) => {
                self.notify(format!("saved as {}", path.display()));
                self.watch();
            }
            Err(e) => self.notify(format!("not saved: {e}")),
        }
    }

    /// Renders at full resolution with the chosen anti-aliasing on a
    /// background thread and writes the file atomically.
    fn export(&mut self, path: PathBuf) {
        if let Err(e) = crate::output::format_for(&path) {
            self.notify(e.to_string());
            return;
        }
        let scene = self.doc.scene().clone();
        // Exports are exact whatever the preview uses: auto's options.
        let options = RenderOptions {
            threads: Some(Worker::default_threads()),
            aa: self.aa,
            ..render::auto(&scene).options
        };
        let tx = self.background_tx.clone();
        let ctx = self.ctx.clone();
        self.notify(format!("exporting {}…", path.display()));
        std::thread::spawn(move || {
            let result = render::render(&scene, &options)
                .map_err(|e| e.to_string())
                .and_then(|image| crate::output::save(&image, &path).map_err(|e| e.to_string()));
            let _ = tx.send(Background::Exported(path, result));
            ctx.request_repaint();
        });
    }

    fn start_dialog(&mut self, kind: DialogKind) {
        let tx = self.background_tx.clone();
        let ctx = self.ctx.clone();
        let start_dir = self.doc.path().and_then(Path::parent).map(Path::to_owned);
        std::thread::spawn(move || {
            let started = Instant::now();
            let mut dialog = rfd::FileDialog::new();
            if let Some(dir) = start_dir {
                dialog = dialog.set_directory(dir);
            }
            let picked = match kind {
                DialogKind::Open => dialog.add_filter("Scene", &["xml"]).pick_file(),
                DialogKind::SaveAs => dialog
                    .add_filter("Scene", &["xml"])
                    .set_file_name("scene.xml")
                    .save_file(),
                DialogKind::Export => dialog
                    .add_filter("Image", &["png", "jpg", "jpeg"])
                    .set_file_name("render.png")
                    .save_file(),
            };
            let _ = tx.send(Background::Dialog(kind, picked, started.elapsed()));
            ctx.request_repaint();
        });
    }

    fn dialog_done(&mut self, kind: DialogKind, path: Option<PathBuf>, took: Duration) {
        match path {
            Some(path) => self.path_chosen(kind, path),
            // A dialog that closes at once without a choice could not open
            // (no desktop portal): offer a plain path field instead.
            None if took < Duration::from_millis(300) => {
                self.path_prompt = Some(PathPrompt::new(kind))
            }
            None => {}
        }
    }

    fn path_chosen(&mut self, kind: DialogKind, path: PathBuf) {
        match kind {
            DialogKind::Open => self.run(Command::OpenFile(path)),
            DialogKind::SaveAs => self.run(Command::SaveTo(path)),
            DialogKind::Export => self.export(path),
        }
    }

    /// Handles what the watcher, the worker and the dialogs sent.
    fn drain_events(&mut self) {
        let newest = self.worker.newest();
        let events: Vec<_> = self.worker.events().collect();
        let mut study_ended = false;
        for event in events {
            match event {
                Event::StudyStarted { .. }
                | Event::StudyRow { .. }
                | Event::StudyFinished { .. }
                | Event::StudyStopped { .. } => study_ended |= self.study.apply(event),
                _ => {
                    self.preview.apply(newest, event);
                }
            }
        }
        // The study took the worker from an unfinished preview: finish it.
        if study_ended && !matches!(self.preview.state(), RenderState::Done { .. }) {
            self.request_render();
        }
        while let Ok(message) = self.background.try_recv() {
            match message {
                Background::File(generation, event) => {
                    if generation == self.watch_generation {
                        self.file_event(event);
                    }
                }
                Background::Exported(path, Ok(())) => {
                    self.notify(format!("exported {}", path.display()))
                }
                Background::Exported(_, Err(e)) => self.notify(format!("export failed: {e}")),
                Background::Dialog(kind, path, took) => self.dialog_done(kind, path, took),
            }
        }
    }

    fn file_event(&mut self, event: FileEvent) {
        match event {
            FileEvent::Loaded(text, scene) => match self.doc.file_loaded(text, *scene) {
                Reload::Replaced => self.after_edit(),
                Reload::Merged => {
                    self.notify("the file changed on disk: your edits were applied onto it".into());
                    self.after_edit();
                }
                Reload::Conflict => self.conflict_choices.clear(),
                Reload::Unchanged | Reload::Broken => {}
            },
            FileEvent::Broken(error) => {
                self.doc.file_broken(&error);
            }
            FileEvent::Missing => self.doc.file_missing(),
        }
    }

    fn shortcuts(&mut self, ctx: &egui::Context) {
        // A question on screen takes the keys.
        if self.confirm.is_some() || self.doc.conflict().is_some() || self.path_prompt.is_some() {
            return;
        }
        let mut commands = Vec::new();
        // Redo before undo: Ctrl+Shift+Z also matches Ctrl+Z.
        for (shortcut, command) in [
            (OPEN, Command::Open),
            (SAVE, Command::Save),
            (EXPORT, Command::Export),
            (QUIT, Command::Quit),
        ] {
            if ctx.input_mut(|i| i.consume_shortcut(&shortcut)) {
                commands.push(command);
            }
        }
        // Undo and redo belong to a text field while one is being typed in.
        if !ctx.egui_wants_keyboard_input() {
            for (shortcut, command) in [
                (REDO, Command::Redo),
                (REDO_Y, Command::Redo),
                (UNDO, Command::Undo),
            ] {
                if ctx.input_mut(|i| i.consume_shortcut(&shortcut)) {
                    commands.push(command);
                }
            }
            ctx.input(|i| {
                for (key, command) in [
                    (Key::F, Command::Fit),
                    (Key::Num1, Command::OneToOne),
                    (Key::Plus, Command::ZoomIn),
                    (Key::Equals, Command::ZoomIn),
                    (Key::Minus, Command::ZoomOut),
                    (Key::Escape, Command::CancelRender),
                ] {
                    if i.key_pressed(key) && i.modifiers.is_none() {
                        commands.push(command);
                    }
                }
            });
        }
        let dropped: Option<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_owned())
                .next()
        });
        if let Some(path) = dropped {
            commands.push(Command::OpenFile(path));
        }
        for command in commands {
            self.run(command);
        }
    }

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        let mut chosen = None;
        let mut pick = |ui: &mut egui::Ui, enabled: bool, text: &str, command: Command| {
            if ui.add_enabled(enabled, egui::Button::new(text)).clicked() {
                chosen = Some(command);
                ui.close();
            }
        };
        let dirty = self.doc.has_unsaved_edits();
        let has_file = self.doc.path().is_some();
        let undo = self.doc.undo_label().map(|l| format!("Undo {l}  Ctrl+Z"));
        let redo = self
            .doc
            .redo_label()
            .map(|l| format!("Redo {l}  Ctrl+Shift+Z"));
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                pick(ui, true, "Open…  Ctrl+O", Command::Open);
                pick(ui, true, "Open path…", Command::OpenPath);
                pick(ui, true, "Open built-in example", Command::OpenBuiltin);
                ui.menu_button("Recent", |ui| {
                    let recent = self.recent.existing();
                    if recent.is_empty() {
                        ui.label("(none)");
                    }
                    for path in &recent {
                        pick(
                            ui,
                            true,
                            &path.display().to_string(),
                            Command::OpenFile(path.clone()),
                        );
                    }
                });
                pick(ui, has_file, "Reload from disk", Command::Reload);
                ui.separator();
                pick(ui, true, "Save  Ctrl+S", Command::Save);
                pick(ui, true, "Save as…", Command::SaveAs);
                pick(ui, true, "Save as path…", Command::SaveAsPath);
                pick(ui, dirty, "Revert edits", Command::RevertEdits);
                ui.separator();
                pick(ui, true, "Export image…  Ctrl+E", Command::Export);
                pick(ui, true, "Export to path…", Command::ExportPath);
                ui.separator();
                pick(ui, true, "Quit  Ctrl+Q", Command::Quit);
            });
            ui.menu_button("Edit", |ui| {
                pick(
                    ui,
                    undo.is_some(),
                    undo.as_deref().unwrap_or("Undo  Ctrl+Z"),
                    Command::Undo,
                );
                pick(
                    ui,
                    redo.is_some(),
                    redo.as_deref().unwrap_or("Redo  Ctrl+Shift+Z"),
                    Command::Redo,
                );
            });
            ui.menu_button("View", |ui| {
                pick(ui, true, "Fit  F", Command::Fit);
                pick(ui, true, "1:1  1", Command::OneToOne);
                pick(ui, true, "Study…", Command::Study);
                ui.separator();
                ui.label("Anti-aliasing");
                for aa in [1, 2, 3, 4] {
                    if ui
                        .selectable_label(self.aa == aa, format!("{aa}×{aa} rays per pixel"))
                        .clicked()
                    {
                        self.aa = aa;
                        self.request_render();
                    }
                }
            });
        });
        if let Some(command) = chosen {
            // Quit goes through the window's close, which asks about edits.
            if command == Command::Quit {
                self.ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            } else {
                self.run(command);
            }
        }
    }

    fn error_banner(&mut self, ui: &mut egui::Ui) {
        let Some(error) = self.doc.error().map(str::to_owned) else {
            return;
        };
        egui::Panel::top("error-banner")
            .frame(
                egui::Frame::new()
                    .fill(Color32::from_rgb(120, 20, 20))
                    .inner_margin(6.0),
            )
            .show(ui, |ui| {
                let what = if self.doc.is_placeholder() {
                    "The file does not load yet; it will show as soon as it does."
                } else {
                    "The last save does not load; showing the last good scene."
                };
                ui.colored_label(Color32::WHITE, format!("{what}\n{error}"));
            });
    }

    fn status_bar(&mut self, ui: &mut egui::Ui) {
        egui::Panel::bottom("status").show(ui, |ui| {
            ui.horizontal(|ui| {
                match self.preview.state() {
                    RenderState::Idle => ui.label("idle"),
                    RenderState::Rendering {
                        scale,
                        tiles_done,
                        tiles_total,
                    } => {
                        let progress = *tiles_done as f32 / (*tiles_total).max(1) as f32;
                        ui.add(egui::ProgressBar::new(progress).desired_width(120.0).text(
                            if *scale == 1 {
                                "rendering".to_owned()
                            } else {
                                format!("preview 1/{scale}")
                            },
                        ))
                    }
                    RenderState::Done { .. } => ui.label("done"),
                    RenderState::Failed(message) => ui.colored_label(Color32::RED, message),
                };
                ui.label(if self.rendered_dragging {
                    self.methods.dragging.as_ref().map_or("", |m| m.name)
                } else {
                    self.methods.preview.name
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
                    FileState::Builtin => "built-in example".to_owned(),
                    FileState::Missing => "file missing: waiting for it to come back".to_owned(),
                    FileState::Watching if self.doc.error().is_some() => {
                        if self.doc.has_unsaved_edits() {
                            "file has errors · unsaved edits".to_owned()
                        } else {
                            "file has errors".to_owned()
                        }
                    }
                    FileState::Watching if self.doc.has_unsaved_edits() => {
                        "unsaved edits (Ctrl+S saves)".to_owned()
                    }
                    FileState::Watching => "watching, saved".to_owned(),
                });
                if let Some((x, y, rgb)) = self.hovered {
                    ui.separator();
                    ui.label(format!(
                        "({x}, {y}) rgb({}, {}, {})",
                        rgb[0], rgb[1], rgb[2]
                    ));
                }
                ui.separator();
                ui.label(format!("{} fps", self.frames.len()));
                if let Some((notice, _)) = &self.notice {
                    ui.separator();
                    ui.label(notice.as_str());
                }
            });
        });
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

    fn picture(&mut self, ui: &mut egui::Ui) {
        egui::CentralPanel::default().show(ui, |ui| {
            if self.preview.take_dirty() || self.texture.is_none() {
                let image = self.preview.image();
                let (w, h) = image.dimensions();
                let color_image =
                    egui::ColorImage::from_rgb([w as usize, h as usize], image.as_raw());
                match &mut self.texture {
                    Some(t) => t.set(color_image, TextureOptions::NEAREST),
                    None => {
                        self.texture = Some(ui.ctx().load_texture(
                            "render",
                            color_image,
                            TextureOptions::NEAREST,
                        ))
                    }
                }
            }
            let Some(texture) = &self.texture else {
                return;
            };
            let area = ui.available_rect_before_wrap();
            let response = ui.allocate_rect(area, Sense::click_and_drag());
            let (w, h) = self.preview.image().dimensions();
            let image_size = Vec2::new(w as f32, h as f32);
            let ppp = ui.ctx().pixels_per_point();
            if self.view.fit {
                let fit = (area.width() / image_size.x).min(area.height() / image_size.y) * ppp;
                // Whole steps when enlarging keep pixels square and crisp.
                self.view.zoom = if fit >= 1.0 { fit.floor() } else { fit };
                self.view.pan = Vec2::ZERO;
            }
            if response.hovered() {
                let (scroll, zoom) = ui.input(|i| (i.smooth_scroll_delta.y, i.zoom_delta()));
                let factor = zoom * (scroll / 200.0).exp();
                if factor != 1.0 {
                    self.view.zoom = (self.view.zoom * factor).clamp(1.0 / 64.0, 64.0);
                    self.view.fit = false;
                }
            }
            if response.dragged() {
                self.view.pan += response.drag_delta();
                self.view.fit = false;
            }
            let size = image_size * self.view.zoom / ppp;
            let rect = Rect::from_center_size(area.center() + self.view.pan, size);
            // Snap to physical pixels so 1:1 stays crisp.
            let rect = Rect::from_min_size(
                Pos2::new(
                    (rect.min.x * ppp).round() / ppp,
                    (rect.min.y * ppp).round() / ppp,
                ),
                size,
            );
            let painter = ui.painter_at(area);
            painter.image(
                texture.id(),
                rect,
                Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
                Color32::WHITE,
            );
            // Pixel inspector and pick.
            self.hovered = None;
            if let Some(pos) = response.hover_pos() {
                let rel = (pos - rect.min) / size * image_size;
                if rel.x >= 0.0 && rel.y >= 0.0 && rel.x < image_size.x && rel.y < image_size.y {
                    let (x, y) = (rel.x as u32, rel.y as u32);
                    let rgb = self.preview.image().get_pixel(x, y).0;
                    self.hovered = Some((x, y, rgb));
                    if response.clicked() {
                        self.pick(f64::from(rel.x), f64::from(rel.y));
                    }
                }
            }
        });
    }

    /// Holds back closing the window while there are unsaved edits: ask.
    fn guard_close(&mut self, ctx: &egui::Context) {
        if ctx.input(|i| i.viewport().close_requested())
            && self.doc.has_unsaved_edits()
            && !self.allow_close
        {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.confirm = Some(Confirm::Discard(Command::Quit));
        }
    }

    fn modals(&mut self, ui: &mut egui::Ui) {
        if let Some(confirm) = self.confirm.clone() {
            self.confirm_modal(ui, confirm);
        }
        if self.doc.conflict().is_some() {
            self.conflict_modal(ui);
        }
        self.path_prompt_modal(ui);
    }

    fn confirm_modal(&mut self, ui: &mut egui::Ui, confirm: Confirm) {
        let mut answer = None;
        egui::Modal::new(egui::Id::unique("confirm")).show(ui.ctx(), |ui| {
            // One width whatever the text: the buttons stay where they were.
            ui.set_width(460.0);
            match &confirm {
                Confirm::Discard(command) => {
                    ui.heading("Unsaved edits");
                    ui.label(format!(
                        "{} has edits that are not saved. {}",
                        self.doc.title(),
                        match command {
                            Command::Quit => "Quit anyway?",
                            Command::Reload => "Reload the file and lose them?",
                            _ => "Open another scene and lose them?",
                        }
                    ));
                    ui.horizontal(|ui| {
                        if ui.button("Save first").clicked() {
                            answer = Some(Answer::SaveThen);
                        }
                        if ui.button("Discard edits").clicked() {
                            answer = Some(Answer::Go);
                        }
                        if ui.button("Cancel").clicked() {
                            answer = Some(Answer::Cancel);
                        }
                    });
                }
                Confirm::Replace(path) => {
                    ui.heading("Replace the file?");
                    ui.label(format!("{} already exists.", path.display()));
                    ui.horizontal(|ui| {
                        if ui.button("Replace").clicked() {
                            answer = Some(Answer::Go);
                        }
                        if ui.button("Cancel").clicked() {
                            answer = Some(Answer::Cancel);
                        }
                    });
                }
            }
        });
        if ui.input(|i| i.key_pressed(Key::Escape)) {
            answer = Some(Answer::Cancel);
        }
        let Some(answer) = answer else { return };
        self.confirm = None;
        match (answer, confirm) {
            (Answer::Cancel, _) => {}
            (Answer::Go, Confirm::Replace(path)) => self.save_as(&path),
            (Answer::Go, Confirm::Discard(command)) => self.execute(command),
            (Answer::SaveThen, Confirm::Discard(command)) => {
                self.save();
                // Saved (no conflict, no error): go on; else the edits stay.
                if !self.doc.has_unsaved_edits() && self.doc.conflict().is_none() {
                    self.execute(command);
                }
            }
            (Answer::SaveThen, Confirm::Replace(_)) => {}
        }
    }

    /// The file changed on disk and some unsaved edits touch what it
    /// changed: both values side by side, a choice for each.
    fn conflict_modal(&mut self, ui: &mut egui::Ui) {
        let Some(pending) = self.doc.conflict() else {
            return;
        };
        let conflicts = pending.conflicts().to_vec();
        self.conflict_choices
            .resize(conflicts.len(), Choice::Theirs);
        let mut done = None;
        egui::Modal::new(egui::Id::unique("conflict")).show(ui.ctx(), |ui| {
            ui.heading("The file changed on disk");
            ui.set_max_width(640.0);
            ui.label(
                "Another program saved the scene file, and it changed values you have \
                 edited too (any other edits of yours are applied onto its version). \
                 Choose which to keep:",
            );
            egui::Grid::new("conflicts").num_columns(3).show(ui, |ui| {
                ui.strong("value");
                ui.strong("yours");
                ui.strong("the file's");
                ui.end_row();
                for (c, choice) in conflicts.iter().zip(self.conflict_choices.iter_mut()) {
                    ui.label(&c.path);
                    ui.add_enabled_ui(c.can_keep_yours, |ui| {
                        ui.radio_value(choice, Choice::Mine, &c.yours);
                    });
                    ui.radio_value(choice, Choice::Theirs, &c.theirs);
                    ui.end_row();
                }
            });
            ui.horizontal(|ui| {
                if ui.button("Apply these choices").clicked() {
                    done = Some(self.conflict_choices.clone());
                }
                if ui.button("Keep all of mine").clicked() {
                    done = Some(
                        conflicts
                            .iter()
                            .map(|c| {
                                if c.can_keep_yours {
                                    Choice::Mine
                                } else {
                                    Choice::Theirs
                                }
                            })
                            .collect(),
                    );
                }
                if ui.button("Take all of the file's").clicked() {
                    done = Some(vec![Choice::Theirs; conflicts.len()]);
                }
            });
        });
        if let Some(choices) = done {
            match self.doc.resolve(&choices) {
                Ok(_) => self.notify("merged".into()),
                Err(e) => self.notify(format!("not saved: {e}")),
            }
            self.conflict_choices.clear();
            self.after_edit();
        }
    }

    fn path_prompt_modal(&mut self, ui: &mut egui::Ui) {
        let mut chosen = None;
        let Some(prompt) = &mut self.path_prompt else {
            return;
        };
        let mut close = false;
        egui::Modal::new(egui::Id::unique("path-prompt")).show(ui.ctx(), |ui| {
            ui.label(match prompt.kind {
                DialogKind::Open => "Open scene file:",
                DialogKind::SaveAs => "Save scene as:",
                DialogKind::Export => "Export image to (.png or .jpg):",
            });
            let edit = ui.text_edit_singleline(&mut prompt.text);
            if !prompt.focused {
                edit.request_focus();
                prompt.focused = true;
            }
            if ui.input(|i| i.key_pressed(Key::Escape)) {
                close = true;
            }
            ui.horizontal(|ui| {
                let enter = edit.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter));
                if (ui.button("OK").clicked() || enter) && !prompt.text.trim().is_empty() {
                    chosen = Some(PathBuf::from(prompt.text.trim()));
                    close = true;
                }
                if ui.button("Cancel").clicked() {
                    close = true;
                }
            });
        });
        if close {
            let prompt = self.path_prompt.take();
            if let (Some(prompt), Some(path)) = (prompt, chosen) {
                self.path_chosen(prompt.kind, path);
            }
        }
    }

    fn count_frame(&mut self) {
        let now = Instant::now();
        // Once a second, with RAYOFLIGHT_STATS set: the figures the status
        // bar shows, on stderr, for measuring the app from outside.
        if self.stats && now.duration_since(self.last_stats) >= Duration::from_secs(1) {
            self.last_stats = now;
            eprintln!(
                "stats: fps={} state={:?} first_pass_ms={:?} last_render_ms={:?}",
                self.frames.len(),
                self.preview.state(),
                self.preview.first_pass().map(|d| d.as_secs_f64() * 1e3),
                self.preview
                    .last_render()
                    .map(|(d, _)| d.as_secs_f64() * 1e3),
            );
        }
        self.frames.push_back(now);
        while self
            .frames
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
        {
            self.frames.pop_front();
        }
        if self
            .notice
            .as_ref()
            .is_some_and(|(_, t)| t.elapsed() > Duration::from_secs(8))
        {
            self.notice = None;
        }
    }
}

impl eframe::App for RayOfLightApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.draw(ui);
    }
}

impl RayOfLightApp {
    /// The whole window's content for one frame.
    pub fn draw(&mut self, ui: &mut egui::Ui) {
        self.count_frame();
        self.drain_events();
        let ctx = ui.ctx().clone();
        self.guard_close(&ctx);
        self.shortcuts(&ctx);
        let title = format!(
            "RayOfLight — {}{}",
            self.doc.title(),
            if self.doc.has_unsaved_edits() {
                " •"
            } else {
                ""
            }
        );
        if title != self.title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
        egui::Panel::top("menu").show(ui, |ui| self.menu_bar(ui));
        self.error_banner(ui);
        self.status_bar(ui);
        self.side_panel(ui);
        self.picture(ui);
        self.modals(ui);
        if self.study.open {
            for action in self.study.show(&ctx, &self.methods) {
                self.study_action(action);
            }
        }
        // A value was dragged with the cheaper method: exact on release.
        if self.rendered_dragging && !ctx.input(|i| i.pointer.any_down()) {
            self.request_render();
        }
        if self.study.is_running() {
            ctx.request_repaint_after(Duration::from_millis(100));
        }
        if matches!(self.preview.state(), RenderState::Rendering { .. }) || self.stats {
            // Keep the progress bar moving between tiles.
            ctx.request_repaint_after(Duration::from_millis(16));
        }
    }
}
