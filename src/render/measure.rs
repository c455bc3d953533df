//! Measuring, written once for the bench, the study, the command line's
//! `-time` and the tests:
//!
//! - **Render time** ([`render_timed`]): from the request resolved for the
//!   scene (`auto`'s planning) through preparing and tracing to the last
//!   pixel, on a thread pool built before the clock starts ([`RenderPool`]).
//!   Loading the scene, encoding and writing the image are not in it. The
//!   app's progressive render ([`progressive_timed`]) is timed the same
//!   way, pass by pass, and its full picture from the request.
//! - **Rays**: the rays actually traced, primary and reflected
//!   ([`RenderStats::rays`]), never width × height × aa².
//! - The **median** of runs ([`median_of`]).
//! - How far an image is from a reference ([`Difference`]).
//! - **CSV** text: a header and rows, fields quoted where they must be
//!   ([`Csv`]).
//! - The **built-in scenes** the bench and the study measure
//!   ([`BuiltinScene`]; the lists are [`crate::study::bench::SCENES`] and
//!   [`crate::study::SCENES`]).

pub use crate::render::RenderPool;
use crate::render::request::RenderRequest;
use crate::render::{
    self, Cancel, KeptPass, LastPrepared, Pass, PassForm, PassImage, Progress, RenderError,
    RenderOptions, RenderStats, Step, Tile,
};
use crate::scene::{self, LoadError, Scene};
use image::RgbImage;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A scene file of `scenes/` built into the binary, so that `rayoflight
/// bench` and `rayoflight study` run from anywhere.
#[derive(Debug, Clone, Copy)]
pub struct BuiltinScene {
    pub name: &'static str,
    /// Where it is in the source tree (named in load errors).
    pub path: &'static str,
    pub text: &'static str,
}

/// `builtin!("bench", "room")`: `scenes/bench/room.xml`, built in.
#[macro_export]
#[doc(hidden)]
macro_rules! builtin {
    ($set:literal, $name:literal) => {
        $crate::render::measure::BuiltinScene {
            name: $name,
            path: concat!("scenes/", $set, "/", $name, ".xml"),
            text: include_str!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/scenes/",
                $set,
                "/",
                $name,
                ".xml"
            )),
        }
    };
}

impl BuiltinScene {
    pub fn scene(&self) -> Result<Scene, LoadError> {
        scene::parse(self.text, std::path::Path::new(self.path))
    }
}

/// A render (the image, or a [`PassImage`]) and how long it took.
#[derive(Debug, Clone)]
pub struct Timed<I = RgbImage> {
    pub image: I,
    pub stats: RenderStats,
    /// Render time, as the module docs define it.
    pub elapsed: Duration,
}

/// Renders `scene` as `request` asks on `pool`, counting pixels and rays
/// in `progress`, and times it: the one definition of render time.
/// `Ok(None)` once `cancel` is set.
pub fn render_timed(
    scene: &Scene,
    request: &RenderRequest,
    pool: &RenderPool,
    cancel: &Cancel,
    progress: &Progress,
) -> Result<Option<Timed>, RenderError> {
    timed(scene, request, pool, |options| {
        render::render_watched(scene, options, cancel, progress)
    })
}

/// Renders one pass of `scene` ([`render::render_pass`]) and times it as
/// [`render_timed`] does.
pub fn pass_timed(
    scene: &Scene,
    request: &RenderRequest,
    pass: Pass,
    pool: &RenderPool,
    cancel: &Cancel,
    progress: &Progress,
) -> Result<Option<Timed<PassImage>>, RenderError> {
    timed(scene, request, pool, |options| {
        render::render_pass(scene, options, pass, cancel, progress)
    })
}

/// Renders one pass of `scene` kept in the form of its file
/// ([`render::render_pass_as`]) and times it as [`render_timed`] does.
pub fn kept_pass_timed(
    scene: &Scene,
    request: &RenderRequest,
    pass: Pass,
    form: PassForm,
    pool: &RenderPool,
    cancel: &Cancel,
    progress: &Progress,
) -> Result<Option<Timed<KeptPass>>, RenderError> {
    timed(scene, request, pool, |options| {
        render::render_pass_as(scene, options, pass, form, cancel, progress)
    })
}

