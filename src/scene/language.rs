//! The scene format as an editor sees it, for `rayoflight lsp`: a text's
//! errors with their places, what may be typed at a place, what a name
//! means, and the text's outline. No protocol here: positions are lines
//! and UTF-16 columns (as the Language Server Protocol counts by default)
//! or byte offsets, and the words come from [`super::grammar`], the table
//! the loader reads with, and from the loader's own errors.
//!
//! Completion reads the text before the cursor leniently, as it is while
//! being typed (a tag not closed yet, an attribute half written): the
//! elements open at the cursor give the parent, the tag the cursor is in
//! gives the element and the attributes it has. An editor's text keeps
//! [`Marks`] of where that reading may start again, so that a completion
//! in a large text does not read it all from the start each time.

use super::grammar::{self, Value};
use super::xml::is_name_char;
use super::{LoadError, Position, Reading, Shape, layout, names};
use std::ops::Range;

/// A place as the protocol counts it: 0-based line, 0-based column in
/// UTF-16 code units.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct Place {
    pub line: u32,
    pub column: u32,
}

/// The offsets where each line starts, to go between byte offsets and
/// [`Place`]s. Lines end at LF, CR LF or a lone CR (as XML and the protocol
/// both say).
#[derive(Debug, Clone)]
pub struct Lines {
    starts: Vec<usize>,
}

impl Lines {
    pub fn new(text: &str) -> Lines {
        let bytes = text.as_bytes();
        let mut starts = vec![0];
        let mut i = 0;
        while i < bytes.len() {
            match bytes[i] {
                b'\n' => starts.push(i + 1),
                b'\r' if bytes.get(i + 1) != Some(&b'\n') => starts.push(i + 1),
                _ => {}
            }
            i += 1;
        }
        Lines { starts }
    }

    /// After `text[range]` was replaced by `inserted` bytes (`text` is the
    /// new text): the line starts moved, without reading the rest of the
    /// text again.
    pub fn edit(&mut self, text: &str, range: Range<usize>, inserted: usize) {
        // A line starts at p when byte p - 1 is LF, or CR not followed by
        // LF: it depends on bytes p - 1 and p. Starts before the edit
        // stay, those from one past its end on move by the change in
        // length, and those in between are found again.
        let (a, b) = (range.start, range.end);
        let new_end = a + inserted;
        let is_start = |p: usize| {
            let bytes = text.as_bytes();
            match bytes.get(p.wrapping_sub(1)) {
                Some(b'\n') => true,
                Some(b'\r') => bytes.get(p) != Some(&b'\n'),
                _ => false,
            }
        };
        let keep = self.starts.partition_point(|&s| s < a.max(1));
        let after = self.starts.partition_point(|&s| s < b + 1).max(keep);
        let found: Vec<usize> = (a.max(1)..=new_end.min(text.len()))
            .filter(|&p| is_start(p))
            .collect();
        // In place: the lines of a million spheres are 56 MB, moved once
        // and shifted where they lie, not copied out and back at each
        // keystroke.
        let moved_from = keep + found.len();
        self.starts.splice(keep..after, found);
        for s in &mut self.starts[moved_from..] {
            *s = *s - b + new_end;
        }
    }

    /// Where each line starts, in bytes.
    pub fn starts(&self) -> &[usize] {
        &self.starts
    }

    /// The place of byte `offset` of `text` (clamped to the text).
    pub fn place(&self, text: &str, offset: usize) -> Place {
        let mut offset = offset.min(text.len());
        while !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let line = self.starts.partition_point(|&s| s <= offset) - 1;
        let start = self.starts[line];
        let column = text[start..offset].encode_utf16().count();
        Place {
            line: u32::try_from(line).unwrap_or(u32::MAX),
            column: u32::try_from(column).unwrap_or(u32::MAX),
        }
    }

    /// The byte offset of `place` in `text`: a column past the line's end is
    /// the line's end, one inside a character its start.
    pub fn offset(&self, text: &str, place: Place) -> usize {
        let Some(&start) = self.starts.get(place.line as usize) else {
            return text.len();
        };
        let end = self
            .starts
            .get(place.line as usize + 1)
            .copied()
            .unwrap_or(text.len());
        let line = &text[start..end];
        let line = line.trim_end_matches(['\n', '\r']);
        let mut units = 0u32;
        for (i, c) in line.char_indices() {
            if units >= place.column {
                return start + i;
            }
            units += c.len_utf16() as u32;
            if units > place.column {
                return start + i;
            }
        }
        start + line.len()
    }

    /// The byte offset of a loader [`Position`] (1-based line, column in
    /// characters).
    pub fn offset_of_position(&self, text: &str, position: Position) -> usize {
        let Some(&start) = self.starts.get(position.line.saturating_sub(1)) else {
            return text.len();
        };
        text[start..]
            .char_indices()
            .nth(position.column.saturating_sub(1))
            .map_or(text.len(), |(i, _)| start + i)
    }
}

/// One error of a text, for an editor to underline.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Diagnostic {
    /// The bytes it is about: the name at the error's place, or the first
    /// line when the error has no place (no camera).
    pub range: Range<usize>,
    /// The loader's message, without the file and place it starts with.
    pub message: String,
}

/// The first error of `text` as the loader reports it, or none: a text
/// read whole ([`diagnostics_after`] with nothing known before).
pub fn diagnostics(text: &str) -> Vec<Diagnostic> {
    diagnostics_after(&mut Reading::default(), text, &Lines::new(text))
}

/// The first error of `text` after edits `reading` was told of, as the
/// loader reports it, or none: read from the edits on where it can be
/// ([`Reading`]), placed by the text's `lines`.
pub fn diagnostics_after(reading: &mut Reading, text: &str, lines: &Lines) -> Vec<Diagnostic> {
    match reading.check(text, Some(lines.starts())) {
        Ok(()) => Vec::new(),
        Err(e) => vec![diagnostic(text, lines, &e)],
    }
}

