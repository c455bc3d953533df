//! Rendering: from a loaded [`Scene`] to an 8-bit image.
//!
//! [`prepare`] turns the scene into a [`Prepared`] scene (what tracing needs
//! and nothing more); [`trace_tiles`] is the one tile loop (bands of
//! tiles to the rayon pool's threads, their last tiles shared one at a
//! time, a [`Cancel`] token
//! checked once per pixel, counting [`Progress`]) that [`render`], the
//! app's worker and `--region` share: a region of the image is traced in
//! the whole image's tiles, so its pixels are the whole render's.
//! [`RenderOptions`] holds every method choice (and the [`region`] to
//! render: a rectangle of the image, what a cluster's part covers);
//! its default gives the reference image (docs/study.md). [`render_pass`]
//! renders one term of the formula (or the hit's normal, depth, object)
//! through the same tile loop; [`explain`] says why a pixel has its colour, from the
//! same trace. [`navigate`] moves the camera as a viewport does (orbit,
//! pan, dolly); [`object_ids`] says which object each pixel shows.
//! [`methods`] are the named ways to render (`auto`, `f32`, `aa4`, …) that
//! `--method`, the app's preview and the study choose among.
//! [`RenderPool`] is the one kind of thread pool renders run on, and
//! [`render_progressive`] the app's render: prepared once, traced coarse
//! to fine (1/8, 1/4, full) through the same tile loop.

mod auto;
mod camera;
pub mod explain;
mod facts;
mod ids;
pub mod measure;
mod method;
pub mod navigate;
mod observer;
mod pass;
mod pool;
mod prepared;
mod progress;
mod progressive;
pub mod region;
pub mod request;
mod tile;

pub use auto::{Decision, Plan, auto};
pub use camera::CameraRays;
pub use explain::Explanation;
pub use ids::{ObjectIds, object_ids};
pub use method::{Method, Options as MethodOptions, method, methods};
pub use pass::{
    KeptPass, Pass, PassForm, PassImage, PassPixels, Texel, f32_keeping_level, in_exr, in_f32,
    object_color, render_pass, render_pass_as, shown,
};
pub use pool::{RenderPool, all_cores};
pub use prepared::{Hit, Prepared, prepare};
pub use progress::{Progress, time_left};
pub use progressive::{LastPrepared, Step, passes, render_progressive};
pub use tile::{Cancel, TILE_SIZE, Tile};

use crate::geometry::{Ray, Real, Vector};
use crate::render::region::{Region, RegionError};
use crate::scene::Scene;
use crate::shading::{SurfacePoint, reflect};
use image::RgbImage;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

/// The most render threads a render may ask for: four per core, at most
/// 1024. More cannot go faster, and asking the system for a billion
/// threads would only spend minutes failing to start them.
pub fn max_threads() -> usize {
    (4 * all_cores()).min(1024)
}

/// Largest `--aa` factor (N×N samples per pixel).
pub const MAX_AA: u32 = 16;

/// Floating-point precision of the geometry (rays, intersections, hit
/// points, normals, reflected rays). Shading is always f64.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Precision {
    /// f64 throughout, as the reference method (docs/study.md) renders.
    #[default]
    F64,
    /// Rays and primitives in f32 (the study's "f32 everywhere").
    F32,
}

/// Which ray/sphere root formula.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SphereTest {
    /// The stable form (distance of the line to the centre, roots from q
    /// and c/q): the reference.
    #[default]
    Stable,
    /// The textbook (−b ± √(b² − 4ac)) / 2a, for the study.
    Textbook,
}

/// How far a reflected ray starts off the surface it leaves, along N.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Offset {
    /// ε = 1e-9 + 1e-12·|M| (world units): the reference method's offset
    /// (docs/study.md), the one that matches POV-Ray on every golden scene.
    #[default]
    Contract,
    /// A fixed ε in world units.
    Fixed(f64),
    /// No offset at all: the reflected ray starts on the surface (acne).
    None,
}

// The fixed ε is never NaN (the study's methods are constants).
impl Eq for Offset {}

