//! A scene made ready to render: textures loaded or generated, mesh files read, the BVH built,
//! and the ray queries every integrator uses.
//!
//! Integrators see surfaces only through [`PreparedScene::interaction`] (the point, the normals
//! and the side), [`PreparedScene::surface_color`] and [`PreparedScene::material`], whatever the
//! shape: spheres, triangle meshes and Bezier surfaces alike.

mod interaction;
mod load;
mod physical;
mod queries;
mod search;
mod triangles;

pub use crate::base::color::luminance;
pub use interaction::Interaction;
use load::{load_meshes, load_textures};
pub use physical::{EnvironmentMap, sphere_local, sphere_world};
use physical::{Physical, load_physical};
use queries::FlatSet;
pub use search::{Located, TextureSearch};
use triangles::SceneTriangles;

use std::collections::HashMap;
use std::path::PathBuf;

use rayon::prelude::*;

use crate::accel::{Box32, BuildParams, WideBvh};
use crate::base::memory::MemoryBudget;
use crate::geometry::{Cylinder, Shape, ShapeHit, Square};
use crate::scene::{Diagnostic, Primitive, Scene};
use crate::texture::{Texture, TextureRef, TextureSource};

/// Scenes with at most this many bounded primitives test them in a loop instead of a BVH.
pub const FLAT_LIMIT: usize = 8;

/// What a ray hit first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Hit {
    /// Nothing.
    Miss,
    /// A primitive.
    Surface {
        /// Index into `scene.primitives`.
        primitive: u32,
        /// Where on it.
        hit: ShapeHit,
    },
    /// The visible shape of a square or sphere light.
    Emitter {
        /// Index into `scene.lights`.
        light: u32,
        /// Distance along the ray.
        t: f64,
    },
}

/// No texture (in [`PreparedScene`]'s per-primitive texture table).
const NO_TEXTURE: u32 = u32::MAX;

/// A scene ready to render.
#[derive(Debug)]
pub struct PreparedScene {
    /// The scene as parsed, with its mesh files loaded: each `primitive mesh` or `polyhedron`
    /// became one primitive per material of its file, in its place.
    pub scene: Scene,
    /// Notes and warnings found while preparing (a mesh's missing material library, a texture
    /// found by its file name only).
    pub diagnostics: Vec<Diagnostic>,
    /// Bytes of the memory budget the scene's textures keep.
    pub memory_used: u64,
    /// The files read besides the scene file (mesh files and their material libraries, then
    /// textures), in the order of the scene: what its pixels depend on.
    pub inputs: Vec<PathBuf>,
    /// Loaded and generated textures.
    textures: Vec<Texture>,
    /// For each primitive, the indices of its texture and of its normal map ([`NO_TEXTURE`]:
    /// none).
    texture_of: Vec<[u32; 2]>,
    /// BVH over the bounded primitives other than meshes, when there are more than
    /// [`FLAT_LIMIT`]; its items are the primitives' indices.
    bvh: WideBvh,
    /// Every mesh's triangles, in one tree of their own.
    triangles: SceneTriangles,
    /// Primitives tested one by one: the unbounded ones (planes), and all bounded ones too when
    /// there are at most [`FLAT_LIMIT`] (a loop beats a tree walk for a handful of shapes).
    linear: FlatSet,
    /// Lights with a visible shape: (light index, shape).
    emitters: Vec<(u32, Shape)>,
    /// The bitmaps, environment map and emitting primitives of physically based scenes.
    physical: Physical,
    /// The same shapes when all are squares (a scene's usual lights), tested without a dispatch
    /// on the kind of shape.
    emitter_squares: Option<Vec<(u32, Square)>>,
    /// Each primitive's rounding-error magnitude ([`Shape::magnitude`]), computed once rather
    /// than at every hit (a square's takes two square roots).
    magnitudes: Vec<f64>,
}

/// What a mesh's triangles and vertices take, for a report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeshStats {
    /// Triangles in all meshes.
    pub triangles: usize,
    /// Bytes of their vertices, indices, packets and BVHs.
    pub bytes: usize,
}

impl PreparedScene {
    /// Loads the textures the scene names (image files through `search`, built-in ones
    /// generated) and its mesh files (found like textures), and builds the acceleration
    /// structures. Every unreadable texture or mesh is reported. The textures must fit in the
    /// default memory budget ([`MemoryBudget::default`]).
    pub fn new(scene: Scene, search: &TextureSearch) -> Result<PreparedScene, Vec<Diagnostic>> {
        PreparedScene::with_budget(scene, search, &MemoryBudget::default())
    }

