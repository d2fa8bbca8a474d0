//! The course's photon mapper (spec section 10), exactly: photons emitted in proportion to each
//! light's power, traced with Russian roulette between diffuse, mirror and refraction, stored on
//! diffuse surfaces; then camera rays traced as in the classic model, with the local light of a
//! diffuse hit read from the photon map's k-nearest irradiance estimate (see
//! [`crate::integrator::Classic::with_photons`]).
//!
//! Conventions: world z-up; colours linear RGB; `Power(c) = (r + g + b) / 3`. A photon's power is
//! in units where every photon of the scene has `Power = total`, the sum of the lights' powers, and
//! the estimate divides by `emit_photons` (the count the scene asks for), as the course's renderer
//! does.
//!
//! Deterministic: photon `i` draws from its own random stream (its index and the seed), photons
//! are stored in index order (a photon's stored hits in path order), and the map keeps the first
//! `max_photons` of them; tracing stops once it is full, which gives the same map as tracing them
//! all. The image is the same bit for bit whatever the thread count.
//!
//! **Ours**, where the spec leaves a choice: the lights' photons are interleaved (photon `i`
//! belongs to the light whose share holds `i * a mod N`, `a` coprime with `N` near the golden
//! section of `N`), so that when the map fills up early every light is in it in proportion to its
//! power (the course's renderer emitted light after light, so a full map missed the last lights).
//! The roulette draws one uniform `xi` and compares it with the running sums of the three
//! probabilities, which gives each choice the same probability as the course's renderer's three
//! draws.

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

pub use crate::base::memory::format_bytes;
use crate::base::rows::Rows;
use crate::base::sampler::{PixelRng, hash_values};
use crate::base::sampling::{cosine_hemisphere, uniform_sphere, uniform_sphere_point};
use crate::geometry::Ray;
use crate::integrator::adaptive::{AdaptiveSampler, PixelSampling};
use crate::integrator::classic::Classic;
use crate::integrator::course_lobes::{GlossyLobe, MAX_DEPTH, refract};
use crate::integrator::photon_map::{BYTES_PER_PHOTON, Photon, PhotonMap};
pub use crate::integrator::photon_map::{MIN_PHOTONS, PhotonEstimate};
pub use crate::integrator::report::PhotonStats;
use crate::integrator::report::{Progress, RenderStats, Stage};
use crate::light::Light;
use crate::material::CourseMaterial;
use crate::prepare::PreparedScene;
use crate::scene::{Diagnostic, PhotonSettings, Severity};

/// Photons traced between two progress reports (and checks of whether the map is full).
const BATCH: u64 = 1 << 16;
/// Photons a worker traces in one go.
const CHUNK: u64 = 1 << 10;
/// Stream code of photon random numbers (kept apart from the pixels' streams).
const PHOTON_STREAM: u64 = 0x7068_6f74_6f6e;

/// The power of a colour: the mean of its channels.
#[inline]
pub fn power(c: DVec3) -> f64 {
    (c.x + c.y + c.z) / 3.0
}

/// How many photons each light emits and which light a photon belongs to.
#[derive(Clone, Debug, PartialEq)]
pub struct EmissionPlan {
    /// Photons of each light (same order as the scene's lights).
    pub counts: Vec<u64>,
    /// `cumulative[l]` = photons of lights `0..=l`.
    cumulative: Vec<u64>,
    /// Sum of the lights' powers.
    pub total_power: f64,
    /// The multiplier of the interleaving permutation.
    multiplier: u64,
}

