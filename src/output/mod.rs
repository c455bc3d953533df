//! Image files: the format follows the file's extension ([`SUPPORTED`]),
//! the target is checked before any work ([`check_target`]), every PNG
//! goes through one row writer ([`write_png`], which deflates bands of
//! rows on every core: [`png_writer`]) and an EXR is written from
//! the pixels with no copy ([`save_exr`]). The bytes leave through the
//! one atomic writer of [`crate::system::files::write`]; the font drawn
//! into images (the study chart, the contact sheet) is [`font`]'s.

use crate::render::{KeptPass, Pass, PassForm, PassImage, PassPixels};
use crate::system::files::write::{
    WriteError, check_room, in_the_way, place, write_atomic, write_atomic_with,
};
use crate::system::files::{Kind, Place};
use image::codecs::jpeg::JpegEncoder;
use image::codecs::pnm::{PnmEncoder, PnmSubtype, SampleEncoding};
use image::{ImageFormat, RgbImage};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub mod font;
mod png_writer;

pub use png_writer::{band_rows, write_png, write_png_image};

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

/// Why an image could not be written: its name, its format or size, or
/// the write itself ([`WriteError`]).
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{}: unknown image extension {ext:?}; supported: {}", path.display(), supported_list())]
    UnknownExtension { path: PathBuf, ext: String },
    #[error("{}: no file extension to choose the image format; supported: {}", path.display(), supported_list())]
    NoExtension { path: PathBuf },
    #[error("{}: cannot encode the image: {}", path.display(), one_line(source))]
    Encode {
        path: PathBuf,
        source: image::ImageError,
    },
    #[error("{}: is {kind}, not an image file", path.display())]
    Special { path: PathBuf, kind: &'static str },
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
    #[error(transparent)]
    Write(#[from] WriteError),
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
        return Err(WriteError::EmptyName.into());
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
    let seen = in_the_way(path, &place)?;
    if let Some((_, meta)) = &seen
        && let Some(kind) = crate::system::files::special_kind(meta)
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
    check_room(path, &place, seen.map(|(kind, _)| kind))?;
    Ok(format)
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
    Ok(write_atomic(path, &encoded)?)
}

/// Writes `image` as a PNG with `texts` (keyword, text) in tEXt chunks
/// before its pixels, atomically. Every PNG the project writes goes
/// through [`png_writer`]: a render saved whole ([`write_png_image`]) and
/// the same image put together from parts by `assemble` ([`write_png`])
/// are the same file, byte for byte.
pub fn save_png(image: &RgbImage, texts: &[(&str, &str)], path: &Path) -> Result<(), OutputError> {
    write_atomic_with(
        path,
        |w| write_png_image(w, image.width(), image.height(), image.as_raw(), texts),
        |_| Ok::<(), OutputError>(()),
    )
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
    let io_error = |source| -> OutputError {
        WriteError::Io {
            path: path.to_owned(),
            source,
        }
        .into()
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
/// in EXR as floats, each channel value / 255; `.ppm` a binary PPM, P6:
/// `image`'s PNM encoder writes PAM, P7, unless told).
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
    } else if format == ImageFormat::Pnm {
        let pixmap = PnmSubtype::Pixmap(SampleEncoding::Binary);
        image.write_with_encoder(PnmEncoder::new(&mut bytes).with_subtype(pixmap))?;
    } else if format == ImageFormat::Png {
        write_png_image(
            &mut bytes,
            image.width(),
            image.height(),
            image.as_raw(),
            &[],
        )
        .map_err(image::ImageError::IoError)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::system::files::write::check_file_target;

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
            if *ext == "ppm" {
                // A PPM, as its name says, not a PAM (P7).
                assert_eq!(&bytes[..2], b"P6");
            }
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
            Err(OutputError::Write(WriteError::EmptyName))
        ));
        let wide = check_target(&dir.path().join("a.webp"), 20_000, 1).unwrap_err();
        assert!(
            wide.to_string().contains("at most 16383 pixels a side"),
            "{wide}"
        );
        let many = check_target(&dir.path().join("a.qoi"), 30_000, 30_000).unwrap_err();
        assert!(matches!(many, OutputError::TooLarge { .. }), "{many}");
        let gone = check_target(&dir.path().join("gone/a.png"), 1, 1).unwrap_err();
        assert!(
            matches!(gone, OutputError::Write(WriteError::NoFolder { .. })),
            "{gone}"
        );
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
            Err(WriteError::IsDirectory { .. })
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
            Err(OutputError::Write(WriteError::NoFolder { .. }))
        ));
    }
}
