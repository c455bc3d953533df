//! Saving a [`Document`], in three steps so that the slow one can run on
//! another thread (a million objects take seconds to write and check; the
//! window must not wait):
//!
//! 1. [`Document::save_job`] takes what the save needs — the source text,
//!    its scene, the edited scene, the fingerprint of the file as last
//!    read or written — all shared, nothing copied;
//! 2. [`SaveJob::run`], on any thread, locks the file (as `rayoflight
//!    edit` does, [`crate::system::files::lock_for_update`]) and reads its
//!    fingerprint: the file as known is written (the edits spliced into
//!    the source and streamed, the new file read back and checked, and the
//!    old one read again, before it is replaced), a file changed by another
//!    program is read and handed back unwritten;
//! 3. [`Document::save_done`] takes the outcome: the edits made while it
//!    ran stay unsaved; a changed file is merged with the edits (asking on
//!    conflicts) and written by a new job.
//!
//! [`Document::save`] does the three in a row.

use super::disk::{FingerprintError, fingerprint_file};
use super::{Document, FileRead, FileState, Reload, SaveError, Version};
use crate::scene::{self, splice};
use std::path::{Path, PathBuf};

/// A save taken from a document, to run on any thread.
#[derive(Debug, Clone)]
pub struct SaveJob {
    path: PathBuf,
    /// The version to write.
    version: Version,
    /// The fingerprint of the file as last read or written.
    disk: Option<u64>,
    dirty: bool,
    /// Told the fingerprint of what it writes, before the rename.
    announce: Option<OwnWrites>,
}

/// The fingerprint of the last file this app's own save wrote, told by the
/// save before it renames the file into place and read by the watcher,
/// which then need not read back (and parse) bytes the document already
/// knows: on a million objects, 400 MB and a second of both cores.
#[derive(Debug, Clone, Default)]
pub struct OwnWrites(std::sync::Arc<std::sync::Mutex<Option<u64>>>);

impl OwnWrites {
    fn wrote(&self, fingerprint: u64) {
        if let Ok(mut last) = self.0.lock() {
            *last = Some(fingerprint);
        }
    }

    /// The fingerprint of the last file written, if the file has not been
    /// seen holding other bytes since.
    pub fn last(&self) -> Option<u64> {
        self.0.lock().ok().and_then(|last| *last)
    }

    /// The file was seen holding other bytes since: the same bytes coming
    /// back later are another program's, to be read.
    pub fn forget(&self) {
        if let Ok(mut last) = self.0.lock() {
            *last = None;
        }
    }
}

/// What a [`SaveJob`] did.
#[derive(Debug)]
pub enum SaveOutcome {
    /// The file was written; its fingerprint (`None` for a device or FIFO,
    /// written without being read back).
    Written(Option<u64>),
    /// Nothing to write: the file is as known and nothing is unsaved.
    Unchanged,
    /// Another program changed the file: it was read, not written.
    FileChanged(Box<FileRead>),
    Failed(SaveError),
}

/// What the document made of a [`SaveOutcome`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SaveStep {
    /// Saved (or nothing to save), after `Reload`.
    Done(Reload),
    /// The file's changes were merged with the edits: run a new job to
    /// write them.
    Again,
}

impl SaveJob {
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The job tells `own` the fingerprint of the file it writes, before
    /// it renames it into place.
    pub fn announcing(self, own: OwnWrites) -> SaveJob {
        SaveJob {
            announce: Some(own),
            ..self
        }
    }

    /// Runs the job on a thread of its own, as the app saves (a million
    /// objects take seconds to write and check), then hands `done` the job
    /// and what it did. Before that, the memory the save freed goes back
    /// to the system ([`crate::system::allocator::give_back`]): the thread's arena
    /// would keep 5–6 MB of 200 000 objects' save one time in three.
    pub fn spawn(self, done: impl FnOnce(SaveJob, SaveOutcome) + Send + 'static) {
        std::thread::spawn(move || {
            let outcome = self.run();
            crate::system::allocator::give_back();
            done(self, outcome);
        });
    }

    /// Writes the edited scene to the file unless another program changed
    /// it; never writes over text the app has not read.
    pub fn run(&self) -> SaveOutcome {
        // Held from this read to the rename: a `rayoflight edit` or
        // another save waits. (A file that cannot be opened is found out
        // by the fingerprint below.)
        let _lock = crate::system::files::lock_for_update(&self.path);
        match fingerprint_file(&self.path) {
            // Nothing unsaved and the file as we know it: nothing to do.
            Ok(seen) if Some(seen) == self.disk && !self.dirty => SaveOutcome::Unchanged,
            Ok(seen) if Some(seen) == self.disk => self.write(Some(seen)),
            Ok(_) => self.read_theirs(),
            // A file deleted since: writing brings it back.
            Err(FingerprintError::Io(e)) if e.kind() == std::io::ErrorKind::NotFound => {
                self.write(None)
            }
            // A FIFO or device in its place is never opened.
            Err(e) => {
                SaveOutcome::Failed(SaveError::DiskBroken(Box::new(e.to_load_error(&self.path))))
            }
        }
    }

    /// Writes the version; `expected`: the fingerprint the file must
    /// still have just before the rename (`None`: there was no file).
    fn write(&self, expected: Option<u64>) -> SaveOutcome {
        match write_scene(&self.path, &self.version, expected, self.announce.as_ref()) {
            Ok(written) => SaveOutcome::Written(written),
            // A program that takes no lock wrote it meanwhile, or put
            // another file at its name: merge.
            Err(
                SaveError::ChangedMeanwhile
                | SaveError::Write(crate::system::files::WriteError::Moved { .. }),
            ) => self.read_theirs(),
            Err(e) => SaveOutcome::Failed(e),
        }
    }

