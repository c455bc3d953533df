//! The scene being edited: the file's text, the scene with its unsaved
//! edits, undo and redo, and the rules that keep the user's file safe.
//!
//! - Every change goes through [`Document::apply`] as an
//!   [`Edit`](crate::scene::edit::Edit) (panel, keys, viewport) and can be
//!   undone; a whole drag of one value is one undo step. Saving does not
//!   clear the history.
//! - The file is never written over text the app has not read: before each
//!   write the file is read again and its fingerprint compared with the
//!   bytes last read or written. A different file is merged with the
//!   unsaved edits value by value ([`crate::scene::merge`]); the user is
//!   asked only where both changed the same value; a file that does not
//!   load is never written over.
//! - The watcher's reports are compared with that same fingerprint, so an
//!   external write is never mistaken for what the app already has.
//! - A reload from disk with nothing unsaved is an undo step too: undoing
//!   it brings back the scene before it, as unsaved edits.
//!
//! Save-back splices the edits into the text last read from disk (the
//! source the edits' origins point into), so unchanged bytes stay as they
//! are and undoing everything and saving gives the file back byte for byte.

use std::collections::BTreeMap;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

use crate::scene::edit::{Edit, EditError, Edited, Field, Owner, Undo};
use crate::scene::merge::{self, Choice, Conflict};
use crate::scene::{self, LoadError, LoadErrorKind, Scene, splice};

/// Where the scene comes from, and how that source is doing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FileState {
    /// The built-in example, not yet saved anywhere.
    Builtin,
    /// A file on disk, watched for changes.
    Watching,
    /// The file was deleted or moved away; the last scene stays on screen.
    Missing,
}

/// What a change of the file on disk did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Reload {
    /// The scene was replaced by the file's: render it.
    Replaced,
    /// The file changed under unsaved edits, which were applied onto it:
    /// render it.
    Merged,
    /// The file is what the app last read or wrote: nothing to do.
    Unchanged,
    /// The file and the unsaved edits changed the same values: ask.
    Conflict,
    /// The file does not load: keep the last good scene, show the error.
    Broken,
}

