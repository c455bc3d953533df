//! Writing images: the format follows the file's extension, and files are
//! written atomically (a temporary file in the target directory, renamed
//! into place), so a failure never leaves a partial file nor touches an
//! existing one. [`write_atomic_with`] is every file's one way out: the
//! path walked to a folder held by its descriptor, links in every part
//! followed only as the kernel would for another user's link
//! ([`crate::system::files::Place`]), the file in the way opened once and
//! compared with what was checked, a file the caller may not write
//! refused, a replaced file's owner, group, mode and extended attributes
//! kept, a file of several hard links updated in place through the
//! descriptor that was checked, as a transaction a crash cannot leave
//! half done ([`crate::system::files::rewrite_in_place`]), and a signal ([`crate::system::interrupt`])
//! stopping it with the temporary file removed. Nothing is written
//! through a path once its folder is held: renaming names meanwhile can
//! make a write fail ([`OutputError::Moved`]), never land elsewhere.

use crate::cluster::part::Part;
use crate::render::{KeptPass, Pass, PassForm, PassImage, PassPixels};
use crate::system::files::{Kind, Place, PlaceError};
use image::codecs::jpeg::JpegEncoder;
use image::{ImageFormat, RgbImage};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// JPEG quality used for `.jpg` / `.jpeg`.
pub const JPEG_QUALITY: u8 = 95;

/// Pixels the GIF palette is learned from, at most (spread evenly over
/// the image).
const GIF_SAMPLE: usize = 1 << 18;

/// Extensions that can be written, lower case, and their formats.
pub const SUPPORTED: &[(&str, ImageFormat)] = &[
    ("png", ImageFormat::Png),
    ("jpg", ImageFormat::Jpeg),
    ("jpeg", ImageFormat::Jpeg),
    ("gif", ImageFormat::Gif),
    ("bmp", ImageFormat::Bmp),
    ("tga", ImageFormat::Tga),
    ("ppm", ImageFormat::Pnm),
    ("tif", ImageFormat::Tiff),
    ("tiff", ImageFormat::Tiff),
    ("qoi", ImageFormat::Qoi),
    ("webp", ImageFormat::WebP),
    ("exr", ImageFormat::OpenExr),
];

/// Why an image or file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{}: unknown image extension {ext:?}; supported: {}", path.display(), supported_list())]
    UnknownExtension { path: PathBuf, ext: String },
    #[error("{}: no file extension to choose the image format; supported: {}", path.display(), supported_list())]
    NoExtension { path: PathBuf },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: cannot encode the image: {}", path.display(), one_line(source))]
    Encode {
        path: PathBuf,
        source: image::ImageError,
    },
    #[error("the output file name is empty")]
    EmptyName,
    #[error("{}: is {kind}, not an image file", path.display())]
    Special { path: PathBuf, kind: &'static str },
    #[error("{}: is a directory, not a file", path.display())]
    IsDirectory { path: PathBuf },
    #[error("{}: the folder {} does not exist", path.display(), folder.display())]
    NoFolder { path: PathBuf, folder: PathBuf },
    #[error("{}: {} is not a folder", path.display(), folder.display())]
    NotAFolder { path: PathBuf, folder: PathBuf },
    #[error("{}: cannot write in the folder {}: {source}", path.display(), folder.display())]
    FolderNotWritable {
        path: PathBuf,
        folder: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: the file is read-only", path.display())]
    ReadOnly { path: PathBuf },
    #[error("{}: permission denied: you may not write this file", path.display())]
    NotWritable { path: PathBuf },
    #[error("{}: {source}", path.display())]
    Link {
        path: PathBuf,
        source: crate::system::files::LinkError,
    },
    #[error("{}: interrupted: nothing was written", path.display())]
    Interrupted { path: PathBuf },
    #[error("{}: already exists; nothing was written", path.display())]
    Exists { path: PathBuf },
    /// The name was given to another file between the look at it and
    /// the write (another program, or another user racing renames).
    #[error(
        "{}: another program replaced the file while it was written; nothing was written",
        path.display()
    )]
    Moved { path: PathBuf },
    #[error(
        "{}: {format} cannot hold a {width}×{height} image ({})",
        path.display(),
        limit
    )]
    TooLarge {
        path: PathBuf,
        format: &'static str,
        width: u32,
        height: u32,
        limit: &'static str,
    },
}

