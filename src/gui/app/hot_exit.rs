//! The app's side of the journal of unsaved edits ([`crate::session::journal`]):
//! keeping this window's entry as edits are made; when a scene opens,
//! restoring the entries of windows that are gone (every one made on this
//! file, one after the other, each merged onto the edits before it, a
//! value two of them changed asked as any conflict), offering rather than
//! merging the one made on another file that was at this path; and
//! ending cleanly on SIGTERM, SIGINT and SIGHUP (a logout, Ctrl+C in the
//! terminal, a closed terminal) with the journal flushed.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use super::RayOfLightApp;
use crate::session::document::Reload;
use crate::session::journal::{self, Claimed, Entry, Job, Match, Writer};

/// How the app ends: the user chose to quit without saving, or a signal
/// asked it to end (and when the app saw it).
#[derive(Default)]
pub(super) struct Ending {
    pub(super) allow_close: bool,
    pub(super) signalled: Arc<AtomicBool>,
    pub(super) signalled_at: Option<Instant>,
}

/// The journal as the app keeps it.
pub(super) struct HotExit {
    writer: Writer,
    /// The document generation last journaled (written or removed).
    kept: Option<u64>,
    /// The base last sent, for which document: (path, fingerprint).
    base: Option<(PathBuf, u64)>,
    /// When the edits not yet journaled must be.
    due: Option<Instant>,
    /// Entries of windows that are gone, restored into the document:
    /// removed once this window's entry holds their edits (and no
    /// conflict about them waits).
    adopted: Vec<Claimed>,
    /// Entries of windows that are gone, to restore one at a time, each
    /// once the conflicts of the one before are settled.
    waiting: VecDeque<Claimed>,
    /// Entries made at this path on a file replaced since, each asked
    /// about in turn.
    offered: VecDeque<Claimed>,
    /// What the restores of this document said, for one notice.
    said: Vec<String>,
}

impl HotExit {
    pub(super) fn new(folder: PathBuf) -> HotExit {
        HotExit {
            writer: Writer::start(folder),
            kept: None,
            base: None,
            due: None,
            adopted: Vec::new(),
            waiting: VecDeque::new(),
            offered: VecDeque::new(),
            said: Vec::new(),
        }
    }
}

/// How long the app waits on a signal for a save or export under way to
/// stop and remove its temporary file.
const STOP_WAIT: Duration = Duration::from_secs(3);