/// Why a save did not write.
#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    #[error("there is no file yet: use Save as")]
    NoPath,
    #[error(
        "the file on disk does not load, so it is not written over: {0}; fix it, or use Save as"
    )]
    DiskBroken(Box<LoadError>),
    #[error("the file changed on disk and some of your edits conflict with it: choose first")]
    Conflict,
    #[error("no scene has loaded from the file yet: fix the file first")]
    NothingLoaded,
    #[error("{0}")]
    Edit(#[from] EditError),
    #[error("{0}")]
    Output(#[from] crate::output::OutputError),
}

/// A file version that conflicts with the unsaved edits, waiting for the
/// user's choices.
#[derive(Debug, Clone)]
pub struct PendingMerge {
    text: String,
    scene: Scene,
    conflicts: Vec<Conflict>,
    /// Save once the conflicts are settled (the merge came from Ctrl+S).
    save_after: bool,
}

impl PendingMerge {
    pub fn conflicts(&self) -> &[Conflict] {
        &self.conflicts
    }
}

/// One entry of the undo (or redo) stack.
#[derive(Debug, Clone)]
struct Step {
    /// "ka of #2 sphere".
    label: String,
    /// Applied last to first.
    undos: Vec<Undo>,
    /// What is being dragged: the next edit of the same values in the same
    /// drag joins this step.
    dragging: Option<DragKey>,
}

/// What a drag changes: values, or a whole transformation.
#[derive(Debug, Clone, Copy, PartialEq)]
enum DragValue {
    Field(Field),
    Transform(Owner),
}

type DragKey = Vec<DragValue>;

/// What `edits` change, if they are edits a drag makes (set values, move
/// the camera).
fn drag_key(edits: &[Edit]) -> Option<DragKey> {
    edits
        .iter()
        .map(|e| match e {
            Edit::Set(field, _) => Some(DragValue::Field(*field)),
            Edit::Transform(owner, _) => Some(DragValue::Transform(*owner)),
            Edit::Insert(..) | Edit::Remove(_) => None,
        })
        .collect()
}

/// "ka of #2 sphere"; "colour of #1 sphere" for a colour's channels set
/// together, "position of light 1" for a light's coordinates.
fn step_label(edits: &[Edit], scene: &Scene) -> String {
    let first = edits
        .first()
        .map_or_else(String::new, |e| e.describe(scene));
    let all = |f: fn(&Field) -> bool| {
        edits.len() > 1
            && edits
                .iter()
                .all(|e| matches!(e, Edit::Set(field, _) if f(field)))
    };
    let colour = all(|f| matches!(f, Field::Color { .. } | Field::LightColor { .. }));
    let position = all(|f| matches!(f, Field::LightPosition { .. }));
    match first.split_once(" of ") {
        Some((_, of)) if colour => format!("colour of {of}"),
        Some((_, of)) if position => format!("position of {of}"),
        _ => first,
    }
}

/// A fingerprint of the file's bytes.
fn fingerprint(bytes: &[u8]) -> u64 {
    let mut h = std::hash::DefaultHasher::new();
    bytes.len().hash(&mut h);
    bytes.hash(&mut h);
    h.finish()
}

#[derive(Debug, Clone)]
pub struct Document {
    path: Option<PathBuf>,
    /// The text last read from the file, which the elements' origins point
    /// into; saves splice the edits into it.
    source: String,
    /// The file's bytes as last read or written, or `None` when unknown
    /// (never read, or missing).
    disk: Option<u64>,
    /// The scene the file holds as of the last read or write.
    /// (With the origins it had then: reverting keeps every element's text.)
    saved: Edited,
    /// The scene on screen: `saved` plus the unsaved edits.
    edited: Edited,
    /// `edited` differs from `saved`.
    dirty: bool,
    /// The edits since the file was last read or written, replayed onto a
    /// newer file.
    log: Vec<Edit>,
    undo: Vec<Step>,
    redo: Vec<Step>,
    state: FileState,
    /// The last load error (`file:line:col: message`), shown in a banner.
    error: Option<String>,
    /// No scene has loaded from the file yet (it was broken when opened):
    /// the panel is read-only and saving refuses.
    placeholder: bool,
    conflict: Option<PendingMerge>,
    /// The first words of the comment above each object of `source`.
    labels: Vec<Option<String>>,
}

impl Document {
    fn from_text(path: Option<PathBuf>, text: String, scene: Scene, state: FileState) -> Document {
        Document {
            path,
            disk: Some(fingerprint(text.as_bytes())),
            labels: splice::object_labels(&text),
            source: text,
            saved: Edited::new(scene.clone()),
            edited: Edited::new(scene),
            dirty: false,
            log: Vec::new(),
            undo: Vec::new(),
            redo: Vec::new(),
            state,
            error: None,
            placeholder: false,
            conflict: None,
        }
    }

    /// The built-in example scene.
    pub fn builtin() -> Document {
        let text = crate::EXAMPLE_SCENE.to_owned();
        let scene = scene::parse(&text, Path::new("example.xml"))
            .expect("the built-in example scene is valid");
        let mut doc = Document::from_text(None, text, scene, FileState::Builtin);
        doc.disk = None;
        doc
    }

    /// Opens a file. A file that does not load (or is not there yet) opens
    /// all the same, on an empty scene with the error shown, and is picked
    /// up when it is fixed; only a directory is refused.
    pub fn open(path: &Path) -> Result<Document, LoadError> {
        match scene::load_with_text(path) {
            Ok((text, scene)) => Ok(Document::from_text(
                Some(path.to_owned()),
                text,
                scene,
                FileState::Watching,
            )),
            Err(e) if e.kind == LoadErrorKind::IsDirectory => Err(e),
            Err(e) => {
                let missing = matches!(
                    &e.kind,
                    LoadErrorKind::Io { kind, .. } if *kind == std::io::ErrorKind::NotFound
                );
                let mut doc = Document::placeholder(path);
                if missing {
                    doc.state = FileState::Missing;
                } else {
                    doc.error = Some(e.to_string());
                }
                Ok(doc)
            }
        }
    }

    /// An empty scene standing in for a file that has not loaded yet.
    fn placeholder(path: &Path) -> Document {
        let text = "<scene><camera width=\"320\" height=\"240\" eyeDistance=\"1\"/></scene>";
        let scene = scene::parse(text, path).expect("the placeholder scene is valid");
        let mut doc = Document::from_text(
            Some(path.to_owned()),
            text.to_owned(),
            scene,
            FileState::Watching,
        );
        doc.disk = None;
        doc.placeholder = true;
        doc
    }

    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// The scene on screen.
    pub fn scene(&self) -> &Scene {
        self.edited.scene()
    }

    /// A short name for the title bar.
    pub fn title(&self) -> String {
        match &self.path {
            Some(p) => p.display().to_string(),
            None => "built-in example".to_owned(),
        }
    }

    pub fn state(&self) -> &FileState {
        &self.state
    }

    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// No scene has loaded from the file yet: nothing to edit or save.
    pub fn is_placeholder(&self) -> bool {
        self.placeholder
    }

    pub fn has_unsaved_edits(&self) -> bool {
        self.dirty
    }

    pub fn conflict(&self) -> Option<&PendingMerge> {
        self.conflict.as_ref()
    }

    /// The panel's name for object `n`: `#2 RED sphere` when a comment
    /// directly above it in the file starts with "RED", else `#2 sphere`.
    pub fn object_label(&self, n: usize) -> String {
        let shape = self
            .scene()
            .objects
            .get(n)
            .map_or("object", |o| o.shape.name());
        let words = self
            .edited
            .object_origin(n)
            .and_then(|k| self.labels.get(k).cloned().flatten());
        match words {
            Some(w) if w.to_lowercase().ends_with(shape) => format!("#{} {w}", n + 1),
            Some(w) => format!("#{} {w} {shape}", n + 1),
            None => format!("#{} {shape}", n + 1),
        }
    }

    /// The scene as the file holds it (after the last read or write).
    pub fn file_scene(&self) -> &Scene {
        self.saved.scene()
    }

    /// The scene with, for each element, where it came from in the text
    /// last read from disk.
    pub fn edited(&self) -> &Edited {
        &self.edited
    }

    // ----- edits, undo, redo -----

    /// Applies an edit as one undo step.
    pub fn apply(&mut self, edit: Edit) -> Result<(), EditError> {
        self.apply_step(vec![edit], false)
    }

    /// Applies edits made together (the three channels of a picked colour)
    /// as one undo step; on an error none is applied. With `dragging`, the
    /// edits of the same fields right after ones also made while dragging
    /// join their step: a whole drag is undone at once.
    pub fn apply_step(&mut self, edits: Vec<Edit>, dragging: bool) -> Result<(), EditError> {
        if edits.is_empty() {
            return Ok(());
        }
        if self.placeholder {
            return Err(EditError::Path {
                path: "scene".to_owned(),
                message: "no scene has loaded from the file yet".to_owned(),
            });
        }
        let label = step_label(&edits, self.scene());
        let mut undos = Vec::new();
        for edit in &edits {
            match self.edited.apply(edit) {
                Ok(undo) => undos.push(undo),
                Err(e) => {
                    // Leave the scene as it was.
                    for undo in undos.into_iter().rev() {
                        let _ = self.edited.undo(undo);
                    }
                    return Err(e);
                }
            }
        }
        let key = if dragging { drag_key(&edits) } else { None };
        let joins = key.is_some()
            && self.redo.is_empty()
            && self.undo.last().is_some_and(|s| s.dragging == key);
        if !joins {
            self.undo.push(Step {
                label,
                undos,
                dragging: key,
            });
        }
        self.redo.clear();
        for edit in edits {
            self.log_edit(edit);
        }
        self.update_dirty();
        Ok(())
    }

    /// Adds `edit` to the unsaved edits. A value set again right after it
    /// was set (each step of a drag), or the camera moved again, replaces
    /// the earlier one: a merge replays, and asks about, each value once.
    fn log_edit(&mut self, edit: Edit) {
        let replaces = match (&edit, self.log.last()) {
            (Edit::Set(field, _), Some(Edit::Set(last, _))) => field == last,
            (Edit::Transform(owner, _), Some(Edit::Transform(last, _))) => owner == last,
            _ => false,
        };
        if replaces {
            self.log.pop();
        }
        self.log.push(edit);
    }

    /// Ends a drag: the next edit of the same field is a step of its own.
    pub fn end_drag(&mut self) {
        if let Some(step) = self.undo.last_mut() {
            step.dragging = None;
        }
    }

    /// "Undo ka of #2 sphere", if there is anything to undo.
    pub fn undo_label(&self) -> Option<&str> {
        self.undo.last().map(|s| s.label.as_str())
    }

    pub fn redo_label(&self) -> Option<&str> {
        self.redo.last().map(|s| s.label.as_str())
    }

    /// Undoes the last step; returns its label.
    pub fn undo(&mut self) -> Option<String> {
        let step = self.undo.pop()?;
        let label = step.label.clone();
        let redo = self.replay(step);
        self.redo.push(redo);
        Some(label)
    }

    /// Redoes the last undone step; returns its label.
    pub fn redo(&mut self) -> Option<String> {
        let step = self.redo.pop()?;
        let label = step.label.clone();
        let undo = self.replay(step);
        self.undo.push(undo);
        Some(label)
    }

    /// Applies a step's undos, last first, and returns the step that
    /// reverses it.
    fn replay(&mut self, step: Step) -> Step {
        let mut back = Vec::new();
        for undo in step.undos.into_iter().rev() {
            let edit = undo.edit().clone();
            // Each undo reverses an edit that was applied to exactly this
            // state, so it applies; one that does not is skipped rather than
            // leaving the stack half done.
            if let Ok(reverse) = self.edited.undo(undo) {
                self.log_edit(edit);
                back.push(reverse);
            }
        }
        self.update_dirty();
        // The reverses, applied last to first, undo this in reverse order.
        Step {
            label: step.label,
            undos: back,
            dragging: None,
        }
    }

    fn update_dirty(&mut self) {
        self.dirty = self.scene() != self.saved.scene();
        if !self.dirty {
            // Back to what the file holds: nothing to replay onto it.
            self.log.clear();
        }
    }

    /// Drops the unsaved edits: back to the file's scene, as one undo step.
    /// Undoing the revert brings the edits back by their paths.
    pub fn revert(&mut self) {
        if !self.dirty {
            return;
        }
        let back = merge::edits_between(self.saved.scene(), self.scene());
        self.edited = self.saved.clone();
        self.undo.push(Step {
            label: "revert edits".to_owned(),
            undos: back.into_iter().rev().map(Undo::from_edit).collect(),
            dragging: None,
        });
        self.redo.clear();
        self.update_dirty();
    }

    // ----- the file on disk -----

    /// The file on disk was read and loads (`text`, `parsed`).
    pub fn file_loaded(&mut self, text: String, parsed: Scene) -> Reload {
        self.state = FileState::Watching;
        self.error = None;
        if self.disk == Some(fingerprint(text.as_bytes())) {
            return Reload::Unchanged;
        }
        if self.placeholder {
            *self = Document::from_text(self.path.clone(), text, parsed, FileState::Watching);
            return Reload::Replaced;
        }
        let save_after = self.conflict.as_ref().is_some_and(|c| c.save_after);
        if !self.dirty && self.conflict.is_none() {
            // Undoing the reload brings back the scene before it.
            let back = merge::edits_between(&parsed, self.scene());
            let undos = back.into_iter().rev().map(Undo::from_edit).collect();
            self.rebase(text, parsed.clone(), Edited::new(parsed), Vec::new());
            self.undo.push(Step {
                label: "reload from disk".to_owned(),
                undos,
                dragging: None,
            });
            self.redo.clear();
            return Reload::Replaced;
        }
        self.merge_with(text, parsed, &BTreeMap::new(), save_after)
    }

    /// Replays the unsaved edits onto the file's `text`; with conflicts
    /// left, keeps it pending and asks.
    fn merge_with(
        &mut self,
        text: String,
        theirs: Scene,
        choices: &BTreeMap<usize, Choice>,
        save_after: bool,
    ) -> Reload {
        let merged = merge::merge(self.saved.scene(), &theirs, &self.log, choices);
        if !merged.conflicts.is_empty() {
            self.conflict = Some(PendingMerge {
                text,
                scene: theirs,
                conflicts: merged.conflicts,
                save_after,
            });
            return Reload::Conflict;
        }
        self.conflict = None;
        self.rebase(text, theirs, merged.edited, merged.applied);
        Reload::Merged
    }

    /// The file's `text` (loading to `theirs`) becomes the source; the
    /// scene on screen becomes `edited`, whose origins point into it, with
    /// `log` its unsaved edits.
    fn rebase(&mut self, text: String, theirs: Scene, edited: Edited, log: Vec<Edit>) {
        self.disk = Some(fingerprint(text.as_bytes()));
        self.labels = splice::object_labels(&text);
        self.source = text;
        self.saved = Edited::new(theirs);
        self.edited = edited;
        self.log = log;
        // The origins the stacks would restore point into the old text.
        for step in self.undo.iter_mut().chain(self.redo.iter_mut()) {
            step.dragging = None;
            for undo in &mut step.undos {
                undo.forget_origin();
            }
        }
        self.update_dirty();
    }

    /// Settles the pending conflicts: `choices[i]` for `conflicts()[i]`.
    /// Returns what happened, and saves if the merge came from a save.
    pub fn resolve(&mut self, choices: &[Choice]) -> Result<Reload, SaveError> {
        let Some(pending) = self.conflict.take() else {
            return Ok(Reload::Unchanged);
        };
        let map: BTreeMap<usize, Choice> = pending
            .conflicts
            .iter()
            .zip(choices)
            .map(|(c, choice)| (c.edit, *choice))
            .collect();
        let reload = self.merge_with(pending.text, pending.scene, &map, pending.save_after);
        if reload == Reload::Merged && pending.save_after {
            self.save()?;
        }
        Ok(reload)
    }

    /// The file on disk changed but does not load (or cannot be read).
    pub fn file_broken(&mut self, error: &LoadError) -> Reload {
        self.state = FileState::Watching;
        self.error = Some(error.to_string());
        Reload::Broken
    }

    /// The file disappeared.
    pub fn file_missing(&mut self) {
        self.state = FileState::Missing;
    }

    /// Writes the edits into the file. The file is read first: if it is not
    /// what the app last read or wrote, the edits are merged onto it (and
    /// the user asked on conflicts) — never written over unread text.
    pub fn save(&mut self) -> Result<Reload, SaveError> {
        let Some(path) = self.path.clone() else {
            return Err(SaveError::NoPath);
        };
        if self.conflict.is_some() {
            return Err(SaveError::Conflict);
        }
        if self.placeholder {
            return Err(SaveError::NothingLoaded);
        }
        let reload = match std::fs::read(&path) {
            // Nothing unsaved and the file as we know it: nothing to do.
            Ok(bytes) if Some(fingerprint(&bytes)) == self.disk && !self.dirty => {
                return Ok(Reload::Unchanged);
            }
            Ok(bytes) if Some(fingerprint(&bytes)) == self.disk => Reload::Unchanged,
            Ok(_) => {
                let (text, theirs) =
                    scene::load_with_text(&path).map_err(|e| SaveError::DiskBroken(Box::new(e)))?;
                if !self.dirty && self.log.is_empty() {
                    // Nothing of ours to write: take the file's version.
                    return Ok(self.file_loaded(text, theirs));
                }
                match self.merge_with(text, theirs, &BTreeMap::new(), true) {
                    Reload::Conflict => return Err(SaveError::Conflict),
                    other => other,
                }
            }
            // A file deleted since: writing brings it back.
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Reload::Unchanged,
            Err(e) => {
                return Err(SaveError::DiskBroken(Box::new(LoadError::new(
                    &path,
                    None,
                    LoadErrorKind::Io {
                        kind: e.kind(),
                        message: e.to_string(),
                    },
                ))));
            }
        };
        self.write(&path)?;
        Ok(reload)
    }

    /// Writes the scene to `path` (atomically, through a symbolic link) and
    /// makes it this document's file. Asking before replacing another file
    /// is the caller's.
    pub fn save_as(&mut self, path: &Path) -> Result<(), SaveError> {
        if self.placeholder {
            return Err(SaveError::NothingLoaded);
        }
        self.write(path)?;
        self.path = Some(path.to_owned());
        self.state = FileState::Watching;
        self.error = None;
        self.conflict = None;
        Ok(())
    }

    fn write(&mut self, path: &Path) -> Result<(), SaveError> {
        let text = splice::save(&self.source, path, &self.edited)?;
        crate::output::write_atomic(path, text.as_bytes())?;
        self.disk = Some(fingerprint(text.as_bytes()));
        self.saved = self.edited.clone();
        self.log.clear();
        self.dirty = false;
        if self.state == FileState::Missing {
            self.state = FileState::Watching;
        }
        Ok(())
    }
}
