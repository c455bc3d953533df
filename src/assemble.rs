//! Putting parts together: the PNGs `--region` wrote, on one machine or
//! many, into the full image, checked first and streamed.
//!
//! [`check`] reads each part's record ([`crate::part`]) and refuses,
//! naming the culprit, a file given twice, a file that is not a part, parts of another render
//! (scene or options) or another version, a part whose pixels are not its
//! region's size, a region outside the image, two parts that overlap and
//! pixels no part holds. [`assemble`] then writes the image row by row:
//! only the parts that cross the current row are open, each decoded a row
//! at a time on a thread of its own while the other thread compresses, so
//! memory holds a few rows, never the image (a 16000×16000 image is 768
//! MB).
//!
//! The image written is the file a one-machine render writes
//! ([`crate::output::write_png`] for both): `cmp` finds no difference.

use crate::output::{self, OutputError};
use crate::part::{self, Part, PartError};
use crate::region::Region;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

/// A part's file and its record.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PartFile {
    pub path: PathBuf,
    pub part: Part,
}

/// Why parts cannot be put together.
#[derive(Debug, thiserror::Error)]
pub enum AssembleError {
    #[error("no parts given")]
    NoParts,
    #[error("{}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: given twice", path.display())]
    Twice { path: PathBuf },
    #[error("{}: is one of the parts: the image cannot be written over it", path.display())]
    OutIsAPart { path: PathBuf },
    #[error("{}: not a PNG that can be read: {reason}", path.display())]
    NotPng { path: PathBuf, reason: String },
    #[error("{}: not a part of a render (no '{}' record: written by 'rayoflight --region'?)", path.display(), part::KEYWORD)]
    NotAPart { path: PathBuf },
    #[error("{}: {source}", path.display())]
    BadRecord { path: PathBuf, source: PartError },
    #[error("{}: not an 8-bit RGB image, as parts are", path.display())]
    NotRgb8 { path: PathBuf },
    #[error("{}: holds {width}×{height} pixels, but its region {region} is {}×{}", path.display(), region.width(), region.height())]
    WrongSize {
        path: PathBuf,
        width: u32,
        height: u32,
        region: Region,
    },
    #[error("{}: made by rayoflight {theirs}, but {} by {ours}: renderers of two versions may not agree", path.display(), first.display())]
    Version {
        path: PathBuf,
        theirs: String,
        first: PathBuf,
        ours: String,
    },
    #[error("{}: a part of a {}×{} image, but {} of a {}×{} one", path.display(), size.0, size.1, first.display(), first_size.0, first_size.1)]
    ImageSize {
        path: PathBuf,
        size: (u32, u32),
        first: PathBuf,
        first_size: (u32, u32),
    },
    #[error("{}: a part of another scene or other render options than {}", path.display(), first.display())]
    OtherRender { path: PathBuf, first: PathBuf },
    #[error("{}: its region {region} is outside the {}×{} image", path.display(), size.0, size.1)]
    Outside {
        path: PathBuf,
        region: Region,
        size: (u32, u32),
    },
    #[error("{} and {} overlap: both hold pixels {overlap}", a.display(), b.display())]
    Overlap {
        a: PathBuf,
        b: PathBuf,
        overlap: Region,
    },
    #[error("no part holds pixels {gap} of the {}×{} image: a part is missing", size.0, size.1)]
    Gap { gap: Region, size: (u32, u32) },
    #[error("{}: {reason}", path.display())]
    Decode { path: PathBuf, reason: String },
    #[error(transparent)]
    Output(#[from] OutputError),
}

type PngReader = png::Reader<BufReader<File>>;

/// Opens a part's PNG and reads its header and record.
fn open(path: &Path) -> Result<(PngReader, PartFile), AssembleError> {
    let file = File::open(path).map_err(|source| AssembleError::Read {
        path: path.to_owned(),
        source,
    })?;
    let reader = png::Decoder::new(BufReader::new(file))
        .read_info()
        .map_err(|e| AssembleError::NotPng {
            path: path.to_owned(),
            reason: e.to_string(),
        })?;
    let info = reader.info();
    let text = info
        .uncompressed_latin1_text
        .iter()
        .find(|chunk| chunk.keyword == part::KEYWORD)
        .ok_or_else(|| AssembleError::NotAPart {
            path: path.to_owned(),
        })?;
    let part = Part::parse(&text.text).map_err(|source| AssembleError::BadRecord {
        path: path.to_owned(),
        source,
    })?;
    if (info.color_type, info.bit_depth) != (png::ColorType::Rgb, png::BitDepth::Eight)
        || info.interlaced
    {
        return Err(AssembleError::NotRgb8 {
            path: path.to_owned(),
        });
    }
    if (info.width, info.height) != (part.region.width(), part.region.height()) {
        return Err(AssembleError::WrongSize {
            path: path.to_owned(),
            width: info.width,
            height: info.height,
            region: part.region,
        });
    }
    Ok((
        reader,
        PartFile {
            path: path.to_owned(),
            part,
        },
    ))
}

/// Reads the parts' records and checks that they make one image exactly:
/// one render, one version, every region inside the image, no pixel in
/// two parts, none in no part. Returns the parts in reading order (by
/// top, then left edge).
pub fn check(paths: &[PathBuf]) -> Result<Vec<PartFile>, AssembleError> {
    // The same file twice, by one name or two.
    let mut seen = std::collections::HashSet::new();
    for path in paths {
        if !seen.insert(path.canonicalize().unwrap_or_else(|_| path.clone())) {
            return Err(AssembleError::Twice { path: path.clone() });
        }
    }
    let mut parts = paths
        .iter()
        .map(|path| open(path).map(|(_, part)| part))
        .collect::<Result<Vec<_>, _>>()?;
    let Some(first) = parts.first().cloned() else {
        return Err(AssembleError::NoParts);
    };
    let size = first.part.image;
    for p in &parts {
        if p.part.version != first.part.version {
            return Err(AssembleError::Version {
                path: p.path.clone(),
                theirs: p.part.version.clone(),
                first: first.path.clone(),
                ours: first.part.version.clone(),
            });
        }
        if p.part.image != size {
            return Err(AssembleError::ImageSize {
                path: p.path.clone(),
                size: p.part.image,
                first: first.path.clone(),
                first_size: size,
            });
        }
        if p.part.render != first.part.render {
            return Err(AssembleError::OtherRender {
                path: p.path.clone(),
                first: first.path.clone(),
            });
        }
        if p.part.region.check_in(size.0, size.1).is_err() {
            return Err(AssembleError::Outside {
                path: p.path.clone(),
                region: p.part.region,
                size,
            });
        }
    }
    parts.sort_by_key(|p| (p.part.region.y0, p.part.region.x0));
    check_tiling(&parts, size)?;
    Ok(parts)
}

/// Checks that the regions cover the image once: in each band of rows
/// between two consecutive top or bottom edges, the parts crossing it,
/// left to right, must follow each other with neither gap nor overlap
/// from x = 0 to the width.
fn check_tiling(parts: &[PartFile], (width, height): (u32, u32)) -> Result<(), AssembleError> {
    let mut edges: Vec<u32> = parts
        .iter()
        .flat_map(|p| [p.part.region.y0, p.part.region.y1])
        .chain([0, height])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    for band in edges.windows(2) {
        let (y0, y1) = (band[0], band[1]);
        let mut crossing: Vec<&PartFile> = parts
            .iter()
            .filter(|p| p.part.region.y0 < y1 && y0 < p.part.region.y1)
            .collect();
        crossing.sort_by_key(|p| p.part.region.x0);
        let mut x = 0;
        let mut left: Option<&PartFile> = None;
        for p in crossing {
            let region = p.part.region;
            if region.x0 < x {
                let a = left.expect("a part ends at x > 0");
                let overlap = a
                    .part
                    .region
                    .intersection(&region)
                    .expect("both cross the band and meet in x");
                return Err(AssembleError::Overlap {
                    a: a.path.clone(),
                    b: p.path.clone(),
                    overlap,
                });
            }
            if region.x0 > x {
                return Err(gap(x, y0, region.x0, y1, parts, width, height));
            }
            x = region.x1;
            left = Some(p);
        }
        if x < width {
            return Err(gap(x, y0, width, y1, parts, width, height));
        }
    }
    Ok(())
}

/// The gap [x0, x1) × [y0, y1) found in one band, grown down over the
/// following rows no part holds either: the missing part's pixels.
fn gap(
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
    parts: &[PartFile],
    width: u32,
    height: u32,
) -> AssembleError {
    let columns = Region { x0, y0, x1, y1 };
    let below = |y: u32| Region {
        y0: y,
        y1: y + 1,
        ..columns
    };
    let mut bottom = y1;
    while bottom < height
        && parts
            .iter()
            .all(|p| p.part.region.intersection(&below(bottom)).is_none())
    {
        bottom += 1;
    }
    AssembleError::Gap {
        gap: Region {
            y1: bottom,
            ..columns
        },
        size: (width, height),
    }
}

/// What [`assemble`] put together.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Assembled {
    pub width: u32,
    pub height: u32,
    pub parts: usize,
}

