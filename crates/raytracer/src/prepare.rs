//! A scene made ready to render: textures loaded or generated, the BVH built, and the ray queries
//! every integrator uses.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::DVec3;
use rayon::prelude::*;

use crate::accel::Bvh;
use crate::geometry::{
    Bounds, Cylinder, Plane, Ray, Shape, ShapeHit, ShapePart, Sphere, Square, offset_origin,
};
use crate::light::Light;
use crate::material::Material;
use crate::procedural;
use crate::scene::{Diagnostic, Scene, Severity};
use crate::texture::{Texture, TextureError, TextureRef, TextureSource};

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

    /// Finds the file a `texture=` path names.
    pub fn resolve(&self, name: &str) -> Result<PathBuf, TextureError> {
        let path = Path::new(name);
        if path.is_absolute() {
            return if path.is_file() {
                Ok(path.to_path_buf())
            } else {
                Err(TextureError::NotFound { name: name.to_owned(), searched: vec![path.to_path_buf()] })
            };
        }
        let searched: Vec<PathBuf> = self.folders().iter().map(|d| d.join(path)).collect();
        searched
            .iter()
            .find(|p| p.is_file())
            .cloned()
            .ok_or(TextureError::NotFound { name: name.to_owned(), searched })
    }
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

/// A scene ready to render.
#[derive(Debug)]
pub struct PreparedScene {
    /// The scene as parsed.
    pub scene: Scene,
    /// Loaded and generated textures.
    textures: Vec<Texture>,
    /// For each primitive, the index of its texture.
    texture_of: Vec<Option<u32>>,
    /// BVH over the bounded primitives, when there are more than [`FLAT_LIMIT`].
    bvh: Bvh,
    /// Primitives tested one by one: the unbounded ones (planes), and all bounded ones too when
    /// there are at most [`FLAT_LIMIT`] (a loop beats a tree walk for a handful of shapes).
    linear: FlatSet,
    /// Rounding-error magnitude of each primitive ([`Shape::magnitude`]).
    magnitudes: Vec<f64>,
    /// Lights with a visible shape: (light index, shape).
    emitters: Vec<(u32, Shape)>,
}

impl PreparedScene {
    /// Loads the textures the scene names (image files through `search`, built-in ones
    /// generated) and builds the acceleration structure. Every unreadable texture is reported.
    pub fn new(scene: Scene, search: &TextureSearch) -> Result<PreparedScene, Vec<Diagnostic>> {
        // Distinct sources, each loaded once, in parallel.
        let mut sources: Vec<&TextureRef> = Vec::new();
        let mut index_of: HashMap<&TextureSource, u32> = HashMap::new();
        let mut texture_of = Vec::with_capacity(scene.primitives.len());
        for p in &scene.primitives {
            texture_of.push(p.material.texture.as_ref().map(|t| {
                *index_of.entry(&t.source).or_insert_with(|| {
                    sources.push(t);
                    sources.len() as u32 - 1
                })
            }));
        }
        let loaded: Vec<Result<Texture, Diagnostic>> = sources
            .par_iter()
            .map(|t| load_texture(&t.source, search).map_err(|e| texture_diagnostic(t, e)))
            .collect();
        let mut textures = Vec::with_capacity(loaded.len());
        let mut errors = Vec::new();
        for r in loaded {
            match r {
                Ok(t) => textures.push(t),
                Err(d) => errors.push(d),
            }
        }
        if !errors.is_empty() {
            return Err(errors);
        }

        let mut bounded: Vec<(u32, Bounds)> = Vec::new();
        let mut linear = Vec::new();
        for (i, p) in scene.primitives.iter().enumerate() {
            match p.shape.bounds() {
                Some(b) => bounded.push((i as u32, b)),
                None => linear.push(i as u32),
            }
        }
        if bounded.len() <= FLAT_LIMIT {
            linear.extend(bounded.drain(..).map(|(i, _)| i));
            linear.sort_unstable();
        }
        let linear = FlatSet::new(&linear, &scene);
        let emitters = scene
            .lights
            .iter()
            .enumerate()
            .filter_map(|(i, l)| match l {
                Light::Point { .. } => None,
                Light::Square { shape, .. } => Some((i as u32, Shape::Square(shape.clone()))),
                Light::Sphere { shape, .. } => Some((i as u32, Shape::Sphere(shape.clone()))),
            })
            .collect();
        let magnitudes = scene.primitives.iter().map(|p| p.shape.magnitude()).collect();
        Ok(PreparedScene {
            bvh: Bvh::build(&bounded),
            linear,
            magnitudes,
            emitters,
            textures,
            texture_of,
            scene,
        })
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
        let t_max = best.map_or(f64::INFINITY, |(_, h)| h.t);
        let prims = &self.scene.primitives;
        self.bvh.closest(ray, 0.0, t_max, |i, limit| {
            let hit = prims[i as usize].shape.intersect(ray, 0.0, limit)?;
            best = Some((i, hit));
            Some(hit.t)
        });
        best
    }

