//! A [`Document`] and its file on disk: what the watcher read (the same
//! bytes, another version to merge with, a broken or missing file), and
//! the fingerprint that tells them apart. Saving is in `save`.

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

/// The file as read from disk, and what the document needs of its text:
/// its fingerprint and the objects' labels. The watcher makes it on its
/// own thread, as on a gigabyte file each takes a second.
#[derive(Debug, Clone)]
pub struct FileRead {
    pub text: String,
    pub scene: Scene,
    fingerprint: u64,
    labels: Vec<Option<String>>,
}

impl FileRead {
    pub fn new(text: String, scene: Scene) -> FileRead {
        FileRead {
            fingerprint: fingerprint(text.as_bytes()),
            labels: splice::object_labels(&text),
            text,
            scene,
        }
    }

    /// The [`fingerprint`] of the text (what the watcher compares).
    pub fn fingerprint(&self) -> u64 {
        self.fingerprint
    }
}

/// A file version that conflicts with the unsaved edits, waiting for the
/// user's choices.
#[derive(Debug, Clone)]
pub struct PendingMerge {
    read: FileRead,
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
    let mut f = Fingerprint::default();
    f.add(bytes);
    f.finish()
}

/// The [`fingerprint`] of the file at `path`, read in pieces (not into
/// memory at once: the file may be a gigabyte).
pub(super) fn fingerprint_file(path: &Path) -> std::io::Result<u64> {
    use std::io::Read;
    let mut file = std::fs::File::open(path)?;
    let mut buffer = vec![0; 1 << 16];
    let mut f = Fingerprint::default();
    loop {
        match file.read(&mut buffer)? {
            0 => return Ok(f.finish()),
            n => f.add(&buffer[..n]),
        }
    }
}

/// A fingerprint made piece by piece: the same however the bytes are cut
/// (SipHash reads what it is given as one stream).
#[derive(Default)]
struct Fingerprint {
    hasher: std::hash::DefaultHasher,
    len: u64,
}

impl Fingerprint {
    fn add(&mut self, piece: &[u8]) {
        self.hasher.write(piece);
        self.len += piece.len() as u64;
    }

    fn finish(mut self) -> u64 {
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
            *self = Document::from_text(
                self.path.clone(),
                read.text,
                read.scene,
                FileState::Watching,
            );
            return Reload::Replaced;
        }
        let save_after = self.conflict.as_ref().is_some_and(|c| c.save_after);
        if !self.dirty && self.conflict.is_none() {
            // Undoing the reload brings back the scene before it.
            let back = merge::edits_between(&read.scene, self.scene());
            let undos = back.into_iter().rev().map(Undo::from_edit).collect();
            self.rebase(read, None, Vec::new());
            self.undo.push(Step {
                label: "reload from disk".to_owned(),
                undos,
                dragging: None,
            });
            self.redo.clear();
            return Reload::Replaced;
        }
        self.merge_with(read, &BTreeMap::new(), save_after)
    }

    /// Replays the unsaved edits onto the file's version `read`; with
    /// conflicts left, keeps it pending and asks.
    pub(super) fn merge_with(
        &mut self,
        read: FileRead,
        choices: &BTreeMap<usize, Choice>,
        save_after: bool,
    ) -> Reload {
        let merged = merge::merge(self.saved.scene(), &read.scene, &self.log, choices);
        if !merged.conflicts.is_empty() {
            self.conflict = Some(PendingMerge {
                read,
                conflicts: merged.conflicts,
                save_after,
            });
            return Reload::Conflict;
        }
        self.conflict = None;
        self.rebase(read, Some(merged.edited), merged.applied);
        Reload::Merged
    }

    /// The file's version `read` becomes the source; the scene on screen
    /// becomes `edited`, whose origins point into its text, with `log` its
    /// unsaved edits (`None`: the file's scene itself).
    fn rebase(&mut self, read: FileRead, edited: Option<Edited>, log: Vec<Edit>) {
        let FileRead {
            text,
            scene: theirs,
            fingerprint,
            labels,
        } = read;
        self.disk = Some(fingerprint);
        self.labels = labels;
        self.source = Arc::new(text);
        self.source_scene = theirs.clone();
        self.saved = Edited::new(theirs);
        self.edited = edited.unwrap_or_else(|| self.saved.clone());
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
        let reload = self.merge_with(pending.read, &map, pending.save_after);
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
        let mut other = bytes.clone();
        other[150_000] ^= 1;
        assert_ne!(fingerprint(&other), fingerprint(&bytes));
        assert_ne!(fingerprint(&bytes[1..]), fingerprint(&bytes));
    }
}