/// What the user answers about an entry made on another file.
enum Offer {
    Restore,
    Later,
    Discard,
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
    /// Once a frame: restores the next entry of a window that is gone,
    /// journals the unsaved edits [`journal::DELAY`] after they change,
    /// removes the journal once nothing is unsaved, and ends the app on a
    /// signal.
    pub(super) fn keep_journal(&mut self, ctx: &egui::Context) {
        if self.ending.signalled.load(Ordering::SeqCst) {
            // A save or an export under way stops at its next write (the
            // signal is recorded for it too, `crate::system::interrupt`) and
            // removes its temporary file: the app ends once it has, or
            // after STOP_WAIT.
            let since = *self.ending.signalled_at.get_or_insert_with(Instant::now);
            if let Some(export) = &self.dialogs.export {
                export.cancel();
            }
            if (self.dialogs.saving.is_some() || self.dialogs.export.is_some())
                && since.elapsed() < STOP_WAIT
            {
                ctx.request_repaint_after(Duration::from_millis(5));
                return;
            }
            self.flush_journal();
            // Nothing asks: the edits are in the journal.
            self.ending.allow_close = true;
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            return;
        }
        self.restore_waiting();
        let Some(hot) = &mut self.hot_exit else {
            return;
        };
        if let Some(e) = hot.writer.error() {
            self.status.notice = Some((e, Instant::now()));
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
    /// nothing is unsaved); then the entries of windows that are gone
    /// whose edits it holds go.
    fn journal_now(&mut self) {
        let Some(hot) = &mut self.hot_exit else {
            return;
        };
        hot.due = None;
        // While the user chooses between restored edits and others, the
        // edits are all in the entries they came from (still claimed):
        // an entry of this window's would only copy some of them, to be
        // asked about again after a crash.
        if self.doc.conflict().is_some_and(|c| c.is_restore()) {
            return;
        }
        hot.kept = Some(self.doc.generation());
        let Some(path) = self.doc.path().map(crate::system::files::absolute) else {
            return;
        };
        if !self.doc.has_unsaved_edits() {
            hot.writer.send(Job::Remove);
            hot.base = None;
        } else {
            let base_fingerprint = self.doc.file_fingerprint();
            let base = (hot.base != Some((path.clone(), base_fingerprint)))
                .then(|| self.doc.file_text_writer());
            hot.base = Some((path.clone(), base_fingerprint));
            hot.writer.send(Job::Write {
                entry: Entry::now(&path, base_fingerprint, self.doc.unsaved_edits()),
                base,
            });
        }
        // Edits waiting for the user's choices are not in the entry yet.
        if self.doc.conflict().is_none() && !hot.adopted.is_empty() {
            hot.writer
                .send(Job::Adopt(std::mem::take(&mut hot.adopted)));
        }
    }

    /// Journals the document at the next frame, whatever its generation
    /// (after the conflicts of a restore are settled, even by keeping
    /// everything as it was: the entries they came from can go).
    pub(super) fn journal_soon(&mut self) {
        if let Some(hot) = &mut self.hot_exit {
            hot.kept = None;
        }
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

    /// The user chose to lose the unsaved edits: their journal goes too,
    /// and the entries of windows that are gone they came from.
    pub(super) fn discard_journal(&mut self) {
        let Some(hot) = &mut self.hot_exit else {
            return;
        };
        hot.writer.send(Job::Remove);
        hot.writer
            .send(Job::Adopt(std::mem::take(&mut hot.adopted)));
        hot.base = None;
    }

    /// Looks in the journal for the document's file, just opened: the
    /// entries of windows that are gone are claimed and restored (made on
    /// another file at this path: offered first), damaged ones set aside
    /// with a notice, and windows still open on it said.
    pub(super) fn restore_journal(&mut self) {
        let Some(hot) = &mut self.hot_exit else {
            return;
        };
        // The previous document's: its edits were saved or discarded with
        // it; those not restored are let go, for a later window.
        hot.writer
            .send(Job::Adopt(std::mem::take(&mut hot.adopted)));
        hot.waiting.clear();
        hot.offered.clear();
        hot.said.clear();
        let Some((path, folder)) = self.doc.path().zip(hot.writer.folder()) else {
            return;
        };
        let found = journal::find(folder, path, hot.writer.id());
        for (e, aside) in found.damaged {
            hot.said.push(match aside {
                Some(aside) => format!("{e}; kept as {}", aside.display()),
                None => e.to_string(),
            });
        }
        if found.live > 0 {
            hot.said.push(
                "another RayOfLight window has unsaved edits of this file (they stay in it)"
                    .to_owned(),
            );
        }
        let disk = self.doc.disk_fingerprint();
        for claimed in found.claimed {
            let holds_base = disk == Some(claimed.restored.entry.base_fingerprint);
            // Made on another file, unless the edits are all in this one
            // already (the window saved, then ended before its entry
            // went: the save replaced the file).
            let replaced = claimed.how == Match::Replaced && !holds_base && {
                let entry = &claimed.restored.entry;
                let mut probe = self.doc.clone();
                let base = || claimed.restored.base().map_err(|e| e.to_string());
                !matches!(
                    probe.restore(entry.base_fingerprint, base, &entry.edits),
                    Ok(Reload::Unchanged) if !probe.has_unsaved_edits()
                )
            };
            match replaced {
                true => hot.offered.push_back(claimed),
                false => hot.waiting.push_back(claimed),
            }
        }
        if !hot.said.is_empty() {
            let text = hot.said.join("; ");
            self.notify(text);
        }
        self.restore_waiting();
    }

    /// Restores the next entry waiting, unless a conflict of the one
    /// before waits for the user, or a question about another is open.
    fn restore_waiting(&mut self) {
        let Some(hot) = &mut self.hot_exit else {
            return;
        };
        if self.doc.conflict().is_some() || !hot.offered.is_empty() {
            return;
        }
        let Some(claimed) = hot.waiting.pop_front() else {
            return;
        };
        let first = hot.adopted.is_empty() && !self.doc.has_unsaved_edits();
        let entry = &claimed.restored.entry;
        let count = entry.edits.len();
        let when = clock(entry.saved_at);
        let base = || claimed.restored.base().map_err(|e| e.to_string());
        let restored = match first {
            true => self.doc.restore(entry.base_fingerprint, base, &entry.edits),
            false => self
                .doc
                .restore_more(entry.base_fingerprint, base, &entry.edits),
        };
        let plural = if count == 1 { "" } else { "s" };
        let said = match restored {
            Ok(Reload::Unchanged) if first && !self.doc.has_unsaved_edits() => {
                format!("the {count} unsaved edit{plural} from {when} are in the file already")
            }
            Ok(reload) => {
                let how = match (reload, first) {
                    (Reload::Merged, true) => ", merged with the file's changes",
                    (Reload::Conflict, true) => ", and the file changed since: choose what to keep",
                    (Reload::Conflict, false) => {
                        ", which changed values edited here too: choose what to keep"
                    }
                    _ => "",
                };
                let whose = if first { "" } else { " of another window" };
                let moved = match &claimed.how {
                    Match::Moved { from } => format!(" (made at {})", from.display()),
                    _ => String::new(),
                };
                format!(
                    "restored {count} unsaved edit{plural}{whose} from {when}{moved}{how} — Ctrl+S saves, Ctrl+Z undoes"
                )
            }
            Err(why) => {
                let e = journal::JournalError::Damaged {
                    path: claimed.path().to_owned(),
                    why,
                };
                let said = match claimed.set_aside() {
                    Some(aside) => format!("{e}; kept as {}", aside.display()),
                    None => e.to_string(),
                };
                self.say_restored(said);
                return;
            }
        };
        if let Some(hot) = &mut self.hot_exit {
            hot.adopted.push(claimed);
            // Journal again from the restored document.
            hot.kept = None;
            hot.base = None;
        }
        self.say_restored(said);
        self.after_edit();
    }

    /// Adds `said` to what this document's restores said, in one notice.
    fn say_restored(&mut self, said: String) {
        if let Some(hot) = &mut self.hot_exit {
            hot.said.push(said);
            let text = hot.said.join("; ");
            self.notify(text);
        }
    }

    /// Asks about an entry made at this path on a file that was replaced
    /// since: restore its edits onto this file (merged, conflicts asked),
    /// keep them for later, or discard them.
    pub(super) fn journal_offer_modal(&mut self, ui: &mut egui::Ui) {
        let Some(claimed) = self.hot_exit.as_ref().and_then(|h| h.offered.front()) else {
            return;
        };
        let entry = &claimed.restored.entry;
        let count = entry.edits.len();
        let (plural, were) = if count == 1 {
            ("", "was")
        } else {
            ("s", "were")
        };
        let text = format!(
            "{count} unsaved edit{plural} from {} {were} made on {} when another file was there \
             (the file there now was saved by another program since, or is another file \
             altogether). They are not applied unless you ask.",
            clock(entry.saved_at),
            entry.scene.display(),
        );
        let mut answer = None;
        egui::Modal::new(egui::Id::unique("journal-offer")).show(ui.ctx(), |ui| {
            ui.set_width(520.0);
            ui.heading("Unsaved edits of another file");
            ui.label(text);
            ui.horizontal(|ui| {
                if ui.button("Restore them onto this file").clicked() {
                    answer = Some(Offer::Restore);
                }
                if ui.button("Keep them for later").clicked() {
                    answer = Some(Offer::Later);
                }
                if ui.button("Discard them").clicked() {
                    answer = Some(Offer::Discard);
                }
            });
        });
        let Some(answer) = answer else {
            return;
        };
        let Some(hot) = &mut self.hot_exit else {
            return;
        };
        let Some(claimed) = hot.offered.pop_front() else {
            return;
        };
        let kept = claimed.path().display().to_string();
        match answer {
            Offer::Restore => hot.waiting.push_back(claimed),
            // Let go: the entry stays, for the next window on this file.
            Offer::Later => {
                drop(claimed);
                self.notify(format!(
                    "the unsaved edits of the other file are kept in {kept}: they are offered again when this file opens"
                ));
            }
            Offer::Discard => {
                claimed.remove();
                self.notify("the unsaved edits of the other file were discarded".to_owned());
            }
        }
        self.restore_waiting();
    }
}
