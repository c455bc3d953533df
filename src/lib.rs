//! RayOfLight: a small raytracer for XML scenes.
//!
//! The flow every front end shares (CLI, desktop app, study):
//!
//! ```text
//! scene::load ──► Scene ──► render::prepare ──► Prepared ──► render tiles ──► Image ──► output::save
//! ```
//!
//! - [`scene`]: the file format, its validation and its errors (`file:line:col`).
//! - [`math`]: transforms with their cached inverse and normal matrix.
//! - [`geometry`]: shapes, rays and the ray/sphere and ray/plane
//!   intersections.
//! - [`shading`]: the illumination formulas (ambient, lambert, phong, whitted).
//! - [`render`]: render options and the named methods (`auto`, `f32`, …),
//!   the prepared scene, tiles, the 8-bit image.
//! - [`request`]: what a front end asks for (method, anti-aliasing,
//!   threads, region) resolved into render options, with one precedence.
//! - [`output`]: writing images atomically, format chosen by extension.
//! - [`region`], [`part`]: a rectangle of the image (`--region`), and the
//!   record a part's PNG keeps of where it belongs.
//! - [`split`], [`assemble`]: past one machine: regions of even cost for
//!   many tasks, and their parts put back together, checked; [`sheet`]:
//!   the renders of a sweep side by side.
//! - [`desktop`]: the app's desktop entry, icons and scene MIME type,
//!   installed for the user and removed again.
//! - [`editor_link`]: the editor's unsaved text from `rayoflight lsp` to
//!   the app, over a socket of the user's own.
//! - [`escape`]: text from outside (file names, comments) with its control
//!   characters made visible, for the terminal and for CSV files.
//! - [`files`]: special files, symbolic links, permissions and locks, for
//!   reading and writing.
//! - [`interrupt`]: SIGINT, SIGTERM and SIGHUP stop a write or a render
//!   cleanly, nothing left behind.
//! - [`allocator`]: glibc's malloc set at start, and asked to give back
//!   what it holds free after a save.
//! - [`resources`]: memory and open files asked for before the work that
//!   needs them, refused in one line instead of an abort.
//! - [`pov`]: the POV-Ray 3.7 translation used to cross-check renders.
//! - [`bench`](mod@bench): the benchmark scenes.
//! - [`measure`]: render time, medians, image differences, CSV: measured
//!   one way by the bench, the study, `-time` and the tests.
//! - [`study`]: speed against accuracy: every method on the study scenes,
//!   measured.
//! - `gui` (feature `gui`): the desktop previewer, which uses only the
//!   modules above.
//!
//! The core never prints and knows nothing of windows or terminals.

// Two modules call what the compiler cannot check, each with its safety
// argument: geometry::avx (AVX instructions) and allocator (glibc's
// malloc parameters). `unsafe_code` is allowed there only.
#![deny(unsafe_code)]

pub mod allocator;
pub mod assemble;
pub mod bench;
pub mod desktop;
#[cfg(unix)]
pub mod editor_link;
pub mod escape;
pub mod files;
pub mod geometry;
#[cfg(feature = "gui")]
pub mod gui;
pub mod interrupt;
pub mod math;
pub mod measure;
pub mod output;
pub mod part;
pub mod pov;
pub mod region;
pub mod render;
pub mod request;
pub mod resources;
pub mod scene;
pub mod shading;
pub mod sheet;
pub mod split;
pub mod study;

/// The built-in example scene, from `scenes/example.xml`.
pub const EXAMPLE_SCENE: &str = include_str!("../scenes/example.xml");
