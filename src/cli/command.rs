//! The subcommands, one line each ([`subcommands!`] below): the table that
//! makes clap's list of subcommands ([`Sub`]), what a command line asks
//! for ([`Command`]), and the dispatch to each ([`Command::run`]).
//!
//! A new subcommand is its module — the type clap reads its flags into,
//! whose doc comment is its help, implementing [`Subcommand`] — and its
//! line here. Its name is the variant's, in kebab case (`ExportPov` is
//! `export-pov`); its line in the top-level usage is its own usage, read
//! from the definition; the man pages and the shell completions are
//! generated from the same definition.

use super::failure::Failure;
use super::render::{self, RenderArgs};
use super::stdout;
use super::subcommand::Subcommand;
use super::usage::UsageError;
use super::{bench, cluster, desktop, edit, explain, generated, lsp, new, plan, pov, study};
use clap::ArgMatches;

/// Writes the enums and the dispatch from the table: each line names the
/// subcommand's variant and the type its flags are read into.
macro_rules! subcommands {
    ($($variant:ident: $flags:ty,)*) => {
        /// The subcommands, as clap reads them.
        #[derive(clap::Subcommand, Debug)]
        pub(super) enum Sub {
            $($variant($flags),)*
        }

        /// What the user asked for: `--help` or `--version`, a render, or a
        /// subcommand with its arguments resolved.
        #[derive(Debug, Clone, PartialEq)]
        pub(super) enum Command {
            /// `--help` or `--version`: print this text on stdout.
            Print(String),
            /// Render a scene (headless), or open the app on it (GUI
            /// build, no headless flag).
            Render(RenderArgs),
            $($variant(<$flags as Subcommand>::Args),)*
        }

        impl Command {
            /// The subcommand `sub` asks for, resolved (`matches`: the
            /// subcommand's own).
            pub(super) fn of(sub: Sub, matches: &ArgMatches) -> Result<Command, UsageError> {
                Ok(match sub {
                    $(Sub::$variant(flags) => Command::$variant(flags.resolve(matches)?),)*
                })
            }

            /// Whether the command prints on stdout: help and version, a
            /// render with `-time`, and the subcommands that say so.
            pub(super) fn prints(&self) -> bool {
                match self {
                    Command::Print(_) => true,
                    Command::Render(args) => args.time,
                    $(Command::$variant(args) => <$flags as Subcommand>::prints(args),)*
                }
            }

            /// Does what the command asks. `definition` gives the command
            /// line's definition.
            pub(super) fn run(self, definition: fn() -> clap::Command) -> Result<(), Failure> {
                match self {
                    Command::Print(text) => stdout::line(text.trim_end()),
                    Command::Render(args) => render::run(args),
                    $(Command::$variant(args) => <$flags as Subcommand>::run(args, definition),)*
                }
            }
        }
    };
}

subcommands! {
    Split: cluster::SplitFlags,
    Assemble: cluster::AssembleFlags,
    Sheet: cluster::SheetFlags,
    ExportPov: pov::ExportPovFlags,
    Plan: plan::PlanFlags,
    Explain: explain::ExplainFlags,
    Bench: bench::BenchFlags,
    Edit: edit::EditFlags,
    Study: study::StudyFlags,
    New: new::NewFlags,
    Schema: generated::SchemaFlags,
    Completions: generated::CompletionsFlags,
    InstallDesktop: desktop::InstallDesktopFlags,
    Lsp: lsp::LspFlags,
    Man: generated::ManFlags,
}