impl Offset {
    /// The reflected ray R leaving hit point M along the mirror of V about
    /// N, from ε off the surface (see [`Offset`]), in the precision
    /// (and lanes) of the point.
    #[inline(always)]
    pub fn reflected<V: Vector>(self, point: &SurfacePoint<V>) -> Ray<V> {
        let SurfacePoint { m, n, v } = *point;
        let epsilon = match self {
            Offset::Contract => V::Real::from_f64(1e-9) + V::Real::from_f64(1e-12) * m.length(),
            Offset::Fixed(epsilon) => V::Real::from_f64(epsilon),
            Offset::None => V::Real::ZERO,
        };
        Ray::new(m + n.scaled(epsilon), reflect(n, v).normalize())
    }
}

/// How to render. `RenderOptions::default()` gives the reference image
/// (docs/study.md): one ray through each pixel centre, f64 throughout,
/// with every exact shortcut allowed; [`RenderOptions::reference`] is the
/// same image without shortcuts, and [`auto`](fn@auto) the options a given scene needs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RenderOptions {
    /// Worker threads; `None` uses rayon's global pool (one per core).
    pub threads: Option<usize>,
    /// Supersampling: `aa × aa` rays per pixel on a regular grid, 1 to
    /// [`MAX_AA`]. 1 is one ray through the pixel centre.
    pub aa: u32,
    /// End a whitted chain once the rest of it cannot change the pixel's
    /// 8-bit value (exact: the image is the same either way).
    pub early_stop: bool,
    /// Use the BVH and the per-tile culling of primary rays where the
    /// scene's object count pays for them (exact). `false`: every ray
    /// tests every object.
    pub accelerate: bool,
    /// Precision of the geometry.
    pub precision: Precision,
    /// Ray/sphere root formula.
    pub sphere: SphereTest,
    /// Offset of reflected rays off the surface.
    pub offset: Offset,
    /// Follow one reflection fewer than the scene's depth (whitted).
    pub depth_cut: bool,
    /// Trace one pixel in four (the top-left of each 2×2 block of the
    /// image, at even x and y) and copy it to the other three: a draft
    /// preview.
    pub draft: bool,
    /// Render only this rectangle of the image (`--region`); `None`: all
    /// of it. Not a method choice: each pixel is what the whole render
    /// gives it.
    pub region: Option<Region>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            threads: None,
            aa: 1,
            early_stop: true,
            accelerate: true,
            precision: Precision::F64,
            sphere: SphereTest::Stable,
            offset: Offset::Contract,
            depth_cut: false,
            draft: false,
            region: None,
        }
    }
}

impl RenderOptions {
    /// The reference method (docs/study.md) done plainly: every ray tests
    /// every object and every whitted chain runs to its depth. The
    /// study's `default` row; its image is the one every exact shortcut
    /// must reproduce.
    pub fn reference() -> Self {
        RenderOptions {
            early_stop: false,
            accelerate: false,
            ..RenderOptions::default()
        }
    }
}

/// Why a render could not run.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("anti-aliasing factor {0} is out of range (1 to {MAX_AA})")]
    AntiAliasing(u32),
    #[error("thread count must be at least 1")]
    NoThreads,
    #[error("{0} render threads is more than this machine can use (at most {max})", max = max_threads())]
    TooManyThreads(usize),
    #[error("--region {0}")]
    Region(#[from] RegionError),
    #[error("{what} {source}")]
    Memory {
        /// What the memory was for: `the 16384×16384 image`.
        what: String,
        source: crate::system::resources::NotEnoughMemory,
    },
    #[error("cannot start a thread to render on: {0}")]
    Thread(std::io::Error),
    #[error("cannot start {threads} render threads: {source}")]
    ThreadPool {
        threads: usize,
        source: rayon::ThreadPoolBuildError,
    },
}

impl RenderOptions {
    /// Checks the options before any work is done.
    pub fn validate(&self) -> Result<(), RenderError> {
        if !(1..=MAX_AA).contains(&self.aa) {
            return Err(RenderError::AntiAliasing(self.aa));
        }
        match self.threads {
            Some(0) => Err(RenderError::NoThreads),
            Some(n) if n > max_threads() => Err(RenderError::TooManyThreads(n)),
            _ => Ok(()),
        }
    }

