//! Files written whole or not at all, shared by the ray tracer's and the terrain engine's image
//! output.
//!
//! [`write_atomically`] creates a temporary file **exclusively** (`O_EXCL`, a random name: a
//! planted file or symlink is never followed) in the target's folder, lets the caller encode
//! into it, flushes it to disk and renames it over the target. On any failure the temporary file
//! is removed and the target is untouched. While it exists, the temporary file is listed in a
//! process-wide registry, so that a signal handler can remove it with [`remove_unfinished`]
//! before the process exits.
//!
//! Errors name the target as the user gave it, never the temporary file, and an I/O error met
//! while encoding (a full disk) is reported as such rather than as the encoder's own error.
//!
//! Reading goes through one gate too: [`open_regular`] opens a file only if it is a regular
//! file, refusing folders, devices and named pipes at once (a pipe would otherwise wait forever
//! for a writer).

mod regular;

pub use regular::{NotRegular, not_regular, open_regular, read_regular, read_regular_to_string};

use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// Prefix of the temporary files' names (they are hidden, then random).
const TEMP_PREFIX: &str = ".rayterra-";
/// Suffix of the temporary files' names.
const TEMP_SUFFIX: &str = ".part";

/// Why a file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError<E: std::error::Error + 'static> {
    /// The folder that should hold the file does not exist.
    #[error("cannot write `{}`: the folder `{}` does not exist", .path.display(), .folder.display())]
    NoFolder {
        /// The target.
        path: PathBuf,
        /// Its folder.
        folder: PathBuf,
    },
    /// The path the folder should be is not a folder.
    #[error("cannot write `{}`: `{}` is not a folder", .path.display(), .folder.display())]
    NotAFolder {
        /// The target.
        path: PathBuf,
        /// Its would-be folder.
        folder: PathBuf,
    },
    /// The target is a folder.
    #[error("cannot write `{}`: it is a directory", .path.display())]
    TargetIsDirectory {
        /// The target.
        path: PathBuf,
    },
    /// The target's form names a folder, not a file: it ends with a slash, `.` or `..`.
    #[error(
        "cannot write `{}`: a path ending with `/`, `.` or `..` names a folder; give a file name",
        .path.display()
    )]
    NotAFileName {
        /// The target.
        path: PathBuf,
    },
    /// The file system refused (no permission, disk full, ...).
    #[error("cannot write `{}`: {source}", .path.display())]
    Io {
        /// The target.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: io::Error,
    },
    /// The caller's encoder failed for a reason of its own.
    #[error("cannot encode `{}`: {source}", .path.display())]
    Encode {
        /// The target.
        path: PathBuf,
        /// What the encoder said.
        #[source]
        source: E,
    },
}

/// The temporary files being written now, for [`remove_unfinished`].
static UNFINISHED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn unfinished() -> MutexGuard<'static, Vec<PathBuf>> {
    UNFINISHED.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Removes every temporary file being written now and keeps any more from being renamed into
/// place: call it from a signal handler (on its own thread, as the `ctrlc` crate runs them)
/// right before exiting. Returns the number of files removed.
pub fn remove_unfinished() -> usize {
    let mut list = unfinished();
    let removed = list.iter().filter(|path| std::fs::remove_file(path).is_ok()).count();
    list.clear();
    // Leak the guard: a writer that finishes after this point blocks on the lock instead of
    // renaming its file into place, until the process exits.
    std::mem::forget(list);
    removed
}

/// Whether `path`'s form names a file: it does not end with a separator, `.` or `..` (which name
/// folders, whatever exists on disk: `out.png/` cannot be created as a file).
fn names_a_file(path: &Path) -> bool {
    let text = path.as_os_str().as_encoded_bytes();
    let ends_with_separator = text.last().is_some_and(|&b| b == b'/' || (cfg!(windows) && b == b'\\'));
    !ends_with_separator
        && matches!(path.components().next_back(), Some(std::path::Component::Normal(_)))
        && !text.ends_with(b"/.")
}

/// The folder a file path lives in (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    }
}

