//! Whether two paths name the same file: by the file itself (device and inode) when both exist,
//! by their resolved folders and names otherwise. `a.exr`, `./a.exr`, `/tmp/../tmp/a.exr` and a
//! symbolic link to it are one file; the strings do not matter.

use std::path::{Path, PathBuf};

/// Whether `a` and `b` name the same file, existing or not.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(ma), Ok(mb)) => same_identity(&ma, &mb, a, b),
        // One exists and the other does not: two different files (the missing one would be
        // created beside its resolved folder, where the existing one is not).
        (Ok(_), Err(_)) | (Err(_), Ok(_)) => false,
        (Err(_), Err(_)) => match (resolved(a), resolved(b)) {
            (Some(ra), Some(rb)) => ra == rb,
            _ => a == b,
        },
    }
}

#[cfg(unix)]
fn same_identity(ma: &std::fs::Metadata, mb: &std::fs::Metadata, _: &Path, _: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    ma.dev() == mb.dev() && ma.ino() == mb.ino()
}

#[cfg(not(unix))]
fn same_identity(_: &std::fs::Metadata, _: &std::fs::Metadata, a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(ra), Ok(rb)) => ra == rb,
        _ => a == b,
    }
}

/// A path that does not exist (yet), resolved: its folder made absolute with every link and
/// `..` followed, then its name.
fn resolved(path: &Path) -> Option<PathBuf> {
    let name = path.file_name()?;
    let folder = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    Some(std::fs::canonicalize(folder).ok()?.join(name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_file_under_other_names() {
        let dir = tempfile::tempdir().expect("temp dir");
        let file = dir.path().join("a.exr");
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).expect("mkdir");
        let dotted = sub.join("..").join(".").join("a.exr");
        // Neither exists yet.
        assert!(same_file(&file, &dotted));
        assert!(!same_file(&file, &dir.path().join("b.exr")));
        std::fs::write(&file, b"x").expect("write");
        assert!(same_file(&file, &dotted));
        // One exists, the other does not.
        assert!(!same_file(&file, &dir.path().join("b.exr")));
        std::fs::write(dir.path().join("b.exr"), b"x").expect("write");
        assert!(!same_file(&file, &dir.path().join("b.exr")), "the same bytes are another file");
        #[cfg(unix)]
        {
            let link = sub.join("link.exr");
            std::os::unix::fs::symlink(&file, &link).expect("symlink");
            assert!(same_file(&file, &link));
            let hard = sub.join("hard.exr");
            std::fs::hard_link(&file, &hard).expect("hard link");
            assert!(same_file(&hard, &file));
        }
    }
}