    /// Whether any primitive lies on the ray before distance `t_max` (lights never block).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        let prims = &self.scene.primitives;
        self.linear.any(ray, t_max)
            || self.bvh.any(ray, 0.0, t_max, |i| prims[i as usize].shape.intersect(ray, 0.0, t_max).is_some())
    }

    /// The rounding-error magnitude of primitive `i` (see [`crate::geometry::offset_origin`]).
    #[inline]
    pub fn magnitude(&self, primitive: u32) -> f64 {
        self.magnitudes[primitive as usize]
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
        let point = ray.at(hit.t);
        let outward = self.scene.primitives[primitive as usize].shape.outward_normal(point, hit.part);
        let front = ray.dir.dot(outward) < 0.0;
        let normal = if front { outward } else { -outward };
        let magnitude = self.magnitude(primitive).max(point.abs().max_element());
        Interaction { primitive, t: hit.t, point, outward, normal, front, magnitude, part: hit.part }
    }

    /// The surface colour at an interaction: the primitive's `color=` times its texture there.
    #[inline]
    pub fn surface_color(&self, at: &Interaction) -> DVec3 {
        let p = &self.scene.primitives[at.primitive as usize];
        match self.texture_of[at.primitive as usize] {
            Some(t) => {
                let (u, v) = p.shape.texture_coordinates(at.point, at.part);
                p.material.color * self.textures[t as usize].sample(u, v)
            }
            None => p.material.color,
        }
    }
}

/// A ray's hit on a primitive, as integrators see it (world space, z-up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interaction {
    /// Index into `scene.primitives`.
    pub primitive: u32,
    /// Distance along the ray (its direction is a unit vector).
    pub t: f64,
    /// The hit point.
    pub point: DVec3,
    /// Unit normal pointing out of the shape (for a plane or square, the normal of the file).
    pub outward: DVec3,
    /// Unit normal on the side the ray came from: `outward` for a front hit, `-outward` for a back
    /// hit.
    pub normal: DVec3,
    /// Whether the ray hit the outside (the side `outward` points to).
    pub front: bool,
    /// The rounding-error magnitude that scales the offset of rays leaving the point.
    pub magnitude: f64,
    /// The part of the shape that was hit (for its texture coordinates).
    part: ShapePart,
}

impl Interaction {
    /// A ray leaving the point in direction `dir` (normalised here), started just off the surface
    /// on the side `dir` goes to, so it cannot hit the surface it leaves.
    #[inline]
    pub fn spawn(&self, dir: DVec3) -> Ray {
        let side = if dir.dot(self.normal) >= 0.0 { self.normal } else { -self.normal };
        Ray::new(offset_origin(self.point, side, self.magnitude), dir)
    }

    /// The origin of a shadow ray towards the side the ray came from.
    #[inline]
    pub fn shadow_origin(&self) -> DVec3 {
        offset_origin(self.point, self.normal, self.magnitude)
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
                Shape::Square(q) => set.squares.push((i, q.clone())),
                Shape::Cylinder(c) => set.cylinders.push((i, c.clone())),
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
        best
    }

    /// Whether anything lies on the ray before `t_max`.
    #[inline]
    fn any(&self, ray: &Ray, t_max: f64) -> bool {
        self.spheres.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
            || self.planes.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
            || self.squares.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
            || self.cylinders.iter().any(|(_, s)| s.intersect(ray, 0.0, t_max).is_some())
    }
}

fn load_texture(source: &TextureSource, search: &TextureSearch) -> Result<Texture, TextureError> {
    match source {
        TextureSource::Builtin(b) => Ok(procedural::generate(*b)),
        TextureSource::File(name) => Texture::load(&search.resolve(name)?),
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
