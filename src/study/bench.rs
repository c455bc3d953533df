//! The benchmark scenes: the four scenes of `scenes/bench/` (built into the
//! binary, so `rayoflight bench` runs from anywhere); the generated scenes
//! of n spheres on a floor for the cost-against-object-count series are
//! [`crate::scene::generated`]'s.
//!
//! Timing is [`crate::render::measure`](mod@crate::render::measure)'s; POV-Ray and reporting live with the
//! command line; this module only says what is rendered.

use crate::render::measure::BuiltinScene;

/// The bench set, in the order reported.
pub const SCENES: [BuiltinScene; 4] = [
    crate::builtin!("bench", "example-2000"),
    crate::builtin!("bench", "spheres-2000"),
    crate::builtin!("bench", "mirrors"),
    crate::builtin!("bench", "room"),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_bench_scene_loads() {
        for s in &SCENES {
            s.scene().unwrap_or_else(|e| panic!("{e}"));
        }
    }
}
