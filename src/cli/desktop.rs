//! `rayoflight install-desktop [--uninstall]`: the app in the desktop's
//! menus and "Open with", for this user, or gone again. The files and
//! their rules are the library's ([`rayoflight::desktop`]); this edge says
//! what was done, on stderr.

use super::failure::{Failure, fail};
use super::subcommand::Subcommand;
use super::usage::UsageError;
use rayoflight::desktop;

/// Put the app in the desktop's menus and "Open with", for this user.
///
/// Writes a desktop entry (that runs this binary, by its absolute
/// path), the icons in the hicolor theme and the type of scenes that
/// name rayoflight.xsd under $XDG_DATA_HOME (default ~/.local/share),
/// and updates the desktop's databases when their tools are installed.
/// RayOfLight is the default for its own type only, never for every
/// XML file: where you chose no default for XML, the application that
/// opens XML files until then is written as your choice into
/// $XDG_CONFIG_HOME/mimeapps.list (default ~/.config). Never over a file
/// it did not write; --uninstall removes exactly what it wrote, those
/// lines included unless you changed them since.
#[derive(clap::Args, Debug, Clone, PartialEq)]
#[command(override_usage = "rayoflight install-desktop [--uninstall]")]
pub(super) struct InstallDesktopFlags {
    /// Remove what install-desktop wrote.
    #[arg(long)]
    pub uninstall: bool,
}

impl Subcommand for InstallDesktopFlags {
    type Args = InstallDesktopFlags;

    fn resolve(self, _: &clap::ArgMatches) -> Result<InstallDesktopFlags, UsageError> {
        Ok(self)
    }

    fn prints(_: &InstallDesktopFlags) -> bool {
        false
    }

    fn run(args: InstallDesktopFlags, _: fn() -> clap::Command) -> Result<(), Failure> {
        let uninstall = args.uninstall;
        if !cfg!(feature = "gui") {
            return Err(Failure::Error(
                "rayoflight: this build has no desktop app (built without the gui feature): \
                 nothing to install"
                    .to_owned(),
            ));
        }
        let home = desktop::data_home().map_err(fail)?;
        let places = desktop::defaults::Places::from_env(&home)
            .ok_or(desktop::DesktopError::NoConfigHome)
            .map_err(fail)?;
        let done = match uninstall {
            false => {
                let exec = std::env::current_exe()
                    .and_then(std::fs::canonicalize)
                    .map_err(|e| {
                        Failure::Error(format!("rayoflight: where is this binary? {e}"))
                    })?;
                let done = desktop::install(&places, &exec).map_err(fail)?;
                eprintln!(
                    "installed under {}: the desktop entry (running {}), {} icons and the scene type",
                    home.display(),
                    exec.display(),
                    desktop::ICON_PNGS.len() + 1
                );
                for line in &done.defaults {
                    let (mime, id) = line.split_once('=').unwrap_or((line, ""));
                    eprintln!(
                        "{} stays the default for {mime}, as your choice in {}",
                        id.trim_end_matches(';'),
                        places.user_list().display()
                    );
                }
                done
            }
            true => {
                let done = desktop::uninstall(&places).map_err(fail)?;
                // A failed install may have made folders and no file.
                let home = home.display();
                match (done.files.len(), done.folders.len()) {
                    (0, 0) => {
                        eprintln!("nothing to remove: install-desktop wrote nothing under {home}")
                    }
                    (0, m) => eprintln!(
                        "removed the {m} folders install-desktop made, empty (it wrote no file under {home})"
                    ),
                    (n, 0) => eprintln!("removed the {n} files install-desktop wrote under {home}"),
                    (n, m) => eprintln!(
                        "removed the {n} files install-desktop wrote under {home} and the {m} folders it made"
                    ),
                }
                for line in &done.defaults {
                    eprintln!(
                        "removed the default install-desktop wrote from {}: {line}",
                        places.user_list().display()
                    );
                }
                for line in &done.kept_defaults {
                    eprintln!(
                        "left the default {line} out of {}: it changed since install-desktop wrote it",
                        places.user_list().display()
                    );
                }
                for kept in &done.kept {
                    eprintln!(
                        "left {}: it changed since install-desktop wrote it",
                        rayoflight::system::escape::visible(&kept.display().to_string(), false)
                    );
                }
                done
            }
        };
        for ran in &done.ran {
            eprintln!("ran {ran}");
        }
        for tool in &done.missing {
            eprintln!(
                "{tool} is not installed: the desktop may see the change only after its next login"
            );
        }
        Ok(())
    }
}
