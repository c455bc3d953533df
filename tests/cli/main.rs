//! The command line as a user drives it, through the built binary: exit
//! statuses, messages and outputs, inputs checked before any work, progress
//! on a terminal, the README's transcripts, the documented limits and the
//! resources a run may take.

#[path = "../common/mod.rs"]
mod common;

mod inputs;
mod limits;
mod progress;
mod readme;
mod resources;
mod usage;
