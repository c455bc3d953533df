//! Files and questions: opening, saving and exporting (with the system's
//! file dialogs, or a plain path field where none can open), and the modal
//! questions — unsaved edits, replacing a file, conflicts with the file on
//! disk.

use super::command::Command;
use super::{Background, RayOfLightApp};
use crate::render;
use crate::scene::merge::Choice;
use crate::session::document::{Document, Reload, SaveError, SaveJob, SaveOutcome, SaveStep};
use egui::Key;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicU64;
use std::time::{Duration, Instant};

/// The dialogs' part: the path being typed, the question waiting for an
/// answer and the choices made in a conflict, the export and the save
/// under way, the keys-and-mouse window.
#[derive(Default)]
pub(super) struct Dialogs {
    pub(super) path_prompt: Option<PathPrompt>,
    pub(super) confirm: Option<Confirm>,
    /// The user's choice for each conflict of the pending merge.
    pub(super) conflict_choices: Vec<Choice>,
    pub(super) export: Option<Export>,
    pub(super) saving: Option<Saving>,
    /// The keys-and-mouse window is shown.
    pub(super) help: bool,
}

/// A question the app is waiting on.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Confirm {
    /// `Command` would drop unsaved edits.
    Discard(Command),
    /// Save as would replace this existing file.
    Replace(PathBuf),
    /// The file was moved, renamed or deleted since it was read: saving
    /// would make a new file at its old path (then `Command`).
    Missing(Option<Command>),
}

/// A file dialog running on its own thread, so the window keeps painting.
pub(super) enum DialogKind {
    Open,
    SaveAs,
    Export,
}

/// An answer to a [`Confirm`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Answer {
    Go,
    SaveThen,
    /// Save as… instead.
    Elsewhere,
    Cancel,
}

/// A plain path field, offered where no file dialog can open.
pub(super) struct PathPrompt {
    kind: DialogKind,
    text: String,
    /// Keyboard focus was given to the field (once, when it opened).
    focused: bool,
}

impl PathPrompt {
    /// A field for `kind`, holding `text` to start from.
    pub(super) fn new(kind: DialogKind, text: Option<String>) -> PathPrompt {
        PathPrompt {
            kind,
            text: text.unwrap_or_default(),
            focused: false,
        }
    }
}

impl RayOfLightApp {
    /// Replaces the document by the file at `path` (the caller asked about
    /// unsaved edits). A file that does not load opens with its error shown.
    /// Opens `path`: at once when it is small, else on a thread of its
    /// own while the window goes on (a million spheres take seconds to
    /// read), with the status saying so and Esc to stop waiting.
    pub(super) fn open(&mut self, path: &Path) {
        // A file that is not there is said, not opened as a window waiting
        // for it (nor kept in Recent).
        if let Err(e) = std::fs::metadata(path)
            && e.kind() == std::io::ErrorKind::NotFound
        {
            self.notify(format!("not opened: {}: no such file", path.display()));
            return;
        }
        let bytes = std::fs::metadata(path).map_or(0, |m| m.len());
        if bytes < crate::session::BACKGROUND_BYTES {
            match Document::open(path) {
                Ok(doc) => self.replace_document(doc),
                Err(e) => self.notify(e.to_string()),
            }
            return;
        }
        // An open still under way is stopped: this one replaces it.
        if let Some(earlier) = &self.files.loading {
            earlier.progress.stop();
        }
        let id = self.files.loading.as_ref().map_or(1, |l| l.id + 1);
        let progress = Arc::new(crate::scene::LoadProgress::default());
        self.files.loading = Some(Loading {
            id,
            path: path.to_owned(),
            bytes,
            started: Instant::now(),
            progress: Arc::clone(&progress),
        });
        let (tx, ctx, path) = (
            self.background.tx.clone(),
            self.ctx.clone(),
            path.to_owned(),
        );
        let _ = std::thread::Builder::new()
            .name("open".to_owned())
            .spawn(move || {
                let doc = Document::open_counting(&path, Some(&progress));
                let _ = tx.send(Background::Opened(id, Box::new(doc)));
                ctx.request_repaint();
            });
    }