impl EmissionPlan {
    /// Shares `photons` among `lights` in proportion to their power (largest remainders, so the
    /// counts sum to `photons` exactly). Lights without power emit nothing.
    pub fn new(lights: &[Light], photons: u64) -> EmissionPlan {
        let powers: Vec<f64> = lights.iter().map(|l| power(l.color()).max(0.0)).collect();
        let total_power: f64 = powers.iter().sum();
        let mut counts = vec![0u64; lights.len()];
        if total_power > 0.0 && photons > 0 {
            let exact: Vec<f64> = powers.iter().map(|p| p / total_power * photons as f64).collect();
            for (c, e) in counts.iter_mut().zip(&exact) {
                *c = e.floor() as u64;
            }
            let mut left = photons.saturating_sub(counts.iter().sum());
            let mut order: Vec<usize> = (0..lights.len()).filter(|&l| powers[l] > 0.0).collect();
            order.sort_by(|&a, &b| (exact[b] - exact[b].floor()).total_cmp(&(exact[a] - exact[a].floor())));
            for &l in order.iter().cycle() {
                if left == 0 {
                    break;
                }
                counts[l] += 1;
                left -= 1;
            }
        }
        let cumulative = counts
            .iter()
            .scan(0u64, |sum, &c| {
                *sum += c;
                Some(*sum)
            })
            .collect();
        EmissionPlan { counts, cumulative, total_power, multiplier: interleave_multiplier(photons) }
    }

    /// Photons emitted in all.
    pub fn photons(&self) -> u64 {
        self.cumulative.last().copied().unwrap_or(0)
    }

    /// The light photon `i` (of `0..photons()`) belongs to.
    #[inline]
    pub fn light_of(&self, i: u64) -> usize {
        let n = self.photons();
        let j = ((i as u128 * self.multiplier as u128) % n as u128) as u64;
        self.cumulative.partition_point(|&c| c <= j)
    }
}

/// A multiplier `a` coprime with `n` near `n (sqrt 5 - 1) / 2`: `i -> i a mod n` is then a
/// permutation of `0..n` that spreads every run of consecutive indices evenly.
fn interleave_multiplier(n: u64) -> u64 {
    if n <= 2 {
        return 1;
    }
    let mut a = ((n as f64 * 0.618_033_988_749_894_9) as u64).clamp(1, n - 1);
    while gcd(a, n) != 1 {
        a += 1;
    }
    a
}

fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// What the roulette does with a photon at a hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scatter {
    /// Bounces diffusely (probability `(diff + spec) Power(colour)`).
    Diffuse,
    /// Bounces off the mirror, jittered by the glossy lobe (probability `refl Power(colour)`).
    Mirror,
    /// Refracts (probability `refr`, times `Power(T)` when leaving the object).
    Refract,
    /// Is absorbed.
    Absorb,
}

/// The roulette of spec section 10 for one uniform `xi` in [0, 1): `colour` is the surface colour
/// (texture included), `transmittance` the Beer factor `T` of the path inside when the photon
/// leaves the object (`None` when it enters or the surface is not transparent).
pub fn roulette(material: &CourseMaterial, colour: DVec3, transmittance: Option<DVec3>, xi: f64) -> Scatter {
    let p = power(colour);
    let diffuse = ((material.diff + material.spec) * p).max(0.0);
    let mirror = (material.refl * p).max(0.0);
    let refract = (material.refr * transmittance.map_or(1.0, power)).max(0.0);
    if xi < diffuse {
        Scatter::Diffuse
    } else if xi < diffuse + mirror {
        Scatter::Mirror
    } else if xi < diffuse + mirror + refract {
        Scatter::Refract
    } else {
        Scatter::Absorb
    }
}

/// The origin and direction of a photon of `light` (spec section 10): a point light emits from its
/// position, a square light from a uniform point of its area, both in a uniform direction over
/// the whole sphere; a sphere light (**ours**) from a uniform point of its surface, in a
/// cosine-distributed direction outward.
pub fn emit(light: &Light, rng: &mut PixelRng) -> Ray {
    match light {
        Light::Point { position, .. } => Ray::new(*position, uniform_sphere(rng.uniform(), rng.uniform())),
        Light::Square { shape, .. } => {
            let origin = shape.point_at(2.0 * rng.uniform() - 1.0, 2.0 * rng.uniform() - 1.0);
            Ray::new(origin, uniform_sphere(rng.uniform(), rng.uniform()))
        }
        Light::Sphere { shape, .. } => {
            let (origin, normal) =
                uniform_sphere_point(shape.centre, shape.radius, rng.uniform(), rng.uniform());
            Ray::new(origin, cosine_hemisphere(normal, rng.uniform(), rng.uniform()))
        }
    }
}

