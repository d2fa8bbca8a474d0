//! A scene made ready to render: textures loaded or generated, mesh files read, the BVH built,
//! and the ray queries every integrator uses.
//!
//! Integrators see surfaces only through [`PreparedScene::interaction`] (the point, the normals
//! and the side), [`PreparedScene::surface_color`] and [`PreparedScene::material`], whatever the
//! shape: spheres, triangle meshes and Bezier surfaces alike.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;
use rayon::prelude::*;

use crate::accel::{Box32, BoxRay, BuildParams, WideBvh};
use crate::geometry::obj::{LoadedObj, ObjError, load_obj};
use crate::geometry::{
    Cylinder, MeshFile, Plane, Ray, Shape, ShapeHit, ShapePart, Sphere, Square, TriangleMesh, offset_origin,
};
use crate::material::Material;
use crate::memory::MemoryBudget;
use crate::procedural;
use crate::scene::{Diagnostic, Location, Primitive, Scene, Severity};
use crate::texture::{ImageInfo, Texture, TextureError, TextureRef, TextureSource, memory_bytes};

/// Scenes with at most this many bounded primitives test them in a loop instead of a BVH.
pub const FLAT_LIMIT: usize = 8;

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
    /// BVH over the bounded primitives, when there are more than [`FLAT_LIMIT`]; its items are
    /// the primitives' indices.
    bvh: WideBvh,
    /// Primitives tested one by one: the unbounded ones (planes), and all bounded ones too when
    /// there are at most [`FLAT_LIMIT`] (a loop beats a tree walk for a handful of shapes).
    linear: FlatSet,
    /// Lights with a visible shape: (light index, shape).
    emitters: Vec<(u32, Shape)>,
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

        // Distinct texture sources (colour textures and normal maps), each loaded once, in
        // parallel.
        let mut sources: Vec<&TextureRef> = Vec::new();
        let mut index_of: HashMap<&TextureSource, u32> = HashMap::new();
        let mut texture_of = Vec::with_capacity(scene.primitives.len());
        for p in &scene.primitives {
            let mut pair = [NO_TEXTURE; 2];
            for (slot, t) in pair.iter_mut().zip([&p.material.texture, &p.material.bump]) {
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
                budget.release(kept);
                return Err(errors);
            }
            Err(texture_errors) => {
                errors.extend(texture_errors);
                return Err(errors);
            }
        };
        diagnostics.extend(notes);
        inputs.extend(sources.iter().filter_map(|t| match &t.source {
            TextureSource::File(name) => search.resolve(name).ok(),
            TextureSource::Builtin(_) => None,
        }));

        // The unbounded primitives (planes) are tested one by one, and so are all when there are
        // few bounded ones; the others go into a BVH whose items are the primitives, each with its
        // box (the unbounded ones get the empty box, which the BVH leaves out).
        let prims = &scene.primitives;
        let mut linear: Vec<u32> = prims
            .par_iter()
            .enumerate()
            .filter(|(_, p)| !p.shape.is_bounded())
            .map(|(i, _)| i as u32)
            .collect();
        let bvh_items = if prims.len() - linear.len() <= FLAT_LIMIT {
            linear = (0..prims.len() as u32).collect();
            0
        } else {
            prims.len()
        };
        let bvh = WideBvh::build_with(
            bvh_items,
            |i| prims[i].shape.bounds().map_or(Box32::EMPTY, |b| Box32::from_bounds(&b)),
            BuildParams::SHAPES,
        );
        let linear = FlatSet::new(&linear, &scene);
        let emitters = scene
            .lights
            .iter()
            .enumerate()
            .filter_map(|(i, l)| l.shape().map(|shape| (i as u32, shape)))
            .collect();
        Ok(PreparedScene {
            bvh,
            linear,
            emitters,
            textures,
            texture_of,
            diagnostics,
            memory_used,
            inputs,
            scene,
        })
    }

    /// The triangles of the scene's meshes and the memory they take.
    pub fn mesh_stats(&self) -> MeshStats {
        let mut seen: Vec<*const crate::geometry::MeshVertices> = Vec::new();
        let mut stats = MeshStats::default();
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

    /// The nearest primitive or light shape along the ray.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Hit {
        let (mut best, mut t_max) = match self.closest_surface(ray) {
            Some((primitive, hit)) => (Hit::Surface { primitive, hit }, hit.t),
            None => (Hit::Miss, f64::INFINITY),
        };
        for (light, shape) in &self.emitters {
            if let Some(hit) = shape.intersect(ray, 0.0, t_max) {
                best = Hit::Emitter { light: *light, t: hit.t };
                t_max = hit.t;
            }
        }
        best
    }

    /// The nearest primitive along the ray, ignoring the lights' shapes (which photons and shadow
    /// rays pass through).
    #[inline]
    pub fn closest_surface(&self, ray: &Ray) -> Option<(u32, ShapeHit)> {
        let mut best = self.linear.closest(ray, f64::INFINITY);
        let mut t_max = best.map_or(f64::INFINITY, |(_, h)| h.t);
        let prims = &self.scene.primitives;
        let items = self.bvh.order();
        self.bvh.traverse(&BoxRay::new(ray), box_limit(t_max), |first, count, _| {
            for &i in &items[first as usize..(first + count) as usize] {
                if let Some(hit) = prims[i as usize].shape.intersect(ray, 0.0, t_max) {
                    best = Some((i, hit));
                    t_max = hit.t;
                }
            }
            box_limit(t_max)
        });
        best
    }

    /// Whether any primitive lies on the ray before distance `t_max` (lights never block).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        if self.linear.any(ray, t_max) {
            return true;
        }
        let prims = &self.scene.primitives;
        let items = self.bvh.order();
        let mut found = false;
        self.bvh.traverse(&BoxRay::new(ray), box_limit(t_max), |first, count, limit| {
            for &i in &items[first as usize..(first + count) as usize] {
                if prims[i as usize].shape.occludes(ray, t_max) {
                    found = true;
                    return -1.0;
                }
            }
            limit
        });
        found
    }

    /// The rounding-error magnitude of primitive `i` (see [`crate::geometry::offset_origin`]).
    #[inline]
    pub fn magnitude(&self, primitive: u32) -> f64 {
        self.scene.primitives[primitive as usize].shape.magnitude()
    }

    /// The material of primitive `i`.
    #[inline]
    pub fn material(&self, primitive: u32) -> &Material {
        &self.scene.primitives[primitive as usize].material
    }

    /// The shading frame of a hit of `ray` on `primitive`: the point, the normals and the side
    /// the ray came from. This is everything an integrator needs to know about a surface, whatever
    /// its shape.
    #[inline]
    pub fn interaction(&self, ray: &Ray, primitive: u32, hit: ShapeHit) -> Interaction {
        let shape = &self.scene.primitives[primitive as usize].shape;
        let point = shape.hit_point(ray, &hit);
        let geometric_outward = shape.outward_normal(point, hit.part);
        let front = ray.dir.dot(geometric_outward) < 0.0;
        let geometric = if front { geometric_outward } else { -geometric_outward };
        let mut outward = shape.shading_normal(hit.part).unwrap_or(geometric_outward);
        let bump = self.texture_of[primitive as usize][1];
        if bump != NO_TEXTURE {
            outward = self.bumped(shape, point, hit.part, outward, &self.textures[bump as usize]);
        }
        let mut normal = if front { outward } else { -outward };
        if normal.dot(geometric) <= 0.0 {
            // A shading normal turned away from the side the ray came from (an interpolated normal
            // at a silhouette, a strong normal map): shade with the true normal instead.
            normal = geometric;
            outward = geometric_outward;
        }
        let magnitude = shape.magnitude().max(point.abs().max_element());
        Interaction {
            primitive,
            t: hit.t,
            point,
            outward,
            normal,
            geometric,
            front,
            magnitude,
            part: hit.part,
        }
    }

    /// The outward shading normal `n` tilted by the tangent-space normal map `map` at `point`.
    fn bumped(&self, shape: &Shape, point: DVec3, part: ShapePart, n: DVec3, map: &Texture) -> DVec3 {
        let (u, v) = shape.texture_coordinates(point, part);
        let m = map.sample(u, v) * 2.0 - DVec3::ONE;
        let (du, dv) = shape.texture_tangents(point, part);
        // Red runs along the texture's columns (v), green along its rows (u), blue along n.
        let Some(tx) = (dv - n * n.dot(dv)).try_normalize() else { return n };
        let ty = n.cross(tx);
        let ty = if ty.dot(du) < 0.0 { -ty } else { ty };
        (tx * m.x + ty * m.y + n * m.z).try_normalize().unwrap_or(n)
    }

    /// The surface colour at an interaction: the primitive's `color=` times its texture there.
    #[inline]
    pub fn surface_color(&self, at: &Interaction) -> DVec3 {
        let p = &self.scene.primitives[at.primitive as usize];
        match self.texture_of[at.primitive as usize][0] {
            NO_TEXTURE => p.material.color,
            t => {
                let (u, v) = p.shape.texture_coordinates(at.point, at.part);
                p.material.color * self.textures[t as usize].sample(u, v)
            }
        }
    }
}

