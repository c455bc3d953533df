//! The scene loader: XML text to a validated [`Scene`] (docs/scene-format.md:
//! Elements, Transformations, Numbers, Everything else in the file and Error
//! messages), or a [`LoadError`] naming the file, the `line:column` and the
//! element and attribute at fault.
//!
//! Here: the ways in, a file read whole or a text at hand ([`load`],
//! [`parse`], their variants that share objects, count progress or keep
//! the text packed), the file's checks before it is parsed (size, kind,
//! encoding) and the limits. [`parser`] is the parser itself: the text's
//! events checked against the grammar, an element at a time. [`pieces`]
//! parses a big text on every core: a text held whole cut in pieces, or a
//! file read and parsed a piece at a time; its guesses are checked, and
//! any doubt falls back to the parse in one, so what is accepted and every
//! error are those of a parse in one. Every way of reading a file whole
//! also records where the root's children sit in it ([`Layout`], 16 bytes
//! a child, the pieces' joined in order). [`reading`] checks a text again
//! after edits, reading only where they fall.
//!
//! Nothing here panics on any input, and every count the file controls is
//! checked against its limit before anything is allocated for it.

use std::fs;
use std::io::Read;
use std::path::Path;
use std::sync::Arc;

use super::error::{LoadError, LoadErrorKind, Position};
use super::{Object, Objects, Scene};

mod parser;
mod pieces;
mod reading;

use parser::Parser;
pub(crate) use parser::{MAX_SIDE, NumberError, parse_integer, parse_number};
use pieces::{PIECE_BYTES, in_pieces, parsing_threads, streamed};
pub use reading::{Layout, Reading, Reread, Span};

/// Largest scene file [`load`] reads: 1 GiB.
pub const MAX_FILE_BYTES: u64 = 1 << 30;
/// Most objects (spheres and planes together) in one scene.
pub const MAX_OBJECTS: usize = 10_000_000;
/// Most lights in one scene.
pub const MAX_LIGHTS: usize = 1_000_000;
/// Most pixels (`width * height`) in the camera's image: 2^28.
pub const MAX_PIXELS: u64 = 1 << 28;

/// Reads and parses the scene file at `path`. A rewrite of it in place
/// that a crash left half done is finished first
/// ([`crate::system::files::finish`]).
///
/// The size is checked from the file's metadata before reading (and again
/// while reading, should the file grow): above [`MAX_FILE_BYTES`] it is
/// refused. A directory, a special file (FIFO, device, socket: refused
/// before opening it) or an unreadable file gives an error without a
/// position; one that is not UTF-8 is refused at its first bad byte.
///
/// A big file is read and parsed a piece at a time ([`streamed`]): its
/// text is never in memory whole, only the scene it makes.
pub fn load(path: &Path) -> Result<Scene, LoadError> {
    load_like(path, &Objects::default())
}

/// [`load`], sharing with `like` each object equal to the one at the same
/// place in it, as [`parse_sharing`] does, and the list itself when every
/// object is (a large file read in pieces); the text is not kept (a save
/// checking the file it wrote).
pub fn load_like(path: &Path, like: &Objects) -> Result<Scene, LoadError> {
    if let Some(streamed) = streamed(path, like, false, None) {
        return Ok(streamed.scene);
    }
    load_sharing(path, like).map(|(_, scene)| scene)
}

/// The encoding of a text that looks like UTF-16 (a byte order mark, or
/// its first characters, up to 16, ASCII with a zero byte beside each, as
/// `<scene>` is in UTF-16 without a mark), and whether it has a mark, for
/// a message that says so; `None` for anything else.
fn utf16_order(bytes: &[u8]) -> Option<(&'static str, bool)> {
    let pairs: Vec<&[u8]> = bytes.chunks_exact(2).take(16).collect();
    let all = |f: fn(u8, u8) -> bool| !pairs.is_empty() && pairs.iter().all(|p| f(p[0], p[1]));
    match bytes {
        [0xff, 0xfe, ..] => Some(("UTF-16LE", true)),
        [0xfe, 0xff, ..] => Some(("UTF-16BE", true)),
        _ if all(|a, b| b == 0 && a != 0 && a.is_ascii()) => Some(("UTF-16LE", false)),
        _ if all(|a, b| a == 0 && b != 0 && b.is_ascii()) => Some(("UTF-16BE", false)),
        _ => None,
    }
}

/// A large file loaded with its text, which is never held whole
/// ([`load_packed`]).
pub struct PackedLoad {
    pub scene: Scene,
    /// The file's text (byte-order mark and all), held packed.
    pub text: super::source::Source,
    /// The text has a comment somewhere (none: no object has a label).
    pub comments: bool,
    /// Where the root's children sit in the text.
    pub layout: Layout,
}

