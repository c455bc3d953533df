//! Errors of the scene loader: what went wrong ([`LoadErrorKind`]), in which
//! file, and where ([`Position`], 1-based line and column counted in
//! characters).
//!
//! A [`LoadError`] displays on one line as `path:line:column: message`, or
//! `path: message` when the problem has no place in the text (the file cannot
//! be read, the scene has no camera). Values quoted from the file are shown
//! with control characters escaped and long values shortened, so a message
//! never spans several lines.

use std::fmt;
use std::path::{Path, PathBuf};

/// A place in the scene text: 1-based line and column, the column counted in
/// characters (a tab is one character, so is `é`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Position {
    pub line: usize,
    pub column: usize,
}

impl Position {
    /// The line and column of the byte `offset` in `text`. An offset past the
    /// end is the end of the text; one inside a multi-byte character is that
    /// character's position.
    ///
    /// Lines end as XML's end-of-line handling says (XML 1.0, 2.11): at LF,
    /// at CR LF (one break) and at a lone CR. Every `line:column` of the
    /// project is computed here.
    pub fn at_offset(text: &str, offset: usize) -> Position {
        let mut offset = offset.min(text.len());
        while !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let before = text.get(..offset).unwrap_or(text);
        let bytes = before.as_bytes();
        // A CR followed by LF is counted at its LF; without a CR, the LFs
        // are counted as fast as memchr finds them (an error in the middle
        // of 200 MB is placed in milliseconds).
        let line = 1 + match memchr::memchr(b'\r', bytes) {
            None => memchr::memchr_iter(b'\n', bytes).count(),
            Some(_) => bytes
                .iter()
                .enumerate()
                .filter(|&(i, &b)| b == b'\n' || (b == b'\r' && bytes.get(i + 1) != Some(&b'\n')))
                .count(),
        };
        let line_start = before.rfind(['\n', '\r']).map_or(0, |i| i + 1);
        let column = 1 + before.get(line_start..).map_or(0, |s| s.chars().count());
        Position { line, column }
    }
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

/// Why a scene file could not be loaded.
///
/// Element names are shown as `<element>`; values quoted from the file are
/// escaped and shortened for display.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LoadErrorKind {
    /// The file could not be read.
    #[error("cannot read the scene file: {message}")]
    Io {
        kind: std::io::ErrorKind,
        message: String,
    },
    /// The path names a directory.
    #[error("is a directory, not a scene file")]
    IsDirectory,
    /// The load was stopped ([`LoadProgress::stop`](super::LoadProgress::stop))
    /// before it ended.
    #[error("the load was stopped")]
    Stopped,
    /// The path names a FIFO, a device or a socket.
    #[error("is {kind}, not a scene file")]
    NotAFile { kind: &'static str },
    /// The file is larger than [`MAX_FILE_BYTES`](super::MAX_FILE_BYTES).
    #[error("the file is {size} bytes, more than the limit of {limit} bytes")]
    FileTooLarge { size: u64, limit: u64 },
    /// The file looks like UTF-16 text.
    #[error(
        "the file looks like {encoding} text{}: scenes are UTF-8 \
         (iconv -f {encoding} -t UTF-8 converts it)",
        if *mark { "" } else { " without a byte order mark" }
    )]
    Utf16 { encoding: &'static str, mark: bool },
    /// The file is not UTF-8 text.
    #[error("the file is not UTF-8 text (invalid byte at offset {offset})")]
    NotUtf8 { offset: usize },
    /// The text is not well-formed XML; `message` says what the parser found.
    #[error("malformed XML: {}", one_line(message))]
    Xml { message: String },
    /// An attribute value holds an entity or character reference that is not
    /// allowed (anything but the five predefined entities and character
    /// references) or is malformed.
    #[error("<{element}> attribute {attribute}: {}", one_line(message))]
    BadReference {
        element: &'static str,
        attribute: &'static str,
        message: String,
    },
    /// A `<!DOCTYPE>`: scene files declare no entities.
    #[error("a DOCTYPE is not allowed in a scene file")]
    Doctype,
    /// Character data where only elements, comments and whitespace may be.
    #[error(
        "unexpected text \"{}\": only elements, comments and whitespace are allowed here",
        shown(text)
    )]
    UnexpectedText { text: String },
    /// The file holds no element at all.
    #[error("the file has no <scene> element")]
    MissingRoot,
    /// The root element is not `<scene>`.
    #[error("the root element is <{}>, expected <scene>", shown(element))]
    RootNotScene { element: String },
    /// Something other than whitespace or comments after `</scene>`.
    #[error("{} after the end of the <scene> element", shown(what))]
    ContentAfterRoot { what: String },
    /// An element that is not allowed where it is.
    #[error(
        "unknown element <{}> in <{parent}> ({})",
        shown(element),
        allowed_children(parent, allowed)
    )]
    UnknownElement {
        element: String,
        parent: &'static str,
        allowed: &'static [&'static str],
    },
    /// An attribute the element does not have (a typo is never ignored).
    #[error(
        "unknown attribute {} on <{element}> ({})",
        shown(attribute),
        allowed_attributes(element, allowed)
    )]
    UnknownAttribute {
        element: &'static str,
        attribute: String,
        allowed: &'static [&'static str],
    },
    /// `<scene>`'s schema attributes, not as XML Schema defines them: an
    /// `xsi:` attribute without `xmlns:xsi`, or `xmlns:xsi` naming another
    /// namespace (`value`).
    #[error(
        "<scene> names its schema with xmlns:xsi=\"{}\"{}",
        super::grammar::XSI_NAMESPACE,
        match value {
            Some(value) => format!(", not \"{}\"", shown(value)),
            None => " first: xsi:noNamespaceSchemaLocation needs it".to_owned(),
        }
    )]
    SchemaNamespace { value: Option<Box<str>> },
    /// A required attribute is absent.
    #[error("<{element}> is missing the required attribute {attribute}")]
    MissingAttribute {
        element: &'static str,
        attribute: &'static str,
    },
    /// The same attribute twice on one element.
    #[error("<{element}> attribute {attribute} is repeated")]
    DuplicateAttribute {
        element: &'static str,
        attribute: &'static str,
    },
    /// A second `<color>`, `<material>` or `<transformation>` in one element.
    #[error("second <{element}> in <{parent}>: at most one is allowed")]
    DuplicateElement {
        element: &'static str,
        parent: &'static str,
    },
    /// A value that is not a number.
    #[error(
        "<{element}> attribute {attribute}=\"{}\" is not a number",
        shown(value)
    )]
    InvalidNumber {
        element: &'static str,
        attribute: &'static str,
        value: Box<str>,
    },
    /// A number that is infinite or NaN (or overflows to infinity).
    #[error(
        "<{element}> attribute {attribute}=\"{}\" is not a finite number",
        shown(value)
    )]
    NotFinite {
        element: &'static str,
        attribute: &'static str,
        value: Box<str>,
    },
    /// An integer attribute that is not an integer or is out of its range.
    #[error(
        "<{element}> attribute {attribute}=\"{}\": expected an integer from {min} to {max}",
        shown(value)
    )]
    InvalidInteger {
        element: &'static str,
        attribute: &'static str,
        value: Box<str>,
        min: u64,
        max: u64,
    },
    /// A number outside its allowed range; `rule` is the condition, e.g. `>= 0`.
    #[error(
        "<{element}> attribute {attribute}=\"{}\" must be {rule}",
        shown(value)
    )]
    OutOfRange {
        element: &'static str,
        attribute: &'static str,
        value: Box<str>,
        rule: &'static str,
    },
    /// `<model type>` names no illumination model.
    #[error(
        "<model> attribute type=\"{}\" is not a known model: expected ambient, lambert, phong or whitted",
        shown(value)
    )]
    UnknownModel { value: Box<str> },
    /// The scene has no `<camera>`.
    #[error("the scene has no <camera>: exactly one is required")]
    MissingCamera,
    /// A second `<camera>`.
    #[error("second <camera>: a scene has exactly one camera")]
    SecondCamera,
    /// A second `<model>`.
    #[error("second <model>: a scene has at most one model")]
    SecondModel,
    /// `<scale>` with both `factor` and one of `x`, `y`, `z`.
    #[error("<scale> attribute {attribute}: factor cannot be combined with x, y or z")]
    ScaleFactorWithAxes { attribute: &'static str },
    /// A zero scale in a `<transformation>`: its matrix has no inverse.
    #[error("singular <transformation>: a zero scale has no inverse")]
    SingularTransform,
    /// Composing the `<transformation>` up to this `<step>` made its matrix
    /// or its inverse non-finite (numbers too large, or a scale too small).
    #[error(
        "the composed <transformation> overflows at this <{step}>: its matrix or its inverse is no longer finite"
    )]
    TransformOverflow { step: &'static str },
    /// `width * height` is above [`MAX_PIXELS`](super::MAX_PIXELS).
    #[error(
        "<camera> image of {width} x {height} pixels is too large: more than the limit of {limit} pixels"
    )]
    ImageTooLarge { width: u64, height: u64, limit: u64 },
    /// More objects than [`MAX_OBJECTS`](super::MAX_OBJECTS).
    #[error("too many objects: more than the limit of {limit}")]
    TooManyObjects { limit: usize },
    /// More lights than [`MAX_LIGHTS`](super::MAX_LIGHTS).
    #[error("too many lights: more than the limit of {limit}")]
    TooManyLights { limit: usize },
}

