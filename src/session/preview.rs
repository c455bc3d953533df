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
    /// A render was asked for and has not sent its first pixels yet (the
    /// scene is being prepared): the picture on screen is older.
    Waiting,
    Rendering {
        scale: u32,
        /// Pixels of the pass painted so far, and in all.
        pixels_done: u64,
        pixels_total: u64,
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
    /// The image was replaced by a black one of a new size since the last
    /// [`Preview::take_dirty`] (`dirty` then says what was painted on it).
    cleared: bool,
    /// Time of the last finished full-resolution pass.
    last_render: Option<(Duration, u64)>,
    /// Time from the request to the end of the first (coarsest) pass of the
    /// current render: how long until the picture first reacts.
    first_pass: Option<Duration>,
    /// When the pass now rendering started.
    pass_started: Option<Instant>,
    /// The picture of a coarse pass (1/scale of each side, scale at least
    /// [`COARSE`]) at its own size: shown stretched, so a coarse picture
    /// costs its few pixels rather than a full-size write and upload.
    coarse: Option<Coarse>,
}

/// Passes this coarse or coarser are kept at their own size.
pub const COARSE: u32 = 4;

/// A coarse pass's picture.
#[derive(Debug, Clone)]
pub struct Coarse {
    pub scale: u32,
    pub image: RgbImage,
    /// Changed since [`Preview::take_coarse_dirty`].
    dirty: bool,
}

impl Default for Preview {
    fn default() -> Self {
        Preview {
            image: RgbImage::new(1, 1),
            generation: 0,
            state: RenderState::Idle,
            dirty: Dirty::Whole,
            cleared: false,
            last_render: None,
            first_pass: None,
            pass_started: None,
            coarse: None,
        }
    }
}

impl Preview {
    pub fn image(&self) -> &RgbImage {
        &self.image
    }

    /// The render generation whose pixels are on screen (or arriving).
    pub fn generation(&self) -> u64 {
        self.generation
    }

    pub fn state(&self) -> &RenderState {
        &self.state
    }

