//! Every write is safe: from another user racing renames or planting links in
//! a shared folder, from a crash or a kill mid-write, from a full disk or a
//! read-only folder.

#[path = "../common/mod.rs"]
mod common;

mod full_disk;
mod races_and_crashes;