    /// The file another program wrote, read for a merge.
    fn read_theirs(&self) -> SaveOutcome {
        match scene::load_counting(&self.path, &self.version.edited.scene().objects, None) {
            Ok(loaded) => SaveOutcome::FileChanged(Box::new(FileRead::loaded(loaded))),
            Err(e) => SaveOutcome::Failed(SaveError::DiskBroken(Box::new(e))),
        }
    }
}

/// Streams `version`'s edited scene spliced into its source to `path`;
/// the new file is read back and must load as the edited scene before it
/// replaces the old one, and the old one must still have the fingerprint
/// `expected` when there is one ([`SaveError::ChangedMeanwhile`]). No copy
/// of the text is built: on a file of a million objects the text is
/// 170 MB. Returns the new file's fingerprint (`None` for a device or
/// FIFO, not read back). `announce` is told that fingerprint before the
/// rename.
fn write_scene(
    path: &Path,
    version: &Version,
    expected: Option<u64>,
    announce: Option<&OwnWrites>,
) -> Result<Option<u64>, SaveError> {
    let edited = &version.edited;
    let rewrite = splice::plan_source(&version.source, &version.source_scene, edited)?;
    let mut written = None;
    crate::system::files::write_atomic_with(
        path,
        |w| rewrite.write_to(w),
        |new: &Path| -> Result<(), SaveError> {
            // Read back as a stream twice (its fingerprint, its scene),
            // never whole: a million objects' text is 214 MB.
            let io = |source| crate::system::files::WriteError::Io {
                path: path.to_owned(),
                source,
            };
            let new_fingerprint = fingerprint_file(new).map_err(|e| match e {
                FingerprintError::Io(e) => io(e),
                FingerprintError::NotAFile(kind) => io(std::io::Error::other(kind)),
            })?;
            splice::check_file(new, path, edited)?;
            if let Some(expected) = expected
                && fingerprint_file(path).ok() != Some(expected)
            {
                return Err(SaveError::ChangedMeanwhile);
            }
            if let Some(announce) = announce {
                announce.wrote(new_fingerprint);
            }
            written = Some(new_fingerprint);
            Ok(())
        },
    )?;
    Ok(written)
}

impl Document {
    /// Takes a save of the edits into the file, to run anywhere.
    pub fn save_job(&self) -> Result<SaveJob, SaveError> {
        let Some(path) = self.path.clone() else {
            return Err(SaveError::NoPath);
        };
        if self.conflict.is_some() {
            return Err(SaveError::Conflict);
        }
        if self.placeholder {
            return Err(SaveError::NothingLoaded);
        }
        if self.editor.is_some() {
            return Err(SaveError::Following);
        }
        Ok(SaveJob {
            path,
            version: self.shown.clone(),
            disk: self.disk,
            dirty: self.dirty,
            announce: None,
        })
    }

    /// Takes what `job` (taken from this document) did. Edits made since
    /// the job was taken stay unsaved.
    pub fn save_done(&mut self, job: SaveJob, outcome: SaveOutcome) -> Result<SaveStep, SaveError> {
        match outcome {
            SaveOutcome::Written(written) => {
                self.wrote(written, job.version);
                Ok(SaveStep::Done(Reload::Unchanged))
            }
            SaveOutcome::Unchanged => Ok(SaveStep::Done(Reload::Unchanged)),
            SaveOutcome::FileChanged(read) => {
                if !self.dirty {
                    // Nothing of ours to write: take the file's version.
                    return Ok(SaveStep::Done(self.file_read(*read)));
                }
                match self.merge_with(*read, &[], true) {
                    Reload::Conflict => Err(SaveError::Conflict),
                    _ => Ok(SaveStep::Again),
                }
            }
            SaveOutcome::Failed(e) => Err(e),
        }
    }

    /// Writes the edits into the file, here and now. The file is read
    /// first: if it is not what the app last read or wrote, the edits are
    /// merged onto it (and the user asked on conflicts) — never written
    /// over unread text.
    pub fn save(&mut self) -> Result<Reload, SaveError> {
        let mut reload = Reload::Unchanged;
        loop {
            let job = self.save_job()?;
            let outcome = job.run();
            match self.save_done(job, outcome)? {
                SaveStep::Done(Reload::Unchanged) => return Ok(reload),
                SaveStep::Done(other) => return Ok(other),
                SaveStep::Again => reload = Reload::Merged,
            }
        }
    }

    /// Writes the scene to `path` (atomically, through a symbolic link) and
    /// makes it this document's file. Asking before replacing another file
    /// is the caller's.
    pub fn save_as(&mut self, path: &Path) -> Result<(), SaveError> {
        if self.placeholder {
            return Err(SaveError::NothingLoaded);
        }
        if self.editor.is_some() {
            return Err(SaveError::Following);
        }
        let written = write_scene(path, &self.shown, None, None)?;
        self.path = Some(path.to_owned());
        self.state = FileState::Watching;
        self.error = None;
        self.conflict = None;
        self.wrote(written, self.shown.clone());
        Ok(())
    }

    /// The file now holds `saved` (`written`: its fingerprint). What was
    /// edited since the save was taken stays unsaved.
    fn wrote(&mut self, written: Option<u64>, saved: Version) {
        self.disk = written;
        self.file = saved;
        if self.state == FileState::Missing {
            self.state = FileState::Watching;
        }
        self.update_dirty();
    }
}
