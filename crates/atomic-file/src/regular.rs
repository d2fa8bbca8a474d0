//! Opening files for reading only when they are regular files.
//!
//! Opening a named pipe (FIFO) for reading waits until something writes to it, forever if
//! nothing does; a device such as `/dev/zero` never ends; a folder cannot be read as a file.
//! [`open_regular`] opens the path without waiting (`O_NONBLOCK` on Unix, which regular files
//! ignore), then looks at what it opened (not at the path again, which could have changed in
//! between) and refuses anything but a regular file. Every file the program reads goes through
//! it.

use std::fs::File;
use std::io;
use std::path::Path;

/// What a path that should be read names instead of a regular file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NotRegular {
    /// A folder.
    Directory,
    /// A named pipe, socket or device.
    Special,
}

impl std::fmt::Display for NotRegular {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            NotRegular::Directory => "it is a directory",
            NotRegular::Special => "it is not a regular file",
        })
    }
}

impl std::error::Error for NotRegular {}

/// Whether an I/O error from [`open_regular`] is its refusal of a folder, pipe or device, and
/// which.
pub fn not_regular(error: &io::Error) -> Option<NotRegular> {
    error.get_ref().and_then(|inner| inner.downcast_ref::<NotRegular>()).copied()
}

/// Opens `path` for reading if it is a regular file (following symbolic links). A folder, a
/// named pipe, a socket or a device is refused at once, without reading or waiting, with an
/// error whose message is "it is a directory" or "it is not a regular file" (see
/// [`not_regular`]); the operating system's errors (no such file, no permission) pass through.
pub fn open_regular(path: &Path) -> io::Result<File> {
    let file = open_without_waiting(path)?;
    let metadata = file.metadata()?;
    if metadata.is_file() {
        // Regular files ignore `O_NONBLOCK`: their reads wait for the disk whatever the flag
        // says, so the file is used as opened.
        Ok(file)
    } else if metadata.is_dir() {
        Err(io::Error::new(io::ErrorKind::IsADirectory, NotRegular::Directory))
    } else {
        Err(io::Error::new(io::ErrorKind::InvalidInput, NotRegular::Special))
    }
}

/// Reads the whole of `path` if it is a regular file, as [`open_regular`] opens it.
pub fn read_regular(path: &Path) -> io::Result<Vec<u8>> {
    use std::io::Read;
    let mut file = open_regular(path)?;
    let mut bytes = Vec::with_capacity(file.metadata().map_or(0, |m| m.len()) as usize);
    file.read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// Reads the whole of `path` as UTF-8 text if it is a regular file, as [`open_regular`] opens it.
pub fn read_regular_to_string(path: &Path) -> io::Result<String> {
    String::from_utf8(read_regular(path)?)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidData, "it is not UTF-8 text"))
}

#[cfg(unix)]
fn open_without_waiting(path: &Path) -> io::Result<File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new().read(true).custom_flags(libc::O_NONBLOCK).open(path)
}

#[cfg(not(unix))]
fn open_without_waiting(path: &Path) -> io::Result<File> {
    // No named pipes to wait on in the file system: look first, then open.
    let metadata = std::fs::metadata(path)?;
    if metadata.is_dir() {
        return Err(io::Error::new(io::ErrorKind::IsADirectory, NotRegular::Directory));
    }
    if !metadata.is_file() {
        return Err(io::Error::new(io::ErrorKind::InvalidInput, NotRegular::Special));
    }
    File::open(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_files_open_and_folders_are_refused() {
        let dir = tempfile::tempdir().expect("temp dir");
        let file = dir.path().join("a.txt");
        std::fs::write(&file, b"hello").expect("write");
        assert_eq!(read_regular(&file).expect("read"), b"hello");
        assert_eq!(read_regular_to_string(&file).expect("read"), "hello");
        let error = open_regular(dir.path()).expect_err("a folder");
        assert_eq!(not_regular(&error), Some(NotRegular::Directory));
        assert_eq!(error.to_string(), "it is a directory");
        let error = open_regular(&dir.path().join("missing")).expect_err("missing");
        assert_eq!(error.kind(), io::ErrorKind::NotFound);
        assert_eq!(not_regular(&error), None);
    }

    #[cfg(unix)]
    #[test]
    fn pipes_and_devices_are_refused_without_waiting() {
        let dir = tempfile::tempdir().expect("temp dir");
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
        assert!(made.success(), "mkfifo failed: {made}");
        // Nothing ever writes to it: a plain open would wait forever.
        let error = open_regular(&fifo).expect_err("a pipe");
        assert_eq!(not_regular(&error), Some(NotRegular::Special));
        assert_eq!(error.to_string(), "it is not a regular file");
        let error = read_regular(Path::new("/dev/zero")).expect_err("a device");
        assert_eq!(not_regular(&error), Some(NotRegular::Special));
        // A link to a regular file is that file.
        let file = dir.path().join("a.txt");
        std::fs::write(&file, b"x").expect("write");
        std::os::unix::fs::symlink(&file, dir.path().join("link")).expect("symlink");
        assert_eq!(read_regular(&dir.path().join("link")).expect("read"), b"x");
    }
}
