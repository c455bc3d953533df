//! Past one machine: `rayoflight split` (regions of even cost, one a
//! line), `rayoflight assemble` (parts back into the image, checked) and
//! `rayoflight sheet` (a sweep's renders side by side). The work is the
//! library's ([`rayoflight::cluster::split`], [`rayoflight::cluster::assemble`],
//! [`rayoflight::cluster::sheet`]); this edge reads files and words failures.
//!
//! The three subcommands' flags, as clap reads them, are here too
//! ([`SplitFlags`], [`AssembleFlags`], [`SheetFlags`]), each resolved into
//! the [`Command`] it asks for.

use super::args::error::UsageError;
use super::args::render::RenderOf;
use super::edit::EditArg;
use super::{Failure, edit, fail, print_line, refused, usage};
use clap::Args;
use image::ImageFormat;
use rayoflight::cluster::{assemble, sheet, split};
use rayoflight::render::request::RenderRequest;
use rayoflight::scene::edit::Edited;
use rayoflight::system::{files, resources};
use rayoflight::{output, scene};
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
    let _cleanly = rayoflight::system::interrupt::cleanly();
    assemble::assemble_until(parts, out, rayoflight::system::interrupt::flag()).map_err(fail)?;
    Ok(())
}

/// `sheet -out sheet.png [--columns N] IMAGE…`: each image named by its
/// file name without the extension. Every image's size is read from its
/// header first, and refused past a render's own limit
/// ([`scene::MAX_PIXELS`]); the sheet's size and the memory it needs are
/// checked before anything is decoded; then the images are decoded one at
/// a time, each dropped once placed.
pub fn sheet(out: &Path, columns: Option<usize>, images: &[PathBuf]) -> Result<(), Failure> {
    // A signal stops it between two images (or in the write), saying so,
    // as every other command: the default action ended it silently.
    let _cleanly = rayoflight::system::interrupt::cleanly();
    let interrupted = || {
        fail(files::WriteError::Interrupted {
            path: out.to_owned(),
        })
    };
    output::format_for(out).map_err(fail)?;
    // The folder takes the sheet, checked before any image is read; its
    // size is checked once it is known.
    files::check_file_target(out).map_err(fail)?;
    if let Some(image) = images.iter().find(|i| files::same_file(i, out)) {
        return Err(Failure::Error(format!(
            "{}: is one of the images: the sheet cannot be written over it",
            image.display()
        )));
    }
    let headers = images
        .iter()
        .map(|path| match rayoflight::system::interrupt::requested() {
            true => Err(interrupted()),
            false => SheetImage::read(path),
        })
        .collect::<Result<Vec<_>, Failure>>()?;
    let sizes: Vec<(u32, u32)> = headers.iter().map(|h| h.size).collect();
    let layout = sheet::Layout::new(&sizes, columns).map_err(fail)?;
    output::check_target(out, layout.width, layout.height).map_err(fail)?;
    // The sheet, the largest image decoded and in 8-bit RGB, and the
    // file where its format is encoded in memory.
    let format = output::format_for(out).map_err(fail)?;
    let encoded = output::bytes_to_render(format, None, layout.width, layout.height)
        .saturating_sub(layout.bytes());
    let largest = headers.iter().map(|h| h.bytes).max().unwrap_or(0);
    let needed = layout.bytes() + largest.max(encoded);
    resources::check_memory(needed).map_err(|e| {
        Failure::Error(format!(
            "{}: the {}×{} contact sheet {e}",
            out.display(),
            layout.width,
            layout.height
        ))
    })?;
    let names: Vec<&str> = headers.iter().map(|h| h.name.as_str()).collect();
    let sheet = sheet::draw(&layout, &names, |k| {
        if rayoflight::system::interrupt::requested() {
            return Err(interrupted());
        }
        headers[k].decode().map(std::borrow::Cow::Owned)
    })?;
    if rayoflight::system::interrupt::requested() {
        return Err(interrupted());
    }
    output::save(&sheet, out).map_err(fail)
}

impl From<sheet::SheetError> for Failure {
    fn from(e: sheet::SheetError) -> Failure {
        fail(e)
    }
}

/// An image for the sheet, its header read.
struct SheetImage<'a> {
    path: &'a Path,
    name: String,
    size: (u32, u32),
    /// Bytes decoding it takes: its pixels as decoded, and in 8-bit RGB.
    bytes: u64,
}

impl<'a> SheetImage<'a> {
    /// The decoder's limits: any image of up to a render's pixels, in
    /// any of its formats (16 bytes a pixel at most: RGBA in f32).
    fn limits() -> image::Limits {
        let mut limits = image::Limits::default();
        limits.max_image_width = None;
        limits.max_image_height = None;
        limits.max_alloc = Some(scene::MAX_PIXELS * 16);
        limits
    }

