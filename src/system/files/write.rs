//! Every file's one way out: [`write_atomic_with`] and the functions on
//! it ([`write_atomic`], [`write_new`], [`check_file_target`]). The scene
//! the app saves, the images and CSVs the commands write, the desktop
//! files `install-desktop` writes all leave through it.
//!
//! A file is written atomically: a temporary file in the target folder,
//! renamed into place, so a failure never leaves a partial file nor
//! touches an existing one. The path is walked to a folder held by its
//! descriptor, links in every part followed only as the kernel would for
//! another user's link ([`Place`]); the file in the way is opened once and
//! compared with what was checked; a file the caller may not write is
//! refused; a replaced file's owner, group, mode and extended attributes
//! are kept; a file of several hard links is updated in place through the
//! descriptor that was checked, as a transaction a crash cannot leave half
//! done ([`super::rewrite_in_place`]); and a signal
//! ([`crate::system::interrupt`]) stops it with the temporary file
//! removed. Nothing is written through a path once its folder is held:
//! renaming names meanwhile can make a write fail ([`WriteError::Moved`]),
//! never land elsewhere.

use super::{Kind, Place, PlaceError};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Why a file could not be written. Each names the path as the caller
/// gave it, never a temporary file.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("the output file name is empty")]
    EmptyName,
    #[error("{}: is a directory, not a file", path.display())]
    IsDirectory { path: PathBuf },
    #[error("{}: the folder {} does not exist", path.display(), folder.display())]
    NoFolder { path: PathBuf, folder: PathBuf },
    #[error("{}: {} is not a folder", path.display(), folder.display())]
    NotAFolder { path: PathBuf, folder: PathBuf },
    #[error("{}: cannot write in the folder {}: {source}", path.display(), folder.display())]
    FolderNotWritable {
        path: PathBuf,
        folder: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: the file is read-only", path.display())]
    ReadOnly { path: PathBuf },
    #[error("{}: permission denied: you may not write this file", path.display())]
    NotWritable { path: PathBuf },
    #[error("{}: {source}", path.display())]
    Link {
        path: PathBuf,
        source: super::LinkError,
    },
    #[error("{}: interrupted: nothing was written", path.display())]
    Interrupted { path: PathBuf },
    #[error("{}: already exists; nothing was written", path.display())]
    Exists { path: PathBuf },
    /// The name was given to another file between the look at it and
    /// the write (another program, or another user racing renames).
    #[error(
        "{}: another program replaced the file while it was written; nothing was written",
        path.display()
    )]
    Moved { path: PathBuf },
}

/// Checks, before the work that makes it, that a file (an image, a CSV, a
/// scene) can be written to `path`: a name, links that may be followed, a folder that
/// exists and takes new files, no directory, read-only file or file the
/// caller may not write in the way. An existing device or pipe
/// (`/dev/stdout`) passes: [`write_atomic`] writes into it. Errors name
/// `path` as given.
pub fn check_file_target(path: &Path) -> Result<(), WriteError> {
    if path.as_os_str().is_empty() {
        return Err(WriteError::EmptyName);
    }
    let place = place(path)?;
    let seen = in_the_way(path, &place)?;
    check_room(path, &place, seen.map(|(kind, _)| kind))
}

/// The end of [`check_file_target`], for a `place` already reached and
/// looked at (`kind`: what [`in_the_way`] found there): a new file can be
/// made in its folder, unless the write goes into what is there.
pub(crate) fn check_room(path: &Path, place: &Place, kind: Option<Kind>) -> Result<(), WriteError> {
    // No new file is made beside it (beside `/proc/self/fd/1` none can be).
    if written_into(place, kind) {
        return Ok(());
    }
    let _cleanly = crate::system::interrupt::cleanly();
    place
        .new_file(".rayoflight-", ".tmp")
        .map(drop)
        .map_err(|source| WriteError::FolderNotWritable {
            path: path.to_owned(),
            folder: place.folder_path().to_owned(),
            source,
        })
}

/// The place writing `path` goes ([`Place::reach`]), its errors naming
/// `path` as given.
pub(crate) fn place(path: &Path) -> Result<Place, WriteError> {
    Place::reach(path).map_err(|e| place_error(path, e))
}

/// Why `path` leads to no place to write, as an output error naming it.
fn place_error(path: &Path, e: PlaceError) -> WriteError {
    let path = path.to_owned();
    match e {
        PlaceError::Link(source) => WriteError::Link { path, source },
        PlaceError::NoFolder(folder) => WriteError::NoFolder { path, folder },
        PlaceError::NotAFolder(folder) => WriteError::NotAFolder { path, folder },
        PlaceError::IsDirectory => WriteError::IsDirectory { path },
        PlaceError::Io(source) => WriteError::Io { path, source },
    }
}

