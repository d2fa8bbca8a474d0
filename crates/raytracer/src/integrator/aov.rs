//! Auxiliary images (AOVs) of a render, for a denoiser and for inspection: at the first
//! non-specular surface a camera ray meets, its albedo, its shading normal and the distance to
//! it.
//!
//! Every pixel averages [`DEFAULT_AOV_SAMPLES`] (or the caller's count) camera rays jittered over
//! the pixel (and the lens), each drawn from its own stream ([`stream::AOV`], keyed like the path
//! model's samples by seed, pixel and sample index), so the images are the same bytes at any
//! thread count. A ray is followed through perfect specular surfaces (mirrors, the smooth
//! dielectric of glass) by sampling their delta lobes, up to [`MAX_SPECULAR_BOUNCES`], to the first
//! surface with a diffuse or glossy lobe. There:
//! - **albedo** is that surface's diffuse plus glossy reflectance ([`Bsdf::smooth_albedo`]: the
//!   colour, texture applied, times the lobes' weights, in [0, 1]) times the tint of the specular
//!   surfaces on the way (a white mirror passes what it reflects unchanged), clamped to [0, 1];
//! - **normal** is the unit shading normal facing the viewer (world space, z-up);
//! - **depth** is the length of the path from the camera to it (through mirrors: the distance of
//!   the reflection, as a photograph of a mirror would focus).
//!
//! A ray that escapes has the background colour there as albedo (clamped to [0, 1]), a zero
//! normal and a zero depth; one that hits a light's shape has the light's colour scaled to a
//! largest channel of at most 1, a zero normal and the distance. A path that is still specular
//! after [`MAX_SPECULAR_BOUNCES`] bounces has a zero albedo and the last surface's normal.

use glam::DVec3;
use rayon::prelude::*;

use crate::base::sampler::{PixelRng, stream};
use crate::camera::Camera;
use crate::geometry::Ray;
use crate::integrator::bsdf::{Bsdf, Transport, class};
use crate::integrator::bsdfs::PhysicalBsdf;
use crate::integrator::emitters::Emitters;
use crate::integrator::lights::Lights;
use crate::prepare::{Hit, PreparedScene};

/// Camera rays a pixel when the caller has no preference.
pub const DEFAULT_AOV_SAMPLES: u32 = 16;
/// Most perfect specular bounces followed before a path gives up.
pub const MAX_SPECULAR_BOUNCES: u32 = 16;

/// The auxiliary images of a render, `width * height` pixels each, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Aovs {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB albedo, each channel in [0, 1].
    pub albedo: Vec<[f32; 3]>,
    /// Mean of the unit shading normals (world space, z-up); shorter than 1 where the samples
    /// saw different surfaces, zero where they saw none.
    pub normal: Vec<[f32; 3]>,
    /// Mean distance along the camera path, in scene units (0 for the background).
    pub depth: Vec<f32>,
}

/// What one camera ray finds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Sample {
    albedo: DVec3,
    normal: DVec3,
    depth: f64,
}

