//! A [`Document`] and its file on disk: what the watcher read (the same
//! bytes, another version to merge with, a broken or missing file), and
//! saving, which reads the file again first and never writes over text the
//! app has not read.

use super::*;

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

/// A fingerprint of the file's bytes.
pub(super) fn fingerprint(bytes: &[u8]) -> u64 {
    let mut h = std::hash::DefaultHasher::new();
    bytes.len().hash(&mut h);
    bytes.hash(&mut h);
    h.finish()
}

impl Document {
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
        // Gone before the scene is copied: on a big file both are large.
        drop(text);
        self.saved = self.edited.clone();
        self.log.clear();
        self.dirty = false;
        if self.state == FileState::Missing {
            self.state = FileState::Watching;
        }
        Ok(())
    }
}
