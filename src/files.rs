//! Facts about the files the core reads and writes that the standard
//! library leaves to each caller: what kind of special file a path is
//! (scenes and images must be regular files: a FIFO would block, a device
//! never ends), where a chain of symbolic links leads, and whether two
//! paths are one file.

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
/// the kernel does); a dangling link gives the path it points to.
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
