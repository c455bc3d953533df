//! `rayoflight plan scene.xml`: what `auto` decides for the scene, each
//! decision with its reason. The decisions are the library's
//! ([`rayoflight::render::auto`]); renders use the same.

use super::failure::{Failure, fail};
use super::stdout;
use super::subcommand::Subcommand;
use super::usage::UsageError;
use rayoflight::{render, scene};
use std::path::PathBuf;

/// Print what 'auto' will do for the scene, and why.
///
/// Precision, BVH and tile culling, early stop, zero terms: each
/// decision with the scene's numbers. Renders use these options.
#[derive(clap::Args, Debug, Clone, PartialEq)]
#[command(override_usage = "rayoflight plan scene.xml")]
pub(super) struct PlanFlags {
    /// The scene file.
    pub scene: PathBuf,
}

impl Subcommand for PlanFlags {
    type Args = PlanFlags;

    fn resolve(self, _: &clap::ArgMatches) -> Result<PlanFlags, UsageError> {
        Ok(self)
    }

    fn prints(_: &PlanFlags) -> bool {
        true
    }

    fn run(args: PlanFlags, _: fn() -> clap::Command) -> Result<(), Failure> {
        let scene = scene::load(&args.scene).map_err(fail)?;
        for d in render::auto(&scene).decisions {
            stdout::line(&format!("{}: {}\n  {}", d.topic, d.choice, d.reason))?;
        }
        Ok(())
    }
}
