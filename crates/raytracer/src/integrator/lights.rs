//! The lights of the physically based models (spec section 11, made exact), shared by the path
//! tracer and SPPM: what each light emits, how a point samples the light it receives from them
//! (next-event estimation) with the densities multiple importance sampling needs, and how photons
//! leave them.
//!
//! Units: a light's `color=` is read per channel as
//! - `light point`: radiant intensity `I` (irradiance `I cos / d^2` at distance `d`), power
//!   `4 pi I`;
//! - `light square`: radiance `L` leaving **both** faces of the parallelogram (**ours**: the
//!   spec's one-sided reading would leave every course file dark, whose lights face up with
//!   `Dx x Dy` towards the sky), power `2 pi A L` with `A = 4 |Dx x Dy|`;
//! - `light sphere`: radiance `L` leaving its surface outwards, power `4 pi^2 R^2 L`;
//! - the background (`color=`, or the `top=`/`bottom=` gradient): the radiance arriving from every
//!   direction that escapes the scene, an environment light of power `pi R_b^2` times its
//!   integral over the sphere (`R_b` the radius of the scene's bounding sphere).
//!
//! Square and sphere lights are also black bodies: rays and photons that meet their shapes stop
//! there, and they shadow one another. Next-event estimation picks a light in proportion to its
//! power, then a point uniformly on a square's area or in the cone of directions under which a
//! sphere is seen; photons leave the lights and the environment in proportion to their power.

use std::f64::consts::PI;

use glam::DVec3;

use crate::base::color::channel_mean;

use crate::base::sampler::PixelRng;
use crate::base::sampling::{Discrete, cosine_hemisphere, sphere_cone, sphere_cone_pdf, uniform_sphere};
use crate::geometry::{Bounds, Ray, Shape, offset_origin};
use crate::light::Light;
use crate::prepare::PreparedScene;
use crate::scene::Scene;

/// The light a point receives along one sampled direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Index of the light in the scene.
    pub light: u32,
    /// Unit direction from the point towards the light.
    pub wi: DVec3,
    /// The sampled point on the light (the light's position for a point light).
    pub target: DVec3,
    /// Incident radiance along `wi` (for a point light, the irradiance `I / d^2` on a surface
    /// facing it).
    pub radiance: DVec3,
    /// Density of the sample per steradian, the light's choice included; for a point light, the
    /// probability of choosing it.
    pub pdf: f64,
    /// Whether the light is a point (a delta distribution that BSDF sampling cannot hit).
    pub delta: bool,
}

/// A photon leaving a light: its ray and its power (flux).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmittedPhoton {
    /// Where it starts and where it goes.
    pub ray: Ray,
    /// Its power: emitted radiance (or intensity) over the density of the emission sample.
    pub power: DVec3,
    /// Whether the environment sent it (its first hit receives light NEE does not sample).
    pub from_environment: bool,
}

/// The scene's lights, ready to sample.
#[derive(Debug)]
pub struct Lights<'s> {
    scene: &'s PreparedScene,
    /// Next-event estimation: lights chosen by power.
    choose: Discrete,
    /// Photon emission: lights by power, then the environment (last entry).
    emission: Discrete,
    /// The light shapes, which block rays: (light index, shape).
    shapes: Vec<(u32, Shape)>,
    /// The area of each square light (0 for the others).
    areas: Vec<f64>,
    /// The bounding sphere of the scene's bounded objects, lights and camera (centre, radius).
    bounds: (DVec3, f64),
}

/// The power (mean over channels) of each light, in the order of the scene's lights.
pub fn light_powers(scene: &Scene) -> Vec<f64> {
    scene.lights.iter().map(|l| channel_mean(l.color().max(DVec3::ZERO)) * power_factor(l)).collect()
}