    fn decoder(path: &Path) -> Result<impl image::ImageDecoder, Failure> {
        let error = |e: &dyn std::fmt::Display| Failure::Error(format!("{}: {e}", path.display()));
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
        let mut reader = image::ImageReader::open(path).map_err(|e| error(&e))?;
        reader.limits(SheetImage::limits());
        reader.into_decoder().map_err(|e| error(&e))
    }

    /// The image's name and size, from its header alone.
    fn read(path: &'a Path) -> Result<SheetImage<'a>, Failure> {
        use image::ImageDecoder;
        let decoder = SheetImage::decoder(path)?;
        let (width, height) = decoder.dimensions();
        let pixels = u64::from(width) * u64::from(height);
        if pixels > scene::MAX_PIXELS {
            return Err(Failure::Error(format!(
                "{}: a {width}×{height} image has more than the {} pixels (2^28) a render may have",
                path.display(),
                scene::MAX_PIXELS
            )));
        }
        let rgb8 = decoder.color_type() == image::ColorType::Rgb8;
        let bytes = decoder.total_bytes() + if rgb8 { 0 } else { 3 * pixels };
        let name = path.file_stem().map_or_else(
            || path.display().to_string(),
            |s| s.to_string_lossy().into_owned(),
        );
        Ok(SheetImage {
            path,
            name,
            size: (width, height),
            bytes,
        })
    }

    /// The picture in 8-bit RGB.
    fn decode(&self) -> Result<image::RgbImage, Failure> {
        use image::ImageDecoder;
        let path = self.path;
        let decoder = SheetImage::decoder(path)?;
        if decoder.dimensions() != self.size {
            return Err(Failure::Error(format!(
                "{}: changed while the sheet was drawn",
                path.display()
            )));
        }
        let picture = image::DynamicImage::from_decoder(decoder)
            .map_err(|e| Failure::Error(format!("{}: {e}", path.display())))?;
        Ok(picture.into_rgb8())
    }
}

// ----- the command line -----

/// `rayoflight split`: which render to split, into how many regions.
#[derive(Debug, Clone, PartialEq)]
pub struct SplitArgs {
    pub scene: PathBuf,
    pub tasks: usize,
    /// The render's method and anti-aliasing (they change the cost).
    pub request: RenderRequest,
    /// `--set`: values changed in memory first, in order.
    pub edits: Vec<EditArg>,
}

// `rayoflight split`'s flags, as clap reads them (a plain comment:
// a doc comment here would be clap's help text).
#[derive(Args, Debug)]
pub(super) struct SplitFlags {
    /// The scene file.
    scene: PathBuf,
    /// How many regions (tasks), at least 1.
    #[arg(
        long,
        short = 'n',
        value_name = "N",
        value_parser = tasks,
        required = true,
        allow_hyphen_values = true
    )]
    tasks: usize,
    #[command(flatten)]
    render: RenderOf,
}

impl SplitFlags {
    /// The split asked for, its edits read against the scene's path.
    pub(super) fn resolve(self) -> Result<SplitArgs, UsageError> {
        let (request, edits) = self.render.resolve(&self.scene)?;
        Ok(SplitArgs {
            scene: self.scene,
            tasks: self.tasks,
            request,
            edits,
        })
    }
}

// `rayoflight assemble`'s flags, as clap reads them (a plain comment:
// a doc comment here would be clap's help text).
#[derive(Args, Debug)]
pub(super) struct AssembleFlags {
    /// The image to write (PNG).
    #[arg(short, long, value_name = "FILE", required = true)]
    out: PathBuf,
    /// The parts, in any order.
    #[arg(value_name = "PART", required = true)]
    parts: Vec<PathBuf>,
}

impl AssembleFlags {
    /// The image to write and the parts, in the order given.
    pub(super) fn resolve(self) -> (PathBuf, Vec<PathBuf>) {
        (self.out, self.parts)
    }
}

// `rayoflight sheet`'s flags, as clap reads them (a plain comment:
// a doc comment here would be clap's help text).
#[derive(Args, Debug)]
pub(super) struct SheetFlags {
    /// The sheet to write; its extension picks the format.
    #[arg(short, long, value_name = "FILE", required = true)]
    out: PathBuf,
    /// Pictures a row [default: as square a grid as the count allows]
    #[arg(long, value_name = "N", value_parser = columns, allow_hyphen_values = true)]
    columns: Option<usize>,
    /// The images, in the order to show them.
    #[arg(value_name = "IMAGE", required = true)]
    images: Vec<PathBuf>,
}

impl SheetFlags {
    /// The sheet to write, its columns, the images in the order given.
    pub(super) fn resolve(self) -> (PathBuf, Option<usize>, Vec<PathBuf>) {
        (self.out, self.columns, self.images)
    }
}

fn tasks(text: &str) -> Result<usize, String> {
    text.trim()
        .parse()
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| "expects a whole number of tasks, at least 1".to_owned())
}

fn columns(text: &str) -> Result<usize, String> {
    text.trim()
        .parse()
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| "expects a whole number, at least 1".to_owned())
}
