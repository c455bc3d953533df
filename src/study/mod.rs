//! The study: speed against accuracy. Every [`Method`] (a [`RenderOptions`]
//! variant, from [`render::methods`]) renders every study scene; each render is timed and compared
//! with the scene's reference image, and the result is a [`Row`].
//!
//! The reference is the default method's image (its agreement with
//! POV-Ray is tested elsewhere); for the anti-aliasing methods it is the
//! default method supersampled 16×16, so that anti-aliasing shows as more
//! accurate, and slower. A method *fails* on a scene when fewer than 99 %
//! of the pixels are within one 8-bit level of the reference.
//!
//! The built-in scenes are those of `scenes/study/`, compiled into the
//! binary; the command line prints and writes files, this module does not.
//! [`chart`] draws the study's pictures (the chart, the failure pictures).
//! Everything is measured one way ([`crate::render::measure`](mod@crate::render::measure));
//! [`bench`](mod@bench) holds the benchmark scenes.

pub mod bench;
pub mod chart;

use crate::render::measure::{
    BuiltinScene, Csv, Difference, RenderPool, Timed, median_of, render_timed,
};
use crate::render::{self, Cancel, MAX_AA, Method, Progress, RenderError, RenderOptions};
use crate::scene::{self, LoadError, Scene};
use image::RgbImage;
use std::path::Path;
use std::time::Duration;

/// Why a study stopped.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error("the study was cancelled")]
    Cancelled,
    /// A scene too large for the memory left.
    #[error("{scene}: the study at {width}×{height} {source}")]
    Memory {
        scene: String,
        width: u32,
        height: u32,
        source: crate::system::resources::NotEnoughMemory,
    },
}

/// Refuses a scene whose study needs more memory than the system gives
/// ([`bytes_for_scene`]): asked before the first ray, a one-line refusal,
/// not an abort when a failure's picture is drawn.
pub fn check_memory(scene: &StudyScene) -> Result<(), StudyError> {
    let (width, height) = (scene.scene.camera.width, scene.scene.camera.height);
    crate::system::resources::check_memory(bytes_for_scene(width, height)).map_err(|source| {
        StudyError::Memory {
            scene: scene.name.clone(),
            width,
            height,
            source,
        }
    })
}

/// Bytes the study holds for a scene of `width × height` pixels at once:
/// its two references, a method's image, and the picture of a failure
/// (three images side by side), 8-bit RGB each.
pub fn bytes_for_scene(width: u32, height: u32) -> u64 {
    let image = 3 * u64::from(width) * u64::from(height);
    (2 + 1 + 3) * image
}

/// Renders on `pool` (the study's, built once), or says the study was
/// cancelled.
fn render_or_stop(
    scene: &Scene,
    options: &RenderOptions,
    pool: &RenderPool,
    cancel: &Cancel,
    progress: &Progress,
) -> Result<RgbImage, StudyError> {
    let options = RenderOptions {
        // The pool's threads.
        threads: None,
        ..options.clone()
    };
    let done = pool.install(|| render::render_watched(scene, &options, cancel, progress))?;
    Ok(done.ok_or(StudyError::Cancelled)?.0)
}

/// Where a study is, for a window to show while it runs (a reference of
/// a large scene, or a slow method, takes a minute): which render, and
/// that render's pixels.
#[derive(Debug, Default)]
pub struct StudyProgress {
    stage: std::sync::Mutex<Stage>,
    /// The pixels of the render under way (counted again from 0 by each).
    pub render: Progress,
}

/// Which render of a study is under way.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Stage {
    /// Not started.
    #[default]
    Waiting,
    /// A scene's reference image: the default method's, or the one
    /// supersampled 16×16.
    Reference { supersampled: bool },
    /// The `index`-th method (from 0) of `of`, at its `run`-th render
    /// (from 0) of `runs` (the time is their median).
    Method {
        index: usize,
        of: usize,
        name: &'static str,
        run: usize,
        runs: usize,
    },
}

impl StudyProgress {
    pub fn stage(&self) -> Stage {
        *self
            .stage
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    fn set(&self, stage: Stage) {
        *self
            .stage
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner) = stage;
    }

    /// A method's `run`-th render begins (a reference's stage kept).
    fn set_run(&self, run: usize) {
        let mut stage = self
            .stage
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Stage::Method { run: now, .. } = &mut *stage {
            *now = run;
        }
    }
}

