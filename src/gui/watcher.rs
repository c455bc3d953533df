//! Watching the scene file for saves made in another editor.
//!
//! The parent directory is watched, not the file: editors that save by
//! writing a temporary file and renaming it over the scene (vim, VS Code,
//! `sed -i`) replace the file's inode, which a watch on the file itself
//! would lose. Events are debounced (notify-debouncer-full) and filtered by
//! file name and kind — opening or reading the file is no change, and the
//! watcher's own reads must not wake it again — then the file is read and
//! parsed completely on the watcher's thread, and only the result is handed
//! to the app.

use crate::scene::{self, LoadError, Scene};
use notify::{EventKind, RecursiveMode};
use notify_debouncer_full::{DebounceEventResult, Debouncer, RecommendedCache, new_debouncer};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Quiet time after the last event before the file is read.
pub const DEBOUNCE: Duration = Duration::from_millis(100);

/// What happened to the watched file.
#[derive(Debug)]
pub enum FileEvent {
    /// It changed and parses: its text and scene.
    Loaded(String, Box<Scene>),
    /// It changed and does not parse (or cannot be read).
    Broken(LoadError),
    /// It is gone (deleted or renamed away).
    Missing,
}

/// Watches one scene file until dropped.
pub struct SceneWatcher {
    _debouncer: Debouncer<notify::RecommendedWatcher, RecommendedCache>,
    path: PathBuf,
}

#[derive(Debug, thiserror::Error)]
#[error("cannot watch {}: {source}", path.display())]
pub struct WatchError {
    path: PathBuf,
    source: notify::Error,
}

impl SceneWatcher {
    /// Starts watching `path`; `on_event` runs on the watcher's thread.
    pub fn new(
        path: &Path,
        on_event: impl Fn(FileEvent) + Send + 'static,
    ) -> Result<SceneWatcher, WatchError> {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
            _ => PathBuf::from("."),
        };
        let name = path.file_name().map(|n| n.to_owned());
        let target = path.clone();
        // What was last reported: a burst of events that leaves the file as
        // it was reported is not reported again.
        let mut last: Option<String> = None;
        let mut debouncer = new_debouncer(DEBOUNCE, None, move |result: DebounceEventResult| {
            let Ok(events) = result else { return };
            let ours = events.iter().any(|e| {
                !matches!(e.kind, EventKind::Access(_))
                    && e.paths.iter().any(|p| p.file_name() == name.as_deref())
            });
            if !ours {
                return;
            }
            let event = read(&target);
            let key = match &event {
                FileEvent::Loaded(text, _) => format!("loaded\n{text}"),
                FileEvent::Broken(e) => format!("broken\n{e}"),
                FileEvent::Missing => "missing".to_owned(),
            };
            if last.as_ref() != Some(&key) {
                last = Some(key);
                on_event(event);
            }
        })
        .map_err(|source| WatchError {
            path: path.clone(),
            source,
        })?;
        debouncer
            .watch(&dir, RecursiveMode::NonRecursive)
            .map_err(|source| WatchError {
                path: path.clone(),
                source,
            })?;
        Ok(SceneWatcher {
            _debouncer: debouncer,
            path,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// Reads and parses the file as it is now.
pub fn read(path: &Path) -> FileEvent {
    if !path.exists() {
        return FileEvent::Missing;
    }
    match scene::load_with_text(path) {
        Ok((text, scene)) => FileEvent::Loaded(text, Box::new(scene)),
        Err(e) => FileEvent::Broken(e),
    }
}
