//! How the binary fails: a [`Failure`] says what to print and which exit
//! status to end with (0 success, 1 a scene, render or output error, 2 a
//! usage error), and [`report`] prints it as one line on stderr, whatever
//! the file names in it hold. The refusals several commands share are
//! here too: an output that would replace the scene ([`refuse_same_file`]),
//! an edit the scene refuses ([`refused`]), a signal before anything was
//! written ([`interrupted`]).

use super::usage::UsageError;
use rayoflight::scene::edit::EditError;
use rayoflight::system::files;
use std::path::Path;
use std::process::ExitCode;

/// A failure at the edge: what to print and which status to exit with.
pub(super) enum Failure {
    /// Exit status 2.
    Usage(UsageError),
    /// A scene, render or output error, as printed: exit status 1.
    Error(String),
}

impl From<UsageError> for Failure {
    fn from(e: UsageError) -> Failure {
        Failure::Usage(e)
    }
}

/// An error of the library, as its message: exit status 1.
pub(super) fn fail(e: impl std::fmt::Display) -> Failure {
    Failure::Error(e.to_string())
}

/// A usage error (exit 2) found once the scene is read.
pub(super) fn usage(message: String) -> Failure {
    Failure::Usage(UsageError::Invalid {
        message,
        command: None,
    })
}

/// An edit `scene` refuses: a usage error (exit 2) that names the scene.
pub(super) fn refused(scene: &Path) -> impl FnOnce(EditError) -> Failure {
    let scene = scene.to_owned();
    |error| Failure::Usage(UsageError::Edit { scene, error })
}

/// What the edge says when a signal stopped a render before any file
/// was written.
pub(super) fn interrupted() -> Failure {
    Failure::Error("rayoflight: interrupted: nothing was written".to_owned())
}

/// The output must never replace the scene: not by another spelling of
/// its path (`./a/../s.xml`), a symbolic link or a hard link.
pub(super) fn refuse_same_file(scene: &Path, out: &Path) -> Result<(), Failure> {
    if files::same_file(scene, out) {
        return Err(Failure::Error(format!(
            "{}: refusing to overwrite the scene file with the output",
            out.display()
        )));
    }
    Ok(())
}

/// Prints what failed, and gives the exit status. `usage` is the usage
/// text, printed when a command needs a scene and was given none.
pub(super) fn report(result: Result<(), Failure>, usage: impl FnOnce() -> String) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Usage(UsageError::NoScene)) => {
            eprintln!("{}", usage());
            ExitCode::from(2)
        }
        Err(Failure::Usage(UsageError::Invalid { message, command })) => {
            let help = match command {
                Some(name) => format!("rayoflight {name} --help"),
                None => "rayoflight --help".to_owned(),
            };
            error_line(&format!("rayoflight: {message}; see '{help}'"));
            ExitCode::from(2)
        }
        Err(Failure::Usage(UsageError::Edit { scene, error })) => {
            error_line(&format!("rayoflight: {}: {error}", scene.display()));
            ExitCode::from(2)
        }
        Err(Failure::Error(msg)) => {
            error_line(&msg);
            ExitCode::from(1)
        }
    }
}

/// An error on stderr: one line, whatever the file names in it hold.
fn error_line(message: &str) {
    eprintln!("{}", rayoflight::system::escape::visible(message, false));
}
