//! A big text parsed on every core (8 MiB or more, on a machine of two
//! cores or more): a text held whole is cut in pieces ([`in_pieces`]), a
//! file is read and parsed a piece at a time ([`streamed`]), each piece
//! parsed at once by a [`Parser`] of its own and the pieces' objects,
//! lights and places (where each child of the root sits, counted in the
//! whole text) joined in order ([`join`]).
//!
//! The cuts fall before the start tags of the root's children; they are
//! guesses made without reading what comes before, which the pieces' own
//! checks confirm. Any doubt or error gives `None`, and the caller parses
//! the text again in one, so what is accepted and every error are those of
//! a parse in one. Kept apart from the parser: it only chooses where to
//! cut and joins what the pieces gather.

use std::fs;
use std::io::Read;
use std::path::Path;
use std::sync::Arc;

use super::parser::{Gathered, Parser};
use super::reading::Layout;
use super::{LoadProgress, MAX_FILE_BYTES, MAX_LIGHTS, MAX_OBJECTS};
use crate::scene::error::LoadError;
use crate::scene::grammar::SCENE_CHILDREN;
use crate::scene::source::Block;
use crate::scene::{Object, Objects, Scene};

/// The cores a text of `bytes` is parsed on: 1 below two pieces' worth
/// ([`PIECE_BYTES`]), without asking rayon, whose first call starts its
/// threads: each takes a malloc arena of 64 MiB of address space, which a
/// small scene loaded under `ulimit -v` should not pay for.
pub(super) fn parsing_threads(bytes: u64) -> usize {
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
pub(super) fn streamed(
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
    // Where the next piece starts in the file, and the byte-order mark's
    // length: the pieces' places are in the text after it.
    let (mut offset, mut bom) = (0, 0);
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
        if first {
            bom = skip;
        }
        let base = offset + skip - bom;
        offset += buf.len();
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
                    parser.record = true;
                    parser.base = base;
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
    // The last piece ends at the root's end tag.
    let (scene, mut layout) = join(pieces, objects, like, &path, offset - bom)?;
    layout.bom = bom;
    Some(Streamed {
        scene,
        layout,
        blocks,
        comments,
    })
}

/// What [`streamed`] read: the scene, where the root's children sit in
/// the text, and when asked for, the text's pieces packed and whether
/// they have a comment.
pub(super) struct Streamed {
    pub(super) scene: Scene,
    pub(super) layout: Layout,
    pub(super) blocks: Vec<Block>,
    pub(super) comments: bool,
}

/// Smallest text parsed in pieces, and smallest piece: below it one core
/// is quick enough (a few milliseconds).
pub(super) const PIECE_BYTES: usize = 1 << 22;

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
/// limit). Where a piece fails, those before it confirmed its cut, and
/// the text is read on from that cut as a parse in one reads it
/// ([`Parser::document_from`]); where that cannot be (the first piece
/// fails, or a second camera in the pieces before), `None`, and the text is
/// parsed again in one. Either way the error is that of a parse in one,
/// at its line and column: what is accepted, and what it makes, is what a
/// parse in one accepts and makes, and where its children sit.
pub(super) fn in_pieces(
    body: &str,
    path: &Path,
    like: &[Arc<Object>],
    progress: Option<&LoadProgress>,
    count: usize,
) -> Option<Result<(Scene, Layout), LoadError>> {
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
    let pieces: Vec<Option<Gathered>> = cuts
        .par_windows(2)
        .enumerate()
        .map(|(k, cut)| {
            let text = body.get(cut[0]..cut[1])?;
            let mut parser = Parser::new(text, path);
            parser.whole = Some(body);
            parser.progress = progress;
            parser.record = true;
            parser.base = cut[0];
            parser.piece(k == 0).ok()
        })
        .collect();
    let Some(failed) = pieces.iter().position(Option::is_none) else {
        let pieces = pieces.into_iter().flatten().collect();
        return join(pieces, Objects::default(), like, path, end).map(Ok);
    };
    // The pieces before the first that failed confirmed its cut: the text
    // is read on from there in one, gathered so far what they gathered (an
    // error in the middle of a million objects costs a piece's parse more
    // than a clean text, not a second parse of the whole).
    let before = pieces
        .into_iter()
        .take(failed)
        .flatten()
        .collect::<Vec<_>>();
    if before.is_empty() {
        return None;
    }
    let (mut before, mut objects) = gather(before, Objects::default(), like)?;
    before.objects = std::mem::take(&mut *objects);
    let mut parser = Parser::new(body, path);
    parser.like = like;
    parser.progress = progress;
    parser.record = true;
    parser
        .document_from(*cuts.get(failed)?, before)
        .map(|read| {
            read.and_then(|(mut scene, _)| {
                let layout = Layout::take(&mut scene);
                scene.finish(path).map(|scene| (scene, layout))
            })
        })
}

/// The scene the `pieces` of a text make, joined in order after
/// `objects` (those of the pieces before them), and where its children
/// sit (the root's end tag at `end`); `None` where only a parse in one
/// can tell (a second camera or model, objects or lights over the limit,
/// no camera).
fn join(
    pieces: Vec<Gathered>,
    objects: Objects,
    like: &[Arc<Object>],
    path: &Path,
    end: usize,
) -> Option<(Scene, Layout)> {
    let (mut scene, objects) = gather(pieces, objects, like)?;
    scene.content_end = Some(end);
    let layout = Layout::take(&mut scene);
    Some((scene.finish_with(objects, path).ok()?, layout))
}

/// What the `pieces` of a text gather, joined in order after `objects`
/// (those of the pieces before them), the objects apart; `None` where only
/// a parse in one can tell (a second camera or model, objects or lights
/// over the limit).
fn gather(
    pieces: Vec<Gathered>,
    objects: Objects,
    like: &[Arc<Object>],
) -> Option<(Gathered, Objects)> {
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
        scene.places.extend(piece.places);
        scene.content_start = scene.content_start.or(piece.content_start);
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
    Some((scene, objects))
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

#[cfg(test)]
mod tests {
    use super::super::tests::{below, in_one, in_one_laid_out, varied};
    use super::*;
    use crate::scene::error::LoadErrorKind;
    use crate::scene::{load, load_counting, load_packed, load_with_text, parse};

    /// Each object of `objects` is the one at its place in `like`.
    fn all_shared(objects: &[Arc<Object>], like: &[Arc<Object>]) -> bool {
        objects.iter().zip(like).all(|(a, b)| Arc::ptr_eq(a, b))
    }

    /// A parse in pieces either makes what the parse in one makes, to the
    /// bit, error included, or gives way to it; `Ok(true)` where it made it.
    fn agrees(text: &str, count: usize) -> Result<bool, String> {
        let one = format!("{:?}", in_one_laid_out(text));
        match in_pieces(text, Path::new("t.xml"), &[], None, count) {
            None => Ok(false),
            Some(pieces) if format!("{pieces:?}") == one => Ok(true),
            Some(pieces) => Err(format!("{count} pieces made {pieces:?}, one piece {one}")),
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
        let again = in_pieces(&text, Path::new("t.xml"), &like, None, 5)
            .unwrap()
            .unwrap();
        assert!(all_shared(&again.0.objects, &like));
    }

    #[test]
    fn an_error_after_the_first_piece_is_found_reading_on_from_its_cut() {
        let text = varied(700);
        // An error at each tenth of the text after the first piece, in
        // several kinds; a second camera or model is seen only when the
        // pieces are joined (`None`: the text is parsed again in one).
        let faults = [
            ("  <sphere>\n", "  <sphere><sphere>\n", false),
            ("<light ", "<light y=\"1\" ", false),
            ("</sphere>", "</plane>", false),
            ("ka=\"", "ka=\"-", false),
            (
                "<plane",
                "<camera width=\"2\" height=\"2\" eyeDistance=\"1\"/><plane",
                true,
            ),
            ("<plane", "<model type=\"lambert\"/><plane", true),
            ("  <sphere>\n", "  x<sphere>\n", false),
        ];
        for (k, (find, put, joined)) in faults.iter().enumerate() {
            for tenth in 2..10 {
                let from = text.len() * tenth / 10;
                let at = from + text[from..].find(find).unwrap();
                let mut bad = text.clone();
                bad.replace_range(at..at + find.len(), put);
                let found = in_pieces(&bad, Path::new("t.xml"), &[], None, 7);
                assert!(in_one(&bad).is_err(), "fault {k} is no fault");
                if *joined && found.is_none() {
                    continue;
                }
                assert_eq!(
                    format!("{found:?}"),
                    format!("{:?}", Some(in_one(&bad))),
                    "fault {k} at {tenth}/10"
                );
            }
        }
        // In the first piece: parsed again in one.
        let at = text.find("  <sphere>\n").unwrap();
        let mut bad = text.clone();
        bad.insert(at, 'x');
        assert!(in_pieces(&bad, Path::new("t.xml"), &[], None, 7).is_none());
        // A cut in a comment that a piece misread: the text read on from
        // the cut before it, as valid as it is.
        let from = text.len() / 2;
        let at = from + text[from..].find("  <sphere>\n").unwrap();
        let mut commented = text.clone();
        commented.insert_str(at, &format!("<!--{}-->", "\n<light x=\"1\"/>".repeat(2000)));
        let read = in_pieces(&commented, Path::new("t.xml"), &[], None, 7);
        assert_eq!(
            format!("{read:?}"),
            format!("{:?}", Some(in_one_laid_out(&commented)))
        );
        assert!(matches!(read, Some(Ok(_))));
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
        let mut next = below(0x2545_F491_4F6C_DD1Du64);
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
            let streamed = streamed(&path, &Objects::default(), false, None);
            assert_eq!(streamed.is_some(), streams, "{}", &text[..60]);
            // Where the children sit, as a parse in one has them, streamed
            // or read whole.
            let laid_out = in_one_laid_out(body).ok().map(|(_, mut layout)| {
                layout.bom = text.len() - body.len();
                layout
            });
            let counted = load_counting(&path, &[], None).ok().map(|l| l.layout);
            assert_eq!(counted, laid_out);
            if let Some(streamed) = streamed {
                assert_eq!(Some(streamed.layout), laid_out);
                assert_eq!(format!("{:?}", Ok::<_, String>(streamed.scene)), one);
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
            loaded.text.is_near(&text, 0),
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
}
