//! Where a write lands: the folder a path names, held open by its
//! descriptor, and the one name in it that the write replaces or creates.
//!
//! A path is walked a part at a time from `/` or the current folder, each
//! folder opened relative to the one before (`openat`, never by its whole
//! path again), and every symbolic link on the way, in a folder part as in
//! the last part, is followed only as the kernel's `fs.protected_symlinks`
//! rule allows, whatever the system's setting: in a sticky folder that
//! everyone may write (`/tmp`), only a link of the caller's or of the
//! folder's owner. From then on everything a write does, it does through
//! descriptors: the file in the way is opened once without following a
//! link and its `fstat` compared with what was looked at, the temporary
//! file is made in the held folder and renamed there, and a file of
//! several hard links is rewritten through the descriptor that was
//! checked. Another user renaming names meanwhile can make a write fail;
//! it cannot send it anywhere else.
//!
//! A link that `/proc` makes (`/dev/stdout` → `/proc/self/fd/1` →
//! `pipe:[…]`) names no path: the kernel opens what it stands for, and
//! the write goes into that open file (a pipe, a terminal, the file the
//! shell redirected to).
//!
//! That is Unix. On Windows (the other `imp`) a place is its folder's
//! path, names are looked at and opened by path, and a file is told from
//! another by when it was made and written and its length: the system
//! has no `openat`, and its links are not planted by other users in a
//! shared `/tmp`.

use std::ffi::{OsStr, OsString};
use std::fs::File;
use std::path::{Component, Path, PathBuf};

use super::LinkError;

/// Why a path leads to no place to write.
#[derive(Debug, thiserror::Error)]
pub enum PlaceError {
    #[error(transparent)]
    Link(#[from] LinkError),
    /// A folder part of the path does not exist.
    #[error("the folder {} does not exist", .0.display())]
    NoFolder(PathBuf),
    /// A folder part of the path is a file.
    #[error("{} is not a folder", .0.display())]
    NotAFolder(PathBuf),
    /// The path names a folder (`dir/..`, `.`).
    #[error("is a directory, not a file")]
    IsDirectory,
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

#[cfg(unix)]
impl From<rustix::io::Errno> for PlaceError {
    fn from(e: rustix::io::Errno) -> PlaceError {
        PlaceError::Io(e.into())
    }
}

/// The folder a write goes into, held open, and the name in it.
#[derive(Debug)]
pub struct Place {
    #[cfg(unix)]
    folder: std::os::fd::OwnedFd,
    /// The folder's path as the walk spelled it (links replaced by their
    /// targets), for messages and for what must have a path; never
    /// opened again to write.
    folder_path: PathBuf,
    /// One part: no `/`, never `.` or `..`.
    name: OsString,
    /// The name is a link `/proc` makes: opened by following it.
    magic: bool,
}

/// What is at a place's name, looked at without following a link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Regular,
    Directory,
    /// A FIFO, a device or a socket: written into, never replaced.
    Special,
    Link,
}

impl Kind {
    /// The kind of a file of type `t` (as `lstat` sees it).
    pub fn of(t: std::fs::FileType) -> Kind {
        if t.is_symlink() {
            Kind::Link
        } else if t.is_file() {
            Kind::Regular
        } else if t.is_dir() {
            Kind::Directory
        } else {
            Kind::Special
        }
    }
}

/// Links followed in one walk at most, as the kernel allows.
#[cfg(unix)]
const MAX_LINKS: usize = 40;

impl Place {
    /// Walks `path` to the folder it writes into; see the module's doc.
    /// A link as the last part is followed too (the rule applied): the
    /// place is where it leads, and a dangling link leads to a new file.
    pub fn reach(path: &Path) -> Result<Place, PlaceError> {
        imp::reach(path, true)
    }

    /// [`Place::reach`] with the last part taken as it is, a link there
    /// not followed: for a file that must be new ([`Place::create_new`]).
    pub fn reach_name(path: &Path) -> Result<Place, PlaceError> {
        imp::reach(path, false)
    }

    /// The path of the file this place names, as the walk spelled it: for
    /// messages and for reading, never for writing.
    pub fn path(&self) -> PathBuf {
        self.folder_path.join(&self.name)
    }

    /// The folder's path as the walk spelled it (for messages).
    pub fn folder_path(&self) -> &Path {
        &self.folder_path
    }

    /// The name in the folder.
    pub fn name(&self) -> &OsStr {
        &self.name
    }

    /// Whether the name is one of `/proc`'s links (`/dev/stdout`).
    pub fn is_magic(&self) -> bool {
        self.magic
    }
}

#[cfg(unix)]
mod imp {
    use super::*;
    use rustix::fs::{AtFlags, CWD, FileType, Mode, OFlags, openat, readlinkat, statat};
    use rustix::io::Errno;
    use std::collections::VecDeque;
    use std::os::fd::{AsFd, BorrowedFd, OwnedFd};
    use std::os::unix::ffi::OsStrExt;

