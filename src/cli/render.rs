//! The render, `rayoflight [-time] scene.xml [-out image.png] …` with no
//! subcommand: its flags ([`RenderFlags`]), resolved into the
//! [`RenderArgs`] it runs with, and its run ([`run`]): every check that
//! can be made before work, the render timed as the bench times it, and
//! the image, part or pass written. In the GUI build, a scene alone opens
//! the app instead ([`opens_app`]). Also [`RenderOf`], the flags that name
//! a render in the subcommands that speak of one (`explain`, `split`).

use super::edit;
use super::edit::{EditArg, Given, edit_args};
use super::failure::{Failure, fail, interrupted, refuse_same_file, refused, usage};
use super::progress;
use super::stdout;
use super::usage::UsageError;
use super::values::{
    Named, aa, method, method_names, pass, pass_names, path_value, region, threads,
};
use clap::Args;
use rayoflight::cluster::part::Part;
use rayoflight::render::measure;
use rayoflight::render::region::Region;
use rayoflight::render::request::RenderRequest;
use rayoflight::render::{Method, Pass};
use rayoflight::scene::edit::Edited;
use rayoflight::system::{interrupt, resources};
use rayoflight::{output, render, scene};
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

/// Whether `r` opens the desktop app rather than rendering here.
pub(super) fn opens_app(r: &RenderArgs) -> bool {
    #[cfg(feature = "gui")]
    return !r.headless();
    #[cfg(not(feature = "gui"))]
    {
        let _ = r;
        false
    }
}

/// Renders the scene as `r` asks, or opens the app on it.
pub(super) fn run(r: RenderArgs) -> Result<(), Failure> {
    // A scene that is not there: said, with no window waiting for it.
    if let Some(scene) = &r.scene
        && let Err(e) = std::fs::metadata(scene)
        && e.kind() == std::io::ErrorKind::NotFound
        && let Err(e) = scene::load(scene)
    {
        let hint = match scene.to_str() {
            Some("help") => "; for help: rayoflight --help",
            _ => "",
        };
        return Err(Failure::Error(format!("{e}{hint}")));
    }
    if opens_app(&r) {
        #[cfg(feature = "gui")]
        return open_app(r.scene.as_deref());
    }
    // No scene: the headless CLI prints its usage.
    let Some(scene_path) = r.scene.clone() else {
        return Err(Failure::Usage(UsageError::NoScene));
    };
    let out = r
        .out
        .clone()
        .unwrap_or_else(|| scene_path.with_extension("png"));
    // Everything that can be checked before work is checked first.
    refuse_same_file(&scene_path, &out)?;
    output::format_for(&out).map_err(fail)?;

    let loaded = scene::load(&scene_path).map_err(fail)?;
    // --set: in memory only, the scene file is never written. The edit
    // engine's record of where each element came from is made only for
    // them (a million objects' origins are 80 MB).
    let edited;
    let scene = if r.edits.is_empty() {
        &loaded
    } else {
        let mut engine = Edited::new(loaded);
        edit::apply(&mut engine, &r.edits).map_err(refused(&scene_path))?;
        edited = engine;
        edited.scene()
    };
    let request = &r.request;
    let (width, height) = match request.region {
        Some(region) => {
            let region = region
                .check_in(scene.camera.width, scene.camera.height)
                .map_err(|e| usage(format!("{}: --region {e}", scene_path.display())))?;
            (region.width(), region.height())
        }
        None => (scene.camera.width, scene.camera.height),
    };
    // The output can take this image: a folder that exists and is
    // writable, a format that holds its size, no special file in the way.
    let format = output::check_target(&out, width, height).map_err(fail)?;
    let pass = output::takes_pass(r.pass, &out).then_some(r.pass);
    // The memory the render and its file take, asked for before the
    // first ray: a one-line refusal, not an abort after minutes of work.
    let needed = output::bytes_to_render(format, pass, width, height);
    resources::check_memory(needed).map_err(|e| {
        let what = match pass {
            Some(pass) => format!("the {} pass", pass.name()),
            None => "the image".to_owned(),
        };
        Failure::Error(format!(
            "{}: rendering {what} at {width}×{height} {e}",
            out.display()
        ))
    })?;
    // Render time as the bench and the study measure it (rayoflight::render::measure).
    let pool = measure::RenderPool::new(request.threads).map_err(fail)?;
    let counted = render::Progress::default();
    // A signal stops the render at its next tile, or the write.
    let _cleanly = interrupt::cleanly();
    let never = render::Cancel::on_signal();
    let cancelled = interrupted;
    let elapsed = if let Some(pass) = pass {
        let form = output::pixel_form(format);
        let rendered = progress::render(&counted, progress::wanted(r.quiet), || {
            measure::kept_pass_timed(scene, request, pass, form, &pool, &never, &counted)
        });
        let timed = rendered.map_err(fail)?.ok_or_else(cancelled)?;
        output::save_kept_pass(&timed.image, &out).map_err(fail)?;
        if let Some((near, far)) = timed.image.depth_range {
            eprintln!("depth: t from {near} to {far}");
        }
        timed.elapsed
    } else {
        let rendered = progress::render(&counted, progress::wanted(r.quiet), || {
            measure::render_timed(scene, request, &pool, &never, &counted)
        });
        let timed = rendered.map_err(fail)?.ok_or_else(cancelled)?;
        // Written on the render's threads (a PNG's bands are deflated on
        // all of them).
        pool.install(|| match request.region {
            // A part records where it belongs, for `assemble`.
            Some(region) => {
                let part = Part::new(scene, &request.options(scene), region);
                rayoflight::cluster::part::save(&timed.image, &part, &out).map_err(fail)
            }
            None => output::save(&timed.image, &out).map_err(fail),
        })?;
        timed.elapsed
    };
    if r.time {
        stdout::line(&format!("render: {} ns", elapsed.as_nanos()))?;
    }
    Ok(())
}

/// Opens the desktop app (GUI build). No display is a usage problem: the
/// message names `--no-gui` and the exit status is 2.
#[cfg(feature = "gui")]
fn open_app(scene: Option<&Path>) -> Result<(), Failure> {
    use rayoflight::gui::{self, GuiError};
    match gui::run(scene) {
        Ok(()) => Ok(()),
        Err(e @ (GuiError::NoDisplay | GuiError::Window(_))) => {
            Err(Failure::Usage(UsageError::Invalid {
                message: e.to_string(),
                command: None,
            }))
        }
        Err(e) => Err(fail(e)),
    }
}