    /// A background open ended.
    pub(super) fn opened(&mut self, id: u64, result: Result<Document, crate::scene::LoadError>) {
        // Cancelled, or another open since: dropped.
        if self.files.loading.as_ref().is_none_or(|l| l.id != id) {
            return;
        }
        self.files.loading = None;
        match result {
            Ok(doc) => self.replace_document(doc),
            Err(e) => self.notify(e.to_string()),
        }
    }

    /// Esc while a file is being opened: stop waiting for it, and stop
    /// the load itself (its thread frees what it made and ends).
    pub(super) fn cancel_loading(&mut self) -> bool {
        let Some(loading) = self.files.loading.take() else {
            return false;
        };
        loading.progress.stop();
        self.notify(format!(
            "stopped opening {} (File › Open opens it)",
            loading.path.display()
        ));
        true
    }

    pub(super) fn save(&mut self) {
        self.save_then(None);
    }

    /// The status of a background open: how far it has got, and
    /// "opening big.xml (170 MB)… 2 s — Esc stops".
    pub(super) fn loading_status(&self) -> Option<(f32, String)> {
        let loading = self.files.loading.as_ref()?;
        Some((
            loading.progress.fraction() as f32,
            format!(
                "opening {} ({:.0} MB)… {:.0} s — Esc stops",
                loading.path.display(),
                loading.bytes as f64 / 1e6,
                loading.started.elapsed().as_secs_f64().floor()
            ),
        ))
    }

    /// Starts saving on a thread of its own ([`SaveJob::spawn`]); `then`
    /// runs once the edits are saved.
    /// Editing goes on meanwhile; what is edited then stays unsaved.
    /// Saves, then runs `then`; asks first when the file is gone (moved,
    /// renamed or deleted since it was read): a new file at its old path
    /// is not what every user expects.
    pub(super) fn save_then(&mut self, then: Option<Command>) {
        if *self.doc.state() == crate::session::document::FileState::Missing
            && self.dialogs.saving.is_none()
        {
            self.dialogs.confirm = Some(Confirm::Missing(then));
            return;
        }
        self.save_now(then);
    }

    /// Saves to the document's path, then runs `then`.
    fn save_now(&mut self, then: Option<Command>) {
        if self.dialogs.saving.is_some() {
            self.notify("already saving: wait for it".into());
            return;
        }
        let job = match self.doc.save_job() {
            Ok(job) => job,
            Err(e) => return self.save_failed(e),
        };
        // The watcher reads the saved file back: it shares what is shown.
        // A large one it does not read back: the job tells it the bytes.
        let job = match &self.files.watcher {
            Some(watcher) => {
                watcher.share(&self.doc.scene().objects);
                job.announcing(watcher.own_writes())
            }
            None => job,
        };
        self.dialogs.saving = Some(Saving {
            then,
            merged: false,
            started: Instant::now(),
        });
        let tx = self.background.tx.clone();
        let ctx = self.ctx.clone();
        job.spawn(move |job, outcome| {
            let _ = tx.send(Background::Saved(Box::new(job), outcome));
            ctx.request_repaint();
        });
    }

    /// A save ended: what it did, then what was to follow it, then the
    /// watcher's reports held back while it ran.
    pub(super) fn saved(&mut self, job: SaveJob, outcome: SaveOutcome) {
        let Some(saving) = self.dialogs.saving.take() else {
            return;
        };
        // The file's version taken, or merged with the edits: the
        // selection goes with its object.
        match self.keeping_selection(|app| app.doc.save_done(job, outcome)) {
            Ok(SaveStep::Again) => {
                // The file's changes were merged with the edits: write both.
                self.after_edit();
                self.save_then(saving.then);
                if let Some(next) = &mut self.dialogs.saving {
                    next.merged = true;
                }
                return;
            }
            Ok(SaveStep::Done(Reload::Replaced)) => {
                self.notify(
                    "the file changed on disk and nothing here was unsaved: showing it".into(),
                );
                self.after_edit();
            }
            Ok(SaveStep::Done(_)) if saving.merged => {
                self.notify("merged the file's changes and saved".into());
            }
            Ok(SaveStep::Done(_)) => self.notify("saved".into()),
            Err(e) => self.save_failed(e),
        }
        if let Some(then) = saving.then {
            if !self.doc.has_unsaved_edits() && self.doc.conflict().is_none() {
                self.execute(then);
            } else if self.doc.conflict().is_none() {
                // Edited while saving, or not saved: ask again.
                self.dialogs.confirm = Some(Confirm::Discard(then));
            }
        }
        for event in std::mem::take(&mut self.files.deferred) {
            self.file_event(event);
        }
    }