/// The single-precision limit of a box test for the double-precision distance `t` (rounded up).
#[inline]
fn box_limit(t: f64) -> f32 {
    let f = t as f32;
    if (f as f64) < t { f.next_up() } else { f }
}

/// A ray's hit on a primitive, as integrators see it (world space, z-up).
///
/// Two normals: `normal` is the one to **shade** with (lighting, reflection, refraction,
/// scattering): the smooth vertex normal of a mesh or the normal-mapped one where there is a
/// normal map, else the true normal. `geometric` is the true normal of the surface: secondary
/// rays are **offset** along it ([`Interaction::spawn`] and [`Interaction::shadow_origin`] do
/// this), and it tells which side of the surface a direction points to. Both face the side the ray
/// came from; on spheres, planes and the other analytic shapes they are equal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interaction {
    /// Index into `scene.primitives`.
    pub primitive: u32,
    /// Distance along the ray (its direction is a unit vector).
    pub t: f64,
    /// The hit point.
    pub point: DVec3,
    /// Unit shading normal pointing out of the shape (for a plane or square, the side of the
    /// normal of the file).
    pub outward: DVec3,
    /// Unit shading normal on the side the ray came from: `outward` for a front hit, `-outward`
    /// for a back hit. Shade with this one.
    pub normal: DVec3,
    /// Unit geometric (true) normal on the side the ray came from. Rays are offset along it.
    pub geometric: DVec3,
    /// Whether the ray hit the outside (the side the outward normal points to).
    pub front: bool,
    /// The rounding-error magnitude that scales the offset of rays leaving the point (larger for
    /// single-precision meshes).
    pub magnitude: f64,
    /// The part of the shape that was hit (for its texture coordinates).
    part: ShapePart,
}

