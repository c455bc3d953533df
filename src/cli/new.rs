//! `rayoflight new scene.xml`: the built-in example, to start from, in a
//! file that did not exist (never over one: its text was not read), or on
//! stdout for `-`.

use super::failure::{Failure, fail};
use super::stdout;
use super::subcommand::Subcommand;
use super::usage::UsageError;
use clap::ValueHint;
use rayoflight::system::files;
use std::path::PathBuf;

/// Write the built-in example scene to a new file, to start from.
///
/// Never over an existing file. '-' prints it on stdout.
#[derive(clap::Args, Debug, Clone, PartialEq)]
#[command(override_usage = "rayoflight new scene.xml")]
pub(super) struct NewFlags {
    /// The scene file to create.
    #[arg(value_name = "FILE", value_hint = ValueHint::FilePath)]
    pub scene: PathBuf,
}

impl Subcommand for NewFlags {
    type Args = NewFlags;

    fn resolve(self, _: &clap::ArgMatches) -> Result<NewFlags, UsageError> {
        Ok(self)
    }

    fn prints(args: &NewFlags) -> bool {
        args.scene.as_os_str() == "-"
    }

    fn run(args: NewFlags, _: fn() -> clap::Command) -> Result<(), Failure> {
        let example = rayoflight::EXAMPLE_SCENE;
        match args.scene.as_os_str() == "-" {
            true => stdout::write(example).map_err(Failure::Error),
            false => files::write_new(&args.scene, example.as_bytes()).map_err(fail),
        }
    }
}
