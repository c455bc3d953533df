//! Tiles of the image and the cancellation token checked inside them.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Edge of the square tiles the image is cut into.
pub const TILE_SIZE: u32 = 32;

/// A rectangle of pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tile {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// A cancellation token: a render request's generation compared with the
/// newest generation requested. One relaxed atomic load per check.
#[derive(Debug, Clone)]
pub struct Cancel {
    newest: Option<Arc<AtomicU64>>,
    generation: u64,
    /// Cancelled too when this counter moves off its value
    /// ([`Cancel::or_when`]).
    also: Option<(Arc<AtomicU64>, u64)>,
    /// Cancelled too by a signal ([`crate::system::interrupt::requested`]).
    on_signal: bool,
}

impl Cancel {
    /// A token that is never cancelled (the CLI).
    pub fn never() -> Cancel {
        Cancel {
            newest: None,
            generation: 0,
            also: None,
            on_signal: false,
        }
    }

    /// A token cancelled by SIGINT, SIGTERM or SIGHUP once
    /// [`crate::system::interrupt::install`] has been called (the CLI); hold a
    /// [`crate::system::interrupt::Cleanly`] guard while rendering with it.
    pub fn on_signal() -> Cancel {
        Cancel {
            on_signal: true,
            ..Cancel::never()
        }
    }

    /// A token for request `generation`, cancelled as soon as `newest`
    /// holds another value.
    pub fn new(newest: Arc<AtomicU64>, generation: u64) -> Cancel {
        Cancel {
            newest: Some(newest),
            generation,
            also: None,
            on_signal: false,
        }
    }

    /// This token, cancelled too as soon as `newest` holds another value
    /// than `generation` (a job of one queue that a newer request of
    /// another supersedes).
    pub fn or_when(self, newest: Arc<AtomicU64>, generation: u64) -> Cancel {
        Cancel {
            also: Some((newest, generation)),
            ..self
        }
    }

    pub fn is_cancelled(&self) -> bool {
        self.newest
            .as_ref()
            .is_some_and(|n| n.load(Ordering::Relaxed) != self.generation)
            || self
                .also
                .as_ref()
                .is_some_and(|(n, g)| n.load(Ordering::Relaxed) != *g)
            || (self.on_signal && crate::system::interrupt::requested())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cancel_follows_the_newest_generation() {
        let newest = Arc::new(AtomicU64::new(3));
        let token = Cancel::new(newest.clone(), 3);
        assert!(!token.is_cancelled());
        newest.store(4, Ordering::Relaxed);
        assert!(token.is_cancelled());
        assert!(!Cancel::never().is_cancelled());
        let other = Arc::new(AtomicU64::new(7));
        let both = Cancel::new(newest.clone(), 4).or_when(other.clone(), 7);
        assert!(!both.is_cancelled());
        other.store(8, Ordering::Relaxed);
        assert!(both.is_cancelled(), "by the other counter");
        let both = Cancel::new(newest.clone(), 4).or_when(other, 8);
        newest.store(5, Ordering::Relaxed);
        assert!(both.is_cancelled(), "by its own");
    }
}
