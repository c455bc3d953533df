//! How coarse to render while the mouse moves: the scale that keeps at
//! least [`TARGET_FPS`] pictures a second, chosen from the measured cost of
//! the passes rendered so far, and the passes that refine the picture from
//! there once the mouse stops.

use std::time::Duration;

/// Pictures a second while a gesture or a drag is under way.
pub const TARGET_FPS: f64 = 30.0;

/// A picture gets this fraction of a frame: the rest goes to preparing the
/// scene, sending the request and showing the picture.
const SHARE: f64 = 2.0 / 3.0;

/// The smallest side a coarse picture is allowed to have, in pixels.
const MIN_SIDE: u32 = 8;

/// The measured cost of rendering, per primary ray.
#[derive(Debug, Clone, Copy, Default)]
pub struct Pace {
    seconds_per_ray: Option<f64>,
}

impl Pace {
    /// A pass of `rays` primary rays took `elapsed`: the estimate follows
    /// it, halfway (a scene or a camera change moves the cost).
    pub fn measured(&mut self, rays: u64, elapsed: Duration) {
        if rays == 0 {
            return;
        }
        let now = elapsed.as_secs_f64() / rays as f64;
        self.seconds_per_ray = Some(match self.seconds_per_ray {
            Some(before) => 0.5 * (before + now),
            None => now,
        });
    }

    /// The 1/scale of each side that renders a `width` × `height` picture
    /// within two thirds of a frame at [`TARGET_FPS`]; 8 until something was
    /// measured.
    pub fn interactive_scale(&self, width: u32, height: u32) -> u32 {
        let most = (width.min(height) / MIN_SIDE).max(1);
        let Some(cost) = self.seconds_per_ray else {
            return 8.min(most);
        };
        let budget = SHARE / TARGET_FPS / cost;
        let pixels = f64::from(width) * f64::from(height);
        let scale = (pixels / budget.max(1.0)).sqrt().ceil();
        (scale as u32).clamp(1, most)
    }

    /// The passes after an interactive one at 1/`scale`: a quarter of it
    /// (while that is coarser than full size), then full size.
    pub fn refine(scale: u32) -> Vec<u32> {
        let next = scale / 4;
        if next > 1 { vec![next, 1] } else { vec![1] }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scale_keeps_a_frame_within_its_budget() {
        let mut pace = Pace::default();
        assert_eq!(pace.interactive_scale(4000, 4000), 8, "unmeasured");
        // 1 µs a ray: 22 222 rays in two thirds of a frame; 4000×4000
        // needs 1/27 per side.
        pace.measured(1_000_000, Duration::from_secs(1));
        let s = pace.interactive_scale(4000, 4000);
        assert_eq!(s, 27);
        let rays = (4000 / s) * (4000 / s);
        assert!(f64::from(rays) * 1e-6 <= 1.0 / TARGET_FPS);
        // Cheap scenes render at full size; tiny images never go below
        // 8 pixels a side.
        pace.measured(1_000_000_000, Duration::from_millis(1));
        pace.measured(1_000_000_000, Duration::from_millis(1));
        assert_eq!(pace.interactive_scale(320, 240), 1);
        let mut slow = Pace::default();
        slow.measured(1, Duration::from_secs(1));
        assert_eq!(slow.interactive_scale(64, 48), 6);
    }

    #[test]
    fn refining_goes_to_full_size_in_at_most_two_passes() {
        assert_eq!(Pace::refine(27), vec![6, 1]);
        assert_eq!(Pace::refine(6), vec![1]);
        assert_eq!(Pace::refine(1), vec![1]);
    }
}