/// An I/O error without the temporary file's path that `tempfile` adds to its messages.
fn without_temp_path(error: io::Error) -> io::Error {
    match error.raw_os_error() {
        Some(code) => io::Error::from_raw_os_error(code),
        None => io::Error::new(error.kind(), error.kind().to_string()),
    }
}

/// A temporary file in `folder`, created exclusively.
fn create_temporary(folder: &Path) -> io::Result<tempfile::NamedTempFile> {
    let mut builder = tempfile::Builder::new();
    builder.prefix(TEMP_PREFIX).suffix(TEMP_SUFFIX);
    // A temporary file is private; the result should be created like any other file (0666 less
    // the umask).
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    builder.tempfile_in(folder).map_err(without_temp_path)
}

/// Checks that `path` can be written, before any long work whose result it is to hold: its
/// folder exists and takes a new file, and `path` is not a folder. Nothing is left behind.
pub fn check_writable<E: std::error::Error + 'static>(path: &Path) -> Result<(), WriteError<E>> {
    if !names_a_file(path) {
        return Err(WriteError::NotAFileName { path: path.to_path_buf() });
    }
    let folder = folder_of(path);
    match std::fs::metadata(folder) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            return Err(WriteError::NoFolder { path: path.to_path_buf(), folder: folder.to_path_buf() });
        }
        Err(source) => return Err(WriteError::Io { path: path.to_path_buf(), source }),
        Ok(m) if !m.is_dir() => {
            return Err(WriteError::NotAFolder { path: path.to_path_buf(), folder: folder.to_path_buf() });
        }
        Ok(_) => {}
    }
    if path.is_dir() {
        return Err(WriteError::TargetIsDirectory { path: path.to_path_buf() });
    }
    create_temporary(folder).map(drop).map_err(|source| WriteError::Io { path: path.to_path_buf(), source })
}

/// The writer an encoder writes into: a buffered temporary file that remembers the first I/O
/// error it met, so a full disk is reported as a full disk whatever the encoder makes of it.
pub struct Writer<W: Write + Seek> {
    inner: BufWriter<Recording<W>>,
}

impl<W: Write + Seek> Writer<W> {
    fn new(inner: W) -> Self {
        Writer { inner: BufWriter::with_capacity(1 << 16, Recording { inner, error: None }) }
    }

    /// Flushes the buffer, then hands back the first I/O error met, if any.
    fn finish(mut self) -> Result<W, io::Error> {
        let flushed = self.inner.flush();
        let recording = self.inner.into_inner().map_err(io::IntoInnerError::into_error)?;
        match (recording.error, flushed) {
            (Some(error), _) | (None, Err(error)) => Err(error),
            (None, Ok(())) => Ok(recording.inner),
        }
    }

    /// The first I/O error met so far, taken out.
    fn take_error(&mut self) -> Option<io::Error> {
        self.inner.get_mut().error.take()
    }
}

impl<W: Write + Seek> Write for Writer<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.inner.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

impl<W: Write + Seek> Seek for Writer<W> {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        self.inner.seek(pos)
    }
}

/// A writer that keeps a copy of its first error.
struct Recording<W> {
    inner: W,
    error: Option<io::Error>,
}

impl<W> Recording<W> {
    fn record<T>(&mut self, result: io::Result<T>) -> io::Result<T> {
        if let Err(e) = &result
            && self.error.is_none()
            && e.kind() != io::ErrorKind::Interrupted
        {
            self.error = Some(
                e.raw_os_error()
                    .map_or_else(|| io::Error::new(e.kind(), e.to_string()), io::Error::from_raw_os_error),
            );
        }
        result
    }
}

impl<W: Write> Write for Recording<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let result = self.inner.write(buf);
        self.record(result)
    }

    fn flush(&mut self) -> io::Result<()> {
        let result = self.inner.flush();
        self.record(result)
    }
}

impl<W: Seek> Seek for Recording<W> {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        let result = self.inner.seek(pos);
        self.record(result)
    }
}