/// A pass of a progressive render ([`progressive_timed`]), timed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassTime {
    /// A pass at 1/`scale` of each side begins.
    Started { scale: u32 },
    /// That pass is done.
    Finished {
        scale: u32,
        /// Rays traced in this pass, primary and reflected.
        rays: u64,
        /// This pass alone.
        elapsed: Duration,
        /// From the request to the end of this pass (every pass so far):
        /// for the full-size pass, how long the full picture took.
        since_start: Duration,
        /// From the request to its first pass: resolving it and preparing
        /// the scene (next to nothing when the last preparation served).
        /// With `elapsed` of the full-size pass: render time.
        prepare: Duration,
    },
}

/// Renders `scene` as `request` asks coarse to fine in `passes`
/// ([`render::render_progressive`], preparing through `last`) on `pool`,
/// and times each pass: the app's render, measured as [`render_timed`]
/// measures one. `step` hears each pass begin and end (on the thread that
/// called this), `tile` gets each finished tile on a render thread.
/// `Ok(None)` once `cancel` is set.
// What a render reads and where its passes and tiles go, each one thing.
#[allow(clippy::too_many_arguments)]
pub fn progressive_timed(
    scene: &Arc<Scene>,
    request: &RenderRequest,
    passes: &[u32],
    last: &LastPrepared,
    pool: &RenderPool,
    cancel: &Cancel,
    step: &mut (dyn FnMut(PassTime) + Send),
    tile: &(dyn Fn(u32, &Tile, &[u8]) + Sync),
) -> Result<Option<()>, RenderError> {
    let start = Instant::now();
    let options = RenderOptions {
        // The pool is the caller's, built before the clock started.
        threads: None,
        ..request.options(scene)
    };
    let (mut prepare, mut pass_start) = (Duration::ZERO, start);
    pool.install(|| {
        render::render_progressive(
            scene,
            &options,
            passes,
            last,
            cancel,
            &mut |s| match s {
                Step::Prepared => prepare = start.elapsed(),
                Step::Started { scale } => {
                    pass_start = Instant::now();
                    step(PassTime::Started { scale });
                }
                Step::Finished { scale, rays } => step(PassTime::Finished {
                    scale,
                    rays,
                    elapsed: pass_start.elapsed(),
                    since_start: start.elapsed(),
                    prepare,
                }),
            },
            tile,
        )
    })
}

/// Times `render` with the request's options for `scene` on `pool`.
fn timed<I: Send>(
    scene: &Scene,
    request: &RenderRequest,
    pool: &RenderPool,
    render: impl FnOnce(&RenderOptions) -> Result<Option<(I, RenderStats)>, RenderError> + Send,
) -> Result<Option<Timed<I>>, RenderError> {
    let start = Instant::now();
    let options = RenderOptions {
        // The pool is the caller's, built before the clock started.
        threads: None,
        ..request.options(scene)
    };
    let done = pool.install(|| render(&options))?;
    Ok(done.map(|(image, stats)| Timed {
        image,
        stats,
        elapsed: start.elapsed(),
    }))
}

/// The median of `runs` (at least one) timings by `run`: the middle one,
/// the slower of the two middle ones for an even count.
pub fn median_of<E>(
    runs: usize,
    mut run: impl FnMut() -> Result<Duration, E>,
) -> Result<Duration, E> {
    let mut times = (0..runs.max(1))
        .map(|_| run())
        .collect::<Result<Vec<_>, _>>()?;
    times.sort();
    Ok(times[times.len() / 2])
}

/// How far an image is from a reference of the same size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Difference {
    /// The largest channel difference, in 8-bit levels.
    pub max: u8,
    /// The mean channel difference over every channel of every pixel.
    pub mean: f64,
    /// The share of pixels whose three channels are within one level.
    pub within1: f64,
}

impl Difference {
    pub fn between(image: &RgbImage, reference: &RgbImage) -> Difference {
        assert_eq!(
            image.dimensions(),
            reference.dimensions(),
            "images of one size"
        );
        let (mut max, mut sum, mut within) = (0u8, 0u64, 0u64);
        for (a, b) in image.pixels().zip(reference.pixels()) {
            let mut worst = 0;
            for c in 0..3 {
                let d = a[c].abs_diff(b[c]);
                worst = worst.max(d);
                sum += u64::from(d);
            }
            max = max.max(worst);
            within += u64::from(worst <= 1);
        }
        let pixels = u64::from(image.width()) * u64::from(image.height());
        let pixels = pixels.max(1) as f64;
        Difference {
            max,
            mean: sum as f64 / (3.0 * pixels),
            within1: within as f64 / pixels,
        }
    }
}