/// Bytes of memory a photon map of `max_photons` photons may need.
pub fn map_bytes(max_photons: u64) -> u64 {
    max_photons.saturating_mul(BYTES_PER_PHOTON)
}

/// Refuses photon settings whose map could need more than `limit` bytes, before anything is
/// allocated. The error points at `max_photons=` when the file sets it.
pub fn check_memory(settings: &PhotonSettings, limit: u64) -> Result<(), Diagnostic> {
    let bytes = map_bytes(settings.max_photons);
    if bytes <= limit {
        return Ok(());
    }
    let message = format!(
        "a photon map of {} photons would need {} of memory, over the limit of {}",
        settings.max_photons,
        format_bytes(bytes),
        format_bytes(limit)
    );
    let note = format!(
        "{BYTES_PER_PHOTON} bytes a stored photon; lower `max_photons=` to at most {}",
        limit / BYTES_PER_PHOTON
    );
    Err(Diagnostic {
        severity: Severity::Error,
        message,
        location: settings.location_of("max_photons").cloned(),
        notes: vec![note],
    })
}

/// Traces the photons of spec section 10 and builds the map. `progress(done, total)` is called
/// from the calling thread after each batch of photons.
pub fn build_photon_map(
    scene: &PreparedScene,
    settings: &PhotonSettings,
    seed: u64,
    progress: &dyn Fn(u64, u64),
) -> (PhotonMap, PhotonStats) {
    let started = Instant::now();
    let plan = EmissionPlan::new(&scene.scene.lights, settings.emit_photons);
    let tracer = Tracer { scene, plan: &plan, seed };
    let total = plan.photons();
    let max = settings.max_photons;
    let mut stored: Vec<Photon> = Vec::new();
    let (mut emitted, mut rays) = (0u64, 0u64);
    progress(0, total);
    while emitted < total && (stored.len() as u64) < max {
        let end = (emitted + BATCH).min(total);
        let chunks: Vec<(Vec<Photon>, u64)> = (emitted..end)
            .step_by(CHUNK as usize)
            .collect::<Vec<u64>>()
            .into_par_iter()
            .map(|start| tracer.trace_range(start, (start + CHUNK).min(end)))
            .collect();
        stored.reserve(chunks.iter().map(|(c, _)| c.len()).sum());
        for (photons, chunk_rays) in chunks {
            rays += chunk_rays;
            let room = (max - stored.len() as u64) as usize;
            stored.extend_from_slice(&photons[..photons.len().min(room)]);
        }
        emitted = end;
        progress(emitted, total);
    }
    let trace_time = started.elapsed();
    let built = Instant::now();
    let map = PhotonMap::build(stored);
    let stats = PhotonStats {
        requested: settings.emit_photons,
        emitted,
        stored: map.len() as u64,
        rays,
        trace_time,
        build_time: built.elapsed(),
        map_bytes: map.memory_bytes() as u64,
    };
    (map, stats)
}

/// Traces photons.
struct Tracer<'a> {
    scene: &'a PreparedScene,
    plan: &'a EmissionPlan,
    seed: u64,
}

