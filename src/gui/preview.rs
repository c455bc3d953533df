//! The image on screen, assembled from the worker's tiles.
//!
//! Holds the full-size picture and keeps the last good one until new pixels
//! replace it: a coarse pass paints blocks of `scale × scale` pixels, the
//! full pass exact pixels. Events of any generation but the newest are
//! dropped, so a stale render can never paint over a newer one.

use super::worker::Event;
use image::RgbImage;
use std::time::{Duration, Instant};

/// What the renderer is doing, for the status bar.
#[derive(Debug, Clone, PartialEq)]
pub enum RenderState {
    Idle,
    Rendering {
        scale: u32,
        tiles_done: usize,
        tiles_total: usize,
    },
    Done {
        elapsed: Duration,
        rays: u64,
    },
    Failed(String),
    /// Stopped by the user (Esc) before it finished.
    Cancelled,
}

#[derive(Debug, Clone)]
pub struct Preview {
    image: RgbImage,
    /// Generation whose pixels are arriving.
    generation: u64,
    state: RenderState,
    /// What changed since the last [`Preview::take_dirty`].
    dirty: Dirty,
    /// Time of the last finished full-resolution pass.
    last_render: Option<(Duration, u64)>,
    /// Time from the request to the end of the first (coarsest) pass of the
    /// current render: how long until the picture first reacts.
    first_pass: Option<Duration>,
    /// When the pass now rendering started.
    pass_started: Option<Instant>,
}

impl Default for Preview {
    fn default() -> Self {
        Preview {
            image: RgbImage::new(1, 1),
            generation: 0,
            state: RenderState::Idle,
            dirty: Dirty::Whole,
            last_render: None,
            first_pass: None,
            pass_started: None,
        }
    }
}

impl Preview {
    pub fn image(&self) -> &RgbImage {
        &self.image
    }

    pub fn state(&self) -> &RenderState {
        &self.state
    }

    /// Duration and primary rays of the last complete render.
    pub fn last_render(&self) -> Option<(Duration, u64)> {
        self.last_render
    }

    /// Time from the request to the first pass's last pixel, for the
    /// current render.
    pub fn first_pass(&self) -> Option<Duration> {
        self.first_pass
    }

    /// The pass in progress: its fraction done, and when it has run for a
    /// second or more, the time it has left at its pace so far.
    pub fn progress(&self) -> Option<(f32, Option<Duration>)> {
        let RenderState::Rendering {
            tiles_done,
            tiles_total,
            ..
        } = self.state
        else {
            return None;
        };
        let fraction = tiles_done as f32 / tiles_total.max(1) as f32;
        let elapsed = self.pass_started?.elapsed();
        let left = (elapsed >= Duration::from_secs(1) && tiles_done > 0).then(|| {
            elapsed.mul_f64((tiles_total - tiles_done.min(tiles_total)) as f64 / tiles_done as f64)
        });
        Some((fraction, left))
    }

    /// The render in progress was cancelled: its late events are dropped
    /// (their generation is old) and the state says so.
    pub fn cancel(&mut self) {
        if matches!(self.state, RenderState::Rendering { .. }) {
            self.state = RenderState::Cancelled;
        }
    }

    /// Whether a render has completed at least once.
    pub fn has_image(&self) -> bool {
        self.last_render.is_some() || self.generation != 0
    }

    /// What changed since the last call: the texture uploads only that.
    pub fn take_dirty(&mut self) -> Dirty {
        std::mem::take(&mut self.dirty)
    }

