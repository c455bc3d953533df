//! Stopping cleanly on SIGINT, SIGTERM and SIGHUP (Ctrl+C, `kill`,
//! Slurm's time limit, a closed terminal): one mechanism for every writer.
//!
//! The command line calls [`install`] once. From then on a signal does
//! what it always does (the process ends) **unless** some work has said
//! that it can stop cleanly by holding a [`Cleanly`] guard: a file being
//! written (its temporary file must be removed, the old file kept), a
//! render (which stops at its next tile, [`crate::render::Cancel::on_signal`]).
//! Then the signal is only recorded; the work sees [`requested`] at its
//! next check, undoes what it started and returns an error, and the edge
//! says "interrupted: nothing was written" and exits with 128 + the
//! signal's number, as a shell reports a process the signal ended.
//!
//! A write past the file-size limit fails instead of ending the process
//! ([`writes_past_the_size_limit_fail`], SIGXFSZ).
//!
//! The desktop app calls [`record_only`] instead: it ends itself on these
//! signals (with its unsaved edits in its journal), so a signal never
//! ends it by default; it is only recorded, and a save or an export under
//! way stops at its next write and removes its temporary file.
//!
//! Without either (the library's tests) nothing is ever requested and
//! guards cost an atomic increment.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

/// What the signal handlers share with the process.
struct Handlers {
    /// The number of the first signal caught, 0 before any.
    caught: Arc<AtomicUsize>,
    /// Set by any caught signal: the flag long loops check.
    requested: Arc<AtomicBool>,
    /// True while no work holds a [`Cleanly`] guard: a signal then ends
    /// the process as its default action does.
    unguarded: Arc<AtomicBool>,
}

static HANDLERS: OnceLock<Handlers> = OnceLock::new();

/// Guards alive, counted under a lock so that `unguarded` always agrees
/// with the count (the handlers only read the flag).
static GUARDS: Mutex<usize> = Mutex::new(0);

/// A flag that is never set, for a process without [`install`].
static NEVER: AtomicBool = AtomicBool::new(false);

/// The signals that ask the process to stop.
#[cfg(unix)]
const SIGNALS: [i32; 3] = [
    signal_hook::consts::SIGINT,
    signal_hook::consts::SIGTERM,
    signal_hook::consts::SIGHUP,
];

/// Installs the handlers (once; later calls do nothing). Until a guard is
/// taken the signals keep their default action.
pub fn install() -> std::io::Result<()> {
    register(true)
}

/// Records SIGINT, SIGTERM and SIGHUP for the writers to see
/// ([`requested`]) and does nothing else: for a process that ends itself
/// on them (the app; once [`install`] or this ran, later calls do
/// nothing).
pub fn record_only() -> std::io::Result<()> {
    register(false)
}

/// The handlers of [`install`] (`ends`: a signal with no work to stop
/// cleanly ends the process, its number kept for the exit status) or of
/// [`record_only`] (it is only recorded).
fn register(ends: bool) -> std::io::Result<()> {
    if HANDLERS.get().is_some() {
        return Ok(());
    }
    let handlers = Handlers {
        caught: Arc::new(AtomicUsize::new(0)),
        requested: Arc::new(AtomicBool::new(false)),
        // Read by no handler when nothing ends the process.
        unguarded: Arc::new(AtomicBool::new(ends)),
    };
    #[cfg(unix)]
    for signal in SIGNALS {
        // Registration order is the order the actions run in: record the
        // signal, then end the process if no work can stop cleanly. A
        // process that ends itself on a signal chooses its own exit
        // status (the app's is 0: its edits are in its journal), so
        // `caught` is not kept for it.
        if ends {
            signal_hook::flag::register_usize(
                signal,
                Arc::clone(&handlers.caught),
                signal as usize,
            )?;
        }
        signal_hook::flag::register(signal, Arc::clone(&handlers.requested))?;
        if ends {
            signal_hook::flag::register_conditional_default(
                signal,
                Arc::clone(&handlers.unguarded),
            )?;
        }
    }
    let _ = HANDLERS.set(handlers);
    Ok(())
}

/// Makes a write past the file-size limit (`ulimit -f`, `prlimit
/// --fsize`) fail with "File too large" (EFBIG), undone like any failed
/// write, instead of SIGXFSZ ending the process with its temporary file
/// left beside the file it was to replace. The signal is caught and
/// nothing is done with it. For every command, the app's included (its
/// save is such a write).
pub fn writes_past_the_size_limit_fail() -> std::io::Result<()> {
    #[cfg(unix)]
    {
        // A flag nobody reads: the handler only has to be there.
        signal_hook::flag::register(signal_hook::consts::SIGXFSZ, Arc::default())?;
    }
    Ok(())
}

/// Whether a signal asked the process to stop.
pub fn requested() -> bool {
    flag().load(Ordering::Relaxed)
}

/// The flag a signal sets, for loops that take one
/// ([`crate::cluster::assemble::assemble_until`]).
pub fn flag() -> &'static AtomicBool {
    HANDLERS.get().map_or(&NEVER, |h| &*h.requested)
}

/// The signal that asked the process to stop, if one did.
pub fn caught() -> Option<i32> {
    let n = HANDLERS.get()?.caught.load(Ordering::Relaxed);
    (n != 0).then_some(n as i32)
}

/// While alive, a signal is recorded instead of ending the process: the
/// holder checks [`requested`] and stops cleanly.
#[must_use = "the guard only protects while it lives"]
pub struct Cleanly(());

/// Takes a [`Cleanly`] guard.
pub fn cleanly() -> Cleanly {
    let mut guards = GUARDS.lock().unwrap_or_else(|e| e.into_inner());
    *guards += 1;
    if let Some(h) = HANDLERS.get() {
        h.unguarded.store(false, Ordering::SeqCst);
    }
    Cleanly(())
}

impl Drop for Cleanly {
    fn drop(&mut self) {
        let mut guards = GUARDS.lock().unwrap_or_else(|e| e.into_inner());
        *guards -= 1;
        if *guards == 0
            && let Some(h) = HANDLERS.get()
        {
            h.unguarded.store(true, Ordering::SeqCst);
        }
    }
}

/// Why a writer stopped: a signal asked it to.
#[derive(Debug, thiserror::Error)]
#[error("interrupted")]
pub struct Stopped;

/// The error a writer returns when a signal stopped it. Not
/// `ErrorKind::Interrupted`, which `write_all` takes as "try again".
pub fn error() -> std::io::Error {
    std::io::Error::other(Stopped)
}

/// Whether `e` is [`error`]'s.
pub fn is_stop(e: &std::io::Error) -> bool {
    e.get_ref().is_some_and(|inner| inner.is::<Stopped>())
}

/// A writer that fails with [`error`] once a signal asked to stop, so
/// that a long write stops at its next call.
pub struct Checked<W>(pub W);

impl<W: std::io::Write> std::io::Write for Checked<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if requested() {
            return Err(error());
        }
        self.0.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}
