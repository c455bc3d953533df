//! The XML 1.0 well-formedness rules quick-xml does not check itself, applied
//! by the loader to each piece of markup quick-xml delimits: the Char
//! production (no C0 control but tab, LF and CR, no U+FFFE or U+FFFF) in
//! comments, processing instructions and attribute values; the Name
//! production; whitespace between attributes; no `<` in an attribute value;
//! a processing instruction's target (a Name without a colon, not `xml` in
//! any case); a comment without `--` that does not end in `-`; and the syntax
//! of the XML declaration, whose encoding must be one the bytes are read in
//! (UTF-8, or ASCII or Latin-1 on ASCII-only bytes).
//!
//! Each check takes the markup's text and returns the byte offset in it of
//! the first fault, with a message.

/// A fault in a piece of markup: where in it (a byte offset), and what.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Fault {
    pub at: usize,
    pub message: String,
}

fn fault<T>(at: usize, message: impl Into<String>) -> Result<T, Fault> {
    Err(Fault {
        at,
        message: message.into(),
    })
}

/// XML's white space (production S): space, tab, CR, LF.
fn is_space(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\r' | '\n')
}

/// The Char production, for a character of a Rust string (which holds no
/// surrogate).
fn is_char(c: char) -> bool {
    !matches!(c, '\0'..='\x08' | '\x0b' | '\x0c' | '\x0e'..='\x1f' | '\u{fffe}' | '\u{ffff}')
}

fn is_name_start(c: char) -> bool {
    matches!(c,
        ':' | 'A'..='Z' | '_' | 'a'..='z'
        | '\u{c0}'..='\u{d6}' | '\u{d8}'..='\u{f6}' | '\u{f8}'..='\u{2ff}'
        | '\u{370}'..='\u{37d}' | '\u{37f}'..='\u{1fff}' | '\u{200c}'..='\u{200d}'
        | '\u{2070}'..='\u{218f}' | '\u{2c00}'..='\u{2fef}' | '\u{3001}'..='\u{d7ff}'
        | '\u{f900}'..='\u{fdcf}' | '\u{fdf0}'..='\u{fffd}' | '\u{10000}'..='\u{effff}')
}

/// XML 1.0's NameChar production.
pub(super) fn is_name_char(c: char) -> bool {
    is_name_start(c)
        || matches!(c, '-' | '.' | '0'..='9' | '\u{b7}' | '\u{300}'..='\u{36f}' | '\u{203f}'..='\u{2040}')
}

/// A character as a message shows it: printable ones quoted, others as
/// U+XXXX.
fn shown(c: char) -> String {
    if c.is_control() || c.is_whitespace() || matches!(c, '\u{fffe}' | '\u{ffff}') {
        format!("U+{:04X}", u32::from(c))
    } else {
        format!("'{c}'")
    }
}