    /// The flags a folder of the walk is held with: enough to name files
    /// in it (`*at` calls), nothing read or written through it.
    fn folder_flags() -> OFlags {
        path_only() | OFlags::DIRECTORY | OFlags::NOFOLLOW | OFlags::CLOEXEC
    }

    /// `O_PATH` where there is one: a descriptor that names a file (even
    /// a link, with `O_NOFOLLOW`) without opening it for anything.
    fn path_only() -> OFlags {
        #[cfg(any(target_os = "linux", target_os = "android"))]
        return OFlags::PATH;
        #[cfg(not(any(target_os = "linux", target_os = "android")))]
        return OFlags::RDONLY;
    }

    fn open_folder(at: BorrowedFd<'_>, name: &OsStr) -> rustix::io::Result<OwnedFd> {
        openat(at, name, folder_flags(), Mode::empty())
    }

    fn kind(st: &rustix::fs::Stat) -> Kind {
        match FileType::from_raw_mode(st.st_mode as _) {
            FileType::RegularFile => Kind::Regular,
            FileType::Directory => Kind::Directory,
            FileType::Symlink => Kind::Link,
            _ => Kind::Special,
        }
    }

    /// The kernel's `may_follow_link`: a link in a sticky, world-writable
    /// folder is followed only by its owner or when the folder's owner
    /// owns it.
    fn may_follow(link: &rustix::fs::Stat, folder: BorrowedFd<'_>) -> bool {
        let Ok(dir) = rustix::fs::fstat(folder) else {
            return false;
        };
        let shared = dir.st_mode & 0o1002 == 0o1002;
        !shared || link.st_uid == rustix::process::geteuid().as_raw() || link.st_uid == dir.st_uid
    }

    /// Whether the folder is `/proc`'s, whose links the kernel resolves.
    fn is_proc(folder: BorrowedFd<'_>) -> bool {
        const PROC_SUPER_MAGIC: i64 = 0x9fa0;
        // f_type's type differs between targets (a long, an u32).
        #[allow(clippy::unnecessary_cast)]
        rustix::fs::fstatfs(folder).is_ok_and(|fs| fs.f_type as i64 == PROC_SUPER_MAGIC)
    }

    /// The parts of `path` to walk, in order; `..` kept, `.` dropped.
    fn parts(path: &Path) -> VecDeque<OsString> {
        path.components()
            .filter_map(|c| match c {
                Component::Normal(p) => Some(p.to_owned()),
                Component::ParentDir => Some(OsString::from("..")),
                _ => None,
            })
            .collect()
    }

    /// A walk of a path a part at a time: the folder reached so far, held
    /// open, its path as the walk spells it, the parts still to walk, and
    /// the links followed. [`reach`] and [`make_folders`] both walk so.
    struct Walk {
        folder: OwnedFd,
        shown: PathBuf,
        pending: VecDeque<OsString>,
        links: usize,
    }

    impl Walk {
        /// The walk of `path`, at `/` or the current folder.
        fn start(path: &Path) -> Result<Walk, PlaceError> {
            let mut walk = Walk {
                folder: open_folder(CWD, OsStr::new("."))?,
                shown: PathBuf::new(),
                pending: parts(path),
                links: 0,
            };
            if path.has_root() {
                walk.back_to_root()?;
            }
            Ok(walk)
        }

        fn back_to_root(&mut self) -> Result<(), PlaceError> {
            self.folder = open_folder(CWD, OsStr::new("/"))?;
            self.shown = PathBuf::from("/");
            Ok(())
        }

        /// The folder's path for a message (`.` for the current one).
        fn shown_folder(&self) -> PathBuf {
            match self.shown.as_os_str().is_empty() {
                true => PathBuf::from("."),
                false => self.shown.clone(),
            }
        }

        /// One more link followed, or a name looked at again: past
        /// [`MAX_LINKS`], a loop.
        fn count_link(&mut self) -> Result<(), PlaceError> {
            self.links += 1;
            match self.links > MAX_LINKS {
                true => Err(LinkError::Loop.into()),
                false => Ok(()),
            }
        }

        /// The link `part` of the folder (`st` its own facts) may be
        /// followed, as the kernel's rule allows; it is counted.
        fn allow_link(&mut self, part: &OsStr, st: &rustix::fs::Stat) -> Result<(), PlaceError> {
            if !may_follow(st, self.folder.as_fd()) {
                return Err(LinkError::Protected {
                    link: self.shown.join(part),
                    folder: self.shown_folder(),
                }
                .into());
            }
            self.count_link()
        }

