//! Scene files: what the loader accepts and the values it gives, what it
//! refuses and where, the properties every input keeps, the fuzzers, and the
//! edits written back into the text (the library and `rayoflight edit`).

#[path = "../common/mod.rs"]
mod common;

mod accepted;
mod edit_command;
mod fuzz_edits;
mod fuzz_loader;
mod properties;
mod refused;
mod save_back;
