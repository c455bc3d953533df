//! Watching the scene file for saves made in another editor.
//!
//! The parent directory is watched, not the file: editors that save by
//! writing a temporary file and renaming it over the scene (vim, VS Code,
//! `sed -i`) replace the file's inode, which a watch on the file itself
//! would lose. A symbolic link's target directory is watched too, so edits
//! made to the target show. Events are debounced (notify-debouncer-full)
//! and filtered by file name and kind — opening or reading the file is no
//! change, and the watcher's own reads must not wake it again — then the
//! file is read, parsed and fingerprinted on a background thread, and only the
//! result is handed to the app.
//!
//! A directory that is deleted takes its watch with it. A second thread
//! therefore checks every [`POLL`] whether the watched directories are
//! still the same ones (watching them again when they come back, or when a
//! link now points elsewhere) and whether the file's size, time or inode
//! changed, and reports a change that events missed.
//!
//! The watch starts from the bytes the document read (their fingerprint):
//! a file that changed between that read and the watch is reported at
//! once, not missed.
//!
//! Every change is reported, even one back to a content reported before
//! (only a repeat of the very same bytes and stamp is not): the document
//! compares what it gets with the text it last read or wrote, which the
//! watcher cannot know.

use crate::scene::{self, LoadError, Object, Objects};
use crate::session::document::{FileRead, OwnWrites, fingerprint_file};
use crate::system::files::through_links;
use notify::{EventKind, RecursiveMode};
use notify_debouncer_full::{DebounceEventResult, Debouncer, RecommendedCache, new_debouncer};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, SystemTime};

/// Quiet time after the last event before the file is read.
pub const DEBOUNCE: Duration = Duration::from_millis(100);

/// How often the directories and the file are checked besides events.
pub const POLL: Duration = Duration::from_millis(250);

/// What happened to the watched file.
#[derive(Debug)]
pub enum FileEvent {
    /// It changed and parses: its text and scene (and what the document
    /// computes from them, computed here).
    Loaded(Box<FileRead>),
    /// It changed and does not parse (or cannot be read).
    Broken(LoadError),
    /// It is gone (deleted or renamed away).
    Missing,
    /// A large file ([`crate::session::BACKGROUND_BYTES`]) changed and is being
    /// read: one of the others follows.
    Reading,
}

type Watcher = Debouncer<notify::RecommendedWatcher, RecommendedCache>;

/// Watches one scene file until dropped.
pub struct SceneWatcher {
    path: PathBuf,
    stop: Arc<AtomicBool>,
    /// The objects the next read shares where equal.
    known: Arc<Mutex<Objects>>,
    /// What the app's own saves wrote: not read back.
    own: OwnWrites,
}

impl Drop for SceneWatcher {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

#[derive(Debug, thiserror::Error)]
#[error("cannot watch {}: {source}", path.display())]
pub struct WatchError {
    path: PathBuf,
    source: notify::Error,
}

/// What identifies a file or directory on disk between two looks.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Stamp {
    len: u64,
    modified: Option<SystemTime>,
    #[cfg(unix)]
    inode: (u64, u64),
}

fn stamp(path: &Path) -> Option<Stamp> {
    let meta = std::fs::metadata(path).ok()?;
    Some(Stamp {
        len: meta.len(),
        modified: meta.modified().ok(),
        #[cfg(unix)]
        inode: {
            use std::os::unix::fs::MetadataExt;
            (meta.dev(), meta.ino())
        },
    })
}

/// Which directory a path is: its inode where there are inodes (a
/// directory deleted and made again is another one), else whether it is
/// there. Its times change with every file saved in it and are left out.
fn identity(path: &Path) -> Option<u64> {
    let meta = std::fs::metadata(path).ok()?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some(hash(&(meta.dev(), meta.ino())))
    }
    #[cfg(not(unix))]
    {
        Some(u64::from(meta.is_dir()))
    }
}

fn hash(value: &impl std::hash::Hash) -> u64 {
    let mut h = std::hash::DefaultHasher::new();
    value.hash(&mut h);
    std::hash::Hasher::finish(&h)
}

fn parent(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    }
}

