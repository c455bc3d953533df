//! The skeleton of a text held packed: the text with the insides of the
//! objects a save leaves as they are left out, and runs of unchanged
//! objects folded away, with the map of its offsets back to the text's.
//! A save of a packed text ([`crate::scene::splice::plan_source`]) and the
//! names of its objects ([`super::source_object_comments`]) read it instead
//! of unpacking the whole text.

use std::cell::RefCell;
use std::rc::Rc;

use quick_xml::Reader;
use quick_xml::events::Event;

use super::internal;
use crate::scene::Shape;
use crate::scene::edit::EditError;
use crate::scene::source::Source;

/// A packed text with the insides of the objects a save leaves as they
/// are left out (`<sphere>…</sphere>` becomes `<sphere></sphere>`): what
/// the save's editor reads instead of the whole text. A million spheres'
/// 214 MB become about 20 MB, and only the changed objects' elements are
/// scanned in full, as in a text held whole
/// ([`plan`](crate::scene::splice::plan)). When only values were
/// edited, runs of unchanged objects are folded away whole ([`Folded`]):
/// a few lines.
///
/// Every splice the editor makes lies outside the parts left out (at an
/// object's start or end, or inside a changed one), so each of its
/// offsets maps to the source's.
pub(in crate::scene) struct Skeleton {
    pub(in crate::scene) text: String,
    /// For each part left out, the skeleton's offset where it was and the
    /// bytes left out up to there in all.
    /// (u32: a text is at most 1 GiB.)
    pub(in crate::scene) gaps: Vec<(u32, u32)>,
    /// The whole text has a CRLF line ending (maybe only in a part left
    /// out): new lines are written with it, as in a text held whole.
    pub(in crate::scene) crlf: bool,
    /// Runs of objects folded away, when they were.
    pub(in crate::scene) folded: Option<Folded>,
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
pub(in crate::scene) struct Folded {
    /// Each object's number in the text, in skeleton order.
    pub(in crate::scene) numbers: Vec<usize>,
    /// Which of the skeleton's objects (by skeleton order) are changed.
    pub(in crate::scene) changed: std::collections::HashSet<usize>,
}

/// What a run of objects folds into in a skeleton ([`Folded`]); its gap
/// is after the second byte.
pub(in crate::scene) const FOLD: &[u8; 4] = b"<_/>";

impl Skeleton {
    /// Reads `source`, keeping whole the objects (numbered in text order)
    /// in `keep`. With `fold` (every object is where it was, with its own
    /// steps: an edit of values only), each run of unchanged objects but
    /// its last is folded into one `<_/>` ([`Folded`]).
    pub(in crate::scene) fn read(
        source: &Source,
        keep: &std::collections::HashSet<usize>,
        fold: bool,
    ) -> Result<Skeleton, EditError> {
        let bom = byte_order_mark(source);
        let pending = Rc::new(RefCell::new(Pending::default()));
        let mut reader = tee_reader(source, &pending, bom);
        let mut taker = Taker {
            pending,
            fold,
            crlf: false,
            last_byte: 0,
            line: Some(Vec::new()),
        };
        let mut kept: Vec<u8> = Vec::new();

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
            let before = position(&reader, bom)?;
            buf.clear();
            let event = reader
                .read_event_into(&mut buf)
                .map_err(|e| internal(format!("XML: {e}")))?;
            let after = position(&reader, bom)?;
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
                            taker.take(h.start, true, &mut kept);
                            kept.extend_from_slice(&FOLD[..2]);
                            folding = Some(kept.len());
                        }
                        // It, and the bytes before it since the last one.
                        left_out += taker.take(h.end, false, &mut kept);
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
                            taker.take(inside, true, &mut kept);
                            left_out += taker.take(end_tag, false, &mut kept);
                            gaps.push(gap(kept.len(), left_out)?);
                        }
                        taker.take(h.end, true, &mut kept);
                    }
                }
                // The bytes since are kept, but before an object that may
                // be folded: they go with it.
                if !foldable {
                    taker.take(before, true, &mut kept);
                }
            }
            match event {
                Event::Start(_) if depth == 0 && root_indent.is_none() => {
                    let line = taker.line.clone();
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
                        may_fold = match (&root_indent, &taker.line) {
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
                            taker.take(after, true, &mut kept);
                            leaving_out = Some(depth);
                            continue;
                        }
                    }
                }
                Event::Start(_) => depth += 1,
                Event::End(_) => {
                    if leaving_out == Some(depth) {
                        // The inside, up to the `<` of the end tag.
                        left_out += taker.take(before, false, &mut kept);
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
                Some(_) => left_out += taker.take(after, false, &mut kept),
                None => {
                    taker.take(after, true, &mut kept);
                }
            }
        }
        taker.take(usize::MAX, true, &mut kept);
        let text = String::from_utf8(kept).map_err(|_| internal("the skeleton is not UTF-8"))?;
        let folded = fold.then_some(Folded { numbers, changed });
        Ok(Skeleton {
            text,
            gaps,
            crlf: taker.crlf,
            folded,
        })
    }

    /// The source's offset of the skeleton's offset `at`.
    pub(in crate::scene) fn in_source(&self, at: usize) -> usize {
        let i = self.gaps.partition_point(|&(gap, _)| gap as usize <= at);
        at + i.checked_sub(1).map_or(0, |i| self.gaps[i].1 as usize)
    }
}

