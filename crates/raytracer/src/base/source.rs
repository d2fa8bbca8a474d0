//! Scene file text: decoding (UTF-8 or GBK) and positions in it.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

pub use super::diagnostic::Span;
use super::diagnostic::{Diagnostic, Location, Severity};

/// The decoded text of a scene file, with the name used in messages and the folder that texture
/// paths are resolved against first.
#[derive(Clone, Debug)]
pub struct SourceFile {
    name: String,
    dir: Option<PathBuf>,
    text: String,
    /// The byte offset of each line's start, made when first needed: a clean file read in pieces
    /// never needs it (see [`crate::scene::parse`]), a diagnostic's position does.
    line_starts: OnceLock<Vec<usize>>,
}

/// Largest scene file read, in bytes (512 MiB, about five million spheres of about 100 bytes of
/// text each). The course's scenes take a few kilobytes and a generated scene of a million
/// spheres about 100 MiB; the limit keeps a wrong path (a disk image) from being read into memory.
pub const MAX_SCENE_FILE_BYTES: u64 = 512 << 20;

/// A scene file that could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The operating system refused.
    #[error("cannot read scene file `{}`: {source}", .path.display())]
    Io {
        /// The path as given.
        path: PathBuf,
        /// The operating-system error.
        #[source]
        source: std::io::Error,
    },
    /// The path names a folder.
    #[error("cannot read scene file `{}`: it is a directory", .path.display())]
    Directory {
        /// The path as given.
        path: PathBuf,
    },
    /// The path names a device, a pipe or a socket.
    #[error("cannot read scene file `{}`: it is not a regular file", .path.display())]
    NotAFile {
        /// The path as given.
        path: PathBuf,
    },
    /// The file is larger than [`MAX_SCENE_FILE_BYTES`].
    #[error(
        "cannot read scene file `{}`: it is larger than {} MiB, the most a scene file may take",
        .path.display(),
        MAX_SCENE_FILE_BYTES >> 20
    )]
    TooLarge {
        /// The path as given.
        path: PathBuf,
    },
}

impl SourceFile {
    /// Reads and decodes a scene file; texture paths will be resolved against its folder first.
    /// Folders, devices and pipes, and files over [`MAX_SCENE_FILE_BYTES`], are refused before
    /// anything is read.
    pub fn read(path: &Path) -> Result<SourceFile, ReadError> {
        use std::io::Read;
        let io = |source| ReadError::Io { path: path.to_path_buf(), source };
        let check = |metadata: &std::fs::Metadata| {
            if metadata.is_dir() {
                Err(ReadError::Directory { path: path.to_path_buf() })
            } else if !metadata.is_file() {
                Err(ReadError::NotAFile { path: path.to_path_buf() })
            } else if metadata.len() > MAX_SCENE_FILE_BYTES {
                Err(ReadError::TooLarge { path: path.to_path_buf() })
            } else {
                Ok(())
            }
        };
        // Opened without waiting on a named pipe, and refused unless a regular file.
        let file = atomic_file::open_regular(path).map_err(|e| match atomic_file::not_regular(&e) {
            Some(atomic_file::NotRegular::Directory) => ReadError::Directory { path: path.to_path_buf() },
            Some(atomic_file::NotRegular::Special) => ReadError::NotAFile { path: path.to_path_buf() },
            None => io(e),
        })?;
        let metadata = file.metadata().map_err(io)?;
        check(&metadata)?;
        let bytes = match read_in_parallel(&file, metadata.len()) {
            Some(bytes) => bytes,
            None => {
                // The file may grow while it is read: read one byte past the limit at most.
                let mut bytes = Vec::with_capacity(metadata.len() as usize);
                file.take(MAX_SCENE_FILE_BYTES + 1).read_to_end(&mut bytes).map_err(io)?;
                bytes
            }
        };
        if bytes.len() as u64 > MAX_SCENE_FILE_BYTES {
            return Err(ReadError::TooLarge { path: path.to_path_buf() });
        }
        let dir = path
            .parent()
            .map(|p| if p.as_os_str().is_empty() { PathBuf::from(".") } else { p.to_path_buf() });
        Ok(SourceFile::from_bytes(path.display().to_string(), dir, bytes))
    }

