//! Save-back: writing an [`Edited`] scene into the XML text it was loaded
//! from.
//!
//! [`save`] splices the edits into the text by the origins the edit engine
//! kept ([`super::edit`]): an element is found again by where it came from,
//! never by matching elements up by position or name. It changes only what
//! differs, in place: an attribute value between its quotes, a missing
//! attribute appended to its element, a removed element with its lines and
//! the comment lines directly above it, an added element after the last one
//! of its kind with the indentation of its siblings. Every other byte of the
//! text is kept: comments, whitespace, attribute order and quoting, the
//! spelling of unchanged numbers (`1.0` stays `1.0`), the XML declaration.
//!
//! [`plan_source`] does the same for a text held as a [`Source`]: one
//! held packed is read twice, a block at a time, never unpacked whole.
//!
//! [`to_xml`] writes a fresh, indented file for a scene that has no source
//! text yet ("Save as" of the built-in example, a new scene).
//!
//! Numbers are written with Rust's shortest round-trip formatting, so the
//! written text parses back to exactly the edited values.
//!
//! How it works: the text is scanned again with quick-xml to find each
//! element's byte span, each attribute value's byte range and each comment;
//! the edits are collected as splices (byte range → replacement) and
//! applied in one pass. Before anything is returned, the new text is parsed
//! and compared with the edited scene: `save` never returns a text that
//! would load differently.

use std::borrow::Cow;
use std::mem::discriminant;
use std::ops::Range;
use std::path::Path;

use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};

use super::edit::{Coef, EditError, Edited, ObjectOrigin, number_text as num};
use super::source::Source;
use super::{Color, Illumination, LoadError, Material, Model, Object, Scene, Shape, parse};
use crate::math::{TransformStep, Vec3};
use crate::shading::Light;

fn internal(message: impl Into<String>) -> EditError {
    EditError::Internal(message.into())
}

/// Writes `edited` into `text`, the source of a valid scene file that
/// `edited` was loaded from (`path` only names it in errors).
///
/// The result parses to `edited`'s scene; every part of `text` that did not
/// need to change is kept byte for byte.
pub fn save(text: &str, path: &Path, edited: &Edited) -> Result<String, EditError> {
    let rewrite = {
        let original = parse(text, path).map_err(|e| EditError::Parse(Box::new(e)))?;
        plan(text, &original, edited)?
    };
    let mut out = Vec::with_capacity(rewrite.len());
    rewrite
        .write_to(&mut out)
        .map_err(|e| internal(e.to_string()))?;
    let out = String::from_utf8(out).map_err(|_| internal("the rewritten text is not UTF-8"))?;
    check(&out, path, edited)?;
    Ok(out)
}

/// The splices that write `edited` into `text`, whose scene is `original`
/// (the scene `text` loads to, sharing its objects with `edited` where
/// they were not changed: the app keeps it rather than parse the text
/// again).
///
/// Only the elements of the objects that changed are scanned in full: on
/// a file of a million objects the others are only placed (16 bytes each).
pub fn plan<'t>(
    text: &'t str,
    original: &Scene,
    edited: &Edited,
) -> Result<Rewrite<'t>, EditError> {
    if edited.is_as_loaded(original) {
        return Ok(Rewrite {
            text: Text::Str(text),
            splices: Vec::new(),
        });
    }
    let changed = changed_objects(original, edited);
    let doc = Doc::scan(text, Keep::Objects(&changed))?;
    Rewrite::new(text, edit_splices(&doc, original, edited)?)
}

/// The splices that write `edited` into `doc`, scanned keeping the
/// elements of the objects `edited` changes ([`changed_objects`]).
fn edit_splices(
    doc: &Doc<'_>,
    original: &Scene,
    edited: &Edited,
) -> Result<Vec<Splice>, EditError> {
    let mut editor = Editor {
        doc,
        splices: Vec::new(),
    };
    editor.scene(original, edited)?;
    Ok(editor.splices)
}

/// Checks that `out`, a text written by a [`Rewrite`], loads as `edited`'s
/// scene: nothing is saved that would load differently.
pub fn check(out: &str, path: &Path, edited: &Edited) -> Result<(), EditError> {
    let scene = edited.scene();
    loads_as(super::parse_sharing(out, path, &scene.objects), scene)
}

/// [`check`] of the file `written`, a text written by a [`Rewrite`] for
/// `path` (which names it in errors): read a piece at a time where it is
/// big, its objects shared with `edited`'s, the text never held whole.
pub fn check_file(written: &Path, path: &Path, edited: &Edited) -> Result<(), EditError> {
    let scene = edited.scene();
    let loaded = super::load_like(written, &scene.objects).map_err(|e| LoadError {
        path: path.to_owned(),
        ..e
    });
    loads_as(loaded, scene)
}

fn loads_as(loaded: Result<Scene, LoadError>, scene: &Scene) -> Result<(), EditError> {
    match loaded {
        Ok(back) if &back == scene => Ok(()),
        Ok(_) => Err(internal(
            "the rewritten text does not load as the edited scene",
        )),
        Err(e) => Err(EditError::Invalid(Box::new(e))),
    }
}

/// The line ending new lines get in `text`: CRLF where it has one, LF
/// where it has one, a lone CR where it has only those (a file of classic
/// Mac OS), else LF.
fn line_ending(text: &str) -> &'static str {
    if text.contains("\r\n") {
        "\r\n"
    } else if text.contains('\n') || !text.contains('\r') {
        "\n"
    } else {
        "\r"
    }
}

/// A scene file's text with splices to apply: [`Rewrite::write_to`]
/// streams the new text without building it.
#[derive(Debug)]
pub struct Rewrite<'t> {
    text: Text<'t>,
    /// Sorted, not overlapping, inside the text ([`plan`] checked).
    splices: Vec<Splice>,
}

/// The text a [`Rewrite`] splices into.
#[derive(Debug)]
enum Text<'t> {
    Str(&'t str),
    /// Read back in order, a block at a time ([`plan_source`]).
    Source(&'t Source),
}

impl<'t> Rewrite<'t> {
    /// Orders the splices: insertions at one offset keep the order they
    /// were made in and come before a replacement starting there.
    /// Overlapping splices, or one outside the text, are an error.
    fn new(text: &'t str, mut splices: Vec<Splice>) -> Result<Rewrite<'t>, EditError> {
        splices.sort_by_key(|s| (s.range.start, !s.range.is_empty()));
        let mut cursor = 0;
        for splice in &splices {
            let Range { start, end } = splice.range;
            if start < cursor || end < start {
                return Err(internal("overlapping edits"));
            }
            if text.get(start..end).is_none() {
                return Err(internal("an edit outside the text"));
            }
            cursor = end;
        }
        Ok(Rewrite {
            text: Text::Str(text),
            splices,
        })
    }

    /// Nothing to change: the new text is the old one.
    pub fn is_empty(&self) -> bool {
        self.splices.is_empty()
    }

    /// The new text's length in bytes.
    pub fn len(&self) -> usize {
        let len = match self.text {
            Text::Str(text) => text.len(),
            Text::Source(source) => source.len(),
        };
        self.splices
            .iter()
            .fold(len, |n, s| n - (s.range.end - s.range.start) + s.text.len())
    }

    /// Writes the new text: the kept bytes and the splices in order.
    pub fn write_to(&self, w: &mut (impl std::io::Write + ?Sized)) -> std::io::Result<()> {
        use std::io::Read;
        match self.text {
            Text::Str(text) => {
                let mut cursor = 0;
                for splice in &self.splices {
                    w.write_all(&text.as_bytes()[cursor..splice.range.start])?;
                    w.write_all(splice.text.as_bytes())?;
                    cursor = splice.range.end;
                }
                w.write_all(&text.as_bytes()[cursor..])
            }
            Text::Source(source) => {
                let mut reader = source.reader();
                let mut cursor = 0;
                for splice in &self.splices {
                    let Range { start, end } = splice.range;
                    let kept = std::io::copy(&mut (&mut reader).take((start - cursor) as u64), w)?;
                    let skipped = std::io::copy(
                        &mut (&mut reader).take((end - start) as u64),
                        &mut std::io::sink(),
                    )?;
                    if kept + skipped != (end - cursor) as u64 {
                        return Err(std::io::Error::other("an edit past the end of the text"));
                    }
                    w.write_all(splice.text.as_bytes())?;
                    cursor = end;
                }
                std::io::copy(&mut reader, w).map(|_| ())
            }
        }
    }
}

/// [`plan`] for a text held as a [`Source`]. A packed one is never
/// unpacked whole: the save reads it once to find the changed objects'
/// elements ([`Skeleton`]) and once more to write the new text.
pub fn plan_source<'s>(
    source: &'s Source,
    original: &Scene,
    edited: &Edited,
) -> Result<Rewrite<'s>, EditError> {
    if edited.is_as_loaded(original) {
        return Ok(Rewrite {
            text: Text::Source(source),
            splices: Vec::new(),
        });
    }
    if let Some(text) = source.as_str() {
        return plan(text, original, edited);
    }
    let changed = changed_objects(original, edited);
    // Values edited in place: the runs of objects between the changed ones
    // are folded away.
    let fold = edited.objects_in_place() && edited.scene().objects.len() == original.objects.len();
    let skeleton = Skeleton::read(source, &changed, fold)?;
    let mut doc = match &skeleton.folded {
        Some(folded) => {
            let mut doc = Doc::scan(&skeleton.text, Keep::Folded(&folded.changed))?;
            doc.numbers = Some(&folded.numbers);
            doc
        }
        None => Doc::scan(&skeleton.text, Keep::Objects(&changed))?,
    };
    if skeleton.crlf {
        doc.nl = "\r\n";
    }
    let checked = Rewrite::new(&skeleton.text, edit_splices(&doc, original, edited)?)?;
    let splices = checked
        .splices
        .into_iter()
        .map(|s| Splice {
            range: skeleton.in_source(s.range.start)..skeleton.in_source(s.range.end),
            text: s.text,
        })
        .collect();
    Ok(Rewrite {
        text: Text::Source(source),
        splices,
    })
}

