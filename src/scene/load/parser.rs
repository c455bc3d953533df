//! The scene parser: quick-xml reads the text as a stream of events; a
//! small recursive descent (at most four levels: scene, object,
//! transformation, step) checks each element against the grammar
//! ([`crate::scene::grammar`]). Positions come from the events' slices,
//! which borrow the text: a slice's address minus the text's address is
//! its byte offset, turned into line and column only when an error is
//! reported.
//!
//! quick-xml is lenient: what it does not check of XML 1.0's
//! well-formedness, [`crate::scene::xml`] checks in each piece of markup it
//! delimits (characters, names, whitespace between attributes, comments,
//! processing instructions, the XML declaration and its encoding); at most
//! one byte-order mark, no CDATA section outside the root. A DOCTYPE is
//! refused on purpose (scene files declare no entities). A file libxml2
//! finds not well-formed is refused, with its line and column.
//!
//! A [`Parser`] parses a whole text ([`Parser::gathered`]) or one piece of
//! it ([`Parser::piece`], for [`super::pieces`]); the format's numbers are
//! read here too, by the rules the edit engine reads typed values with.

use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;

use quick_xml::Reader;
use quick_xml::escape::EscapeError;
use quick_xml::events::attributes::AttrError;
use quick_xml::events::{BytesStart, Event};
use smallvec::SmallVec;

use super::{LoadProgress, MAX_LIGHTS, MAX_OBJECTS, MAX_PIXELS};
use crate::math::{Steps, Transform, TransformError, TransformStep, Vec3};
use crate::scene::error::{LoadError, LoadErrorKind, Position};
use crate::scene::grammar::{
    CAMERA_ATTRS, CAMERA_CHILDREN, COLOR_ATTRS, LIGHT_ATTRS, LIGHT_CHILDREN, MATERIAL_ATTRS,
    MODEL_ATTRS, NONE, OBJECT_CHILDREN, ROTATE_ATTRS, SCALE_ATTRS, SCENE_ATTRS, SCENE_CHILDREN,
    TRANSFORM_CHILDREN, TRANSLATE_ATTRS, XSI_NAMESPACE,
};
use crate::scene::xml;
use crate::scene::{
    Camera, Color, Illumination, Light, Material, Model, Object, Objects, Scene, Shape,
};

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
    /// Between two of the root's children at [`Parser::stop`].
    Stop,
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

/// What ends a run of the root's children ([`Parser::root_children`]).
enum Ended {
    /// An end tag (the root's, where the reading is right), at its `<`.
    Close(usize),
    /// The end of the text.
    Eof,
    /// [`Parser::stop`].
    Stop,
}

/// Everything a `<scene>` gathers before it is checked for completeness.
#[derive(Default)]
pub(super) struct Gathered {
    pub(super) objects: Vec<Arc<Object>>,
    pub(super) lights: Vec<Light>,
    pub(super) camera: Option<Camera>,
    pub(super) model: Option<Model>,
    /// Objects and lights read but not kept ([`Parser::check_only`]).
    pub(super) unkept_objects: usize,
    pub(super) unkept_lights: usize,
    /// Where each child of the root starts in the text, and what it is,
    /// where [`Parser::record`] asks.
    pub(super) places: Vec<(usize, Child)>,
    /// Where the root's content starts (after its start tag) and ends (at
    /// its end tag's `<`), once read.
    pub(super) content_start: Option<usize>,
    pub(super) content_end: Option<usize>,
}

impl Gathered {
    /// The objects read, kept or not.
    pub(super) fn object_count(&self) -> usize {
        self.objects.len() + self.unkept_objects
    }

    /// The lights read, kept or not.
    pub(super) fn light_count(&self) -> usize {
        self.lights.len() + self.unkept_lights
    }
}

/// What a child of the root is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Child {
    Object,
    Light,
    Camera,
    Model,
}

impl Gathered {
    /// The scene, once it is known to have a camera.
    pub(super) fn finish(mut self, path: &Path) -> Result<Scene, LoadError> {
        let objects = std::mem::take(&mut self.objects).into();
        self.finish_with(objects, path)
    }

