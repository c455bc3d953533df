//! Tiles of the image and the cancellation token checked inside them.

use super::Prepared;
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

/// Cuts a width × height image into tiles of at most `size` × `size`, in
/// reading order.
pub fn tiles(width: u32, height: u32, size: u32) -> Vec<Tile> {
    let size = size.max(1);
    let mut out = Vec::new();
    for y in (0..height).step_by(size as usize) {
        for x in (0..width).step_by(size as usize) {
            out.push(Tile {
                x,
                y,
                width: size.min(width - x),
                height: size.min(height - y),
            });
        }
    }
    out
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
    /// Cancelled too by a signal ([`crate::interrupt::requested`]).
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
    /// [`crate::interrupt::install`] has been called (the CLI); hold a
    /// [`crate::interrupt::Cleanly`] guard while rendering with it.
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
            || (self.on_signal && crate::interrupt::requested())
    }
}

/// Traces one tile: row-major RGB8 pixels, or `None` if cancelled (checked
/// before every pixel).
pub fn render_tile(prepared: &Prepared, tile: &Tile, cancel: &Cancel) -> Option<Vec<u8>> {
    let mut pixels = Vec::with_capacity(tile.width as usize * tile.height as usize * 3);
    prepared
        .render_tile_into(tile, cancel, &mut pixels)
        .map(|_| pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_image_once() {
        for (w, h) in [(1, 1), (1, 100), (100, 1), (65, 33), (64, 64)] {
            let mut count = vec![0u8; (w * h) as usize];
            for t in tiles(w, h, 32) {
                for y in t.y..t.y + t.height {
                    for x in t.x..t.x + t.width {
                        count[(y * w + x) as usize] += 1;
                    }
                }
            }
            assert!(count.iter().all(|&c| c == 1), "{w}x{h}");
        }
    }

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
