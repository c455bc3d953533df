//! A file of several hard links rewritten in place, as a transaction.
//!
//! Such a file cannot be replaced by a rename (its other names would keep
//! the old file): its new bytes are copied over its old ones. A crash in
//! the middle of that copy would leave it mixed, the new text up to where
//! the copy got and the old text after it, under every name. So the
//! rewrite is recorded before it starts: once the new bytes are complete
//! and synced in a file beside it (`.rayoflight-XXXXXX.tmp`) and a copy
//! of the old bytes too (`.NAME.XXXXXX.rayoflight-backup`), a record
//! `.NAME.rayoflight-rewrite` names both, the file's device, inode and
//! both lengths, and is locked (`flock`) by the writer for as long as it
//! works. The record goes last, after the copies.
//!
//! [`finish`] is called by every reader and writer of a file before it
//! reads or writes it: an unlocked record (its writer gone) is finished —
//! the new bytes copied in again, whole (roll forward), or where they are
//! not all there the old ones put back (roll back) — and the copies and
//! the record removed. A record is followed only when it, and the copy it
//! names, belong to the caller or to the file's owner, and the file is
//! the one it names: another user cannot plant one to have their bytes
//! copied into someone else's file.

#[cfg(unix)]
use std::ffi::{OsStr, OsString};
#[cfg(unix)]
use std::fs::File;
#[cfg(unix)]
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::Place;

/// What a record's first line says: the format, for later versions.
#[cfg(unix)]
const FORMAT: &str = "rayoflight rewrite 1";

/// The record's name beside the file named `name`.
#[cfg(unix)]
fn record_name(name: &OsStr) -> OsString {
    let mut record = OsString::from(".");
    record.push(name);
    record.push(".rayoflight-rewrite");
    record
}

/// A rewrite that a crash interrupted, finished by [`finish`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Finished {
    /// The new bytes are in the file, whole.
    RolledForward(PathBuf),
    /// The new bytes were not all there: the old ones are back.
    RolledBack(PathBuf),
}

/// Copies `from` over `to` from their starts, cuts `to` to that length
/// and syncs it.
#[cfg(unix)]
fn copy_over(from: &mut File, to: &mut File) -> std::io::Result<u64> {
    from.seek(SeekFrom::Start(0))?;
    to.seek(SeekFrom::Start(0))?;
    let len = std::io::copy(from, to)?;
    to.set_len(len)?;
    to.sync_all()?;
    Ok(len)
}

/// Puts `new`'s bytes into `file` itself (the file at `place`, whose inode
/// other hard links share), as a transaction (see the module's doc): a
/// copy of the old bytes beside it, the record written and locked, the
/// new bytes copied over the old and synced, then the record and the
/// copies removed. If the copy fails (a full disk) the old bytes are put
/// back; if even that fails, the backup and the record stay, and the error
/// names the backup. Only descriptors are written: whatever the names in
/// the folder became meanwhile, the file written is the one that was
/// opened and checked. `new` must be complete and synced, and a record
/// a crash left of an earlier rewrite finished first ([`finish_at`], as
/// [`super::write_atomic_with`] does before any write): this
/// record never replaces one.
#[cfg(unix)]
pub fn rewrite_in_place(
    place: &Place,
    file: &mut File,
    new: &mut super::NewFile<'_>,
) -> std::io::Result<()> {
    use std::os::unix::fs::MetadataExt;
    let name = place.name().to_string_lossy().into_owned();
    let mut backup = place.new_file(&format!(".{name}."), ".rayoflight-backup")?;
    file.seek(SeekFrom::Start(0))?;
    let old_len = std::io::copy(file, &mut backup.file)?;
    backup.file.sync_all()?;
    if crate::system::interrupt::requested() {
        return Err(crate::system::interrupt::error());
    }
    let meta = file.metadata()?;
    let new_len = new.file.metadata()?.len();
    let mut record = place.new_file(".rayoflight-", ".tmp")?;
    write!(
        record.file,
        "{FORMAT}\ndevice {}\ninode {}\nlength {new_len}\nold-length {old_len}\n",
        meta.dev(),
        meta.ino()
    )?;
    record.file.write_all(b"new ")?;
    record.file.write_all(new.name().as_encoded_bytes())?;
    record.file.write_all(b"\nbackup ")?;
    record.file.write_all(backup.name().as_encoded_bytes())?;
    record.file.write_all(b"\n")?;
    record.file.sync_all()?;
    // Locked before it has its name: a reader that finds it finds it
    // locked while this process lives.
    record.file.lock()?;
    record.rename_to(&record_name(place.name()))?;
    // From here the rewrite is finished, signal or not: it is short, and
    // a half-written file is what must never be left.
    if let Err(e) = copy_over(&mut new.file, file) {
        if copy_over(&mut backup.file, file).is_err() || file.metadata()?.len() != old_len {
            // The record stays with the backup: the next reader rolls
            // back (or forward) from them.
            let kept = backup.keep();
            record.keep();
            return Err(std::io::Error::new(
                e.kind(),
                format!(
                    "{e}; the file is damaged, its old bytes are in {}",
                    kept.display()
                ),
            ));
        }
        return Err(e);
    }
    // The copies go first, the record last: a crash between leaves a
    // record whose copies are gone, finished as it stands (the file is
    // whole).
    let _ = place.remove_sibling(new.name());
    drop(backup);
    drop(record);
    Ok(())
}