/// What is in the way of writing at `place` (where `path` leads): nothing
/// (`None`), or an existing file the caller may replace or a special file
/// to write into (what it is). A directory, a read-only file and a file
/// the caller may not write are refused, naming `path`; so is a link that
/// appeared since the walk followed the one there.
pub(crate) fn in_the_way(
    path: &Path,
    place: &Place,
) -> Result<Option<(Kind, std::fs::Metadata)>, WriteError> {
    let seen = place.look().map_err(|source| WriteError::Io {
        path: path.to_owned(),
        source,
    })?;
    let Some((kind, meta)) = seen else {
        return Ok(None);
    };
    let path = path.to_owned();
    match kind {
        Kind::Directory => return Err(WriteError::IsDirectory { path }),
        Kind::Link => return Err(WriteError::Moved { path }),
        // Renaming over a file ignores the file's own permissions: refuse
        // what writing into it would refuse (for root too, a file without
        // any write bit).
        Kind::Regular if meta.permissions().readonly() => {
            return Err(WriteError::ReadOnly { path });
        }
        Kind::Regular if !place.may_write() => return Err(WriteError::NotWritable { path }),
        Kind::Regular | Kind::Special => {}
    }
    Ok(Some((kind, meta)))
}

/// Writes `bytes` to `path` through a temporary file in the same directory,
/// synced, then renamed over `path`. On any failure the temporary file is
/// removed and an existing `path` is left as it was. A symbolic link is
/// followed (as [`Place::reach`] allows): the file it points to is
/// replaced, the link is kept.
///
/// An existing path that is not a regular file (`/dev/stdout`, a FIFO,
/// `/dev/full`) is written directly: renaming over it would replace the
/// device or pipe itself.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    write_atomic_with(path, |w| w.write_all(bytes), |_| Ok(()))
}

/// Writes `bytes` to a new file at `path`, never over anything there (a
/// file, a link, even a dangling one): [`WriteError::Exists`]. The file
/// is created empty, filled and synced; on a failure it is removed.
pub fn write_new(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    let io_error = |source: std::io::Error| WriteError::Io {
        path: path.to_owned(),
        source,
    };
    if path.as_os_str().is_empty() {
        return Err(WriteError::EmptyName);
    }
    let place = Place::reach_name(path).map_err(|e| place_error(path, e))?;
    let _cleanly = crate::system::interrupt::cleanly();
    let mut new = match place.create_new() {
        Ok(new) => new,
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            return Err(WriteError::Exists {
                path: path.to_owned(),
            });
        }
        Err(e) => return Err(io_error(e)),
    };
    // Dropped on a failure: the new file is removed.
    new.file
        .write_all(bytes)
        .and_then(|()| new.file.sync_all())
        .map_err(io_error)?;
    new.keep();
    Ok(())
}

/// Whether a write to `place`, where a `kind` of file is, goes into that
/// file instead of replacing it: a device or pipe, or what a link of
/// `/proc` stands for (the shell's pipe or redirection).
fn written_into(place: &Place, kind: Option<Kind>) -> bool {
    place.is_magic() || kind == Some(Kind::Special)
}

/// How many times a write looks at and opens a name that another program
/// keeps replacing between the two, before it gives up.
const MAX_TRIES: usize = 8;