/// [`load_counting`] for the app, keeping a large file's text packed
/// ([`super::source::Source`]): each piece of the file is parsed and
/// packed on the cores while the next is read, so that the memory of the
/// load is the scene's, the packed text's and a few pieces', never the
/// text's (a million spheres: 214 MB). `Ok(None)` where it is not read so
/// (a file smaller than [`super::source::PACK_BYTES`], or at the least
/// doubt, as [`load`] has it): [`load_counting`] then reads it whole and
/// gives any error, at its line and column. Stopped by `progress`:
/// [`LoadErrorKind::Stopped`].
pub fn load_packed(
    path: &Path,
    progress: Option<&LoadProgress>,
) -> Result<Option<PackedLoad>, LoadError> {
    let large = fs::metadata(path)
        .is_ok_and(|m| m.is_file() && m.len() >= super::source::PACK_BYTES as u64);
    if !large {
        return Ok(None);
    }
    let loaded = streamed(path, &Objects::default(), true, progress);
    if progress.is_some_and(LoadProgress::is_stopped) {
        return Err(LoadError::new(path, None, LoadErrorKind::Stopped));
    }
    if let Some(progress) = progress {
        let total = 2 * fs::metadata(path).map_or(0, |m| m.len());
        progress.set(total, total);
    }
    Ok(loaded.map(|streamed| PackedLoad {
        scene: streamed.scene,
        text: super::source::Source::from_blocks(streamed.blocks),
        comments: streamed.comments,
        layout: streamed.layout,
    }))
}

/// Like [`load`], and also returns the file's text (the app keeps it to
/// write edits back into it).
pub fn load_with_text(path: &Path) -> Result<(String, Scene), LoadError> {
    load_sharing(path, &[])
}

/// [`load_with_text`], sharing objects with `like` as [`parse_sharing`]
/// does (the app reading its file again after a change).
pub fn load_sharing(path: &Path, like: &[Arc<Object>]) -> Result<(String, Scene), LoadError> {
    load_counting(path, like, None).map(|loaded| (loaded.text, loaded.scene))
}

/// A file read whole ([`load_counting`]): its text, the scene, and where
/// the root's children sit in the text (an app following an editor's
/// unsaved text of the file starts from it).
#[derive(Debug)]
pub struct Loaded {
    pub text: String,
    pub scene: Scene,
    pub layout: Layout,
}

/// How far a load has got, for a progress bar: bytes of the file read and
/// then parsed, out of twice its size (set by [`load_counting`], read from
/// any thread); and its stop switch ([`LoadProgress::stop`]).
#[derive(Debug, Default)]
pub struct LoadProgress {
    done: std::sync::atomic::AtomicU64,
    total: std::sync::atomic::AtomicU64,
    stopped: std::sync::atomic::AtomicBool,
}

impl LoadProgress {
    /// Asks the load to stop: it ends with [`LoadErrorKind::Stopped`] at
    /// its next megabyte read or its next few thousand elements parsed,
    /// and frees what it had made (a million spheres are seconds of work
    /// and hundreds of megabytes nobody waits for any more).
    pub fn stop(&self) {
        self.stopped
            .store(true, std::sync::atomic::Ordering::Relaxed);
    }