/// Where each element of a group came from ([`Editor::group`]): the
/// index among the text's elements of current element `i`, or `None` for
/// an element added since.
#[derive(Clone, Copy)]
enum Origins<'a> {
    List(&'a [Option<usize>]),
    /// `len` elements, each asked of `of` (the objects' origins are the
    /// edit engine's, asked for: a list of a million would be 16 MB).
    Asked {
        len: usize,
        of: &'a dyn Fn(usize) -> Option<usize>,
    },
}

impl Origins<'_> {
    fn len(&self) -> usize {
        match self {
            Origins::List(list) => list.len(),
            Origins::Asked { len, .. } => *len,
        }
    }

    fn of(&self, i: usize) -> Option<usize> {
        match self {
            Origins::List(list) => list.get(i).copied().flatten(),
            Origins::Asked { len, of } => (i < *len).then(|| of(i)).flatten(),
        }
    }
}

/// A packed text with the insides of the objects a save leaves as they
/// are left out (`<sphere>…</sphere>` becomes `<sphere></sphere>`): what
/// the save's editor reads instead of the whole text. A million spheres'
/// 214 MB become about 20 MB, and only the changed objects' elements are
/// scanned in full, as in a text held whole ([`plan`]). When only values
/// were edited, runs of unchanged objects are folded away whole
/// ([`Folded`]): a few lines.
///
/// Every splice the editor makes lies outside the parts left out (at an
/// object's start or end, or inside a changed one), so each of its
/// offsets maps to the source's.
struct Skeleton {
    text: String,
    /// For each part left out, the skeleton's offset where it was and the
    /// bytes left out up to there in all.
    /// (u32: a text is at most 1 GiB.)
    gaps: Vec<(u32, u32)>,
    /// The whole text has a CRLF line ending (maybe only in a part left
    /// out): new lines are written with it, as in a text held whole.
    crlf: bool,
    /// Runs of objects folded away, when they were.
    folded: Option<Folded>,
}

/// The objects of a skeleton in which each run of unchanged objects (the
/// root's spheres and planes one after the other, with only spaces and
/// comments between them), but its last, is folded into one `<_/>`: a
/// million spheres edited in one value make a skeleton of a few lines
/// rather than 20 MB, with as many places and gaps. Folded only when no
/// object moves (the edits set values): the editor then has no objects to
/// remove, add or move, and needs no place of an unchanged one but the
/// last of each run (what an element added after it, at the root's end,
/// lines up with), nor any before the first that sets the indentation
/// unit (`Doc::indent_unit`); those stay, their insides left out.
struct Folded {
    /// Each object's number in the text, in skeleton order.
    numbers: Vec<usize>,
    /// Which of the skeleton's objects (by skeleton order) are changed.
    changed: std::collections::HashSet<usize>,
}

/// What a run of objects folds into in a skeleton ([`Folded`]); its gap
/// is after the second byte.
const FOLD: &[u8; 4] = b"<_/>";

impl Skeleton {
    /// Reads `source`, keeping whole the objects (numbered in text order)
    /// in `keep`. With `fold` (every object is where it was, with its own
    /// steps: an edit of values only), each run of unchanged objects but
    /// its last is folded into one `<_/>` ([`Folded`]).
    fn read(
        source: &Source,
        keep: &std::collections::HashSet<usize>,
        fold: bool,
    ) -> Result<Skeleton, EditError> {
        use std::cell::RefCell;
        use std::rc::Rc;

        /// The source's bytes as read, not yet given to the skeleton or
        /// left out; `start`: the source offset of the first.
        #[derive(Default)]
        struct Pending {
            bytes: Vec<u8>,
            start: usize,
        }
        /// The source's bytes to the XML reader, and into `pending`; a
        /// byte order mark (`hide`: its length) to `pending` only, so that
        /// the reader's positions are the text's less it.
        struct Tee<'s> {
            inner: crate::scene::source::SourceReader<'s>,
            pending: Rc<RefCell<Pending>>,
            hide: usize,
        }
        impl std::io::Read for Tee<'_> {
            fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
                loop {
                    let n = self.inner.read(buf)?;
                    self.pending.borrow_mut().bytes.extend_from_slice(&buf[..n]);
                    let hidden = self.hide.min(n);
                    if hidden == 0 {
                        return Ok(n);
                    }
                    buf.copy_within(hidden..n, 0);
                    self.hide -= hidden;
                    if n > hidden {
                        return Ok(n - hidden);
                    }
                }
            }
        }
        /// An object that may be folded, read whole, its fate waiting on
        /// what comes next: folded if another such object follows, else
        /// the last of its run, left as a stub (`<sphere></sphere>`).
        struct Held {
            number: usize,
            start: usize,
            /// Just past its start tag and at its end tag's `<` (`None`
            /// for `<sphere/>`).
            inside: Option<(usize, usize)>,
            end: usize,
        }

        let bom = {
            let mut head = [0u8; 3];
            let read = std::io::Read::read_exact(&mut source.reader(), &mut head);
            match read.is_ok() && head == *b"\xef\xbb\xbf" {
                true => head.len(),
                false => 0,
            }
        };
        let pending = Rc::new(RefCell::new(Pending::default()));
        let tee = Tee {
            inner: source.reader(),
            pending: Rc::clone(&pending),
            hide: bom,
        };
        let mut reader = Reader::from_reader(std::io::BufReader::with_capacity(1 << 16, tee));
        let config = reader.config_mut();
        config.check_end_names = true;
        config.expand_empty_elements = false;
        config.trim_text(false);

        let mut crlf = false;
        let mut kept: Vec<u8> = Vec::new();
        let mut last_byte = 0u8;
        // The current line's bytes so far, while they are all spaces and
        // tabs (`Doc::own_indent`).
        let line: RefCell<Option<Vec<u8>>> = RefCell::new(Some(Vec::new()));
        // Moves the source's bytes up to `to` from the pending ones into
        // the skeleton, or leaves them out; returns how many.
        let mut take = |to: usize, keep: bool, kept: &mut Vec<u8>| {
            let mut p = pending.borrow_mut();
            let n = to.saturating_sub(p.start).min(p.bytes.len());
            let bytes = &p.bytes[..n];
            if bytes.first() == Some(&b'\n') && last_byte == b'\r'
                || bytes.windows(2).any(|w| w == b"\r\n")
            {
                crlf = true;
            }
            if let Some(&b) = bytes.last() {
                last_byte = b;
            }
            // A byte order mark is not on the first line (`Doc::scan`).
            let line_bytes = match p.start == 0 && bytes.starts_with(b"\xef\xbb\xbf") {
                true => &bytes[3..],
                false => bytes,
            };
            let blank = |bytes: &[u8]| bytes.iter().all(|&b| b == b' ' || b == b'\t');
            let mut line = line.borrow_mut();
            if !fold {
            } else if let Some(nl) = line_bytes.iter().rposition(|&b| b == b'\n') {
                let rest = &line_bytes[nl + 1..];
                *line = blank(rest).then(|| rest.to_vec());
            } else if let Some(l) = line.as_mut() {
                match blank(line_bytes) {
                    true => l.extend_from_slice(line_bytes),
                    false => *line = None,
                }
            }
            if keep {
                kept.extend_from_slice(bytes);
            }
            p.bytes.drain(..n);
            p.start += n;
            n
        };
        let position = |reader: &Reader<_>| {
            usize::try_from(reader.buffer_position())
                .map(|p| p + bom)
                .map_err(|_| internal("position out of range"))
        };
        let gap = |at: usize, out: usize| match (u32::try_from(at), u32::try_from(out)) {
            (Ok(at), Ok(out)) => Ok((at, out)),
            _ => Err(internal("a text over 4 GiB")),
        };

        let mut gaps = Vec::new();
        let mut numbers = Vec::new();
        let mut changed = std::collections::HashSet::new();
        let mut left_out = 0;
        let mut buf = Vec::new();
        let mut depth = 0usize;
        let mut objects = 0usize;
        // Inside an object whose inside is left out: its element's depth.
        let mut leaving_out: Option<usize> = None;
        // Inside an object that may be folded: its start, the end of its
        // start tag, its element's depth.
        let mut holding: Option<(usize, usize, usize)> = None;
        let mut held: Option<Held> = None;
        // A fold open in the skeleton: the offset of its gap, inside `<_/>`.
        let mut folding: Option<usize> = None;
        // Whether objects may be folded yet: `Doc::indent_unit` reads the
        // root's first object on its own line, indented further than the
        // root (none when the root is not on its own line); it, and every
        // object before it, stays.
        let mut root_indent: Option<Option<Vec<u8>>> = None;
        let mut may_fold = false;
        loop {
            let before = position(&reader)?;
            buf.clear();
            let event = reader
                .read_event_into(&mut buf)
                .map_err(|e| internal(format!("XML: {e}")))?;
            let after = position(&reader)?;
            // Inside an object that may be folded: nothing is taken yet.
            if let Some((start, inside, at_depth)) = holding {
                match event {
                    Event::Start(_) => depth += 1,
                    Event::End(_) if depth == at_depth => {
                        held = Some(Held {
                            number: objects - 1,
                            start,
                            inside: Some((inside, before)),
                            end: after,
                        });
                        holding = None;
                        depth -= 1;
                    }
                    Event::End(_) => depth -= 1,
                    Event::Eof => return Err(internal("an object not closed")),
                    _ => {}
                }
                continue;
            }
            let root_level =
                depth == 1 && matches!(event, Event::Start(_) | Event::Empty(_) | Event::End(_));
            let object = match &event {
                Event::Start(e) | Event::Empty(e) => {
                    depth == 1 && Shape::from_name_bytes(e.name().as_ref()).is_some()
                }
                _ => false,
            };
            let foldable = fold && may_fold && object && !keep.contains(&objects);
            if root_level || matches!(event, Event::Eof) {
                // What follows the held object decides its fate.
                if let Some(h) = held.take() {
                    if foldable {
                        if folding.is_none() {
                            take(h.start, true, &mut kept);
                            kept.extend_from_slice(&FOLD[..2]);
                            folding = Some(kept.len());
                        }
                        // It, and the bytes before it since the last one.
                        left_out += take(h.end, false, &mut kept);
                    } else {
                        if let Some(at) = folding.take() {
                            // The fold's own four bytes are not the text's.
                            left_out = left_out
                                .checked_sub(FOLD.len())
                                .ok_or_else(|| internal("a fold of nothing"))?;
                            gaps.push(gap(at, left_out)?);
                            kept.extend_from_slice(&FOLD[2..]);
                        }
                        numbers.push(h.number);
                        if let Some((inside, end_tag)) = h.inside {
                            take(inside, true, &mut kept);
                            left_out += take(end_tag, false, &mut kept);
                            gaps.push(gap(kept.len(), left_out)?);
                        }
                        take(h.end, true, &mut kept);
                    }
                }
                // The bytes since are kept, but before an object that may
                // be folded: they go with it.
                if !foldable {
                    take(before, true, &mut kept);
                }
            }
            match event {
                Event::Start(_) if depth == 0 && root_indent.is_none() => {
                    let line = line.borrow().clone();
                    may_fold = line.is_none();
                    root_indent = Some(line);
                    depth += 1;
                }
                Event::Start(_) | Event::Empty(_) if object => {
                    let number = objects;
                    objects += 1;
                    let empty = matches!(event, Event::Empty(_));
                    if foldable {
                        match empty {
                            true => {
                                held = Some(Held {
                                    number,
                                    start: before,
                                    inside: None,
                                    end: after,
                                });
                            }
                            false => {
                                depth += 1;
                                holding = Some((before, after, depth));
                            }
                        }
                        continue;
                    }
                    if fold && !may_fold {
                        may_fold = match (&root_indent, &*line.borrow()) {
                            (Some(Some(root)), Some(own)) => {
                                own.len() > root.len() && own.starts_with(root)
                            }
                            _ => false,
                        };
                    }
                    if fold {
                        if keep.contains(&number) {
                            changed.insert(numbers.len());
                        }
                        numbers.push(number);
                    }
                    if !empty {
                        depth += 1;
                        if !keep.contains(&number) {
                            take(after, true, &mut kept);
                            leaving_out = Some(depth);
                            continue;
                        }
                    }
                }
                Event::Start(_) => depth += 1,
                Event::End(_) => {
                    if leaving_out == Some(depth) {
                        // The inside, up to the `<` of the end tag.
                        left_out += take(before, false, &mut kept);
                        gaps.push(gap(kept.len(), left_out)?);
                        leaving_out = None;
                    }
                    depth = depth.saturating_sub(1);
                }
                Event::Eof => break,
                _ => {}
            }
            if held.is_some() {
                // Between two objects that may be folded: taken with them.
                continue;
            }
            match leaving_out {
                Some(_) => left_out += take(after, false, &mut kept),
                None => {
                    take(after, true, &mut kept);
                }
            }
        }
        take(usize::MAX, true, &mut kept);
        let text = String::from_utf8(kept).map_err(|_| internal("the skeleton is not UTF-8"))?;
        let folded = fold.then_some(Folded { numbers, changed });
        Ok(Skeleton {
            text,
            gaps,
            crlf,
            folded,
        })
    }

    /// The source's offset of the skeleton's offset `at`.
    fn in_source(&self, at: usize) -> usize {
        let i = self.gaps.partition_point(|&(gap, _)| gap as usize <= at);
        at + i.checked_sub(1).map_or(0, |i| self.gaps[i].1 as usize)
    }
}