        /// Follows the link `part`: its target's parts are walked next,
        /// from `/` where it is absolute.
        fn follow(&mut self, part: &OsStr) -> Result<(), PlaceError> {
            let target = readlinkat(&self.folder, part, Vec::new())?;
            let target = Path::new(OsStr::from_bytes(target.as_bytes()));
            if target.has_root() {
                self.back_to_root()?;
            }
            for p in parts(target).into_iter().rev() {
                self.pending.push_front(p);
            }
            Ok(())
        }

        /// Goes into the folder `part`; one made a link or a file since it
        /// was looked at is looked at again.
        fn enter(&mut self, part: OsString) -> Result<(), PlaceError> {
            match open_folder(self.folder.as_fd(), &part) {
                Ok(next) => {
                    self.folder = next;
                    self.shown.push(part);
                    Ok(())
                }
                Err(Errno::LOOP | Errno::NOTDIR) => {
                    self.count_link()?;
                    self.pending.push_front(part);
                    Ok(())
                }
                Err(Errno::NOENT) => Err(PlaceError::NoFolder(self.shown.join(part))),
                Err(e) => Err(PlaceError::Io(e.into())),
            }
        }

        /// The place of the name `name` in the folder reached.
        fn place(self, name: OsString, magic: bool) -> Place {
            Place {
                folder_path: self.shown_folder(),
                folder: self.folder,
                name,
                magic,
            }
        }
    }

    pub(super) fn reach(path: &Path, follow_last: bool) -> Result<Place, PlaceError> {
        let mut walk = Walk::start(path)?;
        while let Some(part) = walk.pending.pop_front() {
            if part == ".." {
                walk.enter(part)?;
                continue;
            }
            let last = walk.pending.is_empty();
            let st = match statat(&walk.folder, &part, AtFlags::SYMLINK_NOFOLLOW) {
                Ok(st) => st,
                Err(Errno::NOENT) if last => return Ok(walk.place(part, false)),
                // The folder the file was to go in, named whole.
                Err(Errno::NOENT) => {
                    let rest = walk.pending.range(..walk.pending.len() - 1);
                    let folder = rest.fold(walk.shown.join(&part), |p, q| p.join(q));
                    return Err(PlaceError::NoFolder(folder));
                }
                Err(e) => return Err(PlaceError::Io(e.into())),
            };
            match kind(&st) {
                Kind::Link if last && !follow_last => return Ok(walk.place(part, false)),
                Kind::Link => {
                    walk.allow_link(&part, &st)?;
                    if last && is_proc(walk.folder.as_fd()) {
                        return Ok(walk.place(part, true));
                    }
                    walk.follow(&part)?;
                    // A link to `/` or `.` as the last part: a folder.
                    if walk.pending.is_empty() {
                        return Err(PlaceError::IsDirectory);
                    }
                }
                _ if last => return Ok(walk.place(part, false)),
                Kind::Directory => walk.enter(part)?,
                _ => return Err(PlaceError::NotAFolder(walk.shown.join(part))),
            }
        }
        Err(PlaceError::IsDirectory)
    }

    impl Place {
        /// What is at the name now, looked at without following it (a
        /// `/proc` link: what it stands for); `None` when nothing is.
        pub fn look(&self) -> std::io::Result<Option<(Kind, std::fs::Metadata)>> {
            let mut flags = path_only() | OFlags::CLOEXEC;
            if !self.magic {
                flags |= OFlags::NOFOLLOW;
            }
            let file = match openat(&self.folder, &self.name, flags, Mode::empty()) {
                Ok(fd) => File::from(fd),
                Err(Errno::NOENT) => return Ok(None),
                Err(e) => return Err(e.into()),
            };
            let meta = file.metadata()?;
            Ok(Some((Kind::of(meta.file_type()), meta)))
        }

        /// Whether the caller may write the file at the name, as the
        /// kernel decides it (`faccessat(W_OK, AT_EACCESS)`: owner, group,
        /// others, ACLs, a read-only mount), not from the mode bits alone.
        pub fn may_write(&self) -> bool {
            use rustix::fs::{Access, accessat};
            let flags = match self.magic {
                true => AtFlags::EACCESS,
                false => AtFlags::EACCESS | AtFlags::SYMLINK_NOFOLLOW,
            };
            match accessat(&self.folder, &self.name, Access::WRITE_OK, flags) {
                Ok(()) => true,
                // A kernel before 5.8 (no faccessat2) takes no flag but
                // AT_EACCESS: the name was just seen to be no link, and
                // the open that follows compares the file's identity.
                Err(Errno::INVAL | Errno::NOSYS) => {
                    accessat(&self.folder, &self.name, Access::WRITE_OK, AtFlags::EACCESS).is_ok()
                }
                Err(_) => false,
            }
        }

