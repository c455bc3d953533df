//! A message's JSON read into the protocol's types with its longest string
//! (a document's text, in a `didOpen` of a big scene) taken out of the
//! bytes in place: serde_json unescapes a string into a buffer of its own
//! and then copies it into the value, so a 230 MB text took its bytes
//! three times at once (the body, the buffer, the copy). Here the text is
//! unescaped where it lies (an escape is never shorter than what it
//! stands for) and the body's own memory becomes the `String`: the text's
//! bytes once. The rest of the message, small, goes through serde_json.
//!
//! Anything this reader is not sure of (no string, a placeholder that
//! cannot be told apart) goes through serde_json whole, as before; a
//! malformed string is malformed JSON either way.

use lsp_server::Message;

/// Bodies from this length have their longest string taken in place;
/// smaller ones go through serde_json whole.
pub const TAKEN_FROM: usize = 1 << 20;

/// The message `body` holds.
pub fn message(body: Vec<u8>) -> Result<Message, String> {
    let whole = |body: &[u8]| {
        serde_json::from_slice::<Message>(body).map_err(|e| format!("malformed LSP payload: {e}"))
    };
    if body.len() < TAKEN_FROM {
        return whole(&body);
    }
    let Some(string) = longest_string(&body) else {
        return whole(&body);
    };
    // The message with the string replaced by a placeholder, parsed
    // first: the body is changed only once the rest is known good.
    let mut rest = Vec::with_capacity(body.len() - string.len() + PLACEHOLDER.len());
    rest.extend_from_slice(&body[..string.start]);
    rest.extend_from_slice(PLACEHOLDER.as_bytes());
    rest.extend_from_slice(&body[string.end..]);
    let Ok(mut value) = serde_json::from_slice::<serde_json::Value>(&rest) else {
        return whole(&body);
    };
    if placeholders(&value) != 1 {
        return whole(&body);
    }
    let text = take(body, string)?;
    put(&mut value, text);
    serde_json::from_value(value).map_err(|e| format!("malformed LSP payload: {e}"))
}

/// What stands for the string taken, as JSON (quotes and all): a string
/// a message may hold too, which is why the ones found are counted.
const PLACEHOLDER: &str = "\"\\u0000rayoflight-taken\\u0000\"";

fn is_placeholder(s: &str) -> bool {
    s == "\0rayoflight-taken\0"
}

/// How many strings of `value` are the placeholder.
fn placeholders(value: &serde_json::Value) -> usize {
    match value {
        serde_json::Value::String(s) => usize::from(is_placeholder(s)),
        serde_json::Value::Array(a) => a.iter().map(placeholders).sum(),
        serde_json::Value::Object(o) => o.values().map(placeholders).sum(),
        _ => 0,
    }
}

/// Puts `text` where the placeholder is.
fn put(value: &mut serde_json::Value, text: String) {
    let mut stack = vec![value];
    while let Some(v) = stack.pop() {
        match v {
            serde_json::Value::String(s) if is_placeholder(s) => {
                *s = text;
                return;
            }
            serde_json::Value::Array(a) => stack.extend(a.iter_mut()),
            serde_json::Value::Object(o) => stack.extend(o.values_mut()),
            _ => {}
        }
    }
}

/// The bytes of the longest string of the JSON `body`, quotes included;
/// none without one (or where a string does not end).
fn longest_string(body: &[u8]) -> Option<std::ops::Range<usize>> {
    let mut longest: Option<std::ops::Range<usize>> = None;
    let mut i = 0;
    // memchr finds the quotes and backslashes: a 230 MB text is crossed
    // in tens of milliseconds, not a byte at a time.
    while let Some(quote) = memchr::memchr(b'"', &body[i..]) {
        let start = i + quote;
        i = start + 1;
        loop {
            let at = i + memchr::memchr2(b'"', b'\\', body.get(i..)?)?;
            match body[at] {
                b'\\' => i = at + 2,
                _ => {
                    i = at + 1;
                    break;
                }
            }
        }
        if longest.as_ref().is_none_or(|l| i - start > l.len()) {
            longest = Some(start..i);
        }
    }
    longest
}

