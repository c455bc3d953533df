//! The app without a display: its model's worker, watcher and picture, and
//! big scenes shared, not copied (feature `session`: no window); editing,
//! undo and save-back through the document, unsaved work kept through
//! crashes and other programs' writes, the panel, looking around with the
//! mouse (feature `gui`, driven by egui_kittest).
#![cfg(feature = "session")]

#[path = "../common/mod.rs"]
mod common;

#[cfg(feature = "gui")]
mod util;

mod background;
mod big_scenes;
#[cfg(feature = "gui")]
mod editing;
#[cfg(feature = "gui")]
mod panel;
#[cfg(feature = "gui")]
mod unsaved_work;
#[cfg(feature = "gui")]
mod viewport;