        /// Opens the file at the name, which must be of `kind` and the
        /// very file `meta` describes (same device and inode): a name
        /// swapped between the look and the open gives `Ok(None)`. A
        /// regular file is opened for reading and, with `write`, for
        /// writing too; a special file for writing, without waiting (a
        /// FIFO nobody reads: `ENXIO`), then made blocking.
        pub fn open(
            &self,
            kind: Kind,
            meta: &std::fs::Metadata,
            write: bool,
        ) -> std::io::Result<Option<File>> {
            use std::os::unix::fs::MetadataExt;
            let access = match (kind, write) {
                (Kind::Special, _) => OFlags::WRONLY,
                (_, true) => OFlags::RDWR,
                (_, false) => OFlags::RDONLY,
            };
            let mut flags = access | OFlags::NONBLOCK | OFlags::NOCTTY | OFlags::CLOEXEC;
            if !self.magic {
                flags |= OFlags::NOFOLLOW;
            }
            let fd = match openat(&self.folder, &self.name, flags, Mode::empty()) {
                Ok(fd) => fd,
                // A file the caller may write but not read: written, not
                // read (no copy of it can be kept).
                Err(Errno::ACCESS) if kind == Kind::Regular => {
                    let flags = (flags - access) | OFlags::WRONLY;
                    openat(&self.folder, &self.name, flags, Mode::empty())?
                }
                Err(Errno::LOOP | Errno::NOENT) => return Ok(None),
                Err(e) => return Err(e.into()),
            };
            let file = File::from(fd);
            let now = file.metadata()?;
            if now.dev() != meta.dev() || now.ino() != meta.ino() {
                return Ok(None);
            }
            if kind == Kind::Special {
                let flags = rustix::fs::fcntl_getfl(&file)?;
                rustix::fs::fcntl_setfl(&file, flags - OFlags::NONBLOCK)?;
            }
            Ok(Some(file))
        }

        /// Whether the name still names `file` (its device and inode),
        /// looked at without following a link.
        pub fn still_names(&self, file: &File) -> std::io::Result<bool> {
            use std::os::unix::fs::MetadataExt;
            let held = file.metadata()?;
            // st_dev and st_ino are narrower on some targets.
            #[allow(clippy::unnecessary_cast)]
            match statat(&self.folder, &self.name, AtFlags::SYMLINK_NOFOLLOW) {
                Ok(st) => Ok(st.st_dev as u64 == held.dev() && st.st_ino as u64 == held.ino()),
                Err(Errno::NOENT) => Ok(false),
                Err(e) => Err(e.into()),
            }
        }

        /// A new file in the folder named `PREFIX<random>SUFFIX`, made
        /// with the usual mode (0666 less the umask) and removed when the
        /// returned value is dropped, unless it is renamed or kept. It is
        /// locked (`flock`) while its descriptor is open, so that
        /// [`Place::sweep`] tells one being written from one a killed
        /// process left.
        pub fn new_file(&self, prefix: &str, suffix: &str) -> std::io::Result<NewFile<'_>> {
            for _ in 0..128 {
                let mut name = OsString::from(prefix);
                name.push(random_part());
                name.push(suffix);
                match openat(
                    &self.folder,
                    &name,
                    OFlags::RDWR
                        | OFlags::CREATE
                        | OFlags::EXCL
                        | OFlags::NOFOLLOW
                        | OFlags::CLOEXEC,
                    Mode::from_raw_mode(0o666),
                ) {
                    Ok(fd) => {
                        // A file system without locks: left to age (see
                        // `sweep`).
                        let _ = rustix::fs::flock(
                            &fd,
                            rustix::fs::FlockOperation::NonBlockingLockExclusive,
                        );
                        return Ok(NewFile {
                            place: self,
                            name: Some(name),
                            file: File::from(fd),
                        });
                    }
                    Err(Errno::EXIST) => continue,
                    Err(e) => return Err(e.into()),
                }
            }
            Err(std::io::Error::from(std::io::ErrorKind::AlreadyExists))
        }