/// Finishes a rewrite of the file `path` names that a crash interrupted,
/// if there is one (see the module's doc); `Ok(None)` where there is
/// none, or its writer still works, or the record is not to be followed.
/// Called before reading a scene and before writing any file.
pub fn finish(path: &Path) -> std::io::Result<Option<Finished>> {
    match Place::reach(path) {
        Ok(place) => finish_at(&place),
        Err(_) => Ok(None),
    }
}

/// [`finish`] at a place already reached.
#[cfg(unix)]
pub fn finish_at(place: &Place) -> std::io::Result<Option<Finished>> {
    use std::os::unix::fs::MetadataExt;
    let record_name = record_name(place.name());
    let Some(mut record) = place.open_sibling(&record_name, false)? else {
        return Ok(None);
    };
    // Its writer still works.
    match record.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => return Ok(None),
        Err(std::fs::TryLockError::Error(e)) => return Err(e),
    }
    let mut text = String::new();
    if record.read_to_string(&mut text).is_err() {
        return Ok(None);
    }
    let Some(facts) = Record::parse(&text) else {
        return Ok(None);
    };
    let Some(mut file) = place.open_sibling(place.name(), true)? else {
        return Ok(None);
    };
    let meta = file.metadata()?;
    if !meta.is_file() || meta.dev() != facts.device || meta.ino() != facts.inode {
        return Ok(None);
    }
    let me = rustix::process::geteuid().as_raw();
    let trusted = |f: &File| {
        f.metadata()
            .is_ok_and(|m| m.is_file() && (m.uid() == me || m.uid() == meta.uid()))
    };
    if !trusted(&record) {
        return Ok(None);
    }
    let mut new = place
        .open_sibling(&facts.new, false)?
        .filter(|f| trusted(f));
    let mut backup = place
        .open_sibling(&facts.backup, false)?
        .filter(|f| trusted(f));
    let whole = |f: &Option<File>, len: u64| {
        f.as_ref()
            .is_some_and(|f| f.metadata().is_ok_and(|m| m.len() == len))
    };
    let done = if whole(&new, facts.length) {
        if let Some(new) = new.as_mut() {
            copy_over(new, &mut file)?;
        }
        Finished::RolledForward(place.path())
    } else if whole(&backup, facts.old_length) {
        if let Some(backup) = backup.as_mut() {
            copy_over(backup, &mut file)?;
        }
        Finished::RolledBack(place.path())
    } else if meta.len() == facts.length {
        // The copies gone, the record not yet: the rewrite had ended.
        Finished::RolledForward(place.path())
    } else {
        // Nothing whole to finish it from: everything left as it is.
        return Ok(None);
    };
    for name in [&facts.new, &facts.backup] {
        let _ = place.remove_sibling(name);
    }
    place.remove_sibling(&record_name)?;
    Ok(Some(done))
}

