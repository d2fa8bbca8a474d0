//! Loading what a scene names: mesh files read (in parallel) into primitives in their place, and
//! textures decoded or generated within the memory budget, each problem a diagnostic at its line.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use rayon::prelude::*;

use super::TextureSearch;
use crate::base::diagnostic::{clip, clip_path};
use crate::base::memory::MemoryBudget;
use crate::geometry::obj::{LoadedObj, ObjError, load_obj};
use crate::geometry::{MeshFile, Shape, TriangleMesh};
use crate::material::{CourseMaterial, Material};
use crate::procedural;
use crate::scene::{Diagnostic, Location, Primitive, Scene, Severity};
use crate::texture::{ImageInfo, Texture, TextureError, TextureRef, TextureSource, memory_bytes};

/// Reads every mesh file the scene names (in parallel) and puts each in its primitive's place,
/// one primitive per material of the file. Unreadable files become errors at their scene line;
/// warnings (a missing material library) go to `diagnostics`.
pub(super) fn load_meshes(
    scene: &mut Scene,
    search: &TextureSearch,
    inputs: &mut Vec<PathBuf>,
    diagnostics: &mut Vec<Diagnostic>,
    errors: &mut Vec<Diagnostic>,
) {
    let files: Vec<(usize, &MeshFile)> = scene.meshes.iter().map(|m| &m.file).enumerate().collect();
    if files.is_empty() {
        return;
    }
    type Loaded = Result<(PathBuf, LoadedObj), Diagnostic>;
    let loaded: Vec<(usize, Loaded)> = files
        .par_iter()
        .map(|&(i, file)| {
            let result = match search.resolve(&file.path) {
                Ok(path) => load_obj(&path, &file.transform)
                    .map(|obj| (path, obj))
                    .map_err(|e| obj_diagnostic(&file.location, e)),
                Err(TextureError::NotFound { searched, .. }) => Err(Diagnostic {
                    severity: Severity::Error,
                    message: format!(
                        "cannot find mesh `{}` (looked in {})",
                        clip(&file.path),
                        searched.iter().map(|p| format!("`{}`", clip_path(p))).collect::<Vec<_>>().join(", ")
                    ),
                    location: Some(file.location.clone()),
                    notes: vec![
                        "a mesh file is looked for like a texture: pass its folder with `--textures DIR`"
                            .into(),
                    ],
                }),
                Err(e) => {
                    // The search is the textures' (which words its errors for textures).
                    let message = match e {
                        TextureError::Directory { .. } => "it is a directory, not an OBJ file".to_string(),
                        TextureError::NotAFile { .. } => "it is not a regular file".to_string(),
                        e => e.to_string(),
                    };
                    Err(obj_diagnostic(
                        &file.location,
                        ObjError { file: clip(&file.path).to_string(), line: None, message },
                    ))
                }
            };
            (i, result)
        })
        .collect();
    let mut replacements: HashMap<usize, Vec<Primitive>> = HashMap::new();
    for (i, result) in loaded {
        let location = scene.meshes[i].file.location.clone();
        match result {
            Ok((path, obj)) => {
                inputs.push(path);
                inputs.extend(obj.material_libraries.iter().filter(|p| p.is_file()).cloned());
                for w in &obj.warnings {
                    diagnostics.push(Diagnostic {
                        severity: Severity::Warning,
                        message: w.clone(),
                        location: Some(location.clone()),
                        notes: Vec::new(),
                    });
                }
                if obj.triangle_count() == 0 {
                    diagnostics.push(Diagnostic {
                        severity: Severity::Warning,
                        message: "this mesh has no triangles".into(),
                        location: Some(location.clone()),
                        notes: Vec::new(),
                    });
                }
                let block_material = scene.meshes[i].material.clone();
                let parts = obj
                    .groups
                    .par_iter()
                    .map(|(colour, tris)| {
                        let material = match colour {
                            Some(c) => match &*block_material {
                                Material::Course(m) => {
                                    Arc::new(Material::Course(CourseMaterial { color: *c, ..m.clone() }))
                                }
                                _ => block_material.clone(),
                            },
                            None => block_material.clone(),
                        };
                        Primitive {
                            shape: Shape::Mesh(Arc::new(TriangleMesh::new(obj.vertices.clone(), tris))),
                            material,
                        }
                    })
                    .collect();
                replacements.insert(i, parts);
            }
            Err(d) => errors.push(d),
        }
    }
    // Each mesh file's primitives go in its place, in file order.
    let meshes = std::mem::take(&mut scene.meshes);
    let old = std::mem::take(&mut scene.primitives);
    let mut meshes = meshes.iter().enumerate().peekable();
    for (i, p) in old.into_iter().map(Some).chain(std::iter::once(None)).enumerate() {
        while let Some((m, _)) = meshes.next_if(|(_, mesh)| mesh.index <= i) {
            scene.primitives.extend(replacements.remove(&m).unwrap_or_default());
        }
        scene.primitives.extend(p);
    }
}

