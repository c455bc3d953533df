//! The app's side of the journal of unsaved edits ([`crate::gui::journal`]):
//! keeping it as edits are made, restoring it when a scene opens, and
//! ending cleanly on SIGTERM, SIGINT and SIGHUP (a logout, Ctrl+C in the
//! terminal, a closed terminal) with the journal flushed.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use super::RayOfLightApp;
use crate::files::absolute;
use crate::gui::journal::{self, Entry, Job, JournalError, Writer};

/// The journal as the app keeps it.
pub(super) struct HotExit {
    folder: PathBuf,
    writer: Writer,
    /// The document generation last journaled (written or removed).
    kept: Option<u64>,
    /// The base last written, for which document: (path, fingerprint).
    base: Option<(PathBuf, u64)>,
    /// When the edits not yet journaled must be.
    due: Option<Instant>,
}

impl HotExit {
    pub(super) fn new(folder: PathBuf) -> HotExit {
        HotExit {
            writer: Writer::start(folder.clone()),
            folder,
            kept: None,
            base: None,
            due: None,
        }
    }
}

/// Set by SIGTERM, SIGINT or SIGHUP.
pub(super) fn watch_signals(ctx: &egui::Context) -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        if let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGTERM, SIGINT, SIGHUP]) {
            let flag = flag.clone();
            let ctx = ctx.clone();
            let _ = std::thread::Builder::new()
                .name("signals".to_owned())
                .spawn(move || {
                    if signals.forever().next().is_some() {
                        flag.store(true, Ordering::SeqCst);
                        ctx.request_repaint();
                    }
                });
        }
    }
    #[cfg(not(unix))]
    let _ = ctx;
    flag
}

/// "14:32", in the system's time zone.
fn clock(time: std::time::SystemTime) -> String {
    jiff::Timestamp::try_from(time)
        .map(|t| {
            t.to_zoned_datetime(jiff::tz::TimeZone::system())
                .strftime("%H:%M")
                .to_string()
        })
        .unwrap_or_else(|_| "before".to_owned())
}

impl RayOfLightApp {
    /// Once a frame: journals the unsaved edits [`journal::DELAY`] after
    /// they change, removes the journal once nothing is unsaved, and ends
    /// the app on a signal.
    pub(super) fn keep_journal(&mut self, ctx: &egui::Context) {
        if self.signalled.load(Ordering::SeqCst) {
            self.flush_journal();
            // Nothing asks: the edits are in the journal.
            self.allow_close = true;
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            return;
        }
        let Some(hot) = &mut self.hot_exit else {
            return;
        };
        if let Some(e) = hot.writer.error() {
            self.notice = Some((e, Instant::now()));
        }
        let generation = self.doc.generation();
        if hot.kept == Some(generation) {
            return;
        }
        let now = Instant::now();
        let due = *hot.due.get_or_insert(now + journal::DELAY);
        if self.doc.has_unsaved_edits() && now < due {
            ctx.request_repaint_after(due - now);
            return;
        }
        self.journal_now();
    }

    /// Journals the document as it is now (or removes its journal when
    /// nothing is unsaved).
    fn journal_now(&mut self) {
        let Some(hot) = &mut self.hot_exit else {
            return;
        };
        hot.due = None;
        hot.kept = Some(self.doc.generation());
        let Some(path) = self.doc.path().map(absolute) else {
            return;
        };
        if !self.doc.has_unsaved_edits() {
            hot.writer.send(Job::Remove(path));
            hot.base = None;
            return;
        }
        let base_fingerprint = self.doc.file_fingerprint();
        let base = (hot.base != Some((path.clone(), base_fingerprint)))
            .then(|| self.doc.file_text_writer());
        hot.base = Some((path.clone(), base_fingerprint));
        hot.writer.send(Job::Write {
            entry: Entry {
                scene: path,
                base_fingerprint,
                saved_at: std::time::SystemTime::now(),
                edits: self.doc.unsaved_edits(),
            },
            base,
        });
    }

    /// Writes what is not yet in the journal and waits for it (at most a
    /// second): before the app ends on a signal.
    pub(super) fn flush_journal(&mut self) {
        if self
            .hot_exit
            .as_ref()
            .is_some_and(|h| h.kept != Some(self.doc.generation()))
        {
            self.journal_now();
        }
        if let Some(hot) = &self.hot_exit {
            hot.writer.flush(Duration::from_secs(1));
        }
    }

    /// The user chose to lose the unsaved edits: their journal goes too.
    pub(super) fn discard_journal(&mut self) {
        let (Some(hot), Some(path)) = (&mut self.hot_exit, self.doc.path()) else {
            return;
        };
        hot.writer.send(Job::Remove(absolute(path)));
        hot.base = None;
    }

    /// Restores the journal of the document's file, if it has one: its
    /// edits come back as unsaved edits (merged with the file if it
    /// changed since), and the status bar says so.
    pub(super) fn restore_journal(&mut self) {
        let (Some(hot), Some(path)) = (&self.hot_exit, self.doc.path()) else {
            return;
        };
        let folder = hot.folder.clone();
        let path = path.to_owned();
        let restored = match journal::read(&folder, &path) {
            Ok(None) => return,
            Ok(Some(restored)) => restored,
            Err(e) => return self.journal_refused(&folder, &path, &e.to_string()),
        };
        let count = restored.entry.edits.len();
        let when = clock(restored.entry.saved_at);
        let base = || restored.base().map_err(|e| e.to_string());
        match self
            .doc
            .restore(restored.entry.base_fingerprint, base, &restored.entry.edits)
        {
            Ok(reload) => {
                let merged = match reload {
                    crate::gui::document::Reload::Merged => ", merged with the file's changes",
                    crate::gui::document::Reload::Conflict => {
                        ", and the file changed since: choose what to keep"
                    }
                    _ => "",
                };
                let plural = if count == 1 { "" } else { "s" };
                self.notify(format!(
                    "restored {count} unsaved edit{plural} from {when}{merged} — Ctrl+S saves, Ctrl+Z undoes"
                ));
                if let Some(hot) = &mut self.hot_exit {
                    // Journal again from the restored document.
                    hot.kept = None;
                    hot.base = None;
                }
                self.after_edit();
            }
            Err(why) => {
                let e = JournalError::Damaged {
                    path: journal::files(&folder, &path).0,
                    why,
                };
                self.journal_refused(&folder, &path, &e.to_string());
            }
        }
    }

    /// A journal that cannot be applied is moved aside (never applied,
    /// never lost), with a notice.
    fn journal_refused(&mut self, folder: &Path, scene: &Path, message: &str) {
        let kept = journal::set_aside(folder, scene);
        self.notify(match kept {
            Some(aside) => format!("{message}; kept as {}", aside.display()),
            None => message.to_owned(),
        });
    }
}