    fn is_stopped(&self) -> bool {
        self.stopped.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The fraction done, 0 to 1 (0 before the size is known).
    pub fn fraction(&self) -> f64 {
        use std::sync::atomic::Ordering::Relaxed;
        let total = self.total.load(Relaxed);
        if total == 0 {
            return 0.0;
        }
        (self.done.load(Relaxed) as f64 / total as f64).min(1.0)
    }

    fn set(&self, done: u64, total: u64) {
        use std::sync::atomic::Ordering::Relaxed;
        self.total.store(total, Relaxed);
        self.done.store(done, Relaxed);
    }

    /// `bytes` more parsed (by any of the pieces parsed at once).
    fn add(&self, bytes: usize) {
        use std::sync::atomic::Ordering::Relaxed;
        self.done.fetch_add(bytes as u64, Relaxed);
    }
}

/// [`load_sharing`], saying how far it has got in `progress`, and where
/// the root's children sit in the text.
pub fn load_counting(
    path: &Path,
    like: &[Arc<Object>],
    progress: Option<&LoadProgress>,
) -> Result<Loaded, LoadError> {
    // As in [`streamed`]: a crashed rewrite in place is finished first.
    let _ = crate::system::files::finish(path);
    let fail = |kind| LoadError::new(path, None, kind);
    let io = |e: std::io::Error| {
        fail(LoadErrorKind::Io {
            kind: e.kind(),
            message: e.to_string(),
        })
    };
    let too_large = |size| {
        fail(LoadErrorKind::FileTooLarge {
            size,
            limit: MAX_FILE_BYTES,
        })
    };

    let meta = fs::metadata(path).map_err(io)?;
    if meta.is_dir() {
        return Err(fail(LoadErrorKind::IsDirectory));
    }
    // A FIFO would block until a writer comes, a device may never end.
    if let Some(kind) = crate::system::files::special_kind(&meta) {
        return Err(fail(LoadErrorKind::NotAFile { kind }));
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(too_large(meta.len()));
    }
    let file = fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    // Special files report a length of 0 and may never end: read one byte
    // past the limit at most.
    let mut limited = file.take(MAX_FILE_BYTES + 1);
    match progress {
        None => {
            limited.read_to_end(&mut bytes).map_err(io)?;
        }
        // In pieces, counted.
        Some(progress) => {
            let total = 2 * meta.len();
            let mut piece = vec![0; 1 << 20];
            loop {
                if progress.is_stopped() {
                    return Err(fail(LoadErrorKind::Stopped));
                }
                let n = limited.read(&mut piece).map_err(io)?;
                if n == 0 {
                    break;
                }
                bytes.extend_from_slice(&piece[..n]);
                progress.set(bytes.len() as u64, total);
            }
        }
    }
    let read = u64::try_from(bytes.len()).unwrap_or(u64::MAX);
    if read > MAX_FILE_BYTES {
        return Err(too_large(read));
    }
    if let Some((encoding, mark)) = utf16_order(&bytes) {
        return Err(LoadError::new(
            path,
            Some(Position::at_offset("", 0)),
            LoadErrorKind::Utf16 { encoding, mark },
        ));
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        // The valid part is text: the bad byte's line and column in it.
        let valid = e.as_bytes().get(..offset).unwrap_or_default();
        let prefix = std::str::from_utf8(valid).unwrap_or_default();
        let prefix = prefix.strip_prefix('\u{feff}').unwrap_or(prefix);
        LoadError::new(
            path,
            Some(Position::at_offset(prefix, prefix.len())),
            LoadErrorKind::NotUtf8 { offset },
        )
    })?;
    let body = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let (scene, mut layout) = parse_body(body, path, like, progress)?;
    layout.bom = text.len() - body.len();
    if let Some(progress) = progress {
        let total = 2 * text.len() as u64;
        progress.set(total, total);
    }
    Ok(Loaded {
        text,
        scene,
        layout,
    })
}

/// Parses a scene from `text`; `path` only names the file in errors.
///
/// A leading byte-order mark is skipped (and not counted in columns).
pub fn parse(text: &str, path: &Path) -> Result<Scene, LoadError> {
    parse_sharing(text, path, &[])
}

/// [`parse`], sharing with `like` each object equal to the one at the same
/// place in it: a file read again after a change of one value holds one
/// new object, not a million (and compares equal to `like` at once).
pub fn parse_sharing(text: &str, path: &Path, like: &[Arc<Object>]) -> Result<Scene, LoadError> {
    let body = text.strip_prefix('\u{feff}').unwrap_or(text);
    parse_body(body, path, like, None).map(|(scene, _)| scene)
}