    /// The pixels to render of `scene`'s image: the region asked for,
    /// checked to lie in the image, or the whole image.
    pub fn region_of(&self, scene: &Scene) -> Result<Region, RenderError> {
        let (width, height) = (scene.camera.width, scene.camera.height);
        match self.region {
            Some(region) => Ok(region.check_in(width, height)?),
            None => Ok(Region::whole(width, height)),
        }
    }
}

/// What a render did, beside the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RenderStats {
    /// Rays traced: primary and reflected. Tiles that can hit nothing are
    /// filled without tracing and count none.
    pub rays: u64,
}

/// Prepares and renders the whole image. This is what `-time` measures.
pub fn render(scene: &Scene, options: &RenderOptions) -> Result<RgbImage, RenderError> {
    render_with_stats(scene, options).map(|(image, _)| image)
}

/// Like [`render`], also counting the rays traced.
pub fn render_with_stats(
    scene: &Scene,
    options: &RenderOptions,
) -> Result<(RgbImage, RenderStats), RenderError> {
    let done = render_cancellable(scene, options, &Cancel::never())?;
    Ok(done.expect("a render that cannot be cancelled finishes"))
}

/// Like [`render_with_stats`], stopping within a pixel once `cancel` is
/// set: `Ok(None)`.
pub fn render_cancellable(
    scene: &Scene,
    options: &RenderOptions,
    cancel: &Cancel,
) -> Result<Option<(RgbImage, RenderStats)>, RenderError> {
    render_watched(scene, options, cancel, &Progress::default())
}

/// Like [`render_cancellable`], counting the pixels done in `progress` as
/// tiles finish.
pub fn render_watched(
    scene: &Scene,
    options: &RenderOptions,
    cancel: &Cancel,
    progress: &Progress,
) -> Result<Option<(RgbImage, RenderStats)>, RenderError> {
    let region = options.region_of(scene)?;
    in_pool(options, || {
        render_all(scene, options, region, cancel, progress)
    })?
}

/// Checks `options` and runs `work` in their thread pool (the current
/// one when they name no thread count).
fn in_pool<R: Send>(
    options: &RenderOptions,
    work: impl FnOnce() -> R + Send,
) -> Result<R, RenderError> {
    options.validate()?;
    Ok(RenderPool::new(options.threads)?.install(work))
}

/// Renders `region` of the scene's image: an image of the region's size.
fn render_all(
    scene: &Scene,
    options: &RenderOptions,
    region: Region,
    cancel: &Cancel,
    progress: &Progress,
) -> Result<Option<(RgbImage, RenderStats)>, RenderError> {
    let (width, height) = (region.width(), region.height());
    // Taken, not assumed: a size the system cannot give is an error.
    // Taken before preparing, which may start the thread pool: each of
    // its threads reserves a malloc arena (64 MiB of address space) as it
    // first allocates, and under `ulimit -v` the image asked for after
    // them may no longer fit where it fitted before them.
    let bytes = (width as usize)
        .saturating_mul(height as usize)
        .saturating_mul(3);
    let pixels =
        crate::system::resources::buffer::<u8>(bytes).map_err(|source| RenderError::Memory {
            what: format!("the {width}×{height} image"),
            source,
        })?;
    let mut image = RgbImage::from_raw(width, height, pixels).expect("3 bytes a pixel");
    let prepared = prepare(scene, options);
    let Some(rays) = trace_tiles(
        &prepared,
        region,
        cancel,
        progress,
        Some(&mut *image),
        |_, _| {},
    ) else {
        return Ok(None);
    };
    Ok(Some((image, RenderStats { rays })))
}

