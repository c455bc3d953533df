//! A [`Document`] and its file on disk: what the watcher read (the same
//! bytes, another version to merge with, a broken or missing file), and
//! the fingerprint that tells them apart. Saving is in `save`.

use super::{Document, FileState, Version};
use crate::scene::edit::{Edit, EditError};
use crate::scene::merge::{self, Choice, Conflict};
use crate::scene::{LoadError, LoadErrorKind, Scene, names};
use std::collections::BTreeMap;
use std::hash::Hasher;
use std::path::Path;
use std::sync::Arc;

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
    #[error("your editor has unsaved text of this file: save it there")]
    Following,
    #[error("{0}")]
    Edit(#[from] EditError),
    #[error("{0}")]
    Write(#[from] crate::system::files::WriteError),
    /// Another program wrote the file between the save's read and its
    /// rename (the save reads it again just before): nothing was written.
    #[error("another program changed the file while it was being saved")]
    ChangedMeanwhile,
}

/// The file as read from disk, and what the document needs of its text:
/// its fingerprint and the objects' labels. The watcher makes it on its
/// own thread, as on a gigabyte file each takes a second.
#[derive(Debug, Clone)]
pub struct FileRead {
    pub text: String,
    pub scene: Scene,
    fingerprint: u64,
    labels: names::Labels,
    /// Where the root's children sit in `text`, where known.
    layout: Option<crate::scene::Layout>,
}

impl FileRead {
    pub fn new(text: String, scene: Scene) -> FileRead {
        FileRead {
            fingerprint: fingerprint(text.as_bytes()),
            labels: names::object_labels(&text),
            text,
            scene,
            layout: None,
        }
    }

    /// What the loader read of the file ([`crate::scene::load_counting`]).
    pub fn loaded(loaded: crate::scene::Loaded) -> FileRead {
        FileRead {
            layout: Some(loaded.layout),
            ..FileRead::new(loaded.text, loaded.scene)
        }
    }

    /// The [`fingerprint`] of the text (what the watcher compares).
    pub fn fingerprint(&self) -> u64 {
        self.fingerprint
    }
}

/// Edits that conflict with what they are merged onto, waiting for the
/// user's choices.
#[derive(Debug, Clone)]
pub struct PendingMerge {
    onto: Onto,
    conflicts: Vec<Conflict>,
    /// The edits the conflicts' indices count in.
    edits: Vec<Edit>,
    /// Save once the conflicts are settled (the merge came from Ctrl+S).
    save_after: bool,
}

/// What a pending merge replays its edits onto.
#[derive(Debug, Clone)]
enum Onto {
    /// A version of the file another program saved: the unsaved edits go
    /// onto it.
    File(FileRead),
    /// The scene on screen: edits restored from another window's journal,
    /// made on `base`, go onto the edits already there. A file read that
    /// comes meanwhile waits in `later` (merged once this is settled).
    Shown {
        base: Box<Scene>,
        label: String,
        later: Option<Box<FileRead>>,
        /// The scene on screen is the file's, changed by another program
        /// since the edits were made (else: other windows' edits).
        from_file: bool,
    },
}

impl PendingMerge {
    pub fn conflicts(&self) -> &[Conflict] {
        &self.conflicts
    }

    /// Whether the conflicts are between edits restored from another
    /// window's journal and the scene on screen (else: between the unsaved
    /// edits and the file another program saved).
    pub fn is_restore(&self) -> bool {
        matches!(self.onto, Onto::Shown { .. })
    }

    /// Whether the conflicts are between restored edits and the file's
    /// own changes since they were made (else: another window's edits).
    pub fn is_restore_onto_the_file(&self) -> bool {
        matches!(
            self.onto,
            Onto::Shown {
                from_file: true,
                ..
            }
        )
    }
}

/// A fingerprint of the file's bytes.
pub(super) fn fingerprint(bytes: &[u8]) -> u64 {
    let mut f = Fingerprint::default();
    f.add(bytes);
    f.finish()
}

/// The [`fingerprint`] of a text held as a
/// [`Source`](crate::scene::source::Source), read a block at a
/// time.
pub(super) fn fingerprint_source(source: &crate::scene::source::Source) -> u64 {
    use std::io::Read;
    let mut f = Fingerprint::default();
    let mut reader = source.reader();
    let mut buffer = vec![0; 1 << 16];
    loop {
        match reader.read(&mut buffer) {
            Ok(0) | Err(_) => return f.finish(),
            Ok(n) => f.add(&buffer[..n]),
        }
    }
}

/// Why a path could not be fingerprinted.
#[derive(Debug)]
pub enum FingerprintError {
    Io(std::io::Error),
    /// A FIFO, device or socket: never opened (a FIFO blocks until a
    /// writer comes, a device may never end).
    NotAFile(&'static str),
}

impl FingerprintError {
    /// The error as the loader words it, for `path`.
    pub fn to_load_error(&self, path: &Path) -> LoadError {
        let kind = match self {
            FingerprintError::Io(e) => LoadErrorKind::Io {
                kind: e.kind(),
                message: e.to_string(),
            },
            FingerprintError::NotAFile(kind) => LoadErrorKind::NotAFile { kind },
        };
        LoadError::new(path, None, kind)
    }
}

/// The [`fingerprint`] of the file at `path`, read in pieces (not into
/// memory at once: the file may be a gigabyte). A path that is not a
/// regular file is not opened.
pub fn fingerprint_file(path: &Path) -> Result<u64, FingerprintError> {
    use std::io::Read;
    let meta = std::fs::metadata(path).map_err(FingerprintError::Io)?;
    if let Some(kind) = crate::system::files::special_kind(&meta) {
        return Err(FingerprintError::NotAFile(kind));
    }
    let mut file = std::fs::File::open(path).map_err(FingerprintError::Io)?;
    let mut buffer = vec![0; 1 << 16];
    let mut f = Fingerprint::default();
    loop {
        match file.read(&mut buffer).map_err(FingerprintError::Io)? {
            0 => return Ok(f.finish()),
            n => f.add(&buffer[..n]),
        }
    }
}

/// A fingerprint made piece by piece: the same however the bytes are cut
/// (SipHash reads what it is given as one stream).
#[derive(Default)]
pub(super) struct Fingerprint {
    hasher: std::hash::DefaultHasher,
    len: u64,
}

impl Fingerprint {
    pub(super) fn add(&mut self, piece: &[u8]) {
        self.hasher.write(piece);
        self.len += piece.len() as u64;
    }

    pub(super) fn finish(mut self) -> u64 {
        self.hasher.write_u64(self.len);
        self.hasher.finish()
    }
}

impl Document {
    /// The file on disk was read and loads (`text`, `parsed`).
    pub fn file_loaded(&mut self, text: String, parsed: Scene) -> Reload {
        self.file_read(FileRead::new(text, parsed))
    }

    /// The file on disk was read and loads.
    pub fn file_read(&mut self, read: FileRead) -> Reload {
        self.state = FileState::Watching;
        self.error = None;
        if self.disk == Some(read.fingerprint) {
            return Reload::Unchanged;
        }
        if self.placeholder {
            let doc = Document::from_text(
                self.path.clone(),
                read.text,
                read.scene,
                FileState::Watching,
            );
            *self = match read.layout {
                Some(layout) => doc.laid_out(layout),
                None => doc,
            };
            return Reload::Replaced;
        }
        if let Some(PendingMerge {
            onto: Onto::Shown { later, .. },
            ..
        }) = &mut self.conflict
        {
            *later = Some(Box::new(read));
            return Reload::Conflict;
        }
        let save_after = self.conflict.as_ref().is_some_and(|c| c.save_after);
        if !self.dirty && self.conflict.is_none() {
            // Undoing the reload brings back the text before it.
            let shown = self.take_file(read);
            self.show_version("reload from disk", shown);
            return Reload::Replaced;
        }
        self.merge_with(read, &[], save_after)
    }

    /// The unsaved edits: what turns the file's scene into the one on
    /// screen, element by element ([`merge::edits_between`]), as a
    /// three-way merge diffs the base with its side. Two edits that cancel
    /// out (a removal undone) are none.
    pub fn unsaved_edits(&self) -> Vec<Edit> {
        merge::edits_between(self.file_scene(), self.scene())
    }

    /// Replays the unsaved edits onto the file's version `read`; with
    /// conflicts left, keeps it pending and asks. `choices` settles the
    /// edits it names. The merge is an undo step: undoing it brings back
    /// the text and edits before it.
    pub(super) fn merge_with(
        &mut self,
        read: FileRead,
        choices: &[(Edit, Choice)],
        save_after: bool,
    ) -> Reload {
        let edits = self.unsaved_edits();
        let by_index: BTreeMap<usize, Choice> = edits
            .iter()
            .enumerate()
            .filter_map(|(i, e)| Some((i, choices.iter().find(|(c, _)| c == e)?.1)))
            .collect();
        let merged = merge::merge(self.file_scene(), &read.scene, &edits, &by_index);
        if !merged.conflicts.is_empty() {
            self.conflict = Some(PendingMerge {
                onto: Onto::File(read),
                conflicts: merged.conflicts,
                edits,
                save_after,
            });
            return Reload::Conflict;
        }
        self.conflict = None;
        let file = self.take_file(read);
        let shown = Version {
            edited: merged.edited,
            ..file
        };
        self.show_version("merge with the file's changes", shown);
        Reload::Merged
    }

    /// Replays `edits`, made on `base`, onto the scene on screen (the edits
    /// of another window, restored from its journal, onto this window's),
    /// as one undo step called `label`; with conflicts left (both changed
    /// a value), keeps them pending and asks. `choices` settles the edits
    /// of the indices it names.
    pub(super) fn merge_into_shown(
        &mut self,
        base: Scene,
        edits: Vec<Edit>,
        choices: &BTreeMap<usize, Choice>,
        label: String,
        from_file: bool,
    ) -> Reload {
        let merged = merge::merge_onto(&base, self.shown.edited.clone(), &edits, choices);
        if !merged.conflicts.is_empty() {
            self.conflict = Some(PendingMerge {
                onto: Onto::Shown {
                    base: Box::new(base),
                    label,
                    later: None,
                    from_file,
                },
                conflicts: merged.conflicts,
                edits,
                save_after: false,
            });
            return Reload::Conflict;
        }
        self.conflict = None;
        if merged.edited == self.shown.edited {
            return Reload::Unchanged;
        }
        let shown = Version {
            edited: merged.edited,
            ..self.shown.clone()
        };
        self.show_version(&label, shown);
        Reload::Merged
    }

    /// The file's version `read` becomes the file's; returns it.
    fn take_file(&mut self, read: FileRead) -> Version {
        let FileRead {
            text,
            scene,
            fingerprint,
            labels,
            layout,
        } = read;
        self.disk = Some(fingerprint);
        self.file = Version::new(
            crate::scene::source::Source::new(text),
            scene,
            Arc::new(labels),
        );
        self.file.layout = layout.map(Arc::new);
        self.file.fingerprint = Some(fingerprint);
        self.file.clone()
    }

    /// Settles the pending conflicts: `choices[i]` for `conflicts()[i]`.
    /// Returns what happened, and saves if the merge came from a save.
    pub fn resolve(&mut self, choices: &[Choice]) -> Result<Reload, SaveError> {
        let Some(pending) = self.conflict.take() else {
            return Ok(Reload::Unchanged);
        };
        let read = match pending.onto {
            Onto::File(read) => read,
            Onto::Shown {
                base,
                label,
                later,
                from_file,
            } => {
                let choices = pending
                    .conflicts
                    .iter()
                    .zip(choices)
                    .map(|(c, choice)| (c.edit, *choice))
                    .collect();
                let reload =
                    self.merge_into_shown(*base, pending.edits, &choices, label, from_file);
                return Ok(match later {
                    Some(read) if reload != Reload::Conflict => self.file_read(*read),
                    _ => reload,
                });
            }
        };
        let settled: Vec<(Edit, Choice)> = pending
            .conflicts
            .iter()
            .zip(choices)
            .filter_map(|(c, choice)| Some((pending.edits.get(c.edit)?.clone(), *choice)))
            .collect();
        let reload = self.merge_with(read, &settled, pending.save_after);
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_read_in_pieces_has_the_fingerprint_of_its_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f");
        // Longer than the 64 KiB pieces, not a multiple of them.
        let bytes: Vec<u8> = (0..200_001u32).map(|i| (i * 7 % 251) as u8).collect();
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(fingerprint_file(&path).unwrap(), fingerprint(&bytes));
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            // Never opened: an open would block until a writer came.
            assert!(matches!(
                fingerprint_file(&fifo),
                Err(FingerprintError::NotAFile("a FIFO"))
            ));
        }
        let mut other = bytes.clone();
        other[150_000] ^= 1;
        assert_ne!(fingerprint(&other), fingerprint(&bytes));
        assert_ne!(fingerprint(&bytes[1..]), fingerprint(&bytes));
    }
}