    /// Decodes scene text given as bytes: UTF-8 (with or without a byte-order mark), or else GBK,
    /// the encoding of the course's Chinese comments. Only ASCII matters outside comments, so a
    /// wrong guess can at worst garble a comment. UTF-8 given as a `Vec` is kept without a copy.
    pub fn from_bytes(
        name: impl Into<String>,
        dir: Option<PathBuf>,
        bytes: impl Into<Vec<u8>>,
    ) -> SourceFile {
        let mut bytes = bytes.into();
        if bytes.starts_with(b"\xEF\xBB\xBF") {
            bytes.drain(..3);
        }
        let text = String::from_utf8(bytes)
            .unwrap_or_else(|e| encoding_rs::GBK.decode_without_bom_handling(e.as_bytes()).0.into_owned());
        SourceFile::from_text(name, dir, text)
    }

    /// Wraps scene text that is already decoded.
    pub fn from_text(name: impl Into<String>, dir: Option<PathBuf>, text: String) -> SourceFile {
        SourceFile { name: name.into(), dir, text, line_starts: OnceLock::new() }
    }

    /// The byte offset of each line's start.
    fn line_starts(&self) -> &[usize] {
        self.line_starts.get_or_init(|| {
            // Counted first, so that a file of millions of lines fills one list of the right size.
            let mut starts = Vec::with_capacity(1 + count_line_ends(&self.text));
            starts.push(0);
            starts.extend(memchr::memchr_iter(b'\n', self.text.as_bytes()).map(|i| i + 1));
            starts
        })
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
        numbered_lines(1, &self.text)
    }

    /// The number of lines (a final line end starts an empty last line).
    pub fn line_count(&self) -> u32 {
        self.line_starts().len() as u32
    }

    /// The text of 1-based line `number`, without its line end (empty past the end).
    pub fn line(&self, number: u32) -> &str {
        let i = number as usize - 1;
        let starts = self.line_starts();
        let Some(&start) = starts.get(i) else {
            return "";
        };
        let end = starts.get(i + 1).map_or(self.text.len(), |&e| e - 1);
        without_return(&self.text[start..end])
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
        Location::new(self.name.clone(), span, self.line(span.line))
    }
}

/// Files of at least this many bytes are read in pieces on all threads.
const PARALLEL_READ_BYTES: u64 = 8 << 20;

/// Reads the `len` bytes of a large file in pieces of [`PARALLEL_READ_BYTES`] on all threads
/// (a file of a million spheres, 107 MB, in 0.05 s instead of 0.09 s on two cores: copying from
/// the page cache and mapping the new pages are both shared out). `None` when the file is small,
/// or its length is no longer `len`, or a read fails: it is then read from the start in one
/// stream (its position is untouched), which reports any error.
#[cfg(unix)]
fn read_in_parallel(file: &std::fs::File, len: u64) -> Option<Vec<u8>> {
    use rayon::prelude::*;
    use std::os::unix::fs::FileExt;
    if !(PARALLEL_READ_BYTES..=MAX_SCENE_FILE_BYTES).contains(&len) {
        return None;
    }
    let mut bytes = vec![0; len as usize];
    let piece = PARALLEL_READ_BYTES as usize;
    bytes
        .par_chunks_mut(piece)
        .enumerate()
        .try_for_each(|(i, chunk)| file.read_exact_at(chunk, (i * piece) as u64))
        .ok()?;
    // A byte past `len` means the file grew while it was read.
    match file.read_at(&mut [0], len) {
        Ok(0) => Some(bytes),
        _ => None,
    }
}

/// Reads in one stream (elsewhere than on Unix).
#[cfg(not(unix))]
fn read_in_parallel(_file: &std::fs::File, _len: u64) -> Option<Vec<u8>> {
    None
}