/// The error `e` of `text`, placed by `lines` (those of `text`).
fn diagnostic(text: &str, lines: &Lines, e: &LoadError) -> Diagnostic {
    let message = e.kind.to_string();
    let range = match e.position {
        Some(position) => {
            // The loader counts columns without a byte-order mark: on the
            // first line after one, counted from after it.
            let bom = if text.starts_with('\u{feff}') && position.line == 1 {
                '\u{feff}'.len_utf8()
            } else {
                0
            };
            let at = match bom {
                0 => lines.offset_of_position(text, position),
                _ => {
                    let column = position.column.saturating_sub(1);
                    bom + text[bom..]
                        .char_indices()
                        .nth(column)
                        .map_or(text.len() - bom, |(i, _)| i)
                }
            };
            at..word_end(text, at)
        }
        None => {
            // The root's start tag, else the start of the text.
            let root = text.find("<scene").unwrap_or(0);
            root..word_end(text, root)
        }
    };
    Diagnostic { range, message }
}

/// The end of the name or word starting at `at` (at least one character,
/// within its line).
fn word_end(text: &str, at: usize) -> usize {
    let rest = &text[at.min(text.len())..];
    let mut end = 0;
    for (i, c) in rest.char_indices() {
        let name = c.is_alphanumeric() || matches!(c, '-' | '_' | ':' | '.' | '<' | '/' | '+');
        if i > 0 && !name || c == '\n' || c == '\r' {
            break;
        }
        end = i + c.len_utf8();
    }
    at + end
}

/// Something that may be typed at a place.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Completion {
    /// What the list shows (`sphere`, `ka`, `phong`).
    pub label: String,
    /// What is inserted in place of the word being typed.
    pub insert: String,
    pub kind: CompletionKind,
    /// Its meaning, range and default.
    pub doc: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CompletionKind {
    Element,
    Attribute,
    Value,
}

/// Where in the markup a byte offset is.
#[derive(Debug, PartialEq, Eq)]
enum Spot<'t> {
    /// Between elements, inside the element whose name is at `parent`
    /// (`None`: outside the root).
    Content { parent: Option<Range<usize>> },
    /// Typing an element's name after `<`, inside `parent`.
    ElementName {
        parent: Option<Range<usize>>,
        typed: &'t str,
    },
    /// In a comment, a declaration or a CDATA section: nothing to type.
    Markup,
    /// In `element`'s start tag, where an attribute name goes; `present`
    /// are those it has.
    AttributeName {
        element: &'t str,
        present: Vec<&'t str>,
        typed: &'t str,
    },
    /// In the value of `attribute` of `element`.
    AttributeValue {
        element: &'t str,
        attribute: &'t str,
        typed: &'t str,
    },
}

/// Where a scan of a text before a cursor ([`completions`], [`hover`])
/// may start again instead of at the start: the elements open at places
/// every [`Marks::DEFAULT_EVERY`] bytes or so, as a scan from the start
/// found them. The state of the scan at a place depends only on the text
/// before it, so a mark stays true until the text before it changes.
///
/// Kept beside an editor's text, [`Marks::edited`] keeps the marks before
/// an edit and holds those after it as unsure, moved by what the edit
/// added or took away. The next scan reads on from the edit; where it
/// comes to an unsure mark's place with the same elements open, it reads
/// the rest of the text as before the edit, so every unsure mark is true
/// again and the scan goes on from the last one. A completion at the end
/// of a million objects (214 MB) reads the whole text once (0.5 s), then
/// only from the last mark, even after an edit in the middle.
#[derive(Debug, Clone)]
pub struct Marks {
    every: usize,
    /// In the order of the text.
    marks: Vec<Mark>,
    /// Marks after an edit, moved with the text after it, not yet found
    /// true again; in order, all after `marks`.
    unsure: Vec<Mark>,
    /// How many places scans have passed (for tests of how far they read).
    #[cfg(test)]
    passed: usize,
}

/// A place a scan passed, and the open elements' names there (their bytes
/// in the text), outermost first.
type Mark = (usize, Vec<Range<usize>>);

impl Default for Marks {
    fn default() -> Marks {
        Marks::every(Marks::DEFAULT_EVERY)
    }
}

impl Marks {
    /// A scan from a mark reads at most this much more than it must
    /// (under a millisecond).
    pub const DEFAULT_EVERY: usize = 256 << 10;

    /// Marks about `every` bytes apart (at least one).
    pub fn every(every: usize) -> Marks {
        Marks {
            every: every.max(1),
            marks: Vec::new(),
            unsure: Vec::new(),
            #[cfg(test)]
            passed: 0,
        }
    }

    /// The bytes `replaced` of the text were replaced by `inserted` bytes:
    /// the marks after the edit's start are unsure from now on, and those
    /// after its end move with the text. A mark with an open element's
    /// name starting or ending in the replaced bytes could not be moved:
    /// it goes.
    pub fn edited(&mut self, replaced: Range<usize>, inserted: usize) {
        let Range { start, end } = replaced;
        let end = end.max(start);
        let moved = |at: usize| {
            if at < start {
                Some(at)
            } else if at >= end {
                (at - end).checked_add(start + inserted)
            } else {
                None
            }
        };
        let keep = self.marks.partition_point(|m| m.0 <= start);
        let mut later = self.marks.split_off(keep);
        later.append(&mut self.unsure);
        self.unsure = later
            .into_iter()
            .filter_map(|(at, open)| {
                let at = if at <= start { at } else { moved(at)? };
                let open = open
                    .into_iter()
                    .map(|name| {
                        if name.end <= start {
                            Some(name)
                        } else {
                            Some(moved(name.start)?..moved(name.end)?)
                        }
                    })
                    .collect::<Option<Vec<_>>>()?;
                Some((at, open))
            })
            .collect();
    }

