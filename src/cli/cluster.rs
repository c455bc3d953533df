//! Past one machine: `rayoflight split` (regions of even cost, one a
//! line), `rayoflight assemble` (parts back into the image, checked) and
//! `rayoflight sheet` (a sweep's renders side by side). The work is the
//! library's ([`rayoflight::split`], [`rayoflight::assemble`],
//! [`rayoflight::sheet`]); this edge reads files and words failures.

use super::args::SplitArgs;
use super::args::UsageError;
use super::{Failure, edit, fail, print_line, refused, usage};
use image::ImageFormat;
use rayoflight::scene::edit::Edited;
use rayoflight::{assemble, files, output, scene, sheet, split};
use std::path::{Path, PathBuf};

/// `split scene.xml --tasks N`: the regions on stdout, one a line.
pub fn split(args: &SplitArgs) -> Result<(), Failure> {
    let mut edited = Edited::new(scene::load(&args.scene).map_err(fail)?);
    edit::apply(&mut edited, &args.edits).map_err(refused(&args.scene))?;
    let scene = edited.scene();
    let options = args.request.options(scene);
    let regions = split::plan(scene, &options, args.tasks).map_err(|e| {
        Failure::Usage(UsageError::Invalid {
            message: format!("{}: {e}", args.scene.display()),
            command: Some("split"),
        })
    })?;
    let lines: Vec<String> = regions.iter().map(ToString::to_string).collect();
    print_line(&lines.join("\n"))
}

/// `assemble -out image.png PART…`.
pub fn assemble(out: &Path, parts: &[PathBuf]) -> Result<(), Failure> {
    if output::format_for(out).ok() != Some(ImageFormat::Png) {
        return Err(usage(format!(
            "{}: assemble writes a PNG (streamed a row at a time): -out must end in .png",
            out.display()
        )));
    }
    // A signal stops the assembly between two rows, its temporary file
    // removed (the default action would leave it behind).
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    #[cfg(unix)]
    for signal in [
        signal_hook::consts::SIGINT,
        signal_hook::consts::SIGTERM,
        signal_hook::consts::SIGHUP,
    ] {
        signal_hook::flag::register(signal, std::sync::Arc::clone(&stop)).map_err(fail)?;
    }
    assemble::assemble_until(parts, out, &stop).map_err(fail)?;
    Ok(())
}

/// `sheet -out sheet.png [--columns N] IMAGE…`: each image named by its
/// file name without the extension.
pub fn sheet(out: &Path, columns: Option<usize>, images: &[PathBuf]) -> Result<(), Failure> {
    output::format_for(out).map_err(fail)?;
    // The folder takes the sheet, checked before any image is read; its
    // size is checked once it is known.
    output::check_file_target(out).map_err(fail)?;
    if let Some(image) = images.iter().find(|i| files::same_file(i, out)) {
        return Err(Failure::Error(format!(
            "{}: is one of the images: the sheet cannot be written over it",
            image.display()
        )));
    }
    let pictures = images
        .iter()
        .map(|path| {
            // A FIFO or a device is never opened: it could block for ever.
            if let Some(kind) = std::fs::metadata(path)
                .ok()
                .and_then(|m| files::special_kind(&m))
            {
                return Err(Failure::Error(format!(
                    "{}: is {kind}, not an image",
                    path.display()
                )));
            }
            let picture = image::open(path)
                .map_err(|e| Failure::Error(format!("{}: {e}", path.display())))?;
            let name = path.file_stem().map_or_else(
                || path.display().to_string(),
                |s| s.to_string_lossy().into_owned(),
            );
            Ok((name, picture.to_rgb8()))
        })
        .collect::<Result<Vec<_>, Failure>>()?;
    let sheet = sheet::contact_sheet(&pictures, columns).map_err(fail)?;
    output::check_target(out, sheet.width(), sheet.height()).map_err(fail)?;
    output::save(&sheet, out).map_err(fail)
}