fn obj_diagnostic(location: &Location, e: ObjError) -> Diagnostic {
    Diagnostic {
        severity: Severity::Error,
        message: format!("cannot use mesh: {e}"),
        location: Some(location.clone()),
        notes: Vec::new(),
    }
}

/// A texture source after the first, parallel step of loading.
enum Probed {
    /// A built-in texture, generated.
    Ready(Texture),
    /// An image file found and its header read.
    File { path: PathBuf, info: ImageInfo },
}

/// Loads the textures `sources` name: finds and probes every file (in parallel), charges the
/// budget in file order, then decodes (in parallel). Returns the textures, the notes, and the
/// bytes kept; or every error.
pub(super) fn load_textures(
    sources: &[&TextureRef],
    search: &TextureSearch,
    budget: &MemoryBudget,
) -> Result<(Vec<Texture>, Vec<Diagnostic>, u64), Vec<Diagnostic>> {
    let probed: Vec<Result<(Probed, Option<Diagnostic>), Diagnostic>> = sources
        .par_iter()
        .map(|t| {
            let probe = || match &t.source {
                TextureSource::Builtin(b) => Ok((Probed::Ready(procedural::generate(*b)), None)),
                TextureSource::File(name) => {
                    let found = search.locate(name)?;
                    let info = Texture::probe(&found.path)?;
                    let note = found.by_file_name.then(|| found_by_file_name_note(t, &found.path));
                    Ok((Probed::File { path: found.path, info }, note))
                }
            };
            probe().map_err(|e| texture_diagnostic(t, e))
        })
        .collect();
    // Charge in file order, so the texture found over the budget does not depend on timing.
    let (mut errors, mut notes) = (Vec::new(), Vec::new());
    let (mut kept, mut decoding) = (0, 0);
    for (t, p) in sources.iter().zip(&probed) {
        let (probed, note) = match p {
            Ok(ok) => ok,
            Err(d) => {
                errors.push(d.clone());
                continue;
            }
        };
        notes.extend(note.clone());
        let (width, height, keeps, decodes) = match probed {
            Probed::Ready(texture) => {
                (texture.width(), texture.height(), memory_bytes(texture.width(), texture.height()), 0)
            }
            Probed::File { info, .. } => (info.width, info.height, info.kept_bytes, info.decoding_bytes),
        };
        match budget.charge(keeps + decodes) {
            Ok(()) => {
                kept += keeps;
                decoding += decodes;
            }
            Err(over) => {
                let path = PathBuf::from(written_name(t));
                errors.push(texture_diagnostic(t, TextureError::OverBudget { path, width, height, over }));
            }
        }
    }
    if !errors.is_empty() {
        budget.release(kept + decoding);
        return Err(errors);
    }
    let decoded: Vec<Result<Texture, Diagnostic>> = probed
        .into_par_iter()
        .zip(sources)
        .map(|(p, t)| match p {
            Ok((Probed::Ready(texture), _)) => Ok(texture),
            Ok((Probed::File { path, .. }, _)) => Texture::load(&path).map_err(|e| texture_diagnostic(t, e)),
            Err(d) => Err(d),
        })
        .collect();
    budget.release(decoding);
    let (textures, errors): (Vec<_>, Vec<_>) = decoded.into_iter().partition(Result::is_ok);
    if errors.is_empty() {
        Ok((textures.into_iter().flatten().collect(), notes, kept))
    } else {
        budget.release(kept);
        Err(errors.into_iter().filter_map(Result::err).collect())
    }
}

/// The `texture=` value as written in the file.
fn written_name(t: &TextureRef) -> String {
    t.location.marked_text()
}

/// The note on a texture found by its bare file name.
fn found_by_file_name_note(t: &TextureRef, path: &Path) -> Diagnostic {
    Diagnostic {
        severity: Severity::Note,
        message: format!(
            "`{}` is not there as written; using `{}`, found by its file name",
            clip(&written_name(t)),
            clip_path(path)
        ),
        location: Some(t.location.clone()),
        notes: vec![
            "the course's scene files name textures relative to the course program's working folder".into(),
        ],
    }
}

fn texture_diagnostic(t: &TextureRef, e: TextureError) -> Diagnostic {
    let mut d = Diagnostic {
        severity: Severity::Error,
        message: e.to_string(),
        location: Some(t.location.clone()),
        notes: Vec::new(),
    };
    if matches!(e, TextureError::NotFound { .. }) {
        d.notes.push("pass the folder that holds the course's textures with `--textures DIR`".into());
    }
    d
}