    /// The last mark at or before `offset`: the scan's place and the open
    /// elements there (the start, with none, where there is no mark).
    fn before(&self, offset: usize) -> Mark {
        let k = self.marks.partition_point(|m| m.0 <= offset);
        k.checked_sub(1)
            .and_then(|k| self.marks.get(k))
            .cloned()
            .unwrap_or_default()
    }

    /// The scan is at `at` with `open` elements: a mark if the last is far
    /// enough behind. Where an unsure mark is at `at` with the same `open`,
    /// the text from here on reads as it did when it was made: all the
    /// unsure marks are true again, and `true` says the scan may go on
    /// from the last before where it is going.
    fn passing(&mut self, at: usize, open: &[Range<usize>]) -> bool {
        #[cfg(test)]
        {
            self.passed += 1;
        }
        let passed = self.unsure.partition_point(|m| m.0 < at);
        self.unsure.drain(..passed);
        if self
            .unsure
            .first()
            .is_some_and(|m| m.0 == at && m.1 == open)
        {
            self.marks.append(&mut self.unsure);
            return true;
        }
        let last = self.marks.last().map_or(0, |m| m.0);
        if at >= last.saturating_add(self.every) {
            self.marks.push((at, open.to_vec()));
        }
        false
    }
}

/// Where `offset` is in `text`, read leniently from the start, or from the
/// last of `marks` before it (and marked on the way).
fn spot<'t>(text: &'t str, offset: usize, marks: &mut Marks) -> Spot<'t> {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let (mut i, mut open) = marks.before(offset);
    let content = |open: &[Range<usize>]| Spot::Content {
        parent: open.last().cloned(),
    };
    let bytes = before.as_bytes();
    loop {
        if marks.passing(i, &open) {
            (i, open) = marks.before(offset);
        }
        let Some(lt) = before[i..].find('<').map(|k| i + k) else {
            break;
        };
        let rest = &before[lt..];
        if rest.starts_with("<!--") {
            match rest.find("-->") {
                Some(end) => i = lt + end + 3,
                None => return Spot::Markup,
            }
            continue;
        }
        if rest.starts_with("<?") || rest.starts_with("<!") {
            match rest.find('>') {
                Some(end) => i = lt + end + 1,
                None => return Spot::Markup,
            }
            continue;
        }
        if let Some(closing) = rest.strip_prefix("</") {
            let name = name_at(closing);
            if let Some(k) = open.iter().rposition(|o| &before[o.clone()] == name) {
                open.truncate(k);
            }
            i = match rest.find('>') {
                Some(end) => lt + end + 1,
                None => return content(&open),
            };
            continue;
        }
        // A start tag: its name, then attributes, up to `>` outside quotes.
        let name = name_at(&rest[1..]);
        let mut j = lt + 1 + name.len();
        if j == before.len() {
            return Spot::ElementName {
                parent: open.last().cloned(),
                typed: name,
            };
        }
        // A tag closed before the offset: only its end matters (a text of
        // a million objects is read this way but for its last tag).
        if let Some(end) = tag_end(bytes, j) {
            if bytes[end - 1] != b'/' {
                open.push(lt + 1..lt + 1 + name.len());
            }
            i = end + 1;
            continue;
        }
        let mut present = Vec::new();
        let mut quote: Option<(u8, usize, &str)> = None;
        while j < bytes.len() {
            let b = bytes[j];
            match quote {
                Some((q, _, _)) if b == q => quote = None,
                Some(_) => {}
                None if b == b'"' || b == b'\'' => {
                    // The attribute this value belongs to: the name before `=`.
                    let head = before[lt..j].trim_end();
                    let head = head.strip_suffix('=').unwrap_or(head).trim_end();
                    let start = head.rfind(|c: char| !is_name_char(c)).map_or(0, |k| k + 1);
                    let attribute = &head[start..];
                    present.push(attribute);
                    quote = Some((b, j + 1, attribute));
                }
                None => {}
            }
            j += 1;
        }
        return match quote {
            Some((_, start, attribute)) => Spot::AttributeValue {
                element: name,
                attribute,
                typed: &before[start..],
            },
            None => {
                let typed_start = before
                    .rfind(|c: char| !is_name_char(c))
                    .map_or(0, |k| k + 1);
                let typed = &before[typed_start.max(lt + 1 + name.len())..];
                Spot::AttributeName {
                    element: name,
                    present,
                    typed,
                }
            }
        };
    }
    content(&open)
}

/// The name `s` starts with (empty where it starts with something else).
fn name_at(s: &str) -> &str {
    &s[..s.find(|c: char| !is_name_char(c)).unwrap_or(s.len())]
}

/// The `>` that ends the tag whose attributes start at `from`: the first
/// outside quotes. `None`: the text ends first.
fn tag_end(bytes: &[u8], from: usize) -> Option<usize> {
    let mut j = from;
    loop {
        let k = j + memchr::memchr3(b'>', b'"', b'\'', bytes.get(j..)?)?;
        match bytes[k] {
            b'>' => return Some(k),
            quote => j = k + 1 + memchr::memchr(quote, bytes.get(k + 1..)?)? + 1,
        }
    }
}

/// The elements that may be added at `offset` in the element whose name
/// is at `parent` (`None`: the root): its children but those it has and
/// may have only one of ([`grammar::Repeat`]), before or after `offset`
/// (the tag being typed there aside).
fn may_add(
    text: &str,
    parent: Option<Range<usize>>,
    offset: usize,
) -> impl Iterator<Item = &'static &'static str> + '_ {
    let element = parent.clone().and_then(|p| grammar::element(&text[p]));
    let children = children_of(parent.clone().map(|p| &text[p]));
    // The tag being typed at `offset`, if any: from its `<`.
    let typing = text[..offset.min(text.len())]
        .rfind(['<', '>'])
        .filter(|&k| text.as_bytes()[k] == b'<');
    let once: Vec<&str> = match element.map(|e| e.repeat) {
        Some(grammar::Repeat::EachOnce) => parent
            .map(|p| direct_children(text, p.end, typing))
            .unwrap_or_default(),
        Some(grammar::Repeat::Scene { one, at_most_one }) => [one, at_most_one]
            .into_iter()
            .filter(|name| anywhere(text, name, typing))
            .collect(),
        Some(grammar::Repeat::Any) | None => Vec::new(),
    };
    children.iter().filter(move |name| !once.contains(name))
}