/// Power over the radiance (or intensity) of a light.
fn power_factor(light: &Light) -> f64 {
    match light {
        Light::Point { .. } => 4.0 * PI,
        Light::Square { shape, .. } => 2.0 * PI * square_area(&shape.dx, &shape.dy),
        Light::Sphere { shape, .. } => 4.0 * PI * PI * shape.radius * shape.radius,
    }
}

fn square_area(dx: &DVec3, dy: &DVec3) -> f64 {
    4.0 * dx.cross(*dy).length()
}

impl<'s> Lights<'s> {
    /// The lights of `scene`.
    pub fn new(scene: &'s PreparedScene) -> Lights<'s> {
        let s = &scene.scene;
        let powers = light_powers(s);
        let shapes: Vec<(u32, Shape)> =
            s.lights.iter().enumerate().filter_map(|(i, l)| Some((i as u32, l.shape()?))).collect();
        let mut b = Bounds::EMPTY.include(s.camera.eye);
        for p in &s.primitives {
            if let Some(pb) = p.shape.bounds() {
                b = b.union(pb);
            }
        }
        for l in &s.lights {
            b = b.include(l.centre());
        }
        for (_, shape) in &shapes {
            if let Some(sb) = shape.bounds() {
                b = b.union(sb);
            }
        }
        let centre = b.centroid();
        let radius = ((b.max - b.min).length() * 0.5).max(1e-3);
        let env_power = PI * radius * radius * 4.0 * PI * channel_mean(environment_mean(s));
        let mut emission_weights = powers.clone();
        emission_weights.push(env_power);
        let areas = s
            .lights
            .iter()
            .map(|l| match l {
                Light::Square { shape, .. } => square_area(&shape.dx, &shape.dy),
                _ => 0.0,
            })
            .collect();
        Lights {
            scene,
            areas,
            choose: Discrete::new(&powers),
            emission: Discrete::new(&emission_weights),
            shapes,
            bounds: (centre, radius),
        }
    }

    /// Whether there is any light to sample by next-event estimation.
    pub fn any(&self) -> bool {
        !self.choose.is_empty()
    }

    /// The radiance arriving along a ray of unit direction `dir` that escapes the scene.
    #[inline]
    pub fn environment(&self, dir: DVec3) -> DVec3 {
        self.scene.scene.background.miss_color(dir)
    }

    /// The radiance a ray that hits light `light` at distance `t` sees (the light's colour on
    /// either face of a square, on the outside of a sphere).
    #[inline]
    pub fn emitted(&self, light: u32, ray: &Ray, t: f64) -> DVec3 {
        let l = &self.scene.scene.lights[light as usize];
        match l {
            Light::Point { .. } => DVec3::ZERO,
            Light::Square { color, .. } => *color,
            Light::Sphere { shape, color } => {
                let n = ray.at(t) - shape.centre;
                if n.dot(ray.dir) < 0.0 { *color } else { DVec3::ZERO }
            }
        }
    }

    /// A light sample for the point `p` from uniform numbers: `u` chooses the light, `u1`, `u2`
    /// the point on it. `None` when nothing was chosen or the point cannot see the sample.
    pub fn sample(&self, p: DVec3, u: f64, u1: f64, u2: f64) -> Option<LightSample> {
        let (index, p_light) = self.choose.sample(u)?;
        let light = &self.scene.scene.lights[index];
        let light_index = index as u32;
        match light {
            Light::Point { position, color } => {
                let to = *position - p;
                let d2 = to.length_squared();
                (d2 > 0.0).then(|| LightSample {
                    light: light_index,
                    wi: to / d2.sqrt(),
                    target: *position,
                    radiance: *color / d2,
                    pdf: p_light,
                    delta: true,
                })
            }
            Light::Square { shape, color } => {
                let target = shape.point_at(2.0 * u1 - 1.0, 2.0 * u2 - 1.0);
                let to = target - p;
                let d2 = to.length_squared();
                let wi = to / d2.sqrt();
                let cos = shape.normal.dot(wi).abs();
                if cos <= 1e-12 || d2 <= 0.0 {
                    return None;
                }
                let area = self.areas[index];
                Some(LightSample {
                    light: light_index,
                    wi,
                    target,
                    radiance: *color,
                    pdf: p_light * d2 / (area * cos),
                    delta: false,
                })
            }
            Light::Sphere { shape, color } => {
                // From inside, none: the surface emits outwards only.
                let (wi, t, pdf) = sphere_cone(p, shape.centre, shape.radius, u1, u2)?;
                Some(LightSample {
                    light: light_index,
                    wi,
                    target: p + wi * t,
                    radiance: *color,
                    pdf: p_light * pdf,
                    delta: false,
                })
            }
        }
    }

    /// The density (per steradian, the light's choice included) with which [`Lights::sample`]
    /// at `p` produces the direction `dir` that meets light `light` at distance `t`.
    pub fn pdf(&self, light: u32, p: DVec3, dir: DVec3, t: f64) -> f64 {
        let p_light = self.choose.pmf(light as usize);
        if p_light <= 0.0 {
            return 0.0;
        }
        match &self.scene.scene.lights[light as usize] {
            Light::Point { .. } => 0.0,
            Light::Square { shape, .. } => {
                let cos = shape.normal.dot(dir).abs();
                if cos <= 1e-12 {
                    return 0.0;
                }
                p_light * t * t / (self.areas[light as usize] * cos)
            }
            Light::Sphere { shape, .. } => p_light * sphere_cone_pdf(p, shape.centre, shape.radius),
        }
    }

    /// Whether nothing blocks the segment from `origin` to the sample's point on the light:
    /// no primitive and no other light's shape. Counts the ray in `rays`.
    pub fn unoccluded(&self, origin: DVec3, target: DVec3, rays: &mut u64) -> bool {
        *rays += 1;
        let to = target - origin;
        let dist = to.length();
        if dist.is_nan() || dist <= 0.0 {
            return true;
        }
        let ray = Ray { origin, dir: to / dist };
        // Stop just short of the light's own surface.
        let t_max = dist * (1.0 - 1e-7);
        !self.scene.occluded(&ray, t_max)
            && !self.shapes.iter().any(|(_, s)| s.intersect(&ray, 0.0, t_max).is_some())
    }

    /// A photon leaving a light or the environment, chosen in proportion to their power; `None`
    /// when the scene emits nothing.
    pub fn emit(&self, rng: &mut PixelRng) -> Option<EmittedPhoton> {
        let (index, p_choice) = self.emission.sample(rng.uniform())?;
        let lights = &self.scene.scene.lights;
        if index == lights.len() {
            return Some(self.emit_from_environment(rng, p_choice));
        }
        let light = &lights[index];
        let color = light.color().max(DVec3::ZERO);
        let power = color * (power_factor(light) / p_choice);
        let (origin, dir) = match light {
            Light::Point { position, .. } => (*position, uniform_sphere(rng.uniform(), rng.uniform())),
            Light::Square { shape, .. } => {
                let point = shape.point_at(2.0 * rng.uniform() - 1.0, 2.0 * rng.uniform() - 1.0);
                let side = if rng.uniform() < 0.5 { shape.normal } else { -shape.normal };
                let magnitude = (shape.centre.abs().max_element() + shape.dx.length() + shape.dy.length())
                    .max(point.abs().max_element());
                let dir = cosine_hemisphere(side, rng.uniform(), rng.uniform());
                (offset_origin(point, side, magnitude), dir)
            }
            Light::Sphere { shape, .. } => {
                let n = uniform_sphere(rng.uniform(), rng.uniform());
                let point = shape.centre + shape.radius * n;
                let magnitude = shape.centre.abs().max_element() + shape.radius;
                let dir = cosine_hemisphere(n, rng.uniform(), rng.uniform());
                (offset_origin(point, n, magnitude), dir)
            }
        };
        Some(EmittedPhoton { ray: Ray::new(origin, dir), power, from_environment: false })
    }

    /// A photon from the environment: the direction it comes from uniform over the sphere, its
    /// start uniform on the disc of the scene's bounding sphere facing that direction.
    fn emit_from_environment(&self, rng: &mut PixelRng, p_choice: f64) -> EmittedPhoton {
        let (centre, radius) = self.bounds;
        let from = uniform_sphere(rng.uniform(), rng.uniform());
        let (t, b) = crate::base::sampling::orthonormal_basis(from);
        let r = radius * rng.uniform().sqrt();
        let phi = std::f64::consts::TAU * rng.uniform();
        let origin = centre + from * radius + (t * phi.cos() + b * phi.sin()) * r;
        let density = p_choice / (4.0 * PI) / (PI * radius * radius);
        EmittedPhoton {
            ray: Ray::new(origin, -from),
            power: self.environment(from) / density,
            from_environment: true,
        }
    }
}

/// The mean over all directions of the background's radiance.
fn environment_mean(scene: &Scene) -> DVec3 {
    match scene.background.gradient {
        // t = (z + 1) / 2 is uniform over the sphere, so the mean is the middle of the gradient.
        Some(g) => (g.bottom + g.top) * 0.5,
        None => scene.background.color,
    }
    .max(DVec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::sampling::chi_square::{check, integral};
    use crate::geometry::test_util::TestRng;
    use crate::scene::{SourceFile, parse};

    fn scene(text: &str) -> PreparedScene {
        let parsed = parse(&SourceFile::from_text("t.txt", None, text.to_owned())).expect("parses");
        PreparedScene::new(parsed.scene, &Default::default()).expect("prepares")
    }

    const SQUARE: &str = "light square\n O= 0.3 0.2 2\n Dx= 0.6 0 0.2\n Dy= 0 0.4 0\n color= 2 2 2\nend\n";
    const SPHERE: &str = "light sphere\n O= -1 0.5 1.5\n R= 0.7\n color= 1 2 3\nend\n";
    const POINT: &str = "light point\n O= 0 0 3\n color= 5 5 5\nend\n";

    #[test]
    fn light_sampling_follows_its_density_and_the_density_integrates_to_one() {
        let s = scene(&format!("{SQUARE}{SPHERE}"));
        let lights = Lights::new(&s);
        let p = DVec3::new(0.1, -0.2, 0.0);
        let mut rng = TestRng::new(3);
        // The density of a direction: the sum over the lights it meets (only the nearest, as a
        // ray would).
        let pdf = |dir: DVec3| -> f64 {
            let ray = Ray::new(p, dir);
            lights
                .shapes
                .iter()
                .filter_map(|(l, shape)| shape.intersect(&ray, 0.0, f64::INFINITY).map(|h| (*l, h.t)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map_or(0.0, |(l, t)| lights.pdf(l, p, dir, t))
        };
        check(
            "square and sphere lights",
            300_000,
            |_| lights.sample(p, rng.uniform(), rng.uniform(), rng.uniform()).map(|s| s.wi),
            pdf,
        );
        // The lights do not overlap as seen from p, so the density integrates to 1.
        let total = integral(pdf);
        assert!((total - 1.0).abs() < 5e-3, "{total}");
    }

    #[test]
    fn samples_report_the_density_of_their_direction() {
        let s = scene(&format!("{SQUARE}{SPHERE}{POINT}"));
        let lights = Lights::new(&s);
        let p = DVec3::new(0.5, 0.0, 0.2);
        let mut rng = TestRng::new(9);
        for _ in 0..1000 {
            let Some(sample) = lights.sample(p, rng.uniform(), rng.uniform(), rng.uniform()) else {
                continue;
            };
            if sample.delta {
                assert_eq!(sample.radiance, DVec3::splat(5.0) / (sample.target - p).length_squared());
                continue;
            }
            let t = (sample.target - p).length();
            let pdf = lights.pdf(sample.light, p, sample.wi, t);
            assert!((pdf - sample.pdf).abs() <= 1e-9 * pdf, "{pdf} vs {}", sample.pdf);
        }
    }

    #[test]
    fn lights_are_chosen_and_emit_by_power() {
        let s = scene(&format!("{SQUARE}{POINT}"));
        let powers = light_powers(&s.scene);
        let area = 4.0 * DVec3::new(0.6, 0.0, 0.2).cross(DVec3::new(0.0, 0.4, 0.0)).length();
        assert!((powers[0] - 2.0 * PI * area * 2.0).abs() < 1e-12);
        assert!((powers[1] - 4.0 * PI * 5.0).abs() < 1e-12);
        let lights = Lights::new(&s);
        assert!((lights.choose.pmf(0) - powers[0] / (powers[0] + powers[1])).abs() < 1e-12);
        // Every photon carries (on average, exactly for grey lights) the total power.
        let mut rng = PixelRng::from_key(4);
        for _ in 0..100 {
            let photon = lights.emit(&mut rng).expect("a photon");
            assert!((photon.power.x - (powers[0] + powers[1])).abs() < 1e-9, "{}", photon.power);
        }
    }

    #[test]
    fn a_sphere_light_is_seen_from_outside_only_and_squares_from_both_sides() {
        let s = scene(&format!("{SQUARE}{SPHERE}"));
        let lights = Lights::new(&s);
        let outside = Ray::new(DVec3::new(-1.0, 0.5, 5.0), -DVec3::Z);
        assert_eq!(lights.emitted(1, &outside, 5.0 - 1.5 - 0.7), DVec3::new(1.0, 2.0, 3.0));
        let inside = Ray::new(DVec3::new(-1.0, 0.5, 1.5), DVec3::Z);
        assert_eq!(lights.emitted(1, &inside, 0.7), DVec3::ZERO);
        assert!(lights.sample(DVec3::new(-1.0, 0.5, 1.5), 0.99, 0.5, 0.5).is_none());
        for dir in [DVec3::Z, -DVec3::Z] {
            let ray = Ray::new(DVec3::new(0.3, 0.2, 2.0) - dir, dir);
            assert_eq!(lights.emitted(0, &ray, 1.0), DVec3::splat(2.0));
        }
    }

    #[test]
    fn light_shapes_block_shadow_rays() {
        let s = scene(&format!("{SPHERE}{POINT}"));
        let lights = Lights::new(&s);
        let mut rays = 0;
        // The sphere light lies between (-1, 0.5, -1) and (-1, 0.5, 3).
        assert!(!lights.unoccluded(DVec3::new(-1.0, 0.5, -1.0), DVec3::new(-1.0, 0.5, 3.0), &mut rays));
        assert!(lights.unoccluded(DVec3::new(2.0, 0.5, -1.0), DVec3::new(0.0, 0.0, 3.0), &mut rays));
        assert_eq!(rays, 2);
    }

    #[test]
    fn environment_photons_carry_its_power() {
        let s = scene(
            "background\n color= 0.5 0.5 0.5\nend\nprimitive sphere\n O= 0 0 0\n R= 1\n diff= 1\nend\n",
        );
        let lights = Lights::new(&s);
        assert!(!lights.any(), "the environment is not sampled by next-event estimation");
        let (_, radius) = lights.bounds;
        let mut rng = PixelRng::from_key(1);
        let photon = lights.emit(&mut rng).expect("a photon");
        assert!(photon.from_environment);
        let power = PI * radius * radius * 4.0 * PI * 0.5;
        assert!((photon.power.x - power).abs() < 1e-9 * power);
        assert!(photon.ray.dir.dot(photon.ray.origin - lights.bounds.0) < 0.0, "it travels inwards");
    }
}