/// The objects of `original` (by index) that `edited` changes: only these
/// need their elements found in the text. An object kept as it was, with
/// its transformation steps where they were, needs nothing.
fn changed_objects(original: &Scene, edited: &Edited) -> std::collections::HashSet<usize> {
    (0..edited.scene().objects.len())
        .filter_map(|n| {
            let origin = edited.origin_of(n)?;
            let unchanged = original
                .objects
                .get(origin.index)
                .is_some_and(|o| unchanged(o, &edited.scene().objects[n], &origin.steps));
            (!unchanged).then_some(origin.index)
        })
        .collect()
}

/// `e`, whose steps came from `step_origins` of `o`'s, is `o` as it was.
fn unchanged(o: &Object, e: &Object, step_origins: &[Option<usize>]) -> bool {
    step_origins.len() == o.transform.steps().len()
        && step_origins
            .iter()
            .enumerate()
            .all(|(k, origin)| *origin == Some(k))
        && (std::ptr::eq(o, e) || o == e)
}

/// Writes `edited` into `text`, pairing the text's objects, lights and
/// transformation steps with `edited`'s by their index (and steps only when
/// of the same kind); the rest are removed or added.
///
/// For scenes changed outside the edit engine, which has no origins to go
/// by (tests, tools). The app and the command line save with [`save`].
pub fn rewrite_by_index(text: &str, path: &Path, edited: &Scene) -> Result<String, EditError> {
    let original = parse(text, path).map_err(|e| EditError::Parse(Box::new(e)))?;
    let steps = |o: &[TransformStep], e: &[TransformStep]| -> Vec<Option<usize>> {
        e.iter()
            .enumerate()
            .map(|(k, s)| {
                o.get(k)
                    .filter(|t| discriminant(*t) == discriminant(s))
                    .map(|_| k)
            })
            .collect()
    };
    let mut by_index = Edited::new(edited.clone());
    by_index.set_object_origins(
        edited
            .objects
            .iter()
            .enumerate()
            .map(|(i, e)| {
                original.objects.get(i).map(|o| ObjectOrigin {
                    index: i,
                    steps: steps(o.transform.steps(), e.transform.steps()),
                })
            })
            .collect(),
    );
    for (i, origin) in by_index.lights.iter_mut().enumerate() {
        *origin = (i < original.lights.len()).then_some(i);
    }
    by_index.camera_steps = steps(
        original.camera.transform.steps(),
        edited.camera.transform.steps(),
    );
    save(text, path, &by_index)
}

/// The comment directly above each object that has one (spheres and
/// planes numbered in file order from 0), between its `<!--` and `-->`.
/// [`super::names`] makes the panel's labels of them.
pub(super) fn object_comments(text: &str) -> impl Iterator<Item = (usize, &str)> {
    // Where the objects are is all it needs: they are not kept as nodes
    // (a million objects would be a million nodes, and five million with
    // their elements).
    let doc = Doc::scan(text, Keep::Placed).ok();
    // Without a comment in the text, no object has one.
    let places = doc
        .as_ref()
        .filter(|d| !d.comments.is_empty())
        .map_or(0, |d| d.objects.len());
    (0..places).filter_map(move |k| {
        let doc = doc.as_ref()?;
        let comment = doc.comments_above(doc.objects[k].start).last()?.clone();
        Some((k, text.get(comment.start + 4..comment.end - 3)?))
    })
}

/// [`object_comments`] of a text held as a [`Source`]: of its skeleton
/// with every object's inside left out (a packed text is never unpacked
/// whole). The comments above the objects are all outside them, and so is
/// every line an object starts on, up to its start: what is found is what
/// the whole text gives.
pub(super) fn source_object_comments(source: &Source) -> Vec<(usize, String)> {
    if let Some(text) = source.as_str() {
        return object_comments(text)
            .map(|(k, c)| (k, c.to_owned()))
            .collect();
    }
    let Ok(skeleton) = Skeleton::read(source, &std::collections::HashSet::new(), false) else {
        return Vec::new();
    };
    object_comments(&skeleton.text)
        .map(|(k, c)| (k, c.to_owned()))
        .collect()
}

/// The elements directly inside `<scene>`, in file order: each one's name,
/// its bytes (`<` to the end of its end tag) and its start tag's bytes.
/// Empty when the text is not well-formed XML.
pub fn top_level(text: &str) -> Vec<(&str, Range<usize>, Range<usize>)> {
    let Ok(doc) = Doc::scan(text, Keep::TopLevel) else {
        return Vec::new();
    };
    doc.node(doc.root)
        .children
        .iter()
        .map(|&id| {
            let node = doc.node(id);
            (
                node.name,
                node.start..node.elem_end(),
                node.start..node.tag_end,
            )
        })
        .collect()
}

/// Where the element of object `index` (spheres and planes in file order)
/// starts in `text`: its line and column, for an editor to open at.
pub fn object_position(text: &str, index: usize) -> Option<super::Position> {
    let doc = Doc::scan(text, Keep::Placed).ok()?;
    let place = doc.objects.get(index)?;
    Some(super::Position::at_offset(text, place.start))
}

/// A fresh scene file for `scene`, indented by two spaces:
/// `parse(&to_xml(scene), path) == Ok(scene)` for every valid scene.
///
/// Objects come first, then lights, the camera and the model. Each object
/// gets its colour and its full material, so that the file is easy to edit
/// by hand; a transformation is written when it has steps, a light colour
/// when it is not white.
pub fn to_xml(scene: &Scene) -> String {
    let mut lines: Lines = vec![(0, "<scene>".to_owned())];
    for object in &scene.objects {
        let name = object.shape.name();
        lines.push((1, format!("<{name}>")));
        lines.push((2, color_tag(object.color)));
        lines.push((2, material_tag(&object.material, false)));
        push_nested(
            &mut lines,
            2,
            transformation_lines(object.transform.steps()),
        );
        lines.push((1, format!("</{name}>")));
    }
    for light in &scene.lights {
        push_nested(&mut lines, 1, light_lines(light));
    }
    let camera = &scene.camera;
    let camera_tag = format!(
        "camera width=\"{}\" height=\"{}\" eyeDistance=\"{}\"",
        camera.width,
        camera.height,
        num(camera.eye_distance)
    );
    if camera.transform.steps().is_empty() {
        lines.push((1, format!("<{camera_tag}/>")));
    } else {
        lines.push((1, format!("<{camera_tag}>")));
        push_nested(
            &mut lines,
            2,
            transformation_lines(camera.transform.steps()),
        );
        lines.push((1, "</camera>".to_owned()));
    }
    let model = scene.model;
    let depth = if model.depth != 1 || model.illumination == Illumination::Whitted {
        format!(" depth=\"{}\"", model.depth)
    } else {
        String::new()
    };
    lines.push((
        1,
        format!("<model type=\"{}\"{depth}/>", model.illumination.name()),
    ));
    lines.push((0, "</scene>".to_owned()));

    let mut out = String::from("<?xml version=\"1.0\"?>\n");
    for (level, line) in lines {
        out.push_str(&"  ".repeat(level));
        out.push_str(&line);
        out.push('\n');
    }
    out
}