/// A message on one line: an encoder's own message may span several.
fn one_line(e: &impl std::fmt::Display) -> String {
    e.to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// The largest image a format holds: pixels a side, pixels in all, and how
/// to say it.
fn limits(format: ImageFormat) -> (u32, u64, &'static str) {
    match format {
        ImageFormat::Jpeg => (65_535, u64::MAX, "at most 65535 pixels a side"),
        ImageFormat::Gif => (65_535, u64::MAX, "at most 65535 pixels a side"),
        ImageFormat::Tga => (65_535, u64::MAX, "at most 65535 pixels a side"),
        ImageFormat::WebP => (16_383, u64::MAX, "at most 16383 pixels a side"),
        ImageFormat::Qoi => (u32::MAX, 400_000_000, "at most 400 million pixels"),
        // Classic TIFF addresses 4 GiB: 3 bytes a pixel and some room.
        ImageFormat::Tiff => (
            u32::MAX,
            1_400_000_000,
            "at most 1.4 billion pixels (4 GiB)",
        ),
        ImageFormat::Bmp => (
            i32::MAX as u32,
            1_400_000_000,
            "at most 1.4 billion pixels (4 GiB)",
        ),
        // PNG allows 2^31 - 1 a side.
        _ => (
            i32::MAX as u32,
            u64::MAX,
            "at most 2147483647 pixels a side",
        ),
    }
}

/// Checks, before any rendering, that a `width × height` image can be
/// written to `path`: a name with a known extension, a format that holds
/// that size, a folder that exists and takes new files, and no directory,
/// special file or read-only file in the way. Returns the format.
///
/// The folder is tried by creating and removing an empty temporary file in
/// it: the only test that holds for every file system and every user.
pub fn check_target(path: &Path, width: u32, height: u32) -> Result<ImageFormat, OutputError> {
    if path.as_os_str().is_empty() {
        return Err(OutputError::EmptyName);
    }
    let format = format_for(path)?;
    let (max_side, max_pixels, limit) = limits(format);
    if width > max_side || height > max_side || u64::from(width) * u64::from(height) > max_pixels {
        return Err(OutputError::TooLarge {
            path: path.to_owned(),
            format: format
                .extensions_str()
                .first()
                .copied()
                .unwrap_or("this format"),
            width,
            height,
            limit,
        });
    }
    // A device or a pipe would be written directly: never an image.
    let place = place(path)?;
    if let Some((_, meta)) = in_the_way(path, &place)?
        && let Some(kind) = crate::system::files::special_kind(&meta)
    {
        // Through /dev/stdout or /proc/self/fd/N: the shell's pipe.
        let kind = if kind == "a FIFO" && place.is_magic() {
            "a pipe"
        } else {
            kind
        };
        return Err(OutputError::Special {
            path: path.to_owned(),
            kind,
        });
    }
    check_file_target(path)?;
    Ok(format)
}

/// [`check_target`] for a file of any kind (a CSV, a scene), before the
/// work that makes it: a name, links that may be followed, a folder that
/// exists and takes new files, no directory, read-only file or file the
/// caller may not write in the way. An existing device or pipe
/// (`/dev/stdout`) passes: [`write_atomic`] writes into it. Errors name
/// `path` as given.
pub fn check_file_target(path: &Path) -> Result<(), OutputError> {
    if path.as_os_str().is_empty() {
        return Err(OutputError::EmptyName);
    }
    let place = place(path)?;
    in_the_way(path, &place)?;
    let _cleanly = crate::system::interrupt::cleanly();
    place
        .new_file(".rayoflight-", ".tmp")
        .map(drop)
        .map_err(|source| OutputError::FolderNotWritable {
            path: path.to_owned(),
            folder: place.folder_path().to_owned(),
            source,
        })
}

/// The supported extensions, comma separated, for messages.
pub fn supported_list() -> String {
    SUPPORTED
        .iter()
        .map(|(ext, _)| *ext)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The image format for a path, from its extension (case-insensitive).
pub fn format_for(path: &Path) -> Result<ImageFormat, OutputError> {
    let ext = path
        .extension()
        .ok_or_else(|| OutputError::NoExtension {
            path: path.to_owned(),
        })?
        .to_string_lossy()
        .to_ascii_lowercase();
    SUPPORTED
        .iter()
        .find(|(e, _)| *e == ext)
        .map(|(_, f)| *f)
        .ok_or(OutputError::UnknownExtension {
            path: path.to_owned(),
            ext,
        })
}

/// Encodes `image` in the format of `path`'s extension and writes it
/// atomically.
pub fn save(image: &RgbImage, path: &Path) -> Result<(), OutputError> {
    let format = format_for(path)?;
    if format == ImageFormat::Png {
        return save_png(image, &[], path);
    }
    if format == ImageFormat::OpenExr {
        // Each channel value / 255, as `image` converts 8 bits to floats.
        let (width, raw) = (image.width() as usize, image.as_raw());
        return save_exr(path, image.width(), image.height(), |x, y| {
            let i = 3 * (y * width + x);
            [0, 1, 2].map(|c| f32::from(raw[i + c]) / 255.0)
        });
    }
    let encoded = encode(image, format).map_err(|source| OutputError::Encode {
        path: path.to_owned(),
        source,
    })?;
    write_atomic(path, &encoded)
}

/// Writes a part of a render (`--region`) as a PNG that records where it
/// belongs ([`crate::cluster::part`]).
pub fn save_part(image: &RgbImage, part: &Part, path: &Path) -> Result<(), OutputError> {
    save_png(
        image,
        &[(crate::cluster::part::KEYWORD, &part.to_string())],
        path,
    )
}

/// Writes `image` as a PNG with `texts` (keyword, text) in tEXt chunks
/// before its pixels, atomically. Every PNG the project writes goes
/// through [`write_png`]: a render saved whole and the same image put
/// together from parts by `assemble` are the same file, byte for byte.
pub fn save_png(image: &RgbImage, texts: &[(&str, &str)], path: &Path) -> Result<(), OutputError> {
    write_atomic_with(
        path,
        |w| {
            let mut rows = image.as_raw().chunks_exact(image.width() as usize * 3);
            write_png(w, image.width(), image.height(), texts, |row| {
                row.copy_from_slice(rows.next().unwrap_or_default());
                Ok(())
            })
        },
        |_| Ok::<(), OutputError>(()),
    )
}

/// Writes a `width × height` PNG (8-bit RGB) into `w` a row at a time,
/// top to bottom, so that an image need never be in memory whole:
/// `next_row` fills each row (width × 3 bytes) in turn. `texts` (keyword,
/// text) go in Latin-1 tEXt chunks before the pixels. Compressed as
/// `image` writes PNG by default (fast deflate, adaptive filter).
pub fn write_png<W: Write>(
    w: W,
    width: u32,
    height: u32,
    texts: &[(&str, &str)],
    mut next_row: impl FnMut(&mut [u8]) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let mut encoder = png::Encoder::new(w, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::Filter::Adaptive);
    for (keyword, text) in texts {
        encoder
            .add_text_chunk((*keyword).to_owned(), (*text).to_owned())
            .map_err(std::io::Error::other)?;
    }
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    let mut stream = writer.stream_writer().map_err(std::io::Error::other)?;
    let mut row = vec![0; width as usize * 3];
    for _ in 0..height {
        next_row(&mut row)?;
        stream.write_all(&row)?;
    }
    stream.finish().map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)
}

/// Whether writing `pass` to `path` takes the passes' render (f64 values,
/// [`save_pass`]) rather than the 8-bit image ([`save`]): any pass but
/// `final`, and `final` too in an EXR (floats, unclamped).
pub fn takes_pass(pass: Pass, path: &Path) -> bool {
    pass != Pass::Final || format_for(path).is_ok_and(|f| f == ImageFormat::OpenExr)
}

/// Writes a render pass atomically: unclamped 32-bit floats in an EXR
/// (each value the pass's f64 rounded once), else its 8-bit picture
/// ([`PassImage::to_rgb8`]) in the format of the extension.
pub fn save_pass(pass: &PassImage, path: &Path) -> Result<(), OutputError> {
    if format_for(path)? != ImageFormat::OpenExr {
        return save(&pass.to_rgb8(), path);
    }
    let (width, values) = (pass.width as usize, &pass.values);
    save_exr(path, pass.width, pass.height, |x, y| {
        let i = 3 * (y * width + x);
        [0, 1, 2].map(|c| crate::render::in_exr(pass.pass, values[i + c]))
    })
}

/// Writes a pass rendered in the form of its file
/// ([`crate::render::render_pass_as`]): the same file as [`save_pass`]
/// of its whole image.
pub fn save_kept_pass(pass: &KeptPass, path: &Path) -> Result<(), OutputError> {
    match &pass.pixels {
        PassPixels::Picture(image) => save(image, path),
        PassPixels::Floats(image) => {
            let (width, values) = (image.width() as usize, image.as_raw());
            save_exr(path, image.width(), image.height(), |x, y| {
                let i = 3 * (y * width + x);
                [values[i], values[i + 1], values[i + 2]]
            })
        }
    }
}

/// The most memory rendering a `width × height` image for `path` takes,
/// in bytes, before any margin: the pixels as they are kept while the
/// render runs (the 8-bit image, or `pass`'s [`PassForm`] where the file
/// takes the passes' render, [`takes_pass`]), or those pixels and the
/// encoded file where the format is encoded in memory (PNG is written a
/// row at a time, EXR block by block). Checked against what the system
/// gives ([`crate::system::resources::check_memory`]) before the first ray.
pub fn bytes_to_render(format: ImageFormat, pass: Option<Pass>, width: u32, height: u32) -> u64 {
    let pixels = u64::from(width) * u64::from(height);
    let kept = match pass {
        Some(pass) => pixel_form(format).bytes_per_pixel(pass),
        None => 3,
    };
    let encoded = match format {
        ImageFormat::Png | ImageFormat::OpenExr => 0,
        // The indices and the file, and the table of every 24-bit colour.
        ImageFormat::Gif => 2 * pixels + (2 << 24),
        // At most about the pixels themselves.
        _ => 3 * pixels,
    };
    // A depth picture's 8 bytes become its 3 before it is encoded.
    (kept * pixels).max(3 * pixels + encoded)
}

/// The form a pass is rendered in for a file of `format`: floats for an
/// EXR, the 8-bit picture for the rest.
pub fn pixel_form(format: ImageFormat) -> PassForm {
    if format == ImageFormat::OpenExr {
        PassForm::Floats
    } else {
        PassForm::Picture
    }
}

/// Writes a `width × height` EXR of `pixel(x, y)` (RGB, f32) atomically,
/// with no copy of the image: the exr crate's writer (RLE in 64×64 tiles,
/// the file `image` itself writes) pulls each pixel as it encodes. It
/// seeks back to its table of offsets at the end, so it writes into a
/// scratch file beside the output (unnamed, gone with the process
/// whatever happens), which is then copied into place
/// ([`write_atomic_with`]): the encoded image is never in memory either.
pub fn save_exr(
    path: &Path,
    width: u32,
    height: u32,
    pixel: impl Fn(usize, usize) -> [f32; 3] + Sync,
) -> Result<(), OutputError> {
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    use std::io::{Seek, SeekFrom};
    let io_error = |source| OutputError::Io {
        path: path.to_owned(),
        source,
    };
    let mut scratch = scratch_file(path).map_err(io_error)?;
    let image = Image::from_channels(
        (width as usize, height as usize),
        SpecificChannels::rgb(|at: Vec2<usize>| {
            let [r, g, b] = pixel(at.x(), at.y());
            (r, g, b)
        }),
    );
    {
        let mut w = BufWriter::new(&mut scratch);
        let written = image.write().to_buffered(&mut w).map_err(|e| match e {
            exr::error::Error::Io(source) => io_error(source),
            other => OutputError::Encode {
                path: path.to_owned(),
                source: image::ImageError::Encoding(image::error::EncodingError::new(
                    ImageFormat::OpenExr.into(),
                    other,
                )),
            },
        });
        written?;
        w.flush().map_err(io_error)?;
    }
    scratch.seek(SeekFrom::Start(0)).map_err(io_error)?;
    write_atomic_with(
        path,
        |w| std::io::copy(&mut scratch, w).map(drop),
        |_| Ok::<(), OutputError>(()),
    )
}

/// An unnamed scratch file for writing `path`: in its folder (the disk
/// it is going to, where `check_target` found room for a new file), or
/// the system's temporary folder where that cannot hold one (a device).
fn scratch_file(path: &Path) -> std::io::Result<std::fs::File> {
    let in_folder = Place::reach(path).ok().and_then(|place| {
        let regular = place
            .look()
            .ok()?
            .is_none_or(|(kind, _)| kind == Kind::Regular);
        regular.then(|| place.unnamed_file()).flatten()
    });
    match in_folder {
        Some(file) => Ok(file),
        None => tempfile::tempfile(),
    }
}

/// The image encoded in memory (JPEG at [`JPEG_QUALITY`]; an 8-bit image
/// in EXR as floats, each channel value / 255).
pub fn encode(image: &RgbImage, format: ImageFormat) -> Result<Vec<u8>, image::ImageError> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    if format == ImageFormat::OpenExr {
        image::DynamicImage::ImageRgb8(image.clone())
            .into_rgb32f()
            .write_to(&mut bytes, format)?;
    } else if format == ImageFormat::Jpeg {
        image.write_with_encoder(JpegEncoder::new_with_quality(&mut bytes, JPEG_QUALITY))?;
    } else if format == ImageFormat::Gif {
        return encode_gif(image);
    } else {
        image.write_to(&mut bytes, format)?;
    }
    Ok(bytes.into_inner())
}