/// A scene of the study and the name its rows carry.
#[derive(Debug, Clone)]
pub struct StudyScene {
    pub name: String,
    pub scene: Scene,
}

/// The built-in study scenes (`scenes/study/`), in the order reported.
pub const SCENES: [BuiltinScene; 10] = [
    crate::builtin!("study", "example"),
    crate::builtin!("study", "example-1e3"),
    crate::builtin!("study", "example-1e5"),
    crate::builtin!("study", "example-1e7"),
    crate::builtin!("study", "grazing-plane"),
    crate::builtin!("study", "tiny-on-huge"),
    crate::builtin!("study", "tiny-far"),
    crate::builtin!("study", "mirror-corridor"),
    crate::builtin!("study", "inside-sphere"),
    crate::builtin!("study", "many-spheres"),
];

/// Parses the built-in study scenes.
pub fn builtin_scenes() -> Result<Vec<StudyScene>, LoadError> {
    SCENES
        .iter()
        .map(|builtin| {
            Ok(StudyScene {
                name: builtin.name.to_owned(),
                scene: builtin.scene()?,
            })
        })
        .collect()
}

/// Loads user scene files; each is named by its file stem.
pub fn load_scenes<P: AsRef<Path>>(paths: &[P]) -> Result<Vec<StudyScene>, LoadError> {
    paths
        .iter()
        .map(|path| {
            let path = path.as_ref();
            Ok(StudyScene {
                name: path.file_stem().map_or_else(
                    || path.display().to_string(),
                    |s| s.to_string_lossy().into_owned(),
                ),
                scene: scene::load(path)?,
            })
        })
        .collect()
}

/// The reference images of one scene.
#[derive(Debug, Clone)]
pub struct References {
    /// The default method's image ([`RenderOptions::reference`]).
    pub default: RgbImage,
    /// The default image supersampled [`MAX_AA`]×[`MAX_AA`]: the
    /// reference of the anti-aliasing methods. Rendered only when asked,
    /// on the exact fast path (256 plain renders would dominate the study;
    /// the fast path's image is the plain one, see tests/render/exact_shortcuts.rs).
    pub supersampled: Option<RgbImage>,
}

impl References {
    /// Renders the references `methods` need on `pool` (the one the
    /// methods are timed on), unless cancelled.
    pub fn new(
        scene: &Scene,
        methods: &[Method],
        pool: &RenderPool,
        cancel: &Cancel,
        progress: &StudyProgress,
    ) -> Result<References, StudyError> {
        progress.set(Stage::Reference {
            supersampled: false,
        });
        let options = RenderOptions::reference();
        let default = render_or_stop(scene, &options, pool, cancel, &progress.render)?;
        let supersampled = if methods.iter().any(Method::supersamples) {
            let options = RenderOptions {
                aa: MAX_AA,
                ..RenderOptions::default()
            };
            progress.set(Stage::Reference { supersampled: true });
            Some(render_or_stop(
                scene,
                &options,
                pool,
                cancel,
                &progress.render,
            )?)
        } else {
            None
        };
        Ok(References {
            default,
            supersampled,
        })
    }

    /// The image `method` is measured against.
    pub fn for_method(&self, method: &Method) -> &RgbImage {
        match &self.supersampled {
            Some(image) if method.supersamples() => image,
            _ => &self.default,
        }
    }
}

/// One scene and method: a CSV row.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub scene: String,
    pub method: &'static str,
    /// Median render time (prepare and trace) over the runs.
    pub time: Duration,
    /// Rays traced by one render.
    pub rays: u64,
    /// Largest difference of one channel from the reference, in levels.
    pub max_diff: u8,
    /// Mean difference over every channel of every pixel, in levels.
    pub mean_diff: f64,
    /// Share of pixels whose three channels are within one level.
    pub within1: f64,
    /// `within1 < 0.99`.
    pub failed: bool,
}

/// The share of pixels within one level below which a method fails.
pub const FAIL_BELOW: f64 = 0.99;

/// Renders `scene` with `method` `runs` times (at least once) and measures
/// it against `reference`: the median time, the rays, the error.
pub fn measure(
    scene: &StudyScene,
    method: &Method,
    reference: &RgbImage,
    runs: usize,
) -> Result<Row, StudyError> {
    let pool = RenderPool::new(None)?;
    let watch = StudyProgress::default();
    measure_image(
        scene,
        method,
        reference,
        runs,
        &pool,
        &Cancel::never(),
        &watch,
    )
    .map(|(row, _)| row)
}