// ----- writing elements -----

/// Lines of XML, each with its nesting level relative to the first.
type Lines = Vec<(usize, String)>;

fn push_nested(lines: &mut Lines, level: usize, nested: Lines) {
    lines.extend(nested.into_iter().map(|(l, s)| (l + level, s)));
}

fn color_tag(c: Color) -> String {
    format!(
        "<color red=\"{}\" green=\"{}\" blue=\"{}\"/>",
        num(c.x),
        num(c.y),
        num(c.z)
    )
}

/// `<material .../>`; with `only_changed`, the attributes equal to their
/// defaults are left out.
fn material_tag(m: &Material, only_changed: bool) -> String {
    let d = Material::default();
    let mut tag = String::from("<material");
    for coef in Coef::ALL {
        let v = coef.of(m);
        if !only_changed || v != coef.of(&d) {
            tag.push_str(&format!(" {}=\"{}\"", coef.name(), num(v)));
        }
    }
    tag.push_str("/>");
    tag
}

fn xyz(v: Vec3) -> String {
    format!("x=\"{}\" y=\"{}\" z=\"{}\"", num(v.x), num(v.y), num(v.z))
}

fn step_tag(step: &TransformStep) -> String {
    match *step {
        TransformStep::Translate(v) => format!("<translate {}/>", xyz(v)),
        TransformStep::RotateX(a) => format!("<rotate-x angle=\"{}\"/>", num(a)),
        TransformStep::RotateY(a) => format!("<rotate-y angle=\"{}\"/>", num(a)),
        TransformStep::RotateZ(a) => format!("<rotate-z angle=\"{}\"/>", num(a)),
        TransformStep::UniformScale(f) => format!("<scale factor=\"{}\"/>", num(f)),
        TransformStep::Scale(v) => format!("<scale {}/>", xyz(v)),
    }
}

/// `<transformation>` with its steps; nothing when there are none.
fn transformation_lines(steps: &[TransformStep]) -> Lines {
    if steps.is_empty() {
        return Vec::new();
    }
    let mut lines = vec![(0, "<transformation>".to_owned())];
    lines.extend(steps.iter().map(|s| (1, step_tag(s))));
    lines.push((0, "</transformation>".to_owned()));
    lines
}

/// A new object element: only what differs from the defaults.
fn object_lines(object: &Object) -> Lines {
    let name = object.shape.name();
    let mut inner: Lines = Vec::new();
    if object.color != Vec3::ONE {
        inner.push((0, color_tag(object.color)));
    }
    if object.material != Material::default() {
        inner.push((0, material_tag(&object.material, true)));
    }
    inner.extend(transformation_lines(object.transform.steps()));
    wrap(name, "", inner)
}

fn light_lines(light: &Light) -> Lines {
    let inner = if light.color == Vec3::ONE {
        Vec::new()
    } else {
        vec![(0, color_tag(light.color))]
    };
    wrap("light", &format!(" {}", xyz(light.position)), inner)
}

fn model_tag(model: &Model) -> String {
    let depth = if model.depth == 1 {
        String::new()
    } else {
        format!(" depth=\"{}\"", model.depth)
    };
    format!("<model type=\"{}\"{depth}/>", model.illumination.name())
}

/// `<name attrs/>`, or `<name attrs>` + `inner` one level deeper + `</name>`.
fn wrap(name: &str, attrs: &str, inner: Lines) -> Lines {
    if inner.is_empty() {
        return vec![(0, format!("<{name}{attrs}/>"))];
    }
    let mut lines = vec![(0, format!("<{name}{attrs}>"))];
    push_nested(&mut lines, 1, inner);
    lines.push((0, format!("</{name}>")));
    lines
}

// ----- the scanned document -----

/// One attribute: its name and the byte range of its raw value, between the
/// quotes.
struct AttrSpan<'t> {
    name: &'t str,
    value: Range<usize>,
}

/// One element of the text, with byte offsets into the whole text.
struct Node<'t> {
    name: &'t str,
    /// Offset of the `<` of the start tag.
    start: usize,
    /// Offset just past the `>` of the start tag.
    tag_end: usize,
    /// `<x/>`: no content and no end tag.
    empty: bool,
    /// The end tag `</x>`; `tag_end..tag_end` for an empty element.
    end: Range<usize>,
    attrs: Vec<AttrSpan<'t>>,
    children: Vec<usize>,
}

impl Node<'_> {
    /// Offset just past the whole element.
    fn elem_end(&self) -> usize {
        if self.empty {
            self.tag_end
        } else {
            self.end.end
        }
    }
}

struct Doc<'t> {
    text: &'t str,
    /// Offset of the text after a byte-order mark (0 without one).
    base: usize,
    /// The file's line ending.
    nl: &'static str,
    /// One level of indentation, as the file writes it.
    unit: String,
    nodes: Vec<Node<'t>>,
    root: usize,
    /// Every comment, `<!--` to `-->`, in text order.
    comments: Vec<Range<usize>>,
    /// Where each object (the root's spheres and planes, in text order)
    /// is, whether or not it is kept as a node: a million objects need a
    /// million places (16 bytes each), not a million nodes (over 100).
    objects: Vec<Place>,
    /// The node of each object kept as one: (object number, node).
    object_nodes: Vec<(usize, usize)>,
    /// In a skeleton with objects folded away, each object's number in
    /// the whole text ([`Folded::numbers`]); `None`: the objects are all
    /// here.
    numbers: Option<&'t [usize]>,
}

/// Where an element is: the offset of its `<` and the offset just past
/// the whole element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Place {
    start: usize,
    end: usize,
}