/// A scene that could not be loaded: the file, where in it (when the problem
/// has a place) and what.
///
/// Displays as `path:line:column: message` or `path: message`, on one line.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadError {
    pub path: PathBuf,
    pub position: Option<Position>,
    pub kind: LoadErrorKind,
}

impl LoadError {
    pub fn new(path: &Path, position: Option<Position>, kind: LoadErrorKind) -> LoadError {
        LoadError {
            path: path.to_owned(),
            position,
            kind,
        }
    }

    /// Where in the file the problem is, if it has a place.
    pub fn position(&self) -> Option<Position> {
        self.position
    }

    pub fn kind(&self) -> &LoadErrorKind {
        &self.kind
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.position {
            Some(p) => write!(f, "{}:{}: {}", self.path.display(), p, self.kind),
            None => write!(f, "{}: {}", self.path.display(), self.kind),
        }
    }
}

impl std::error::Error for LoadError {}

/// Longest quoted value shown in a message, in characters.
const SHOWN_CHARS: usize = 40;

/// `s` made safe for a one-line message: control characters escaped, and cut
/// after [`SHOWN_CHARS`] characters with an ellipsis.
fn shown(s: &str) -> String {
    match s.char_indices().nth(SHOWN_CHARS) {
        Some((cut, _)) => format!("{}…", one_line(s.get(..cut).unwrap_or(s))),
        None => one_line(s),
    }
}

