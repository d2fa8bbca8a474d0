//! The lexer: a line cut at its comment and split into whitespace-separated tokens with their
//! columns.

use crate::base::source::Span;

/// A whitespace-separated word of a line, with its position.
#[derive(Clone, Copy, Debug)]
pub(super) struct Token<'a> {
    pub(super) text: &'a str,
    /// 1-based character column.
    pub(super) column: u32,
    /// Length in characters.
    pub(super) len: u32,
}

impl Token<'_> {
    pub(super) fn span(&self, line: u32) -> Span {
        Span { line, column: self.column, len: self.len }
    }
}

/// Splits a line into `tokens` (cleared first), dropping the comment (from the first `#` or `//`).
pub(super) fn tokenize<'a>(line: &'a str, tokens: &mut Vec<Token<'a>>) {
    tokens.clear();
    if !line.is_ascii() {
        tokenize_chars(line, tokens);
        return;
    }
    // ASCII (nearly every line of a scene file): a column is a byte. `u8::is_ascii_whitespace`
    // leaves out the vertical tab, which `char::is_whitespace` counts.
    let bytes = line.as_bytes();
    let blank = |b: u8| b.is_ascii_whitespace() || b == 0x0B;
    let comment = |i: usize| bytes[i] == b'#' || (bytes[i] == b'/' && bytes.get(i + 1) == Some(&b'/'));
    let mut i = 0;
    while i < bytes.len() {
        if blank(bytes[i]) {
            i += 1;
            continue;
        }
        let start = i;
        while i < bytes.len() && !blank(bytes[i]) && !comment(i) {
            i += 1;
        }
        if i > start {
            tokens.push(Token { text: &line[start..i], column: start as u32 + 1, len: (i - start) as u32 });
        }
        if i < bytes.len() && comment(i) {
            break;
        }
    }
}

/// [`tokenize`] for a line with characters beyond ASCII: columns count characters.
pub(super) fn tokenize_chars<'a>(line: &'a str, tokens: &mut Vec<Token<'a>>) {
    let mut start: Option<(usize, u32)> = None;
    let mut column = 0u32;
    let mut chars = line.char_indices().peekable();
    let mut end_of_code = line.len();
    while let Some((i, ch)) = chars.next() {
        column += 1;
        let comment = ch == '#' || (ch == '/' && chars.peek().is_some_and(|&(_, c)| c == '/'));
        if comment {
            end_of_code = i;
            break;
        }
        if ch.is_whitespace() {
            if let Some((s, c)) = start.take() {
                tokens.push(Token { text: &line[s..i], column: c, len: column - c });
            }
        } else if start.is_none() {
            start = Some((i, column));
        }
    }
    if let Some((s, c)) = start {
        let text = &line[s..end_of_code];
        tokens.push(Token { text, column: c, len: char_count(text) });
    }
}

/// The number of characters of `text` (its length when it is ASCII, as scene text nearly always is).
pub(super) fn char_count(text: &str) -> u32 {
    if text.is_ascii() { text.len() as u32 } else { text.chars().count() as u32 }
}