impl Tracer<'_> {
    /// Traces photons `start..end`; returns their stored photons in order and the rays traced.
    fn trace_range(&self, start: u64, end: u64) -> (Vec<Photon>, u64) {
        let mut out = Vec::new();
        let mut rays = 0;
        for i in start..end {
            rays += self.trace(i, &mut out);
        }
        (out, rays)
    }

    /// Traces photon `i`, appending what it stores to `out`; returns the rays traced.
    fn trace(&self, i: u64, out: &mut Vec<Photon>) -> u64 {
        let scene = self.scene;
        let mut rng = PixelRng::from_key(hash_values(&[self.seed, PHOTON_STREAM, i]));
        let light = &scene.scene.lights[self.plan.light_of(i)];
        let colour = light.color();
        let mut flux = colour / power(colour) * self.plan.total_power;
        let mut ray = emit(light, &mut rng);
        let mut rays = 0;
        for _depth in 1..=MAX_DEPTH {
            rays += 1;
            let Some((primitive, hit)) = scene.closest_surface(&ray) else { break };
            let at = scene.interaction(&ray, primitive, hit);
            let material = scene.course_material(primitive);
            if material.diff > 0.0 {
                out.push(Photon {
                    position: at.point.as_vec3(),
                    direction: ray.dir.as_vec3(),
                    power: flux.as_vec3(),
                });
            }
            let surface = if material.diff > 0.0 || material.spec > 0.0 || material.refl > 0.0 {
                scene.surface_color(&at)
            } else {
                DVec3::ZERO
            };
            let transmittance = (!at.front && material.refr > 0.0).then(|| (-material.absor * at.t).exp());
            let dir = match roulette(material, surface, transmittance, rng.uniform()) {
                Scatter::Diffuse => {
                    flux *= surface / power(surface);
                    cosine_hemisphere(at.normal, rng.uniform(), rng.uniform())
                }
                Scatter::Mirror => {
                    flux *= surface / power(surface);
                    let reflected = ray.dir - 2.0 * ray.dir.dot(at.normal) * at.normal;
                    if material.drefl > 0.0 {
                        GlossyLobe::new(reflected, material.drefl).direction(rng.uniform(), rng.uniform())
                    } else {
                        reflected
                    }
                }
                Scatter::Refract => {
                    if let Some(t) = transmittance {
                        flux *= t / power(t);
                    }
                    let eta = if at.front { 1.0 / material.rindex } else { material.rindex };
                    refract(ray.dir, at.normal, eta)
                }
                Scatter::Absorb => break,
            };
            ray = at.spawn(dir);
        }
        rays
    }
}