/// A GIF of `image`: a 256-colour palette learned by NeuQuant from at most
/// [`GIF_SAMPLE`] pixels, each distinct colour of the image mapped to it
/// once (a table of every 24-bit colour), and the indices LZW-coded.
///
/// `image`'s own GIF encoder learns from every pixel and searches the
/// palette for every pixel: 37 s for a 4096² render that PNG writes in
/// 0.3 s. Learning at NeuQuant's finest (every sample used) from a quarter
/// of a million pixels gives a palette as close as `image`'s at its best
/// (tested), in a few times PNG's time.
fn encode_gif(image: &RgbImage) -> Result<Vec<u8>, image::ImageError> {
    let gif_error = |e: gif::EncodingError| {
        image::ImageError::Encoding(image::error::EncodingError::new(ImageFormat::Gif.into(), e))
    };
    let (w, h) = image.dimensions();
    let (Ok(width), Ok(height)) = (u16::try_from(w), u16::try_from(h)) else {
        return Err(image::ImageError::Limits(
            image::error::LimitError::from_kind(image::error::LimitErrorKind::DimensionError),
        ));
    };
    let pixels = image.as_raw();
    let count = pixels.len() / 3;
    let step = count.div_ceil(GIF_SAMPLE).max(1);
    let sample: Vec<u8> = pixels
        .chunks_exact(3)
        .step_by(step)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    let quant = color_quant::NeuQuant::new(1, 256, &sample);
    // The palette index of each 24-bit colour met so far (u16::MAX: not
    // yet looked up).
    let mut index = vec![u16::MAX; 1 << 24];
    let indices: Vec<u8> = pixels
        .chunks_exact(3)
        .map(|p| {
            let key = (usize::from(p[0]) << 16) | (usize::from(p[1]) << 8) | usize::from(p[2]);
            if index[key] == u16::MAX {
                index[key] = quant.index_of(&[p[0], p[1], p[2], 255]) as u16;
            }
            index[key] as u8
        })
        .collect();
    let mut bytes = Vec::new();
    {
        let mut encoder = gif::Encoder::new(&mut bytes, width, height, &quant.color_map_rgb())
            .map_err(gif_error)?;
        let frame = gif::Frame {
            width,
            height,
            buffer: std::borrow::Cow::Owned(indices),
            ..gif::Frame::default()
        };
        encoder.write_frame(&frame).map_err(gif_error)?;
    }
    Ok(bytes)
}