/// The source's bytes as read, not yet given to the skeleton or left out;
/// `start`: the source offset of the first.
#[derive(Default)]
struct Pending {
    bytes: Vec<u8>,
    start: usize,
}

/// The source's bytes to the XML reader, and into `pending`; a byte order
/// mark (`hide`: its length) to `pending` only, so that the reader's
/// positions are the text's less it.
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

/// An object that may be folded, read whole, its fate waiting on what
/// comes next: folded if another such object follows, else the last of
/// its run, left as a stub (`<sphere></sphere>`).
struct Held {
    number: usize,
    start: usize,
    /// Just past its start tag and at its end tag's `<` (`None` for
    /// `<sphere/>`).
    inside: Option<(usize, usize)>,
    end: usize,
}

/// The length of `source`'s byte order mark: 3, or 0 without one.
fn byte_order_mark(source: &Source) -> usize {
    let mut head = [0u8; 3];
    let read = std::io::Read::read_exact(&mut source.reader(), &mut head);
    match read.is_ok() && head == *b"\xef\xbb\xbf" {
        true => head.len(),
        false => 0,
    }
}

/// An XML reader of `source` (less its byte order mark, `bom` bytes)
/// whose every byte read also goes to `pending`.
fn tee_reader<'s>(
    source: &'s Source,
    pending: &Rc<RefCell<Pending>>,
    bom: usize,
) -> Reader<std::io::BufReader<Tee<'s>>> {
    let tee = Tee {
        inner: source.reader(),
        pending: Rc::clone(pending),
        hide: bom,
    };
    let mut reader = Reader::from_reader(std::io::BufReader::with_capacity(1 << 16, tee));
    let config = reader.config_mut();
    config.check_end_names = true;
    config.expand_empty_elements = false;
    config.trim_text(false);
    reader
}

/// The source's bytes read and not yet placed, moved into the skeleton or
/// left out a run at a time ([`Taker::take`]), and what they tell on the
/// way: the text's line ending, the current line's indentation.
struct Taker {
    pending: Rc<RefCell<Pending>>,
    /// Objects may be folded: `line` is followed.
    fold: bool,
    /// A CRLF line ending was seen (maybe in a part left out).
    crlf: bool,
    last_byte: u8,
    /// The current line's bytes so far, while they are all spaces and
    /// tabs (`Doc::own_indent`).
    line: Option<Vec<u8>>,
}

impl Taker {
    /// Moves the source's bytes up to `to` from the pending ones into the
    /// skeleton (`kept`, with `keep`), or leaves them out; returns how
    /// many.
    fn take(&mut self, to: usize, keep: bool, kept: &mut Vec<u8>) -> usize {
        let mut p = self.pending.borrow_mut();
        let n = to.saturating_sub(p.start).min(p.bytes.len());
        let bytes = &p.bytes[..n];
        if bytes.first() == Some(&b'\n') && self.last_byte == b'\r'
            || bytes.windows(2).any(|w| w == b"\r\n")
        {
            self.crlf = true;
        }
        if let Some(&b) = bytes.last() {
            self.last_byte = b;
        }
        // A byte order mark is not on the first line (`Doc::scan`).
        let line_bytes = match p.start == 0 && bytes.starts_with(b"\xef\xbb\xbf") {
            true => &bytes[3..],
            false => bytes,
        };
        let blank = |bytes: &[u8]| bytes.iter().all(|&b| b == b' ' || b == b'\t');
        let line = &mut self.line;
        if !self.fold {
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
    }
}

/// The reader's position in the source (`bom`: the byte order mark it
/// does not see).
fn position<R>(reader: &Reader<R>, bom: usize) -> Result<usize, EditError> {
    usize::try_from(reader.buffer_position())
        .map(|p| p + bom)
        .map_err(|_| internal("position out of range"))
}

/// A gap at skeleton offset `at`, `out` bytes left out up to there.
fn gap(at: usize, out: usize) -> Result<(u32, u32), EditError> {
    match (u32::try_from(at), u32::try_from(out)) {
        (Ok(at), Ok(out)) => Ok((at, out)),
        _ => Err(internal("a text over 4 GiB")),
    }
}