    /// Applies a worker event; `newest` is the newest generation requested.
    /// Returns false when the event was stale and dropped.
    pub fn apply(&mut self, newest: u64, event: Event) -> bool {
        if event.generation() != newest {
            return false;
        }
        match event {
            Event::PassStarted {
                generation,
                scale,
                width,
                height,
            } => {
                if generation != self.generation {
                    self.first_pass = None;
                }
                self.generation = generation;
                if self.image.dimensions() != (width, height) {
                    self.image = RgbImage::new(width, height);
                    self.dirty = Dirty::Whole;
                }
                let tiles_total = crate::render::tiles(
                    width.div_ceil(scale),
                    height.div_ceil(scale),
                    crate::render::TILE_SIZE,
                )
                .len();
                self.pass_started = Some(Instant::now());
                self.state = RenderState::Rendering {
                    scale,
                    tiles_done: 0,
                    tiles_total,
                };
            }
            Event::Tile {
                scale,
                tile,
                pixels,
                ..
            } => {
                self.paint(scale, &tile, &pixels);
                if let RenderState::Rendering { tiles_done, .. } = &mut self.state {
                    *tiles_done += 1;
                }
            }
            Event::PassFinished {
                scale,
                elapsed,
                since_start,
                rays,
                ..
            } => {
                self.first_pass.get_or_insert(since_start);
                if scale == 1 {
                    self.state = RenderState::Done { elapsed, rays };
                    self.last_render = Some((elapsed, rays));
                }
            }
            Event::Failed { message, .. } => self.state = RenderState::Failed(message),
            // The study's events belong to the study window.
            Event::StudyStarted { .. }
            | Event::StudyRow { .. }
            | Event::StudyFinished { .. }
            | Event::StudyStopped { .. } => return false,
        }
        true
    }

    /// Paints a tile of a pass at 1/`scale` resolution into the full image.
    fn paint(&mut self, scale: u32, tile: &crate::render::Tile, pixels: &[u8]) {
        let (width, height) = self.image.dimensions();
        let x = (tile.x * scale).min(width);
        let y = (tile.y * scale).min(height);
        let region = Region {
            x,
            y,
            width: (tile.width * scale).min(width - x),
            height: (tile.height * scale).min(height - y),
        };
        let row_bytes = tile.width as usize * 3;
        for (row, line) in pixels.chunks_exact(row_bytes).enumerate() {
            let y0 = (tile.y + row as u32) * scale;
            for (col, rgb) in line.chunks_exact(3).enumerate() {
                let x0 = (tile.x + col as u32) * scale;
                let color = image::Rgb([rgb[0], rgb[1], rgb[2]]);
                for y in y0..(y0 + scale).min(height) {
                    for x in x0..(x0 + scale).min(width) {
                        self.image.put_pixel(x, y, color);
                    }
                }
            }
        }
        self.dirty.add(region);
    }
}

/// A rectangle of the image, in pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Region {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// What of the image changed since the texture was last uploaded.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum Dirty {
    #[default]
    Nothing,
    /// These tiles: only they are uploaded (a 4000×4000 image is 48 MB; a
    /// tile is 3 KB to 50 KB).
    Regions(Vec<Region>),
    /// Everything (a new size).
    Whole,
}

impl Dirty {
    /// More regions than this are uploaded as the whole image.
    const MAX_REGIONS: usize = 256;

    fn add(&mut self, region: Region) {
        if region.width == 0 || region.height == 0 {
            return;
        }
        match self {
            Dirty::Whole => {}
            Dirty::Nothing => *self = Dirty::Regions(vec![region]),
            Dirty::Regions(list) if list.len() >= Dirty::MAX_REGIONS => *self = Dirty::Whole,
            Dirty::Regions(list) => list.push(region),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Tile;

    fn tile(x: u32, y: u32, width: u32, height: u32, scale: u32) -> Event {
        Event::Tile {
            generation: 1,
            scale,
            tile: Tile {
                x,
                y,
                width,
                height,
            },
            pixels: vec![200; (width * height * 3) as usize],
        }
    }

    #[test]
    fn only_the_tiles_painted_are_uploaded() {
        let mut p = Preview::default();
        let start = Event::PassStarted {
            generation: 1,
            scale: 2,
            width: 100,
            height: 60,
        };
        assert!(p.apply(1, start));
        assert_eq!(p.take_dirty(), Dirty::Whole, "a new size");
        assert_eq!(p.take_dirty(), Dirty::Nothing);
        // A tile of the half-resolution pass covers twice its size, cut at
        // the image's edge.
        p.apply(1, tile(40, 20, 16, 16, 2));
        assert_eq!(
            p.take_dirty(),
            Dirty::Regions(vec![Region {
                x: 80,
                y: 40,
                width: 20,
                height: 20
            }])
        );
        assert_eq!(p.image().get_pixel(99, 59).0, [200, 200, 200]);
        // Many tiles at once: the whole image in one upload.
        for k in 0..300 {
            p.apply(1, tile(k % 50, 0, 1, 1, 2));
        }
        assert_eq!(p.take_dirty(), Dirty::Whole);
    }
}