/// The place writing `path` goes ([`Place::reach`]), its errors naming
/// `path` as given.
fn place(path: &Path) -> Result<Place, OutputError> {
    Place::reach(path).map_err(|e| place_error(path, e))
}

/// Why `path` leads to no place to write, as an output error naming it.
fn place_error(path: &Path, e: PlaceError) -> OutputError {
    let path = path.to_owned();
    match e {
        PlaceError::Link(source) => OutputError::Link { path, source },
        PlaceError::NoFolder(folder) => OutputError::NoFolder { path, folder },
        PlaceError::NotAFolder(folder) => OutputError::NotAFolder { path, folder },
        PlaceError::IsDirectory => OutputError::IsDirectory { path },
        PlaceError::Io(source) => OutputError::Io { path, source },
    }
}

/// What is in the way of writing at `place` (where `path` leads): nothing
/// (`None`), or an existing file the caller may replace or a special file
/// to write into (what it is). A directory, a read-only file and a file
/// the caller may not write are refused, naming `path`; so is a link that
/// appeared since the walk followed the one there.
fn in_the_way(
    path: &Path,
    place: &Place,
) -> Result<Option<(Kind, std::fs::Metadata)>, OutputError> {
    let seen = place.look().map_err(|source| OutputError::Io {
        path: path.to_owned(),
        source,
    })?;
    let Some((kind, meta)) = seen else {
        return Ok(None);
    };
    let path = path.to_owned();
    match kind {
        Kind::Directory => return Err(OutputError::IsDirectory { path }),
        Kind::Link => return Err(OutputError::Moved { path }),
        // Renaming over a file ignores the file's own permissions: refuse
        // what writing into it would refuse (for root too, a file without
        // any write bit).
        Kind::Regular if meta.permissions().readonly() => {
            return Err(OutputError::ReadOnly { path });
        }
        Kind::Regular if !place.may_write() => return Err(OutputError::NotWritable { path }),
        Kind::Regular | Kind::Special => {}
    }
    Ok(Some((kind, meta)))
}

