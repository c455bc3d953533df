//! Writing images: the format follows the file's extension, and files are
//! written atomically (a temporary file in the target directory, renamed
//! into place), so a failure never leaves a partial file nor touches an
//! existing one.

use image::codecs::jpeg::JpegEncoder;
use image::{ImageFormat, RgbImage};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// JPEG quality used for `.jpg` / `.jpeg`.
pub const JPEG_QUALITY: u8 = 95;

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
    #[error("{}: cannot encode the image: {source}", path.display())]
    Encode {
        path: PathBuf,
        source: image::ImageError,
    },
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
    let encoded = encode(image, format).map_err(|source| OutputError::Encode {
        path: path.to_owned(),
        source,
    })?;
    write_atomic(path, &encoded)
}

/// The image encoded in memory (JPEG at [`JPEG_QUALITY`]).
pub fn encode(image: &RgbImage, format: ImageFormat) -> Result<Vec<u8>, image::ImageError> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    if format == ImageFormat::Jpeg {
        image.write_with_encoder(JpegEncoder::new_with_quality(&mut bytes, JPEG_QUALITY))?;
    } else {
        image.write_to(&mut bytes, format)?;
    }
    Ok(bytes.into_inner())
}

/// Writes `bytes` to `path` through a temporary file in the same directory,
/// synced, then renamed over `path`. On any failure the temporary file is
/// removed and an existing `path` is left as it was. A symbolic link is
/// followed: the file it points to is replaced, the link is kept.
///
/// An existing path that is not a regular file (`/dev/stdout`, a FIFO,
/// `/dev/full`) is written directly: renaming over it would replace the
/// device or pipe itself.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let io_error = |source| OutputError::Io {
        path: path.to_owned(),
        source,
    };
    // A symbolic link is written through: its target gets the new bytes
    // and the link stays a link.
    let target = through_links(path);
    let path = target.as_path();
    if let Ok(meta) = std::fs::metadata(path)
        && !meta.is_file()
        && !meta.is_dir()
    {
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(io_error)?;
        file.write_all(bytes).map_err(io_error)?;
        return file.flush().map_err(io_error);
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if path.is_dir() {
        return Err(io_error(std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "is a directory",
        )));
    }
    // Renaming over a file ignores the file's own permissions: refuse a
    // read-only file here, as writing into it would fail.
    if std::fs::metadata(path).is_ok_and(|m| m.permissions().readonly()) {
        return Err(io_error(std::io::Error::new(
            std::io::ErrorKind::PermissionDenied,
            "the file is read-only",
        )));
    }
    let mut builder = tempfile::Builder::new();
    builder.prefix(".rayoflight-").suffix(".tmp");
    // A new file gets the usual mode (0666 less the umask, as the kernel
    // applies it at creation), not tempfile's private 0600.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    // tempfile names its own temporary path in its errors: report the
    // system's error for the path the user gave.
    let mut file = builder.tempfile_in(dir).map_err(|e| {
        io_error(
            e.raw_os_error()
                .map_or(e, std::io::Error::from_raw_os_error),
        )
    })?;
    // A replaced file keeps its own permissions.
    if let Ok(meta) = std::fs::metadata(path) {
        file.as_file()
            .set_permissions(meta.permissions())
            .map_err(io_error)?;
    }
    {
        let mut w = BufWriter::new(file.as_file_mut());
        w.write_all(bytes).map_err(io_error)?;
        w.flush().map_err(io_error)?;
    }
    file.as_file().sync_all().map_err(io_error)?;
    file.persist(path).map_err(|e| io_error(e.error))?;
    Ok(())
}

/// The file `path` names once symbolic links are followed (at most 40, as
/// the kernel does); a dangling link gives the path it points to.
pub fn through_links(path: &Path) -> std::path::PathBuf {
    let mut p = path.to_owned();
    for _ in 0..40 {
        let Ok(target) = std::fs::read_link(&p) else {
            break;
        };
        p = match p.parent() {
            Some(dir) => dir.join(target),
            None => target,
        };
    }
    p
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
            Err(OutputError::Io { .. })
        ));
    }
}