/// Runs `encode` on a buffered writer into `w` and flushes it; on failure, returns the I/O error
/// the writer met (the first one) or else the encoder's error, both naming `path`.
/// [`write_atomically`] encodes through it; it is public so that encoders can be tested against
/// a failing writer (such as `/dev/full`).
pub fn encode_into<W: Write + Seek, E: std::error::Error + 'static>(
    w: W,
    path: &Path,
    encode: impl FnOnce(&mut Writer<W>) -> Result<(), E>,
) -> Result<W, WriteError<E>> {
    let mut writer = Writer::new(w);
    let io = |source| WriteError::Io { path: path.to_path_buf(), source };
    if let Err(source) = encode(&mut writer) {
        return Err(match writer.take_error() {
            Some(error) => io(error),
            None => WriteError::Encode { path: path.to_path_buf(), source },
        });
    }
    writer.finish().map_err(io)
}

/// Writes `path` whole or not at all: `encode` writes into a temporary file created exclusively
/// in `path`'s folder, which is flushed to disk and renamed over `path` when `encode` succeeds,
/// and removed when it fails (or when [`remove_unfinished`] is called meanwhile).
pub fn write_atomically<E: std::error::Error + 'static>(
    path: &Path,
    encode: impl FnOnce(&mut Writer<&mut File>) -> Result<(), E>,
) -> Result<(), WriteError<E>> {
    let io = |source| WriteError::Io { path: path.to_path_buf(), source };
    if !names_a_file(path) {
        return Err(WriteError::NotAFileName { path: path.to_path_buf() });
    }
    let folder = folder_of(path);
    if !folder.is_dir() {
        return Err(if folder.exists() {
            WriteError::NotAFolder { path: path.to_path_buf(), folder: folder.to_path_buf() }
        } else {
            WriteError::NoFolder { path: path.to_path_buf(), folder: folder.to_path_buf() }
        });
    }
    if path.is_dir() {
        return Err(WriteError::TargetIsDirectory { path: path.to_path_buf() });
    }
    // Created and registered under the registry's lock: a signal handler that sees the file on
    // disk also finds it in the registry (it waits for the lock), so it never outlives the process.
    let (mut tmp, tmp_path) = {
        let mut list = unfinished();
        let tmp = create_temporary(folder).map_err(io)?;
        let tmp_path = tmp.path().to_path_buf();
        list.push(tmp_path.clone());
        (tmp, tmp_path)
    };
    let result = (|| {
        let file = encode_into(tmp.as_file_mut(), path, encode)?;
        file.sync_all().map_err(io)?;
        // Under the registry's lock: a signal handler removes the file either before (and the
        // rename never happens) or after (and the file is complete).
        let mut list = unfinished();
        list.retain(|p| *p != tmp_path);
        tmp.persist(path).map(drop).map_err(|e| io(without_temp_path(e.error)))
    })();
    if result.is_err() {
        // `tmp` was dropped (and removed) on the way out; forget it here too.
        unfinished().retain(|p| *p != tmp_path);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("the encoder gave up")]
    struct GaveUp;

    fn files_in(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .expect("list")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn writes_whole_files_and_leaves_nothing_on_failure() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("out.txt");
        write_atomically(&path, |w| w.write_all(b"hello")).expect("written");
        assert_eq!(std::fs::read(&path).expect("read"), b"hello");
        let err = write_atomically(&path, |w| {
            w.write_all(b"half").expect("buffered");
            Err(GaveUp)
        })
        .expect_err("the encoder fails");
        assert!(matches!(err, WriteError::Encode { .. }), "{err}");
        assert_eq!(std::fs::read(&path).expect("read"), b"hello", "the old file is untouched");
        assert_eq!(files_in(dir.path()), ["out.txt"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_planted_symlink_is_never_followed() {
        let dir = tempfile::tempdir().expect("temp dir");
        let victim = dir.path().join("victim.txt");
        std::fs::write(&victim, b"precious").expect("write");
        // Every name the old writer could have used, and a few of ours, point at the victim.
        for name in [format!(".shot.png.{}.tmp", std::process::id()), ".rayterra-000000.part".into()] {
            std::os::unix::fs::symlink(&victim, dir.path().join(name)).expect("symlink");
        }
        write_atomically(&dir.path().join("shot.png"), |w| w.write_all(b"image")).expect("written");
        assert_eq!(std::fs::read(&victim).expect("read"), b"precious");
        assert_eq!(std::fs::read(dir.path().join("shot.png")).expect("read"), b"image");
    }

    #[test]
    fn errors_name_the_target_never_the_temporary_file() {
        let dir = tempfile::tempdir().expect("temp dir");
        let missing = dir.path().join("no/such/folder/out.png");
        for err in [
            check_writable::<GaveUp>(&missing).expect_err("no folder").to_string(),
            write_atomically(&missing, |w| w.write_all(b"x")).expect_err("no folder").to_string(),
        ] {
            assert!(err.contains("out.png") && err.contains("does not exist"), "{err}");
            assert!(!err.contains(TEMP_PREFIX), "{err}");
        }
        let err = check_writable::<GaveUp>(dir.path()).expect_err("a folder").to_string();
        assert!(err.ends_with("it is a directory"), "{err}");
        std::fs::write(dir.path().join("file"), b"").expect("write");
        let err =
            check_writable::<GaveUp>(&dir.path().join("file/out.png")).expect_err("not a folder").to_string();
        assert!(err.contains("is not a folder"), "{err}");
        check_writable::<GaveUp>(&dir.path().join("fine.png")).expect("writable");
        // Issue 31, defect 6: a trailing slash (or `.`, `..`) names a folder, though the folder
        // `dir/out.png` does not exist and the parent `dir` does.
        for bad in ["out.png/", "out.png/.", "sub/..", ".", "out.png//"] {
            let path = PathBuf::from(format!("{}/{bad}", dir.path().display()));
            let err = check_writable::<GaveUp>(&path).expect_err(bad);
            assert!(matches!(err, WriteError::NotAFileName { .. }), "{bad}: {err}");
            let err = write_atomically(&path, |w| w.write_all(b"x")).expect_err(bad);
            assert!(err.to_string().contains("names a folder"), "{bad}: {err}");
        }
        assert_eq!(files_in(dir.path()), ["file"], "checking leaves nothing behind");
    }

    #[cfg(unix)]
    #[test]
    fn a_full_disk_is_reported_as_such_whatever_the_encoder_says() {
        // /dev/full fails every write with "No space left on device".
        let mut full = match File::options().write(true).open("/dev/full") {
            Ok(file) => file,
            Err(_) => return,
        };
        let err = encode_into(&mut full, Path::new("out.exr"), |w| {
            // An encoder that hides the I/O error behind its own.
            w.write_all(&[0; 1 << 20]).map_err(|_| GaveUp)
        })
        .expect_err("disk full");
        let text = err.to_string();
        assert!(matches!(err, WriteError::Io { .. }), "{text}");
        assert!(text.contains("No space left on device"), "{text}");
    }

    #[test]
    fn unfinished_files_are_removed_on_request() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("out.txt");
        let (started, wait) = std::sync::mpsc::channel();
        let (proceed, resume) = std::sync::mpsc::channel::<()>();
        let writer = std::thread::spawn(move || {
            write_atomically(&path, |w| {
                w.write_all(b"partial")?;
                started.send(()).expect("send");
                resume.recv().expect("resume");
                Ok::<(), io::Error>(())
            })
        });
        wait.recv().expect("writing");
        assert_eq!(files_in(dir.path()).len(), 1, "the temporary file exists while writing");
        // What the signal handler does; it then exits the process, which the writer cannot
        // outrun: it blocks on the registry's lock before renaming.
        let list = unfinished();
        let removed =
            list.iter().filter(|p| p.starts_with(dir.path()) && std::fs::remove_file(p).is_ok()).count();
        drop(list);
        assert_eq!(removed, 1);
        proceed.send(()).expect("resume");
        let result = writer.join().expect("writer thread");
        assert!(result.is_err(), "the file it wrote is gone, so it cannot be renamed");
        assert!(files_in(dir.path()).is_empty(), "{:?}", files_in(dir.path()));
    }
}