/// Writes `bytes` to `path` through a temporary file in the same directory,
/// synced, then renamed over `path`. On any failure the temporary file is
/// removed and an existing `path` is left as it was. A symbolic link is
/// followed (as [`Place::reach`] allows): the file it points to is
/// replaced, the link is kept.
///
/// An existing path that is not a regular file (`/dev/stdout`, a FIFO,
/// `/dev/full`) is written directly: renaming over it would replace the
/// device or pipe itself.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_atomic_with(path, |w| w.write_all(bytes), |_| Ok(()))
}

/// Writes `bytes` to a new file at `path`, never over anything there (a
/// file, a link, even a dangling one): [`OutputError::Exists`]. The file
/// is created empty, filled and synced; on a failure it is removed.
pub fn write_new(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let io_error = |source: std::io::Error| OutputError::Io {
        path: path.to_owned(),
        source,
    };
    if path.as_os_str().is_empty() {
        return Err(OutputError::EmptyName);
    }
    let place = Place::reach_name(path).map_err(|e| place_error(path, e))?;
    let _cleanly = crate::system::interrupt::cleanly();
    let mut new = match place.create_new() {
        Ok(new) => new,
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            return Err(OutputError::Exists {
                path: path.to_owned(),
            });
        }
        Err(e) => return Err(io_error(e)),
    };
    // Dropped on a failure: the new file is removed.
    new.file
        .write_all(bytes)
        .and_then(|()| new.file.sync_all())
        .map_err(io_error)?;
    new.keep();
    Ok(())
}

/// How many times a write looks at and opens a name that another program
/// keeps replacing between the two, before it gives up.
const MAX_TRIES: usize = 8;

