//! Facts about the files the core reads and writes that the standard
//! library leaves to each caller: what kind of special file a path is
//! (scenes and images must be regular files: a FIFO would block, a device
//! never ends), where a chain of symbolic links leads for reading, the
//! owner, group and extended attributes a replaced file keeps, the lock
//! every read-modify-write of a scene holds, and whether two paths are
//! one file; a rewrite in place as a transaction that a crash cannot
//! leave half done ([`rewrite`]); the folders the user's own state lives in (settings, the
//! journal, the editor link's sockets), which must be the user's and
//! writable by no one else ([`own_folder`]). Where a write lands, held by
//! descriptors so that no rename can redirect it, is [`place`]'s; every
//! file's one atomic way out is [`write`](mod@write)'s.

mod place;
mod rewrite;
pub mod write;

pub use place::{Kind, NewFile, Place, PlaceError, make_folders};
#[cfg(unix)]
pub use rewrite::rewrite_in_place;
pub use rewrite::{Finished, finish, finish_at};
pub use write::{WriteError, check_file_target, write_atomic, write_atomic_with, write_new};

use std::fs::Metadata;
use std::path::{Path, PathBuf};

/// What a file that is neither a regular file nor a directory is, for a
/// message ("a FIFO"); `None` for a regular file or a directory.
pub fn special_kind(meta: &Metadata) -> Option<&'static str> {
    if meta.is_file() || meta.is_dir() {
        return None;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return Some("a FIFO");
        }
        if t.is_char_device() {
            return Some("a character device");
        }
        if t.is_block_device() {
            return Some("a block device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

/// `path` made absolute against the current folder (without resolving
/// links or `..`), or as given when the current folder is unknown: the
/// one name the app keeps a file under (watcher, recent files, journal).
/// A path as a user types it: a leading `~` (alone or before a `/`) is
/// the home folder (`$HOME`), as a shell reads it; anything else (and
/// `~user`, and `~` without a home) is taken as written.
pub fn typed_path(text: &str, home: Option<&Path>) -> PathBuf {
    match (text.strip_prefix('~'), home) {
        (Some(""), Some(home)) => home.to_owned(),
        (Some(rest), Some(home)) if rest.starts_with('/') => {
            home.join(rest.trim_start_matches('/'))
        }
        _ => PathBuf::from(text),
    }
}

pub fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_owned())
}

/// What makes two paths one file: on Unix its device and inode (a
/// symbolic link or a hard link is the file itself), elsewhere its
/// canonical path; a path that cannot be read stands for itself.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum FileIdentity {
    Inode { device: u64, inode: u64 },
    Path(PathBuf),
}

/// The file `path` names ([`FileIdentity`]).
pub fn identity(path: &Path) -> FileIdentity {
    #[cfg(unix)]
    if let Ok(meta) = std::fs::metadata(path) {
        use std::os::unix::fs::MetadataExt;
        return FileIdentity::Inode {
            device: meta.dev(),
            inode: meta.ino(),
        };
    }
    FileIdentity::Path(path.canonicalize().unwrap_or_else(|_| path.to_owned()))
}

/// Whether `b` names the existing file `a`: by another spelling of the
/// path, through a symbolic link, or (Unix) as a hard link.
pub fn same_file(a: &Path, b: &Path) -> bool {
    a.exists() && b.exists() && identity(a) == identity(b)
}

/// The file `path` names once symbolic links are followed (at most 40, as
/// the kernel does); a dangling link gives the path it points to. For
/// reading and watching; writing goes through [`Place::reach`].
pub fn through_links(path: &Path) -> PathBuf {
    let mut p = path.to_owned();
    for _ in 0..40 {
        let Ok(target) = std::fs::read_link(&p) else {
            break;
        };
        p = match p.parent() {
            Some(dir) => dir.join(target),
            None => target,
        };
    }
    p
}

