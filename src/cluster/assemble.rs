//! Putting parts together: the PNGs `--region` wrote, on one machine or
//! many, into the full image, checked first and streamed.
//!
//! [`check`] reads each part's record ([`crate::cluster::part`]) and refuses,
//! naming the culprit, a file given twice, a file that is not a part, parts of another render
//! (scene or options) or another version, a part whose pixels are not its
//! region's size, a region outside the image, two parts that overlap and
//! pixels no part holds. [`assemble`] then writes the image band by band:
//! only the parts that cross the current rows are open, each decoding its
//! columns of a band straight into it, the parts side by side on the
//! pool's threads while the bands before are compressed
//! ([`crate::output::write_png`]), so memory holds a few bands, never the
//! image (a 16000×16000 image is 768 MB).
//!
//! Every part crossing a row is open while the row is assembled: the
//! soft limit of open files is raised to the hard one first, and parts
//! that still need more at once are refused before any pixel is read.
//!
//! The image written is the file a one-machine render writes
//! ([`crate::output::write_png`] for both): `cmp` finds no difference.

use crate::cluster::part::{self, Part, PartError};
use crate::output::{self, OutputError};
use crate::render::region::Region;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

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
    #[error("{}: not a part of a render: no '{}' record before its pixels (parts are written by 'rayoflight --region'; a part re-saved by another program is not one)", path.display(), part::KEYWORD)]
    NotAPart { path: PathBuf },
    #[error("{}: holds two '{}' records: a part has one", path.display(), part::KEYWORD)]
    TwoRecords { path: PathBuf },
    #[error("{}: is {kind}, not a part", path.display())]
    Special { path: PathBuf, kind: &'static str },
    #[error("{}: interrupted: nothing was written", path.display())]
    Interrupted { path: PathBuf },
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
    #[error("{}: made by rayoflight {theirs}, but {} by {ours}: renderers of two versions may not agree", path.display(), other.display())]
    Version {
        path: PathBuf,
        theirs: String,
        other: PathBuf,
        ours: String,
    },
    #[error("{}: a part of a {}×{} image, but {} of a {}×{} one", path.display(), size.0, size.1, other.display(), other_size.0, other_size.1)]
    ImageSize {
        path: PathBuf,
        size: (u32, u32),
        other: PathBuf,
        other_size: (u32, u32),
    },
    #[error("{}: a part of another scene or other render options than {}", path.display(), other.display())]
    OtherRender { path: PathBuf, other: PathBuf },
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
    #[error(
        "{parts} parts cross row {row} of the image and must be open together, but this process may open {limit} files at once ({open} open already; hard limit {}): give fewer parts across the image, or raise the hard limit ('ulimit -Hn'); no pixel was read",
        hard.map_or("none".to_owned(), |h| h.to_string())
    )]
    TooManyOpen {
        parts: usize,
        row: u32,
        limit: u64,
        hard: Option<u64>,
        open: u64,
    },
    #[error(transparent)]
    Output(#[from] OutputError),
}

impl From<crate::system::files::WriteError> for AssembleError {
    fn from(e: crate::system::files::WriteError) -> AssembleError {
        AssembleError::Output(e.into())
    }
}

type PngReader = png::Reader<BufReader<File>>;

/// At most one record in the chunks read so far (tEXt, zTXt or iTXt: a
/// second one, before the pixels or after them, would make the part
/// ambiguous).
fn one_record(info: &png::Info, path: &Path) -> Result<(), AssembleError> {
    let records = info
        .uncompressed_latin1_text
        .iter()
        .filter(|c| c.keyword == part::KEYWORD)
        .count()
        + info
            .compressed_latin1_text
            .iter()
            .filter(|c| c.keyword == part::KEYWORD)
            .count()
        + info
            .utf8_text
            .iter()
            .filter(|c| c.keyword == part::KEYWORD)
            .count();
    if records > 1 {
        return Err(AssembleError::TwoRecords {
            path: path.to_owned(),
        });
    }
    Ok(())
}