/// [`write_atomic`] of what `write` streams, without the bytes in memory
/// at once. Before the new file replaces the old one, `check` is given a
/// path to read it back by (its descriptor's), and may refuse it: the
/// temporary file is removed and the old file left as it was. A path that
/// is not a regular file is written directly and not checked.
///
/// The file in the way is opened once, without following a link, and
/// must be the one that was looked at; just before it is replaced, its
/// name must still name it, and where there was no file none may have
/// appeared: else [`OutputError::Moved`], nothing written. A replaced
/// file keeps its owner and group (as far as the caller may give them),
/// its mode and its extended attributes. A file with several hard links
/// is not replaced but rewritten in place, through the descriptor that
/// was opened and checked, once the new bytes are complete and checked,
/// so that every name keeps showing the same file; a copy of the old
/// bytes (`.NAME.XXXXXX.rayoflight-backup`) waits beside it until then,
/// and stays, named in the error, if the rewrite fails and the old bytes
/// cannot be put back. A signal ([`crate::system::interrupt`]) stops the write
/// with [`OutputError::Interrupted`], nothing changed.
pub fn write_atomic_with<E: From<OutputError>>(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    check: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let io_error = |source: std::io::Error| {
        // The stop may come back wrapped by an encoder: a failure after a
        // signal is the signal's.
        if crate::system::interrupt::is_stop(&source) || crate::system::interrupt::requested() {
            OutputError::Interrupted {
                path: path.to_owned(),
            }
        } else {
            OutputError::Io {
                path: path.to_owned(),
                source,
            }
        }
    };
    let moved = || OutputError::Moved {
        path: path.to_owned(),
    };
    // From here a signal is recorded, not fatal: the temporary file must go.
    let _cleanly = crate::system::interrupt::cleanly();
    let place = place(path)?;
    // A rewrite of this file that a crash left half done, finished first.
    crate::system::files::finish_at(&place).map_err(io_error)?;
    // What killed writes left beside it (a save or render killed in the
    // middle leaves a temporary file as big as the file), removed.
    #[cfg(unix)]
    place.sweep(STALE_AFTER);
    let mut old = None;
    for _ in 0..MAX_TRIES {
        let Some((kind, meta)) = in_the_way(path, &place)? else {
            old = Some(None);
            break;
        };
        // Written through: a device or pipe, a file of several names, or
        // what a link of /proc stands for (the shell's redirection).
        let into = kind == Kind::Special || several_names(&meta) || place.is_magic();
        let opened = place
            .open(kind, &meta, into)
            .map_err(|e| match e.raw_os_error() {
                #[cfg(unix)]
                Some(libc::ENXIO) if kind == Kind::Special => {
                    io_error(std::io::Error::other("a FIFO that no program is reading"))
                }
                _ => io_error(e),
            })?;
        if let Some(file) = opened {
            old = Some(Some((kind, meta, file)));
            break;
        }
    }
    let Some(old) = old else {
        return Err(moved().into());
    };
    if let Some((kind, meta, file)) = &old
        && (*kind == Kind::Special || place.is_magic())
    {
        if meta.is_file() {
            file.set_len(0).map_err(io_error)?;
        }
        let mut w = crate::system::interrupt::Checked(file);
        write(&mut w).map_err(io_error)?;
        return Ok(w.flush().map_err(io_error)?);
    }
    let mut new = place.new_file(".rayoflight-", ".tmp").map_err(&io_error)?;
    if let Some((_, meta, file)) = &old {
        crate::system::files::keep_attributes(file, meta, &new.file).map_err(io_error)?;
    }
    {
        let mut w = BufWriter::new(crate::system::interrupt::Checked(&mut new.file));
        write(&mut w).map_err(io_error)?;
        w.flush().map_err(io_error)?;
    }
    new.file.sync_all().map_err(io_error)?;
    check(&new.path_to_read())?;
    if crate::system::interrupt::requested() {
        return Err(OutputError::Interrupted {
            path: path.to_owned(),
        }
        .into());
    }
    match old {
        Some((_, meta, mut file)) => {
            if !place.still_names(&file).map_err(io_error)? {
                return Err(moved().into());
            }
            if several_names(&meta) {
                crate::system::files::rewrite_in_place(&place, &mut file, &mut new)
                    .map_err(io_error)?;
            } else {
                new.rename_over(true).map_err(io_error)?;
            }
        }
        None => match new.rename_over(false) {
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => return Err(moved().into()),
            other => other.map_err(io_error)?,
        },
    }
    Ok(())
}

/// How long a temporary file no process holds locked must have been
/// left unchanged before a write beside it removes it: a writer locks its
/// file at once; this only covers the moment between making and locking.
#[cfg(unix)]
const STALE_AFTER: std::time::Duration = std::time::Duration::from_secs(2);

