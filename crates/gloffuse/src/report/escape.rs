//! Names from users' files (materials, nodes, files) made safe for where they are shown: a
//! terminal, which would obey an escape sequence, a newline or a bidi override in them, and
//! the JUnit file: XML 1.0 cannot hold some characters at all, and its writer drops the
//! other control characters. A character that is not let through
//! is shown as text, one way everywhere: `\n`, `\t`, `\r`, `\x1b` (below U+0100), `\u{fffe}`.
//! A backslash itself is left as it is (names and Windows paths hold them), so `\x1b` in the
//! output is either that text or an ESC: the JSON report holds the exact name. JSON and HTML
//! escape on their own, losslessly, and do not use this.

use std::borrow::Cow;
use std::fmt::Write as _;

/// `s` for a terminal: every control character (C0 with tab and newline, DEL, C1), every
/// bidi control, U+FFFE and U+FFFF shown as text, so a name is one line that prints as it
/// reads.
pub fn terminal(s: &str) -> Cow<'_, str> {
    escape(s, |c| {
        c.is_control() || is_bidi(c) || is_xml_noncharacter(c)
    })
}

/// As [`terminal`], but newlines are kept: for messages that are several lines by design.
pub fn terminal_lines(s: &str) -> Cow<'_, str> {
    escape(s, |c| {
        c != '\n' && (c.is_control() || is_bidi(c) || is_xml_noncharacter(c))
    })
}

/// `s` for the JUnit file's element text: what XML 1.0 cannot hold at all (C0 controls but
/// tab, newline and carriage return; U+FFFE, U+FFFF) shown as text, and so is every other
/// control character but the newline, since the JUnit writer drops them (with the escape
/// sequences they start) and the name would no longer match the material's. The writer
/// escapes `<`, `&` and quotes.
pub fn xml_text(s: &str) -> Cow<'_, str> {
    escape(s, |c| (c.is_control() && c != '\n') || !is_xml_char(c))
}

/// `s` for an XML attribute value: as [`xml_text`], and the newline shown as text too,
/// since a parser reads it as a space there.
pub fn xml_attribute(s: &str) -> Cow<'_, str> {
    escape(s, |c| c.is_control() || !is_xml_char(c))
}

/// `s` with every character `hide` picks shown as text.
fn escape(s: &str, hide: impl Fn(char) -> bool) -> Cow<'_, str> {
    if !s.chars().any(&hide) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        match c {
            c if !hide(c) => out.push(c),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if (c as u32) < 0x100 => {
                let _ = write!(out, "\\x{:02x}", c as u32);
            }
            c => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
        }
    }
    Cow::Owned(out)
}

/// XML 1.0's `Char` production (a Rust `char` is never a surrogate).
fn is_xml_char(c: char) -> bool {
    matches!(c, '\t' | '\n' | '\r' | '\u{20}'..='\u{fffd}' | '\u{10000}'..='\u{10ffff}')
}

/// U+FFFE and U+FFFF: not characters, and not allowed in XML.
fn is_xml_noncharacter(c: char) -> bool {
    matches!(c, '\u{fffe}' | '\u{ffff}')
}

/// The characters that reorder the text around them: marks, embeddings, overrides, isolates.
fn is_bidi(c: char) -> bool {
    matches!(
        c,
        '\u{061c}' | '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}'
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_terminal_gets_no_control_character() {
        let name = "a\u{1b}]0;owned\u{7}b\nc\td\u{7f}\u{9b}e\u{202e}f\u{fffe}";
        assert_eq!(
            terminal(name),
            r"a\x1b]0;owned\x07b\nc\td\x7f\x9be\u{202e}f\u{fffe}"
        );
        assert_eq!(terminal_lines("one\ntwo\u{1b}[2J"), "one\ntwo\\x1b[2J");
        assert!(matches!(terminal("Glass — 1\\2 ü"), Cow::Borrowed(_)));
    }

    #[test]
    fn xml_gets_what_it_can_hold_and_the_writer_keeps() {
        assert_eq!(
            xml_text("a\u{1b}b\u{fffe}\u{ffff}\n\t\r\u{7f}\u{85}\u{202e}<&"),
            "a\\x1bb\\u{fffe}\\u{ffff}\n\\t\\r\\x7f\\x85\u{202e}<&"
        );
        assert_eq!(
            xml_attribute("a\nb\tc\u{0}\u{202e}"),
            "a\\nb\\tc\\x00\u{202e}"
        );
    }
}