/// The lines of `text` numbered from `first`, without line ends (`\n` or `\r\n`); a final line
/// end starts an empty last line.
pub(crate) fn numbered_lines(first: u32, text: &str) -> impl Iterator<Item = (u32, &str)> {
    // The line ends found by `memchr` (vector instructions); `str::split` is slower on lines of
    // a few bytes.
    let mut start = 0;
    let ends = memchr::memchr_iter(b'\n', text.as_bytes()).chain([text.len()]);
    (first..).zip(ends.map(move |end| {
        let line = &text[start..end];
        start = end + 1;
        without_return(line)
    }))
}

/// The number of `\n` in `text`.
pub(crate) fn count_line_ends(text: &str) -> usize {
    memchr::memchr_iter(b'\n', text.as_bytes()).count()
}

/// A line without the `\r` of a `\r\n` line end.
pub(crate) fn without_return(line: &str) -> &str {
    line.strip_suffix('\r').unwrap_or(line)
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
    fn folders_devices_and_huge_files_are_refused_before_reading() {
        let dir = tempfile::tempdir().expect("temp dir");
        let err = SourceFile::read(dir.path()).expect_err("a folder");
        assert!(err.to_string().ends_with("it is a directory"), "{err}");
        #[cfg(unix)]
        {
            let err = SourceFile::read(Path::new("/dev/zero")).expect_err("a device");
            assert!(err.to_string().ends_with("it is not a regular file"), "{err}");
        }
        // A sparse file over the limit: refused from its size, without reading it.
        let big = dir.path().join("big.txt");
        let file = std::fs::File::create(&big).expect("create");
        file.set_len(MAX_SCENE_FILE_BYTES + 1).expect("sparse file");
        let err = SourceFile::read(&big).expect_err("too large");
        assert!(err.to_string().contains("larger than 512 MiB"), "{err}");
        let err = SourceFile::read(&dir.path().join("none.txt")).expect_err("missing");
        assert!(matches!(err, ReadError::Io { .. }), "{err}");
    }

    #[test]
    fn scene_files_of_tens_of_mib_are_read() {
        // 40 MiB: a generated scene of 400,000 spheres takes as much. Mostly one long comment
        // line, so that the test reads a large file without parsing a large scene; its letters
        // run through the alphabet, whose 26 does not divide the pieces the file is read in, so
        // a piece out of place would show.
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("large.txt");
        let mut text = String::from("# ");
        text.extend((0..40u32 << 20).map(|i| char::from(b'a' + (i % 26) as u8)));
        text.push_str("\nprimitive sphere\n O= 0 0 0\n R= 1\nend\n");
        std::fs::write(&path, &text).expect("write");
        let src = SourceFile::read(&path).expect("a 40 MiB scene file is read");
        assert!(src.text() == text);
        assert_eq!(src.line_count(), 6);
        assert_eq!(src.line(3), " O= 0 0 0");
    }

    #[cfg(unix)]
    #[test]
    fn a_file_that_changed_length_is_read_in_one_stream() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("large.txt");
        std::fs::write(&path, vec![b'#'; 3 * PARALLEL_READ_BYTES as usize + 5]).expect("write");
        let file = std::fs::File::open(&path).expect("open");
        let len = 3 * PARALLEL_READ_BYTES + 5;
        assert_eq!(read_in_parallel(&file, len).map(|b| b.len() as u64), Some(len));
        // Longer than when its length was asked (it grew), shorter (it shrank), or small.
        assert!(read_in_parallel(&file, len - 1).is_none());
        assert!(read_in_parallel(&file, len + 1).is_none());
        assert!(read_in_parallel(&file, 1000).is_none());
    }

    #[test]
    fn utf8_bom_is_dropped() {
        let src = SourceFile::from_bytes("t", None, b"\xEF\xBB\xBFcamera\nend\n");
        assert_eq!(src.line(1), "camera");
    }
}