/// The tile loop every front end shares (the CLI's render, the study, the
/// app's worker, the passes, `--region`): `region` of the prepared view's
/// image (all of it, or a part) cut along the image's grid of
/// [`TILE_SIZE`] tiles, so that every pixel is traced as the whole render
/// traces it. Each thread of the current rayon pool takes a band (a row
/// of tiles) no other has begun and traces its tiles left to right, one
/// at a time; once every band is begun, a thread that is done helps with
/// the band that has the most tiles left, a tile at a time. So however
/// uneven the tiles' costs (mirrors beside floor) and however many the
/// threads, they finish within about one tile of each other, while the
/// threads mostly write rows of their own (no waiting on a band's lock, no
/// cache line written by two); each tile is traced whole (so it culls
/// once). Each finished tile (three texels a pixel, row-major: 8-bit
/// channels of the image, or f64 values of the prepared view's [`Pass`])
/// is copied into `image` when one is given (region-sized; into its band
/// of rows, whose lock is held for the copy only) and handed to
/// `finished` (on a render thread), and counted in `progress`. Returns the
/// rays traced, or `None` once `cancel` is set.
pub fn trace_tiles<T: Texel>(
    prepared: &Prepared,
    region: Region,
    cancel: &Cancel,
    progress: &Progress,
    image: Option<&mut [T]>,
    finished: impl Fn(&Tile, &[T]) + Sync,
) -> Option<u64> {
    debug_assert!(region.x1 <= prepared.width() && region.y1 <= prepared.height());
    progress.start(region.area());
    let row_bytes = region.width() as usize * 3;
    // The bands (the grid's rows of tiles) and columns, cut to the region.
    let bands: Vec<(u32, u32)> = grid_cuts(region.y0, region.y1).collect();
    let columns: Vec<(u32, u32)> = grid_cuts(region.x0, region.x1).collect();
    // Each band's rows of the image: the tiles of a band write disjoint
    // columns of the same rows, one copy at a time.
    let rows: Vec<Mutex<Option<&mut [T]>>> = match image {
        Some(mut image) => {
            debug_assert_eq!(image.len(), row_bytes * region.height() as usize);
            let mut rows = Vec::with_capacity(bands.len());
            for &(y0, y1) in &bands {
                let (band, rest) = image.split_at_mut(row_bytes * (y1 - y0) as usize);
                rows.push(Mutex::new(Some(band)));
                image = rest;
            }
            rows
        }
        None => bands.iter().map(|_| Mutex::new(None)).collect(),
    };
    let tiles = bands.len() * columns.len();
    // The next band no thread has begun, and each band's next tile.
    let next_band = AtomicUsize::new(0);
    let next_tile: Vec<Padded> = bands.iter().map(|_| Padded::default()).collect();
    let stopped = AtomicBool::new(false);
    // The tiles of band `b` that are left, one at a time, to `worker`'s
    // thread; false once the render is cancelled.
    let drain = |b: usize, pixels: &mut Vec<T>, rays: &mut u64| -> bool {
        let (y, y_end) = bands[b];
        loop {
            let c = next_tile[b].0.fetch_add(1, Ordering::Relaxed);
            if c >= columns.len() || stopped.load(Ordering::Relaxed) {
                return true;
            }
            let (x, x_end) = columns[c];
            let tile = Tile {
                x,
                y,
                width: x_end - x,
                height: y_end - y,
            };
            let Some(traced) = prepared.render_tile_into(&tile, cancel, pixels) else {
                stopped.store(true, Ordering::Relaxed);
                return false;
            };
            *rays += traced;
            progress.add(u64::from(tile.width) * u64::from(tile.height), traced);
            let mut band = rows[b].lock().unwrap_or_else(PoisonError::into_inner);
            if let Some(rows) = band.as_deref_mut() {
                let tile_row = tile.width as usize * 3;
                for (r, src) in pixels.chunks_exact(tile_row).enumerate() {
                    let start = r * row_bytes + (x - region.x0) as usize * 3;
                    rows[start..start + tile_row].copy_from_slice(src);
                }
            }
            drop(band);
            finished(&tile, pixels);
        }
    };
    // One worker a thread: it takes a band no one has begun and traces its
    // tiles left to right; once every band is begun, it helps with the
    // band that has the most tiles left, a tile at a time.
    let worker = |_| {
        let (mut pixels, mut rays) = (Vec::new(), 0);
        loop {
            let b = next_band.fetch_add(1, Ordering::Relaxed);
            let b = match b < bands.len() {
                true => b,
                false => {
                    let left = |b: &usize| {
                        columns
                            .len()
                            .saturating_sub(next_tile[*b].0.load(Ordering::Relaxed))
                    };
                    match (0..bands.len()).filter(|b| left(b) > 0).max_by_key(left) {
                        Some(b) => b,
                        None => return rays,
                    }
                }
            };
            if !drain(b, &mut pixels, &mut rays) {
                return rays;
            }
        }
    };
    let workers = rayon::current_num_threads().min(tiles);
    let rays: u64 = (0..workers).into_par_iter().map(worker).sum();
    (!stopped.load(Ordering::Relaxed)).then_some(rays)
}

