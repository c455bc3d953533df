//! The app's model, without a window (feature `session`, which `gui`
//! builds on): what one person's editing of a scene holds and does, apart
//! from how it is drawn, as Helix keeps helix-view apart from its terminal.
//! It builds and is tested without egui; the window (`crate::gui`) draws
//! it and turns clicks and keys into its calls, and `rayoflight bench
//! --app-*` measures it with no window at all.
//!
//! - [`document`]: the file's text, the scene with its unsaved edits, undo
//!   and redo, saves that never write over unread text, merges.
//! - [`worker`]: the background render thread, coarse to fine, newest wins.
//! - [`preview`]: the picture assembled from the worker's tiles, and what
//!   of it changed since the window last took it.
//! - [`pace`]: how coarse to render while the mouse moves.
//! - [`watcher`]: the file watcher (notify), debounced.
//! - [`journal`]: the unsaved edits kept on disk as they are made, restored
//!   after a crash or a logout.
//! - [`settings`]: what the app remembers between runs, the recent files
//!   among it.
//! - [`editor`]: the user's editor, started on the scene at an element
//!   (Edit › Open in editor).

pub mod document;
pub mod editor;
pub mod journal;
pub mod pace;
pub mod preview;
pub mod settings;
pub mod watcher;
pub mod worker;

/// Files at least this large open on a thread of their own, the window
/// showing at once (a million spheres are 170 MB and take seconds).
pub const BACKGROUND_BYTES: u64 = 4 << 20;
