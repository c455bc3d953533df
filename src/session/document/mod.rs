//! The scene being edited: the file's text, the scene with its unsaved
//! edits, undo and redo, and the rules that keep the user's file safe.
//!
//! - Every change goes through [`Document::apply`] as an
//!   [`Edit`](crate::scene::edit::Edit) (panel, keys, viewport) and can be
//!   undone; a whole drag of one value is one undo step. Saving does not
//!   clear the history.
//! - The document holds two [`Version`]s, each a text with the scene shown
//!   from it: the file's, and the one on screen. The unsaved edits are what
//!   differs between their scenes, element by element.
//! - The file is never written over text the app has not read: before each
//!   write the file is read again and its fingerprint compared with the
//!   bytes last read or written. A different file is merged with the
//!   unsaved edits ([`crate::scene::merge`]), each edit going to the same
//!   element however the other program moved things around it; the user is
//!   asked only where both changed the same value or the element is gone;
//!   a file that does not load is never written over.
//! - The watcher's reports are compared with that same fingerprint, so an
//!   external write is never mistaken for what the app already has.
//! - A reload from disk, a merge and a revert are undo steps too: undoing
//!   one puts the version on screen before it back whole, so its text comes
//!   back byte for byte, as unsaved edits against the file.
//! - While the user's editor has unsaved text of the file (handed over by
//!   `rayoflight lsp`, [`Document::follow`]), a third version, the
//!   editor's, is on screen; the other two wait untouched, and edits,
//!   undo and saving wait with them until the editor lets go.
//!
//! Save-back splices the edits into the text of the version on screen
//! (the source the edits' origins point into), so unchanged bytes stay as
//! they are and undoing everything and saving gives the file back byte for
//! byte. A large text is held packed ([`Source`]: a million spheres' 214
//! MB in about 40) and a save reads it back a block at a time
//! ([`scene::splice::plan_source`]), never whole.
//!
//! The undo history lives in `history`, reading the file in `disk`,
//! saving (on another thread if need be) in `save`, what the journal of
//! unsaved edits needs in `restore`.

mod disk;
mod follow;
mod history;
mod restore;
mod save;

pub use disk::{FileRead, FingerprintError, PendingMerge, Reload, SaveError, fingerprint_file};
use disk::{fingerprint, fingerprint_source};
pub use follow::{EditorBase, Followed, Rebuilt, Unfit};
use history::Step;
pub use restore::{TextWriter, fingerprint_text};
pub use save::{OwnWrites, SaveJob, SaveOutcome, SaveStep};

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::scene::edit::Edited;
use crate::scene::source::Source;
use crate::scene::{self, LoadError, LoadErrorKind, Scene, names};

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
/// A text and what is shown from it: the text the elements' origins point
/// into, the scene it loads to, the edited scene and the objects' labels.
///
/// The document holds two: the file's (what the file holds as last read or
/// written) and the one on screen. A reload, a merge or a revert replaces
/// the one on screen whole, and undoing it puts the old one back, so its
/// text comes back byte for byte, comments and spelling included.
#[derive(Debug, Clone)]
pub(crate) struct Version {
    /// The text the origins of `edited` point into; saves splice the edits
    /// into it. A large one is held packed ([`Source`]).
    source: Source,
    /// The scene `source` loads to (sharing its objects with `edited` where
    /// they are the same): saves compare with it rather than parse the text
    /// again.
    source_scene: Scene,
    /// The scene, with where each element came from in `source`.
    edited: Edited,
    /// The first words of the comment above each object of `source`.
    labels: Arc<names::Labels>,
    /// Where the root's children sit in `source`, where the load said
    /// (following an editor's text of the file starts from it).
    layout: Option<Arc<scene::Layout>>,
    /// The fingerprint of `source`'s text, where it was read from a file
    /// (an editor's saved text is known again as the file's by it).
    fingerprint: Option<u64>,
}

impl Version {
    fn new(text: Source, scene: Scene, labels: Arc<names::Labels>) -> Version {
        Version {
            source: text,
            source_scene: scene.clone(),
            edited: Edited::new(scene),
            labels,
            layout: None,
            fingerprint: None,
        }
    }

    /// Whether this writes the same text as `other` would: the same source
    /// and the same scene. (Two versions of one source text share it.)
    fn same_as(&self, other: &Version) -> bool {
        self.source.same(&other.source) && self.edited.scene() == other.edited.scene()
    }
}

