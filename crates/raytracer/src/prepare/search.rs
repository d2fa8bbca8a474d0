//! Where texture and mesh files named by a scene are looked for.

use std::path::{Path, PathBuf};

use crate::texture::TextureError;

/// Where `texture=` file paths are looked for, in order: the scene file's folder, the extra
/// folders (`--textures`), then the working directory. Absolute paths are used as they are.
#[derive(Clone, Debug, Default)]
pub struct TextureSearch {
    /// The scene file's folder, if the scene came from a file.
    pub scene_dir: Option<PathBuf>,
    /// Extra folders, searched after the scene's folder.
    pub extra_dirs: Vec<PathBuf>,
}

impl TextureSearch {
    /// The folders searched for a relative path, in order, each once.
    pub fn folders(&self) -> Vec<PathBuf> {
        let mut dirs: Vec<PathBuf> = Vec::new();
        let candidates = self.scene_dir.iter().chain(&self.extra_dirs).cloned().chain([PathBuf::from(".")]);
        for dir in candidates {
            if !dirs.contains(&dir) {
                dirs.push(dir);
            }
        }
        dirs
    }

    /// Finds the file a `texture=` (or mesh file) path names (see [`TextureSearch::locate`]).
    pub fn resolve(&self, name: &str) -> Result<PathBuf, TextureError> {
        self.locate(name).map(|found| found.path)
    }

    /// Finds the file a `texture=` path names: in each folder in turn, the path as written; when
    /// that is nowhere and the path has folders in it, its bare file name in each folder (the
    /// course's files name textures relative to the course program's own working folder, as in
    /// `texture= src/floor.bmp`). A folder or a device found under the name is an error of its
    /// own, not "cannot find".
    pub fn locate(&self, name: &str) -> Result<Located, TextureError> {
        let path = Path::new(name);
        let mut searched = Vec::new();
        let mut not_a_file = None;
        let mut try_in = |candidates: Vec<PathBuf>, searched: &mut Vec<PathBuf>| {
            for candidate in candidates {
                match std::fs::metadata(&candidate) {
                    Ok(m) if m.is_file() => return Some(candidate),
                    Ok(m) => {
                        not_a_file.get_or_insert((candidate.clone(), m.is_dir()));
                    }
                    Err(_) => {}
                }
                searched.push(candidate);
            }
            None
        };
        let as_written = if path.is_absolute() {
            vec![path.to_path_buf()]
        } else {
            self.folders().iter().map(|d| d.join(path)).collect()
        };
        if let Some(path) = try_in(as_written, &mut searched) {
            return Ok(Located { path, by_file_name: false });
        }
        let file_name = path.file_name().filter(|f| Path::new(f) != path);
        if let Some(file_name) = file_name {
            let by_name = self.folders().iter().map(|d| d.join(file_name)).collect();
            if let Some(path) = try_in(by_name, &mut searched) {
                return Ok(Located { path, by_file_name: true });
            }
        }
        Err(match not_a_file {
            Some((path, true)) => TextureError::Directory { path },
            Some((path, false)) => TextureError::NotAFile { path },
            None => TextureError::NotFound { name: name.to_owned(), searched },
        })
    }
}

/// A file found by [`TextureSearch::locate`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Located {
    /// The file.
    pub path: PathBuf,
    /// Whether it was found by its bare file name only, the path as written leading nowhere.
    pub by_file_name: bool,
}