        /// Removes what writes of the place's file left when they were
        /// killed (a power cut, `kill -9`, a crash): the temporary files
        /// of [`Place::new_file`] named `.rayoflight-XXXXXX.tmp` in the
        /// folder, and the copies `.NAME.XXXXXX.rayoflight-backup` of the
        /// file's old bytes that no record of a rewrite names (run
        /// [`crate::system::files::finish_at`] first). Only the caller's own
        /// regular files, and only those no process holds locked (every
        /// writer locks its file) and unchanged for `quiet` (a file made
        /// but not yet locked). Returns how many files and bytes went.
        pub fn sweep(&self, quiet: std::time::Duration) -> (usize, u64) {
            use rustix::fs::{Dir, FlockOperation, flock, unlinkat};
            let mut gone = (0, 0);
            // The held folder is an `O_PATH` descriptor: listing needs
            // one opened for reading, of that same folder.
            let Ok(listing) = openat(
                &self.folder,
                ".",
                OFlags::RDONLY | OFlags::DIRECTORY | OFlags::CLOEXEC,
                Mode::empty(),
            ) else {
                return gone;
            };
            let Ok(dir) = Dir::read_from(&listing) else {
                return gone;
            };
            let mut backup_of = OsString::from(".");
            backup_of.push(&self.name);
            backup_of.push(".");
            let mut record = backup_of.clone();
            record.push("rayoflight-rewrite");
            let rewriting = statat(&self.folder, &record, AtFlags::SYMLINK_NOFOLLOW).is_ok();
            let me = rustix::process::geteuid().as_raw();
            let now = std::time::SystemTime::now();
            for entry in dir.flatten() {
                let name = OsStr::from_bytes(entry.file_name().to_bytes()).to_owned();
                let bytes = name.as_bytes();
                // PREFIX, the six letters of `random_part`, SUFFIX: a
                // backup of `s.xml.2` is not one of `s.xml`'s.
                let made = |prefix: &[u8], suffix: &[u8]| {
                    bytes.len() == prefix.len() + 6 + suffix.len()
                        && bytes.starts_with(prefix)
                        && bytes.ends_with(suffix)
                        && bytes[prefix.len()..prefix.len() + 6]
                            .iter()
                            .all(u8::is_ascii_alphanumeric)
                };
                let temporary = made(b".rayoflight-", b".tmp");
                let backup = !rewriting && made(backup_of.as_bytes(), b".rayoflight-backup");
                if !(temporary || backup) {
                    continue;
                }
                let Ok(fd) = openat(
                    &self.folder,
                    &name,
                    OFlags::RDONLY | OFlags::NOFOLLOW | OFlags::NONBLOCK | OFlags::CLOEXEC,
                    Mode::empty(),
                ) else {
                    continue;
                };
                let Ok(st) = rustix::fs::fstat(&fd) else {
                    continue;
                };
                let changed = std::time::UNIX_EPOCH
                    + std::time::Duration::new(
                        u64::try_from(st.st_mtime).unwrap_or(0),
                        u32::try_from(st.st_mtime_nsec).unwrap_or(0),
                    );
                let old_enough = now.duration_since(changed).is_ok_and(|age| age >= quiet);
                if FileType::from_raw_mode(st.st_mode) != FileType::RegularFile
                    || st.st_uid != me
                    || !old_enough
                    || flock(&fd, FlockOperation::NonBlockingLockExclusive).is_err()
                {
                    continue;
                }
                // Still this very file under that name.
                #[allow(clippy::unnecessary_cast)]
                let same = statat(&self.folder, &name, AtFlags::SYMLINK_NOFOLLOW)
                    .is_ok_and(|now| now.st_dev == st.st_dev && now.st_ino == st.st_ino);
                if same && unlinkat(&self.folder, &name, AtFlags::empty()).is_ok() {
                    gone.0 += 1;
                    gone.1 += u64::try_from(st.st_size).unwrap_or(0);
                }
            }
            gone
        }

        /// A new file at the name itself, never over anything there (a
        /// file, a link, even a dangling one): `AlreadyExists`.
        pub fn create_new(&self) -> std::io::Result<NewFile<'_>> {
            let fd = openat(
                &self.folder,
                &self.name,
                OFlags::WRONLY | OFlags::CREATE | OFlags::EXCL | OFlags::NOFOLLOW | OFlags::CLOEXEC,
                Mode::from_raw_mode(0o666),
            )?;
            Ok(NewFile {
                place: self,
                name: Some(self.name.clone()),
                file: File::from(fd),
            })
        }

        /// An unnamed file in the folder (`O_TMPFILE`), for scratch data
        /// on the disk the write goes to; `None` where the file system
        /// has no such files.
        pub fn unnamed_file(&self) -> Option<File> {
            #[cfg(any(target_os = "linux", target_os = "android"))]
            {
                openat(
                    &self.folder,
                    ".",
                    OFlags::RDWR | OFlags::TMPFILE | OFlags::CLOEXEC,
                    Mode::from_raw_mode(0o600),
                )
                .ok()
                .map(File::from)
            }
            #[cfg(not(any(target_os = "linux", target_os = "android")))]
            None
        }

