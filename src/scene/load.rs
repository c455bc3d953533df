//! The scene loader: XML text to a validated [`Scene`] (docs/scene-format.md:
//! Elements, Transformations, Numbers, Everything else in the file and Error
//! messages), or a [`LoadError`] naming the file, the `line:column` and the
//! element and attribute at fault.
//!
//! quick-xml reads the text as a stream of events; a small recursive descent
//! (at most four levels: scene, object, transformation, step) checks each
//! element against the grammar. Positions come from the events' slices, which
//! borrow the text: a slice's address minus the text's address is its byte
//! offset, turned into line and column only when an error is reported.
//!
//! quick-xml is lenient: what it does not check of XML 1.0's
//! well-formedness, [`super::xml`] checks in each piece of markup it
//! delimits (characters, names, whitespace between attributes, comments,
//! processing instructions, the XML declaration and its encoding); at most
//! one byte-order mark, no CDATA section outside the root. A DOCTYPE is
//! refused on purpose (scene files declare no entities). A file libxml2
//! finds not well-formed is refused, with its line and column.
//!
//! A big text (8 MiB or more, on a machine of two cores or more) is parsed
//! in pieces at once, cut before the start tags of the root's children;
//! the cuts are guesses that the pieces' own checks confirm, and any doubt
//! or error parses it again in one ([`in_pieces`]), so what is accepted and
//! every error are those of a parse in one.
//!
//! Nothing here panics on any input, and every count the file controls is
//! checked against its limit before anything is allocated for it.

use super::source::Block;
use std::borrow::Cow;
use std::fs;
use std::io::Read;
use std::path::Path;
use std::sync::Arc;

use quick_xml::Reader;
use quick_xml::escape::EscapeError;
use quick_xml::events::attributes::AttrError;
use quick_xml::events::{BytesStart, Event};

use super::error::{LoadError, LoadErrorKind, Position};
use super::grammar::{
    CAMERA_ATTRS, CAMERA_CHILDREN, COLOR_ATTRS, LIGHT_ATTRS, LIGHT_CHILDREN, MATERIAL_ATTRS,
    MODEL_ATTRS, NONE, OBJECT_CHILDREN, ROTATE_ATTRS, SCALE_ATTRS, SCENE_ATTRS, SCENE_CHILDREN,
    TRANSFORM_CHILDREN, TRANSLATE_ATTRS, XSI_NAMESPACE,
};
use super::xml;
use super::{Camera, Color, Illumination, Light, Material, Model, Object, Objects, Scene, Shape};
use crate::math::{Steps, Transform, TransformError, TransformStep, Vec3};
use smallvec::SmallVec;

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
    }))
}

/// The cores a text of `bytes` is parsed on: 1 below two pieces' worth
/// ([`PIECE_BYTES`]), without asking rayon, whose first call starts its
/// threads: each takes a malloc arena of 64 MiB of address space, which a
/// small scene loaded under `ulimit -v` should not pay for.
fn parsing_threads(bytes: u64) -> usize {
    if bytes < 2 * PIECE_BYTES as u64 {
        1
    } else {
        rayon::current_num_threads()
    }
}

/// Pieces of a streamed text being parsed at once, per core: enough to
/// keep every core busy while the next is read.
const STREAM_AHEAD: usize = 2;

/// A streamed text's pieces ([`streamed`]): small, so that the few held at
/// once are little beside the scene, big enough that each is some
/// thousands of objects.
const STREAM_PIECE_BYTES: usize = 1 << 20;

/// Reads the file at `path` a piece of about [`STREAM_PIECE_BYTES`] at a time,
/// cut as [`in_pieces`] cuts a text, each piece parsed on the cores while
/// the next is read, and at most [`STREAM_AHEAD`] per core held: the
/// memory of a load is the scene's and a few pieces', not the file's.
///
/// As [`in_pieces`], `None` at the least doubt (and then the file is read
/// whole and parsed in one, which gives any error): a file small enough to
/// read at once, a call from a thread of the pool that parses the pieces
/// (it would wait on itself), a read that fails, a text that is not UTF-8,
/// a cut that does not fall between two of the root's children, a text
/// that declares an ASCII encoding (checked of the whole text only).
fn streamed(
    path: &Path,
    like: &Objects,
    pack: bool,
    progress: Option<&LoadProgress>,
) -> Option<Streamed> {
    // A rewrite in place that a crash left half done is finished before
    // the file is looked at ([`crate::system::files::finish`]): no reader sees it
    // mixed, nor its length mid-copy.
    let _ = crate::system::files::finish(path);
    let meta = fs::metadata(path).ok()?;
    if !meta.is_file() || meta.len() > MAX_FILE_BYTES {
        return None;
    }
    let threads = parsing_threads(meta.len());
    if threads < 2 || rayon::current_thread_index().is_some() {
        return None;
    }
    let mut file = fs::File::open(path).ok()?.take(MAX_FILE_BYTES + 1);
    if let Some(progress) = progress {
        progress.set(0, 2 * meta.len());
    }
    let mut blocks: Vec<Option<Block>> = Vec::new();
    let mut comments = false;
    let (done, results) = std::sync::mpsc::channel();
    let path: Arc<Path> = Arc::from(path);
    let mut pieces: Vec<Option<Gathered>> = Vec::new();
    // The scene's objects, each piece's put in as soon as the pieces before
    // it are in (their own lists freed for the next pieces: a second list
    // of a million objects would be 8 MB more); `None` while every object
    // so far is `like`'s own at its place (a save's check: then its list
    // is the scene's). How many so far, the next piece to come.
    let mut objects: Option<Vec<Arc<Object>>> = None;
    let (mut count, mut next) = (0, 0);
    let mut in_flight = 0;
    let mut carry: Vec<u8> = Vec::new();
    let mut total = 0u64;
    let mut first = true;
    // How much of `carry` was searched for a cut and had none: a text with
    // no cut for megabytes (1 GiB of zeros) is searched once, not once
    // per piece read (which made it quadratic: 107 s for 1 GiB).
    let mut searched: usize = 0;
    loop {
        if progress.is_some_and(LoadProgress::is_stopped) {
            return None;
        }
        let mut buf = std::mem::take(&mut carry);
        let wanted = buf.len() + STREAM_PIECE_BYTES;
        buf.reserve(STREAM_PIECE_BYTES);
        let read = (&mut file)
            .take((wanted - buf.len()) as u64)
            .read_to_end(&mut buf)
            .ok()?;
        total += read as u64;
        if total > MAX_FILE_BYTES {
            return None;
        }
        let last = read == 0 || buf.len() < wanted;
        let skip = if first && buf.starts_with("\u{feff}".as_bytes()) {
            3
        } else {
            0
        };
        let end = if last {
            root_end(std::str::from_utf8(&buf).ok()?)?
        } else {
            // The last cut in the piece's second half; none: read on. A
            // `<` within a tag name's length of the old end may be a cut
            // now that its name is whole: searched again.
            let from = (buf.len() / 2).max(searched.saturating_sub(CUT_NAME_BYTES));
            match last_cut(&buf, skip.max(from), buf.len()) {
                Some(cut) => cut,
                None => {
                    searched = buf.len();
                    carry = buf;
                    continue;
                }
            }
        };
        carry = buf.get(end..)?.to_vec();
        searched = 0;
        buf.truncate(end);
        let k = pieces.len();
        pieces.push(None);
        blocks.push(None);
        if let Some(progress) = progress {
            progress.add(buf.len());
        }
        let (done, path, is_first) = (done.clone(), Arc::clone(&path), first);
        rayon::spawn(move || {
            let piece = std::str::from_utf8(buf.get(skip..).unwrap_or_default())
                .ok()
                .and_then(|text| {
                    let mut parser = Parser::new(text, &path);
                    parser.whole = None;
                    let gathered = parser.piece(is_first).ok()?;
                    // The text kept packed (from the byte-order mark on).
                    let kept = pack.then(|| (Block::pack(&buf), text.contains("<!--")));
                    Some((gathered, kept, buf.len()))
                });
            // The loader stops listening only once it has given up.
            let _ = done.send((k, piece));
        });
        first = false;
        in_flight += 1;
        while in_flight >= STREAM_AHEAD * threads || (last && in_flight > 0) {
            let (k, piece) = results.recv().ok()?;
            let (gathered, kept, bytes) = piece?;
            *pieces.get_mut(k)? = Some(gathered);
            if let Some((block, has_comments)) = kept {
                *blocks.get_mut(k)? = Some(block);
                comments |= has_comments;
            }
            if let Some(progress) = progress {
                progress.add(bytes);
            }
            in_flight -= 1;
            // Each piece's objects shared with `like` as soon as the pieces
            // before it are in: a save's check of a million objects holds
            // a few pieces' copies at once, not a second scene (150 MB).
            while let Some(Some(piece)) = pieces.get_mut(next) {
                let mut own = std::mem::take(&mut piece.objects);
                let here = like.get(count..).unwrap_or_default();
                share(&mut own, here);
                count += own.len();
                if count > MAX_OBJECTS {
                    return None;
                }
                let alike =
                    own.len() <= here.len() && own.iter().zip(here).all(|(a, b)| Arc::ptr_eq(a, b));
                match &mut objects {
                    None if alike => {}
                    None => {
                        let before = count - own.len();
                        let mut list = like.get(..before)?.to_vec();
                        list.extend(own);
                        objects = Some(list);
                    }
                    Some(list) => list.extend(own),
                }
                next += 1;
            }
        }
        if last {
            break;
        }
    }
    let pieces = pieces.into_iter().collect::<Option<Vec<_>>>()?;
    let blocks = match pack {
        true => {
            // The root's end tag and what follows it: the last piece's rest.
            blocks.push(Some(Block::pack(&carry)));
            blocks.into_iter().collect::<Option<Vec<_>>>()?
        }
        false => Vec::new(),
    };
    let objects = match objects {
        Some(list) => Objects::from(list),
        None if count == like.len() => like.clone(),
        None => Objects::from(like.get(..count)?.to_vec()),
    };
    Some(Streamed {
        scene: join(pieces, objects, like, &path)?,
        blocks,
        comments,
    })
}

