//! Past one machine: `rayoflight split` (regions of even cost, one a
//! line), `rayoflight assemble` (parts back into the image, checked) and
//! `rayoflight sheet` (a sweep's renders side by side). The work is the
//! library's ([`rayoflight::cluster::split`], [`rayoflight::cluster::assemble`],
//! [`rayoflight::cluster::sheet`]); this edge reads files and words failures.
//!
//! The three subcommands' flags, as clap reads them, are here too
//! ([`SplitFlags`], [`AssembleFlags`], [`SheetFlags`]), each a
//! [`Subcommand`].

use super::edit::{self, EditArg};
use super::failure::{Failure, fail, refused, usage};
use super::render::RenderOf;
use super::stdout;
use super::subcommand::Subcommand;
use super::usage::UsageError;
use clap::Args;
use image::ImageFormat;
use rayoflight::cluster::{assemble, sheet, split};
use rayoflight::render::request::RenderRequest;
use rayoflight::scene::edit::Edited;
use rayoflight::system::{files, resources};
use rayoflight::{output, scene};
use std::path::{Path, PathBuf};

/// `split scene.xml --tasks N`: the regions on stdout, one a line.
fn split(args: &SplitArgs) -> Result<(), Failure> {
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
    stdout::line(&lines.join("\n"))
}

/// `assemble -out image.png PART…`.
fn assemble(out: &Path, parts: &[PathBuf]) -> Result<(), Failure> {
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
fn sheet(out: &Path, columns: Option<usize>, images: &[PathBuf]) -> Result<(), Failure> {
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

/// N regions of the image, one a line, of even estimated cost.
///
/// Each line is X0,Y0,X1,Y1 (pixels, X1 and Y1 excluded): give it to
/// `rayoflight scene.xml --region X0,Y0,X1,Y1 -out part-I.png`, one
/// task a line (a Slurm array, xargs -P, GNU parallel), then put the
/// parts together with `rayoflight assemble`. The regions are balanced
/// by cost, not area: a coarse pre-pass traces a few rays in each cell
/// of a grid over the image and counts the rays each costs, reflections
/// included; cuts follow the render's 32-pixel tiles where they can.
/// Give the render's --set, --aa and --method: they change the cost.
#[derive(Args, Debug)]
#[command(
    override_usage = "rayoflight split scene.xml --tasks N [--set PATH=VALUE]… [--aa N] \
                      [--method NAME]"
)]
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

impl Subcommand for SplitFlags {
    type Args = SplitArgs;

    /// The split asked for, its edits read against the scene's path.
    fn resolve(self, _: &clap::ArgMatches) -> Result<SplitArgs, UsageError> {
        let (request, edits) = self.render.resolve(&self.scene)?;
        Ok(SplitArgs {
            scene: self.scene,
            tasks: self.tasks,
            request,
            edits,
        })
    }

    fn prints(_: &SplitArgs) -> bool {
        true
    }

    fn run(args: SplitArgs, _: fn() -> clap::Command) -> Result<(), Failure> {
        split(&args)
    }
}

/// Put the parts that --region wrote together into the full image.
///
/// The image is the same file a render of the whole writes, byte for
/// byte. Every part's PNG records where it belongs, the full image's
/// size and a fingerprint of the scene and render options: assemble
/// refuses, naming the culprit, a file that is not a part, parts of
/// other scenes, options or versions, overlapping parts, pixels no
/// part holds (a missing part), a region outside the image. Rows are
/// streamed: only the parts crossing a row are open, so memory holds a
/// few rows, never the image.
#[derive(Args, Debug, Clone, PartialEq)]
#[command(override_usage = "rayoflight assemble -out image.png PART.png…")]
pub(super) struct AssembleFlags {
    /// The image to write (PNG).
    #[arg(short, long, value_name = "FILE", required = true)]
    pub(super) out: PathBuf,
    /// The parts, in any order.
    #[arg(value_name = "PART", required = true)]
    pub(super) parts: Vec<PathBuf>,
}

impl Subcommand for AssembleFlags {
    type Args = AssembleFlags;

    fn resolve(self, _: &clap::ArgMatches) -> Result<AssembleFlags, UsageError> {
        Ok(self)
    }

    fn prints(_: &AssembleFlags) -> bool {
        false
    }

    fn run(args: AssembleFlags, _: fn() -> clap::Command) -> Result<(), Failure> {
        assemble(&args.out, &args.parts)
    }
}

/// A contact sheet: the images side by side in a grid, each named.
///
/// Each picture sits in a cell as large as the largest, its file name
/// (its end, when too long) under it: the renders of a --set sweep at
/// a glance.
#[derive(Args, Debug, Clone, PartialEq)]
#[command(override_usage = "rayoflight sheet -out sheet.png [--columns N] IMAGE…")]
pub(super) struct SheetFlags {
    /// The sheet to write; its extension picks the format.
    #[arg(short, long, value_name = "FILE", required = true)]
    pub(super) out: PathBuf,
    /// Pictures a row [default: as square a grid as the count allows]
    #[arg(long, value_name = "N", value_parser = columns, allow_hyphen_values = true)]
    pub(super) columns: Option<usize>,
    /// The images, in the order to show them.
    #[arg(value_name = "IMAGE", required = true)]
    pub(super) images: Vec<PathBuf>,
}

impl Subcommand for SheetFlags {
    type Args = SheetFlags;

    fn resolve(self, _: &clap::ArgMatches) -> Result<SheetFlags, UsageError> {
        Ok(self)
    }

    fn prints(_: &SheetFlags) -> bool {
        false
    }

    fn run(args: SheetFlags, _: fn() -> clap::Command) -> Result<(), Failure> {
        sheet(&args.out, args.columns, &args.images)
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
