//! How far a render is, for whoever shows it while it runs (the app's
//! status bar during an export, a progress bar on a terminal): pixels done
//! out of the image's and rays traced, counted once per tile with relaxed
//! atomic adds, and the time left estimated from the pace so far.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// Pixels done and pixels in all, shared between the render and a reader.
#[derive(Debug, Default)]
pub struct Progress {
    done: AtomicU64,
    total: AtomicU64,
    /// Rays traced so far.
    rays: AtomicU64,
}

impl Progress {
    /// Starts counting a render of `total` pixels.
    pub(crate) fn start(&self, total: u64) {
        self.done.store(0, Ordering::Relaxed);
        self.rays.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
    }

    /// `pixels` more are done, tracing `rays`.
    pub(crate) fn add(&self, pixels: u64, rays: u64) {
        self.done.fetch_add(pixels, Ordering::Relaxed);
        self.rays.fetch_add(rays, Ordering::Relaxed);
    }

    /// Rays traced so far (as [`RenderStats::rays`](super::RenderStats)
    /// counts them).
    pub fn rays(&self) -> u64 {
        self.rays.load(Ordering::Relaxed)
    }

    /// Pixels done and in all (0 in all before the render starts).
    pub fn pixels(&self) -> (u64, u64) {
        (
            self.done.load(Ordering::Relaxed),
            self.total.load(Ordering::Relaxed),
        )
    }

    /// The fraction done, 0 to 1.
    pub fn fraction(&self) -> f64 {
        let (done, total) = self.pixels();
        if total == 0 {
            0.0
        } else {
            done.min(total) as f64 / total as f64
        }
    }

    /// The time left at the pace of the first `elapsed`, see [`time_left`].
    pub fn left(&self, elapsed: Duration) -> Option<Duration> {
        let (done, total) = self.pixels();
        time_left(elapsed, done, total)
    }
}

/// The time `total - done` more units take at the pace of `done` in
/// `elapsed`; `None` before a second has passed or anything is done (too
/// early to say).
pub fn time_left(elapsed: Duration, done: u64, total: u64) -> Option<Duration> {
    (elapsed >= Duration::from_secs(1) && done > 0)
        .then(|| elapsed.mul_f64(total.saturating_sub(done) as f64 / done as f64))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_left_follows_the_pace_so_far() {
        assert_eq!(time_left(Duration::from_millis(500), 1, 4), None);
        assert_eq!(time_left(Duration::from_secs(2), 0, 4), None);
        assert_eq!(
            time_left(Duration::from_secs(2), 1, 4),
            Some(Duration::from_secs(6))
        );
        let p = Progress::default();
        assert_eq!(p.fraction(), 0.0);
        p.start(8);
        p.add(2, 5);
        assert_eq!(p.rays(), 5);
        assert_eq!(p.fraction(), 0.25);
        assert_eq!(p.left(Duration::from_secs(1)), Some(Duration::from_secs(3)));
    }
}