    /// [`Gathered::finish`] with `objects` for the objects.
    pub(super) fn finish_with(self, objects: Objects, path: &Path) -> Result<Scene, LoadError> {
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

/// [`Position::at_offset`] of byte `offset` of `text`, found with the
/// line starts of the text `bom` bytes longer before it (its byte-order
/// mark): the same line and column, in a search.
fn position_by_lines(text: &str, starts: &[usize], bom: usize, offset: usize) -> Position {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let at = offset + bom;
    let line = starts.partition_point(|&s| s <= at).max(1);
    let start = starts
        .get(line - 1)
        .map_or(0, |&s| s.saturating_sub(bom))
        .min(offset);
    // As `at_offset` counts: from the last line break (the CR of a CRLF
    // included) before the offset.
    let tail = text.get(start..offset).unwrap_or_default();
    let from = tail.rfind(['\n', '\r']).map_or(0, |i| i + 1);
    let column = 1 + tail[from..].chars().count();
    Position { line, column }
}

pub(super) struct Parser<'a> {
    /// What is parsed: the file's text, or a piece of it
    /// ([`in_pieces`](super::pieces::in_pieces)).
    text: &'a str,
    /// The whole text (after its byte-order mark), for what is checked of
    /// the file as a whole; `None` where it is not at hand
    /// ([`streamed`](super::pieces::streamed)), and such a check fails (the
    /// text is then read whole).
    pub(super) whole: Option<&'a str>,
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
    /// Objects to share where equal ([`parse_sharing`](super::parse_sharing)).
    pub(super) like: &'a [Arc<Object>],
    /// Where to say how far the parse has got
    /// ([`load_counting`](super::load_counting)).
    pub(super) progress: Option<&'a LoadProgress>,
    /// Events read, to update `progress` every so many.
    events: u32,
    /// How far into `text` `progress` has been told.
    reported: usize,
    /// Bytes of `text` the reader was moved past unread
    /// ([`Parser::document_from`]): added to the offsets it counts.
    skipped: usize,
    /// Where `text` starts in the whole text (a piece's cut), for
    /// [`Gathered::places`].
    pub(super) base: usize,
    /// Objects and lights are read and checked, not kept: a check of a
    /// text's errors holds no scene.
    pub(super) check_only: bool,
    /// The children's places are kept ([`Gathered::places`]).
    pub(super) record: bool,
    /// Between two of the root's children at this byte of `text`, the
    /// parse stops ([`Node::Stop`]).
    pub(super) stop: Option<usize>,
    /// Where the lines of `text` start, `bom` bytes before it (the text
    /// as an editor holds it, its byte-order mark included), where the
    /// caller has them: an error's line is found by a search, not by
    /// counting the lines before it.
    pub(super) lines: Option<(&'a [usize], usize)>,
}

impl<'a> Parser<'a> {
    pub(super) fn new(text: &'a str, path: &'a Path) -> Parser<'a> {
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
            skipped: 0,
            base: 0,
            check_only: false,
            record: false,
            stop: None,
            lines: None,
        }
    }

    // ----- positions and errors -----

    /// The byte offset of `slice` in the text, if it is a part of it.
    fn offset_of(&self, slice: &[u8]) -> Option<usize> {
        let offset = (slice.as_ptr() as usize).checked_sub(self.text.as_ptr() as usize)?;
        (offset <= self.text.len()).then_some(offset)
    }

    fn error_at(&self, offset: usize, kind: LoadErrorKind) -> LoadError {
        let position = match self.lines {
            Some((starts, bom)) => position_by_lines(self.text, starts, bom, offset),
            None => Position::at_offset(self.text, offset),
        };
        LoadError::new(self.path, Some(position), kind)
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
        usize::try_from(self.reader.buffer_position())
            .unwrap_or(usize::MAX)
            .saturating_add(self.skipped)
    }

    // ----- events -----