/// What [`streamed`] read: the scene, and when asked for, the text's
/// pieces packed and whether they have a comment.
struct Streamed {
    scene: Scene,
    blocks: Vec<Block>,
    comments: bool,
}

/// Like [`load`], and also returns the file's text (the app keeps it to
/// write edits back into it).
pub fn load_with_text(path: &Path) -> Result<(String, Scene), LoadError> {
    load_sharing(path, &[])
}

/// [`load_with_text`], sharing objects with `like` as [`parse_sharing`]
/// does (the app reading its file again after a change).
pub fn load_sharing(path: &Path, like: &[Arc<Object>]) -> Result<(String, Scene), LoadError> {
    load_counting(path, like, None)
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

/// [`load_sharing`], saying how far it has got in `progress`.
pub fn load_counting(
    path: &Path,
    like: &[Arc<Object>],
    progress: Option<&LoadProgress>,
) -> Result<(String, Scene), LoadError> {
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
    let scene = parse_body(body, path, like, progress)?;
    if let Some(progress) = progress {
        let total = 2 * text.len() as u64;
        progress.set(total, total);
    }
    Ok((text, scene))
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
    parse_body(body, path, like, None)
}

/// Parses `body`, the text after its byte-order mark: in pieces on every
/// core ([`in_pieces`]) where it is big enough and cuts cleanly, else in
/// one, which is also what gives any error.
fn parse_body(
    body: &str,
    path: &Path,
    like: &[Arc<Object>],
    progress: Option<&LoadProgress>,
) -> Result<Scene, LoadError> {
    // One or two pieces per core, none under PIECE_BYTES.
    let threads = parsing_threads(body.len() as u64);
    let pieces = (2 * threads).min(body.len() / PIECE_BYTES);
    if threads > 1
        && pieces > 1
        && let Some(scene) = in_pieces(body, path, like, progress, pieces)
    {
        return Ok(scene);
    }
    if let Some(progress) = progress {
        let len = body.len() as u64;
        progress.set(len, 2 * len);
    }
    let mut parser = Parser::new(body, path);
    parser.like = like;
    parser.progress = progress;
    parser.document()
}

/// Smallest text parsed in pieces, and smallest piece: below it one core
/// is quick enough (a few milliseconds).
const PIECE_BYTES: usize = 1 << 22;

/// Parses `body` in `count` pieces (or fewer), cut just before the `<`
/// of an element that starts a line inside the root: each piece is parsed
/// on its own with every check of a parse in one (the first one from the
/// file's start, through the root's start tag; the last one up to the
/// root's end tag, after which only whitespace may follow), and the
/// pieces' objects and lights joined in order.
///
/// A cut is a guess, made without reading what comes before it: it might
/// fall inside a comment or an attribute value. The guess is checked: a
/// piece that does not end exactly at the next one's start, with nothing
/// left open, fails as an error, and so does anything the pieces would
/// only see whole (a second camera or model, one object or light over the
/// limit). Any failure gives `None`, and the text is parsed again in one
/// piece, which gives the error of a parse in one, at its line and column:
/// what is accepted, and what it makes, is what a parse in one accepts and
/// makes.
fn in_pieces(
    body: &str,
    path: &Path,
    like: &[Arc<Object>],
    progress: Option<&LoadProgress>,
    count: usize,
) -> Option<Scene> {
    use rayon::prelude::*;
    let end = root_end(body)?;
    let mut cuts = vec![0];
    for k in 1..count {
        let from = (end / count * k).max(cuts.last().copied().unwrap_or(0) + 1);
        if let Some(cut) = cut_after(body.as_bytes(), from, end) {
            cuts.push(cut);
        }
    }
    cuts.push(end);
    if let Some(progress) = progress {
        let len = body.len() as u64;
        progress.set(len, 2 * len);
    }
    let pieces: Vec<Gathered> = cuts
        .par_windows(2)
        .enumerate()
        .map(|(k, cut)| {
            let text = body.get(cut[0]..cut[1])?;
            let mut parser = Parser::new(text, path);
            parser.whole = Some(body);
            parser.progress = progress;
            parser.piece(k == 0).ok()
        })
        .collect::<Option<_>>()?;

    join(pieces, Objects::default(), like, path)
}

/// The scene the `pieces` of a text make, joined in order after
/// `objects` (those of the pieces before them); `None` where
/// only a parse in one can tell (a second camera or model, objects or
/// lights over the limit, no camera).
fn join(
    pieces: Vec<Gathered>,
    objects: Objects,
    like: &[Arc<Object>],
    path: &Path,
) -> Option<Scene> {
    let in_pieces = pieces.iter().map(|p| p.objects.len()).sum::<usize>();
    let lights = pieces.iter().map(|p| p.lights.len()).sum::<usize>();
    if objects.len() + in_pieces > MAX_OBJECTS || lights > MAX_LIGHTS {
        return None;
    }
    let mut objects = objects;
    let mut scene = Gathered {
        lights: Vec::with_capacity(lights),
        ..Gathered::default()
    };
    if in_pieces > 0 {
        objects.reserve_exact(in_pieces);
    }
    for piece in pieces {
        if !piece.objects.is_empty() {
            objects.extend(piece.objects);
        }
        scene.lights.extend(piece.lights);
        for (one, found) in [
            (scene.camera.is_some(), piece.camera.is_some()),
            (scene.model.is_some(), piece.model.is_some()),
        ] {
            if one && found {
                return None;
            }
        }
        scene.camera = scene.camera.or(piece.camera);
        scene.model = scene.model.or(piece.model);
    }
    // Shared as a parse in one shares them (a streamed load shared each
    // piece's as it came).
    if in_pieces > 0 {
        share(&mut objects, like);
    }
    scene.finish_with(objects, path).ok()
}

/// Shares with `like` each object equal to the one at the same place.
fn share(objects: &mut [Arc<Object>], like: &[Arc<Object>]) {
    for (object, same) in objects.iter_mut().zip(like) {
        if !Arc::ptr_eq(object, same) && **object == **same {
            *object = Arc::clone(same);
        }
    }
}

/// Is XML whitespace.
fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n')
}

/// The offset of the `<` of `</scene>` where it ends the file (followed by
/// nothing but whitespace); `None` where anything else follows the root.
fn root_end(body: &str) -> Option<usize> {
    let end = body.rfind("</scene")?;
    let rest = body.get(end + "</scene".len()..)?.as_bytes();
    let rest = rest.trim_ascii_start();
    let after = rest.strip_prefix(b">")?;
    after.iter().all(|&b| is_space(b)).then_some(end)
}

