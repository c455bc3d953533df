//! Rendering: from a loaded [`Scene`] to an 8-bit image.
//!
//! [`prepare`] turns the scene into a [`Prepared`] scene (what tracing needs
//! and nothing more); [`render_tile`] traces one rectangle of pixels, checking
//! a [`Cancel`] token once per pixel; [`render`] does the whole image on a
//! rayon pool. [`RenderOptions`] holds every method choice; its default is
//! the contract's reference image.

mod camera;
mod prepared;
mod tile;

pub use camera::CameraRays;
pub use prepared::{Hit, Prepared, prepare};
pub use tile::{Cancel, TILE_SIZE, Tile, render_tile, tiles};

use crate::scene::Scene;
use image::RgbImage;
use rayon::prelude::*;

/// Largest `--aa` factor (N×N samples per pixel).
pub const MAX_AA: u32 = 16;

/// How to render. `RenderOptions::default()` is the contract's reference:
/// one ray through each pixel centre, f64 throughout.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RenderOptions {
    /// Worker threads; `None` uses rayon's global pool (one per core).
    pub threads: Option<usize>,
    /// Supersampling: `aa × aa` rays per pixel on a regular grid, 1 to
    /// [`MAX_AA`]. 1 is one ray through the pixel centre.
    pub aa: u32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            threads: None,
            aa: 1,
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
        if self.threads == Some(0) {
            return Err(RenderError::NoThreads);
        }
        Ok(())
    }
}

/// Prepares and renders the whole image. This is what `-time` measures.
pub fn render(scene: &Scene, options: &RenderOptions) -> Result<RgbImage, RenderError> {
    options.validate()?;
    match options.threads {
        None => Ok(render_all(scene, options)),
        Some(threads) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|source| RenderError::ThreadPool { threads, source })?;
            Ok(pool.install(|| render_all(scene, options)))
        }
    }
}

fn render_all(scene: &Scene, options: &RenderOptions) -> RgbImage {
    let prepared = prepare(scene, options);
    let (width, height) = (prepared.width(), prepared.height());
    let cancel = Cancel::never();
    let done: Vec<(Tile, Vec<u8>)> = tiles(width, height, TILE_SIZE)
        .into_par_iter()
        .filter_map(|t| render_tile(&prepared, &t, &cancel).map(|px| (t, px)))
        .collect();
    let mut image = RgbImage::new(width, height);
    for (t, pixels) in done {
        t.copy_into(&pixels, &mut image);
    }
    image
}

/// Clamps a channel to [0, 1] and rounds it to 8 bits: floor(c·255 + 0.5).
/// NaN becomes 0.
pub fn to_8bit(c: f64) -> u8 {
    if c > 0.0 {
        (c.min(1.0) * 255.0 + 0.5).floor() as u8
    } else {
        0
    }
}