    fn save_failed(&mut self, e: SaveError) {
        match e {
            SaveError::NoPath => self.start_dialog(DialogKind::SaveAs),
            SaveError::Conflict => {
                self.notify("the file changed on disk: choose between the versions".into());
                self.dialogs.conflict_choices.clear();
            }
            e => self.notify(format!("not saved: {e}")),
        }
    }

    pub(super) fn save_as(&mut self, path: &Path) {
        match self.doc.save_as(path) {
            Ok(()) => {
                self.notify(format!("saved as {}", path.display()));
                self.watch();
            }
            Err(e) => self.notify(format!("not saved: {e}")),
        }
    }

    /// Renders at full resolution with the chosen anti-aliasing (by the
    /// worker, beside the preview) and writes the file atomically; the status bar
    /// shows its progress and can cancel it. The pass shown (View › Pass)
    /// is what is exported; an EXR holds its floats, unclamped.
    pub(super) fn export(&mut self, path: PathBuf) {
        if let Some(export) = &self.dialogs.export {
            self.notify(format!(
                "already exporting {}: wait for it or cancel it",
                export.path.display()
            ));
            return;
        }
        let scene = self.doc.scene().clone();
        // The same checks as the command line's, before any rendering: the
        // folder, the format and whether it holds the image's size.
        if let Err(e) = crate::output::check_target(&path, scene.camera.width, scene.camera.height)
        {
            self.notify(e.to_string());
            return;
        }
        // Exports are exact whatever the preview uses: auto's options, at
        // the chosen anti-aliasing.
        let request = crate::render::request::RenderRequest {
            method: None,
            aa: Some(self.choice.aa),
            threads: None,
            region: None,
        };
        let export = Export {
            path: path.clone(),
            progress: Arc::new(render::Progress::default()),
            stop: Arc::new(AtomicU64::new(0)),
            started: Instant::now(),
        };
        let job = crate::session::worker::ExportJob {
            pass: crate::output::takes_pass(self.passes.pass, &path).then_some(self.passes.pass),
            scene,
            request,
            progress: export.progress.clone(),
            cancel: render::Cancel::new(export.stop.clone(), 0),
        };
        self.dialogs.export = Some(export);
        let tx = self.background.tx.clone();
        let ctx = self.ctx.clone();
        // Rendered by the worker, beside the preview; written here, on the
        // export's thread.
        self.worker.export(job, move |rendered| {
            use crate::session::worker::Exported;
            let written = rendered.map(|done| {
                done.map(|image| match image {
                    Exported::Pass(image) => crate::output::save_pass(&image, &path),
                    Exported::Picture(image) => crate::output::save(&image, &path),
                })
            });
            let result = match written {
                Ok(Some(saved)) => saved.map(|()| true).map_err(|e| e.to_string()),
                Ok(None) => Ok(false),
                Err(e) => Err(e.to_string()),
            };
            let _ = tx.send(Background::Exported(path, result));
            ctx.request_repaint();
        });
    }

    /// The export ended (see [`Background::Exported`]).
    pub(super) fn exported(&mut self, path: &Path, result: Result<bool, String>) {
        self.dialogs.export = None;
        self.notify(match result {
            Ok(true) => format!("exported {}", path.display()),
            Ok(false) => format!("export of {} cancelled", path.display()),
            Err(e) => format!("export failed: {e}"),
        });
    }