/// Checks the parts ([`check`]) and writes the full image to `out` as a
/// PNG, atomically. Two threads share the work: one decodes the rows of
/// the parts crossing each row of the image, the other filters
/// and compresses them, a bounded queue of rows between them.
pub fn assemble(paths: &[PathBuf], out: &Path) -> Result<Assembled, AssembleError> {
    let parts = check(paths)?;
    let target = out.canonicalize().ok();
    if target.is_some() && paths.iter().any(|p| p.canonicalize().ok() == target) {
        return Err(AssembleError::OutIsAPart {
            path: out.to_owned(),
        });
    }
    let (width, height) = parts[0].part.image;
    output::check_target(out, width, height)?;
    let (send, receive) =
        std::sync::mpsc::sync_channel::<Result<Vec<u8>, AssembleError>>(QUEUED_ROWS);
    let mut failure: Option<AssembleError> = None;
    let written = std::thread::scope(|scope| {
        scope.spawn(|| {
            let mut rows = Rows::new(&parts, width);
            for _ in 0..height {
                let row = rows.next_row();
                let failed = row.is_err();
                // The writer has stopped: nothing more to decode for it.
                if send.send(row).is_err() || failed {
                    return;
                }
            }
        });
        let written = output::write_atomic_with(
            out,
            |w| {
                output::write_png(w, width, height, &[], |row| match receive.recv() {
                    Ok(Ok(decoded)) => {
                        row.copy_from_slice(&decoded);
                        Ok(())
                    }
                    Ok(Err(e)) => Err(stop(&mut failure, e)),
                    Err(_) => Err(std::io::Error::other("the decoding thread stopped")),
                })
            },
            |_| Ok::<(), AssembleError>(()),
        );
        // A writer that stopped early (a failure, a full disk) lets the
        // decoding thread's next send fail, and the thread end.
        drop(receive);
        written
    });
    match (written, failure) {
        (_, Some(e)) => Err(e),
        (Err(e), None) => Err(e),
        (Ok(()), None) => Ok(Assembled {
            width,
            height,
            parts: parts.len(),
        }),
    }
}