/// [`measure()`] on `pool`, and the image the method rendered (its first
/// run), unless cancelled; each run said in `watch` (where its stage is
/// this method) and its pixels counted in `watch.render`. The time is render time as [`crate::render::measure`](mod@crate::render::measure)
/// defines it (`auto`'s planning included), as the command line renders
/// with `--method`.
fn measure_image(
    scene: &StudyScene,
    method: &Method,
    reference: &RgbImage,
    runs: usize,
    pool: &RenderPool,
    cancel: &Cancel,
    watch: &StudyProgress,
) -> Result<(Row, RgbImage), StudyError> {
    let request = crate::render::request::RenderRequest {
        method: Some(method.clone()),
        ..Default::default()
    };
    let mut first = None;
    let mut run = 0;
    let time = median_of(runs, || {
        watch.set_run(run);
        run += 1;
        let timed = render_timed(&scene.scene, &request, pool, cancel, &watch.render)?
            .ok_or(StudyError::Cancelled)?;
        let elapsed = timed.elapsed;
        first.get_or_insert(timed);
        Ok::<_, StudyError>(elapsed)
    })?;
    let Timed { image, stats, .. } = first.ok_or(StudyError::Cancelled)?;
    let difference = Difference::between(&image, reference);
    let row = Row {
        scene: scene.name.clone(),
        method: method.name,
        time,
        rays: stats.rays,
        max_diff: difference.max,
        mean_diff: difference.mean,
        within1: difference.within1,
        failed: difference.within1 < FAIL_BELOW,
    };
    Ok((row, image))
}

/// Runs every method on every scene, `runs` renders each, with `threads`
/// threads (`None`: one per core, or the pool it runs in), stopping within
/// a pixel once `cancel` is set; `progress` sees each row as it is done,
/// with the method's image and the reference it was measured against (to
/// picture a failure); `watch` says which render is under way and how far.
pub fn run(
    scenes: &[StudyScene],
    methods: &[Method],
    runs: usize,
    threads: Option<usize>,
    cancel: &Cancel,
    watch: &StudyProgress,
    progress: &mut dyn FnMut(&Row, &RgbImage, &RgbImage),
) -> Result<Vec<Row>, StudyError> {
    let mut rows = Vec::new();
    let pool = RenderPool::new(threads)?;
    for scene in scenes {
        check_memory(scene)?;
        let references = References::new(&scene.scene, methods, &pool, cancel, watch)?;
        for (index, method) in methods.iter().enumerate() {
            watch.set(Stage::Method {
                index,
                of: methods.len(),
                name: method.name,
                run: 0,
                runs: runs.max(1),
            });
            let reference = references.for_method(method);
            let (row, image) = measure_image(scene, method, reference, runs, &pool, cancel, watch)?;
            progress(&row, &image, reference);
            rows.push(row);
        }
    }
    Ok(rows)
}

/// The CSV header line (no newline).
pub const CSV_HEADER: &str = "scene,method,time_ms,rays,max_diff,mean_diff,within1,failed";

/// The rows as CSV text, header first.
pub fn csv(rows: &[Row]) -> String {
    let mut csv = Csv::new(&CSV_HEADER.split(',').collect::<Vec<_>>());
    for r in rows {
        csv.row([
            r.scene.clone(),
            r.method.to_owned(),
            format!("{:.3}", r.time.as_secs_f64() * 1e3),
            r.rays.to_string(),
            r.max_diff.to_string(),
            format!("{:.4}", r.mean_diff),
            format!("{:.6}", r.within1),
            r.failed.to_string(),
        ]);
    }
    csv.into_text()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_study_scene_loads_and_is_small() {
        for s in builtin_scenes().unwrap() {
            let c = &s.scene.camera;
            assert!(c.width <= 320 && c.height <= 240, "{}", s.name);
        }
    }

    #[test]
    fn csv_quotes_odd_names() {
        let row = Row {
            scene: "a,b".into(),
            method: "default",
            time: Duration::from_millis(2),
            rays: 5,
            max_diff: 0,
            mean_diff: 0.0,
            within1: 1.0,
            failed: false,
        };
        let text = csv(&[row]);
        assert_eq!(
            text,
            format!("{CSV_HEADER}\n\"a,b\",default,2.000,5,0,0.0000,1.000000,false\n")
        );
    }
}
