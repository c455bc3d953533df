//! The live preview and the events that reach the app: render requests
//! (coarse to fine, or one interactive pass at the pace's scale while the
//! mouse moves, each waiting for the one in flight), the worker's tiles and
//! passes, the watcher's file events, dialogs' answers, the Study window's
//! runs, and what the user's editor says over the editor link (its
//! unsaved text of the open file, shown as it comes, and the object its
//! cursor is in, selected).

use super::{Background, RayOfLightApp};
use crate::desktop::editor_link::apply_change;
use crate::gui::panel::Selection;
use crate::gui::study;
use crate::session::document::{EditorBase, Followed, Rebuilt, Reload};
use crate::session::pace::Pace;
use crate::session::preview::RenderState;
use crate::session::watcher::FileEvent;
use crate::session::worker::Event;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The open file as the app follows it: its watcher (and which one is
/// current: events of an older one, for a file no longer open, are
/// dropped), the reports held while a save runs, a large changed file
/// being read, a file being opened in the background.
#[derive(Default)]
pub(super) struct Files {
    pub(super) watcher: Option<crate::session::watcher::SceneWatcher>,
    pub(super) generation: u64,
    /// The watcher's reports that came while a save ran: handled after
    /// it, as they came.
    pub(super) deferred: Vec<FileEvent>,
    pub(super) reading: bool,
    pub(super) loading: Option<super::dialogs::Loading>,
}

/// What the preview renders with: the anti-aliasing (exports' too) and
/// the live preview's method (auto unless chosen in the Study window) and
/// the one while a value is dragged.
#[derive(Default)]
pub(super) struct RenderChoice {
    pub(super) aa: u32,
    pub(super) methods: study::PreviewMethods,
}

/// How long an interactive picture may keep the next one waiting (one
/// that was cancelled never says it is done).
pub(super) const IN_FLIGHT_PATIENCE: Duration = Duration::from_millis(500);

/// The newest render asked for: its generation, when, and how many frames
/// the window had drawn by then (for the frames drawn while it renders,
/// on the `RAYOFLIGHT_STATS` line of its full picture).
#[derive(Debug, Clone, Copy)]
pub(super) struct Asked {
    generation: u64,
    at: Instant,
    frames: u64,
}

/// When the preview renders, how coarse, and what is in flight: the
/// schedule of the renders the app asks the worker for.
#[derive(Debug, Default)]
pub(super) struct RenderSchedule {
    /// The measured cost of rendering, for the interactive scale.
    pub(super) pace: Pace,
    /// The newest request was one interactive pass at this scale: refine
    /// once the mouse stops.
    pub(super) interactive: Option<u32>,
    /// The interactive pass being rendered (generation, asked when), and
    /// whether the scene changed since: render again when it is done.
    pub(super) in_flight: Option<(u64, Instant)>,
    pub(super) render_pending: bool,
    /// The newest render used the while-dragging method: render again
    /// with the exact one on release.
    pub(super) rendered_dragging: bool,
    /// The newest render asked for, and when.
    pub(super) asked: Option<Asked>,
}

impl RayOfLightApp {
    /// Asks the worker for the preview of the current scene, with the
    /// while-dragging method when one is set and a button is held.
    ///
    /// While the mouse moves the camera or drags a value, only one pass is
    /// rendered, as coarse as keeps [`TARGET_FPS`](crate::session::pace::TARGET_FPS)
    /// pictures a second; the next request after the mouse stops refines
    /// from that scale.
    pub(super) fn request_render(&mut self) {
        let interacting = self.interacting();
        // While the mouse moves, a new picture waits for the one being
        // rendered: cancelling it at every move would starve the screen.
        if interacting
            && let Some((_, since)) = self.schedule.in_flight
            && since.elapsed() < IN_FLIGHT_PATIENCE
        {
            self.schedule.render_pending = true;
            return;
        }
        self.schedule.render_pending = false;
        let dragging = self.choice.methods.dragging.is_some() && interacting;
        let request = self.choice.methods.request(dragging, self.choice.aa);
        self.schedule.rendered_dragging = dragging;
        let camera = &self.doc.scene().camera;
        let (width, height) = (camera.width, camera.height);
        let scene = Arc::new(self.doc.scene().clone());
        let generation = if interacting {
            // One pass, on a thread fewer: the gesture keeps a core.
            let scale = self.schedule.pace.interactive_scale(width, height);
            self.schedule.interactive = Some(scale);
            self.worker.request_while_dragging(scene, request, scale)
        } else {
            let passes = match self.schedule.interactive.take() {
                Some(scale) => Pace::refine(scale),
                None => crate::session::worker::passes(width, height),
            };
            self.worker.request_passes(scene, request, passes)
        };
        self.preview.requested();
        self.schedule.asked = Some(Asked {
            generation,
            at: Instant::now(),
            frames: self.status.frame_stats.frames_drawn,
        });
        self.schedule.in_flight = interacting.then(|| (generation, Instant::now()));
        self.study.superseded(generation);
        if self.study.open {
            self.study.set_plan(self.doc.scene());
        }
    }

    /// A drag of the camera or of a value is under way.
    pub(super) fn interacting(&self) -> bool {
        self.screen.interaction.is_navigating()
            || self.screen.interaction.is_grabbing()
            || self.ctx.dragged_id().is_some()
    }

    /// Handles what the watcher, the worker and the dialogs sent.
    pub(super) fn drain_events(&mut self) {
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
                    let finished = match &event {
                        Event::PassFinished {
                            elapsed,
                            rays,
                            scale,
                            since_start,
                            ..
                        } => {
                            self.schedule.pace.measured(*rays, *elapsed);
                            if self.status.frame_stats.stats && *scale == 1 {
                                // The frames drawn while it rendered.
                                let (frames, per_second) = match self.schedule.asked {
                                    Some(asked) if asked.generation == event.generation() => {
                                        let frames =
                                            self.status.frame_stats.frames_drawn - asked.frames;
                                        let secs = asked.at.elapsed().as_secs_f64().max(1e-9);
                                        (frames, frames as f64 / secs)
                                    }
                                    _ => (0, 0.0),
                                };
                                eprintln!(
                                    "stats: full picture {:.1} ms after its request, {frames} frames meanwhile ({per_second:.1} frames/s)",
                                    since_start.as_secs_f64() * 1e3
                                );
                            }
                            true
                        }
                        _ => false,
                    };
                    let generation = event.generation();
                    if self.preview.apply(newest, event) && finished {
                        self.status.frame_stats.pictures.push_back(Instant::now());
                        // The interactive picture is done: the next one.
                        if self
                            .schedule
                            .in_flight
                            .is_some_and(|(g, _)| g == generation)
                        {
                            self.schedule.in_flight = None;
                            if self.schedule.render_pending {
                                self.request_render();
                            }
                        }
                    }
                }
            }
        }
        // The study took the worker from an unfinished preview: finish it.
        if study_ended && !matches!(self.preview.state(), RenderState::Done { .. }) {
            self.request_render();
        }
        while let Ok(message) = self.background.rx.try_recv() {
            match message {
                Background::Ids(key, ids) => self.outline_ready(key, ids),
                Background::Pass(key, image) => self.pass_ready(key, *image),
                Background::File(generation, _) if generation != self.files.generation => {}
                // What the watcher saw while a save ran comes after it.
                Background::File(_, event) if self.dialogs.saving.is_some() => {
                    self.files.deferred.push(event);
                }
                Background::File(_, event) => self.file_event(event),
                Background::Saved(job, outcome) => self.saved(*job, outcome),
                Background::Exported(path, result) => self.exported(&path, result),
                Background::Dialog(kind, path, took) => self.dialog_done(kind, path, took),
                Background::Opened(id, result) => self.opened(id, *result),
                Background::Editor(connection, message) => self.editor_said(connection, message),
                Background::EditorGone(connection) => self.editors.know(connection, None),
                Background::Explained(id, explanation) => self.explained(id, explanation),
            }
        }
    }

    /// The user's editor's unsaved text of the open file is shown as it
    /// comes, and the document again when the editor saves or closes it;
    /// the object or light its cursor is in is selected (outlined, its
    /// marker ringed), and nothing once the cursor leaves every one.
    /// Messages about other files are not this window's.
    fn editor_said(&mut self, connection: u64, message: crate::desktop::editor_link::Message) {
        use crate::desktop::editor_link::{Message, Under};
        let ours = |path: &Path| {
            self.doc
                .path()
                .is_some_and(|open| crate::system::files::same_file(open, path))
        };
        match message {
            Message::Buffer { path, text } if ours(&path) => {
                self.show_editor_text(connection, text.into());
            }
            Message::Change {
                path,
                range,
                text,
                length,
            } if ours(&path) => {
                let held = self
                    .editors
                    .holding
                    .iter()
                    .position(|(c, _)| *c == connection);
                let on_screen = held.is_some_and(|i| i + 1 == self.editors.holding.len())
                    && self.doc.is_following();
                match held {
                    // The text on screen, read again where the edit falls.
                    Some(_) if on_screen => {
                        let followed =
                            self.keeping_selection(|app| app.doc.follow_edit(range, &text, length));
                        match followed {
                            Ok(Followed::Shown) => {}
                            // This editor's text is the file's again.
                            Ok(Followed::File(base)) => {
                                self.editors.holding.pop();
                                self.editors.know(connection, Some(base));
                                self.show_newest_held();
                            }
                            Err(_) => {
                                self.editors.holding.pop();
                                self.ask_again(connection, path);
                                return;
                            }
                        }
                        self.after_edit();
                    }
                    // Another editor's text: now the newest, shown.
                    Some(i) => {
                        let (_, held) = self.editors.holding.remove(i);
                        let changed = held.and_then(|mut held| {
                            apply_change(&mut held, range, &text, length).then_some(held)
                        });
                        match changed {
                            Some(held) => self.show_editor_text(connection, held.into()),
                            None => self.ask_again(connection, path),
                        }
                    }
                    // A text the app keeps off screen (the file's, or one
                    // the editor saved), or was never handed (it opened
                    // the file since): asked for whole again.
                    None => {
                        let base = self.editors.take(connection);
                        match base.and_then(|b| self.doc.text_from(b, range, &text, length)) {
                            Some(text) => self.show_editor_text(connection, text),
                            None => self.ask_again(connection, path),
                        }
                    }
                }
            }
            Message::Select { path, under } if ours(&path) => match under {
                // The object as the panel numbers it now (objects added or
                // deleted in the panel since the file was read move it).
                Some(Under::Object(object)) => {
                    if let Some(n) = self.doc.object_from_text(object) {
                        self.selection = Selection::revealed(Some(n));
                    }
                }
                Some(Under::Light(light)) => self.selection = Selection::light(light),
                // Out of every object and light: nothing outlined.
                None => self.selection = Selection::default(),
            },
            Message::Released { path } if ours(&path) => {
                let on_screen = self.editors.holding.last().map(|(c, _)| *c);
                // Saved (or closed): its next change, if any, is of the
                // text it saved.
                let held = self
                    .editors
                    .holding
                    .iter_mut()
                    .find(|(c, _)| *c == connection);
                let base = match held {
                    Some((_, held @ Some(_))) => held.take().map(EditorBase::saved),
                    Some((_, None)) => self.doc.take_saved_base(),
                    None => None,
                };
                if base.is_some() {
                    self.editors.know(connection, base);
                }
                self.editors.holding.retain(|(c, _)| *c != connection);
                if on_screen != Some(connection) && !self.editors.holding.is_empty() {
                    // Another editor's text is on screen: it stays.
                    return;
                }
                match self.show_newest_held() {
                    // Another editor still holds unsaved text: its newest
                    // is shown again.
                    true => self.notify(
                        "an editor let go of its text: another editor's unsaved text".into(),
                    ),
                    false if self.doc.is_following() => {
                        self.keeping_selection(|app| app.doc.unfollow());
                        self.notify("your editor let go of its text: the file again".into());
                    }
                    false => return,
                }
                self.after_edit();
            }
            _ => {}
        }
    }

    /// Shows `text`, editor `connection`'s newest text of the open file
    /// (or, where it is the file's, another editor's unsaved text if one
    /// holds any); the text on screen before, another editor's, is kept
    /// for when this one lets go.
    fn show_editor_text(&mut self, connection: u64, text: Rebuilt) {
        let was = self.doc.is_following();
        if let Some((c, held)) = self.editors.holding.last_mut()
            && *c != connection
            && held.is_none()
        {
            *held = self.doc.take_editor_text();
        }
        self.editors.holding.retain(|(c, _)| *c != connection);
        // This editor's text is the newest: last in the list.
        match self.keeping_selection(|app| app.doc.follow_rebuilt(text)) {
            Followed::Shown => {
                self.editors.know(connection, None);
                self.editors.holding.push((connection, None));
            }
            // This editor's text is the file's again (it saved): another
            // editor's unsaved text, if one holds any.
            Followed::File(base) => {
                self.editors.know(connection, Some(base));
                self.show_newest_held();
            }
        }
        if !was && self.doc.is_following() {
            self.notify("the panel waits while your editor has unsaved text".into());
        }
        self.after_edit();
    }

    /// Editor `connection`'s text of `path` is not known here (a change
    /// came of a text this app missed): it is asked for whole again.
    fn ask_again(&mut self, connection: u64, path: PathBuf) {
        self.editors.holding.retain(|(c, _)| *c != connection);
        self.editors.know(connection, None);
        self.editors.peers.tell_one(
            connection,
            &crate::desktop::editor_link::Message::Resend { path },
        );
    }

    /// Shows again the newest unsaved text an editor still holds of the
    /// open file; false when none does.
    fn show_newest_held(&mut self) -> bool {
        let Some((editor, held)) = self.editors.holding.pop() else {
            return false;
        };
        let Some(text) = held else {
            // The one on screen: its text is the document's already.
            self.editors.holding.push((editor, None));
            return true;
        };
        match self.keeping_selection(|app| app.doc.follow(text)) {
            Followed::Shown => self.editors.holding.push((editor, None)),
            // Its text is the file's after all.
            Followed::File(base) => self.editors.know(editor, Some(base)),
        }
        true
    }

    pub(super) fn file_event(&mut self, event: FileEvent) {
        self.files.reading = matches!(event, FileEvent::Reading);
        match event {
            FileEvent::Loaded(read) => match self.keeping_selection(|app| app.doc.file_read(*read))
            {
                Reload::Replaced => self.after_edit(),
                Reload::Merged => {
                    self.notify("the file changed on disk: your edits were applied onto it".into());
                    self.after_edit();
                }
                Reload::Conflict => self.dialogs.conflict_choices.clear(),
                Reload::Unchanged | Reload::Broken => {}
            },
            FileEvent::Broken(error) => {
                self.doc.file_broken(&error);
            }
            FileEvent::Missing => self.doc.file_missing(),
            FileEvent::Reading => {}
        }
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
        let progress = std::sync::Arc::default();
        let generation =
            self.worker
                .study(scene, self.study.runs, std::sync::Arc::clone(&progress));
        self.study.started(generation, name, progress);
        self.study.set_plan(self.doc.scene());
    }

    /// Does what the Study window asked.
    pub fn study_action(&mut self, action: study::Action) {
        match action {
            study::Action::Run => self.run_study(),
            study::Action::Cancel => self.worker.cancel(),
            study::Action::Preview(name) => {
                if let Some(method) = crate::render::method(name) {
                    self.choice.methods.preview = method;
                    self.request_render();
                }
            }
            study::Action::WhileDragging(name) => {
                self.choice.methods.dragging = name.and_then(crate::render::method);
            }
        }
    }
}