/// `s` with control characters escaped, so that it stays on one line.
fn one_line(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

fn allowed_children(parent: &str, allowed: &[&str]) -> String {
    if allowed.is_empty() {
        format!("<{parent}> has no child elements")
    } else {
        let list: Vec<String> = allowed.iter().map(|a| format!("<{a}>")).collect();
        format!("allowed: {}", list.join(", "))
    }
}

fn allowed_attributes(element: &str, allowed: &[&str]) -> String {
    if allowed.is_empty() {
        format!("<{element}> has no attributes")
    } else {
        format!("allowed: {}", allowed.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_count_characters() {
        let text = "ab\n\té<x";
        assert_eq!(
            Position::at_offset(text, 0),
            Position { line: 1, column: 1 }
        );
        assert_eq!(
            Position::at_offset(text, 3),
            Position { line: 2, column: 1 }
        );
        // '\t' and 'é' (two bytes) are one column each.
        let lt = text.find('<').unwrap();
        assert_eq!(
            Position::at_offset(text, lt),
            Position { line: 2, column: 3 }
        );
        // Inside a multi-byte character: that character.
        assert_eq!(
            Position::at_offset(text, 5),
            Position { line: 2, column: 2 }
        );
        // Past the end: the end.
        assert_eq!(
            Position::at_offset(text, 99),
            Position { line: 2, column: 5 }
        );
    }

    #[test]
    fn lines_end_at_lf_crlf_and_a_lone_cr() {
        // Line 1 "a", CR LF, line 2 "b", CR, line 3 "c", LF, line 4 "d".
        let text = "a\r\nb\rc\nd";
        let at = |o| {
            let p = Position::at_offset(text, o);
            (p.line, p.column)
        };
        assert_eq!(at(0), (1, 1));
        // The CR of CR LF ends line 1; just after it (before the LF) is
        // already line 2, as is the character after the pair.
        assert_eq!(at(1), (1, 2));
        assert_eq!(at(2), (2, 1));
        assert_eq!(at(3), (2, 1));
        assert_eq!(at(4), (2, 2));
        assert_eq!(at(5), (3, 1));
        assert_eq!(at(7), (4, 1));
        assert_eq!(at(99), (4, 2));
        // Only CRs: each one a line.
        assert_eq!(
            Position::at_offset("\r\r\rx", 3),
            Position { line: 4, column: 1 }
        );
    }

    #[test]
    fn display_is_one_line() {
        let e = LoadError::new(
            Path::new("s.xml"),
            Some(Position {
                line: 7,
                column: 12,
            }),
            LoadErrorKind::InvalidNumber {
                element: "color",
                attribute: "red",
                value: "1\n2".into(),
            },
        );
        assert_eq!(
            e.to_string(),
            "s.xml:7:12: <color> attribute red=\"1\\n2\" is not a number"
        );
        let e = LoadError::new(Path::new("s.xml"), None, LoadErrorKind::MissingCamera);
        assert_eq!(
            e.to_string(),
            "s.xml: the scene has no <camera>: exactly one is required"
        );
    }
}