/// Why a path is not followed to the file it would write.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    #[error("a loop of symbolic links (or more than 40 in a row)")]
    Loop,
    #[error(
        "not followed: the symbolic link {} is another user's, in the shared folder {} \
         (sticky and writable by all): the kernel's fs.protected_symlinks rule",
        link.display(),
        folder.display()
    )]
    Protected { link: PathBuf, folder: PathBuf },
}

/// Why a folder of the user's own state is not used.
#[derive(Debug, thiserror::Error)]
pub enum OwnFolderError {
    #[error("{}: not used: it is another user's (uid {owner}), not yours", path.display())]
    NotYours { path: PathBuf, owner: u32 },
    #[error("{}: not used: others may {what} it (mode {mode:o})", path.display())]
    Open {
        path: PathBuf,
        mode: u32,
        what: &'static str,
    },
    #[error("{}: not used: not a folder", path.display())]
    NotAFolder { path: PathBuf },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// The folder `home/below…` where the app keeps state of the user's own
/// (`home` an XDG base such as `$XDG_STATE_HOME`), made where missing
/// (mode 0700), and used only if `home` and every folder below it are the
/// user's and no one else may write in them — else another user could
/// plant files there (a journal of edits that a save then writes into
/// the user's scene) or swap names. `private`: the last folder must be
/// closed to others altogether (it holds copies of the user's files, or
/// sockets). Links are followed: a folder the user linked elsewhere is
/// checked where it is.
pub fn own_folder(home: &Path, below: &[&str], private: bool) -> Result<PathBuf, OwnFolderError> {
    let make = |path: &Path, recursive: bool| -> Result<(), OwnFolderError> {
        let mut builder = std::fs::DirBuilder::new();
        builder.recursive(recursive);
        #[cfg(unix)]
        std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
        match builder.create(path) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
            Err(source) => Err(OwnFolderError::Io {
                path: path.to_owned(),
                source,
            }),
        }
    };
    make(home, true)?;
    check_own(home, private && below.is_empty())?;
    let mut path = home.to_owned();
    for (i, part) in below.iter().enumerate() {
        path.push(part);
        // Made in a folder no one else may write: no one else can swap it
        // between this and the check.
        make(&path, false)?;
        check_own(&path, private && i + 1 == below.len())?;
    }
    Ok(path)
}

/// [`own_folder`]'s rule for one folder.
fn check_own(path: &Path, private: bool) -> Result<(), OwnFolderError> {
    let meta = std::fs::metadata(path).map_err(|source| OwnFolderError::Io {
        path: path.to_owned(),
        source,
    })?;
    if !meta.is_dir() {
        return Err(OwnFolderError::NotAFolder {
            path: path.to_owned(),
        });
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let path = path.to_owned();
        let mode = meta.mode() & 0o7777;
        if meta.uid() != rustix::process::geteuid().as_raw() {
            return Err(OwnFolderError::NotYours {
                path,
                owner: meta.uid(),
            });
        }
        if mode & 0o022 != 0 {
            let what = "write in";
            return Err(OwnFolderError::Open { path, mode, what });
        }
        if private && mode & 0o077 != 0 {
            let what = "enter";
            return Err(OwnFolderError::Open { path, mode, what });
        }
    }
    #[cfg(not(unix))]
    let _ = private;
    Ok(())
}

/// Gives `new` (a file about to replace `old`, whose metadata is `meta`)
/// what `old` has beside its bytes, as far as the caller may: its owner
/// and group (a user may give a file only to a group of theirs; root to
/// anyone), its mode (set after the owner, which clears set-id bits) and
/// its extended attributes (ACLs, SELinux labels, user attributes). What
/// the system refuses is left as a new file has it.
pub fn keep_attributes(
    old: &std::fs::File,
    meta: &Metadata,
    new: &std::fs::File,
) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if std::os::unix::fs::fchown(new, Some(meta.uid()), Some(meta.gid())).is_err() {
            let _ = std::os::unix::fs::fchown(new, None, Some(meta.gid()));
        }
        copy_xattrs(old, new);
    }
    #[cfg(not(unix))]
    let _ = old;
    new.set_permissions(meta.permissions())
}