/// Follows `ray` through perfect specular surfaces to the first smooth one (see the module notes).
fn follow(
    scene: &PreparedScene,
    lights: &Lights<'_>,
    emitters: Option<&Emitters<'_>>,
    mut ray: Ray,
    rng: &mut PixelRng,
) -> Sample {
    let mut tint = DVec3::ONE;
    let mut depth = 0.0;
    let mut last_normal = DVec3::ZERO;
    for _ in 0..=MAX_SPECULAR_BOUNCES {
        let (primitive, hit) = match scene.closest_hit(&ray) {
            Hit::Miss => {
                let background = match emitters {
                    Some(e) => e.environment(ray.dir),
                    None => lights.environment(ray.dir),
                }
                .clamp(DVec3::ZERO, DVec3::ONE);
                return Sample {
                    albedo: (tint * background).min(DVec3::ONE),
                    normal: DVec3::ZERO,
                    depth: 0.0,
                };
            }
            Hit::Emitter { light, t } => {
                let le = lights.emitted(light, &ray, t).max(DVec3::ZERO);
                let albedo = le / le.max_element().max(1.0);
                return Sample {
                    albedo: (tint * albedo).min(DVec3::ONE),
                    normal: DVec3::ZERO,
                    depth: depth + t,
                };
            }
            Hit::Surface { primitive, hit } => (primitive, hit),
        };
        let at = scene.interaction(&ray, primitive, hit);
        depth += at.t;
        last_normal = at.normal;
        if scene.material(primitive).as_course().is_none() {
            // A physically based material: the albedo of its lobes as seen from the front.
            let bsdf = PhysicalBsdf::new(scene.material(primitive), &mut |p| scene.param(p, &at));
            let albedo = (tint * bsdf.albedo()).clamp(DVec3::ZERO, DVec3::ONE);
            return Sample { albedo, normal: at.normal, depth };
        }
        let bsdf = Bsdf::new(scene.course_material(primitive), scene.surface_color(&at), &at);
        if bsdf.has(class::SMOOTH) || !bsdf.has(class::SPECULAR) {
            // A surface with a diffuse or glossy lobe, or one that does not scatter at all
            // (black): the albedo is what it reflects smoothly.
            let albedo = (tint * bsdf.smooth_albedo()).clamp(DVec3::ZERO, DVec3::ONE);
            return Sample { albedo, normal: at.normal, depth };
        }
        let (u, u1, u2) = (rng.uniform(), rng.uniform(), rng.uniform());
        // Importance transport: a refracted direction's weight is not scaled by 1 / eta^2, which
        // is a radiance effect, not a colour of the surface.
        let Some(s) = bsdf.sample(-ray.dir, u, u1, u2, class::SPECULAR, Transport::Importance) else {
            return Sample { albedo: DVec3::ZERO, normal: at.normal, depth };
        };
        tint = (tint * s.weight).min(DVec3::ONE);
        ray = at.spawn(s.wi);
    }
    Sample { albedo: DVec3::ZERO, normal: last_normal, depth }
}

