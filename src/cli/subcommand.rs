//! What a subcommand is to the binary: one type in the subcommand's own
//! module, which clap reads its flags into (derived with `clap::Args`; its
//! doc comment is the subcommand's help, its `override_usage` its line in
//! the usage), and which says what they resolve into, whether the
//! subcommand prints on stdout, and how it runs ([`Subcommand`]). The
//! table in [`super::command`] lists them, one line each.

use super::failure::Failure;
use super::usage::UsageError;

/// One subcommand: its flags as clap reads them (the type itself).
pub(super) trait Subcommand: clap::Args + clap::FromArgMatches + std::fmt::Debug {
    /// What the subcommand runs with: every default applied, every rule
    /// across flags checked.
    type Args: std::fmt::Debug + Clone + PartialEq;

    /// Resolves the flags read. `matches` are the subcommand's own, which
    /// alone know the order the flags were given in (`edit`'s edits).
    fn resolve(self, matches: &clap::ArgMatches) -> Result<Self::Args, UsageError>;

    /// Whether it prints on stdout: then a stdout closed from the start
    /// fails it before any work, not after.
    fn prints(args: &Self::Args) -> bool;

    /// Runs it. `definition` gives the command line's definition, which
    /// what is generated from it (man pages, completions) needs.
    fn run(args: Self::Args, definition: fn() -> clap::Command) -> Result<(), Failure>;
}