/// Copies `old`'s extended attributes to `new`, each one that the
/// system lets us read and set.
#[cfg(unix)]
fn copy_xattrs(old: &std::fs::File, new: &std::fs::File) {
    use rustix::fs::{
        XattrFlags, fgetxattr as getxattr, fgetxattr_query as getxattr_query,
        flistxattr as listxattr, flistxattr_query as listxattr_query, fsetxattr,
    };
    let Ok(len) = listxattr_query(old) else {
        return;
    };
    let mut names = vec![0u8; len];
    let Ok(len) = listxattr(old, &mut names[..]) else {
        return;
    };
    for name in names[..len].split(|&b| b == 0).filter(|n| !n.is_empty()) {
        let name = <std::ffi::OsStr as std::os::unix::ffi::OsStrExt>::from_bytes(name);
        let Ok(size) = getxattr_query(old, name) else {
            continue;
        };
        let mut value = vec![0u8; size];
        if let Ok(size) = getxattr(old, name, &mut value[..]) {
            let _ = fsetxattr(new, name, &value[..size], XattrFlags::empty());
        }
    }
}

/// Held from reading a scene to renaming its new text into place, by
/// `rayoflight edit` and by the app's save, so that two of them never
/// both read the old text and the second write loses the first's edits.
/// An advisory `flock` on the file itself: a program that takes no lock is
/// not stopped (the writers re-read the file before renaming instead).
/// On Windows a file held open cannot be renamed over, and its locks bar
/// others from reading it: the lock is on a file of its own instead, in
/// the user's temporary folder, named after the scene's full path.
#[derive(Debug)]
pub struct UpdateLock {
    _file: std::fs::File,
}

/// Locks the scene `path` for an update, waiting for any other holder.
/// The lock is on the file's inode, and a writer that renames a new file
/// into place leaves the lock on the old one: after locking, the path must
/// still name the locked file, or the new one is locked instead. `None`
/// when there is no regular file to lock (it is about to be created, or
/// is a device).
#[cfg(unix)]
pub fn lock_for_update(path: &Path) -> std::io::Result<Option<UpdateLock>> {
    loop {
        // A FIFO is never opened (it would block until a writer came).
        match std::fs::metadata(path) {
            Ok(meta) if meta.is_file() => {}
            Ok(_) => return Ok(None),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(e),
        }
        let mut open = std::fs::OpenOptions::new();
        open.read(true);
        #[cfg(unix)]
        std::os::unix::fs::OpenOptionsExt::custom_flags(&mut open, libc::O_NONBLOCK);
        let file = match open.open(path) {
            Ok(file) => file,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(e),
        };
        if !file.metadata()?.is_file() {
            return Ok(None);
        }
        file.lock()?;
        let locked = identity_of(&file.metadata()?);
        match std::fs::metadata(path) {
            Ok(now) if identity_of(&now) == locked => return Ok(Some(UpdateLock { _file: file })),
            Ok(_) => continue,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(e),
        }
    }
}

/// Locks the scene `path` for an update, waiting for any other holder
/// (see [`UpdateLock`]: elsewhere than Unix, a lock file of the scene's).
#[cfg(not(unix))]
pub fn lock_for_update(path: &Path) -> std::io::Result<Option<UpdateLock>> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => {}
        Ok(_) => return Ok(None),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e),
    }
    // FNV-1a of the full path: the same name in every process and version.
    let full = path.canonicalize()?;
    let hash = full
        .as_os_str()
        .as_encoded_bytes()
        .iter()
        .fold(0xcbf2_9ce4_8422_2325_u64, |h, &b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        });
    let folder = std::env::temp_dir().join("rayoflight-locks");
    std::fs::create_dir_all(&folder)?;
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(folder.join(format!("{hash:016x}.lock")))?;
    file.lock()?;
    Ok(Some(UpdateLock { _file: file }))
}