/// The string at `string` (quotes included) of `body`, unescaped in the
/// body's own memory, which it becomes.
fn take(mut body: Vec<u8>, string: std::ops::Range<usize>) -> Result<String, String> {
    let malformed = |why: &str| format!("malformed LSP payload: {why} in a string");
    let (mut read, end) = (string.start + 1, string.end - 1);
    let mut write = read;
    let hex = |body: &[u8], at: usize| -> Result<u32, String> {
        let digits = body
            .get(at..at + 4)
            .ok_or_else(|| malformed("a short \\u escape"))?;
        let digits = std::str::from_utf8(digits).map_err(|_| malformed("a bad \\u escape"))?;
        u32::from_str_radix(digits, 16).map_err(|_| malformed("a bad \\u escape"))
    };
    while read < end {
        let byte = body[read];
        if byte < 0x20 {
            return Err(malformed("a control character"));
        }
        if byte != b'\\' {
            body[write] = byte;
            (read, write) = (read + 1, write + 1);
            continue;
        }
        let escaped = *body
            .get(read + 1)
            .ok_or_else(|| malformed("a lone backslash"))?;
        let simple = match escaped {
            b'"' => Some(b'"'),
            b'\\' => Some(b'\\'),
            b'/' => Some(b'/'),
            b'b' => Some(0x08),
            b'f' => Some(0x0c),
            b'n' => Some(b'\n'),
            b'r' => Some(b'\r'),
            b't' => Some(b'\t'),
            b'u' => None,
            _ => return Err(malformed("an unknown escape")),
        };
        if let Some(byte) = simple {
            body[write] = byte;
            (read, write) = (read + 2, write + 1);
            continue;
        }
        let mut code = hex(&body, read + 2)?;
        read += 6;
        if (0xD800..0xDC00).contains(&code) {
            // A surrogate pair: the low half must follow.
            if body.get(read..read + 2) != Some(b"\\u") {
                return Err(malformed("a lone surrogate"));
            }
            let low = hex(&body, read + 2)?;
            if !(0xDC00..0xE000).contains(&low) {
                return Err(malformed("a lone surrogate"));
            }
            code = 0x10000 + ((code - 0xD800) << 10) + (low - 0xDC00);
            read += 6;
        }
        let c = char::from_u32(code).ok_or_else(|| malformed("a lone surrogate"))?;
        let mut utf8 = [0u8; 4];
        let encoded = c.encode_utf8(&mut utf8).as_bytes();
        body[write..write + encoded.len()].copy_from_slice(encoded);
        write += encoded.len();
    }
    body.truncate(write);
    body.drain(..string.start + 1);
    String::from_utf8(body).map_err(|_| malformed("bytes that are not UTF-8"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A didOpen of `text`, as an editor writes it, padded past
    /// [`TAKEN_FROM`].
    fn did_open(text: &str) -> Vec<u8> {
        let padded = format!("{text}{}", " ".repeat(TAKEN_FROM));
        serde_json::to_vec(&serde_json::json!({
            "jsonrpc": "2.0",
            "method": "textDocument/didOpen",
            "params": {"textDocument": {"uri": "file:///s.xml", "languageId": "xml",
                "version": 1, "text": padded}}
        }))
        .unwrap()
    }

    #[test]
    fn the_longest_string_is_taken_as_serde_json_reads_it() {
        for text in [
            "<scene>\n\t\"quoted\" \\ back/slash\r\n</scene>",
            "é😀 \u{1}\u{1f}\u{7f} \u{feff}\u{fffd}",
            "\\u0041 is not an escape once escaped",
        ] {
            let body = did_open(text);
            let expected: Message = serde_json::from_slice(&body).unwrap();
            let taken = message(body).unwrap();
            assert_eq!(format!("{taken:?}"), format!("{expected:?}"), "{text:?}");
        }
        // Escapes as other writers write them: \u for every character.
        let body = r#"{"jsonrpc":"2.0","method":"x","params":{"a":"\u00e9\ud83d\ude00\u0022","pad":"PAD"}}"#
            .replace("PAD", &"x".repeat(TAKEN_FROM));
        let expected: Message = serde_json::from_slice(body.as_bytes()).unwrap();
        let taken = message(body.into_bytes()).unwrap();
        assert_eq!(format!("{taken:?}"), format!("{expected:?}"));
    }

    #[test]
    fn a_placeholder_already_in_the_message_goes_through_serde_json() {
        let body = did_open("<scene/>");
        let mut with = String::from_utf8(body).unwrap();
        with = with.replace("\"xml\"", PLACEHOLDER);
        let expected: Message = serde_json::from_slice(with.as_bytes()).unwrap();
        let taken = message(with.into_bytes()).unwrap();
        assert_eq!(format!("{taken:?}"), format!("{expected:?}"));
    }

    #[test]
    fn malformed_strings_are_malformed() {
        let pad = "x".repeat(TAKEN_FROM);
        for bad in [r"\x", r"\ud83d", r"\ud83dx", r"\u12", "\u{1}"] {
            let body = format!(r#"{{"jsonrpc":"2.0","method":"x","params":"{pad}{bad}"}}"#);
            assert!(serde_json::from_slice::<Message>(body.as_bytes()).is_err());
            assert!(message(body.into_bytes()).is_err(), "{bad}");
        }
    }
}