/// Which elements [`Doc::scan`] keeps; the others are only checked.
#[derive(Clone, Copy)]
enum Keep<'a> {
    #[cfg(test)]
    All,
    /// The root and its children.
    TopLevel,
    /// The root and its children but the objects (spheres and planes),
    /// which are only placed (`Doc::objects`).
    Placed,
    /// Every element but the objects (spheres and planes, numbered in
    /// text order) not in the set, which are only placed.
    Objects(&'a std::collections::HashSet<usize>),
    /// As `Objects`, in a skeleton with objects folded away ([`Folded`]):
    /// its folds are not elements.
    Folded(&'a std::collections::HashSet<usize>),
}

impl<'t> Doc<'t> {
    /// Scans `text`, keeping the elements `keep` asks for.
    fn scan(text: &'t str, keep: Keep) -> Result<Doc<'t>, EditError> {
        let body = text.strip_prefix('\u{feff}').unwrap_or(text);
        let base = text.len() - body.len();
        let offset = |slice: &[u8]| -> Result<usize, EditError> {
            (slice.as_ptr() as usize)
                .checked_sub(body.as_ptr() as usize)
                .filter(|&o| o.saturating_add(slice.len()) <= body.len())
                .map(|o| o + base)
                .ok_or_else(|| internal("a slice outside the text"))
        };

        let mut reader = Reader::from_str(body);
        let config = reader.config_mut();
        config.check_end_names = true;
        config.expand_empty_elements = false;
        config.trim_text(false);

        let mut nodes: Vec<Node<'t>> = Vec::new();
        // The open elements, `None` for those not kept.
        let mut stack: Vec<Option<usize>> = Vec::new();
        // While inside an object whose elements are not kept: the depth of
        // the stack at its start.
        let mut skip_below: Option<usize> = None;
        let mut root = None;
        let mut comments = Vec::new();
        let mut objects: Vec<Place> = Vec::new();
        let mut object_nodes = Vec::new();
        // Inside an object that is only placed: its end is not known yet.
        let mut placing = false;
        loop {
            let event = reader
                .read_event()
                .map_err(|e| internal(format!("XML: {e}")))?;
            let position = usize::try_from(reader.buffer_position())
                .map_err(|_| internal("position out of range"))?
                .saturating_add(base);
            let (start, empty) = match event {
                Event::Start(start) => (start, false),
                Event::Empty(start) => (start, true),
                Event::End(_) => {
                    let at = text
                        .get(..position)
                        .and_then(|before| before.rfind('<'))
                        .ok_or_else(|| internal("end tag without '<'"))?;
                    let id = stack.pop().ok_or_else(|| internal("unbalanced end tag"))?;
                    if let Some(id) = id {
                        nodes[id].end = at..position;
                    }
                    if skip_below.is_some_and(|d| stack.len() <= d) {
                        skip_below = None;
                        if placing && let Some(place) = objects.last_mut() {
                            place.end = position;
                            placing = false;
                        }
                    }
                    continue;
                }
                Event::Eof => break,
                Event::Comment(content) => {
                    let from = offset(&content)?;
                    comments.push(from - 4..from + content.len() + 3);
                    continue;
                }
                _ => continue,
            };
            // A fold of a skeleton's objects ([`Folded`]) is nothing.
            if matches!(keep, Keep::Folded(_)) && stack.len() == 1 && start.name().as_ref() == b"_"
            {
                match empty {
                    true => continue,
                    false => return Err(internal("a fold with an inside")),
                }
            }
            let object = stack.len() == 1
                && skip_below.is_none()
                && Shape::from_name_bytes(start.name().as_ref()).is_some();
            // An object only placed, or kept with or without its elements.
            let (placed, deep) = match keep {
                _ if !object => (false, true),
                #[cfg(test)]
                Keep::All => (false, true),
                Keep::TopLevel => (false, false),
                Keep::Placed => (true, false),
                Keep::Objects(deep) | Keep::Folded(deep) => {
                    let deep = deep.contains(&objects.len());
                    (!deep, deep)
                }
            };
            if object {
                let at = offset(start.name().as_ref())?
                    .checked_sub(1)
                    .ok_or_else(|| internal("start tag without '<'"))?;
                objects.push(Place {
                    start: at,
                    end: position,
                });
            }
            let kept = match keep {
                _ if placed => false,
                #[cfg(test)]
                Keep::All => true,
                Keep::TopLevel | Keep::Placed => stack.len() <= 1,
                Keep::Objects(_) | Keep::Folded(_) => skip_below.is_none_or(|d| stack.len() <= d),
            };
            if !kept {
                if !empty {
                    if placed {
                        // Up to its end tag (this one's depth): not kept.
                        skip_below = Some(stack.len());
                        placing = true;
                    }
                    stack.push(None);
                }
                continue;
            }
            let id = nodes.len();
            nodes.push(element(text, &start, empty, position, &offset)?);
            if object {
                object_nodes.push((objects.len() - 1, id));
                if !deep && !empty {
                    skip_below = Some(stack.len());
                }
            }
            match stack.last() {
                Some(&Some(parent)) => nodes[parent].children.push(id),
                Some(None) => return Err(internal("an element inside one not kept")),
                None if root.is_none() => root = Some(id),
                None => return Err(internal("a second root element")),
            }
            if !empty {
                stack.push(Some(id));
            }
        }
        let root = match (root, stack.is_empty()) {
            (Some(root), true) => root,
            _ => return Err(internal("unbalanced elements")),
        };
        let nl = line_ending(text);
        let mut doc = Doc {
            text,
            base,
            nl,
            unit: String::new(),
            nodes,
            root,
            comments,
            objects,
            object_nodes,
            numbers: None,
        };
        // A kept object ends where its node does.
        for &(k, id) in &doc.object_nodes {
            doc.objects[k].end = doc.nodes[id].elem_end();
        }
        doc.unit = doc.indent_unit();
        Ok(doc)
    }

    /// The extra indentation of the first child, on its own line, of a
    /// parent on its own line; two spaces when the file shows none.
    fn indent_unit(&self) -> String {
        for node in &self.nodes {
            let Some(parent) = self.own_indent(node.start) else {
                continue;
            };
            let unit_at = |start: usize| {
                self.own_indent(start)
                    .filter(|indent| indent.len() > parent.len())
                    .and_then(|indent| indent.strip_prefix(parent))
            };
            let first_at = |start: usize| unit_at(start).map(|unit| (start, unit));
            let child = node
                .children
                .iter()
                .find_map(|&c| first_at(self.nodes[c].start));
            // The root's children are its kept nodes and its placed objects.
            let object = match std::ptr::eq(node, &self.nodes[self.root]) {
                true => self.objects.iter().find_map(|p| first_at(p.start)),
                false => None,
            };
            let earliest = match (child, object) {
                (Some(c), Some(o)) => Some(if o.0 < c.0 { o } else { c }),
                (c, o) => c.or(o),
            };
            if let Some((_, unit)) = earliest {
                return unit.to_owned();
            }
        }
        "  ".to_owned()
    }

    /// Where node `id` is.
    fn place(&self, id: usize) -> Place {
        let node = self.node(id);
        Place {
            start: node.start,
            end: node.elem_end(),
        }
    }

    /// The node of object `k` (in text order), if it was kept as one.
    fn object_node(&self, k: usize) -> Option<usize> {
        let i = self
            .object_nodes
            .binary_search_by_key(&k, |&(k, _)| k)
            .ok()?;
        Some(self.object_nodes[i].1)
    }

    /// Offset of the start of the line holding `pos`.
    fn line_start(&self, pos: usize) -> usize {
        let before = self.text.get(..pos).unwrap_or_default();
        // A lone CR (classic Mac OS) ends a line too.
        before
            .rfind(['\n', '\r'])
            .map_or(0, |i| i + 1)
            .max(self.base)
    }

    /// The indentation before `pos` when only spaces and tabs precede it on
    /// its line.
    fn own_indent(&self, pos: usize) -> Option<&'t str> {
        let indent = self.text.get(self.line_start(pos)..pos)?;
        indent
            .bytes()
            .all(|b| b == b' ' || b == b'\t')
            .then_some(indent)
    }

    /// The offset just past the line ending that follows `pos`, when only
    /// spaces and tabs come between (or the end of the text).
    fn line_end_after(&self, pos: usize) -> Option<usize> {
        let rest = self.text.get(pos..)?;
        let spaces = rest.len() - rest.trim_start_matches([' ', '\t']).len();
        let after = &rest[spaces..];
        let ending = if after.starts_with("\r\n") {
            2
        } else if after.starts_with(['\n', '\r']) {
            1
        } else if after.is_empty() {
            0
        } else {
            return None;
        };
        Some(pos + spaces + ending)
    }

    /// The comments directly above the line holding `pos`, in text order:
    /// each alone on its lines, with no blank line between them and `pos`.
    fn comments_above(&self, pos: usize) -> Vec<Range<usize>> {
        let mut found = Vec::new();
        if self.own_indent(pos).is_none() {
            return found;
        }
        let mut line = self.line_start(pos);
        let mut next = self.comments.partition_point(|c| c.end <= line);
        while let Some(c) = next.checked_sub(1).and_then(|i| self.comments.get(i)) {
            let alone =
                self.own_indent(c.start).is_some() && self.line_end_after(c.end) == Some(line);
            if !alone {
                break;
            }
            found.push(c.clone());
            line = self.line_start(c.start);
            next -= 1;
        }
        found.reverse();
        found
    }

    /// Where the lines of the element starting at `start` begin: the
    /// first comment directly above it, or its own line; `None` when it
    /// shares its line.
    fn block_start(&self, start: usize) -> Option<usize> {
        self.own_indent(start)?;
        let first = self
            .comments_above(start)
            .first()
            .map_or(start, |c| c.start);
        Some(self.line_start(first))
    }

    fn node(&self, id: usize) -> &Node<'t> {
        &self.nodes[id]
    }

    /// The only child of `id` named `name`, if any.
    fn child(&self, id: usize, name: &str) -> Option<usize> {
        self.node(id)
            .children
            .iter()
            .copied()
            .find(|&c| self.node(c).name == name)
    }

    fn children_named(&self, id: usize, names: &[&str]) -> Vec<usize> {
        self.node(id)
            .children
            .iter()
            .copied()
            .filter(|&c| names.contains(&self.node(c).name))
            .collect()
    }
}

/// A node for a start tag read at `tag_end` (the offset past its `>`).
fn element<'t>(
    text: &'t str,
    start: &BytesStart<'_>,
    empty: bool,
    tag_end: usize,
    offset: &impl Fn(&[u8]) -> Result<usize, EditError>,
) -> Result<Node<'t>, EditError> {
    // Names as slices of the text: no allocation per element.
    let slice = |bytes: &[u8]| -> Result<&'t str, EditError> {
        let from = offset(bytes)?;
        text.get(from..from + bytes.len())
            .ok_or_else(|| internal("a name outside the text"))
    };
    let name = start.name();
    let name_text = slice(name.as_ref())?;
    let at = offset(name.as_ref())?
        .checked_sub(1)
        .ok_or_else(|| internal("start tag without '<'"))?;
    let mut attrs = Vec::new();
    let mut iter = start.attributes();
    iter.with_checks(false);
    for attr in iter {
        let attr = attr.map_err(|e| internal(format!("attribute: {e}")))?;
        let Cow::Borrowed(value) = attr.value else {
            return Err(internal("an attribute value not borrowed from the text"));
        };
        let from = offset(value)?;
        attrs.push(AttrSpan {
            name: slice(attr.key.as_ref())?,
            value: from..from + value.len(),
        });
    }
    Ok(Node {
        name: name_text,
        start: at,
        tag_end,
        empty,
        end: tag_end..tag_end,
        attrs,
        children: Vec::new(),
    })
}

// ----- edits -----

/// `items` as lines indented by `indent` plus their own levels.
fn block(doc: &Doc<'_>, indent: &str, items: &[Lines]) -> String {
    let mut text = String::new();
    for item in items {
        for (level, line) in item {
            text.push_str(indent);
            text.push_str(&doc.unit.repeat(*level));
            text.push_str(line);
            text.push_str(doc.nl);
        }
    }
    text
}

/// `items` written one after another on the current line.
fn inline(items: &[Lines]) -> String {
    items.iter().flatten().map(|(_, l)| l.as_str()).collect()
}

/// Replace `range` of the text with `text` (an insertion when empty).
#[derive(Debug)]
struct Splice {
    range: Range<usize>,
    text: String,
}

/// Ranks of an object's children: where a new one goes among its siblings.
const OBJECT_RANKS: &[(&str, u8)] = &[("color", 0), ("material", 1), ("transformation", 2)];
const LIGHT_RANKS: &[(&str, u8)] = &[("color", 0)];
const CAMERA_RANKS: &[(&str, u8)] = &[("transformation", 0)];

struct Editor<'d, 't> {
    doc: &'d Doc<'t>,
    splices: Vec<Splice>,
}

impl Editor<'_, '_> {
    fn splice(&mut self, range: Range<usize>, text: impl Into<String>) {
        self.splices.push(Splice {
            range,
            text: text.into(),
        });
    }

    fn scene(&mut self, original: &Scene, edited: &Edited) -> Result<(), EditError> {
        let doc = self.doc;
        let scene = edited.scene();
        let root = doc.root;
        let objects = &doc.objects;
        let lights = doc.children_named(root, &["light"]);
        let cameras = doc.children_named(root, &["camera"]);
        let models = doc.children_named(root, &["model"]);
        let objects_here = doc.numbers.map_or(original.objects.len(), <[usize]>::len);
        if objects.len() != objects_here
            || lights.len() != original.lights.len()
            || cameras.len() != 1
            || models.len() > 1
        {
            return Err(internal("the text's elements do not match its scene"));
        }

        if let Some(numbers) = doc.numbers {
            // Every object where it was (a skeleton folds objects only
            // then): the changed ones are edited in place, as `group` would.
            for (k, &n) in numbers.iter().enumerate() {
                let (Some(o), Some(e), Some(origin)) = (
                    original.objects.get(n),
                    scene.objects.get(n),
                    edited.origin_of(n),
                ) else {
                    return Err(internal("the text's elements do not match its scene"));
                };
                if origin.index != n {
                    return Err(internal("an object moved in a folded skeleton"));
                }
                if unchanged(o, e, &origin.steps) {
                    continue;
                }
                let node = doc
                    .object_node(k)
                    .ok_or_else(|| internal("a changed object was not scanned"))?;
                self.object(node, o, e, &origin.steps)?;
            }
        } else {
            self.objects(original, edited, objects)?;
        }
        self.lights_camera_model(original, edited, lights, cameras, models)
    }

