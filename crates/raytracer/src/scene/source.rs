//! Scene file text: decoding (UTF-8 or GBK) and positions in it.

use std::path::{Path, PathBuf};

use super::diagnostic::{Diagnostic, Location, Severity};

/// A position in a scene file: 1-based line and column (counted in characters; a tab is one
/// column) and the length of the marked text in characters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Span {
    /// 1-based line number.
    pub line: u32,
    /// 1-based column of the first marked character.
    pub column: u32,
    /// Number of marked characters (at least 1 when displayed).
    pub len: u32,
}

/// The decoded text of a scene file, with the name used in messages and the folder that texture
/// paths are resolved against first.
#[derive(Clone, Debug)]
pub struct SourceFile {
    name: String,
    dir: Option<PathBuf>,
    text: String,
    line_starts: Vec<usize>,
}

/// A scene file that could not be read.
#[derive(Debug, thiserror::Error)]
#[error("cannot read scene file `{path}`: {source}")]
pub struct ReadError {
    /// The path as given.
    pub path: PathBuf,
    /// The operating-system error.
    #[source]
    pub source: std::io::Error,
}

impl SourceFile {
    /// Reads and decodes a scene file; texture paths will be resolved against its folder first.
    pub fn read(path: &Path) -> Result<SourceFile, ReadError> {
        let bytes = std::fs::read(path).map_err(|source| ReadError { path: path.to_path_buf(), source })?;
        let dir = path
            .parent()
            .map(|p| if p.as_os_str().is_empty() { PathBuf::from(".") } else { p.to_path_buf() });
        Ok(SourceFile::from_bytes(path.display().to_string(), dir, &bytes))
    }

    /// Decodes scene text given as bytes: UTF-8 (with or without a byte-order mark), or else GBK,
    /// the encoding of the course's Chinese comments. Only ASCII matters outside comments, so a
    /// wrong guess can at worst garble a comment.
    pub fn from_bytes(name: impl Into<String>, dir: Option<PathBuf>, bytes: &[u8]) -> SourceFile {
        let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        let text = match std::str::from_utf8(bytes) {
            Ok(text) => text.to_owned(),
            Err(_) => encoding_rs::GBK.decode_without_bom_handling(bytes).0.into_owned(),
        };
        SourceFile::from_text(name, dir, text)
    }

    /// Wraps scene text that is already decoded.
    pub fn from_text(name: impl Into<String>, dir: Option<PathBuf>, text: String) -> SourceFile {
        let mut line_starts = vec![0];
        line_starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        SourceFile { name: name.into(), dir, text, line_starts }
    }

    /// The name used in messages (normally the path as given).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The folder texture paths are resolved against first, if the text came from a file.
    pub fn dir(&self) -> Option<&Path> {
        self.dir.as_deref()
    }

    /// The whole decoded text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The lines of the text with their 1-based numbers, without line ends (`\n` or `\r\n`).
    pub fn lines(&self) -> impl Iterator<Item = (u32, &str)> {
        (0..self.line_starts.len()).map(|i| (i as u32 + 1, self.line(i as u32 + 1)))
    }

    /// The text of 1-based line `number`, without its line end (empty past the end).
    pub fn line(&self, number: u32) -> &str {
        let i = number as usize - 1;
        let Some(&start) = self.line_starts.get(i) else {
            return "";
        };
        let end = self.line_starts.get(i + 1).map_or(self.text.len(), |&e| e - 1);
        let line = &self.text[start..end];
        line.strip_suffix('\r').unwrap_or(line)
    }

    /// A diagnostic at `span` of this file.
    pub fn diagnostic(&self, severity: Severity, span: Span, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity,
            message: message.into(),
            location: Some(self.location(span)),
            notes: Vec::new(),
        }
    }

    /// The place `span` marks in this file, for a diagnostic made later.
    pub fn location(&self, span: Span) -> Location {
        Location { file: self.name.clone(), span, line_text: self.line(span.line).to_owned() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crlf_and_lf_lines_lose_their_ends() {
        let src = SourceFile::from_text("t", None, "a\r\nbb\nccc".to_owned());
        let lines: Vec<_> = src.lines().collect();
        assert_eq!(lines, vec![(1, "a"), (2, "bb"), (3, "ccc")]);
        assert_eq!(src.line(9), "");
    }

    #[test]
    fn gbk_comments_are_decoded() {
        // "# 设置" in GBK, then a key line.
        let bytes = b"# \xC9\xE8\xD6\xC3\nO= 1 2 3\n";
        let src = SourceFile::from_bytes("t", None, bytes);
        assert_eq!(src.line(1), "# 设置");
        assert_eq!(src.line(2), "O= 1 2 3");
    }

    #[test]
    fn utf8_bom_is_dropped() {
        let src = SourceFile::from_bytes("t", None, b"\xEF\xBB\xBFcamera\nend\n");
        assert_eq!(src.line(1), "camera");
    }
}