/// [`write_atomic`] of what `write` streams, without the bytes in memory
/// at once. Before the new file replaces the old one, `check` is given a
/// path to read it back by (its descriptor's), and may refuse it: the
/// temporary file is removed and the old file left as it was. A path that
/// is not a regular file is written directly and not checked.
///
/// The file in the way is opened once, without following a link, and
/// must be the one that was looked at; just before it is replaced, its
/// name must still name it, and where there was no file none may have
/// appeared: else [`WriteError::Moved`], nothing written. A replaced
/// file keeps its owner and group (as far as the caller may give them),
/// its mode and its extended attributes. A file with several hard links
/// is not replaced but rewritten in place, through the descriptor that
/// was opened and checked, once the new bytes are complete and checked,
/// so that every name keeps showing the same file; a copy of the old
/// bytes (`.NAME.XXXXXX.rayoflight-backup`) waits beside it until then,
/// and stays, named in the error, if the rewrite fails and the old bytes
/// cannot be put back. A signal ([`crate::system::interrupt`]) stops the write
/// with [`WriteError::Interrupted`], nothing changed.
pub fn write_atomic_with<E: From<WriteError>>(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    check: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let io_error = |source: std::io::Error| {
        // The stop may come back wrapped by an encoder: a failure after a
        // signal is the signal's.
        if crate::system::interrupt::is_stop(&source) || crate::system::interrupt::requested() {
            WriteError::Interrupted {
                path: path.to_owned(),
            }
        } else {
            WriteError::Io {
                path: path.to_owned(),
                source,
            }
        }
    };
    let moved = || WriteError::Moved {
        path: path.to_owned(),
    };
    // From here a signal is recorded, not fatal: the temporary file must go.
    let _cleanly = crate::system::interrupt::cleanly();
    let place = place(path)?;
    // A rewrite of this file that a crash left half done, finished first.
    super::finish_at(&place).map_err(io_error)?;
    // What killed writes left beside it (a save or render killed in the
    // middle leaves a temporary file as big as the file), removed.
    #[cfg(unix)]
    place.sweep(STALE_AFTER);
    let mut old = None;
    for _ in 0..MAX_TRIES {
        let Some((kind, meta)) = in_the_way(path, &place)? else {
            old = Some(None);
            break;
        };
        // Written through: what is written into, or a file of several names.
        let into = written_into(&place, Some(kind)) || several_names(&meta);
        let opened = place
            .open(kind, &meta, into)
            .map_err(|e| match e.raw_os_error() {
                #[cfg(unix)]
                Some(libc::ENXIO) if kind == Kind::Special => {
                    io_error(std::io::Error::other("a FIFO that no program is reading"))
                }
                _ => io_error(e),
            })?;
        if let Some(file) = opened {
            old = Some(Some((kind, meta, file)));
            break;
        }
    }
    let Some(old) = old else {
        return Err(moved().into());
    };
    if let Some((kind, meta, file)) = &old
        && written_into(&place, Some(*kind))
    {
        if meta.is_file() {
            file.set_len(0).map_err(io_error)?;
        }
        let mut w = crate::system::interrupt::Checked(file);
        write(&mut w).map_err(io_error)?;
        return Ok(w.flush().map_err(io_error)?);
    }
    let mut new = place.new_file(".rayoflight-", ".tmp").map_err(&io_error)?;
    if let Some((_, meta, file)) = &old {
        super::keep_attributes(file, meta, &new.file).map_err(io_error)?;
    }
    {
        let mut w = BufWriter::new(crate::system::interrupt::Checked(&mut new.file));
        write(&mut w).map_err(io_error)?;
        w.flush().map_err(io_error)?;
    }
    new.file.sync_all().map_err(io_error)?;
    check(&new.path_to_read())?;
    if crate::system::interrupt::requested() {
        return Err(WriteError::Interrupted {
            path: path.to_owned(),
        }
        .into());
    }
    match old {
        Some((_, meta, file)) => {
            if !place.still_names(&file).map_err(io_error)? {
                return Err(moved().into());
            }
            #[cfg(unix)]
            if several_names(&meta) {
                let mut file = file;
                super::rewrite_in_place(&place, &mut file, &mut new).map_err(io_error)?;
                return Ok(());
            }
            #[cfg(not(unix))]
            let _ = meta;
            // Closed first: Windows renames over no file this process
            // holds open.
            drop(file);
            new.rename_over(true).map_err(io_error)?;
        }
        None => match new.rename_over(false) {
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => return Err(moved().into()),
            other => other.map_err(io_error)?,
        },
    }
    Ok(())
}

/// How long a temporary file no process holds locked must have been
/// left unchanged before a write beside it removes it: a writer locks its
/// file at once; this only covers the moment between making and locking.
#[cfg(unix)]
const STALE_AFTER: std::time::Duration = std::time::Duration::from_secs(2);

/// Whether the file has other hard links than the one being written.
fn several_names(meta: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        std::os::unix::fs::MetadataExt::nlink(meta) > 1
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn atomic_write_keeps_usual_and_existing_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        write_atomic(&path, b"a").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        // The same mode as a file created the ordinary way.
        let plain = dir.path().join("plain.txt");
        std::fs::write(&plain, b"a").unwrap();
        assert_eq!(mode(&path), mode(&plain));
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomic(&path, b"b").unwrap();
        assert_eq!(mode(&path), 0o640);
        // A read-only file is not replaced.
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o444)).unwrap();
        let err = write_atomic(&path, b"c").unwrap_err().to_string();
        assert!(err.contains("read-only"), "{err}");
        assert_eq!(std::fs::read(&path).unwrap(), b"b");
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_nobody_reads_is_refused_at_once() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe");
        assert!(
            std::process::Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .unwrap()
                .success()
        );
        let err = write_atomic(&fifo, b"x").unwrap_err().to_string();
        assert!(err.ends_with("a FIFO that no program is reading"), "{err}");
        // With a reader, the bytes go through.
        let reader = std::thread::spawn({
            let fifo = fifo.clone();
            move || std::fs::read(fifo).unwrap()
        });
        let start = std::time::Instant::now();
        loop {
            match write_atomic(&fifo, b"hello") {
                Ok(()) => break,
                Err(_) if start.elapsed().as_secs() < 5 => std::thread::yield_now(),
                Err(e) => panic!("{e}"),
            }
        }
        assert_eq!(reader.join().unwrap(), b"hello");
    }

    #[cfg(unix)]
    #[test]
    fn devices_are_written_not_replaced() {
        // /dev/null takes the bytes and stays a device.
        write_atomic(Path::new("/dev/null"), b"x").unwrap();
        assert!(!std::fs::metadata("/dev/null").unwrap().is_file());
        // /dev/full reports the full disk.
        if Path::new("/dev/full").exists() {
            let err = write_atomic(Path::new("/dev/full"), &[0; 100_000]).unwrap_err();
            assert!(err.to_string().contains("/dev/full"), "{err}");
            assert!(!std::fs::metadata("/dev/full").unwrap().is_file());
        }
    }
}
