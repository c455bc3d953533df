//! The app without a display: its worker, watcher and picture; editing, undo
//! and save-back through the document; unsaved work kept through crashes and
//! other programs' writes; looking around with the mouse; big scenes shared,
//! not copied.
// The app's document, watcher and worker are in the GUI build.
#![cfg(feature = "gui")]

#[path = "../common/mod.rs"]
mod common;

mod util;

mod background;
mod big_scenes;
mod editing;
mod unsaved_work;
mod viewport;