/// The directories to watch for `path`: its own and, through links, its
/// target's.
fn directories(path: &Path) -> Vec<PathBuf> {
    let mut dirs = vec![parent(path)];
    let target = parent(&through_links(path));
    if !dirs.contains(&target) {
        dirs.push(target);
    }
    dirs
}

/// The directories being watched, with the identity each had then.
struct Watched {
    watcher: Watcher,
    dirs: Vec<(PathBuf, Option<u64>)>,
}

impl Watched {
    /// Watches the directories `path` needs now; returns whether any watch
    /// changed (a directory came back, a link points elsewhere).
    fn refresh(&mut self, path: &Path) -> Result<bool, notify::Error> {
        let wanted: Vec<(PathBuf, Option<u64>)> = directories(path)
            .into_iter()
            .map(|d| {
                let id = identity(&d);
                (d, id)
            })
            .collect();
        if wanted == self.dirs {
            return Ok(false);
        }
        for (dir, _) in &self.dirs {
            let _ = self.watcher.unwatch(dir);
        }
        let mut result = Ok(());
        for (dir, s) in &wanted {
            if s.is_some()
                && let Err(e) = self.watcher.watch(dir, RecursiveMode::NonRecursive)
            {
                result = Err(e);
            }
        }
        self.dirs = wanted;
        result.map(|()| true)
    }
}

impl SceneWatcher {
    /// Starts watching `path`, whose bytes the document read had the
    /// fingerprint `document_read` (`None`: it read none, the file was missing or
    /// broken); `on_event` runs on a watcher thread.
    ///
    /// The watch starts from those bytes, not from a look at the file now:
    /// a file replaced between the document's read and this call (no
    /// event and no new stamp would tell) is read and reported at once.
    pub fn new(
        path: &Path,
        document_read: Option<u64>,
        on_event: impl Fn(FileEvent) + Send + Sync + 'static,
    ) -> Result<SceneWatcher, WatchError> {
        let path = crate::system::files::absolute(path);
        let on_event = Arc::new(on_event);
        let error = |source| WatchError {
            path: path.clone(),
            source,
        };

        // The file's stamp when it was last read for a report, and what the
        // report said: a burst of events that leaves the file exactly as
        // reported (same bytes, same stamp) is not reported again, and the
        // poll reports only stamps no report has seen. A file written back
        // to a content reported before has a new stamp and is reported.
        let seen: Arc<Mutex<(Option<Stamp>, Option<u64>)>> =
            Arc::new(Mutex::new((stamp(&path), None)));
        // The objects last read or shown: the next read shares those it
        // still has.
        let known = Arc::new(Mutex::new(Objects::default()));
        let last = known.clone();
        let own = OwnWrites::default();
        let report = {
            let on_event = on_event.clone();
            let target = path.clone();
            let seen = seen.clone();
            let own = own.clone();
            // `missed`: called by the poll, for a change no report saw.
            move |missed: bool| {
                // One read at a time (a gigabyte file takes a second).
                let Ok(mut last) = last.lock() else { return };
                let now = stamp(&target);
                // A report that ran meanwhile saw it.
                if missed && seen.lock().is_ok_and(|s| s.0 == now) {
                    return;
                }
                // A large file takes a while: say so first, and then
                // always say how it ended.
                let large = std::fs::metadata(&target)
                    .is_ok_and(|m| m.len() >= crate::session::BACKGROUND_BYTES);
                // The bytes the app's own save just wrote: the document
                // knows them (it would find the read unchanged). Only a
                // large file after such a save is fingerprinted first: a
                // small one is read at once, and the fingerprint costs a
                // read of its own.
                if large
                    && let Some(fingerprint) = own.last()
                    && fingerprint_file(&target).ok() == Some(fingerprint)
                {
                    if let Ok(mut seen) = seen.lock() {
                        *seen = (now, Some(hash(&("loaded", fingerprint))));
                    }
                    return;
                }
                // Other bytes: should the app's own come back, the
                // document will have read these meanwhile.
                own.forget();
                if large {
                    on_event(FileEvent::Reading);
                }
                let event = read(&target, &last);
                if let FileEvent::Loaded(read) = &event {
                    *last = read.scene.objects.clone();
                }
                drop(last);
                let key = match &event {
                    FileEvent::Loaded(read) => hash(&("loaded", read.fingerprint())),
                    FileEvent::Broken(e) => hash(&("broken", e.to_string())),
                    FileEvent::Missing | FileEvent::Reading => hash(&"missing"),
                };
                if let Ok(mut seen) = seen.lock() {
                    if *seen == (now.clone(), Some(key)) && !large {
                        return;
                    }
                    *seen = (now, Some(key));
                }
                on_event(event);
            }
        };
        let events_path = path.clone();
        let on_notify = {
            let report = report.clone();
            move |result: DebounceEventResult| {
                let Ok(events) = result else { return };
                let names = [
                    events_path.file_name().map(ToOwned::to_owned),
                    through_links(&events_path)
                        .file_name()
                        .map(ToOwned::to_owned),
                ];
                let ours = events.iter().any(|e| {
                    !matches!(e.kind, EventKind::Access(_))
                        && e.paths
                            .iter()
                            .any(|p| names.iter().flatten().any(|n| p.file_name() == Some(n)))
                });
                if ours {
                    report(false);
                }
            }
        };
        let watcher = new_debouncer(DEBOUNCE, None, on_notify).map_err(error)?;
        let mut watched = Watched {
            watcher,
            dirs: Vec::new(),
        };
        watched.refresh(&path).map_err(error)?;

        let stop = Arc::new(AtomicBool::new(false));
        let poll_stop = stop.clone();
        let poll_path = path.clone();
        let watched = Arc::new(Mutex::new(watched));
        std::thread::Builder::new()
            .name("scene-watcher-poll".to_owned())
            .spawn(move || {
                if document_read.is_none() || fingerprint_file(&poll_path).ok() != document_read {
                    report(false);
                }
                poll(&poll_path, &watched, &seen, &poll_stop, report);
            })
            .map_err(|e| error(notify::Error::io(e)))?;
        Ok(SceneWatcher {
            path,
            stop,
            known,
            own,
        })
    }