#[derive(Debug, Clone)]
pub struct Document {
    path: Option<PathBuf>,
    /// What the file holds as of the last read or write (its `edited` is the
    /// scene there, with the origins it had then: reverting keeps every
    /// element's text).
    file: Version,
    /// The scene on screen: the file's plus the unsaved edits, or another
    /// text altogether after undoing a reload.
    shown: Version,
    /// The file's bytes as last read or written, or `None` when unknown
    /// (never read, or missing).
    disk: Option<u64>,
    /// `shown` would write another text than the file's.
    dirty: bool,
    undo: Vec<Step>,
    redo: Vec<Step>,
    state: FileState,
    /// The last load error (`file:line:col: message`), shown in a banner.
    error: Option<String>,
    /// No scene has loaded from the file yet (it was broken when opened):
    /// the panel is read-only and saving refuses.
    placeholder: bool,
    conflict: Option<PendingMerge>,
    /// The user's editor's unsaved text of this file and its last scene
    /// that loaded, shown instead of `shown` while the editor has it
    /// ([`Document::follow`]); the file and the unsaved panel edits wait.
    editor: Option<follow::Following>,
    /// Why the editor's newest text does not load, if it does not.
    editor_error: Option<String>,
    /// Changes with every change of the scene on screen or of the labels
    /// (see [`Document::generation`]).
    generation: u64,
}

/// A fresh value for [`Document::generation`], never given before in this
/// process: two documents never share one.
fn next_generation() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

impl Document {
    fn from_text(path: Option<PathBuf>, text: String, scene: Scene, state: FileState) -> Document {
        let labels = names::object_labels(&text);
        let disk = fingerprint(text.as_bytes());
        Document::from_parts(path, Source::new(text), scene, labels, disk, state)
    }

    /// A document on a large file loaded with its text packed
    /// ([`scene::load_packed`]); `comments`: the text has some (else no
    /// object has a label, and the text is not read again for them).
    fn from_packed(path: &Path, loaded: scene::PackedLoad) -> Document {
        let labels = match loaded.comments {
            true => names::source_labels(&loaded.text),
            false => names::Labels::default(),
        };
        let disk = fingerprint_source(&loaded.text);
        Document::from_parts(
            Some(path.to_owned()),
            loaded.text,
            loaded.scene,
            labels,
            disk,
            FileState::Watching,
        )
        .laid_out(loaded.layout)
    }

    fn from_parts(
        path: Option<PathBuf>,
        text: Source,
        scene: Scene,
        labels: names::Labels,
        disk: u64,
        state: FileState,
    ) -> Document {
        let file = Version {
            fingerprint: Some(disk),
            ..Version::new(text, scene, Arc::new(labels))
        };
        Document {
            path,
            disk: Some(disk),
            shown: file.clone(),
            file,
            dirty: false,
            undo: Vec::new(),
            redo: Vec::new(),
            state,
            error: None,
            placeholder: false,
            conflict: None,
            editor: None,
            editor_error: None,
            generation: next_generation(),
        }
    }

    /// The document, the file's text placed by `layout`.
    fn laid_out(mut self, layout: scene::Layout) -> Document {
        let layout = Some(Arc::new(layout));
        self.file.layout = layout.clone();
        self.shown.layout = layout;
        self
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
        Document::open_counting(path, None)
    }