#[cfg(not(unix))]
pub fn finish_at(_place: &Place) -> std::io::Result<Option<Finished>> {
    Ok(None)
}

/// What a record says.
#[cfg(unix)]
struct Record {
    device: u64,
    inode: u64,
    length: u64,
    old_length: u64,
    new: OsString,
    backup: OsString,
}

#[cfg(unix)]
impl Record {
    fn parse(text: &str) -> Option<Record> {
        let mut lines = text.lines();
        if lines.next()? != FORMAT {
            return None;
        }
        let mut field = |key: &str| -> Option<String> {
            let line = lines.next()?;
            line.strip_prefix(key)?.strip_prefix(' ').map(str::to_owned)
        };
        let device = field("device")?.parse().ok()?;
        let inode = field("inode")?.parse().ok()?;
        let length = field("length")?.parse().ok()?;
        let old_length = field("old-length")?.parse().ok()?;
        let name = |n: String| {
            // A name in the folder, never a path.
            (!n.is_empty() && !n.contains('/') && n != "." && n != "..").then(|| OsString::from(n))
        };
        let new = name(field("new")?)?;
        let backup = name(field("backup")?)?;
        Some(Record {
            device,
            inode,
            length,
            old_length,
            new,
            backup,
        })
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn a_record_names_only_files_of_its_folder() {
        let ok = format!(
            "{FORMAT}\ndevice 1\ninode 2\nlength 3\nold-length 4\nnew .rayoflight-a.tmp\nbackup .s.xml.b.rayoflight-backup\n"
        );
        assert!(Record::parse(&ok).is_some());
        for bad in [
            ok.replace("new .rayoflight-a.tmp", "new ../../etc/passwd"),
            ok.replace("new .rayoflight-a.tmp", "new .."),
            ok.replace("length 3", "length x"),
            ok.replace(FORMAT, "rayoflight rewrite 2"),
        ] {
            assert!(Record::parse(&bad).is_none(), "{bad}");
        }
    }

    #[test]
    fn an_interrupted_rewrite_is_rolled_forward_then_gone() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.xml");
        std::fs::write(&path, "old text, longer than the new").unwrap();
        std::fs::hard_link(&path, dir.path().join("t.xml")).unwrap();
        let place = Place::reach(&path).unwrap();
        let mut new = place.new_file(".rayoflight-", ".tmp").unwrap();
        new.file.write_all(b"new text").unwrap();
        let mut backup = place.new_file(".s.xml.", ".rayoflight-backup").unwrap();
        backup
            .file
            .write_all(b"old text, longer than the new")
            .unwrap();
        // A crash: the copy half done, the record left unlocked.
        std::fs::write(&path, "new textxt, longer than the new").unwrap();
        use std::os::unix::fs::MetadataExt;
        let meta = std::fs::metadata(&path).unwrap();
        let record = format!(
            "{FORMAT}\ndevice {}\ninode {}\nlength 8\nold-length 29\nnew {}\nbackup {}\n",
            meta.dev(),
            meta.ino(),
            new.name().to_string_lossy(),
            backup.name().to_string_lossy()
        );
        std::fs::write(dir.path().join(".s.xml.rayoflight-rewrite"), record).unwrap();
        let (new_name, backup_name) = (new.keep(), backup.keep());
        assert_eq!(
            finish(&path).unwrap(),
            Some(Finished::RolledForward(path.clone()))
        );
        assert_eq!(std::fs::read(&path).unwrap(), b"new text");
        assert_eq!(
            std::fs::read(dir.path().join("t.xml")).unwrap(),
            b"new text"
        );
        assert!(!new_name.exists() && !backup_name.exists());
        let mut left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        left.sort();
        assert_eq!(left, ["s.xml", "t.xml"]);
        assert_eq!(finish(&path).unwrap(), None);
    }
}