        /// Opens the file `name` of the held folder, never through a link,
        /// for reading (and writing with `write`); `None` where there is
        /// none.
        pub fn open_sibling(&self, name: &OsStr, write: bool) -> std::io::Result<Option<File>> {
            let access = if write { OFlags::RDWR } else { OFlags::RDONLY };
            let flags = access | OFlags::NOFOLLOW | OFlags::NONBLOCK | OFlags::CLOEXEC;
            match openat(&self.folder, name, flags, Mode::empty()) {
                Ok(fd) => Ok(Some(File::from(fd))),
                Err(Errno::NOENT) => Ok(None),
                Err(e) => Err(e.into()),
            }
        }

        /// Unlinks the file `name` of the held folder.
        pub fn remove_sibling(&self, name: &OsStr) -> std::io::Result<()> {
            Ok(rustix::fs::unlinkat(&self.folder, name, AtFlags::empty())?)
        }
    }

    /// A file made in a place's folder, removed when dropped unless
    /// [`NewFile::rename_over`] or [`NewFile::keep`] took it.
    #[derive(Debug)]
    pub struct NewFile<'p> {
        place: &'p Place,
        name: Option<OsString>,
        pub file: File,
    }

    impl NewFile<'_> {
        /// Its name in the folder (while it has one).
        pub fn name(&self) -> &OsStr {
            self.name.as_deref().unwrap_or_default()
        }

        /// Renames it to `to` in the same folder, never over a file there
        /// (`AlreadyExists`); it is still removed when dropped.
        pub fn rename_to(&mut self, to: &OsStr) -> std::io::Result<()> {
            use rustix::fs::{RenameFlags, renameat_with};
            let Some(name) = self.name.as_ref() else {
                return Ok(());
            };
            let folder = &self.place.folder;
            renameat_with(folder, name, folder, to, RenameFlags::NOREPLACE)?;
            self.name = Some(to.to_owned());
            Ok(())
        }

        /// A path that opens this very file for reading (its descriptor
        /// in `/proc/self/fd`), whatever is renamed meanwhile; its path
        /// in the folder where there is no `/proc`.
        pub fn path_to_read(&self) -> PathBuf {
            use std::os::fd::AsRawFd;
            let by_fd = PathBuf::from(format!("/proc/self/fd/{}", self.file.as_raw_fd()));
            if by_fd.exists() {
                return by_fd;
            }
            self.place
                .folder_path
                .join(self.name.as_deref().unwrap_or_default())
        }

        /// Renames the file over the place's name in the same folder. With
        /// `replace` false, nothing may be at the name (a file that
        /// appeared meanwhile is not written over): `AlreadyExists`.
        pub fn rename_over(mut self, replace: bool) -> std::io::Result<()> {
            use rustix::fs::{RenameFlags, renameat, renameat_with};
            let Some(name) = self.name.as_ref() else {
                return Ok(());
            };
            let folder = &self.place.folder;
            let done = match replace {
                true => renameat(folder, name, folder, &self.place.name),
                false => {
                    match renameat_with(
                        folder,
                        name,
                        folder,
                        &self.place.name,
                        RenameFlags::NOREPLACE,
                    ) {
                        // A file system without RENAME_NOREPLACE: a link
                        // fails on an existing name as well.
                        Err(Errno::INVAL | Errno::NOSYS) => rustix::fs::linkat(
                            folder,
                            name,
                            folder,
                            &self.place.name,
                            AtFlags::empty(),
                        )
                        .and_then(|()| rustix::fs::unlinkat(folder, name, AtFlags::empty())),
                        other => other,
                    }
                }
            };
            match done {
                Ok(()) => {
                    self.name = None;
                    Ok(())
                }
                Err(e) => Err(e.into()),
            }
        }

        /// Leaves the file where it is; returns its path (for a message).
        pub fn keep(mut self) -> PathBuf {
            let name = self.name.take().unwrap_or_default();
            self.place.folder_path.join(name)
        }
    }

    impl Drop for NewFile<'_> {
        fn drop(&mut self) {
            if let Some(name) = &self.name {
                let _ = rustix::fs::unlinkat(&self.place.folder, name, AtFlags::empty());
            }
        }
    }

    /// Makes the folder `path` and any folder above it that is missing
    /// (mode 0777 less the umask), walking it as [`Place::reach`] does:
    /// a link in any part followed only as the rule allows.
    pub fn make_folders(path: &Path) -> Result<(), PlaceError> {
        let mut walk = Walk::start(path)?;
        while let Some(part) = walk.pending.pop_front() {
            match statat(&walk.folder, &part, AtFlags::SYMLINK_NOFOLLOW) {
                Ok(st) if kind(&st) == Kind::Link => {
                    walk.allow_link(&part, &st)?;
                    walk.follow(&part)?;
                    continue;
                }
                Ok(st) if kind(&st) != Kind::Directory => {
                    return Err(PlaceError::NotAFolder(walk.shown.join(part)));
                }
                Ok(_) => {}
                Err(Errno::NOENT) => {
                    match rustix::fs::mkdirat(&walk.folder, &part, Mode::from_raw_mode(0o777)) {
                        Ok(()) | Err(Errno::EXIST) => {}
                        Err(e) => return Err(PlaceError::Io(e.into())),
                    }
                }
                Err(e) => return Err(PlaceError::Io(e.into())),
            }
            walk.enter(part)?;
        }
        Ok(())
    }
}