    /// [`Document::open`], saying how far the load has got in `progress`
    /// (a large file opened beside the window).
    pub fn open_counting(
        path: &Path,
        progress: Option<&scene::LoadProgress>,
    ) -> Result<Document, LoadError> {
        // A large file's text is never held whole: read a piece at a time
        // and packed as it is parsed.
        let loaded = match scene::load_packed(path, progress) {
            Ok(Some(loaded)) => return Ok(Document::from_packed(path, loaded)),
            Ok(None) => scene::load_counting(path, &[], progress),
            Err(e) => Err(e),
        };
        match loaded {
            Ok(loaded) => Ok(Document::from_text(
                Some(path.to_owned()),
                loaded.text,
                loaded.scene,
                FileState::Watching,
            )
            .laid_out(loaded.layout)),
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

    /// Nothing yet: an empty scene, no file, nothing to edit or save (while
    /// the first file loads in the background).
    pub fn empty() -> Document {
        let mut doc = Document::placeholder(Path::new("loading.xml"));
        doc.path = None;
        doc.state = FileState::Builtin;
        doc
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

    /// The text on screen is held packed ([`Source`]: a large file's).
    pub fn holds_packed_text(&self) -> bool {
        self.editor.is_none() && self.shown.source.is_packed()
    }

    /// The scene on screen.
    pub fn scene(&self) -> &Scene {
        self.on_screen().edited.scene()
    }

    /// The version on screen: the editor's while it is followed.
    fn on_screen(&self) -> &Version {
        self.editor.as_ref().map_or(&self.shown, |f| &f.version)
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
        self.editor_error.as_deref().or(self.error.as_deref())
    }

    /// No scene has loaded from the file yet: nothing to edit or save.
    pub fn is_placeholder(&self) -> bool {
        self.placeholder
    }

    /// The fingerprint of the file's bytes as last read or written
    /// ([`fingerprint_file`]), `None` when unknown: what the watcher
    /// starts from.
    pub fn disk_fingerprint(&self) -> Option<u64> {
        self.disk
    }

    pub fn has_unsaved_edits(&self) -> bool {
        self.dirty
    }

    pub fn conflict(&self) -> Option<&PendingMerge> {
        self.conflict.as_ref()
    }

    /// Where object `n`'s element starts in the text last read from disk,
    /// for an editor to open at; `None` for an object added since (it is
    /// not in the file).
    pub fn object_position(&self, n: usize) -> Option<scene::Position> {
        let version = self.on_screen();
        let origin = version.edited.object_origin(n)?;
        if let Some(following) = &self.editor {
            return scene::layout::object_position(following.text(), origin);
        }
        // (A packed text is unpacked for it: asked for by a menu, once.)
        scene::layout::object_position(&version.source.text(), origin)
    }

    /// Object `n`'s number among the spheres and planes of the text on
    /// screen (the file's, or the editor's being followed), which the
    /// editor link names objects by; `None` for an object added since.
    pub fn object_in_text(&self, n: usize) -> Option<usize> {
        self.on_screen().edited.object_origin(n)
    }

    /// The object that is number `index` among the spheres and planes of
    /// the text on screen ([`Document::object_in_text`]'s inverse), if it
    /// is still there.
    pub fn object_from_text(&self, index: usize) -> Option<usize> {
        let edited = &self.on_screen().edited;
        (0..edited.scene().objects.len()).find(|&n| edited.object_origin(n) == Some(index))
    }

    /// The panel's name for object `n`: `#2 RED sphere` when a comment
    /// directly above it in the file starts with "RED", else `#2 sphere`.
    pub fn object_label(&self, n: usize) -> String {
        names::object_name(n, self.object_shape(n), self.comment_words(n))
    }

    fn object_shape(&self, n: usize) -> &'static str {
        self.scene()
            .objects
            .get(n)
            .map_or("object", |o| o.shape.name())
    }

    /// The first words of the comment above object `n` in the file.
    fn comment_words(&self, n: usize) -> Option<&str> {
        let version = self.on_screen();
        let k = version.edited.object_origin(n)?;
        version.labels.get(k)
    }

    /// The objects (in order) that `query` finds: each of its words, case
    /// aside, is either a number, `12` or `#12`, that is the object's
    /// number or a word of its label, or a part of its label
    /// ([`Document::object_label`]'s words after the number). An empty
    /// query finds every object.
    pub fn find_objects(&self, query: &str) -> Vec<usize> {
        let words: Vec<(String, Option<usize>)> = query
            .split_whitespace()
            .map(|w| {
                let number = w.strip_prefix('#').unwrap_or(w);
                let number = number
                    .bytes()
                    .all(|b| b.is_ascii_digit())
                    .then(|| number.parse::<usize>().ok())
                    .flatten();
                (w.to_lowercase(), number)
            })
            .collect();
        (0..self.scene().objects.len())
            .filter(|&n| {
                let shape = self.object_shape(n);
                let comment = self.comment_words(n).map(str::to_lowercase);
                let comment = comment.as_deref().unwrap_or_default();
                words.iter().all(|(word, number)| match number {
                    Some(k) => {
                        *k == n + 1
                            || comment
                                .split_whitespace()
                                .any(|c| c == word.trim_start_matches('#'))
                    }
                    None => comment.contains(word.as_str()) || shape.contains(word.as_str()),
                })
            })
            .collect()
    }

    /// A number that changes whenever the scene on screen or the objects'
    /// labels change, and that no other document has: what is computed
    /// from them (the panel's search) is good while it stays the same.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The scene as the file holds it (after the last read or write).
    pub fn file_scene(&self) -> &Scene {
        self.file.edited.scene()
    }

    /// The scene with, for each element, where it came from in the text
    /// last read from disk.
    pub fn edited(&self) -> &Edited {
        &self.shown.edited
    }
}