/// The photon model's row loop: the colours of the pixels of `rows` (row by row, in the order of
/// [`Rows::ys`]) and what they took, gathering from `map`, which is built first (reporting
/// [`Stage::TracingPhotons`] and [`Stage::BuildingPhotonMap`]) when it is `None`: its making is
/// counted in the stats of the call that builds it.
pub fn render_rows(
    scene: &PreparedScene,
    map: &mut Option<(PhotonMap, PhotonStats)>,
    settings: &PhotonSettings,
    pixels: &PixelSampling,
    rows: &Rows,
    progress: &(dyn Fn(Progress) + Sync),
) -> (Vec<DVec3>, RenderStats) {
    let mut built = None;
    let (map, _) = map.get_or_insert_with(|| {
        let report = |done, total| progress(Progress { stage: Stage::TracingPhotons, done, total });
        let (map, stats) = build_photon_map(scene, settings, pixels.seed, &report);
        progress(Progress { stage: Stage::BuildingPhotonMap, done: 1, total: 1 });
        built = Some(stats);
        (map, stats)
    });
    let integrator = Classic::with_photons(scene, PhotonEstimate::new(map, settings));
    let (colors, mut stats) = AdaptiveSampler::new(integrator, pixels).run(rows, progress);
    stats.photons = built;
    (colors, stats)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::geometry::{Sphere, Square};

    fn point_light(c: f64) -> Light {
        Light::Point { position: DVec3::ZERO, color: DVec3::splat(c) }
    }

    #[test]
    fn photons_are_shared_in_proportion_to_power() {
        let plan = EmissionPlan::new(&[point_light(1.0), point_light(3.0)], 1000);
        assert_eq!(plan.counts, [250, 750]);
        assert_eq!(plan.total_power, 4.0);
        // Every photon belongs to one light, each light gets exactly its count, and any run of
        // photons holds the lights in proportion.
        let owners: Vec<usize> = (0..1000).map(|i| plan.light_of(i)).collect();
        assert_eq!(owners.iter().filter(|&&l| l == 0).count(), 250);
        let first_hundred = owners[..100].iter().filter(|&&l| l == 0).count();
        assert!((20..=30).contains(&first_hundred), "{first_hundred} of the first 100");
        // Rounding keeps the total exact; a dark light gets nothing.
        let plan =
            EmissionPlan::new(&[point_light(1.0), point_light(1.0), point_light(1.0), point_light(0.0)], 100);
        assert_eq!(plan.counts.iter().sum::<u64>(), 100);
        assert_eq!(plan.counts[3], 0);
        assert!(plan.counts[..3].iter().all(|&c| c == 33 || c == 34));
        assert_eq!(EmissionPlan::new(&[point_light(0.0)], 100).photons(), 0);
    }

    #[test]
    fn a_photon_carries_its_light_colour_scaled_to_the_total_power() {
        // Spec: colour_l / Power(colour_l) * total; Power = total for every photon.
        let lights =
            [Light::Point { position: DVec3::ZERO, color: DVec3::new(3.0, 0.0, 0.0) }, point_light(2.0)];
        let plan = EmissionPlan::new(&lights, 10);
        let p = lights[0].color() / power(lights[0].color()) * plan.total_power;
        assert_eq!(p, DVec3::new(9.0, 0.0, 0.0));
        assert_eq!(power(p), plan.total_power);
    }

    #[test]
    fn roulette_keeps_diff_times_power_of_the_photons() {
        let m = CourseMaterial { diff: 0.5, color: DVec3::ONE, ..CourseMaterial::default() };
        let n = 100_000;
        let kept = (0..n)
            .filter(|&i| roulette(&m, DVec3::ONE, None, (i as f64 + 0.5) / n as f64) != Scatter::Absorb)
            .count();
        assert_eq!(kept, n / 2);
        // Mirror and refraction take the next shares; leaving glass also weighs by Power(T).
        let m = CourseMaterial { diff: 0.2, refl: 0.3, refr: 0.4, rindex: 1.5, ..CourseMaterial::default() };
        let c = DVec3::new(1.0, 0.5, 0.0); // Power 0.5
        assert_eq!(roulette(&m, c, None, 0.09), Scatter::Diffuse);
        assert_eq!(roulette(&m, c, None, 0.11), Scatter::Mirror);
        assert_eq!(roulette(&m, c, None, 0.24), Scatter::Mirror);
        assert_eq!(roulette(&m, c, None, 0.26), Scatter::Refract);
        assert_eq!(roulette(&m, c, None, 0.64), Scatter::Refract);
        assert_eq!(roulette(&m, c, None, 0.66), Scatter::Absorb);
        let t = DVec3::new(0.5, 0.5, 0.5);
        assert_eq!(roulette(&m, c, Some(t), 0.44), Scatter::Refract);
        assert_eq!(roulette(&m, c, Some(t), 0.46), Scatter::Absorb);
    }

    /// `n` photons of power `p` on a disc of radius `r` around the origin in the plane z = 0,
    /// arriving from above, plus `extra` arriving from below.
    fn disc(n: usize, extra: usize, r: f32, p: f32) -> PhotonMap {
        let mut photons = Vec::new();
        for i in 0..n + extra {
            let a = i as f32 * 2.399_963; // golden angle
            let rho = r * ((i % n.max(1)) as f32 + 0.5).sqrt() / (n as f32).sqrt();
            let direction = if i < n { Vec3::NEG_Z } else { Vec3::Z };
            photons.push(Photon {
                position: Vec3::new(rho * a.cos(), rho * a.sin(), 0.0),
                direction,
                power: Vec3::splat(p),
            });
        }
        PhotonMap::build(photons)
    }

    fn settings(k: u64, dist: f64, emit: u64) -> PhotonSettings {
        PhotonSettings {
            sample_photons: k,
            sample_dist: dist,
            emit_photons: emit,
            ..PhotonSettings::default()
        }
    }

    #[test]
    fn irradiance_is_the_formula_on_a_known_photon_set() {
        // 100 photons of power 2 within radius 0.5; gather all of them (k larger than the set):
        // fewer than k were found, so r^2 is sample_dist^2.
        let map = disc(100, 0, 0.5, 2.0);
        let e = PhotonEstimate::new(&map, &settings(500, 0.5, 1000)).irradiance(DVec3::ZERO, DVec3::Z);
        let expect = 100.0 * 2.0 * 4.0 / (1000.0 * 0.25);
        assert!((e - DVec3::splat(expect)).abs().max_element() < 1e-4 * expect, "{e} vs {expect}");
        // k = 40 of them: r^2 is the squared distance of the 40th nearest.
        let est = PhotonEstimate::new(&map, &settings(40, 0.5, 1000));
        let mut found = Vec::new();
        let nearest = map.k_nearest(DVec3::ZERO, 40, 0.25, &mut found);
        let expect = 40.0 * 2.0 * 4.0 / (1000.0 * nearest.radius2 as f64);
        let e = est.irradiance(DVec3::ZERO, DVec3::Z);
        assert!((e.x - expect).abs() < 1e-6 * expect, "{e} vs {expect}");
    }

    #[test]
    fn only_photons_arriving_on_the_visible_side_count() {
        // 50 from above and 50 from below: seen from above, half the power counts, but all 100
        // photons set the radius.
        let map = disc(50, 50, 0.5, 1.0);
        let est = PhotonEstimate::new(&map, &settings(1000, 0.5, 100));
        let above = est.irradiance(DVec3::ZERO, DVec3::Z);
        let below = est.irradiance(DVec3::ZERO, -DVec3::Z);
        let expect = 50.0 * 4.0 / (100.0 * 0.25);
        assert!((above.x - expect).abs() < 1e-6 && (below.x - expect).abs() < 1e-6, "{above} {below}");
    }

    #[test]
    fn eight_photons_or_fewer_give_no_light() {
        for (n, lit) in [(8, false), (9, true)] {
            let map = disc(n, 0, 0.1, 1.0);
            let e = PhotonEstimate::new(&map, &settings(100, 1.0, 10)).irradiance(DVec3::ZERO, DVec3::Z);
            assert_eq!(e != DVec3::ZERO, lit, "{n} photons: {e}");
        }
    }

    #[test]
    fn emission_follows_each_light_kind() {
        let mut rng = PixelRng::from_key(5);
        let square = Square::new(DVec3::new(0.0, 0.0, 3.0), DVec3::X, DVec3::Y).expect("square");
        let sphere = Sphere::new(DVec3::new(1.0, 2.0, 3.0), 0.5).expect("sphere");
        let (mut down, mut outward) = (0, 0);
        for _ in 0..10_000 {
            let ray = emit(&Light::Square { shape: square.clone(), color: DVec3::ONE }, &mut rng);
            assert!(
                (ray.origin.z - 3.0).abs() < 1e-12 && ray.origin.x.abs() <= 1.0 && ray.origin.y.abs() <= 1.0
            );
            down += (ray.dir.z < 0.0) as u32;
            let ray = emit(&Light::Sphere { shape: sphere.clone(), color: DVec3::ONE }, &mut rng);
            let n = (ray.origin - sphere.centre) / sphere.radius;
            assert!((n.length() - 1.0).abs() < 1e-12);
            outward += (ray.dir.dot(n) >= 0.0) as u32;
        }
        // Both sides of a square light; always outward from a sphere light.
        assert!((4700..5300).contains(&down), "{down}");
        assert_eq!(outward, 10_000);
    }

    #[test]
    fn memory_check_names_the_limit_and_the_key() {
        let mut s = PhotonSettings { max_photons: 200_000_000, ..PhotonSettings::default() };
        assert!(check_memory(&s, 16 << 30).is_ok());
        let e = check_memory(&s, 4 << 30).expect_err("over 4 GiB");
        assert!(e.message.contains("4.0 GiB") && e.message.contains("7.5 GiB"), "{}", e.message);
        s.max_photons = 1000;
        assert!(check_memory(&s, 4 << 30).is_ok());
    }
}
