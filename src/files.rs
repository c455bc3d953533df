//! Facts about the files the core reads and writes that the standard
//! library leaves to each caller: what kind of special file a path is
//! (scenes and images must be regular files: a FIFO would block, a device
//! never ends), where a chain of symbolic links leads and which links may
//! be followed for writing (the kernel's `fs.protected_symlinks` rule),
//! whether the caller may write a file (`access(W_OK)`, not mode bits),
//! the owner, group and extended attributes a replaced file keeps, the
//! lock every read-modify-write of a scene holds, and whether two paths
//! are one file.

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
/// reading and watching; writing goes through [`follow_for_writing`].
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

/// The file that writing to `path` writes: symbolic links followed as the
/// kernel follows them, with its `fs.protected_symlinks` rule applied
/// whatever the system's setting: in a sticky folder that everyone may
/// write (`/tmp`), a link is followed only when it belongs to the caller
/// or to the folder's owner — else another user could plant
/// `/tmp/x.png -> ~victim/notes.txt` and have our output replace it. A
/// loop is refused. A link the kernel resolves by itself (`/dev/stdout`'s
/// `/proc/self/fd/1 -> pipe:[…]`) ends the chain: the link is the path.
pub fn follow_for_writing(path: &Path) -> Result<PathBuf, LinkError> {
    let mut p = path.to_owned();
    // 40 links followed, and the path they lead to looked at.
    for _ in 0..=40 {
        let Ok(meta) = std::fs::symlink_metadata(&p) else {
            return Ok(p);
        };
        if !meta.file_type().is_symlink() {
            return Ok(p);
        }
        let folder = match p.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir.to_owned(),
            _ => PathBuf::from("."),
        };
        if !may_follow(&meta, &folder) {
            return Err(LinkError::Protected { link: p, folder });
        }
        let Ok(target) = std::fs::read_link(&p) else {
            return Ok(p);
        };
        let next = folder.join(target);
        // A "magic" link of /proc names no path: the kernel opens it.
        if std::fs::symlink_metadata(&next).is_err() && std::fs::metadata(&p).is_ok() {
            return Ok(p);
        }
        p = next;
    }
    Err(LinkError::Loop)
}

/// The kernel's `may_follow_link`: a link in a sticky, world-writable
/// folder is followed only by its owner or when the folder's owner owns it.
fn may_follow(link: &Metadata, folder: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let Ok(dir) = std::fs::metadata(folder) else {
            return true;
        };
        let shared = dir.mode() & 0o1002 == 0o1002;
        !shared || link.uid() == rustix::process::geteuid().as_raw() || link.uid() == dir.uid()
    }
    #[cfg(not(unix))]
    {
        let _ = (link, folder);
        true
    }
}

/// Whether the caller may write the existing file `path`, as the kernel
/// decides it (`faccessat(W_OK, AT_EACCESS)`: owner, group, others, ACLs,
/// a read-only mount), not from the mode bits alone: in a group-writable
/// folder a user can rename over another's private file, and must not.
pub fn may_write(path: &Path) -> bool {
    #[cfg(unix)]
    {
        use rustix::fs::{Access, AtFlags, CWD, accessat};
        accessat(CWD, path, Access::WRITE_OK, AtFlags::EACCESS).is_ok()
    }
    #[cfg(not(unix))]
    {
        std::fs::metadata(path).is_ok_and(|m| !m.permissions().readonly())
    }
}

/// Gives `new` (a file about to replace `old`, whose metadata is `meta`)
/// what `old` has beside its bytes, as far as the caller may: its owner
/// and group (a user may give a file only to a group of theirs; root to
/// anyone), its mode (set after the owner, which clears set-id bits) and
/// its extended attributes (ACLs, SELinux labels, user attributes). What
/// the system refuses is left as a new file has it.
pub fn keep_attributes(old: &Path, meta: &Metadata, new: &std::fs::File) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if std::os::unix::fs::fchown(new, Some(meta.uid()), Some(meta.gid())).is_err() {
            let _ = std::os::unix::fs::fchown(new, None, Some(meta.gid()));
        }
        copy_xattrs(old, new);
    }
    new.set_permissions(meta.permissions())
}

/// Copies `old`'s extended attributes to `new`, each one that the
/// system lets us read and set.
#[cfg(unix)]
fn copy_xattrs(old: &Path, new: &std::fs::File) {
    use rustix::fs::{XattrFlags, fsetxattr, getxattr, getxattr_query, listxattr, listxattr_query};
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

/// The inode of `meta` (Unix); elsewhere every file is alike, which makes
/// [`lock_for_update`] take the first file it locks.
fn identity_of(meta: &Metadata) -> (u64, u64) {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        (meta.dev(), meta.ino())
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        (0, 0)
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

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