/// The first character of `s` that is not an XML Char, with its offset.
pub(super) fn chars(s: &str, what: &str) -> Result<(), Fault> {
    // Fast path: only C0 controls and U+FFFE/U+FFFF (EF BF BE/BF) are out.
    let suspect = s
        .bytes()
        .any(|b| (b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r')) || b == 0xef);
    if !suspect {
        return Ok(());
    }
    match s.char_indices().find(|&(_, c)| !is_char(c)) {
        Some((at, c)) => fault(at, format!("{} is not allowed in {what}", shown(c))),
        None => Ok(()),
    }
}

/// The character at byte `at` of `s`, if any.
fn char_at(s: &str, at: usize) -> Option<char> {
    s.get(at..).and_then(|r| r.chars().next())
}

/// [`is_name_char`] of an ASCII byte: what it says of the same character.
fn is_ascii_name_char(b: u8) -> bool {
    b.is_ascii_alphanumeric() || matches!(b, b':' | b'_' | b'-' | b'.')
}

/// The end of the Name that starts at `at`, or a fault there.
fn name_end(s: &str, at: usize, what: &str) -> Result<usize, Fault> {
    let rest = s.get(at..).unwrap_or_default();
    match rest.chars().next() {
        Some(c) if is_name_start(c) => {}
        Some(c) => return fault(at, format!("expected {what}, found {}", shown(c))),
        None => return fault(at, format!("expected {what}")),
    }
    // A byte at a time while the name is ASCII (every name of the
    // format); from its first other character on, a character at a time.
    let ascii = rest
        .bytes()
        .position(|b| !is_ascii_name_char(b))
        .unwrap_or(rest.len());
    let tail = rest.get(ascii..).unwrap_or_default();
    if tail.as_bytes().first().is_none_or(u8::is_ascii) {
        return Ok(at + ascii);
    }
    let len = tail
        .char_indices()
        .find(|&(_, c)| !is_name_char(c))
        .map_or(tail.len(), |(i, _)| i);
    Ok(at + ascii + len)
}

fn skip_space(s: &str, at: usize) -> usize {
    let rest = s.get(at..).unwrap_or_default().as_bytes();
    at + rest
        .iter()
        .position(|&b| !matches!(b, b' ' | b'\t' | b'\r' | b'\n'))
        .unwrap_or(rest.len())
}

/// Whether an attribute value may hold a fault [`start_tag`] reports: a
/// `<`, a C0 control other than tab, LF and CR, or the first byte of
/// U+FFFE or U+FFFF. One pass over the bytes; the exact fault, where
/// there is one, is found by the checks themselves.
fn suspect_value(value: &[u8]) -> bool {
    value
        .iter()
        .any(|&b| b == b'<' || (b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r')) || b == 0xef)
}

/// A start tag or empty-element tag between `<` and `>` (an empty one
/// without its `/`): `Name (S Attribute)* S?`, each attribute
/// `Name S? = S? "value"` with a value of Chars and no `<`.
pub(super) fn start_tag(s: &str) -> Result<(), Fault> {
    let mut at = name_end(s, 0, "an element name")?;
    let element = s.get(..at).unwrap_or_default();
    loop {
        let spaced = skip_space(s, at);
        let Some(c) = char_at(s, spaced) else {
            return Ok(());
        };
        if spaced == at {
            let message = if is_name_start(c) {
                format!("in <{element}>: no whitespace before the attribute")
            } else {
                format!("in <{element}>: unexpected {}", shown(c))
            };
            return fault(at, message);
        }
        at = name_end(s, spaced, "an attribute name").map_err(|f| Fault {
            message: format!("in <{element}>: {}", f.message),
            ..f
        })?;
        let attribute = s.get(spaced..at).unwrap_or_default();
        at = skip_space(s, at);
        if char_at(s, at) != Some('=') {
            return fault(
                at,
                format!("in <{element}>: expected `=` after the attribute name {attribute}"),
            );
        }
        at = skip_space(s, at + 1);
        let quote = match char_at(s, at) {
            Some(q @ ('"' | '\'')) => q,
            _ => {
                return fault(
                    at,
                    format!("in <{element}>: attribute {attribute}: value without quotes"),
                );
            }
        };
        let start = at + 1;
        let rest = s.get(start..).unwrap_or_default();
        // The quote is ASCII: a byte search finds the character.
        let Some(len) = rest.bytes().position(|b| char::from(b) == quote) else {
            return fault(
                at,
                format!("in <{element}>: attribute {attribute}: value not closed: missing {quote}"),
            );
        };
        let value = rest.get(..len).unwrap_or_default();
        if !suspect_value(value.as_bytes()) {
            at = start + len + 1;
            continue;
        }
        if let Some(lt) = value.find('<') {
            return fault(
                start + lt,
                format!(
                    "in <{element}>: attribute {attribute}: '<' is not allowed in a value (write &lt;)"
                ),
            );
        }
        chars(value, "an attribute value").map_err(|f| Fault {
            at: start + f.at,
            message: format!("in <{element}>: attribute {attribute}: {}", f.message),
        })?;
        at = start + len + 1;
    }
}

/// A comment's text between `<!--` and `-->`: Chars, no `--`, not ending
/// in `-`.
pub(super) fn comment(s: &str) -> Result<(), Fault> {
    if let Some(at) = s.find("--") {
        return fault(at, "'--' is not allowed in a comment");
    }
    if s.ends_with('-') {
        return fault(s.len() - 1, "a comment cannot end in '-' (before -->)");
    }
    chars(s, "a comment")
}

/// A processing instruction between `<?` and `?>`: a target that is a Name
/// without a colon and not `xml` in any case, then nothing or whitespace
/// and Chars.
pub(super) fn processing_instruction(s: &str) -> Result<(), Fault> {
    let end = name_end(s, 0, "a processing instruction's target")?;
    let target = s.get(..end).unwrap_or_default();
    if target.eq_ignore_ascii_case("xml") {
        return fault(
            0,
            "the target xml is reserved: the XML declaration <?xml ...?> must be at the very start of the file",
        );
    }
    if let Some(colon) = target.find(':') {
        return fault(
            colon,
            format!("a colon is not allowed in the processing instruction target {target}"),
        );
    }
    let rest = s.get(end..).unwrap_or_default();
    match rest.chars().next() {
        None => Ok(()),
        Some(c) if is_space(c) => chars(rest, "a processing instruction").map_err(|f| Fault {
            at: end + f.at,
            ..f
        }),
        Some(c) => fault(
            end,
            format!(
                "expected whitespace after the processing instruction target {target}, found {}",
                shown(c)
            ),
        ),
    }
}

/// Encodings whose reading of ASCII bytes is UTF-8's.
const ASCII_ENCODINGS: &[&str] = &[
    "US-ASCII",
    "ASCII",
    "ISO-8859-1",
    "ISO_8859-1",
    "ISO-LATIN-1",
    "LATIN1",
    "LATIN-1",
];

/// The XML declaration between `<?xml` and `?>`:
/// `VersionInfo EncodingDecl? SDDecl? S?`. The file is read as UTF-8: the
/// encoding must be UTF-8, or an ASCII-compatible one when `ascii` (the
/// file is ASCII only).
pub(super) fn declaration(s: &str, ascii: &dyn Fn() -> bool) -> Result<(), Fault> {
    // Each pseudo-attribute: S name Eq quoted value.
    let mut at = 0;
    let mut seen: Vec<&str> = Vec::new();
    loop {
        let spaced = skip_space(s, at);
        if spaced == s.len() {
            break;
        }
        if spaced == at {
            return fault(at, "in the XML declaration: expected whitespace");
        }
        let end = s
            .get(spaced..)
            .unwrap_or_default()
            .find(|c: char| !c.is_ascii_alphabetic())
            .map_or(s.len(), |i| spaced + i);
        let name = s.get(spaced..end).unwrap_or_default();
        let order = ["version", "encoding", "standalone"];
        let Some(index) = order.iter().position(|&n| n == name) else {
            return fault(
                spaced,
                "in the XML declaration: expected version, encoding or standalone",
            );
        };
        if seen.contains(&name)
            || seen
                .iter()
                .any(|s| order.iter().position(|n| n == s) > Some(index))
        {
            return fault(
                spaced,
                format!(
                    "in the XML declaration: {name} is repeated or out of order (version, encoding, standalone)"
                ),
            );
        }
        if index > 0 && seen.is_empty() {
            return fault(
                spaced,
                "in the XML declaration: the version must come first",
            );
        }
        seen.push(name);
        at = skip_space(s, end);
        if char_at(s, at) != Some('=') {
            return fault(
                at,
                format!("in the XML declaration: expected `=` after {name}"),
            );
        }
        at = skip_space(s, at + 1);
        let quote = match char_at(s, at) {
            Some(q @ ('"' | '\'')) => q,
            _ => return fault(at, format!("in the XML declaration: {name} without quotes")),
        };
        let start = at + 1;
        let Some(len) = s.get(start..).unwrap_or_default().find(quote) else {
            return fault(
                at,
                format!("in the XML declaration: {name} not closed: missing {quote}"),
            );
        };
        let value = s.get(start..start + len).unwrap_or_default();
        let bad = |what: String| fault(start, format!("in the XML declaration: {what}"));
        match name {
            "version" => {
                let ok = value
                    .strip_prefix("1.")
                    .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()));
                if !ok {
                    return bad(format!("version \"{value}\" is not 1.0"));
                }
            }
            "encoding" => {
                let well_formed = value
                    .chars()
                    .next()
                    .is_some_and(|c| c.is_ascii_alphabetic())
                    && value
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'));
                if !well_formed {
                    return bad(format!("\"{value}\" is not an encoding name"));
                }
                let utf8 =
                    value.eq_ignore_ascii_case("UTF-8") || value.eq_ignore_ascii_case("UTF8");
                let fits = ASCII_ENCODINGS
                    .iter()
                    .any(|e| value.eq_ignore_ascii_case(e))
                    && ascii();
                if !utf8 && !fits {
                    return bad(format!(
                        "encoding \"{value}\": the file is read as UTF-8, declare encoding=\"UTF-8\" or none"
                    ));
                }
            }
            _ => {
                if value != "yes" && value != "no" {
                    return bad(format!("standalone=\"{value}\" must be yes or no"));
                }
            }
        }
        at = start + len + 1;
    }
    if seen.first() != Some(&"version") {
        return fault(
            s.len(),
            "the XML declaration has no version (<?xml version=\"1.0\"?>)",
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(r: Result<(), Fault>) -> Option<usize> {
        r.err().map(|f| f.at)
    }

    #[test]
    fn start_tags() {
        assert_eq!(at(start_tag("light x=\"1\" y='2'  ")), None);
        assert_eq!(at(start_tag("light x = \"1\"\n\ty=\"&lt;\"")), None);
        assert_eq!(at(start_tag("light x=\"1\"y=\"2\"")), Some(11));
        assert_eq!(at(start_tag("light x=\"<\"")), Some(9));
        assert_eq!(at(start_tag("light x=\"\u{1}\"")), Some(9));
        assert_eq!(at(start_tag("light x=1")), Some(8));
        assert_eq!(at(start_tag("light x")), Some(7));
        assert_eq!(at(start_tag(" light")), Some(0));
        assert_eq!(at(start_tag("1light")), Some(0));
        assert_eq!(at(start_tag("light/")), Some(5));
        assert_eq!(at(start_tag("sphère")), None);
        // Names that leave ASCII midway, values with a fault after clean
        // bytes: the byte-at-a-time paths hand over at the right place.
        assert_eq!(at(start_tag("sph\u{b7}re a\u{300}b=\"1\"")), None);
        assert_eq!(at(start_tag("sph\u{d7}re")), Some(3));
        assert_eq!(at(start_tag("light x\u{d7}=\"1\"")), Some(7));
        assert_eq!(at(start_tag("light x=\"12\u{ffff}\"")), Some(11));
        assert_eq!(at(start_tag("light x=\"é\u{fffe}\" y=\"<\"")), Some(11));
        assert_eq!(at(start_tag("light x=\"é\" y=\"a<\"")), Some(17));
        assert_eq!(at(start_tag("light x=\"1\"\u{a0}y=\"2\"")), Some(11));
    }

    /// The byte-at-a-time name test says what the character test says of
    /// every ASCII character.
    #[test]
    fn ascii_name_bytes_are_name_characters() {
        for b in 0..0x80u8 {
            assert_eq!(is_ascii_name_char(b), is_name_char(char::from(b)), "{b:#x}");
        }
    }

    #[test]
    fn comments_and_instructions() {
        assert_eq!(at(comment(" a - b ")), None);
        assert_eq!(at(comment(" a -- b ")), Some(3));
        assert_eq!(at(comment(" a -")), Some(3));
        assert_eq!(at(comment(" \u{0} ")), Some(1));
        assert_eq!(at(comment(" \u{ffff} ")), Some(1));
        assert_eq!(at(processing_instruction("pi")), None);
        assert_eq!(at(processing_instruction("pi data \u{1}")), Some(8));
        assert_eq!(at(processing_instruction("xm--> a")), Some(4));
        assert_eq!(at(processing_instruction("XmL a")), Some(0));
        assert_eq!(at(processing_instruction("a:b")), Some(1));
        assert_eq!(at(processing_instruction("xml-stylesheet a")), None);
    }

    #[test]
    fn declarations() {
        let ok = |s: &str| at(declaration(s, &|| false)).is_none();
        assert!(ok(" version=\"1.0\""));
        assert!(ok(" version = '1.0' encoding=\"utf-8\" standalone='yes' "));
        assert!(!ok(""));
        assert!(!ok(" version=\"2.0\""));
        assert!(!ok(" version=\"1.0\"encoding=\"UTF-8\""));
        assert!(!ok(" encoding=\"UTF-8\" version=\"1.0\""));
        assert!(!ok(" version=\"1.0\" encoding=\"UTF-16\""));
        assert!(!ok(" version=\"1.0\" standalone=\"maybe\""));
        assert!(!ok(" version=\"1.0\" standalone=\"no\" encoding=\"UTF-8\""));
        assert!(!ok(" version=\"1.0\" encoding=\"latin1\""));
        assert_eq!(
            at(declaration(" version=\"1.0\" encoding=\"latin1\"", &|| {
                true
            })),
            None
        );
    }
}
