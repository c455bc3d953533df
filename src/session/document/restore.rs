//! What the journal of unsaved edits needs of a [`Document`]
//! ([`crate::session::journal`]): the edits and the text they apply to, to
//! write, and the edits restored onto that text, merged through the usual
//! engine with the file as it is now.

use super::disk::{Fingerprint, fingerprint};
use super::{Document, FileState, Reload};
use crate::scene::edit::Edit;
use crate::scene::{self, splice};

/// Writes a text, on any thread.
pub type TextWriter = Box<dyn Fn(&mut dyn std::io::Write) -> std::io::Result<()> + Send>;

impl Document {
    /// The fingerprint of the text the file holds as last read or written:
    /// the text the unsaved edits apply to.
    pub fn file_fingerprint(&self) -> u64 {
        if let Some(disk) = self.disk {
            return disk;
        }
        // Unknown (the file is gone): the text itself.
        let mut f = Fingerprint::default();
        let _ = self.file_text_writer()(&mut FingerprintWriter(&mut f));
        f.finish()
    }

    /// Something that writes the text the file holds as last read or
    /// written (the source with the file's scene spliced in), on any
    /// thread: the base the unsaved edits apply to.
    pub fn file_text_writer(&self) -> TextWriter {
        let file = self.file.clone();
        Box::new(move |w| {
            let rewrite = splice::plan_source(&file.source, &file.source_scene, &file.edited)
                .map_err(std::io::Error::other)?;
            rewrite.write_to(w)
        })
    }

    /// Restores `edits`, made on the text whose fingerprint is
    /// `base_fingerprint`, onto this document just opened from the file,
    /// as one undo step (undoing it gives the file as it opened). A file
    /// that still holds that text (the usual case after a crash) takes
    /// them as it is, and `base` is never called: a million objects' base
    /// is not read and parsed a second time (the app peaked at 700 MB
    /// restoring one edit). Otherwise the text `base` gives is loaded and
    /// the edits replayed from it onto the file as it is now (a value the
    /// file changed too is asked, [`super::PendingMerge::is_restore`]); where
    /// that changes nothing (the edits are all in the file: a save that
    /// finished before the app ended), the document is left as it opened
    /// and `Unchanged` returned with nothing unsaved. Returns how it
    /// merged, or why the edits cannot be restored (a base that does not
    /// load, an edit that does not apply: the journal is damaged).
    pub fn restore(
        &mut self,
        base_fingerprint: u64,
        base: impl FnOnce() -> Result<String, String>,
        edits: &[Edit],
    ) -> Result<Reload, String> {
        let label = restore_label(edits.len(), "");
        let path = self.path.clone().ok_or("the scene has no file")?;
        if self.placeholder || self.state == FileState::Missing {
            // The file does not load now, or is gone: the edits stay on
            // their base, and saving refuses until the file loads again.
            let base = base()?;
            let base_scene = parse_base(&base, &path)?;
            let mut doc = Document::from_text(Some(path), base, base_scene, FileState::Watching);
            doc.apply_labelled(edits.to_vec(), label)
                .map_err(|e| format!("an edit does not apply: {e}"))?;
            doc.disk = None;
            let reload = if self.placeholder {
                doc.error.clone_from(&self.error);
                Reload::Broken
            } else {
                doc.state = FileState::Missing;
                Reload::Unchanged
            };
            *self = doc;
            return Ok(reload);
        }
        if self.disk == Some(base_fingerprint) && !self.dirty {
            self.apply_labelled(edits.to_vec(), label)
                .map_err(|e| format!("an edit does not apply: {e}"))?;
            return Ok(Reload::Unchanged);
        }
        self.replay_restored(base_fingerprint, base, edits, label, true)
    }

    /// Restores `edits` of another window, made on the text whose
    /// fingerprint is `base_fingerprint` (`base` gives it, called only
    /// when the file no longer holds it), onto the scene on screen, which
    /// may hold unsaved edits already (another window's, restored before):
    /// merged as one undo step, a value both changed asked as any conflict
    /// ([`Document::resolve`]). Returns how it merged (`Unchanged`: every
    /// edit is there already), or why the edits cannot be restored.
    pub fn restore_more(
        &mut self,
        base_fingerprint: u64,
        base: impl FnOnce() -> Result<String, String>,
        edits: &[Edit],
    ) -> Result<Reload, String> {
        let label = restore_label(edits.len(), " of another window");
        self.replay_restored(base_fingerprint, base, edits, label, false)
    }

    /// Replays `edits`, made on the text of fingerprint `base_fingerprint`
    /// (the file's as last read, else `base`'s), onto the scene on screen.
    /// `from_file`: the scene on screen is the file's, changed by another
    /// program since the edits were made (else: other restored edits).
    fn replay_restored(
        &mut self,
        base_fingerprint: u64,
        base: impl FnOnce() -> Result<String, String>,
        edits: &[Edit],
        label: String,
        from_file: bool,
    ) -> Result<Reload, String> {
        let path = self.path.clone().ok_or("the scene has no file")?;
        let base_scene = if !self.placeholder && self.disk == Some(base_fingerprint) {
            self.file_scene().clone()
        } else {
            parse_base(&base()?, &path)?
        };
        // Each edit must apply to its base: a merge leaves out an edit
        // that does not, and a journal is applied whole or not at all.
        let mut check = crate::scene::edit::Edited::new(base_scene.clone());
        for edit in edits {
            check
                .apply(edit)
                .map_err(|e| format!("an edit does not apply: {e}"))?;
        }
        Ok(self.merge_into_shown(
            base_scene,
            edits.to_vec(),
            &Default::default(),
            label,
            from_file,
        ))
    }
}

/// The undo step's label of `n` restored edits (`whose`: of another
/// window, or nothing).
fn restore_label(n: usize, whose: &str) -> String {
    match n {
        1 => format!("restore 1 unsaved edit{whose}"),
        n => format!("restore {n} unsaved edits{whose}"),
    }
}

/// The scene of a journal's base text, or why it is damaged.
fn parse_base(text: &str, path: &std::path::Path) -> Result<scene::Scene, String> {
    scene::parse(text, path).map_err(|e| format!("its base: {e}"))
}

/// Feeds written bytes to a [`Fingerprint`].
struct FingerprintWriter<'a>(&'a mut Fingerprint);

impl std::io::Write for FingerprintWriter<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.add(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The [`fingerprint`] of a text, as [`super::fingerprint_file`] gives for a
/// file holding it.
pub fn fingerprint_text(text: &str) -> u64 {
    fingerprint(text.as_bytes())
}