    /// Duration and rays traced (primary and reflected) of the last complete render.
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
            pixels_done,
            pixels_total,
            ..
        } = self.state
        else {
            return None;
        };
        let fraction = (pixels_done as f64 / pixels_total.max(1) as f64) as f32;
        let elapsed = self.pass_started?.elapsed();
        let left = crate::render::time_left(elapsed, pixels_done, pixels_total);
        Some((fraction, left))
    }

    /// A newer render was asked for: until its first pass starts, the
    /// picture is of an older scene, and the state says so.
    pub fn requested(&mut self) {
        self.state = RenderState::Waiting;
    }

    /// The render in progress (or asked for) was cancelled: its late events
    /// are dropped (their generation is old) and the state says so.
    pub fn cancel(&mut self) {
        if matches!(
            self.state,
            RenderState::Rendering { .. } | RenderState::Waiting
        ) {
            self.state = RenderState::Cancelled;
        }
    }

    /// Whether a render has completed at least once.
    pub fn has_image(&self) -> bool {
        self.last_render.is_some() || self.generation != 0
    }

    /// The coarse picture to show instead of [`Preview::image`], if the
    /// newest pass is coarse.
    pub fn coarse(&self) -> Option<&Coarse> {
        self.coarse.as_ref()
    }

    /// True once after the coarse picture changed.
    pub fn take_coarse_dirty(&mut self) -> bool {
        self.coarse
            .as_mut()
            .is_some_and(|c| std::mem::take(&mut c.dirty))
    }

    /// What changed since the last call, the texture uploads only that:
    /// whether the image was replaced by a black one of a new size, and
    /// what was painted (on it).
    pub fn take_dirty(&mut self) -> (bool, Dirty) {
        (
            std::mem::take(&mut self.cleared),
            std::mem::take(&mut self.dirty),
        )
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
                    self.dirty = Dirty::Nothing;
                    self.cleared = true;
                }
                if scale >= COARSE {
                    let size = (width.div_ceil(scale), height.div_ceil(scale));
                    if self
                        .coarse
                        .as_ref()
                        .is_none_or(|c| c.scale != scale || c.image.dimensions() != size)
                    {
                        self.coarse = Some(Coarse {
                            scale,
                            image: RgbImage::new(size.0, size.1),
                            dirty: true,
                        });
                    }
                } else if let Some(coarse) = self.coarse.take() {
                    // A finer pass paints over the coarse picture, which
                    // shows through until it is done: write it once at
                    // full size.
                    blow_up(&mut self.image, 0, 0, coarse.scale, &coarse.image);
                    self.dirty = Dirty::Whole;
                }
                let pixels_total =
                    u64::from(width.div_ceil(scale)) * u64::from(height.div_ceil(scale));
                self.pass_started = Some(Instant::now());
                self.state = RenderState::Rendering {
                    scale,
                    pixels_done: 0,
                    pixels_total,
                };
            }
            Event::Tile {
                scale,
                tile,
                pixels,
                ..
            } => {
                match &mut self.coarse {
                    Some(coarse) if coarse.scale == scale => coarse.paint(&tile, pixels),
                    _ => self.paint(scale, &tile, pixels),
                }
                if let RenderState::Rendering { pixels_done, .. } = &mut self.state {
                    *pixels_done += u64::from(tile.width) * u64::from(tile.height);
                }
            }
            Event::PassFinished {
                scale,
                elapsed,
                since_start,
                prepare,
                rays,
                ..
            } => {
                self.first_pass.get_or_insert(since_start);
                if scale == 1 {
                    // Render time: the request resolved, the scene
                    // prepared, the full-size pass traced (the coarse
                    // passes are previews, not part of the picture's cost).
                    let elapsed = prepare + elapsed;
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
    fn paint(&mut self, scale: u32, tile: &crate::render::Tile, pixels: Vec<u8>) {
        let (width, height) = self.image.dimensions();
        let x = (tile.x * scale).min(width);
        let y = (tile.y * scale).min(height);
        let Some(pixels) = RgbImage::from_raw(tile.width, tile.height, pixels) else {
            return;
        };
        blow_up(&mut self.image, x, y, scale, &pixels);
        self.dirty.add(Region {
            x,
            y,
            width: (tile.width * scale).min(width - x),
            height: (tile.height * scale).min(height - y),
        });
    }
}

/// Writes `small` into `image` at (`x`, `y`), each of its pixels as a block
/// of `scale × scale`, cut at the image's edges: one row built, then copied.
fn blow_up(image: &mut RgbImage, x: u32, y: u32, scale: u32, small: &RgbImage) {
    let (width, height) = image.dimensions();
    if x >= width || y >= height {
        return;
    }
    let scale = scale.max(1) as usize;
    let span = ((width - x) as usize).min(small.width() as usize * scale);
    let stride = width as usize * 3;
    let raw: &mut [u8] = image;
    let mut line = Vec::with_capacity(span * 3);
    for (row, pixels) in small.rows().enumerate() {
        line.clear();
        for p in pixels {
            for _ in 0..scale {
                line.extend_from_slice(&p.0);
            }
        }
        line.truncate(span * 3);
        let top = y as usize + row * scale;
        for out in top..(top + scale).min(height as usize) {
            let start = out * stride + x as usize * 3;
            raw[start..start + line.len()].copy_from_slice(&line);
        }
    }
}

impl Coarse {
    /// Copies a tile's rows into the coarse picture.
    fn paint(&mut self, tile: &crate::render::Tile, pixels: Vec<u8>) {
        if let Some(pixels) = RgbImage::from_raw(tile.width, tile.height, pixels) {
            blow_up(&mut self.image, tile.x, tile.y, 1, &pixels);
            self.dirty = true;
        }
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

/// What of the image changed since the window last took it (the window
/// uploads only that to its texture).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum Dirty {
    #[default]
    Nothing,
    /// These tiles: only they are uploaded (a 4000×4000 image is 48 MB; a
    /// tile is 3 KB to 50 KB).
    Regions(Vec<Region>),
    /// Everything (a new size, or a coarse picture written at full size).
    Whole,
}

impl Region {
    pub fn area(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }

    /// The smallest region holding both.
    fn union(self, other: Region) -> Region {
        let x = self.x.min(other.x);
        let y = self.y.min(other.y);
        let right = (self.x + self.width).max(other.x + other.width);
        let bottom = (self.y + self.height).max(other.y + other.height);
        Region {
            x,
            y,
            width: right - x,
            height: bottom - y,
        }
    }
}

impl Dirty {
    /// Past this many regions in one frame, a new one joins the region it
    /// grows least (tiles come in bands: neighbours join into a band, and
    /// a band at the top never joins one at the bottom into the whole
    /// image).
    const MAX_REGIONS: usize = 64;

    pub fn add(&mut self, region: Region) {
        if region.width == 0 || region.height == 0 {
            return;
        }
        match self {
            Dirty::Whole => {}
            Dirty::Nothing => *self = Dirty::Regions(vec![region]),
            Dirty::Regions(list) if list.len() >= Dirty::MAX_REGIONS => {
                let growth = |r: &Region| r.union(region).area() - r.area();
                if let Some(nearest) = list.iter_mut().min_by_key(|r| growth(r)) {
                    *nearest = nearest.union(region);
                }
            }
            Dirty::Regions(list) => list.push(region),
        }
    }

    /// Pixels to upload.
    pub fn area(&self, whole: u64) -> u64 {
        match self {
            Dirty::Nothing => 0,
            Dirty::Regions(list) => list.iter().map(Region::area).sum(),
            Dirty::Whole => whole,
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
    fn render_time_is_the_request_prepared_and_the_full_pass() {
        let mut p = Preview::default();
        let finished = |scale, elapsed| Event::PassFinished {
            generation: 1,
            scale,
            elapsed: Duration::from_millis(elapsed),
            since_start: Duration::from_millis(100),
            prepare: Duration::from_millis(30),
            rays: 1000,
        };
        p.apply(1, finished(4, 5));
        assert_eq!(p.last_render(), None, "a coarse pass is a preview");
        p.apply(1, finished(1, 50));
        assert_eq!(p.last_render(), Some((Duration::from_millis(80), 1000)));
    }

    #[test]
    fn coarse_passes_stay_small_until_a_finer_one_starts() {
        let mut p = Preview::default();
        let start = |scale| Event::PassStarted {
            generation: 1,
            scale,
            width: 100,
            height: 60,
        };
        p.apply(1, start(8));
        let _ = p.take_dirty();
        p.apply(1, tile(0, 0, 13, 8, 8));
        let coarse = p.coarse().expect("a coarse picture");
        assert_eq!(coarse.image.dimensions(), (13, 8));
        assert_eq!(coarse.image.get_pixel(12, 7).0, [200, 200, 200]);
        assert!(p.take_coarse_dirty());
        assert_eq!(
            p.take_dirty(),
            (false, Dirty::Nothing),
            "the full image untouched"
        );
        // A finer pass: the coarse picture, written once at full size.
        p.apply(1, start(2));
        assert!(p.coarse().is_none());
        assert_eq!(p.take_dirty(), (false, Dirty::Whole));
        assert_eq!(p.image().get_pixel(99, 59).0, [200, 200, 200]);
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
        assert_eq!(p.take_dirty(), (true, Dirty::Nothing), "a new size, black");
        assert_eq!(p.take_dirty(), (false, Dirty::Nothing));
        // A tile of the half-resolution pass covers twice its size, cut at
        // the image's edge.
        p.apply(1, tile(40, 20, 16, 16, 2));
        assert_eq!(
            p.take_dirty().1,
            Dirty::Regions(vec![Region {
                x: 80,
                y: 40,
                width: 20,
                height: 20
            }])
        );
        assert_eq!(p.image().get_pixel(99, 59).0, [200, 200, 200]);
        // Many tiles at once: past 64 regions, each joins its neighbours.
        for k in 0..200 {
            p.apply(1, tile(k % 50, k / 50, 1, 1, 2));
        }
        let dirty = p.take_dirty().1;
        let Dirty::Regions(regions) = &dirty else {
            panic!("regions")
        };
        assert_eq!(regions.len(), 64);
        // Tiles 0 to 199 cover rows 0 to 7 of the image, 100 wide.
        assert!(dirty.area(0) <= 100 * 8, "{regions:?}");
    }
}