    /// The objects, brought to `edited`'s ([`Editor::group`]); `places`:
    /// the text's.
    fn objects(
        &mut self,
        original: &Scene,
        edited: &Edited,
        places: &[Place],
    ) -> Result<(), EditError> {
        let doc = self.doc;
        let scene = edited.scene();
        let (root, objects) = (doc.root, places);
        let origins = Origins::Asked {
            len: scene.objects.len(),
            of: &|n| edited.object_origin(n),
        };
        self.group(
            root,
            objects,
            origins,
            |i| object_lines(&scene.objects[i]),
            |editor, k, i| {
                let origin = edited.origin_of(i);
                let steps = origin.as_ref().map_or(&[][..], |o| &o.steps[..]);
                // Its elements were not scanned (see `changed_objects`).
                if unchanged(&original.objects[k], &scene.objects[i], steps) {
                    return Ok(());
                }
                let node = doc
                    .object_node(k)
                    .ok_or_else(|| internal("a changed object was not scanned"))?;
                editor.object(node, &original.objects[k], &scene.objects[i], steps)
            },
        )
    }

    /// The lights, the camera and the model, brought to `edited`'s.
    fn lights_camera_model(
        &mut self,
        original: &Scene,
        edited: &Edited,
        lights: Vec<usize>,
        cameras: Vec<usize>,
        models: Vec<usize>,
    ) -> Result<(), EditError> {
        let doc = self.doc;
        let scene = edited.scene();
        let root = doc.root;
        let light_places: Vec<Place> = lights.iter().map(|&id| doc.place(id)).collect();
        self.group(
            root,
            &light_places,
            Origins::List(&edited.lights),
            |i| light_lines(&scene.lights[i]),
            |editor, k, i| editor.light(lights[k], &original.lights[k], &scene.lights[i]),
        )?;

        self.camera(
            cameras[0],
            &original.camera,
            &scene.camera,
            &edited.camera_steps,
        )?;

        let (om, em) = (original.model, scene.model);
        if om != em {
            match models.first() {
                Some(&node) => {
                    if om.illumination != em.illumination {
                        self.set_attr(node, "type", em.illumination.name());
                    }
                    if om.depth != em.depth {
                        self.set_attr(node, "depth", &em.depth.to_string());
                    }
                }
                None => self.insert(root, "scene", None, &[vec![(0, model_tag(&em))]])?,
            }
        }
        Ok(())
    }

    /// Brings a group of sibling elements of `parent` (`nodes`, in text
    /// order: the objects, the lights, the steps of one transformation) to
    /// the current elements. `origins[i]` is the index in `nodes` that
    /// current element `i` came from, or `None` for a new one (written by
    /// `lines(i)`). Nodes no element came from are removed with the comment
    /// lines above them; kept ones are edited by `keep(self, k, i)`; new
    /// ones go before the next kept element, or after the group's last
    /// node, or at the end of `parent`.
    fn group(
        &mut self,
        parent: usize,
        nodes: &[Place],
        origins: Origins<'_>,
        lines: impl Fn(usize) -> Lines,
        mut keep: impl FnMut(&mut Self, usize, usize) -> Result<(), EditError>,
    ) -> Result<(), EditError> {
        let doc = self.doc;
        let mut kept = vec![false; nodes.len()];
        let mut last = None;
        for i in 0..origins.len() {
            let Some(k) = origins.of(i) else { continue };
            if k >= nodes.len() || kept[k] || last.is_some_and(|l| l >= k) {
                return Err(internal("the elements' origins are not in text order"));
            }
            kept[k] = true;
            last = Some(k);
            keep(self, k, i)?;
        }
        for (k, &place) in nodes.iter().enumerate() {
            if !kept[k] {
                self.remove(place);
            }
        }
        let name = doc.node(parent).name;
        let mut i = 0;
        while i < origins.len() {
            if origins.of(i).is_some() {
                i += 1;
                continue;
            }
            let run_end = (i..origins.len())
                .find(|&j| origins.of(j).is_some())
                .unwrap_or(origins.len());
            let items: Vec<Lines> = (i..run_end).map(&lines).collect();
            match origins.of(run_end) {
                Some(k) => self.insert_before(nodes[k], &items),
                None => match nodes.last() {
                    Some(&place) => self.insert_after(place, &items),
                    None => self.insert(parent, name, None, &items)?,
                },
            }
            i = run_end;
        }
        Ok(())
    }

    fn object(
        &mut self,
        node: usize,
        o: &Object,
        e: &Object,
        step_origins: &[Option<usize>],
    ) -> Result<(), EditError> {
        let doc = self.doc;
        let name = e.shape.name();
        if o.shape != e.shape {
            self.rename(node, name)?;
        }
        let mut new_items: Vec<(u8, Lines)> = Vec::new();
        if o.color != e.color {
            match doc.child(node, "color") {
                Some(c) => self.set_color(c, o.color, e.color),
                None => new_items.push((0, vec![(0, color_tag(e.color))])),
            }
        }
        if o.material != e.material {
            match doc.child(node, "material") {
                Some(m) => {
                    let (om, em) = (o.material, e.material);
                    let values = Coef::ALL.map(|c| (c.name(), c.of(&om), c.of(&em)));
                    self.set_numbers(m, &values);
                }
                None => new_items.push((1, vec![(0, material_tag(&e.material, true))])),
            }
        }
        self.transformation(
            node,
            o.transform.steps(),
            e.transform.steps(),
            step_origins,
            2,
            &mut new_items,
        )?;
        self.insert_ranked(node, name, OBJECT_RANKS, new_items)
    }

    fn light(&mut self, node: usize, o: &Light, e: &Light) -> Result<(), EditError> {
        self.set_vec3(node, ["x", "y", "z"], o.position, e.position);
        if o.color != e.color {
            match self.doc.child(node, "color") {
                Some(c) => self.set_color(c, o.color, e.color),
                None => {
                    let item = vec![(0, vec![(0, color_tag(e.color))])];
                    self.insert_ranked(node, "light", LIGHT_RANKS, item)?;
                }
            }
        }
        Ok(())
    }

    fn camera(
        &mut self,
        node: usize,
        o: &super::Camera,
        e: &super::Camera,
        step_origins: &[Option<usize>],
    ) -> Result<(), EditError> {
        if o.width != e.width {
            self.set_attr(node, "width", &e.width.to_string());
        }
        if o.height != e.height {
            self.set_attr(node, "height", &e.height.to_string());
        }
        if o.eye_distance != e.eye_distance {
            self.set_attr(node, "eyeDistance", &num(e.eye_distance));
        }
        let mut new_items = Vec::new();
        self.transformation(
            node,
            o.transform.steps(),
            e.transform.steps(),
            step_origins,
            0,
            &mut new_items,
        )?;
        self.insert_ranked(node, "camera", CAMERA_RANKS, new_items)
    }

    /// Brings the `<transformation>` of `parent` from steps `o` to `e`,
    /// step by step by their origins; queues a new `<transformation>` (at
    /// `rank`) in `new_items` when `parent` has none.
    fn transformation(
        &mut self,
        parent: usize,
        o: &[TransformStep],
        e: &[TransformStep],
        origins: &[Option<usize>],
        rank: u8,
        new_items: &mut Vec<(u8, Lines)>,
    ) -> Result<(), EditError> {
        let Some(node) = self.doc.child(parent, "transformation") else {
            if !e.is_empty() {
                new_items.push((rank, transformation_lines(e)));
            }
            return Ok(());
        };
        if o == e {
            // Back to the steps the text has (a camera moved and brought
            // back): its text says it already, whatever the origins.
            return Ok(());
        }
        let steps = self.doc.node(node).children.clone();
        if steps.len() != o.len() || origins.len() != e.len() {
            return Err(internal("a transformation's steps do not match its text"));
        }
        let places: Vec<Place> = steps.iter().map(|&id| self.doc.place(id)).collect();
        self.group(
            node,
            &places,
            Origins::List(origins),
            |i| vec![(0, step_tag(&e[i]))],
            |editor, k, i| editor.step(steps[k], &o[k], &e[i]),
        )
    }

    /// Edits the values of one step node from `a` to `b` (same kind).
    fn step(&mut self, node: usize, a: &TransformStep, b: &TransformStep) -> Result<(), EditError> {
        use TransformStep as S;
        match (*a, *b) {
            (S::Translate(u), S::Translate(v)) | (S::Scale(u), S::Scale(v)) => {
                self.set_vec3(node, ["x", "y", "z"], u, v);
            }
            (S::RotateX(u), S::RotateX(v))
            | (S::RotateY(u), S::RotateY(v))
            | (S::RotateZ(u), S::RotateZ(v)) => {
                if u != v {
                    self.set_attr(node, "angle", &num(v));
                }
            }
            (S::UniformScale(u), S::UniformScale(v)) => {
                if u != v {
                    self.set_attr(node, "factor", &num(v));
                }
            }
            _ => return Err(internal("a step changed its kind")),
        }
        Ok(())
    }

    fn set_color(&mut self, node: usize, o: Color, e: Color) {
        self.set_vec3(node, ["red", "green", "blue"], o, e);
    }

    /// Sets the three attributes `names` of `node` that changed from `o`
    /// to `e`.
    fn set_vec3(&mut self, node: usize, names: [&str; 3], o: Vec3, e: Vec3) {
        self.set_numbers(
            node,
            &[
                (names[0], o.x, e.x),
                (names[1], o.y, e.y),
                (names[2], o.z, e.z),
            ],
        );
    }

    /// Sets each attribute of `node` whose value changed, `(name, old,
    /// new)`; the others keep their text.
    fn set_numbers(&mut self, node: usize, values: &[(&str, f64, f64)]) {
        for &(attr, old, new) in values {
            if old != new {
                self.set_attr(node, attr, &num(new));
            }
        }
    }

    /// Sets attribute `name` of `node`: its value replaced between the
    /// quotes, or ` name="value"` appended after the last attribute.
    fn set_attr(&mut self, node: usize, name: &str, value: &str) {
        let n = self.doc.node(node);
        if let Some(attr) = n.attrs.iter().find(|a| a.name == name) {
            self.splice(attr.value.clone(), value);
            return;
        }
        let (at, quote) = match n.attrs.last() {
            Some(last) => {
                let quote = match self.doc.text.as_bytes().get(last.value.end) {
                    Some(b'\'') => '\'',
                    _ => '"',
                };
                (last.value.end + 1, quote)
            }
            None => (n.start + 1 + n.name.len(), '"'),
        };
        self.splice(at..at, format!(" {name}={quote}{value}{quote}"));
    }

