//! `rayoflight export-pov scene.xml [-out scene.pov]`: the scene as a
//! POV-Ray 3.7 file (`-out -`: on stdout), for cross-checking a render
//! against POV-Ray's. The translation is the library's
//! ([`rayoflight::pov`]).

use super::failure::{Failure, fail, refuse_same_file};
use super::stdout;
use super::subcommand::Subcommand;
use super::usage::UsageError;
use rayoflight::scene;
use rayoflight::system::files;
use std::path::PathBuf;

/// Write the scene as a POV-Ray 3.7 file, for cross-checking.
#[derive(clap::Args, Debug, Clone, PartialEq)]
#[command(override_usage = "rayoflight export-pov scene.xml [-out scene.pov]")]
pub(super) struct ExportPovFlags {
    /// The scene file.
    pub scene: PathBuf,
    /// The POV-Ray file to write, - for stdout [default: the scene's path with .pov]
    #[arg(short, long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

impl Subcommand for ExportPovFlags {
    type Args = ExportPovFlags;

    fn resolve(self, _: &clap::ArgMatches) -> Result<ExportPovFlags, UsageError> {
        Ok(self)
    }

    /// `-out -`: the POV-Ray text on stdout, as `new -` prints its scene.
    fn prints(args: &ExportPovFlags) -> bool {
        args.out.as_deref().is_some_and(|o| o.as_os_str() == "-")
    }

    /// Never over the scene, atomically, the scene's path and the file's
    /// own in its header.
    fn run(args: ExportPovFlags, _: fn() -> clap::Command) -> Result<(), Failure> {
        let scene_path = &args.scene;
        if Self::prints(&args) {
            let scene = scene::load(scene_path).map_err(fail)?;
            // The header names the file a redirection would make by default.
            let header = rayoflight::pov::Header {
                scene: scene_path,
                written_to: &scene_path.with_extension("pov"),
            };
            let text = rayoflight::pov::export_named(&scene, Some(header));
            return stdout::write(&text).map_err(Failure::Error);
        }
        let out = args.out.unwrap_or_else(|| scene_path.with_extension("pov"));
        refuse_same_file(scene_path, &out)?;
        files::check_file_target(&out).map_err(fail)?;
        let scene = scene::load(scene_path).map_err(fail)?;
        let header = rayoflight::pov::Header {
            scene: scene_path,
            written_to: &out,
        };
        let text = rayoflight::pov::export_named(&scene, Some(header));
        files::write_atomic(&out, text.as_bytes()).map_err(fail)
    }
}