/// Per pixel, row by row, the largest channel difference between two
/// images of one size (for a map of where they differ).
pub fn pixel_differences(image: &RgbImage, reference: &RgbImage) -> Vec<u8> {
    assert_eq!(
        image.dimensions(),
        reference.dimensions(),
        "images of one size"
    );
    image
        .pixels()
        .zip(reference.pixels())
        .map(|(a, b)| (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0))
        .collect()
}

/// CSV text: a header line, then a line a row; a field holding a comma, a
/// quote or a line break is quoted, its other control characters
/// escaped ([`crate::system::escape::visible`]).
#[derive(Debug, Clone)]
pub struct Csv {
    text: String,
    columns: usize,
}

impl Csv {
    pub fn new(header: &[&str]) -> Csv {
        let mut csv = Csv {
            text: String::new(),
            columns: header.len(),
        };
        csv.push_line(header.iter().copied());
        csv
    }

    /// Adds a row of as many fields as the header has.
    pub fn row<S: AsRef<str>>(&mut self, fields: impl IntoIterator<Item = S>) {
        let fields: Vec<S> = fields.into_iter().collect();
        debug_assert_eq!(fields.len(), self.columns, "a field per column");
        self.push_line(fields.iter().map(AsRef::as_ref));
    }

    fn push_line<'a>(&mut self, fields: impl Iterator<Item = &'a str>) {
        for (k, field) in fields.enumerate() {
            if k > 0 {
                self.text.push(',');
            }
            // A name from outside: its controls shown, not obeyed by the
            // terminal a `cat` of the file drives.
            let field = crate::system::escape::visible(field, true);
            if field.contains([',', '"', '\n', '\r']) {
                self.text.push('"');
                self.text.push_str(&field.replace('"', "\"\""));
                self.text.push('"');
            } else {
                self.text.push_str(&field);
            }
        }
        self.text.push('\n');
    }

    pub fn text(&self) -> &str {
        &self.text
    }

    pub fn into_text(self) -> String {
        self.text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differences_count_levels() {
        let a = RgbImage::from_pixel(2, 2, image::Rgb([10, 10, 10]));
        let mut b = a.clone();
        b.put_pixel(0, 0, image::Rgb([11, 10, 10]));
        b.put_pixel(1, 1, image::Rgb([10, 14, 10]));
        let d = Difference::between(&a, &b);
        assert_eq!(d.max, 4);
        assert_eq!(d.within1, 0.75);
        assert!((d.mean - 5.0 / 12.0).abs() < 1e-12);
        assert_eq!(pixel_differences(&a, &b), vec![1, 0, 0, 4]);
    }

    #[test]
    fn the_median_is_the_middle_run() {
        let mut times = [5, 1, 9, 3].into_iter().map(Duration::from_millis);
        let median = median_of::<()>(4, || Ok(times.next().unwrap())).unwrap();
        assert_eq!(median, Duration::from_millis(5));
        assert_eq!(
            median_of::<()>(0, || Ok(Duration::from_millis(7))),
            Ok(Duration::from_millis(7))
        );
    }

    #[test]
    fn csv_fields_are_quoted_where_they_must_be() {
        let mut csv = Csv::new(&["scene", "ms"]);
        csv.row(["a,b", "1.5"]);
        csv.row(["say \"hi\"", "2"]);
        assert_eq!(csv.text(), "scene,ms\n\"a,b\",1.5\n\"say \"\"hi\"\"\",2\n");
    }

    #[test]
    fn render_time_is_measured_on_the_pool_given() {
        let scene = crate::scene::parse(crate::EXAMPLE_SCENE, std::path::Path::new("e.xml"))
            .expect("the example loads");
        let mut small = scene.clone();
        (small.camera.width, small.camera.height) = (32, 32);
        let pool = RenderPool::new(Some(1)).unwrap();
        let timed = render_timed(
            &small,
            &RenderRequest::default(),
            &pool,
            &Cancel::never(),
            &Progress::default(),
        )
        .unwrap()
        .unwrap();
        let plain = render::render(&small, &RenderRequest::default().options(&small)).unwrap();
        assert_eq!(timed.image, plain);
        assert!(timed.stats.rays >= 32 * 32);
        assert!(timed.elapsed > Duration::ZERO);
        assert!(RenderPool::new(Some(0)).is_err());
    }
}