    /// Renames the element `node` (start and end tags) to `name`.
    fn rename(&mut self, node: usize, name: &str) -> Result<(), EditError> {
        let n = self.doc.node(node);
        let old = n.name.len();
        let start = n.start + 1..n.start + 1 + old;
        let end = (!n.empty).then(|| n.end.start + 2..n.end.start + 2 + old);
        for range in std::iter::once(start).chain(end) {
            if self.doc.text.get(range.clone()) != Some(n.name) {
                return Err(internal("a tag name not where expected"));
            }
            self.splice(range, name);
        }
        Ok(())
    }

    /// Removes the element `node`: with its lines and the comment lines
    /// directly above it when it is alone on its lines, else just its text.
    fn remove(&mut self, place: Place) {
        let doc = self.doc;
        let Place { start, end } = place;
        let range = match (doc.block_start(start), doc.line_end_after(end)) {
            (Some(line), Some(after)) => line..after,
            _ => start..end,
        };
        self.splice(range, "");
    }

    /// Inserts `items` (siblings of `node`) just before it, with its
    /// indentation and before the comments above it.
    fn insert_before(&mut self, place: Place, items: &[Lines]) {
        let doc = self.doc;
        let at = place.start;
        match (doc.block_start(at), doc.own_indent(at)) {
            (Some(line), Some(indent)) => self.splice(line..line, block(doc, indent, items)),
            _ => self.splice(at..at, inline(items)),
        }
    }

    /// Inserts `items` (siblings of `node`) on the lines just after it, with
    /// its indentation.
    fn insert_after(&mut self, place: Place, items: &[Lines]) {
        let doc = self.doc;
        let Place { start, end } = place;
        match (doc.own_indent(start), doc.line_end_after(end)) {
            (Some(indent), Some(after)) => {
                let mut text = block(doc, indent, items);
                if !doc.text[..after].ends_with(['\n', '\r']) {
                    // The text ends on this line: start a new one.
                    text = format!("{}{}", doc.nl, text.trim_end_matches(['\r', '\n']));
                }
                self.splice(after..after, text);
            }
            _ => self.splice(end..end, inline(items)),
        }
    }

    /// Inserts new children of `parent` (named `name` in the edited scene),
    /// each before the first existing child of a higher rank, or at the end.
    /// `items` are in rank order; `removed` is a child being removed.
    fn insert_ranked(
        &mut self,
        parent: usize,
        name: &str,
        ranks: &[(&str, u8)],
        items: Vec<(u8, Lines)>,
    ) -> Result<(), EditError> {
        if items.is_empty() {
            return Ok(());
        }
        let doc = self.doc;
        let rank_of = |id: usize| {
            ranks
                .iter()
                .find(|(n, _)| *n == doc.node(id).name)
                .map_or(u8::MAX, |&(_, r)| r)
        };
        let existing: Vec<usize> = doc.node(parent).children.to_vec();
        let mut groups: Vec<(Option<usize>, Vec<Lines>)> = Vec::new();
        for (rank, lines) in items {
            let anchor = existing.iter().copied().find(|&c| rank_of(c) > rank);
            match groups.last_mut() {
                Some((a, group)) if *a == anchor => group.push(lines),
                _ => groups.push((anchor, vec![lines])),
            }
        }
        for (anchor, group) in groups {
            self.insert(parent, name, anchor, &group)?;
        }
        Ok(())
    }