/// The names of the elements directly inside the one whose start tag's
/// name ends at `from`, but the tag that starts at `typing`: read
/// leniently up to its end tag (or any end tag at its level, or the end).
fn direct_children(text: &str, from: usize, typing: Option<usize>) -> Vec<&str> {
    let bytes = text.as_bytes();
    let Some(mut i) = tag_end(bytes, from).map(|end| end + 1) else {
        return Vec::new();
    };
    if bytes[i - 2] == b'/' {
        return Vec::new();
    }
    let mut names = Vec::new();
    let mut depth = 0usize;
    while let Some(lt) = memchr::memchr(b'<', &bytes[i..]).map(|k| i + k) {
        let rest = &text[lt..];
        if Some(lt) == typing {
            // Not a tag yet: what follows may be the next one.
            i = lt + 1;
            continue;
        }
        if rest.starts_with("<!--") {
            let Some(end) = rest.find("-->") else { break };
            i = lt + end + 3;
            continue;
        }
        let Some(end) = tag_end(bytes, lt + 1) else {
            break;
        };
        i = end + 1;
        if rest.starts_with("</") {
            if depth == 0 {
                break;
            }
            depth -= 1;
        } else if !rest.starts_with("<!") && !rest.starts_with("<?") {
            let name = name_at(&rest[1..]);
            if depth == 0 {
                names.push(name);
            }
            if bytes[end - 1] != b'/' {
                depth += 1;
            }
        }
    }
    names
}

/// Whether a start tag of `name` is anywhere in `text` but at `typing`:
/// the root's children that must be one (the camera, the model) are found
/// by a search rather than a reading (a million objects' text is searched
/// in milliseconds from its end, where they usually are). Comments are not
/// told apart.
fn anywhere(text: &str, name: &str, typing: Option<usize>) -> bool {
    let tag = format!("<{name}");
    memchr::memmem::rfind_iter(text.as_bytes(), tag.as_bytes()).any(|at| {
        Some(at) != typing
            && text[at + tag.len()..]
                .chars()
                .next()
                .is_none_or(|c| !is_name_char(c))
    })
}

/// The elements that may go in `parent` (`None`: the root).
fn children_of(parent: Option<&str>) -> &'static [&'static str] {
    match parent {
        None => &["scene"],
        Some(p) => grammar::element(p).map_or(&[][..], |e| e.children),
    }
}

fn element_doc(name: &str) -> String {
    grammar::element(name).map_or_else(String::new, grammar::Element::documentation)
}

/// What may be typed at byte `offset` of `text` (read from the last of
/// its `marks` before it).
pub fn completions(text: &str, offset: usize, marks: &mut Marks) -> Vec<Completion> {
    let element = |name: &str, insert: String| Completion {
        label: name.to_owned(),
        insert,
        kind: CompletionKind::Element,
        doc: element_doc(name),
    };
    match spot(text, offset, marks) {
        Spot::Content { parent } => may_add(text, parent, offset)
            .map(|name| element(name, format!("<{name}")))
            .collect(),
        Spot::ElementName { parent, typed } => may_add(text, parent, offset)
            .filter(|name| name.starts_with(typed))
            .map(|name| element(name, (*name).to_owned()))
            .collect(),
        Spot::Markup => Vec::new(),
        Spot::AttributeName {
            element,
            present,
            typed,
        } => grammar::element(element)
            .map(|e| e.attributes)
            .unwrap_or_default()
            .iter()
            .filter(|a| !present.contains(a) && a.starts_with(typed))
            .filter_map(|a| grammar::attribute(element, a))
            .map(|a| Completion {
                label: a.name.to_owned(),
                insert: format!("{}=\"\"", a.name),
                kind: CompletionKind::Attribute,
                doc: a.documentation(),
            })
            .collect(),
        Spot::AttributeValue {
            element,
            attribute,
            typed,
        } => match grammar::attribute(element, attribute).map(|a| (a, a.value)) {
            Some((a, Value::Choice(values))) => values
                .iter()
                .filter(|v| v.starts_with(typed.trim_start()))
                .map(|v| Completion {
                    label: (*v).to_owned(),
                    insert: (*v).to_owned(),
                    kind: CompletionKind::Value,
                    doc: a.doc.to_owned(),
                })
                .collect(),
            _ => Vec::new(),
        },
    }
}

/// What the name at byte `offset` means (an element's or an attribute's),
/// and the bytes of that name (the text read as [`completions`] reads it).
pub fn hover(text: &str, offset: usize, marks: &mut Marks) -> Option<(String, Range<usize>)> {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    // The whole name around the offset.
    let start = text[..offset]
        .rfind(|c: char| !is_name_char(c))
        .map_or(0, |k| k + 1);
    let end = text[offset..]
        .find(|c: char| !is_name_char(c))
        .map_or(text.len(), |k| offset + k);
    let name = &text[start..end];
    if name.is_empty() {
        return None;
    }
    let before = text[..start].trim_end_matches([' ', '\t']);
    if before.ends_with('<') || before.ends_with("</") {
        return grammar::element(name).map(|_| (element_doc(name), start..end));
    }
    match spot(text, end, marks) {
        Spot::AttributeName { element, .. } | Spot::AttributeValue { element, .. } => {
            grammar::attribute(element, name).map(|a| (a.documentation(), start..end))
        }
        _ => None,
    }
}