    /// The next read of the file shares with `objects` those equal to
    /// them (the app passes the scene it shows: a file saved with one
    /// change is read back as one new object, not a million).
    pub fn share(&self, objects: &Objects) {
        if let Ok(mut known) = self.known.lock() {
            *known = objects.clone();
        }
    }

    /// Where a save tells the fingerprint of what it writes
    /// ([`SaveJob::announcing`](crate::session::document::SaveJob::announcing)):
    /// a large file with those bytes is not read back.
    pub fn own_writes(&self) -> OwnWrites {
        self.own.clone()
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The second look: directories watched again when they change, and the
/// file's stamp compared with the one last `seen` by a report, every
/// [`POLL`] until `stop`. A new stamp is reported once it has held still
/// for one poll (a save in progress is not read half written).
fn poll(
    path: &Path,
    watched: &Mutex<Watched>,
    seen: &Mutex<(Option<Stamp>, Option<u64>)>,
    stop: &AtomicBool,
    report: impl Fn(bool),
) {
    let mut settling: Option<Option<Stamp>> = None;
    while !stop.load(Ordering::Relaxed) {
        std::thread::sleep(POLL);
        if stop.load(Ordering::Relaxed) {
            return;
        }
        let rewatched = watched
            .lock()
            .map(|mut w| w.refresh(path).unwrap_or(true))
            .unwrap_or(false);
        let now = stamp(path);
        let known = seen.lock().map(|s| s.0 == now).unwrap_or(true);
        if rewatched || (!known && settling.as_ref() == Some(&now)) {
            settling = None;
            report(true);
        } else {
            settling = (!known).then_some(now);
        }
    }
}

/// Reads and parses the file as it is now, sharing the objects that are
/// the same as in `like` (the objects last read).
pub fn read(path: &Path, like: &[Arc<Object>]) -> FileEvent {
    if !path.exists() {
        return FileEvent::Missing;
    }
    match scene::load_counting(path, like, None) {
        Ok(loaded) => FileEvent::Loaded(Box::new(FileRead::loaded(loaded))),
        Err(e) => FileEvent::Broken(e),
    }
}