/// The auxiliary images of `scene` seen through `camera` at `width x height` pixels, each pixel
/// the mean of `samples` (at least 1) camera rays of render seed `seed` (see the module notes).
/// Runs on the current rayon pool; the result does not depend on its size.
pub fn render_aovs(
    scene: &PreparedScene,
    camera: &Camera,
    width: u32,
    height: u32,
    seed: u64,
    samples: u32,
) -> Aovs {
    let lights = Lights::new(scene);
    let emitters = scene.is_physical().then(|| Emitters::new(scene));
    let samples = samples.max(1);
    let w = width as usize;
    let mut pixels = vec![Sample::default(); w * height as usize];
    if w > 0 {
        pixels.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, pixel) in row.iter_mut().enumerate() {
                let mut sum = Sample::default();
                for s in 0..samples {
                    let mut rng = PixelRng::for_sample(seed, stream::AOV, x as u32, y as u32, s as u64);
                    let (dx, dy) = (rng.uniform(), rng.uniform());
                    let lens = if camera.has_lens() { (rng.uniform(), rng.uniform()) } else { (0.0, 0.0) };
                    let found = follow(
                        scene,
                        &lights,
                        emitters.as_ref(),
                        camera.ray(x as f64 + dx, y as f64 + dy, lens),
                        &mut rng,
                    );
                    sum.albedo += found.albedo;
                    sum.normal += found.normal;
                    sum.depth += found.depth;
                }
                let n = samples as f64;
                *pixel = Sample { albedo: sum.albedo / n, normal: sum.normal / n, depth: sum.depth / n };
            }
        });
    }
    Aovs {
        width,
        height,
        albedo: pixels.iter().map(|p| p.albedo.as_vec3().to_array()).collect(),
        normal: pixels.iter().map(|p| p.normal.as_vec3().to_array()).collect(),
        depth: pixels.iter().map(|p| p.depth as f32).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{SourceFile, parse};

    fn scene(text: &str) -> PreparedScene {
        let parsed = parse(&SourceFile::from_text("t.txt", None, text.to_owned())).expect("parses");
        PreparedScene::new(parsed.scene, &Default::default()).expect("prepares")
    }

    /// A camera at `eye` looking along `dir`.
    fn camera(eye: &str, dir: &str) -> String {
        format!("camera\n O= {eye}\n N= {dir}\n lens_W= 0.2\n lens_H= 0.2\n image_W= 8\n image_H= 8\nend\n")
    }

    fn aovs(text: &str, threads: usize) -> Aovs {
        let s = scene(text);
        let cam = Camera::new(&s.scene.camera, 8, 8, 1.0);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a pool");
        pool.install(|| render_aovs(&s, &cam, 8, 8, 3, 4))
    }

    const RED_FLOOR: &str =
        "primitive plane\n N= 0 0 1\n R= 0\n color= 1 0.2 0.1\n diff= 0.5\n spec= 0.25\nend\n";

    #[test]
    fn a_diffuse_floor_gives_its_albedo_normal_and_distance() {
        let text = format!("{}{RED_FLOOR}", camera("0 0 2", "0 0 -1"));
        let a = aovs(&text, 1);
        for (i, ((albedo, normal), depth)) in a.albedo.iter().zip(&a.normal).zip(&a.depth).enumerate() {
            // diff + spec = 0.75 of the colour.
            let want = [0.75f32, 0.15, 0.075];
            for c in 0..3 {
                assert!((albedo[c] - want[c]).abs() < 1e-6, "pixel {i}: {albedo:?}");
            }
            assert_eq!(*normal, [0.0, 0.0, 1.0], "pixel {i}");
            // Looking straight down from height 2 through a narrow lens: about 2.
            assert!((*depth - 2.0).abs() < 0.02, "pixel {i}: {depth}");
        }
    }

    #[test]
    fn a_mirror_shows_the_albedo_of_what_it_reflects() {
        // A white mirror facing the camera at y = 2, the red floor's colour behind the camera
        // replaced by a green wall at y = -3 that the mirror reflects.
        let text = format!(
            "{}primitive plane\n N= 0 -1 0\n R= -2\n color= 1 1 1\n refl= 1\nend\n\
             primitive plane\n N= 0 1 0\n R= -3\n color= 0.1 0.9 0.2\n diff= 1\nend\n",
            camera("0 0 0", "0 1 0")
        );
        let a = aovs(&text, 1);
        for (albedo, normal) in a.albedo.iter().zip(&a.normal) {
            assert_eq!(*albedo, [0.1, 0.9, 0.2]);
            assert_eq!(*normal, [0.0, 1.0, 0.0], "the wall's normal, facing the mirror");
        }
        for depth in &a.depth {
            // 2 to the mirror, 5 back to the wall.
            assert!((*depth - 7.0).abs() < 0.1, "{depth}");
        }
    }

    #[test]
    fn misses_give_the_background_and_a_zero_normal() {
        let text = format!("{}background\n color= 0.2 0.4 3\nend\n", camera("0 0 0", "0 1 0"));
        let a = aovs(&text, 1);
        assert!(a.albedo.iter().all(|p| *p == [0.2, 0.4, 1.0]), "{:?}", a.albedo[0]);
        assert!(a.normal.iter().all(|p| *p == [0.0; 3]));
        assert!(a.depth.iter().all(|d| *d == 0.0));
    }

    #[test]
    fn the_same_bytes_at_any_thread_count() {
        // Glass over the red floor: the dielectric's choice between reflection and refraction
        // draws random numbers, as does the jitter.
        let text = format!(
            "{}{RED_FLOOR}primitive sphere\n O= 0.1 0 0.5\n R= 0.4\n color= 1 1 1\n refr= 1\n rindex= 1.5\nend\n\
             background\n color= 0.3 0.3 0.5\nend\n",
            camera("0 -1.2 1.6", "0 1 -1")
        );
        let one = aovs(&text, 1);
        assert_eq!(one, aovs(&text, 2));
        assert_eq!(one, aovs(&text, 3));
        assert!(one.albedo.iter().any(|p| p[1] != one.albedo[0][1]), "the picture is not uniform");
    }
}