/// The half-open spans of `start..end` that the image's tile grid (lines
/// at multiples of [`TILE_SIZE`]) cuts it into.
fn grid_cuts(start: u32, end: u32) -> impl Iterator<Item = (u32, u32)> {
    let mut at = start;
    std::iter::from_fn(move || {
        (at < end).then(|| {
            let next = ((at / TILE_SIZE + 1) * TILE_SIZE).min(end);
            let span = (at, next);
            at = next;
            span
        })
    })
}

/// A counter on a cache line of its own: the bands' counters are taken
/// by different threads at once.
#[derive(Default)]
#[repr(align(64))]
struct Padded(AtomicUsize);

/// Clamps a channel to [0, 1] and rounds it to 8 bits: floor(c·255 + 0.5).
/// NaN becomes 0.
#[inline]
pub fn to_8bit(c: f64) -> u8 {
    if c > 0.0 {
        // The value is in [0.5, 255.5], where truncation is floor (and
        // avoids a libm call on baseline x86-64).
        (c.min(1.0) * 255.0 + 0.5) as u8
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// However many threads take the tiles, and in whatever order they
    /// finish, the image and every region of it are the same bytes: the
    /// mirrors (uneven tiles), at a size that is not a whole number of
    /// tiles, on 1 to 64 threads.
    #[test]
    fn every_thread_count_gives_the_same_image_and_regions() {
        let text = include_str!("../../scenes/bench/mirrors.xml");
        let mut scene = crate::scene::parse(text, std::path::Path::new("mirrors.xml")).unwrap();
        (scene.camera.width, scene.camera.height) = (150, 101);
        let on = |threads: usize, options: &RenderOptions| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| render(&scene, options).unwrap())
        };
        let whole = on(1, &RenderOptions::default());
        let regions = [
            (0, 0, 150, 101),
            (31, 0, 97, 33),
            (5, 40, 6, 101),
            (64, 64, 150, 101),
        ];
        for threads in 1..=64 {
            assert!(
                on(threads, &RenderOptions::default()) == whole,
                "the image on {threads} threads"
            );
            if threads % 7 != 1 {
                continue;
            }
            for (x0, y0, x1, y1) in regions {
                let options = RenderOptions {
                    region: Some(Region::new(x0, y0, x1, y1).unwrap()),
                    ..RenderOptions::default()
                };
                let part = on(threads, &options);
                let crop = image::imageops::crop_imm(&whole, x0, y0, x1 - x0, y1 - y0).to_image();
                assert!(
                    part == crop,
                    "region {x0},{y0},{x1},{y1} on {threads} threads"
                );
            }
        }
    }

    #[test]
    fn the_grid_cuts_a_span_once_at_the_images_tile_lines() {
        for (start, end) in [(0, 1), (0, 64), (0, 65), (5, 33), (31, 32), (40, 200)] {
            let cuts: Vec<_> = grid_cuts(start, end).collect();
            assert_eq!(cuts.first().map(|c| c.0), Some(start));
            assert_eq!(cuts.last().map(|c| c.1), Some(end));
            for pair in cuts.windows(2) {
                assert_eq!(pair[0].1, pair[1].0, "{start}..{end}");
                assert_eq!(pair[0].1 % TILE_SIZE, 0, "{start}..{end}");
            }
            assert!(cuts.iter().all(|(a, b)| a < b && b - a <= TILE_SIZE));
        }
        assert_eq!(grid_cuts(7, 7).count(), 0);
    }
}