#[cfg(not(unix))]
mod imp {
    //! Elsewhere (Windows) a place is its folder's path: the system has
    //! no `openat` to hold a folder by, and a file's identity is what its
    //! metadata says (created, last written, length), not an inode. A
    //! file of several hard links is replaced, not rewritten in place.
    use super::*;

    pub(super) fn reach(path: &Path, _follow_last: bool) -> Result<Place, PlaceError> {
        let name = match path.components().next_back() {
            Some(Component::Normal(name)) => name.to_owned(),
            Some(_) => return Err(PlaceError::IsDirectory),
            None => return Err(PlaceError::IsDirectory),
        };
        let folder_path = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
            _ => PathBuf::from("."),
        };
        match std::fs::metadata(&folder_path) {
            Err(_) => return Err(PlaceError::NoFolder(folder_path)),
            Ok(m) if !m.is_dir() => return Err(PlaceError::NotAFolder(folder_path)),
            Ok(_) => {}
        }
        Ok(Place {
            folder_path,
            name,
            magic: false,
        })
    }

    use super::super::identity_of as identity;

    impl Place {
        /// What is at the name now, looked at without following it;
        /// `None` when nothing is.
        pub fn look(&self) -> std::io::Result<Option<(Kind, std::fs::Metadata)>> {
            let meta = match std::fs::symlink_metadata(self.path()) {
                Ok(meta) => meta,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
                Err(e) => return Err(e),
            };
            Ok(Some((Kind::of(meta.file_type()), meta)))
        }

        /// Whether the caller may write the file: the open that follows
        /// says (the read-only attribute is checked before).
        pub fn may_write(&self) -> bool {
            true
        }

        /// Opens the file at the name, which must be of `kind` and look
        /// as `meta` does (made, written and sized alike): `Ok(None)`
        /// when another file took the name meanwhile.
        pub fn open(
            &self,
            kind: Kind,
            meta: &std::fs::Metadata,
            write: bool,
        ) -> std::io::Result<Option<File>> {
            let file = match std::fs::OpenOptions::new()
                .read(kind != Kind::Special)
                .write(write || kind == Kind::Special)
                .open(self.path())
            {
                Ok(file) => file,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
                Err(e) => return Err(e),
            };
            if kind == Kind::Regular && identity(&file.metadata()?) != identity(meta) {
                return Ok(None);
            }
            Ok(Some(file))
        }

        /// Whether the name still names a file that looks as `file` does.
        pub fn still_names(&self, file: &File) -> std::io::Result<bool> {
            match std::fs::symlink_metadata(self.path()) {
                Ok(now) => Ok(now.is_file() && identity(&now) == identity(&file.metadata()?)),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
                Err(e) => Err(e),
            }
        }

        /// A new file in the folder named `PREFIX<random>SUFFIX`, removed
        /// when the returned value is dropped, unless renamed or kept.
        pub fn new_file(&self, prefix: &str, suffix: &str) -> std::io::Result<NewFile<'_>> {
            for _ in 0..128 {
                let mut name = OsString::from(prefix);
                name.push(random_part());
                name.push(suffix);
                match std::fs::OpenOptions::new()
                    .read(true)
                    .write(true)
                    .create_new(true)
                    .open(self.folder_path.join(&name))
                {
                    Ok(file) => {
                        return Ok(NewFile {
                            place: self,
                            name: Some(name),
                            file,
                        });
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                    Err(e) => return Err(e),
                }
            }
            Err(std::io::Error::from(std::io::ErrorKind::AlreadyExists))
        }

        /// A new file at the name itself, never over anything there:
        /// `AlreadyExists`.
        pub fn create_new(&self) -> std::io::Result<NewFile<'_>> {
            let file = std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(self.path())?;
            Ok(NewFile {
                place: self,
                name: Some(self.name.clone()),
                file,
            })
        }

        /// No unnamed files here.
        pub fn unnamed_file(&self) -> Option<File> {
            None
        }
    }

    /// A file made in a place's folder, removed when dropped unless
    /// [`NewFile::rename_over`] or [`NewFile::keep`] took it.
    #[derive(Debug)]
    pub struct NewFile<'p> {
        place: &'p Place,
        name: Option<OsString>,
        pub file: File,
    }

    impl NewFile<'_> {
        fn path(&self) -> PathBuf {
            self.place
                .folder_path
                .join(self.name.as_deref().unwrap_or_default())
        }

        /// Its path in the folder, to read it back by.
        pub fn path_to_read(&self) -> PathBuf {
            self.path()
        }

        /// Renames the file over the place's name. With `replace` false,
        /// nothing may be at the name: `AlreadyExists` (a hard link is
        /// made, which fails on an existing name, and the temporary name
        /// removed; where links cannot be made, the name is looked at
        /// first).
        pub fn rename_over(mut self, replace: bool) -> std::io::Result<()> {
            let (from, to) = (self.path(), self.place.path());
            match replace {
                true => std::fs::rename(&from, &to)?,
                false => match std::fs::hard_link(&from, &to) {
                    Ok(()) => {
                        let _ = std::fs::remove_file(&from);
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => return Err(e),
                    Err(_) if std::fs::symlink_metadata(&to).is_ok() => {
                        return Err(std::io::ErrorKind::AlreadyExists.into());
                    }
                    Err(_) => std::fs::rename(&from, &to)?,
                },
            }
            self.name = None;
            Ok(())
        }

        /// Leaves the file where it is; returns its path (for a message).
        pub fn keep(mut self) -> PathBuf {
            let path = self.path();
            self.name = None;
            path
        }
    }

    impl Drop for NewFile<'_> {
        fn drop(&mut self) {
            if self.name.is_some() {
                let _ = std::fs::remove_file(self.path());
            }
        }
    }

    /// Makes the folder `path` and any folder above it that is missing.
    pub fn make_folders(path: &Path) -> Result<(), PlaceError> {
        Ok(std::fs::create_dir_all(path)?)
    }
}