impl Interaction {
    /// A ray leaving the point in direction `dir` (normalised here), started just off the surface
    /// on the side `dir` goes to, so it cannot hit the surface it leaves.
    #[inline]
    pub fn spawn(&self, dir: DVec3) -> Ray {
        let side = if dir.dot(self.geometric) >= 0.0 { self.geometric } else { -self.geometric };
        Ray::new(offset_origin(self.point, side, self.magnitude), dir)
    }

    /// The origin of a shadow ray towards the side the ray came from.
    #[inline]
    pub fn shadow_origin(&self) -> DVec3 {
        offset_origin(self.point, self.geometric, self.magnitude)
    }
}

/// Primitives tested in plain loops, one loop per kind of shape, so that every test is inlined
/// without a dispatch per shape.
#[derive(Debug, Default)]
struct FlatSet {
    spheres: Vec<(u32, Sphere)>,
    planes: Vec<(u32, Plane)>,
    squares: Vec<(u32, Square)>,
    cylinders: Vec<(u32, Cylinder)>,
    /// Triangles, meshes and Bezier surfaces.
    others: Vec<(u32, Shape)>,
}

/// Tests every shape of a list, keeping the nearest hit.
#[inline]
fn nearest<S>(
    list: &[(u32, S)],
    ray: &Ray,
    t_max: &mut f64,
    best: &mut Option<(u32, ShapeHit)>,
    intersect: impl Fn(&S, &Ray, f64) -> Option<ShapeHit>,
) {
    for (i, shape) in list {
        if let Some(hit) = intersect(shape, ray, *t_max) {
            *best = Some((*i, hit));
            *t_max = hit.t;
        }
    }
}