/// Opens a part's PNG and reads its header and record.
fn open(path: &Path) -> Result<(PngReader, PartFile), AssembleError> {
    let read_error = |source| AssembleError::Read {
        path: path.to_owned(),
        source,
    };
    // A FIFO or a device is never opened: reading one could wait for ever.
    let meta = std::fs::metadata(path).map_err(read_error)?;
    if let Some(kind) = crate::system::files::special_kind(&meta) {
        return Err(AssembleError::Special {
            path: path.to_owned(),
            kind,
        });
    }
    let file = File::open(path).map_err(read_error)?;
    let mut decoder = png::Decoder::new(BufReader::new(file));
    // Every chunk's CRC and the pixels' Adler-32: a flipped bit must not
    // pass into the image.
    decoder.ignore_checksums(false);
    let reader = decoder.read_info().map_err(|e| AssembleError::NotPng {
        path: path.to_owned(),
        reason: e.to_string(),
    })?;
    let info = reader.info();
    one_record(info, path)?;
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
    // The same file twice, by one name or two (a link, a hard link).
    let mut seen = std::collections::HashSet::new();
    for path in paths {
        if !seen.insert(crate::system::files::identity(path)) {
            return Err(AssembleError::Twice { path: path.clone() });
        }
    }
    let mut parts = paths
        .iter()
        .map(|path| open(path).map(|(_, part)| part))
        .collect::<Result<Vec<_>, _>>()?;
    if parts.is_empty() {
        return Err(AssembleError::NoParts);
    }
    // What most parts are parts of; the culprit is a part that differs
    // from them (the first part may be the odd one out).
    let kind = |p: &PartFile| (p.part.version.clone(), p.part.image, p.part.render);
    let mut counts: Vec<(_, usize)> = Vec::new();
    for p in &parts {
        match counts.iter_mut().find(|(k, _)| *k == kind(p)) {
            Some((_, n)) => *n += 1,
            None => counts.push((kind(p), 1)),
        }
    }
    let most = counts.iter().map(|(_, n)| *n).max().unwrap_or(0);
    let common = counts
        .iter()
        .find(|(_, n)| *n == most)
        .map(|(k, _)| k.clone())
        .expect("at least one part");
    let model = parts
        .iter()
        .find(|p| kind(p) == common)
        .expect("a part of the commonest kind")
        .clone();
    let size = model.part.image;
    for p in &parts {
        if p.part.version != model.part.version {
            return Err(AssembleError::Version {
                path: p.path.clone(),
                theirs: p.part.version.clone(),
                other: model.path.clone(),
                ours: model.part.version.clone(),
            });
        }
        if p.part.image != size {
            return Err(AssembleError::ImageSize {
                path: p.path.clone(),
                size: p.part.image,
                other: model.path.clone(),
                other_size: size,
            });
        }
        if p.part.render != model.part.render {
            return Err(AssembleError::OtherRender {
                path: p.path.clone(),
                other: model.path.clone(),
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
/// PNG, atomically, decoding and compressing on every core.
pub fn assemble(paths: &[PathBuf], out: &Path) -> Result<Assembled, AssembleError> {
    assemble_until(paths, out, &AtomicBool::new(false))
}

/// [`assemble`], giving up between two rows once `stop` is set (a signal,
/// at the binary's edge): [`AssembleError::Interrupted`], and the
/// temporary file is removed, an older image left as it was.
pub fn assemble_until(
    paths: &[PathBuf],
    out: &Path,
    stop: &AtomicBool,
) -> Result<Assembled, AssembleError> {
    let parts = check(paths)?;
    if paths
        .iter()
        .any(|p| crate::system::files::same_file(p, out))
    {
        return Err(AssembleError::OutIsAPart {
            path: out.to_owned(),
        });
    }
    let (width, height) = parts[0].part.image;
    output::check_target(out, width, height)?;
    check_open_files(&parts)?;
    let mut rows = Rows::new(&parts, width);
    let mut failure: Option<AssembleError> = None;
    let written = crate::system::files::write_atomic_with(
        out,
        |w| {
            output::write_png(w, width, height, &[], |band| {
                let filled = match stop.load(Ordering::Relaxed) {
                    true => Err(AssembleError::Interrupted {
                        path: out.to_owned(),
                    }),
                    false => rows.fill(band),
                };
                filled.map_err(|e| keep(&mut failure, e))
            })
        },
        |_| Ok::<(), AssembleError>(()),
    );
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

/// Descriptors besides the parts' that an assembly may hold: the output's
/// temporary file, its folder probe, a scratch file, the standard streams
/// and a few the runtime keeps.
const SPARE_FILES: u64 = 16;

/// The most parts that cross one row, and the first row they do: the
/// files open together while it is assembled. `parts` in reading order.
pub fn most_open(parts: &[PartFile]) -> (usize, u32) {
    // Each part opens at its top row and closes after its bottom one:
    // the count peaks at some part's top.
    let mut events: Vec<(u32, i64)> = parts
        .iter()
        .flat_map(|p| [(p.part.region.y0, 1), (p.part.region.y1, -1)])
        .collect();
    // At one row, the parts that end close before those that start open.
    events.sort_unstable();
    let (mut open, mut most, mut row) = (0i64, 0i64, 0);
    for (y, change) in events {
        open += change;
        if open > most {
            (most, row) = (open, y);
        }
    }
    (most as usize, row)
}

/// Raises the soft limit of open files to the hard one
/// ([`crate::system::resources::raise_open_files`]) and refuses, before any
/// pixel is read, parts that a row needs open together beyond it.
fn check_open_files(parts: &[PartFile]) -> Result<(), AssembleError> {
    let (most, row) = most_open(parts);
    let Some(files) = crate::system::resources::raise_open_files() else {
        return Ok(());
    };
    if files.open + most as u64 + SPARE_FILES > files.limit {
        return Err(AssembleError::TooManyOpen {
            parts: most,
            row,
            limit: files.limit,
            hard: files.hard,
            open: files.open,
        });
    }
    Ok(())
}

/// The image's rows, top to bottom, from the parts: each part opened as
/// the rows reach its top, closed after its bottom, read a row at a time
/// straight into the image's band.
struct Rows<'a> {
    waiting: std::iter::Peekable<std::slice::Iter<'a, PartFile>>,
    /// The parts crossing the current row, from left to right.
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

    /// Fills `band`, the next rows of the image: a stretch of rows at a
    /// time that the same parts cross, each part decoding its columns of
    /// them on a thread of the pool while the others decode theirs.
    fn fill(&mut self, band: &mut [u8]) -> Result<(), AssembleError> {
        use rayon::prelude::*;
        let row_bytes = self.width as usize * 3;
        let mut rows: Vec<&mut [u8]> = band.chunks_exact_mut(row_bytes).collect();
        while !rows.is_empty() {
            self.open_and_close()?;
            let y = self.y;
            // Rows until a part ends or another begins.
            let until = self
                .open
                .iter()
                .map(|(_, p)| p.part.region.y1)
                .chain(self.waiting.peek().map(|p| p.part.region.y0))
                .fold(y + rows.len() as u32, u32::min);
            let mut columns: Vec<Vec<&mut [u8]>> = (0..self.open.len())
                .map(|_| Vec::with_capacity((until - y) as usize))
                .collect();
            for row in rows.drain(..(until - y) as usize) {
                // The open parts tile the row (`check`), left to right.
                let mut rest = row;
                let mut x = 0;
                for ((_, p), column) in self.open.iter().zip(&mut columns) {
                    let region = p.part.region;
                    let (_, at) = rest.split_at_mut((region.x0 - x) as usize * 3);
                    let (mine, after) = at.split_at_mut(region.width() as usize * 3);
                    column.push(mine);
                    (rest, x) = (after, region.x1);
                }
            }
            self.open
                .par_iter_mut()
                .zip(columns)
                .try_for_each(|((reader, p), column)| decode(reader, p, column, until))?;
            self.y = until;
        }
        Ok(())
    }

    /// Closes the parts that ended above the current row and opens those
    /// that begin on it.
    fn open_and_close(&mut self) -> Result<(), AssembleError> {
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
        self.open.sort_by_key(|(_, p)| p.part.region.x0);
        Ok(())
    }
}

/// Decodes the next rows of part `p` into `rows`, its columns of the
/// image's rows; `until`: the image's row after them.
fn decode(
    reader: &mut PngReader,
    p: &PartFile,
    rows: Vec<&mut [u8]>,
    until: u32,
) -> Result<(), AssembleError> {
    let decode_error = |reason: String| AssembleError::Decode {
        path: p.path.clone(),
        reason,
    };
    for row in rows {
        reader
            .read_row(row)
            .map_err(|e| decode_error(e.to_string()))?
            .ok_or_else(|| decode_error("ends before its last row".to_owned()))?;
    }
    if p.part.region.y1 == until {
        // Its last row: read to the end of its pixels, so that the last
        // chunk's CRC and the Adler-32 are checked too.
        reader.finish().map_err(|e| decode_error(e.to_string()))?;
        one_record(reader.info(), &p.path)?;
    }
    Ok(())
}

/// Keeps `e` to report (the PNG writer only passes I/O errors through)
/// and stops the writing.
fn keep(failure: &mut Option<AssembleError>, e: AssembleError) -> std::io::Error {
    let message = e.to_string();
    *failure = Some(e);
    std::io::Error::other(message)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_files_open_at_once_are_the_parts_crossing_the_busiest_row() {
        let part = |x0, y0, x1, y1| PartFile {
            path: PathBuf::from(format!("{x0},{y0}")),
            part: Part {
                region: Region::new(x0, y0, x1, y1).unwrap(),
                image: (10, 10),
                render: 0,
                version: String::new(),
            },
        };
        // Three bands; the middle one cut in four.
        let parts = [
            part(0, 0, 10, 3),
            part(0, 3, 2, 7),
            part(2, 3, 5, 7),
            part(5, 3, 9, 7),
            part(9, 3, 10, 7),
            part(0, 7, 10, 10),
        ];
        // The top band closes before the middle one opens.
        assert_eq!(most_open(&parts), (4, 3));
        assert_eq!(most_open(&parts[..1]), (1, 0));
        assert_eq!(most_open(&[]), (0, 0));
    }
}