    /// Inserts `items` as children of `parent` (named `name` once edited),
    /// before the child `anchor` or at the end, with the indentation of
    /// their siblings. An empty `<x/>` becomes `<x>…</x>`.
    fn insert(
        &mut self,
        parent: usize,
        name: &str,
        anchor: Option<usize>,
        items: &[Lines],
    ) -> Result<(), EditError> {
        let doc = self.doc;
        let p = doc.node(parent);
        let block = |indent: &str| block(doc, indent, items);
        let inline = || inline(items);
        let parent_indent = doc.own_indent(p.start).unwrap_or("");

        if let Some(sibling) = anchor {
            let at = doc.node(sibling).start;
            match doc.own_indent(at) {
                Some(indent) => {
                    let line = doc.line_start(at);
                    self.splice(line..line, block(indent));
                }
                None => self.splice(at..at, inline()),
            }
            return Ok(());
        }

        if p.empty {
            // `<x .../>` (maybe `<x ... />`): replace from the end of the
            // attributes to the end of the tag.
            let slash = p
                .tag_end
                .checked_sub(2)
                .filter(|&s| doc.text.get(s..p.tag_end) == Some("/>"))
                .ok_or_else(|| internal("an empty element without '/>'"))?;
            let tag = doc.text.get(p.start..slash).unwrap_or_default();
            let from = p.start + tag.trim_end_matches([' ', '\t', '\r', '\n']).len();
            let child_indent = format!("{parent_indent}{}", doc.unit);
            let text = format!(
                ">{}{}{parent_indent}</{name}>",
                doc.nl,
                block(&child_indent)
            );
            self.splice(from..p.tag_end, text);
            return Ok(());
        }

        let end = p.end.start;
        if let Some(end_indent) = doc.own_indent(end) {
            // The last child: a node, or for the root maybe an object.
            let last_node = p.children.last().map(|&c| doc.node(c).start);
            let last_object = doc.objects.last().map(|o| o.start);
            let last = match (last_node, last_object) {
                (Some(n), Some(o)) if parent == doc.root => Some(n.max(o)),
                (n, o) if parent == doc.root => n.or(o),
                (n, _) => n,
            };
            let sibling_indent = last.and_then(|start| doc.own_indent(start));
            let indent = match sibling_indent {
                Some(indent) => indent.to_owned(),
                None => {
                    let outer = doc.own_indent(p.start).unwrap_or(end_indent);
                    format!("{outer}{}", doc.unit)
                }
            };
            let line = doc.line_start(end);
            self.splice(line..line, block(&indent));
        } else if doc
            .text
            .get(p.tag_end..end)
            .is_some_and(|s| s.trim_matches([' ', '\t']).is_empty())
        {
            let child_indent = format!("{parent_indent}{}", doc.unit);
            let text = format!("{}{}{parent_indent}", doc.nl, block(&child_indent));
            self.splice(p.tag_end..end, text);
        } else {
            self.splice(end..end, inline());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(text: &str) -> Scene {
        parse(text, Path::new("t.xml")).unwrap()
    }

    #[test]
    fn no_change_means_no_splice() {
        for text in [
            crate::EXAMPLE_SCENE,
            "\u{feff}<scene><!-- x --><camera width='2' height=\"3\" eyeDistance=\"1.0\"/></scene>",
        ] {
            let s = scene(text);
            let doc = Doc::scan(text, Keep::All).unwrap();
            let mut editor = Editor {
                doc: &doc,
                splices: Vec::new(),
            };
            editor.scene(&s, &Edited::new(s.clone())).unwrap();
            assert!(editor.splices.is_empty());
            assert_eq!(
                save(text, Path::new("t.xml"), &Edited::new(s)).unwrap(),
                text
            );
        }
    }

    #[test]
    fn numbers_read_back_exactly() {
        for v in [
            0.0,
            -0.0,
            1.0,
            0.1,
            1.0 / 3.0,
            1e-7,
            1e-300,
            5e-324,
            1e16,
            1e300,
            f64::MAX,
            -2.5e-8,
            123456.789,
            0.000001,
        ] {
            let s = num(v);
            let back: f64 = s.parse().unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{v} -> {s}");
            assert!(s.len() < 30, "{s}");
        }
    }

    #[test]
    fn indentation_unit_is_detected() {
        assert_eq!(
            Doc::scan(crate::EXAMPLE_SCENE, Keep::All).unwrap().unit,
            " "
        );
        let tabs = "<scene>\n\t<camera width=\"1\" height=\"1\" eyeDistance=\"1\"/>\n</scene>\n";
        assert_eq!(Doc::scan(tabs, Keep::All).unwrap().unit, "\t");
        let flat = "<scene><camera width=\"1\" height=\"1\" eyeDistance=\"1\"/></scene>";
        assert_eq!(Doc::scan(flat, Keep::All).unwrap().unit, "  ");
        // Only the objects show it (the rest on one line): the same unit
        // when they are only placed as when they are nodes (without their
        // elements, as in a save: see `Keep::TopLevel`).
        let objects = "<scene>\n   <sphere/>\n   <plane>\n      <color red=\"1\" green=\"1\" blue=\"1\"/>\n   </plane>\n<camera width=\"1\" height=\"1\" eyeDistance=\"1\"/></scene>";
        let none = std::collections::HashSet::new();
        for text in [crate::EXAMPLE_SCENE, tabs, flat, objects] {
            let unit = Doc::scan(text, Keep::TopLevel).unwrap().unit;
            assert_eq!(Doc::scan(text, Keep::Placed).unwrap().unit, unit, "{text}");
        }
        for keep in [Keep::Placed, Keep::Objects(&none)] {
            assert_eq!(Doc::scan(objects, keep).unwrap().unit, "   ");
        }
    }

    #[test]
    fn overlapping_splices_are_an_error() {
        let splices = vec![
            Splice {
                range: 0..3,
                text: "a".into(),
            },
            Splice {
                range: 2..4,
                text: "b".into(),
            },
        ];
        assert!(matches!(
            Rewrite::new("abcdef", splices),
            Err(EditError::Internal(_))
        ));
    }

    #[test]
    fn a_save_scans_only_the_objects_it_changes() {
        let text = "<scene>\n  <sphere><color red=\"1\" green=\"0\" blue=\"0\"/></sphere>\n  \
                    <sphere><color red=\"0\" green=\"1\" blue=\"0\"/></sphere>\n  \
                    <plane><color red=\"0\" green=\"0\" blue=\"1\"/></plane>\n  \
                    <camera width=\"2\" height=\"2\" eyeDistance=\"1\"/>\n</scene>\n";
        fn count(text: &str, keep: Keep) -> usize {
            Doc::scan(text, keep).unwrap().nodes.len()
        }
        let (second, ends) = ([1].into(), [0, 2].into());
        // The root, three objects and the camera; then a colour each. An
        // object not asked for is only placed: no node.
        assert_eq!(count(text, Keep::TopLevel), 5);
        assert_eq!(count(text, Keep::All), 8);
        assert_eq!(count(text, Keep::Placed), 2);
        assert_eq!(count(text, Keep::Objects(&second)), 4);
        assert_eq!(count(text, Keep::Objects(&ends)), 6);
        // Every object placed, whichever are kept, at the same place.
        let places = |keep| Doc::scan(text, keep).unwrap().objects;
        let all = places(Keep::All);
        assert_eq!(all.len(), 3);
        assert_eq!(
            &text[all[1].start..all[1].end],
            "<sphere><color red=\"0\" green=\"1\" blue=\"0\"/></sphere>"
        );
        for keep in [
            Keep::TopLevel,
            Keep::Placed,
            Keep::Objects(&second),
            Keep::Objects(&ends),
        ] {
            assert_eq!(places(keep), all);
        }

        let original = scene(text);
        let mut edited = Edited::new(original.clone());
        edited
            .apply(&crate::scene::edit::Edit::Set(
                crate::scene::edit::Field::parse("object[2].color.blue").unwrap(),
                crate::scene::edit::Value::Number(0.5),
            ))
            .unwrap();
        assert_eq!(changed_objects(&original, &edited), [1].into());
        let saved = save(text, Path::new("t.xml"), &edited).unwrap();
        assert_eq!(
            saved,
            text.replacen("green=\"1\" blue=\"0\"", "green=\"1\" blue=\"0.5\"", 1)
        );
    }

    /// The text of `rewrite`.
    fn written(rewrite: &Rewrite<'_>) -> String {
        let mut out = Vec::new();
        rewrite.write_to(&mut out).unwrap();
        assert_eq!(out.len(), rewrite.len());
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn a_packed_text_is_saved_as_the_same_text_held_whole() {
        use crate::scene::edit::{Edit, Element, Field, Item, Owner, Value};
        // Comments above objects, objects on one line and on several, an
        // empty one, CRLF inside objects only, tabs.
        let mut text = String::from("\u{feff}<?xml version=\"1.0\"?>\n<!-- top -->\n<scene>\n");
        for i in 0..60 {
            text.push_str(&match i % 5 {
                0 => format!("  <!-- BALL {i} -->\n  <sphere><color red=\"0.{i}\" green=\"1\" blue=\"0\"/><material ka=\"0.1\"/></sphere>\n"),
                1 => format!("  <sphere>\r\n    <material kd=\"0.{i}\"/>\r\n    <transformation><translate x=\"{i}\"/></transformation>\r\n  </sphere>\n"),
                2 => "\t<sphere/>\n".to_owned(),
                3 => format!("  <plane><transformation><rotate-x angle=\"1.{i}\"/><translate y=\"{i}\"/></transformation></plane>\n"),
                _ => format!("  <sphere> <!-- inside {i} --> <color red=\"1\" green=\"0\" blue=\"0\"/> </sphere>\n"),
            });
        }
        text.push_str("  <light x=\"1\" y=\"2\" z=\"3\"/>\n  <camera width=\"8\" height=\"6\" eyeDistance=\"1\"/>\n</scene>\n");
        let original = scene(&text);
        let packed = Source::packed(&text);
        let mut edited = Edited::new(original.clone());
        let mut rng = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: usize| {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng % n as u64) as usize
        };
        for round in 0..120 {
            let objects = edited.scene().objects.len();
            // An insertion first, before any object is kept whole.
            let kind = if round == 0 { 3 } else { next(8) };
            let edit = match kind {
                0 | 1 => Edit::Set(
                    Field::parse(&format!("object[{}].material.ka", next(objects) + 1)).unwrap(),
                    Value::Number(round as f64 / 100.0),
                ),
                2 => Edit::Remove(Item::Object(next(objects))),
                3 => {
                    let copy = edited.scene().objects[next(objects)].as_ref().clone();
                    Edit::Insert(
                        Item::Object(next(objects + 1)),
                        Element::Object(Box::new(copy)),
                    )
                }
                4 => Edit::add_step(
                    edited.scene(),
                    Owner::Object(next(objects)),
                    crate::math::TransformStep::UniformScale(1.5),
                )
                .unwrap(),
                5 => Edit::Set(
                    Field::parse("light[1].x").unwrap(),
                    Value::Number(round as f64),
                ),
                6 => Edit::Set(
                    Field::parse("camera.width").unwrap(),
                    Value::Integer(4 + round as u64 % 9),
                ),
                _ => Edit::Set(
                    Field::parse(&format!("object[{}].color.red", next(objects) + 1)).unwrap(),
                    Value::Number(0.5),
                ),
            };
            if edited.apply(&edit).is_err() {
                continue;
            }
            let whole = written(&plan(&text, &original, &edited).unwrap());
            let from_packed = written(&plan_source(&packed, &original, &edited).unwrap());
            assert_eq!(from_packed, whole, "round {round}: {edit:?}");
            assert_eq!(&scene(&whole), edited.scene());
        }
        // Nothing changed: the text as it is.
        let unchanged = Edited::new(original.clone());
        assert_eq!(
            written(&plan_source(&packed, &original, &unchanged).unwrap()),
            text
        );
    }

    /// Values edited in place, on texts laid out every which way: the
    /// save of a packed text folds the unchanged objects away (its
    /// skeleton a fraction of the text) and writes the text a text held
    /// whole would.
    #[test]
    fn a_skeleton_with_objects_folded_away_saves_as_the_whole_text() {
        use crate::scene::edit::{Edit, Field, Item, NewElement};
        let ball =
            |i: usize| format!("<sphere><color red=\"0.{i}\" green=\"1\" blue=\"0\"/></sphere>");
        let many = |each: &dyn Fn(usize) -> String| (0..40).map(each).collect::<String>();
        let texts = [
            // Comments between objects, a light among them, no model.
            format!(
                "<scene>\n{}  <light x=\"1\" y=\"2\" z=\"3\"/>\n{}  <camera width=\"8\" height=\"6\" eyeDistance=\"1\"/>\n</scene>\n",
                many(&|i| format!("  <!-- ball {i} -->\n  {}\n", ball(i))),
                many(&|i| format!("  <plane/><!-- {i} -->\n  {}\n", ball(i))),
            ),
            // The root not on its own line, objects on its line.
            format!(
                "<?xml version=\"1.0\"?><scene>{}\n<light x=\"1\" y=\"2\" z=\"3\"/><camera width=\"8\" height=\"6\" eyeDistance=\"1\"/><model type=\"lambert\"/></scene>",
                many(&|i| ball(i)),
            ),
            // A byte order mark, CRLF, tabs; the first objects not on lines
            // of their own, then some less indented than the root.
            format!(
                "{}  <scene>\r\n  <sphere/> {}\r\n {}\r\n{}\t\t<light x=\"1\" y=\"2\" z=\"3\"/>\r\n\t\t<camera width=\"8\" height=\"6\" eyeDistance=\"1\"/>\r\n  </scene>\r\n",
                '\u{feff}',
                ball(0),
                ball(1),
                many(&|i| format!("  \t{}\r\n", ball(i))),
            ),
            // The first object sets the indentation unit (three spaces)
            // that an empty sphere given a colour indents it with.
            format!(
                "<scene>\n   <sphere/>\n{}  <light x=\"1\" y=\"2\" z=\"3\"/>\n  <camera width=\"8\" height=\"6\" eyeDistance=\"1\"/>\n</scene>\n",
                many(&|_| "  <sphere/>\n".to_owned()),
            ),
            // Every object on one line; lights last, one after the other.
            format!(
                "<scene>\n  {}<light x=\"1\" y=\"2\" z=\"3\"/><light x=\"4\" y=\"2\" z=\"3\"/>\n  <camera width=\"8\" height=\"6\" eyeDistance=\"1\"/>\n</scene>",
                many(&|i| ball(i)),
            ),
        ];
        for (t, text) in texts.iter().enumerate() {
            let original = scene(text);
            let packed = Source::packed(text);
            let mut edited = Edited::new(original.clone());
            let mut rng = 0x9e37_79b9_7f4a_7c15u64 + t as u64;
            let mut next = |n: usize| {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                (rng % n.max(1) as u64) as usize
            };
            for round in 0..40 {
                let objects = original.objects.len();
                let lights = edited.scene().lights.len();
                let set = |path: String, value: &str| {
                    let field = Field::parse(&path).unwrap();
                    Edit::Set(field, field.parse_value(value).unwrap())
                };
                let edit = match next(8) {
                    0 | 1 => set(
                        format!("object[{}].material.ka", next(objects) + 1),
                        &format!("0.{round}"),
                    ),
                    2 => set(format!("object[{}].color.green", next(objects) + 1), "0.5"),
                    3 if lights > 0 => set(format!("light[{}].x", next(lights) + 1), "7"),
                    4 => Edit::add(edited.scene(), NewElement::Light),
                    5 if lights > 1 => Edit::Remove(Item::Light(next(lights))),
                    6 => set("camera.width".to_owned(), &format!("{}", 4 + round)),
                    _ => set("model.type".to_owned(), ["phong", "whitted"][round % 2]),
                };
                if edited.apply(&edit).is_err() {
                    continue;
                }
                assert!(edited.objects_in_place());
                let changed = changed_objects(&original, &edited);
                let skeleton = Skeleton::read(&packed, &changed, true).unwrap();
                let folded = skeleton.folded.as_ref().unwrap();
                assert!(
                    folded.numbers.len() <= 2 * changed.len() + 8,
                    "text {t}, round {round}: {} objects left of {objects}",
                    folded.numbers.len()
                );
                let whole = written(&plan(text, &original, &edited).unwrap());
                let from_packed = written(&plan_source(&packed, &original, &edited).unwrap());
                assert_eq!(from_packed, whole, "text {t}, round {round}: {edit:?}");
                assert_eq!(&scene(&whole), edited.scene());
            }
        }
    }
}