/// One entry of a text's outline.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Symbol {
    /// As the app's panel names it: `#2 RED sphere`, `light 1`, `camera`;
    /// a group's: `1000000 objects`, `… 999500 more objects`.
    pub name: String,
    pub kind: SymbolKind,
    /// The element's bytes, and its start tag's (a group's: from its first
    /// element's start to its last one's end, and the first start tag).
    pub range: Range<usize>,
    pub selection: Range<usize>,
    /// A group's entries ([`symbols`]); none for an element.
    pub children: Vec<Symbol>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SymbolKind {
    Object,
    Light,
    Camera,
    Model,
}

/// The most objects, and the most lights, an outline lists one by one
/// ([`symbols`]): about what an editor's outline shows at once, and what
/// it can draw quickly. Past it they are found by name ([`find_symbols`]).
pub const SYMBOLS_LISTED: usize = 500;

/// The outline of `text`: its root's children in file order, named as the
/// app's panel names them; none when it is not well-formed XML.
///
/// Objects, or lights, over [`SYMBOLS_LISTED`] are one group in place of
/// the first (`1000000 objects`), holding the first [`SYMBOLS_LISTED`] and
/// one entry for the rest (`… 999500 more objects`, spanning them): an
/// outline of a million spheres is 600 entries, not 218 MB of JSON, and
/// names are made for those only.
pub fn symbols(text: &str) -> Vec<Symbol> {
    // The first SYMBOLS_LISTED + 1 of each kind, in file order, and each
    // kind's count and last end: all that is shown.
    let labels = names::object_labels(text);
    let mut named = Named::default();
    let mut kept: Vec<Symbol> = Vec::new();
    let mut last_end = [0usize; 4];
    let well_formed = layout::each_top_level(text, |name, range, selection| {
        let kind = kind_of(name);
        let k = kind as usize;
        last_end[k] = range.end;
        if named.count(kind) <= SYMBOLS_LISTED {
            kept.push(named.symbol(name, kind, &range, &selection, &labels));
        }
        named.skip(kind);
    });
    if !well_formed {
        return Vec::new();
    }
    let mut out: Vec<Symbol> = Vec::new();
    // Where each kind's group is in `out`, once begun.
    let mut groups = [None::<usize>; 4];
    let mut listed = [0usize; 4];
    for symbol in kept {
        let (kind, k) = (symbol.kind, symbol.kind as usize);
        let total = named.count(kind);
        if total <= SYMBOLS_LISTED {
            out.push(symbol);
            continue;
        }
        let group = *groups[k].get_or_insert_with(|| {
            out.push(Symbol {
                name: format!("{total} {}", plural(kind)),
                kind,
                range: symbol.range.start..last_end[k],
                selection: symbol.selection.clone(),
                children: Vec::with_capacity(SYMBOLS_LISTED + 1),
            });
            out.len() - 1
        });
        let entry = match listed[k] {
            n if n < SYMBOLS_LISTED => symbol,
            _ => Symbol {
                name: format!("… {} more {}", total - SYMBOLS_LISTED, plural(kind)),
                range: symbol.range.start..last_end[k],
                ..symbol
            },
        };
        listed[k] += 1;
        out[group].children.push(entry);
    }
    out
}

/// The symbols of `text` whose names hold `query` (letter case aside),
/// in file order, at most `limit`, and how many hold it in all: an
/// outline too long to list is searched by name (`workspace/symbol`).
pub fn find_symbols(text: &str, query: &str, limit: usize) -> (Vec<Symbol>, usize) {
    let query = query.to_lowercase();
    let labels = names::object_labels(text);
    let mut named = Named::default();
    let (mut found, mut total) = (Vec::new(), 0);
    let well_formed = layout::each_top_level(text, |name, range, selection| {
        let kind = kind_of(name);
        let symbol = named.symbol(name, kind, &range, &selection, &labels);
        named.skip(kind);
        if symbol.name.to_lowercase().contains(&query) {
            total += 1;
            if found.len() < limit {
                found.push(symbol);
            }
        }
    });
    match well_formed {
        true => (found, total),
        false => (Vec::new(), 0),
    }
}

/// The kind of a root's child named `name`.
fn kind_of(name: &str) -> SymbolKind {
    match name {
        _ if Shape::from_name(name).is_some() => SymbolKind::Object,
        "light" => SymbolKind::Light,
        "camera" => SymbolKind::Camera,
        _ => SymbolKind::Model,
    }
}

/// A kind's elements as a group names them.
fn plural(kind: SymbolKind) -> &'static str {
    match kind {
        SymbolKind::Object => "objects",
        SymbolKind::Light => "lights",
        SymbolKind::Camera => "cameras",
        SymbolKind::Model => "models",
    }
}

/// The elements of each kind named so far, in file order: the next
/// object's or light's number.
#[derive(Default)]
struct Named {
    counts: [usize; 4],
}

impl Named {
    /// The symbol of element `name` (of `kind`), the next of its kind.
    fn symbol(
        &self,
        name: &str,
        kind: SymbolKind,
        range: &Range<usize>,
        selection: &Range<usize>,
        labels: &names::Labels,
    ) -> Symbol {
        let n = self.count(kind);
        let name = match kind {
            SymbolKind::Object => names::object_name(n, name, labels.get(n)),
            SymbolKind::Light => format!("light {}", n + 1),
            _ => name.to_owned(),
        };
        Symbol {
            name,
            kind,
            range: range.clone(),
            selection: selection.clone(),
            children: Vec::new(),
        }
    }

    /// How many elements of `kind` were named.
    fn count(&self, kind: SymbolKind) -> usize {
        self.counts[kind as usize]
    }

    /// Counts one more element of `kind`.
    fn skip(&mut self, kind: SymbolKind) {
        self.counts[kind as usize] += 1;
    }
}

/// The objects' elements of `text` (spheres and planes, in file order, as
/// the loader numbers them), each with its start tag's bytes; none when it
/// is not well-formed XML.
fn objects(text: &str) -> impl Iterator<Item = (Range<usize>, Range<usize>)> + '_ {
    layout::top_level(text)
        .into_iter()
        .filter(|(name, ..)| Shape::from_name(name).is_some())
        .map(|(_, range, selection)| (range, selection))
}