/// Rows decoded ahead of the writer, at most: a few hundred kilobytes on
/// a 16000-pixel-wide image.
const QUEUED_ROWS: usize = 16;

/// The image's rows, top to bottom, from the parts: each part opened as
/// the rows reach its top, closed after its bottom, read a row at a time.
struct Rows<'a> {
    waiting: std::iter::Peekable<std::slice::Iter<'a, PartFile>>,
    open: Vec<(PngReader, &'a PartFile)>,
    width: u32,
    y: u32,
}

impl<'a> Rows<'a> {
    /// `parts` in reading order, as [`check`] returns them.
    fn new(parts: &'a [PartFile], width: u32) -> Rows<'a> {
        Rows {
            waiting: parts.iter().peekable(),
            open: Vec::new(),
            width,
            y: 0,
        }
    }

    fn next_row(&mut self) -> Result<Vec<u8>, AssembleError> {
        let y = self.y;
        self.open.retain(|(_, p)| p.part.region.y1 > y);
        while let Some(p) = self.waiting.next_if(|p| p.part.region.y0 == y) {
            let (reader, again) = open(&p.path)?;
            // The file was read once by `check`: it must not have changed.
            if again.part != p.part {
                return Err(AssembleError::Decode {
                    path: p.path.clone(),
                    reason: "changed while the parts were put together".to_owned(),
                });
            }
            self.open.push((reader, p));
        }
        let mut row = vec![0; self.width as usize * 3];
        for (reader, p) in &mut self.open {
            let decode_error = |reason: String| AssembleError::Decode {
                path: p.path.clone(),
                reason,
            };
            let decoded = reader
                .next_row()
                .map_err(|e| decode_error(e.to_string()))?
                .ok_or_else(|| decode_error("ends before its last row".to_owned()))?;
            let at = p.part.region.x0 as usize * 3;
            row[at..at + decoded.data().len()].copy_from_slice(decoded.data());
        }
        self.y += 1;
        Ok(row)
    }
}

/// Keeps `e` to report (the PNG writer only passes I/O errors through)
/// and stops the writing.
fn stop(failure: &mut Option<AssembleError>, e: AssembleError) -> std::io::Error {
    let message = e.to_string();
    *failure = Some(e);
    std::io::Error::other(message)
}