    pub(super) fn start_dialog(&mut self, kind: DialogKind) {
        let tx = self.background.tx.clone();
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

    pub(super) fn dialog_done(&mut self, kind: DialogKind, path: Option<PathBuf>, took: Duration) {
        match path {
            Some(path) => self.path_chosen(kind, path),
            // A dialog that closes at once without a choice could not open
            // (no desktop portal): offer a plain path field instead.
            None if took < Duration::from_millis(300) => {
                self.dialogs.path_prompt = Some(PathPrompt::new(kind, None))
            }
            None => {}
        }
    }

    pub(super) fn path_chosen(&mut self, kind: DialogKind, path: PathBuf) {
        match kind {
            DialogKind::Open => self.run(Command::OpenFile(path)),
            DialogKind::SaveAs => self.run(Command::SaveTo(path)),
            DialogKind::Export => self.export(path),
        }
    }

    /// Holds back closing the window while there are unsaved edits (ask)
    /// or a save runs (close when it is done).
    pub(super) fn guard_close(&mut self, ctx: &egui::Context) {
        if !ctx.input(|i| i.viewport().close_requested()) || self.ending.allow_close {
            return;
        }
        // The window's close button asks as Quit does.
        if self.dialogs.saving.is_some() || self.doc.has_unsaved_edits() {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.run(Command::Quit);
        }
    }

    pub(super) fn modals(&mut self, ui: &mut egui::Ui) {
        if let Some(confirm) = self.dialogs.confirm.clone() {
            self.confirm_modal(ui, confirm);
        }
        if self.doc.conflict().is_some() {
            self.conflict_modal(ui);
        } else {
            self.journal_offer_modal(ui);
        }
        self.path_prompt_modal(ui);
    }

    pub(super) fn confirm_modal(&mut self, ui: &mut egui::Ui, confirm: Confirm) {
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
                Confirm::Missing(_) => {
                    ui.heading("The file is gone");
                    ui.label(format!(
                        "{} was moved, renamed or deleted since it was read. Save the \
                         scene there again as a new file, or somewhere else?",
                        self.doc
                            .path()
                            .map(|p| p.display().to_string())
                            .unwrap_or_default()
                    ));
                    ui.horizontal(|ui| {
                        if ui.button("Save it there again").clicked() {
                            answer = Some(Answer::Go);
                        }
                        if ui.button("Save as…").clicked() {
                            answer = Some(Answer::Elsewhere);
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
        self.dialogs.confirm = None;
        match (answer, confirm) {
            (Answer::Cancel, _) => {}
            (Answer::Go, Confirm::Replace(path)) => self.save_as(&path),
            (Answer::Go, Confirm::Discard(command)) => {
                self.discard_journal();
                self.execute(command);
            }
            // Once saved (no conflict, no error) it goes on; else the edits
            // stay.
            (Answer::SaveThen, Confirm::Discard(command)) => self.save_then(Some(command)),
            (Answer::Go, Confirm::Missing(then)) => self.save_now(then),
            (Answer::Elsewhere, Confirm::Missing(_)) => self.start_dialog(DialogKind::SaveAs),
            (Answer::SaveThen | Answer::Elsewhere, _) => {}
        }
    }

    /// The file changed on disk and some unsaved edits touch what it
    /// changed: both values side by side, a choice for each.
    pub(super) fn conflict_modal(&mut self, ui: &mut egui::Ui) {
        let Some(pending) = self.doc.conflict() else {
            return;
        };
        let conflicts = pending.conflicts().to_vec();
        let restore = pending.is_restore();
        let onto_the_file = pending.is_restore_onto_the_file();
        self.dialogs
            .conflict_choices
            .resize(conflicts.len(), Choice::Theirs);
        let mut done = None;
        let (heading, text, yours, theirs, take_theirs) = match (restore, onto_the_file) {
            (true, true) => (
                "The file changed since these edits were made",
                "Unsaved edits restored from the journal change values that another \
                 program changed in the file since (their other edits are applied onto \
                 its version). Choose which to keep:",
                "the restored edit",
                "the file's",
                "Take all of the file's",
            ),
            (false, _) => (
                "The file changed on disk",
                "Another program saved the scene file, and it changed values you have \
                 edited too (any other edits of yours are applied onto its version). \
                 Choose which to keep:",
                "yours",
                "the file's",
                "Take all of the file's",
            ),
            (true, false) => (
                "Two windows edited the same values",
                "Another window that was open on this file left unsaved edits of values \
                 that are edited here too (its other edits are applied). Choose which to \
                 keep:",
                "the other window's",
                "this window's",
                "Keep all of this window's",
            ),
        };
        egui::Modal::new(egui::Id::unique("conflict")).show(ui.ctx(), |ui| {
            ui.heading(heading);
            ui.set_max_width(640.0);
            ui.label(text);
            egui::Grid::new("conflicts").num_columns(3).show(ui, |ui| {
                ui.strong("value");
                ui.strong(yours);
                ui.strong(theirs);
                ui.end_row();
                for (c, choice) in conflicts
                    .iter()
                    .zip(self.dialogs.conflict_choices.iter_mut())
                {
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
                    done = Some(self.dialogs.conflict_choices.clone());
                }
                let keep_mine = match (restore, onto_the_file) {
                    (false, _) => "Keep all of mine",
                    (true, true) => "Keep all of the restored edits",
                    (true, false) => "Keep all of the other window's",
                };
                if ui.button(keep_mine).clicked() {
                    done = Some(
                        conflicts
                            .iter()
                            .map(crate::scene::merge::Conflict::mine_if_possible)
                            .collect(),
                    );
                }
                if ui.button(take_theirs).clicked() {
                    done = Some(vec![Choice::Theirs; conflicts.len()]);
                }
            });
        });
        if let Some(choices) = done {
            // The selection stays on its object, wherever the merge put it.
            match self.keeping_selection(|app| app.doc.resolve(&choices)) {
                Ok(_) => self.notify("merged".into()),
                Err(e) => self.notify(format!("not saved: {e}")),
            }
            self.dialogs.conflict_choices.clear();
            self.journal_soon();
            self.after_edit();
        }
    }

    pub(super) fn path_prompt_modal(&mut self, ui: &mut egui::Ui) {
        let mut chosen = None;
        let Some(prompt) = &mut self.dialogs.path_prompt else {
            return;
        };
        let mut close = false;
        egui::Modal::new(egui::Id::unique("path-prompt")).show(ui.ctx(), |ui| {
            ui.label(match prompt.kind {
                DialogKind::Open => "Open scene file:",
                DialogKind::SaveAs => "Save scene as:",
                DialogKind::Export => "Export image to (.png, .jpg or .exr):",
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
                    let home = std::env::var_os("HOME").map(PathBuf::from);
                    let typed = prompt.text.trim();
                    chosen = Some(crate::system::files::typed_path(typed, home.as_deref()));
                    close = true;
                }
                if ui.button("Cancel").clicked() {
                    close = true;
                }
            });
        });
        if close {
            let prompt = self.dialogs.path_prompt.take();
            if let (Some(prompt), Some(path)) = (prompt, chosen) {
                self.path_chosen(prompt.kind, path);
            }
        }
    }
}

/// A file being opened on a thread of its own.
pub(super) struct Loading {
    /// Which open this is: a later one (or Esc) drops the earlier's result.
    pub(super) id: u64,
    pub(super) path: PathBuf,
    pub(super) bytes: u64,
    pub(super) started: Instant,
    /// How far the load has got.
    pub(super) progress: Arc<crate::scene::LoadProgress>,
}

/// A save under way (see [`RayOfLightApp::save_then`]).
pub(super) struct Saving {
    /// What to do once saved.
    pub(super) then: Option<Command>,
    /// The file's changes were merged into the edits on the way.
    merged: bool,
    pub(super) started: Instant,
}

/// An export under way: where it goes, how far it is, and its stop switch
/// (the render's cancel token for generation 0 stops once it is set to 1).
pub(super) struct Export {
    pub(super) path: PathBuf,
    pub(super) progress: Arc<render::Progress>,
    pub(super) stop: Arc<AtomicU64>,
    pub(super) started: Instant,
}

impl Export {
    pub(super) fn cancel(&self) {
        self.stop.store(1, std::sync::atomic::Ordering::Relaxed);
    }
}
