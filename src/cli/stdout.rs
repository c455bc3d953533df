//! The binary's one way to stdout. Every line the commands print (help,
//! version, `plan`, `split`, `explain`, `-time`, the tables of `bench`
//! and `study`) goes through [`write`], so that a failure to print is an
//! error (exit 1, a message on stderr) wherever it happens: a script never
//! takes a cut list, a plan or a time it did not get for one it did; and
//! so that names from outside reach the terminal escaped
//! ([`rayoflight::system::escape::visible`]).
//!
//! A closed pipe (`rayoflight split … | head`) is the reader's choice and
//! no error. A stdout closed from the start (`rayoflight plan s.xml >&-`)
//! is: the Rust runtime opens `/dev/null` on a closed standard descriptor
//! before `main`, where every write would succeed unseen, so whether
//! descriptor 1 was open is recorded before the runtime starts (Linux: a
//! function in `.init_array`, which the C runtime calls before `main`).

use super::failure::Failure;
use std::io::Write;

/// The message for a stdout closed from the start.
pub const CLOSED: &str = "rayoflight: cannot write to stdout: it is closed";

/// Writes `text` to stdout and flushes it; the error is the one-line
/// message to print on stderr.
pub fn write(text: &str) -> Result<(), String> {
    if closed_at_start() {
        return Err(CLOSED.to_owned());
    }
    let mut out = std::io::stdout().lock();
    let text = rayoflight::system::escape::visible(text, true);
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(format!("rayoflight: cannot write to stdout: {e}"))
        }
        _ => Ok(()),
    }
}

/// Writes `text` and a newline to stdout ([`write`]): a failure to print
/// is the command's.
pub(super) fn line(text: &str) -> Result<(), Failure> {
    write(&format!("{text}\n")).map_err(Failure::Error)
}

/// Whether descriptor 1 was closed when the process started (always
/// false where that is not recorded).
#[cfg(target_os = "linux")]
pub fn closed_at_start() -> bool {
    at_start::CLOSED.load(std::sync::atomic::Ordering::Relaxed)
}

#[cfg(not(target_os = "linux"))]
pub fn closed_at_start() -> bool {
    false
}

#[cfg(target_os = "linux")]
mod at_start {
    use std::sync::atomic::{AtomicBool, Ordering};

    pub static CLOSED: AtomicBool = AtomicBool::new(false);

    /// Runs before the Rust runtime (and its `/dev/null` on closed
    /// descriptors): is descriptor 1 open?
    extern "C" fn record() {
        // SAFETY: F_GETFD only reads the descriptor's flags; an invalid
        // descriptor gives -1 (EBADF) and changes nothing.
        let closed = unsafe { libc::fcntl(1, libc::F_GETFD) } == -1;
        CLOSED.store(closed, Ordering::Relaxed);
    }

    // SAFETY: `.init_array` holds functions the C runtime calls with no
    // arguments before `main`; `record` is one, and uses nothing that
    // needs the Rust runtime.
    #[used]
    #[unsafe(link_section = ".init_array")]
    static RECORD: extern "C" fn() = record;
}
