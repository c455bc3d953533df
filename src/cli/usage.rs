//! What a command line that does not parse is ([`UsageError`], exit status
//! 2): its own module, below the parser and every subcommand, so that each
//! subcommand's module can refuse its arguments without importing the
//! parser that imports it.

use rayoflight::scene::edit::EditError;
use std::path::PathBuf;

/// A command line that does not parse, or an edit the scene refuses: exit
/// status 2.
#[derive(Debug, Clone, PartialEq)]
pub enum UsageError {
    /// No scene where the command needs one: the usage is printed.
    NoScene,
    /// Arguments that do not fit the command. `command` is the subcommand
    /// whose `--help` to point to (`None`: the top-level one).
    Invalid {
        message: String,
        command: Option<&'static str>,
    },
    /// A `--set`, `--remove` or `--add` whose path or value the edit engine
    /// refuses, for this scene (`object[5]: the scene has 3 objects`).
    Edit { scene: PathBuf, error: EditError },
}
