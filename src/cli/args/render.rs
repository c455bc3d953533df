//! The render's own flags, those of `rayoflight [-time] scene.xml [-out
//! image.png] …` with no subcommand ([`RenderFlags`]), resolved into the
//! [`RenderArgs`] the render runs with; and [`RenderOf`], the flags that
//! name a render in the subcommands that speak of one (`explain`,
//! `split`).

use super::error::UsageError;
use super::values::{
    Named, aa, method, method_names, pass, pass_names, path_value, region, threads,
};
use crate::cli::edit::{EditArg, Given, edit_args};
use clap::Args;
use rayoflight::render::region::Region;
use rayoflight::render::request::RenderRequest;
use rayoflight::render::{Method, Pass};
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, PartialEq, Default)]
pub struct RenderArgs {
    /// The scene file; `None` means the built-in example (app only).
    pub scene: Option<PathBuf>,
    pub out: Option<PathBuf>,
    pub time: bool,
    pub no_gui: bool,
    /// `--method`, `--aa`, `--threads` and `--region`.
    pub request: RenderRequest,
    /// `--set`: values changed in memory before rendering, in order.
    pub edits: Vec<EditArg>,
    /// `--quiet`: no progress bar.
    pub quiet: bool,
    /// `--pass`: what to write (default: the image).
    pub pass: Pass,
}

impl RenderArgs {
    /// Whether the command asks for headless work: any of `-out`, `-time`,
    /// `--no-gui`, `--quiet`, `--threads`, `--aa`, `--method`, `--region`,
    /// `--set`, `--pass`: every flag but the scene is the command line's.
    /// In the GUI build, anything else opens the app (the headless build
    /// never asks).
    #[cfg_attr(not(feature = "gui"), allow(dead_code))]
    pub fn headless(&self) -> bool {
        self.out.is_some()
            || self.time
            || self.no_gui
            || self.quiet
            || self.request != RenderRequest::default()
            || !self.edits.is_empty()
            || self.pass != Pass::Final
    }
}

/// The render's flags: `rayoflight [-time] scene.xml [-out image.png] …`.
#[derive(Args, Debug)]
pub(super) struct RenderFlags {
    /// The scene file (none: the app opens on the built-in example).
    scene: Option<PathBuf>,
    /// The image to write (also -out); the extension picks the format.
    ///
    /// png, jpg, jpeg, gif, bmp, tga, ppm, tif, tiff, qoi, webp, or exr
    /// (32-bit floats, unclamped). Default: the scene's path with the
    /// extension .png.
    #[arg(short, long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Print the render time (prepare + trace) as 'render: N ns' (also
    /// -time).
    #[arg(long)]
    time: bool,
    /// Render threads [default: one per core]
    #[arg(long, value_name = "N", value_parser = threads, allow_negative_numbers = true)]
    threads: Option<usize>,
    /// N×N rays per pixel, 1 to 16 [default: 1, the pixel centre]
    #[arg(long, value_name = "N", value_parser = aa, allow_negative_numbers = true)]
    aa: Option<u32>,
    /// Render with this method instead of auto (see docs/study.md).
    #[arg(long, value_name = "NAME", value_parser = Named::new(method, method_names))]
    method: Option<Method>,
    /// Never open a window (the headless build never does).
    #[arg(long)]
    no_gui: bool,
    /// Render with a value changed (object[2].material.ka=0.5), in memory
    /// only: the scene file is not written.
    ///
    /// Repeatable; the paths are listed by 'rayoflight edit --help'.
    #[arg(long, value_name = "PATH=VALUE", value_parser = path_value)]
    set: Vec<(String, String)>,
    /// No progress bar on stderr.
    ///
    /// One shows on a terminal for renders over a second: percentage,
    /// rays/s, time left.
    #[arg(short, long)]
    quiet: bool,
    /// Write one render pass instead of the image.
    ///
    /// final (default), ambient, diffuse, specular, reflection (the camera
    /// ray's terms; in .exr they add up to final), normal, depth, object.
    #[arg(long, value_name = "NAME", value_parser = Named::new(pass, pass_names))]
    pass: Option<Pass>,
    /// Render only this rectangle of the image, into the PNG part -out
    /// names.
    ///
    /// Pixels from the top left, X1 and Y1 excluded; -out is required.
    /// The part's pixels are the whole render's, and it records where it
    /// belongs: 'rayoflight assemble' puts parts together.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = region, allow_hyphen_values = true)]
    region: Option<Region>,
}

/// Which render a subcommand speaks of (`explain`, `split`): the scene's
/// values changed, the anti-aliasing and the method.
#[derive(Args, Debug)]
pub(in crate::cli) struct RenderOf {
    /// The render with this value changed, in memory only.
    #[arg(long, value_name = "PATH=VALUE", value_parser = path_value)]
    set: Vec<(String, String)>,
    /// N×N rays per pixel, 1 to 16.
    #[arg(long, value_name = "N", value_parser = aa, allow_negative_numbers = true)]
    aa: Option<u32>,
    /// The study method the render uses instead of auto.
    #[arg(long, value_name = "NAME", value_parser = Named::new(method, method_names))]
    method: Option<Method>,
}

impl RenderOf {
    /// The request and the edits, read against `scene`'s path.
    pub(in crate::cli) fn resolve(
        self,
        scene: &Path,
    ) -> Result<(RenderRequest, Vec<EditArg>), UsageError> {
        let given = self.set.into_iter().map(|(p, v)| Given::Set(p, v));
        let request = RenderRequest {
            method: self.method,
            aa: self.aa,
            ..RenderRequest::default()
        };
        Ok((request, edit_args(given.collect(), scene)?))
    }
}

pub(super) fn render_args(r: RenderFlags) -> Result<RenderArgs, UsageError> {
    let edits = match &r.scene {
        Some(scene) => {
            let given = r.set.into_iter().map(|(p, v)| Given::Set(p, v));
            edit_args(given.collect(), scene)?
        }
        // --set makes the render headless, which needs a scene.
        None if !r.set.is_empty() => return Err(UsageError::NoScene),
        None => Vec::new(),
    };
    if r.region.is_some() {
        let invalid = |message: &str| UsageError::Invalid {
            message: message.to_owned(),
            command: None,
        };
        if r.pass.is_some_and(|p| p != Pass::Final) {
            return Err(invalid(
                "--region renders the image: it cannot be used with --pass",
            ));
        }
        let png = |out: &Path| {
            out.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("png"))
        };
        match r.out.as_deref() {
            None => {
                return Err(invalid(
                    "--region needs -out PART.png: written to the scene's own image \
                     path, a part would replace its whole render",
                ));
            }
            Some(out) if !png(out) => {
                return Err(invalid(
                    "--region writes a PNG part, which records where it belongs for \
                     'rayoflight assemble': -out must end in .png",
                ));
            }
            Some(_) => {}
        }
    }
    Ok(RenderArgs {
        scene: r.scene,
        out: r.out,
        time: r.time,
        no_gui: r.no_gui,
        request: RenderRequest {
            method: r.method,
            aa: r.aa,
            threads: r.threads,
            region: r.region,
        },
        edits,
        quiet: r.quiet,
        pass: r.pass.unwrap_or_default(),
    })
}
