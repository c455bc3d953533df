//! Text from outside made visible. File names and the scene's comments
//! come from outside: an ESC byte in one would drive the terminal that
//! shows it (colours, a moved cursor, a changed title), a newline would
//! make one line look like two, and a right-to-left override would show
//! another name than the one meant. Every line the CLI prints goes
//! through [`visible`], and so does every field of the CSV files the core
//! writes ([`crate::render::measure::Csv`], read with `cat` as often as by a
//! program): such characters are written as visible escapes (`\n`, `\e`,
//! `\x07`, `\u{202e}`).

use std::borrow::Cow;

/// `text` with its control characters escaped; line breaks and tabs kept
/// where `lines` (the many-line outputs of `plan` and `explain`), escaped
/// too otherwise (an error is one line).
pub fn visible(text: &str, lines: bool) -> Cow<'_, str> {
    let odd = |c: char| !(lines && matches!(c, '\n' | '\t')) && needs_escape(c);
    if !text.chars().any(odd) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if !odd(c) {
            out.push(c);
            continue;
        }
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            '\u{1b}' => out.push_str("\\e"),
            c if (c as u32) < 0x80 => out.push_str(&format!("\\x{:02x}", c as u32)),
            c => out.push_str(&format!("\\u{{{:x}}}", c as u32)),
        }
    }
    Cow::Owned(out)
}

/// C0 and C1 controls, DEL, the Unicode line and paragraph separators and
/// the bidirectional embeddings, overrides and isolates.
fn needs_escape(c: char) -> bool {
    c.is_control()
        || matches!(c, '\u{2028}' | '\u{2029}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controls_are_shown_not_obeyed() {
        assert_eq!(visible("a.xml: fine", false), "a.xml: fine");
        assert_eq!(
            visible("x\u{1b}]0;pwned\u{7}\ny\r\u{202e}z\u{85}", false),
            "x\\e]0;pwned\\x07\\ny\\r\\u{202e}z\\u{85}"
        );
        assert_eq!(visible("one\ntwo\u{1b}[2J", true), "one\ntwo\\e[2J");
        assert!(matches!(visible("plain\ntext", true), Cow::Borrowed(_)));
    }
}
