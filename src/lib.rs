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
//!   the prepared scene, tiles, the 8-bit image;
//!   [`render::request`]: what a front end asks for (method,
//!   anti-aliasing, threads, region) resolved into render options, with
//!   one precedence; [`render::region`]: a rectangle of the image
//!   (`--region`).
//! - [`output`]: image files: the format by extension, the target checked
//!   first, one PNG row writer, EXR; and the one font drawn into images.
//! - [`pov`]: the POV-Ray 3.7 translation used to cross-check renders.
//! - [`cluster`]: past one machine: the record a part's PNG keeps (which
//!   region of the image it holds), regions of even cost
//!   for many tasks, their parts put back together and checked, and the
//!   renders of a sweep side by side (`sheet`).
//! - [`study`]: speed against accuracy: every method on the study scenes,
//!   measured; with `bench` (the benchmark scenes; its generated scenes
//!   are `scene::generated`'s). What measures (render
//!   time, medians, image differences, CSV: one way for the bench, the
//!   study, `-time` and the tests) is `render::measure`.
//! - [`desktop`]: the app's desktop entry, icons and scene MIME type,
//!   installed for the user and removed again; and the editor link
//!   (Unix): the editor's unsaved text from `rayoflight lsp` to the app,
//!   over a socket of the user's own.
//! - [`system`]: the process at the system's edges: files (special files,
//!   links, permissions, locks, where a write lands, and every file's one
//!   atomic way out, `system::files::write`), interrupts (SIGINT,
//!   SIGTERM and SIGHUP stop a write or a render cleanly), resources
//!   (memory and open files asked for first), the allocator (glibc's
//!   malloc tuned), and text from outside escaped for the terminal.
//! - `session` (feature `session`): the app's model without a window: the
//!   document and its undo, the journal of unsaved edits, the file
//!   watcher, the render worker, the settings.
//! - `gui` (feature `gui`, on `session`): the desktop previewer's window,
//!   which uses only the modules above.
//!
//! The core never prints and knows nothing of windows or terminals.

// Two modules call what the compiler cannot check, each with its safety
// argument: geometry::avx (AVX instructions) and system::allocator (glibc's
// malloc parameters). `unsafe_code` is allowed there only.
#![deny(unsafe_code)]

pub mod cluster;
pub mod desktop;
pub mod geometry;
#[cfg(feature = "gui")]
pub mod gui;
pub mod math;
pub mod output;
pub mod pov;
pub mod render;
pub mod scene;
#[cfg(feature = "session")]
pub mod session;
pub mod shading;
pub mod study;
pub mod system;

/// The built-in example scene, from `scenes/example.xml`.
pub const EXAMPLE_SCENE: &str = include_str!("../scenes/example.xml");
