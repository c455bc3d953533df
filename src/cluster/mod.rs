//! Past one machine: what lets a render be cut into parts on a cluster
//! and put back together. A part covers a
//! [`Region`](crate::render::region::Region) of the image, the render's own
//! idea (what `--region` renders).
//!
//! - [`part`]: the record a part's PNG keeps of where it belongs;
//! - [`split`]: regions of even cost for many tasks;
//! - [`assemble`]: the parts put back together, checked;
//! - [`sheet`]: the renders of a sweep side by side.

pub mod assemble;
pub mod part;
pub mod sheet;
pub mod split;