/// Whether the `<` at `tag` starts a start tag of one of the root's
/// children (`<sphere`, `<light`, …) before `end`: the grammar allows them
/// nowhere else, so outside a comment, a processing instruction or a CDATA
/// section it is a cut between two of them. One after a `<!--` with no
/// `-->` since, in the 4 KiB before it, is passed over (an object
/// commented out).
fn is_cut(body: &[u8], tag: usize, end: usize) -> bool {
    let name = body.get(tag + 1..end).unwrap_or_default();
    let child = SCENE_CHILDREN.iter().any(|child| {
        name.strip_prefix(child.as_bytes()).is_some_and(|after| {
            after
                .first()
                .is_some_and(|&b| is_space(b) || b == b'/' || b == b'>')
        })
    });
    let in_comment = || {
        let before = body.get(tag.saturating_sub(4096)..tag).unwrap_or_default();
        let last = |what: &[u8]| before.windows(what.len()).rposition(|w| w == what);
        match (last(b"<!--"), last(b"-->")) {
            (Some(open), Some(close)) => open > close,
            (open, _) => open.is_some(),
        }
    };
    child && !in_comment()
}

/// The first cut ([`is_cut`]) at or after `from` and before `end`.
fn cut_after(body: &[u8], from: usize, end: usize) -> Option<usize> {
    let mut at = from;
    loop {
        let tag = at + body.get(at..end)?.iter().position(|&b| b == b'<')?;
        if is_cut(body, tag, end) {
            return Some(tag);
        }
        at = tag + 1;
    }
}

/// Bytes from a `<` to the end of the longest name [`is_cut`] looks for,
/// and the byte after it.
const CUT_NAME_BYTES: usize = 2 + {
    let mut longest = 0;
    let mut i = 0;
    while i < SCENE_CHILDREN.len() {
        if SCENE_CHILDREN[i].len() > longest {
            longest = SCENE_CHILDREN[i].len();
        }
        i += 1;
    }
    longest
};

/// The last cut ([`is_cut`]) at or after `from` and before `end`.
fn last_cut(body: &[u8], from: usize, end: usize) -> Option<usize> {
    let mut before = end;
    loop {
        let tag = from + body.get(from..before)?.iter().rposition(|&b| b == b'<')?;
        if is_cut(body, tag, end) {
            return Some(tag);
        }
        before = tag;
    }
}

/// Why a number attribute was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NumberError {
    /// Not a number at all.
    Invalid,
    /// `inf`, `NaN` or an overflow to infinity.
    NotFinite,
}

/// A number as the format reads it (docs/scene-format.md, Numbers): a
/// finite `f64`, surrounding ASCII whitespace ignored. The edit engine reads
/// values typed on the command line with the same rule.
pub(crate) fn parse_number(text: &str) -> Result<f64, NumberError> {
    match text.trim_ascii().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(NumberError::NotFinite),
        Err(_) => Err(NumberError::Invalid),
    }
}

/// An integer as the format reads it (docs/scene-format.md, Numbers):
/// ASCII digits with an optional leading `+`, surrounding ASCII whitespace
/// ignored; `None` when it is not one or does not fit in a `u64`.
pub(crate) fn parse_integer(text: &str) -> Option<u64> {
    let text = text.trim_ascii();
    let digits = text.strip_prefix('+').unwrap_or(text);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.bytes().try_fold(0u64, |acc, b| {
        acc.checked_mul(10)?.checked_add(u64::from(b - b'0'))
    })
}

/// Largest `width` or `height` on its own (the product is bounded by
/// [`MAX_PIXELS`] too).
pub(crate) const MAX_SIDE: u64 = u32::MAX as u64;

/// A start tag as the reader gave it.
struct Elem<'a> {
    start: BytesStart<'a>,
    /// Byte offset of its `<`.
    at: usize,
    /// `<x/>`: no children and no end tag follow.
    empty: bool,
}

/// What [`Parser::next`] returns once comments, whitespace and the like are
/// skipped.
enum Node<'a> {
    Open(Elem<'a>),
    /// An end tag, with the byte offset of its `<`.
    Close(usize),
    Eof,
}

/// One attribute of an element, its value unescaped.
struct Attr<'b> {
    name: &'static str,
    value: Cow<'b, str>,
    /// Byte offset of the first character of its name.
    at: usize,
}

/// The attributes of one element (names already checked against the
/// element's list, no repeats).
struct Attrs<'b> {
    element: &'static str,
    /// Byte offset of the element's `<`.
    at: usize,
    /// In place: no element of the format has more than four.
    list: SmallVec<[Attr<'b>; 4]>,
}

impl<'b> Attrs<'b> {
    fn get(&self, name: &str) -> Option<&Attr<'b>> {
        self.list.iter().find(|a| a.name == name)
    }
}

/// Everything a `<scene>` gathers before it is checked for completeness.
#[derive(Default)]
struct Gathered {
    objects: Vec<Arc<Object>>,
    lights: Vec<Light>,
    camera: Option<Camera>,
    model: Option<Model>,
}

impl Gathered {
    /// The scene, once it is known to have a camera.
    fn finish(mut self, path: &Path) -> Result<Scene, LoadError> {
        let objects = std::mem::take(&mut self.objects).into();
        self.finish_with(objects, path)
    }

    /// [`Gathered::finish`] with `objects` for the objects.
    fn finish_with(self, objects: Objects, path: &Path) -> Result<Scene, LoadError> {
        let Some(camera) = self.camera else {
            return Err(LoadError::new(path, None, LoadErrorKind::MissingCamera));
        };
        Ok(Scene {
            objects,
            lights: self.lights,
            camera,
            model: self.model.unwrap_or_default(),
        })
    }
}

struct Parser<'a> {
    /// What is parsed: the file's text, or a piece of it ([`in_pieces`]).
    text: &'a str,
    /// The whole text (after its byte-order mark), for what is checked of
    /// the file as a whole; `None` where it is not at hand ([`streamed`]),
    /// and such a check fails (the text is then read whole).
    whole: Option<&'a str>,
    path: &'a Path,
    reader: Reader<&'a [u8]>,
    /// No event seen yet (an XML declaration must come first).
    at_start: bool,
    /// `</scene>` (or `<scene/>`) has been read.
    after_root: bool,
    /// Elements open: 0 outside the root.
    depth: usize,
    /// [`MAX_OBJECTS`] and [`MAX_LIGHTS`], lowered by unit tests.
    max_objects: usize,
    max_lights: usize,
    /// Objects to share where equal ([`parse_sharing`]).
    like: &'a [Arc<Object>],
    /// Where to say how far the parse has got ([`load_counting`]).
    progress: Option<&'a LoadProgress>,
    /// Events read, to update `progress` every so many.
    events: u32,
    /// How far into `text` `progress` has been told.
    reported: usize,
}