pub use imp::{NewFile, make_folders};

/// Six letters or digits, different each call (a counter and the
/// process's randomly keyed hasher, mixed with the time).
fn random_part() -> String {
    use std::hash::{BuildHasher, Hasher};
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNT: AtomicU64 = AtomicU64::new(0);
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u64(COUNT.fetch_add(1, Ordering::Relaxed));
    h.write_u128(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos()),
    );
    h.write_u32(std::process::id());
    let mut n = h.finish();
    const LETTERS: &[u8] = b"abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
    (0..6)
        .map(|_| {
            let c = LETTERS[(n % LETTERS.len() as u64) as usize];
            n /= LETTERS.len() as u64;
            c as char
        })
        .collect()
}

#[cfg(test)]
#[cfg(unix)]
mod tests {
    use super::*;

    #[test]
    fn folder_links_are_followed_and_named() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("real")).unwrap();
        std::os::unix::fs::symlink("real", dir.path().join("via")).unwrap();
        let place = Place::reach(&dir.path().join("via/out.png")).unwrap();
        assert_eq!(place.path(), dir.path().join("real/out.png"));
        assert!(place.look().unwrap().is_none());
    }

    #[test]
    fn a_missing_folder_and_a_file_as_folder_are_named() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("f"), "x").unwrap();
        let err = Place::reach(&dir.path().join("no/such/out.png")).unwrap_err();
        assert!(matches!(err, PlaceError::NoFolder(p) if p == dir.path().join("no/such")));
        let err = Place::reach(&dir.path().join("f/out.png")).unwrap_err();
        assert!(matches!(err, PlaceError::NotAFolder(p) if p == dir.path().join("f")));
        let err = Place::reach(&dir.path().join("..")).unwrap_err();
        assert!(matches!(err, PlaceError::IsDirectory));
    }

    #[test]
    fn a_loop_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::os::unix::fs::symlink("b", dir.path().join("a")).unwrap();
        std::os::unix::fs::symlink("a", dir.path().join("b")).unwrap();
        let err = Place::reach(&dir.path().join("a/x")).unwrap_err();
        assert!(matches!(err, PlaceError::Link(LinkError::Loop)));
    }

    #[test]
    fn standard_output_is_a_magic_place() {
        let place = Place::reach(Path::new("/proc/self/fd/0")).unwrap();
        assert!(place.is_magic());
    }

    #[test]
    fn new_files_go_when_dropped_and_stay_when_renamed() {
        let dir = tempfile::tempdir().unwrap();
        let place = Place::reach(&dir.path().join("out.txt")).unwrap();
        drop(place.new_file(".t-", ".tmp").unwrap());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        let mut new = place.new_file(".t-", ".tmp").unwrap();
        std::io::Write::write_all(&mut new.file, b"hello").unwrap();
        assert_eq!(std::fs::read(new.path_to_read()).unwrap(), b"hello");
        new.rename_over(false).unwrap();
        assert_eq!(std::fs::read(dir.path().join("out.txt")).unwrap(), b"hello");
        let again = place.new_file(".t-", ".tmp").unwrap();
        let err = again.rename_over(false).unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::AlreadyExists);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
