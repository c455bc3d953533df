//! The command line: `rayoflight [-time] scene.xml [-out image.png]` and its
//! subcommands. This is the binary's edge: it turns typed library errors into
//! one-line messages on stderr and exit statuses (0 success, 1 a scene,
//! render or output error, 2 a usage error).
//!
//! Where things are: [`args`] parses the command line into a
//! [`command::Command`]; [`command`] lists the subcommands, one line each,
//! and dispatches to them; each subcommand is one module, with its flags
//! as clap reads them and its work ([`subcommand`] says what one is); the
//! render without a subcommand is [`render`]. What they share: the value
//! parsers of common flags ([`values`]), [`edit`]'s edits, the one way to
//! stdout ([`stdout`]), the progress bar ([`progress`]), and how a command
//! fails ([`failure`], [`usage`]).

mod args;
mod bench;
mod cluster;
mod command;
mod desktop;
mod edit;
mod explain;
mod failure;
mod generated;
mod lsp;
mod new;
mod plan;
mod pov;
mod progress;
mod render;
mod stdout;
mod study;
mod subcommand;
mod usage;
mod values;

use command::Command;
use failure::{Failure, fail};
use rayoflight::system::interrupt;
use std::process::ExitCode;

pub fn main() -> ExitCode {
    rayoflight::system::allocator::tune();
    let code = failure::report(run(std::env::args_os().skip(1)), args::usage);
    // A signal that stopped the work: the status a shell gives a process
    // the signal ended (130 for Ctrl+C, 143 for SIGTERM).
    match interrupt::caught() {
        Some(signal) => ExitCode::from(128u8.saturating_add(signal as u8)),
        None => code,
    }
}

fn run(args: impl IntoIterator<Item = std::ffi::OsString>) -> Result<(), Failure> {
    let command = args::parse(args)?;
    interrupt::writes_past_the_size_limit_fail().map_err(fail)?;
    // SIGINT, SIGTERM and SIGHUP stop a render or a write cleanly (the
    // app, which saves unsaved edits on them, has its own handlers).
    if !matches!(&command, Command::Render(r) if render::opens_app(r)) {
        interrupt::install().map_err(fail)?;
    }
    // What prints on stdout finds it closed before any work, not after.
    if command.prints() && stdout::closed_at_start() {
        return Err(Failure::Error(stdout::CLOSED.to_owned()));
    }
    command.run(args::definition)
}