impl FlatSet {
    fn new(indices: &[u32], scene: &Scene) -> FlatSet {
        let mut set = FlatSet::default();
        for &i in indices {
            match &scene.primitives[i as usize].shape {
                Shape::Sphere(s) => set.spheres.push((i, s.clone())),
                Shape::Plane(p) => set.planes.push((i, p.clone())),
                Shape::Square(q) => set.squares.push((i, (**q).clone())),
                Shape::Cylinder(c) => set.cylinders.push((i, (**c).clone())),
                other => set.others.push((i, other.clone())),
            }
        }
        set
    }

    /// The nearest hit closer than `t_max`.
    #[inline]
    fn closest(&self, ray: &Ray, mut t_max: f64) -> Option<(u32, ShapeHit)> {
        let mut best = None;
        nearest(&self.spheres, ray, &mut t_max, &mut best, |s, r, t| s.intersect(r, 0.0, t));
        nearest(&self.planes, ray, &mut t_max, &mut best, |s, r, t| s.intersect(r, 0.0, t));
        nearest(&self.squares, ray, &mut t_max, &mut best, |s, r, t| s.intersect(r, 0.0, t));
        nearest(&self.cylinders, ray, &mut t_max, &mut best, |s, r, t| s.intersect(r, 0.0, t));
        nearest(&self.others, ray, &mut t_max, &mut best, |s, r, t| s.intersect(r, 0.0, t));
        best
    }

    /// Whether anything lies on the ray before `t_max`.
    #[inline]
    fn any(&self, ray: &Ray, t_max: f64) -> bool {
        self.spheres.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
            || self.planes.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
            || self.squares.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
            || self.cylinders.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
            || self.others.iter().any(|(_, s)| s.occludes(ray, t_max))
    }
}

/// Reads every mesh file the scene names (in parallel) and puts each in its primitive's place,
/// one primitive per material of the file. Unreadable files become errors at their scene line;
/// warnings (a missing material library) go to `diagnostics`.
fn load_meshes(
    scene: &mut Scene,
    search: &TextureSearch,
    inputs: &mut Vec<PathBuf>,
    diagnostics: &mut Vec<Diagnostic>,
    errors: &mut Vec<Diagnostic>,
) {
    let files: Vec<(usize, &MeshFile)> = scene
        .primitives
        .iter()
        .enumerate()
        .filter_map(|(i, p)| match &p.shape {
            Shape::MeshFile(f) => Some((i, &**f)),
            _ => None,
        })
        .collect();
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
                        file.path,
                        searched.iter().map(|p| format!("`{}`", p.display())).collect::<Vec<_>>().join(", ")
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
                        ObjError { file: file.path.clone(), line: None, message },
                    ))
                }
            };
            (i, result)
        })
        .collect();
    let mut replacements: HashMap<usize, Vec<Primitive>> = HashMap::new();
    for (i, result) in loaded {
        let location = match &scene.primitives[i].shape {
            Shape::MeshFile(f) => f.location.clone(),
            _ => continue,
        };
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
                let block_material = scene.primitives[i].material.clone();
                let parts = obj
                    .groups
                    .par_iter()
                    .map(|(colour, tris)| {
                        let material = match colour {
                            Some(c) => Arc::new(Material { color: *c, ..(*block_material).clone() }),
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
    let old = std::mem::take(&mut scene.primitives);
    for (i, p) in old.into_iter().enumerate() {
        match replacements.remove(&i) {
            Some(parts) => scene.primitives.extend(parts),
            None if matches!(p.shape, Shape::MeshFile(_)) => {}
            None => scene.primitives.push(p),
        }
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
fn load_textures(
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
    let span = t.location.span;
    t.location.line_text.chars().skip(span.column as usize - 1).take(span.len as usize).collect()
}

/// The note on a texture found by its bare file name.
fn found_by_file_name_note(t: &TextureRef, path: &Path) -> Diagnostic {
    Diagnostic {
        severity: Severity::Note,
        message: format!(
            "`{}` is not there as written; using `{}`, found by its file name",
            written_name(t),
            path.display()
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