impl<'a> Parser<'a> {
    fn new(text: &'a str, path: &'a Path) -> Parser<'a> {
        let mut reader = Reader::from_str(text);
        let config = reader.config_mut();
        config.check_end_names = true;
        config.check_comments = true;
        config.expand_empty_elements = false;
        config.trim_text(false);
        Parser {
            text,
            whole: Some(text),
            path,
            reader,
            at_start: true,
            after_root: false,
            depth: 0,
            max_objects: MAX_OBJECTS,
            max_lights: MAX_LIGHTS,
            like: &[],
            progress: None,
            events: 0,
            reported: 0,
        }
    }

    // ----- positions and errors -----

    /// The byte offset of `slice` in the text, if it is a part of it.
    fn offset_of(&self, slice: &[u8]) -> Option<usize> {
        let offset = (slice.as_ptr() as usize).checked_sub(self.text.as_ptr() as usize)?;
        (offset <= self.text.len()).then_some(offset)
    }

    fn error_at(&self, offset: usize, kind: LoadErrorKind) -> LoadError {
        LoadError::new(
            self.path,
            Some(Position::at_offset(self.text, offset)),
            kind,
        )
    }

    fn xml_at(&self, offset: usize, message: String) -> LoadError {
        self.error_at(offset, LoadErrorKind::Xml { message })
    }

    /// End of file inside `<element>`.
    fn unclosed(&self, element: &str) -> LoadError {
        self.xml_at(
            self.text.len(),
            format!("<{element}> is not closed: the file ends before </{element}>"),
        )
    }

    fn reader_offset(&self) -> usize {
        usize::try_from(self.reader.buffer_position()).unwrap_or(usize::MAX)
    }

    // ----- events -----

    /// The next start tag, end tag or end of file; comments, processing
    /// instructions, the XML declaration and whitespace are skipped, anything
    /// else is an error.
    fn next(&mut self) -> Result<Node<'a>, LoadError> {
        loop {
            let before = self.reader_offset();
            self.events = self.events.wrapping_add(1);
            if self.events.is_multiple_of(4096)
                && let Some(progress) = self.progress
            {
                if progress.is_stopped() {
                    return Err(LoadError::new(self.path, None, LoadErrorKind::Stopped));
                }
                progress.add(before.saturating_sub(self.reported));
                self.reported = before;
            }
            let event = match self.reader.read_event() {
                Ok(event) => event,
                Err(e) => {
                    let at = usize::try_from(self.reader.error_position()).unwrap_or(usize::MAX);
                    let message = match e {
                        quick_xml::Error::Syntax(e) => e.to_string(),
                        quick_xml::Error::IllFormed(e) => e.to_string(),
                        other => other.to_string(),
                    };
                    return Err(self.xml_at(at, message));
                }
            };
            let first = std::mem::replace(&mut self.at_start, false);
            // The markup's text between `<` + `open` bytes and `close`
            // bytes + `>`, checked by `check` (quick-xml delimits markup but
            // does not check what is inside).
            let after = self.reader_offset();
            let inside =
                |open: usize, close: usize, check: &dyn Fn(&str) -> Result<(), xml::Fault>| {
                    let start = before.saturating_add(open);
                    let inner = self
                        .text
                        .get(start..after.saturating_sub(close))
                        .unwrap_or_default();
                    check(inner).map_err(|f| self.xml_at(start.saturating_add(f.at), f.message))
                };
            match event {
                Event::Start(start) => {
                    inside(1, 1, &xml::start_tag)?;
                    self.depth = self.depth.saturating_add(1);
                    return Ok(Node::Open(self.elem(start, before, false)));
                }
                Event::Empty(start) => {
                    inside(1, 2, &xml::start_tag)?;
                    return Ok(Node::Open(self.elem(start, before, true)));
                }
                Event::End(_) => {
                    self.depth = self.depth.saturating_sub(1);
                    return Ok(Node::Close(before));
                }
                Event::Eof => return Ok(Node::Eof),
                Event::Text(text) => self.check_text(&text, before)?,
                Event::CData(data) => {
                    if self.depth == 0 {
                        let what = "a CDATA section";
                        return Err(if self.after_root {
                            self.error_at(
                                before,
                                LoadErrorKind::ContentAfterRoot {
                                    what: what.to_owned(),
                                },
                            )
                        } else {
                            self.xml_at(before, format!("{what} outside the <scene> element"))
                        });
                    }
                    self.check_text(&data, before)?;
                }
                Event::GeneralRef(reference) => {
                    let text = format!("&{};", String::from_utf8_lossy(&reference));
                    return Err(self.text_error(before, text));
                }
                Event::Comment(_) => inside(4, 3, &xml::comment)?,
                Event::PI(_) => inside(2, 2, &xml::processing_instruction)?,
                Event::Decl(_) => {
                    if !first || before != 0 {
                        return Err(self.xml_at(
                            before,
                            "the XML declaration <?xml ...?> must be at the very start of the file"
                                .to_owned(),
                        ));
                    }
                    let ascii = || self.whole.is_some_and(str::is_ascii);
                    inside(5, 2, &|s| xml::declaration(s, &ascii))?;
                }
                Event::DocType(_) => return Err(self.error_at(before, LoadErrorKind::Doctype)),
            }
        }
    }

    fn elem(&self, start: BytesStart<'a>, before: usize, empty: bool) -> Elem<'a> {
        // The tag's bytes start just after its `<`.
        let at = self
            .offset_of(start.name().as_ref())
            .and_then(|o| o.checked_sub(1))
            .unwrap_or(before);
        Elem { start, at, empty }
    }

    /// Character data must be XML whitespace.
    fn check_text(&self, bytes: &[u8], before: usize) -> Result<(), LoadError> {
        let Some(index) = bytes
            .iter()
            .position(|b| !matches!(b, b' ' | b'\t' | b'\r' | b'\n'))
        else {
            return Ok(());
        };
        let at = self
            .offset_of(bytes)
            .unwrap_or(before)
            .saturating_add(index);
        let rest = bytes.get(index..).unwrap_or_default();
        let line = rest
            .split(|&b| b == b'\n' || b == b'\r')
            .next()
            .unwrap_or_default();
        let text = String::from_utf8_lossy(line).trim_end().to_owned();
        Err(self.text_error(at, text))
    }

    fn text_error(&self, at: usize, text: String) -> LoadError {
        let kind = if self.after_root {
            LoadErrorKind::ContentAfterRoot {
                what: format!("text \"{text}\""),
            }
        } else {
            LoadErrorKind::UnexpectedText { text }
        };
        self.error_at(at, kind)
    }

    /// Reads the children of `e` up to its end tag. Each child must be one of
    /// `allowed` (its name is passed to `f`); with `once`, none may repeat.
    fn children(
        &mut self,
        e: &Elem<'a>,
        parent: &'static str,
        allowed: &'static [&'static str],
        once: bool,
        mut f: impl FnMut(&mut Self, &Elem<'a>, &'static str) -> Result<(), LoadError>,
    ) -> Result<(), LoadError> {
        if e.empty {
            return Ok(());
        }
        // Bit i: allowed[i] has been read (the lists are short).
        let mut seen = 0u64;
        loop {
            match self.next()? {
                Node::Open(child) => {
                    let (index, known) = self.known_child(&child, parent, allowed)?;
                    let bit = 1u64
                        .checked_shl(u32::try_from(index).unwrap_or(u32::MAX))
                        .unwrap_or(0);
                    if once {
                        if seen & bit != 0 {
                            return Err(self.error_at(
                                child.at,
                                LoadErrorKind::DuplicateElement {
                                    element: known,
                                    parent,
                                },
                            ));
                        }
                        seen |= bit;
                    }
                    f(self, &child, known)?;
                }
                Node::Close(_) => return Ok(()),
                Node::Eof => return Err(self.unclosed(parent)),
            }
        }
    }

    /// The name of `child` as one of `allowed`, with its index there.
    fn known_child(
        &self,
        child: &Elem<'a>,
        parent: &'static str,
        allowed: &'static [&'static str],
    ) -> Result<(usize, &'static str), LoadError> {
        let name = child.start.name();
        let found = allowed
            .iter()
            .enumerate()
            .find(|(_, a)| a.as_bytes() == name.as_ref());
        match found {
            Some((index, &known)) => Ok((index, known)),
            None => Err(self.error_at(
                child.at,
                LoadErrorKind::UnknownElement {
                    element: String::from_utf8_lossy(name.as_ref()).into_owned(),
                    parent,
                    allowed,
                },
            )),
        }
    }

    /// A leaf element: no children allowed.
    fn leaf(&mut self, e: &Elem<'a>, name: &'static str) -> Result<(), LoadError> {
        self.children(e, name, NONE, false, |_, _, _| Ok(()))
    }

    // ----- attributes -----

    /// The attributes of `e`, checked against `allowed`, without repeats,
    /// their values unescaped.
    fn attrs<'b>(
        &self,
        e: &'b Elem<'a>,
        element: &'static str,
        allowed: &'static [&'static str],
    ) -> Result<Attrs<'b>, LoadError> {
        let mut list: SmallVec<[Attr<'b>; 4]> = SmallVec::new();
        let mut iter = e.start.attributes();
        iter.with_checks(false);
        for attr in iter {
            let attr = attr.map_err(|err| self.attr_syntax_error(e, element, err))?;
            let key: &'b [u8] = attr.key.into_inner();
            let at = self.offset_of(key).unwrap_or(e.at);
            let known = std::str::from_utf8(key)
                .ok()
                .and_then(|k| allowed.iter().copied().find(|&a| a == k));
            let Some(name) = known else {
                return Err(self.error_at(
                    at,
                    LoadErrorKind::UnknownAttribute {
                        element,
                        attribute: String::from_utf8_lossy(key).into_owned(),
                        allowed,
                    },
                ));
            };
            if list.iter().any(|a| a.name == name) {
                return Err(self.error_at(
                    at,
                    LoadErrorKind::DuplicateAttribute {
                        element,
                        attribute: name,
                    },
                ));
            }
            // Without a reference, the value is the text's own slice
            // (what decoding and unescaping would give, without checking
            // the UTF-8 of a text that is a `str` already).
            let plain = match &attr.value {
                Cow::Borrowed(raw) if !raw.contains(&b'&') => self
                    .offset_of(raw)
                    .and_then(|start| self.text.get(start..start + raw.len())),
                _ => None,
            };
            let value = match plain {
                Some(plain) => Ok(Cow::Borrowed(plain)),
                None => attr.decode_and_unescape_value(self.reader.decoder()),
            }
            .map_err(|err| {
                self.error_at(
                    at,
                    LoadErrorKind::BadReference {
                        element,
                        attribute: name,
                        message: reference_message(&err),
                    },
                )
            })?;
            // A literal non-Char was refused with the tag (`xml::start_tag`):
            // one in the unescaped value came from a character reference.
            if let Cow::Owned(unescaped) = &value
                && let Err(f) =
                    xml::chars(unescaped, "an attribute value (from a character reference)")
            {
                return Err(self.error_at(
                    at,
                    LoadErrorKind::BadReference {
                        element,
                        attribute: name,
                        message: f.message,
                    },
                ));
            }
            list.push(Attr { name, value, at });
        }
        Ok(Attrs {
            element,
            at: e.at,
            list,
        })
    }

    fn attr_syntax_error(&self, e: &Elem<'a>, element: &str, err: AttrError) -> LoadError {
        let (relative, what) = match err {
            AttrError::ExpectedEq(p) => (p, "expected `=` after an attribute name".to_owned()),
            AttrError::ExpectedValue(p) => (p, "expected a quoted value after `=`".to_owned()),
            AttrError::UnquotedValue(p) => (p, "attribute value without quotes".to_owned()),
            AttrError::ExpectedQuote(p, q) => (
                p,
                format!("attribute value not closed: missing {}", char::from(q)),
            ),
            AttrError::Duplicated(p, _) => (p, "repeated attribute".to_owned()),
        };
        // Positions are relative to the tag's bytes, which start after `<`.
        let at = e.at.saturating_add(1).saturating_add(relative);
        self.xml_at(at, format!("in <{element}>: {what}"))
    }

    fn required<'c, 'b>(
        &self,
        attrs: &'c Attrs<'b>,
        name: &'static str,
    ) -> Result<&'c Attr<'b>, LoadError> {
        attrs.get(name).ok_or_else(|| {
            self.error_at(
                attrs.at,
                LoadErrorKind::MissingAttribute {
                    element: attrs.element,
                    attribute: name,
                },
            )
        })
    }

    /// A finite number (docs/scene-format.md, Numbers).
    fn number(&self, attrs: &Attrs<'_>, attr: &Attr<'_>) -> Result<f64, LoadError> {
        let fields = || (attrs.element, attr.name, Box::from(attr.value.as_ref()));
        match parse_number(&attr.value) {
            Ok(v) => Ok(v),
            Err(NumberError::NotFinite) => {
                let (element, attribute, value) = fields();
                Err(self.error_at(
                    attr.at,
                    LoadErrorKind::NotFinite {
                        element,
                        attribute,
                        value,
                    },
                ))
            }
            Err(NumberError::Invalid) => {
                let (element, attribute, value) = fields();
                Err(self.error_at(
                    attr.at,
                    LoadErrorKind::InvalidNumber {
                        element,
                        attribute,
                        value,
                    },
                ))
            }
        }
    }

    /// The number `name`, or `default` when absent.
    fn number_or(
        &self,
        attrs: &Attrs<'_>,
        name: &'static str,
        default: f64,
    ) -> Result<f64, LoadError> {
        match attrs.get(name) {
            Some(attr) => self.number(attrs, attr),
            None => Ok(default),
        }
    }

    fn required_number(&self, attrs: &Attrs<'_>, name: &'static str) -> Result<f64, LoadError> {
        let attr = self.required(attrs, name)?;
        self.number(attrs, attr)
    }

    /// `value` must satisfy `ok`, described by `rule`, or the attribute is
    /// out of range.
    fn check(
        &self,
        attrs: &Attrs<'_>,
        name: &'static str,
        value: f64,
        ok: bool,
        rule: &'static str,
    ) -> Result<f64, LoadError> {
        if ok {
            return Ok(value);
        }
        let (at, text) = attrs.get(name).map_or((attrs.at, value.to_string()), |a| {
            (a.at, a.value.as_ref().to_owned())
        });
        Err(self.error_at(
            at,
            LoadErrorKind::OutOfRange {
                element: attrs.element,
                attribute: name,
                value: text.into(),
                rule,
            },
        ))
    }

    fn non_negative(
        &self,
        attrs: &Attrs<'_>,
        name: &'static str,
        value: f64,
    ) -> Result<f64, LoadError> {
        self.check(attrs, name, value, value >= 0.0, ">= 0")
    }

    /// An integer in `min..=max`: ASCII digits with an optional leading `+`
    /// (docs/scene-format.md, Numbers).
    fn integer(
        &self,
        attrs: &Attrs<'_>,
        attr: &Attr<'_>,
        min: u64,
        max: u64,
    ) -> Result<u64, LoadError> {
        match parse_integer(&attr.value) {
            Some(v) if (min..=max).contains(&v) => Ok(v),
            _ => Err(self.error_at(
                attr.at,
                LoadErrorKind::InvalidInteger {
                    element: attrs.element,
                    attribute: attr.name,
                    value: Box::from(attr.value.as_ref()),
                    min,
                    max,
                },
            )),
        }
    }

    // ----- the grammar -----

    fn document(mut self) -> Result<Scene, LoadError> {
        let root = self.root()?;
        let mut scene = Gathered::default();
        self.children(&root, "scene", SCENE_CHILDREN, false, |p, e, name| {
            p.scene_child(e, name, &mut scene)
        })?;
        self.epilogue()?;
        scene.finish(self.path)
    }

    /// The `<scene>` start tag and its attributes, after at most what may
    /// come before it.
    fn root(&mut self) -> Result<Elem<'a>, LoadError> {
        // One byte-order mark is skipped before the parser sees the text
        // (and quick-xml would skip another).
        if self.text.starts_with('\u{feff}') {
            return Err(self.xml_at(
                0,
                "a second byte-order mark: at most one may start the file".to_owned(),
            ));
        }
        let root = match self.next()? {
            Node::Open(e) => e,
            // quick-xml reports an end tag without a start tag itself.
            Node::Close(at) => {
                return Err(self.xml_at(at, "end tag without a start tag".to_owned()));
            }
            Node::Eof => return Err(self.error_at(self.text.len(), LoadErrorKind::MissingRoot)),
        };
        if root.start.name().as_ref() != b"scene" {
            return Err(self.error_at(
                root.at,
                LoadErrorKind::RootNotScene {
                    element: String::from_utf8_lossy(root.start.name().as_ref()).into_owned(),
                },
            ));
        }
        // A scene may name its schema, as editors write it, and nothing else.
        {
            let attrs = self.attrs(&root, "scene", SCENE_ATTRS)?;
            match (
                attrs.get("xmlns:xsi"),
                attrs.get("xsi:noNamespaceSchemaLocation"),
            ) {
                (Some(ns), _) if ns.value != XSI_NAMESPACE => {
                    let value = Some(Box::from(ns.value.as_ref()));
                    return Err(self.error_at(ns.at, LoadErrorKind::SchemaNamespace { value }));
                }
                (None, Some(location)) => {
                    let kind = LoadErrorKind::SchemaNamespace { value: None };
                    return Err(self.error_at(location.at, kind));
                }
                _ => {}
            }
        }
        Ok(root)
    }

    /// After `</scene>`: nothing but what may follow the root.
    fn epilogue(&mut self) -> Result<(), LoadError> {
        self.after_root = true;
        match self.next()? {
            Node::Open(e) => {
                let what = format!(
                    "element <{}>",
                    String::from_utf8_lossy(e.start.name().as_ref())
                );
                Err(self.error_at(e.at, LoadErrorKind::ContentAfterRoot { what }))
            }
            Node::Close(at) => Err(self.xml_at(at, "end tag without a start tag".to_owned())),
            Node::Eof => Ok(()),
        }
    }

    /// One piece of the scene's children ([`in_pieces`]): its whole text,
    /// from the root's start tag for the first piece, from inside the root
    /// for the others. An end tag of the root, or anything left open at
    /// the piece's end, is an error (and the text is parsed in one piece).
    fn piece(mut self, first: bool) -> Result<Gathered, LoadError> {
        if first {
            let root = self.root()?;
            if root.empty {
                return Err(self.xml_at(root.at, "an empty root in a piece".to_owned()));
            }
        } else {
            self.at_start = false;
            self.depth = 1;
        }
        let mut scene = Gathered::default();
        loop {
            match self.next()? {
                Node::Open(child) => {
                    let (_, name) = self.known_child(&child, "scene", SCENE_CHILDREN)?;
                    self.scene_child(&child, name, &mut scene)?;
                }
                Node::Close(at) => {
                    return Err(self.xml_at(at, "the root ends inside a piece".to_owned()));
                }
                Node::Eof => return Ok(scene),
            }
        }
    }

    fn scene_child(
        &mut self,
        e: &Elem<'a>,
        name: &'static str,
        scene: &mut Gathered,
    ) -> Result<(), LoadError> {
        if let Some(shape) = Shape::from_name(name) {
            if scene.objects.len() >= self.max_objects {
                return Err(self.error_at(
                    e.at,
                    LoadErrorKind::TooManyObjects {
                        limit: self.max_objects,
                    },
                ));
            }
            let object = self.object(e, shape)?;
            let object = match self.like.get(scene.objects.len()) {
                Some(same) if **same == object => Arc::clone(same),
                _ => Arc::new(object),
            };
            scene.objects.push(object);
            return Ok(());
        }
        match name {
            "light" => {
                if scene.lights.len() >= self.max_lights {
                    return Err(self.error_at(
                        e.at,
                        LoadErrorKind::TooManyLights {
                            limit: self.max_lights,
                        },
                    ));
                }
                let light = self.light(e)?;
                scene.lights.push(light);
            }
            "camera" => {
                if scene.camera.is_some() {
                    return Err(self.error_at(e.at, LoadErrorKind::SecondCamera));
                }
                scene.camera = Some(self.camera(e)?);
            }
            _ => {
                if scene.model.is_some() {
                    return Err(self.error_at(e.at, LoadErrorKind::SecondModel));
                }
                scene.model = Some(self.model(e)?);
            }
        }
        Ok(())
    }

    fn object(&mut self, e: &Elem<'a>, shape: Shape) -> Result<Object, LoadError> {
        let name = shape.name();
        self.attrs(e, name, NONE)?;
        let mut color = None;
        let mut material = None;
        let mut transform = None;
        self.children(e, name, OBJECT_CHILDREN, true, |p, child, child_name| {
            match child_name {
                "color" => color = Some(p.color(child)?),
                "material" => material = Some(p.material(child)?),
                _ => transform = Some(p.transformation(child)?),
            }
            Ok(())
        })?;
        Ok(Object {
            shape,
            color: color.unwrap_or(Vec3::ONE),
            material: material.unwrap_or_default(),
            transform: transform.unwrap_or_default(),
        })
    }

    fn color(&mut self, e: &Elem<'a>) -> Result<Color, LoadError> {
        let color = {
            let a = self.attrs(e, "color", COLOR_ATTRS)?;
            let mut c = [0.0; 3];
            for (slot, name) in c.iter_mut().zip(COLOR_ATTRS) {
                let v = self.required_number(&a, name)?;
                *slot = self.non_negative(&a, name, v)?;
            }
            Vec3::from_array(c)
        };
        self.leaf(e, "color")?;
        Ok(color)
    }

    fn material(&mut self, e: &Elem<'a>) -> Result<Material, LoadError> {
        let material = {
            let a = self.attrs(e, "material", MATERIAL_ATTRS)?;
            let d = Material::default();
            let get = |name: &'static str, default: f64| -> Result<f64, LoadError> {
                let v = self.number_or(&a, name, default)?;
                self.non_negative(&a, name, v)
            };
            Material {
                ka: get("ka", d.ka)?,
                kd: get("kd", d.kd)?,
                ks: get("ks", d.ks)?,
                m: get("m", d.m)?,
            }
        };
        self.leaf(e, "material")?;
        Ok(material)
    }

    fn light(&mut self, e: &Elem<'a>) -> Result<Light, LoadError> {
        let position = {
            let a = self.attrs(e, "light", LIGHT_ATTRS)?;
            Vec3::new(
                self.required_number(&a, "x")?,
                self.required_number(&a, "y")?,
                self.required_number(&a, "z")?,
            )
        };
        let mut color = None;
        self.children(e, "light", LIGHT_CHILDREN, true, |p, child, _| {
            color = Some(p.color(child)?);
            Ok(())
        })?;
        Ok(Light {
            position,
            color: color.unwrap_or(Vec3::ONE),
        })
    }

    fn camera(&mut self, e: &Elem<'a>) -> Result<Camera, LoadError> {
        let (width, height, eye_distance) = {
            let a = self.attrs(e, "camera", CAMERA_ATTRS)?;
            let width = self.integer(&a, self.required(&a, "width")?, 1, MAX_SIDE)?;
            let height = self.integer(&a, self.required(&a, "height")?, 1, MAX_SIDE)?;
            let eye = self.required_number(&a, "eyeDistance")?;
            let eye = self.check(&a, "eyeDistance", eye, eye > 0.0, "> 0")?;
            (width, height, eye)
        };
        // Both are at most u32::MAX: the product fits in a u64.
        if width.saturating_mul(height) > MAX_PIXELS {
            return Err(self.error_at(
                e.at,
                LoadErrorKind::ImageTooLarge {
                    width,
                    height,
                    limit: MAX_PIXELS,
                },
            ));
        }
        let mut transform = None;
        self.children(e, "camera", CAMERA_CHILDREN, true, |p, child, _| {
            transform = Some(p.transformation(child)?);
            Ok(())
        })?;
        Ok(Camera {
            width: u32::try_from(width).unwrap_or(u32::MAX),
            height: u32::try_from(height).unwrap_or(u32::MAX),
            eye_distance,
            transform: transform.unwrap_or_default(),
        })
    }

    fn model(&mut self, e: &Elem<'a>) -> Result<Model, LoadError> {
        let model = {
            let a = self.attrs(e, "model", MODEL_ATTRS)?;
            let kind = self.required(&a, "type")?;
            let Some(illumination) = Illumination::from_name(kind.value.trim_ascii()) else {
                return Err(self.error_at(
                    kind.at,
                    LoadErrorKind::UnknownModel {
                        value: Box::from(kind.value.as_ref()),
                    },
                ));
            };
            let depth = match a.get("depth") {
                Some(attr) => self.integer(&a, attr, 0, u64::from(Model::MAX_DEPTH))?,
                None => 1,
            };
            Model {
                illumination,
                depth: u32::try_from(depth).unwrap_or(Model::MAX_DEPTH),
            }
        };
        self.leaf(e, "model")?;
        Ok(model)
    }

    fn transformation(&mut self, e: &Elem<'a>) -> Result<Transform, LoadError> {
        self.attrs(e, "transformation", NONE)?;
        let mut steps = Steps::new();
        // Each step's `<` and name, for an overflow's message.
        let mut places: SmallVec<[(usize, &'static str); 2]> = SmallVec::new();
        self.children(
            e,
            "transformation",
            TRANSFORM_CHILDREN,
            false,
            |p, child, name| {
                steps.push(p.step(child, name)?);
                places.push((child.at, name));
                Ok(())
            },
        )?;
        Transform::from_steps(steps).map_err(|err| match err {
            TransformError::Singular { .. } => {
                self.error_at(e.at, LoadErrorKind::SingularTransform)
            }
            TransformError::Overflow { step } => {
                let (at, step) = places
                    .get(step)
                    .copied()
                    .unwrap_or((e.at, "transformation"));
                self.error_at(at, LoadErrorKind::TransformOverflow { step })
            }
        })
    }

    fn step(&mut self, e: &Elem<'a>, name: &'static str) -> Result<TransformStep, LoadError> {
        let step = match name {
            "translate" => {
                let a = self.attrs(e, name, TRANSLATE_ATTRS)?;
                TransformStep::Translate(Vec3::new(
                    self.number_or(&a, "x", 0.0)?,
                    self.number_or(&a, "y", 0.0)?,
                    self.number_or(&a, "z", 0.0)?,
                ))
            }
            "rotate-x" | "rotate-y" | "rotate-z" => {
                let a = self.attrs(e, name, ROTATE_ATTRS)?;
                let angle = self.required_number(&a, "angle")?;
                match name {
                    "rotate-x" => TransformStep::RotateX(angle),
                    "rotate-y" => TransformStep::RotateY(angle),
                    _ => TransformStep::RotateZ(angle),
                }
            }
            _ => {
                let a = self.attrs(e, name, SCALE_ATTRS)?;
                let mut factor_seen = false;
                let mut axis_seen = false;
                for attr in &a.list {
                    if attr.name == "factor" {
                        factor_seen = true;
                    } else {
                        axis_seen = true;
                    }
                    if factor_seen && axis_seen {
                        return Err(self.error_at(
                            attr.at,
                            LoadErrorKind::ScaleFactorWithAxes {
                                attribute: attr.name,
                            },
                        ));
                    }
                }
                match a.get("factor") {
                    Some(factor) => TransformStep::UniformScale(self.number(&a, factor)?),
                    None => TransformStep::Scale(Vec3::new(
                        self.number_or(&a, "x", 1.0)?,
                        self.number_or(&a, "y", 1.0)?,
                        self.number_or(&a, "z", 1.0)?,
                    )),
                }
            }
        };
        self.leaf(e, name)?;
        Ok(step)
    }
}

/// A one-line description of a bad reference in an attribute value.
fn reference_message(err: &quick_xml::Error) -> String {
    match err {
        quick_xml::Error::Escape(EscapeError::UnrecognizedEntity(_, name)) => format!(
            "unknown entity &{name}; (only &lt; &gt; &amp; &apos; &quot; and character references like &#49; are allowed)"
        ),
        quick_xml::Error::Escape(EscapeError::UnterminatedEntity(_)) => {
            "'&' without a closing ';' (write &amp; for a literal '&')".to_owned()
        }
        quick_xml::Error::Escape(EscapeError::InvalidCharRef(e)) => {
            format!("invalid character reference: {e}")
        }
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parse in one piece, which gives every error.
    fn in_one(text: &str) -> Result<Scene, LoadError> {
        Parser::new(text, Path::new("t.xml")).document()
    }

    /// A scene with every kind of element, spread over lines and nested
    /// as people write them, with comments and processing instructions
    /// between the root's children.
    fn varied(n: usize) -> String {
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

    /// Each object of `objects` is the one at its place in `like`.
    fn all_shared(objects: &[Arc<Object>], like: &[Arc<Object>]) -> bool {
        objects.iter().zip(like).all(|(a, b)| Arc::ptr_eq(a, b))
    }

    /// A parse in pieces either makes what the parse in one makes, to the
    /// bit, or gives way to it.
    fn agrees(text: &str, count: usize) -> Result<bool, String> {
        let one = in_one(text);
        match in_pieces(text, Path::new("t.xml"), &[], None, count) {
            None => Ok(false),
            Some(pieces) => match one {
                Ok(one) if format!("{one:?}") == format!("{pieces:?}") => Ok(true),
                Ok(_) => Err(format!("{count} pieces made another scene")),
                Err(e) => Err(format!("{count} pieces accepted what one refuses: {e}")),
            },
        }
    }

    #[test]
    fn pieces_make_what_one_piece_makes() {
        let text = varied(700);
        for count in [2, 3, 7, 16, 64, 500] {
            assert_eq!(agrees(&text, count), Ok(true), "{count} pieces");
        }
        // The objects come back shared as a parse in one shares them.
        let like = in_one(&text).unwrap().objects;
        let again = in_pieces(&text, Path::new("t.xml"), &like, None, 5).unwrap();
        assert!(all_shared(&again.objects, &like));
    }

    #[test]
    fn a_text_the_pieces_misread_is_parsed_in_one() {
        // Bits of markup put where a cut may fall: whatever the pieces
        // then make must be what one piece makes, and anything refused is
        // refused by the pieces too.
        let base = varied(120);
        let inserts = [
            "</scene>",
            "<camera width=\"2\" height=\"2\" eyeDistance=\"1\"/>",
            "<model type=\"lambert\"/>",
            "<!--",
            "-->",
            "<!-- <sphere/> -->",
            "<sphere>",
            "</sphere>",
            "<![CDATA[",
            "]]>",
            "<?xml version=\"1.0\"?>",
            "<?",
            "x",
            "&amp;",
            "\"",
            "<scene>",
            "<light x=\"1\" y=\"2\" z=\"3\"/>",
            "\u{feff}",
        ];
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut next = move |n: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % n as u64) as usize
        };
        let mut clean = 0;
        for round in 0..400 {
            let mut text = base.clone();
            for _ in 0..1 + round % 3 {
                let mut at = next(text.len());
                while !text.is_char_boundary(at) {
                    at -= 1;
                }
                if round % 5 == 4 {
                    // A cut out instead.
                    let mut to = (at + next(40)).min(text.len());
                    while !text.is_char_boundary(to) {
                        to -= 1;
                    }
                    text.replace_range(at..to, "");
                } else {
                    text.insert_str(at, inserts[next(inserts.len())]);
                }
            }
            for count in [2, 5, 13] {
                match agrees(&text, count) {
                    Ok(true) => clean += 1,
                    Ok(false) => {}
                    Err(e) => panic!("round {round}: {e}\n{text}"),
                }
            }
        }
        // Most changes fall inside a piece that then fails, or leave the
        // scene valid; some of the valid ones are cut cleanly.
        assert!(clean > 0, "no mutated text was parsed in pieces");
    }

    #[test]
    fn cuts_fall_before_the_roots_children_only() {
        let text = "<scene> <sphere/><spheres/><light\tx=\"1\"/> <!-- <plane> --></scene>";
        assert_eq!(&text[root_end(text).unwrap()..], "</scene>");
        let cut = |text: &str, from| cut_after(text.as_bytes(), from, root_end(text).unwrap());
        assert_eq!(cut(text, 1), Some(8));
        assert_eq!(cut(text, 9), Some(27));
        // Inside a comment: passed over.
        assert_eq!(cut(text, 28), None);
        let bytes = text.as_bytes();
        assert_eq!(last_cut(bytes, 0, bytes.len()), Some(27));
        assert_eq!(last_cut(bytes, 0, 27), Some(8));
        assert_eq!(last_cut(bytes, 9, 27), None);
        assert_eq!(cut("<scene><!-- --> <plane/></scene>", 1), Some(16));
        assert_eq!(root_end("<scene/>"), None);
        assert_eq!(root_end("<scene></scene> <!-- -->"), None);
        assert_eq!(root_end("<scene></scene >\n\t"), Some(7));
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
        let (_, scene) = load_counting(&path, &[], Some(&whole)).unwrap();
        assert!(!scene.objects.is_empty());
        assert!(
            stopped_after < start.elapsed(),
            "stopped after {stopped_after:?}, a whole load {:?}",
            start.elapsed()
        );
    }

    #[test]
    fn a_big_file_is_streamed_with_the_errors_of_one() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.xml");
        let text = varied(100_000);
        let check = |text: &str, streams: bool| {
            fs::write(&path, text).unwrap();
            let body = text.strip_prefix('\u{feff}').unwrap_or(text);
            let one = format!("{:?}", in_one(body).map_err(|e| e.to_string()));
            let loaded = format!("{:?}", load(&path).map_err(|e| e.to_string()));
            let read = format!(
                "{:?}",
                load_with_text(&path)
                    .map(|(_, s)| s)
                    .map_err(|e| e.to_string())
            );
            assert_eq!(loaded.replace(&path.display().to_string(), "t.xml"), one);
            assert_eq!(loaded, read);
            let streamed = streamed(&path, &Objects::default(), false, None).map(|s| s.scene);
            assert_eq!(streamed.is_some(), streams, "{}", &text[..60]);
            if let Some(scene) = streamed {
                assert_eq!(format!("{:?}", Ok::<_, String>(scene)), one);
            }
        };
        check(&text, true);
        check(&format!("\u{feff}{text}"), true);
        // Objects commented out, a comment at every line start.
        check(&text.replace("  <sphere/>", "  <!-- <sphere/> -->"), true);
        check(&text.replace("\n  <", "\n<!---->  <"), true);
        // Checked of the whole text: read whole.
        check(
            &text.replace("encoding=\"UTF-8\"", "encoding=\"US-ASCII\""),
            false,
        );
        // Errors anywhere: read whole, the error of a parse in one.
        for at in [0.1, 0.5, 0.99] {
            let at = (text.len() as f64 * at) as usize;
            let at = at + text[at..].find("<light").unwrap();
            for insert in [
                "<light x=\"1\" y=\"no\" z=\"0\"/>",
                "<camera width=\"1\" height=\"1\" eyeDistance=\"1\"/>",
                "<!--",
                "</scene>",
                "\u{0}",
            ] {
                let mut bad = text.clone();
                bad.insert_str(at, insert);
                check(&bad, false);
            }
        }
        let mut not_utf8 = text.clone().into_bytes();
        not_utf8[text.len() / 2] = 0xff;
        fs::write(&path, &not_utf8).unwrap();
        assert!(streamed(&path, &Objects::default(), false, None).is_none());
        assert!(matches!(
            load(&path).unwrap_err().kind,
            LoadErrorKind::NotUtf8 { .. }
        ));
        check(&text.replace("</scene>", "</scene><!-- after -->"), false);
    }

    #[test]
    fn a_large_file_is_loaded_with_its_text_packed() {
        use crate::scene::source::PACK_BYTES;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.xml");
        let text = format!("\u{feff}{}", varied(200_000));
        assert!(text.len() >= PACK_BYTES, "{}", text.len());
        fs::write(&path, &text).unwrap();
        let loaded = load_packed(&path, None).unwrap().expect("streamed");
        assert!(loaded.text.is_packed());
        assert!(
            loaded.text.is(&text),
            "the file's text, byte-order mark and all"
        );
        assert!(loaded.comments);
        assert_eq!(loaded.scene, load(&path).unwrap());
        // No comment: said so.
        let plain: String = text
            .split_inclusive('\n')
            .filter(|line| !line.contains("<!--"))
            .collect();
        fs::write(&path, &plain).unwrap();
        assert!(!load_packed(&path, None).unwrap().unwrap().comments);
        // Stopped: said so.
        let progress = LoadProgress::default();
        progress.stop();
        let err = load_packed(&path, Some(&progress)).err().unwrap();
        assert_eq!(err.kind, LoadErrorKind::Stopped);
        // Broken: not streamed, for the whole read to give the error.
        fs::write(&path, plain.replacen("<light", "<lihgt", 1)).unwrap();
        assert!(load_packed(&path, None).unwrap().is_none());
        // Small: not packed.
        fs::write(&path, varied(10)).unwrap();
        assert!(load_packed(&path, None).unwrap().is_none());
    }

    #[test]
    fn a_streamed_load_shares_the_objects_it_is_like() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.xml");
        let text = varied(100_000);
        fs::write(&path, &text).unwrap();
        let like = in_one(&text).unwrap().objects;
        // Every object shared; one changed in the file: that one not.
        let again = streamed(&path, &like, false, None).expect("streamed").scene;
        assert_eq!(again.objects.len(), like.len());
        assert!(all_shared(&again.objects, &like));
        // Every one of them: the very list (a save's check makes none).
        assert!(again.objects.same_list(&like));
        let at = text.len() / 2;
        // (Not the one in a comment.)
        let at = at + text[at..].find("\n  <sphere>\n").unwrap() + 1;
        let changed = format!("{}<sphere/>{}", &text[..at], &text[at..]);
        fs::write(&path, &changed).unwrap();
        let shifted = streamed(&path, &like, false, None).expect("streamed").scene;
        let k = shifted
            .objects
            .iter()
            .zip(&like)
            .position(|(a, b)| !Arc::ptr_eq(a, b))
            .unwrap();
        assert_eq!(shifted, in_one(&changed).unwrap());
        assert!(k > 0, "the objects before the inserted one are shared");
        assert!(!shifted.objects.same_list(&like));
        // A file with one object fewer (the last sphere): a list of its own
        // too.
        let last = text.rfind("\n  <sphere>\n").unwrap() + 1;
        let end = last + text[last..].find("</sphere>\n").unwrap() + "</sphere>\n".len();
        let cut = text[..last].to_owned() + &text[end..];
        let fewer = in_one(&cut).unwrap();
        fs::write(&path, &cut).unwrap();
        let streamed = streamed(&path, &like, false, None).expect("streamed");
        assert_eq!(streamed.scene, fewer);
        assert!(fewer.objects.len() < like.len());
        assert!(!streamed.scene.objects.same_list(&like));
    }

    #[test]
    fn a_big_text_is_read_in_pieces_with_the_errors_of_one() {
        // Big enough for pieces on a machine of two cores or more.
        let text = varied(100_000);
        assert!(text.len() > 2 * PIECE_BYTES, "{}", text.len());
        let path = Path::new("t.xml");
        assert_eq!(
            format!("{:?}", parse(&text, path)),
            format!("{:?}", in_one(&text))
        );
        // An error three quarters in: the same message, line and column.
        let at = text.len() * 3 / 4;
        let at = at + text[at..].find("<light").unwrap();
        let mut bad = text.clone();
        bad.insert_str(at, "<light x=\"1\" y=\"nope\" z=\"0\"/>");
        let error = parse(&bad, path).unwrap_err().to_string();
        assert_eq!(error, in_one(&bad).unwrap_err().to_string());
        assert!(error.contains("nope"), "{error}");
    }

    fn parse_with_limits(text: &str, objects: usize, lights: usize) -> Result<Scene, LoadError> {
        let mut parser = Parser::new(text, Path::new("t.xml"));
        parser.max_objects = objects;
        parser.max_lights = lights;
        parser.document()
    }

    const CAMERA: &str = r#"<camera width="2" height="2" eyeDistance="1"/>"#;

    #[test]
    fn object_count_is_refused_at_the_first_one_over_the_limit() {
        let text = format!("<scene>{CAMERA}\n<sphere/>\n<plane/>\n<sphere/>\n</scene>");
        assert_eq!(
            parse_with_limits(&text, 3, 1).map(|s| s.objects.len()),
            Ok(3)
        );
        let err = parse_with_limits(&text, 2, 1).expect_err("over the limit");
        assert_eq!(err.kind, LoadErrorKind::TooManyObjects { limit: 2 });
        assert_eq!(err.position, Some(Position { line: 4, column: 1 }));
        assert_eq!(
            err.to_string(),
            "t.xml:4:1: too many objects: more than the limit of 2"
        );
    }

    #[test]
    fn light_count_is_refused_at_the_first_one_over_the_limit() {
        let light = r#"<light x="0" y="0" z="0"/>"#;
        let text = format!("<scene>\n{light}{light} {light}{CAMERA}</scene>");
        assert_eq!(
            parse_with_limits(&text, 1, 3).map(|s| s.lights.len()),
            Ok(3)
        );
        let err = parse_with_limits(&text, 1, 2).expect_err("over the limit");
        assert_eq!(err.kind, LoadErrorKind::TooManyLights { limit: 2 });
        let column = 2 * light.chars().count() + 2;
        assert_eq!(err.position, Some(Position { line: 2, column }));
    }

    #[test]
    fn limits_are_the_documented_ones() {
        assert_eq!(MAX_FILE_BYTES, 1 << 30);
        assert_eq!(MAX_OBJECTS, 10_000_000);
        assert_eq!(MAX_LIGHTS, 1_000_000);
        assert_eq!(MAX_PIXELS, 1 << 28);
    }
}