/// Whether the file has other hard links than the one being written.
fn several_names(meta: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        std::os::unix::fs::MetadataExt::nlink(meta) > 1
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> RgbImage {
        RgbImage::from_fn(7, 5, |x, y| image::Rgb([x as u8 * 30, y as u8 * 40, 200]))
    }

    #[test]
    fn every_supported_format_encodes() {
        for (ext, format) in SUPPORTED {
            let bytes = encode(&sample(), *format).unwrap_or_else(|e| panic!("{ext}: {e}"));
            let back = image::load_from_memory_with_format(&bytes, *format)
                .unwrap_or_else(|e| panic!("{ext}: {e}"))
                .to_rgb8();
            assert_eq!(back.dimensions(), (7, 5), "{ext}");
            if !matches!(format, ImageFormat::Jpeg | ImageFormat::Gif) {
                assert_eq!(back, sample(), "{ext} should be lossless");
            }
        }
    }

    #[test]
    fn an_exr_written_from_the_pixels_is_the_file_image_encodes() {
        // The pixels pulled by the encoder, the file streamed from a
        // scratch file: the same bytes as `image`'s in-memory encoding.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.exr");
        save(&sample(), &path).unwrap();
        let ours = std::fs::read(&path).unwrap();
        assert_eq!(ours, encode(&sample(), ImageFormat::OpenExr).unwrap());
        let pass = PassImage {
            pass: Pass::Depth,
            width: 3,
            height: 2,
            values: (0..18).map(|v| f64::from(v) * 0.1 + 1e-12).collect(),
        };
        save_pass(&pass, &path).unwrap();
        let mut theirs = std::io::Cursor::new(Vec::new());
        pass.to_rgb32f()
            .write_to(&mut theirs, ImageFormat::OpenExr)
            .unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), theirs.into_inner());
        // No scratch or temporary file is left beside it.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn the_memory_to_render_counts_what_each_format_holds() {
        let px = 1000 * 1000;
        let bytes = |f, p| bytes_to_render(f, p, 1000, 1000);
        assert_eq!(bytes(ImageFormat::Png, None), 3 * px);
        assert_eq!(bytes(ImageFormat::Bmp, None), 6 * px);
        assert_eq!(bytes(ImageFormat::Png, Some(Pass::Normal)), 3 * px);
        assert_eq!(bytes(ImageFormat::Png, Some(Pass::Depth)), 8 * px);
        assert_eq!(bytes(ImageFormat::OpenExr, Some(Pass::Final)), 12 * px);
        assert_eq!(bytes(ImageFormat::Gif, None), 5 * px + (2 << 24));
    }

    #[test]
    fn encoder_messages_are_one_line() {
        let e = OutputError::Encode {
            path: PathBuf::from("x.gif"),
            source: image::ImageError::IoError(std::io::Error::other("first\n  second")),
        };
        assert_eq!(
            e.to_string(),
            "x.gif: cannot encode the image: first second"
        );
    }

    #[test]
    fn a_gif_keeps_close_to_the_image() {
        // A smooth gradient of 60 000 colours in 256: about as close as
        // `image`'s own GIF encoder at its best quality (speed 1).
        let image = RgbImage::from_fn(300, 200, |x, y| {
            image::Rgb([(x * 255 / 299) as u8, (y * 255 / 199) as u8, 128])
        });
        let mean_error = |bytes: &[u8]| {
            let back = image::load_from_memory_with_format(bytes, ImageFormat::Gif)
                .unwrap()
                .to_rgb8();
            let sum: u64 = image
                .as_raw()
                .iter()
                .zip(back.as_raw())
                .map(|(a, b)| u64::from(a.abs_diff(*b)))
                .sum();
            sum as f64 / image.as_raw().len() as f64
        };
        let ours = mean_error(&encode(&image, ImageFormat::Gif).unwrap());
        let mut theirs = Vec::new();
        image
            .write_with_encoder(image::codecs::gif::GifEncoder::new_with_speed(
                &mut theirs,
                1,
            ))
            .unwrap();
        let theirs = mean_error(&theirs);
        assert!(ours <= theirs * 1.2 + 0.1, "ours {ours}, image's {theirs}");
        // Few colours come back exactly.
        let flat = RgbImage::from_fn(64, 64, |x, _| {
            image::Rgb([if x < 32 { 250 } else { 10 }, 40, 90])
        });
        let bytes = encode(&flat, ImageFormat::Gif).unwrap();
        let back = image::load_from_memory(&bytes).unwrap().to_rgb8();
        let off = flat
            .as_raw()
            .iter()
            .zip(back.as_raw())
            .map(|(a, b)| a.abs_diff(*b))
            .max();
        assert!(off.unwrap_or(0) <= 2, "{off:?}");
    }

    #[test]
    fn the_target_is_checked_before_any_work() {
        let dir = tempfile::tempdir().unwrap();
        let ok = dir.path().join("a.png");
        assert_eq!(check_target(&ok, 10, 10).unwrap(), ImageFormat::Png);
        assert!(matches!(
            check_target(Path::new(""), 1, 1),
            Err(OutputError::EmptyName)
        ));
        let wide = check_target(&dir.path().join("a.webp"), 20_000, 1).unwrap_err();
        assert!(
            wide.to_string().contains("at most 16383 pixels a side"),
            "{wide}"
        );
        let many = check_target(&dir.path().join("a.qoi"), 30_000, 30_000).unwrap_err();
        assert!(matches!(many, OutputError::TooLarge { .. }), "{many}");
        let gone = check_target(&dir.path().join("gone/a.png"), 1, 1).unwrap_err();
        assert!(matches!(gone, OutputError::NoFolder { .. }), "{gone}");
        // The probe leaves nothing behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn errors_name_the_path_given_never_a_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let gone = dir.path().join("gone/x.csv");
        let err = write_atomic(&gone, b"x").unwrap_err().to_string();
        assert_eq!(
            err,
            format!(
                "{}: the folder {} does not exist",
                gone.display(),
                dir.path().join("gone").display()
            )
        );
        let err = check_file_target(&gone).unwrap_err().to_string();
        assert!(
            err.contains("the folder") && !err.contains(".rayoflight-"),
            "{err}"
        );
        assert!(matches!(
            check_file_target(dir.path()),
            Err(OutputError::IsDirectory { .. })
        ));
        // A device takes a text file written into it, never an image.
        check_file_target(Path::new("/dev/null")).unwrap();
        #[cfg(unix)]
        {
            let link = dir.path().join("null.png");
            std::os::unix::fs::symlink("/dev/null", &link).unwrap();
            assert!(matches!(
                check_target(&link, 1, 1),
                Err(OutputError::Special { .. })
            ));
        }
    }

    #[test]
    fn format_follows_the_extension() {
        assert_eq!(format_for(Path::new("a.PNG")).unwrap(), ImageFormat::Png);
        assert_eq!(format_for(Path::new("a.jpeg")).unwrap(), ImageFormat::Jpeg);
        let err = format_for(Path::new("a.xyz")).unwrap_err().to_string();
        assert!(err.contains("\"xyz\"") && err.contains("png, jpg"), "{err}");
        assert!(matches!(
            format_for(Path::new("noext")),
            Err(OutputError::NoExtension { .. })
        ));
    }

    #[cfg(unix)]
    #[test]
    fn atomic_write_keeps_usual_and_existing_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        write_atomic(&path, b"a").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        // The same mode as a file created the ordinary way.
        let plain = dir.path().join("plain.txt");
        std::fs::write(&plain, b"a").unwrap();
        assert_eq!(mode(&path), mode(&plain));
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomic(&path, b"b").unwrap();
        assert_eq!(mode(&path), 0o640);
        // A read-only file is not replaced.
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o444)).unwrap();
        let err = write_atomic(&path, b"c").unwrap_err().to_string();
        assert!(err.contains("read-only"), "{err}");
        assert_eq!(std::fs::read(&path).unwrap(), b"b");
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_nobody_reads_is_refused_at_once() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe");
        assert!(
            std::process::Command::new("mkfifo")
                .arg(&fifo)
                .status()
                .unwrap()
                .success()
        );
        let err = write_atomic(&fifo, b"x").unwrap_err().to_string();
        assert!(err.ends_with("a FIFO that no program is reading"), "{err}");
        // With a reader, the bytes go through.
        let reader = std::thread::spawn({
            let fifo = fifo.clone();
            move || std::fs::read(fifo).unwrap()
        });
        let start = std::time::Instant::now();
        loop {
            match write_atomic(&fifo, b"hello") {
                Ok(()) => break,
                Err(_) if start.elapsed().as_secs() < 5 => std::thread::yield_now(),
                Err(e) => panic!("{e}"),
            }
        }
        assert_eq!(reader.join().unwrap(), b"hello");
    }

    #[cfg(unix)]
    #[test]
    fn devices_are_written_not_replaced() {
        // /dev/null takes the bytes and stays a device.
        write_atomic(Path::new("/dev/null"), b"x").unwrap();
        assert!(!std::fs::metadata("/dev/null").unwrap().is_file());
        // /dev/full reports the full disk.
        if Path::new("/dev/full").exists() {
            let err = write_atomic(Path::new("/dev/full"), &[0; 100_000]).unwrap_err();
            assert!(err.to_string().contains("/dev/full"), "{err}");
            assert!(!std::fs::metadata("/dev/full").unwrap().is_file());
        }
    }

    #[test]
    fn atomic_write_replaces_and_cleans_up() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.png");
        save(&sample(), &path).unwrap();
        save(&sample(), &path).unwrap();
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "no temporary file left behind");
        let missing = dir.path().join("no/such/dir/out.png");
        assert!(matches!(
            save(&sample(), &missing),
            Err(OutputError::NoFolder { .. })
        ));
    }
}