/// The bytes of object `index`'s element (spheres and planes in file
/// order): what an editor shows when the app asks for that object.
pub fn object_element(text: &str, index: usize) -> Option<Range<usize>> {
    objects(text).nth(index).map(|(range, _)| range)
}

/// The object (its index among the spheres and planes, in file order)
/// whose element holds byte `offset`, with its start tag's bytes: what
/// the app outlines when the editor's cursor is there.
pub fn object_at(text: &str, offset: usize) -> Option<(usize, Range<usize>)> {
    objects(text)
        .enumerate()
        .find(|(_, (range, _))| range.contains(&offset))
        .map(|(index, (_, selection))| (index, selection))
}

/// An element the editor's cursor can be in that the app shows: an
/// object (outlined) or a light (its marker), by its index among its
/// kind in file order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Under {
    Object(usize),
    Light(usize),
}

/// The object's or light's element that holds byte `offset`, with its
/// start tag's bytes; none when the cursor is in neither (the camera, the
/// model, between elements) or the text is not well-formed.
pub fn element_at(text: &str, offset: usize) -> Option<(Under, Range<usize>)> {
    if let Some((object, tag)) = object_at(text, offset) {
        return Some((Under::Object(object), tag));
    }
    layout::top_level(text)
        .into_iter()
        .filter(|(name, ..)| *name == "light")
        .enumerate()
        .find(|(_, (_, range, _))| range.contains(&offset))
        .map(|(index, (_, _, tag))| (Under::Light(index), tag))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn places_count_utf16_units() {
        let text = "<!-- é😀 -->\r\n<scene>\r<x/>\n";
        let lines = Lines::new(text);
        let at = text.find("-->").unwrap();
        // é is one unit, 😀 two.
        assert_eq!(lines.place(text, at), Place { line: 0, column: 9 });
        assert_eq!(lines.offset(text, Place { line: 0, column: 9 }), at);
        let x = text.find("<x").unwrap();
        assert_eq!(lines.place(text, x), Place { line: 2, column: 0 });
        assert_eq!(
            lines.offset(
                text,
                Place {
                    line: 1,
                    column: 99
                }
            ),
            text.find('\r').unwrap() + 9
        );
        assert_eq!(lines.offset(text, Place { line: 9, column: 0 }), text.len());
    }

    #[test]
    fn lines_follow_edits_without_reading_the_text_again() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut rng = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let pieces = ["a", "\n", "\r", "\r\n", "é", "😀", "<x/>", ""];
        let mut text = "ab\ncd\r\nef\rgh\n".to_owned();
        let mut lines = Lines::new(&text);
        for _ in 0..2000 {
            let mut start = rng() as usize % (text.len() + 1);
            while !text.is_char_boundary(start) {
                start -= 1;
            }
            let mut end = (start + rng() as usize % 4).min(text.len());
            while !text.is_char_boundary(end) {
                end += 1;
            }
            let inserted: String = (0..rng() % 3)
                .map(|_| pieces[rng() as usize % pieces.len()])
                .collect();
            text.replace_range(start..end, &inserted);
            lines.edit(&text, start..end, inserted.len());
            assert_eq!(lines.starts, Lines::new(&text).starts, "{text:?}");
        }
    }

    #[test]
    fn an_error_is_at_its_name_after_non_ascii_text() {
        let text = "<scene><!-- é😀 --><sphere><material ka=\"-1\"/></sphere></scene>";
        let d = diagnostics(text);
        assert_eq!(d.len(), 1);
        assert_eq!(&text[d[0].range.clone()], "ka");
        assert!(d[0].message.contains("must be >= 0"), "{}", d[0].message);
        assert!(diagnostics(crate::EXAMPLE_SCENE).is_empty());
        let no_camera = diagnostics("<scene>\n</scene>");
        assert_eq!(no_camera[0].range, 0..6);
    }

    /// Completion offers only what the loader takes there: not a second
    /// camera or model, nor a second colour in a sphere, whether the one
    /// there is before the cursor or after it; and nothing in a comment.
    #[test]
    fn completion_leaves_out_what_may_be_there_once_and_is() {
        let at_bar = |text: &str| -> Vec<String> {
            let offset = text.find('|').unwrap();
            let text = text.replace('|', "");
            completions(&text, offset, &mut Marks::default())
                .into_iter()
                .map(|c| c.label)
                .collect()
        };
        let all = ["sphere", "plane", "light", "camera", "model"];
        assert_eq!(at_bar("<scene>\n  |\n</scene>"), all);
        let scene = "<scene>\n  <model type=\"phong\"/>\n  |\n  <sphere/>\n  \
                     <camera width=\"2\" height=\"2\" eyeDistance=\"1\"/>\n</scene>";
        assert_eq!(at_bar(scene), ["sphere", "plane", "light"]);
        assert_eq!(
            at_bar(&scene.replace('|', "<|")),
            ["sphere", "plane", "light"]
        );
        // The tag being typed is not one that is there.
        assert_eq!(
            at_bar("<scene>\n  <cam|\n  <sphere/>\n</scene>"),
            ["camera"]
        );
        assert_eq!(at_bar("<scene>\n  <camera|\n</scene>"), ["camera"]);
        // Not found in a longer name or by its element alone.
        assert_eq!(at_bar("<scene><cameras/>|</scene>"), all);
        // In a sphere: colour before the cursor, material after; the
        // transformation's steps are its own.
        let sphere = "<scene><sphere><color red=\"1\"/>\n|<material kd=\"1\"/>\
                      <transformation><scale factor=\"2\"/></transformation></sphere>\
                      <sphere><color/></sphere></scene>";
        assert_eq!(at_bar(sphere), Vec::<String>::new());
        assert_eq!(
            at_bar(&sphere.replace("<material kd=\"1\"/>", "")),
            ["material"]
        );
        assert_eq!(
            at_bar(&sphere.replace("\n|", "\n<|\n")),
            Vec::<String>::new()
        );
        assert_eq!(
            at_bar("<scene><sphere><transformation><scale/>|</transformation></sphere></scene>"),
            ["translate", "rotate-x", "rotate-y", "rotate-z", "scale"]
        );
        // In a comment, before the root or in it, nothing.
        assert_eq!(at_bar("<!-- a comment <|"), Vec::<String>::new());
        assert_eq!(
            at_bar("<scene>\n<!-- type < here |-->\n</scene>"),
            Vec::<String>::new()
        );
        assert_eq!(at_bar("<scene>\n<!-- done -->\n|</scene>"), all);
    }

    #[test]
    fn completion_knows_where_it_is() {
        let labels = |text: &str| -> Vec<String> {
            completions(text, text.len(), &mut Marks::default())
                .into_iter()
                .map(|c| c.label)
                .collect()
        };
        assert_eq!(labels(""), ["scene"]);
        assert_eq!(
            labels("<scene>\n  "),
            ["sphere", "plane", "light", "camera", "model"]
        );
        assert_eq!(labels("<scene>\n  <sp"), ["sphere"]);
        assert_eq!(
            labels("<scene><sphere><"),
            ["color", "material", "transformation"]
        );
        assert_eq!(
            labels("<scene><sphere/><"),
            ["sphere", "plane", "light", "camera", "model"]
        );
        assert_eq!(
            labels("<scene><!-- <x> --><sphere></sphere><light "),
            ["x", "y", "z"]
        );
        assert_eq!(labels("<scene><light x=\"1\" "), ["y", "z"]);
        assert_eq!(labels("<scene><material ka=\"0.2\" k"), ["kd", "ks"]);
        assert_eq!(
            labels("<scene><model type=\""),
            ["ambient", "lambert", "phong", "whitted"]
        );
        assert_eq!(labels("<scene><model type=\"ph"), ["phong"]);
        assert_eq!(labels("<scene><light x=\""), Vec::<String>::new());
        let c = completions("<scene><material ", 17, &mut Marks::default());
        assert_eq!(c[0].insert, "ka=\"\"");
        assert!(c[0].doc.contains("Default: 0.2."), "{}", c[0].doc);
    }

    /// A reading from a mark finds what a reading from the start finds, at
    /// every offset of texts of every kind of markup, marks close or far
    /// apart, and after an edit that changes what the text after it means.
    #[test]
    fn a_reading_from_the_marks_finds_what_one_from_the_start_finds() {
        let texts = [
            crate::EXAMPLE_SCENE,
            "<?xml version=\"1.0\"?>\n<!DOCTYPE scene>\n<scene><!-- <sphere> é😀 -->\
             <sphere><material ka=\"0.2\" kd='>'/><color red=\"1\"></color></sphere>\
             </x><light x=\"1\" y='2'/><plane></plane><![CDATA[ <a> ]]>\n</scene>\n",
            "<scene>\r\n\t<sphere >< material/></sphere\n><camera width=\"2\" ",
        ];
        fn fresh(text: &str, offset: usize) -> Spot<'_> {
            spot(text, offset, &mut Marks::every(usize::MAX))
        }
        for text in texts {
            for every in [1, 3, 17] {
                let mut marks = Marks::every(every);
                spot(text, text.len(), &mut marks);
                assert!(marks.marks.len() >= 2, "{every}: {:?}", marks.marks);
                for offset in 0..=text.len() {
                    let mut m = marks.clone();
                    assert_eq!(spot(text, offset, &mut m), fresh(text, offset), "{offset}");
                }
                let mut at = text.len() / 2;
                while !text.is_char_boundary(at) {
                    at += 1;
                }
                // Insertions that change what the text after them means,
                // and replacements of more, as many or fewer bytes.
                let mut edits: Vec<(Range<usize>, &str)> =
                    ["<!--", "\"", "</sphere>", "<camera ", "-->", "<x>"]
                        .into_iter()
                        .map(|edit| (at..at, edit))
                        .collect();
                for (len, by) in [(1, "<a b='"), (4, "é!"), (9, "<!-- x --"), (12, "")] {
                    let mut end = (at + len).min(text.len());
                    while !text.is_char_boundary(end) {
                        end += 1;
                    }
                    edits.push((at..end, by));
                }
                for (replaced, by) in edits {
                    let mut edited = text.to_owned();
                    edited.replace_range(replaced.clone(), by);
                    let mut m = marks.clone();
                    m.edited(replaced.clone(), by.len());
                    assert!(m.before(edited.len()).0 <= at);
                    // Read from the unsure marks, and from the marks a reading
                    // to the end leaves.
                    let mut after = m.clone();
                    spot(&edited, edited.len(), &mut after);
                    for offset in 0..=edited.len() {
                        let want = fresh(&edited, offset);
                        let why = format!("{by:?} for {replaced:?}, {offset}");
                        assert_eq!(spot(&edited, offset, &mut m.clone()), want, "{why}");
                        assert_eq!(spot(&edited, offset, &mut after.clone()), want, "{why}");
                    }
                }
            }
        }
    }

    /// After an edit in the middle of a large text, a reading at its end
    /// goes on from the marks after the edit as soon as it finds them true
    /// again, and reads no more than it did before the edit.
    #[test]
    fn a_reading_after_an_edit_goes_on_from_the_marks_it_finds_again() {
        let sphere = "<sphere>\n  <material ka=\"0.2\" kd=\"0.5\"/>\n</sphere>\n";
        let text = format!("<scene>\n{}</scene>\n", sphere.repeat(2000));
        let mut marks = Marks::every(1024);
        spot(&text, text.len(), &mut marks);
        let places = marks.passed;
        let count = marks.marks.len();
        assert!(
            places > 4000 && count > 50,
            "{places} places, {count} marks"
        );
        // An edit of a value, one that adds a whole object, one that takes
        // two away; then another edit before the first, before any reading.
        let middle = text.len() / 2;
        let at = middle + text[middle..].find("0.5").unwrap();
        let object = middle + text[middle..].find("<sphere>").unwrap();
        for (replaced, by) in [
            (at..at + 3, "0.75"),
            (object..object, sphere),
            (object..object + 2 * sphere.len(), ""),
        ] {
            let mut edited = text.clone();
            edited.replace_range(replaced.clone(), by);
            let mut m = marks.clone();
            m.edited(replaced.clone(), by.len());
            let between = "<scene>\n".len() + sphere.len() - 1;
            edited.replace_range(between..between + 1, "<!-- - -->\n");
            m.edited(between..between + 1, 11);
            m.passed = 0;
            let want = spot(&edited, edited.len(), &mut Marks::every(usize::MAX));
            assert_eq!(spot(&edited, edited.len(), &mut m), want);
            // From the mark before the first edit to one past the second.
            assert!(m.passed < 100, "{by:?}: {} places read again", m.passed);
            assert!(m.marks.len() + 2 >= count, "{} marks", m.marks.len());
            m.passed = 0;
            spot(&edited, edited.len(), &mut m);
            assert!(m.passed < 40, "{by:?}: {} places", m.passed);
        }
    }

    #[test]
    fn hover_says_what_a_name_means() {
        let text = "<scene><sphere><material ka=\"0.5\"/></sphere><model type=\"phong\"/></scene>";
        let hover = |offset| hover(text, offset, &mut Marks::default());
        let (doc, range) = hover(text.find("ka").unwrap() + 1).unwrap();
        assert_eq!(&text[range], "ka");
        assert!(
            doc.contains("Ambient") && doc.contains("Default: 0.2."),
            "{doc}"
        );
        let (doc, _) = hover(text.find("model").unwrap()).unwrap();
        assert!(doc.contains("illumination model"), "{doc}");
        assert!(hover(text.find("0.5").unwrap()).is_none());
    }

    #[test]
    fn symbols_are_named_as_the_panel_names_them() {
        let text = "<scene>\n<!-- RED ball -->\n<sphere/>\n<plane/>\n<light x=\"0\" y=\"0\" z=\"0\"/>\n<camera width=\"2\" height=\"2\" eyeDistance=\"1\"/>\n</scene>";
        let s = symbols(text);
        let names: Vec<&str> = s.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(
            names,
            ["#1 RED ball sphere", "#2 plane", "light 1", "camera"]
        );
        assert_eq!(&text[s[0].range.clone()], "<sphere/>");
        assert!(s.iter().all(|s| s.children.is_empty()));
    }

    #[test]
    fn an_outline_too_long_to_list_is_grouped_and_searched_by_name() {
        let n = SYMBOLS_LISTED + 7;
        let mut text = String::from("<scene>\n<light x=\"0\" y=\"0\" z=\"0\"/>\n");
        for _ in 0..n {
            text.push_str("<sphere/>\n");
        }
        text.push_str("<camera width=\"2\" height=\"2\" eyeDistance=\"1\"/>\n</scene>");
        let s = symbols(&text);
        let names: Vec<&str> = s.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["light 1", &format!("{n} objects"), "camera"]);
        let group = &s[1];
        assert_eq!(group.children.len(), SYMBOLS_LISTED + 1);
        assert_eq!(group.children[0].name, "#1 sphere");
        assert_eq!(
            group.children[SYMBOLS_LISTED - 1].name,
            format!("#{SYMBOLS_LISTED} sphere")
        );
        let more = &group.children[SYMBOLS_LISTED];
        assert_eq!(more.name, "… 7 more objects");
        // The group spans its objects, the last entry those not listed.
        let first = text.find("<sphere/>").unwrap();
        let last = text.rfind("<sphere/>").unwrap() + "<sphere/>".len();
        assert_eq!(group.range, first..last);
        assert_eq!(more.range, first + SYMBOLS_LISTED * 10..last);
        // Any of them is found by name.
        let (found, total) = find_symbols(&text, "#50", 3);
        assert_eq!(total, 9, "#50 and #500 to #507");
        let names: Vec<&str> = found.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["#50 sphere", "#500 sphere", "#501 sphere"]);
        assert_eq!(&text[found[2].range.clone()], "<sphere/>");
        assert_eq!(find_symbols(&text, "LIGHT", 10).1, 1);
    }

    #[test]
    fn objects_are_found_by_number_and_by_place() {
        let text = "<scene>\n<light x=\"0\" y=\"0\" z=\"0\"/>\n<sphere>\n<color red=\"1\" green=\"0\" blue=\"0\"/>\n</sphere>\n<plane/>\n</scene>";
        let sphere = object_element(text, 0).unwrap();
        assert!(
            text[sphere.clone()].starts_with("<sphere>")
                && text[sphere.clone()].ends_with("</sphere>")
        );
        assert_eq!(&text[object_element(text, 1).unwrap()], "<plane/>");
        assert_eq!(object_element(text, 2), None);
        let inside = text.find("green").unwrap();
        assert_eq!(
            object_at(text, inside),
            Some((0, sphere.start..sphere.start + 8))
        );
        assert_eq!(
            object_at(text, text.find("<plane").unwrap()).map(|o| o.0),
            Some(1)
        );
        // In a light, or a text that is not XML: no object.
        assert_eq!(object_at(text, text.find("<light").unwrap() + 2), None);
        let light = text.find("<light").unwrap();
        assert_eq!(
            element_at(text, light + 2).map(|(u, tag)| (u, &text[tag])),
            Some((Under::Light(0), "<light x=\"0\" y=\"0\" z=\"0\"/>"))
        );
        assert_eq!(
            element_at(text, inside).map(|(u, _)| u),
            Some(Under::Object(0))
        );
        assert_eq!(element_at(text, 2), None, "in the scene, no element");
        assert_eq!(object_at("<scene><sphere>", 9), None);
    }
}