    /// As [`PreparedScene::new`], charging `budget` with the memory the textures keep (and,
    /// while they decode, the memory decoding takes). Each texture's size is read from its
    /// header and charged in file order before anything is decoded, so a texture over the budget
    /// is an error at its line, whatever the thread count.
    pub fn with_budget(
        mut scene: Scene,
        search: &TextureSearch,
        budget: &MemoryBudget,
    ) -> Result<PreparedScene, Vec<Diagnostic>> {
        let mut diagnostics = Vec::new();
        let mut errors = Vec::new();
        let mut inputs = Vec::new();
        load_meshes(&mut scene, search, &mut inputs, &mut diagnostics, &mut errors);
        let (physical, physical_memory) = load_physical(&scene, budget, &mut inputs, &mut errors);

        // Distinct texture sources (colour textures and normal maps), each loaded once, in
        // parallel.
        let mut sources: Vec<&TextureRef> = Vec::new();
        let mut index_of: HashMap<&TextureSource, u32> = HashMap::new();
        let mut texture_of = Vec::with_capacity(scene.primitives.len());
        for p in &scene.primitives {
            let mut pair = [NO_TEXTURE; 2];
            let course = p.material.as_course();
            let refs = [course.and_then(|m| m.texture.as_ref()), course.and_then(|m| m.bump.as_ref())];
            for (slot, t) in pair.iter_mut().zip(refs) {
                if let Some(t) = t {
                    *slot = *index_of.entry(&t.source).or_insert_with(|| {
                        sources.push(t);
                        sources.len() as u32 - 1
                    });
                }
            }
            texture_of.push(pair);
        }
        // Every unusable mesh and texture is reported at once.
        let (textures, notes, memory_used) = match load_textures(&sources, search, budget) {
            Ok(loaded) if errors.is_empty() => loaded,
            Ok((_, _, kept)) => {
                budget.release(kept + physical_memory);
                return Err(errors);
            }
            Err(texture_errors) => {
                budget.release(physical_memory);
                errors.extend(texture_errors);
                return Err(errors);
            }
        };
        diagnostics.extend(notes);
        let memory_used = memory_used + physical_memory;
        inputs.extend(sources.iter().filter_map(|t| match &t.source {
            TextureSource::File(name) => search.resolve(name).ok(),
            TextureSource::Builtin(_) => None,
        }));

        // The meshes' triangles go into one tree of their own. Of the other primitives, the
        // unbounded ones (planes) are tested one by one, and so are all when there are few
        // bounded ones; the others go into a BVH whose items are the primitives, each with its
        // box (the unbounded ones and the meshes get the empty box, which the BVH leaves out).
        let prims = &scene.primitives;
        let triangles = match SceneTriangles::build(prims) {
            Ok(triangles) => triangles,
            Err(error) => {
                budget.release(memory_used);
                return Err(vec![error]);
            }
        };
        let is_mesh = |p: &Primitive| matches!(p.shape, Shape::Mesh(_));
        let mut linear: Vec<u32> = prims
            .par_iter()
            .enumerate()
            .filter(|(_, p)| !p.shape.is_bounded() && !is_mesh(p))
            .map(|(i, _)| i as u32)
            .collect();
        let others = prims.iter().filter(|p| p.shape.is_bounded() && !is_mesh(p)).count();
        let bvh_items = if others <= FLAT_LIMIT {
            linear = (0..prims.len() as u32).filter(|&i| !is_mesh(&prims[i as usize])).collect();
            0
        } else {
            prims.len()
        };
        let bvh = WideBvh::build_with(
            bvh_items,
            |i| match prims[i].shape.bounds() {
                Some(b) if !is_mesh(&prims[i]) => Box32::from_bounds(&b),
                _ => Box32::EMPTY,
            },
            BuildParams::SHAPES,
        );
        let linear = FlatSet::new(&linear, &scene);
        let emitters: Vec<(u32, Shape)> = scene
            .lights
            .iter()
            .enumerate()
            .filter_map(|(i, l)| l.shape().map(|shape| (i as u32, shape)))
            .collect();
        Ok(PreparedScene {
            bvh,
            triangles,
            linear,
            emitter_squares: emitters
                .iter()
                .map(|(i, s)| match s {
                    Shape::Square(q) => Some((*i, (**q).clone())),
                    _ => None,
                })
                .collect::<Option<Vec<_>>>(),
            emitters,
            physical,
            magnitudes: scene.primitives.iter().map(|p| p.shape.magnitude()).collect(),
            textures,
            texture_of,
            diagnostics,
            memory_used,
            inputs,
            scene,
        })
    }

    /// The triangles of the scene's meshes and the memory they take (with the tree over all of
    /// them).
    pub fn mesh_stats(&self) -> MeshStats {
        let mut seen: Vec<*const crate::geometry::MeshVertices> = Vec::new();
        let mut stats = MeshStats { triangles: 0, bytes: self.triangles.memory() };
        for p in &self.scene.primitives {
            if let Shape::Mesh(m) = &p.shape {
                stats.triangles += m.len();
                stats.bytes += m.memory();
                let v = m.vertices();
                if !seen.contains(&(v as *const _)) {
                    seen.push(v as *const _);
                    stats.bytes += v.positions.len() * 12 + v.normals.len() * 12 + v.uvs.len() * 8;
                }
            }
        }
        stats
    }

    /// Bytes the scene's geometry takes once prepared: the primitives (not their shared materials
    /// or textures), the per-primitive tables, the scene's BVH and the meshes.
    pub fn geometry_memory(&self) -> usize {
        let boxed: usize = self
            .scene
            .primitives
            .iter()
            .map(|p| match &p.shape {
                Shape::Sphere(s) => s.frame_memory(),
                Shape::Plane(p) => p.axes_memory(),
                Shape::Square(_) => std::mem::size_of::<Square>(),
                Shape::Cylinder(_) => std::mem::size_of::<Cylinder>(),
                Shape::Triangle(_) => std::mem::size_of::<crate::geometry::Triangle>(),
                Shape::Bezier(_) => std::mem::size_of::<crate::geometry::Bezier>(),
                _ => 0,
            })
            .sum();
        self.scene.primitives.capacity() * std::mem::size_of::<Primitive>()
            + boxed
            + self.texture_of.capacity() * std::mem::size_of::<[u32; 2]>()
            + self.bvh.memory()
            + self.mesh_stats().bytes
    }
}
