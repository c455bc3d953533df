//! The scene being edited: the file's text, the scene it parses to, and the
//! panel's unsaved edits on top of it.
//!
//! The file is the truth until the user edits in the panel; then the edits
//! are kept as an edited copy of the scene until saved (written back into
//! the text with [`crate::scene::splice`], keeping the file's
//! comments and layout) or discarded. A change of the file on disk while
//! edits are unsaved is held back and the user is asked.

use crate::scene::{self, Scene};
use std::path::{Path, PathBuf};

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
    /// The scene was replaced: render it.
    Replaced,
    /// The file is the same as what we have: nothing to do.
    Unchanged,
    /// The file changed while the panel has unsaved edits: ask the user.
    Conflict,
    /// The file does not parse: keep the last good scene, show the error.
    Broken,
}

#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    #[error("{0}")]
    Edit(#[from] scene::edit::EditError),
    #[error("{0}")]
    Output(#[from] crate::output::OutputError),
}

#[derive(Debug, Clone)]
pub struct Document {
    path: Option<PathBuf>,
    /// The source text of `saved`.
    text: String,
    /// The scene as the file says.
    saved: Scene,
    /// The scene on screen: `saved` plus the panel's edits.
    pub scene: Scene,
    state: FileState,
    /// The last load error (`file:line:col: message`), shown in a banner.
    error: Option<String>,
    /// A newer file content held back while edits are unsaved.
    pending: Option<(String, Scene)>,
}

impl Document {
    /// The built-in example scene.
    pub fn builtin() -> Document {
        let text = crate::EXAMPLE_SCENE.to_owned();
        let saved = scene::parse(&text, Path::new("example.xml"))
            .expect("the built-in example scene is valid");
        Document {
            path: None,
            text,
            scene: saved.clone(),
            saved,
            state: FileState::Builtin,
            error: None,
            pending: None,
        }
    }

    /// Opens a file. A file that does not parse is an error here: there is
    /// no last good scene to fall back on.
    pub fn open(path: &Path) -> Result<Document, scene::LoadError> {
        let (text, saved) = scene::load_with_text(path)?;
        Ok(Document {
            path: Some(path.to_owned()),
            text,
            scene: saved.clone(),
            saved,
            state: FileState::Watching,
            error: None,
            pending: None,
        })
    }

    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
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

    pub fn has_unsaved_edits(&self) -> bool {
        self.scene != self.saved
    }

    pub fn has_conflict(&self) -> bool {
        self.pending.is_some()
    }

    /// Drops the panel's edits: back to the file's scene.
    pub fn revert(&mut self) {
        self.scene = self.saved.clone();
    }

    /// The file on disk was read and parsed.
    pub fn file_loaded(&mut self, text: String, parsed: Scene) -> Reload {
        self.state = FileState::Watching;
        self.error = None;
        if text == self.text {
            self.pending = None;
            return Reload::Unchanged;
        }
        if self.has_unsaved_edits() {
            self.pending = Some((text, parsed));
            return Reload::Conflict;
        }
        self.text = text;
        self.saved = parsed.clone();
        self.scene = parsed;
        Reload::Replaced
    }

    /// The file on disk changed but does not parse (or cannot be read).
    pub fn file_broken(&mut self, error: &scene::LoadError) -> Reload {
        self.state = FileState::Watching;
        self.error = Some(error.to_string());
        Reload::Broken
    }

    /// The file disappeared.
    pub fn file_missing(&mut self) {
        self.state = FileState::Missing;
    }

    /// Resolves a conflict: take the file's new content, dropping the edits.
    pub fn take_file_version(&mut self) {
        if let Some((text, parsed)) = self.pending.take() {
            self.text = text;
            self.saved = parsed.clone();
            self.scene = parsed;
        }
    }

    /// Resolves a conflict: keep the panel's edits (saving will overwrite
    /// the file's new content, rewritten from it).
    pub fn keep_edits(&mut self) {
        if let Some((text, parsed)) = self.pending.take() {
            self.text = text;
            self.saved = parsed;
        }
    }

    /// Writes the edits back into the file, keeping its comments and layout.
    pub fn save(&mut self) -> Result<(), SaveError> {
        match self.path.clone() {
            Some(path) => self.save_as(&path),
            None => Ok(()),
        }
    }

    /// Writes the scene to `path` (atomically) and makes it this document's
    /// file.
    pub fn save_as(&mut self, path: &Path) -> Result<(), SaveError> {
        let text = scene::splice::rewrite_by_index(&self.text, path, &self.scene)?;
        crate::output::write_atomic(path, text.as_bytes())?;
        self.text = text;
        self.saved = self.scene.clone();
        self.path = Some(path.to_owned());
        self.state = FileState::Watching;
        Ok(())
    }
}