/// Whether two files' metadata are of one file ([`identity_of`]).
pub fn same_metadata(a: &Metadata, b: &Metadata) -> bool {
    identity_of(a) == identity_of(b)
}

/// What tells one file from another by its metadata: on Unix its device
/// and inode; elsewhere, where std gives no file number, when it was made
/// and last written and its length (a file written between two looks is
/// taken for another, which makes a check fail, never pass wrongly).
#[cfg(unix)]
pub type MetaIdentity = (u64, u64);
#[cfg(not(unix))]
pub type MetaIdentity = (
    Option<std::time::SystemTime>,
    Option<std::time::SystemTime>,
    u64,
);

/// The [`MetaIdentity`] of `meta`.
pub fn identity_of(meta: &Metadata) -> MetaIdentity {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        (meta.dev(), meta.ino())
    }
    #[cfg(not(unix))]
    {
        (meta.created().ok(), meta.modified().ok(), meta.len())
    }
}

#[cfg(all(test, unix))]
mod tests {
    #[test]
    fn a_typed_tilde_is_the_home_folder() {
        let home = Some(Path::new("/home/u"));
        assert_eq!(typed_path("~", home), Path::new("/home/u"));
        assert_eq!(typed_path("~/a/b.xml", home), Path::new("/home/u/a/b.xml"));
        assert_eq!(typed_path("~//a.xml", home), Path::new("/home/u/a.xml"));
        assert_eq!(typed_path("~bob/a.xml", home), Path::new("~bob/a.xml"));
        assert_eq!(typed_path("a/~/b", home), Path::new("a/~/b"));
        assert_eq!(typed_path("~/a.xml", None), Path::new("~/a.xml"));
    }

    use super::*;

    #[test]
    fn own_folders_are_made_private_and_others_refused() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let home = dir.path().join("state");
        let made = own_folder(&home, &["rayoflight", "journal"], true).unwrap();
        assert_eq!(made, home.join("rayoflight/journal"));
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&made), 0o700);
        assert_eq!(mode(&home), 0o700);
        // Open to others' writes: refused, at any level.
        let set = |p: &Path, m: u32| {
            std::fs::set_permissions(p, std::fs::Permissions::from_mode(m)).unwrap()
        };
        set(&home.join("rayoflight"), 0o777);
        let err = own_folder(&home, &["rayoflight", "journal"], true).unwrap_err();
        assert!(
            matches!(&err, OwnFolderError::Open { path, .. } if path == &home.join("rayoflight")),
            "{err}"
        );
        set(&home.join("rayoflight"), 0o755);
        // Readable by others: fine for settings, not for a private one.
        set(&made, 0o755);
        own_folder(&home, &["rayoflight", "journal"], false).unwrap();
        let err = own_folder(&home, &["rayoflight", "journal"], true).unwrap_err();
        assert_eq!(
            err.to_string(),
            format!(
                "{}: not used: others may enter it (mode 755)",
                made.display()
            )
        );
        if rustix::process::geteuid().is_root() {
            std::os::unix::fs::chown(&made, Some(65534), Some(65534)).unwrap();
            set(&made, 0o700);
            let err = own_folder(&home, &["rayoflight", "journal"], true).unwrap_err();
            assert!(
                matches!(err, OwnFolderError::NotYours { owner: 65534, .. }),
                "{err}"
            );
        }
    }

    #[test]
    fn special_files_are_named() {
        let kind = |p: &str| special_kind(&std::fs::metadata(p).unwrap());
        assert_eq!(kind("/dev/null"), Some("a character device"));
        assert_eq!(kind("/"), None);
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f");
        std::fs::write(&file, "x").unwrap();
        assert_eq!(special_kind(&std::fs::metadata(&file).unwrap()), None);
    }
}