/// Parses `body`, the text after its byte-order mark: in pieces on every
/// core ([`in_pieces`]) where it is big enough and cuts cleanly, else in
/// one, which is also what gives any error. Also where the root's
/// children sit in `body`.
fn parse_body(
    body: &str,
    path: &Path,
    like: &[Arc<Object>],
    progress: Option<&LoadProgress>,
) -> Result<(Scene, Layout), LoadError> {
    // One or two pieces per core, none under PIECE_BYTES.
    let threads = parsing_threads(body.len() as u64);
    let pieces = (2 * threads).min(body.len() / PIECE_BYTES);
    if threads > 1
        && pieces > 1
        && let Some(parsed) = in_pieces(body, path, like, progress, pieces)
    {
        return parsed;
    }
    if let Some(progress) = progress {
        let len = body.len() as u64;
        progress.set(len, 2 * len);
    }
    let mut parser = Parser::new(body, path);
    parser.like = like;
    parser.progress = progress;
    parser.record = true;
    let mut gathered = parser.gathered()?;
    let layout = Layout::take(&mut gathered);
    Ok((gathered.finish(path)?, layout))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Numbers below the one asked for, the same sequence from `seed` on
    /// every run (xorshift): where the loader's tests put their edits.
    pub(super) fn below(seed: u64) -> impl FnMut(usize) -> usize {
        let mut state = seed;
        move |n| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % n as u64) as usize
        }
    }

    /// The parse in one piece, which gives every error.
    pub(super) fn in_one(text: &str) -> Result<Scene, LoadError> {
        Parser::new(text, Path::new("t.xml")).document()
    }

    /// [`in_one`], with where the root's children sit.
    pub(super) fn in_one_laid_out(text: &str) -> Result<(Scene, Layout), LoadError> {
        let mut parser = Parser::new(text, Path::new("t.xml"));
        parser.record = true;
        let mut gathered = parser.gathered()?;
        let layout = Layout::take(&mut gathered);
        Ok((gathered.finish(Path::new("t.xml"))?, layout))
    }

    /// A scene with every kind of element, spread over lines and nested
    /// as people write them, with comments and processing instructions
    /// between the root's children.
    pub(super) fn varied(n: usize) -> String {
        let mut text =
            String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!-- a scene -->\n<scene>\n");
        for i in 0..n {
            let x = i as f64 * 0.37 - 11.0;
            text.push_str(&match i % 7 {
                0 => format!(
                    "  <sphere>\n    <color red=\"{}\" green=\"0.5\" blue=\"1e-3\"/>\n    \
                     <material ka=\"0.1\" m=\"{i}\"/>\n    <transformation>\n      \
                     <scale factor=\"0.25\"/>\n      <translate x=\"{x}\" z=\"7\"/>\n    \
                     </transformation>\n  </sphere>\n",
                    (i % 10) as f64 / 10.0
                ),
                1 => format!(
                    "  <plane><transformation><rotate-x angle=\"{x}\"/><rotate-y angle=\"0.1\"/>\
                     <rotate-z angle=\"-0.2\"/><translate y=\"{i}\"/></transformation></plane>"
                ),
                2 => format!("\t<light x=\"{x}\" y=\"-1\" z=\"-2\"><color red=\"0.5\" green=\"0.5\" blue=\"0.5\"/></light>\n"),
                3 => format!("  <!-- object {i}: <sphere> -->\n  <?pi {i}?>\n"),
                4 => format!(
                    "  <sphere><transformation><scale x=\"1\" y=\"{}\" z=\"3\"/></transformation></sphere>\r\n",
                    1.0 + i as f64
                ),
                5 => format!("  <light x=\"{i}\" y=\"0\" z=\"0\"/>  "),
                _ => "  <sphere/>\n".to_owned(),
            });
            if i == n / 2 {
                text.push_str(
                    "  <camera width=\"8\" height=\"6\" eyeDistance=\"2\">\n    \
                     <transformation><translate z=\"-3\"/></transformation>\n  </camera>\n  \
                     <model type=\"phong\" depth=\"3\"/>\n",
                );
            }
        }
        text.push_str("</scene>\n\n");
        text
    }

    /// A stopped load ends with `Stopped`, whether it was stopped before
    /// it began or while it read or parsed, in one piece or in several;
    /// left alone, the same file loads.
    #[test]
    fn a_stopped_load_ends_and_says_so() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.xml");
        fs::write(&path, varied(300_000)).unwrap();
        let stopped = |progress: &LoadProgress| {
            let e = load_counting(&path, &[], Some(progress)).unwrap_err();
            assert_eq!(e.kind, LoadErrorKind::Stopped, "{e}");
            assert_eq!(e.to_string().matches("stopped").count(), 1, "{e}");
        };
        let before = LoadProgress::default();
        before.stop();
        stopped(&before);
        // Parsing in one: a file small enough not to be cut.
        let small = dir.path().join("small.xml");
        fs::write(&small, varied(20_000)).unwrap();
        let e = parse_body(
            &fs::read_to_string(&small).unwrap(),
            &small,
            &[],
            Some(&before),
        )
        .unwrap_err();
        assert_eq!(e.kind, LoadErrorKind::Stopped);
        // Stopped while it reads or parses: it ends well before a whole load.
        let progress = LoadProgress::default();
        let start = std::time::Instant::now();
        std::thread::scope(|s| {
            s.spawn(|| stopped(&progress));
            while progress.fraction() < 0.3 {
                std::thread::yield_now();
            }
            progress.stop();
        });
        let stopped_after = start.elapsed();
        let start = std::time::Instant::now();
        let whole = LoadProgress::default();
        let scene = load_counting(&path, &[], Some(&whole)).unwrap().scene;
        assert!(!scene.objects.is_empty());
        assert!(
            stopped_after < start.elapsed(),
            "stopped after {stopped_after:?}, a whole load {:?}",
            start.elapsed()
        );
    }

    #[test]
    fn limits_are_the_documented_ones() {
        assert_eq!(MAX_FILE_BYTES, 1 << 30);
        assert_eq!(MAX_OBJECTS, 10_000_000);
        assert_eq!(MAX_LIGHTS, 1_000_000);
        assert_eq!(MAX_PIXELS, 1 << 28);
    }
}
