//! The process at the system's edges: what every command and the app
//! need of the operating system, kept apart from the raytracer.
//!
//! - [`files`]: special files, symbolic links, permissions and locks,
//!   where a write lands (held by descriptors), rewrites in place;
//! - [`interrupt`]: SIGINT, SIGTERM and SIGHUP stop a write or a render
//!   cleanly, nothing left behind;
//! - [`resources`]: memory and open files asked for before the work that
//!   needs them, refused in one line instead of an abort;
//! - [`allocator`]: glibc's malloc set at start, and asked to give back
//!   what it holds free after a save;
//! - [`escape`]: text from outside (file names, comments) with its
//!   control characters made visible, for the terminal and CSV files.

pub mod allocator;
pub mod escape;
pub mod files;
pub mod interrupt;
pub mod resources;