    /// The next start tag, end tag or end of file; comments, processing
    /// instructions, the XML declaration and whitespace are skipped, anything
    /// else is an error.
    fn next(&mut self) -> Result<Node<'a>, LoadError> {
        loop {
            let before = self.reader_offset();
            if self.depth == 1 && self.stop == Some(before) {
                return Ok(Node::Stop);
            }
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
                    let at = usize::try_from(self.reader.error_position())
                        .unwrap_or(usize::MAX)
                        .saturating_add(self.skipped);
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
                Node::Eof | Node::Stop => return Err(self.unclosed(parent)),
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

    /// The text's scene, parsed in one (the tests' yardstick).
    #[cfg(test)]
    pub(super) fn document(self) -> Result<Scene, LoadError> {
        let path = self.path;
        self.gathered()?.finish(path)
    }

    /// What a parse of the whole text gathers, before it makes the scene (a
    /// camera checked for).
    pub(super) fn gathered(mut self) -> Result<Gathered, LoadError> {
        let root = self.root()?;
        let scene = Gathered {
            content_start: Some(self.reader_offset()),
            ..Gathered::default()
        };
        let path = self.path;
        let (scene, _) = self.rest_of_document(&root, scene)?;
        match scene.camera {
            Some(_) => Ok(scene),
            None => Err(LoadError::new(path, None, LoadErrorKind::MissingCamera)),
        }
    }

    /// [`Parser::gathered`], the root's children before byte `at` of the
    /// text not read: `before` is what a parse in one has gathered when it
    /// gets there, and `at` must be a place between two of the root's
    /// children, as a cut that the pieces before it confirmed
    /// ([`in_pieces`](super::pieces::in_pieces)) or the place of a child
    /// in a text read before ([`super::reading`]). The rest is read as a
    /// parse in one reads it (the reader holds the root open, as there),
    /// so what it returns, an error included, is what a parse in one
    /// returns; with true, it stopped at [`Parser::stop`] instead, the
    /// rest not read. `None` where `at` is not after the root's start tag.
    pub(super) fn document_from(
        mut self,
        at: usize,
        before: Gathered,
    ) -> Option<Result<(Gathered, bool), LoadError>> {
        let root = match self.root() {
            Ok(root) => root,
            Err(e) => return Some(Err(e)),
        };
        let here = self.reader_offset();
        if root.empty || at < here {
            return None;
        }
        let text: &'a str = self.text;
        *self.reader.get_mut() = text.as_bytes().get(at..)?;
        self.skipped = at - here;
        Some(self.rest_of_document(&root, before))
    }

    /// The root's children after those in `scene`, its end and what
    /// follows it; true where it stopped at [`Parser::stop`] first.
    fn rest_of_document(
        mut self,
        root: &Elem<'a>,
        mut scene: Gathered,
    ) -> Result<(Gathered, bool), LoadError> {
        if !root.empty {
            match self.root_children(&mut scene)? {
                Ended::Close(at) => scene.content_end = Some(at),
                Ended::Eof => return Err(self.unclosed("scene")),
                Ended::Stop => return Ok((scene, true)),
            }
        }
        self.epilogue()?;
        Ok((scene, false))
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
            Node::Eof | Node::Stop => {
                return Err(self.error_at(self.text.len(), LoadErrorKind::MissingRoot));
            }
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
            Node::Eof | Node::Stop => Ok(()),
        }
    }

    /// One piece of the scene's children
    /// ([`in_pieces`](super::pieces::in_pieces)): its whole text, from the
    /// root's start tag for the first piece, from inside the root for the
    /// others. An end tag of the root, or anything left open at
    /// the piece's end, is an error (and the text is parsed in one piece).
    pub(super) fn piece(mut self, first: bool) -> Result<Gathered, LoadError> {
        let mut scene = Gathered::default();
        if first {
            let root = self.root()?;
            if root.empty {
                return Err(self.xml_at(root.at, "an empty root in a piece".to_owned()));
            }
            scene.content_start = Some(self.base + self.reader_offset());
        } else {
            self.at_start = false;
            self.depth = 1;
        }
        match self.root_children(&mut scene)? {
            Ended::Close(at) => Err(self.xml_at(at, "the root ends inside a piece".to_owned())),
            Ended::Eof | Ended::Stop => Ok(scene),
        }
    }

    /// The root's children from here on, each gathered into `scene`, up
    /// to what ends them.
    fn root_children(&mut self, scene: &mut Gathered) -> Result<Ended, LoadError> {
        loop {
            match self.next()? {
                Node::Open(child) => {
                    let (_, name) = self.known_child(&child, "scene", SCENE_CHILDREN)?;
                    self.scene_child(&child, name, scene)?;
                }
                Node::Close(at) => return Ok(Ended::Close(at)),
                Node::Eof => return Ok(Ended::Eof),
                Node::Stop => return Ok(Ended::Stop),
            }
        }
    }

    fn scene_child(
        &mut self,
        e: &Elem<'a>,
        name: &'static str,
        scene: &mut Gathered,
    ) -> Result<(), LoadError> {
        if self.record {
            let child = match name {
                _ if Shape::from_name(name).is_some() => Child::Object,
                "light" => Child::Light,
                "camera" => Child::Camera,
                _ => Child::Model,
            };
            scene.places.push((self.base + e.at, child));
        }
        if let Some(shape) = Shape::from_name(name) {
            if scene.object_count() >= self.max_objects {
                return Err(self.error_at(
                    e.at,
                    LoadErrorKind::TooManyObjects {
                        limit: self.max_objects,
                    },
                ));
            }
            let object = self.object(e, shape)?;
            if self.check_only {
                scene.unkept_objects += 1;
                return Ok(());
            }
            let object = match self.like.get(scene.objects.len()) {
                Some(same) if **same == object => Arc::clone(same),
                _ => Arc::new(object),
            };
            scene.objects.push(object);
            return Ok(());
        }
        match name {
            "light" => {
                if scene.light_count() >= self.max_lights {
                    return Err(self.error_at(
                        e.at,
                        LoadErrorKind::TooManyLights {
                            limit: self.max_lights,
                        },
                    ));
                }
                let light = self.light(e)?;
                match self.check_only {
                    true => scene.unkept_lights += 1,
                    false => scene.lights.push(light),
                }
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
}
