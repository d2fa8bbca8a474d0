//! A clear atmosphere's light: single scattering of sunlight by air molecules (Rayleigh) and
//! aerosols (Mie) through a spherical shell of exponentially thinning air, with ozone's
//! absorption, as in Bruneton and Neyret, "Precomputed Atmospheric Scattering" (2008) and
//! Hillaire, "A Scalable and Production Ready Sky and Atmosphere Rendering Technique" (2020),
//! whose Earth coefficients these are. Multiple scattering is left out.
//!
//! The transmittance (the optical depth from any altitude to space in any direction) is
//! tabulated once; a sky-view table of the radiance seen from near the ground in every
//! direction above the horizon is then worked out each time the sun moves (a few milliseconds),
//! for the renderer to look up ([`SkyLight`]).
//!
//! Units: distances in metres, radiance for a sun of irradiance 1 (per colour channel, in the
//! red, green and blue bands Hillaire uses), directions y-up.

use std::f64::consts::PI;

use glam::{DVec3, Vec3};

use crate::world::procedural::smoothstep_f32;

/// The sky-view table's width: the view's azimuth from the sun's, 0 to 180 degrees (the sky is
/// symmetric about the sun's vertical plane).
pub const SKY_VIEW_WIDTH: u32 = 64;

/// The sky-view table's height: the view's elevation, 0 (the horizon, row 0) to 90 degrees
/// (the zenith), rows spaced by the square root of the elevation (finer near the horizon).
pub const SKY_VIEW_HEIGHT: u32 = 32;

const GROUND_RADIUS: f64 = 6_360_000.0;
const TOP_RADIUS: f64 = 6_460_000.0;
const RAYLEIGH_SCATTERING: [f64; 3] = [5.802e-6, 13.558e-6, 33.1e-6];
const RAYLEIGH_SCALE_HEIGHT: f64 = 8_000.0;
const MIE_SCATTERING: f64 = 3.996e-6;
const MIE_EXTINCTION: f64 = 4.440e-6;
const MIE_SCALE_HEIGHT: f64 = 1_200.0;
const MIE_ASYMMETRY: f64 = 0.8;
const OZONE_ABSORPTION: [f64; 3] = [0.650e-6, 1.881e-6, 0.085e-6];
/// The ozone layer: a tent 30 km wide centred 25 km up.
const OZONE_CENTRE: f64 = 25_000.0;
const OZONE_HALF_WIDTH: f64 = 15_000.0;
/// The eye's altitude for the sky-view table.
const OBSERVER_ALTITUDE: f64 = 200.0;

/// The transmittance table's size: altitudes (spaced by their square root) and directions
/// (cosines of the zenith angle, spaced by their square root either side of the horizon).
const ALTITUDES: usize = 32;
const COSINES: usize = 256;
/// Steps of the integrals: along a ray to space, and along a view ray of the sky.
const DEPTH_STEPS: usize = 48;
const VIEW_STEPS: usize = 32;

/// The single-scattering sky's gain: multiple scattering (left out of the model) and light from
/// the ground add about as much again to a clear day's sky, and the rest brings the sky to the
/// brightness a camera exposed for the sunlit land records (chosen by eye against photographs).
const SKY_GAIN: f32 = 4.0;

/// The eye's adaptation at twilight: the scene is exposed up to this many times brighter as the
/// sky's light fades below [`ADAPTED_LUMINANCE`].
const MAX_ADAPTATION: f32 = 6.0;
const ADAPTED_LUMINANCE: f32 = 0.08;

/// The sun's angular radius, degrees, and the elevation below which its light is gone.
const SUN_RADIUS_DEGREES: f32 = 0.27;

/// Below this sun elevation (degrees) the moon is the key light.
const MOON_TAKES_OVER_DEGREES: f32 = -2.0;

/// The night's own light, linear display values: the sky's radiance with the sun far down
/// (starlight and airglow, seen with eyes adapted to the dark), and the full moon's light.
/// These are chosen for a readable night, not measured.
const NIGHT_SKY: [f32; 3] = [0.012, 0.019, 0.045];
const MOON_LIGHT: [f32; 3] = [0.085, 0.10, 0.15];

/// The Earth's clear atmosphere, with its transmittance table.
#[derive(Debug, Clone)]
pub struct Atmosphere {
    /// Optical depth to space (per channel), by altitude (rows) and direction (columns).
    optical_depth: Vec<[f32; 3]>,
}

/// What the renderer needs of the sky for one position of the sun: the sky-view table and the
/// lights, in linear display values (a white surface facing a light of colour `c` shows `c`;
/// the renderer's colours are stored values, the square roots of these).
#[derive(Debug, Clone, PartialEq)]
pub struct SkyLight {
    /// [`SKY_VIEW_WIDTH`] x [`SKY_VIEW_HEIGHT`] RGBA texels, row 0 the horizon, column 0 toward
    /// the sun: the sky's colour as stored values (square roots of linear values, 0..=255),
    /// alpha 255.
    pub texels: Vec<[u8; 4]>,
    /// Unit vector toward the sun.
    pub sun_direction: Vec3,
    /// The sun's light on the ground, linear (0 once it has set).
    pub sun_colour: Vec3,
    /// The light of the sky dome on a level surface (the cosine-weighted mean of its radiance),
    /// linear, the night's included.
    pub sky_light: Vec3,
    /// How deep into the night (0 by day, 1 with the sun 12 degrees below the horizon).
    pub night: f32,
    /// The direction of the light that casts shadows: the sun, or the full moon (opposite the
    /// sun) once the sun is below [`MOON_TAKES_OVER_DEGREES`].
    pub key_direction: Vec3,
    /// The colour of that light, linear.
    pub key_colour: Vec3,
    /// How bright the scene is against a sunny day, 0.05 to 1 (the water's own colour and the
    /// foam follow it).
    pub daylight: f32,
}

fn density_rayleigh(altitude: f64) -> f64 {
    (-altitude.max(0.0) / RAYLEIGH_SCALE_HEIGHT).exp()
}

fn density_mie(altitude: f64) -> f64 {
    (-altitude.max(0.0) / MIE_SCALE_HEIGHT).exp()
}

fn density_ozone(altitude: f64) -> f64 {
    (1.0 - (altitude - OZONE_CENTRE).abs() / OZONE_HALF_WIDTH).max(0.0)
}

/// Extinction per metre at `altitude`.
fn extinction(altitude: f64) -> DVec3 {
    let (r, m, o) = (density_rayleigh(altitude), density_mie(altitude), density_ozone(altitude));
    DVec3::from_array(RAYLEIGH_SCATTERING) * r
        + DVec3::splat(MIE_EXTINCTION * m)
        + DVec3::from_array(OZONE_ABSORPTION) * o
}

/// Distance from radius `r` along a ray of zenith cosine `mu` to the sphere of radius `radius`
/// (the far crossing; `None` if the ray misses it).
fn distance_to_sphere(r: f64, mu: f64, radius: f64) -> Option<f64> {
    let discriminant = r * r * (mu * mu - 1.0) + radius * radius;
    (discriminant >= 0.0).then(|| -r * mu + discriminant.sqrt())
}

/// Whether a ray from radius `r` with zenith cosine `mu` hits the ground.
fn hits_ground(r: f64, mu: f64) -> bool {
    mu < 0.0 && r * r * (mu * mu - 1.0) + GROUND_RADIUS * GROUND_RADIUS >= 0.0
}

/// Rayleigh's phase function.
fn phase_rayleigh(cos_angle: f64) -> f64 {
    3.0 / (16.0 * PI) * (1.0 + cos_angle * cos_angle)
}

/// The Cornette-Shanks phase function for aerosols.
fn phase_mie(cos_angle: f64) -> f64 {
    let g = MIE_ASYMMETRY;
    let denominator = (1.0 + g * g - 2.0 * g * cos_angle).max(1e-9);
    3.0 / (8.0 * PI) * (1.0 - g * g) * (1.0 + cos_angle * cos_angle)
        / ((2.0 + g * g) * denominator * denominator.sqrt())
}

/// Table coordinate (0..=1) of a zenith cosine: square-root spaced either side of 0.
fn cosine_to_unit(mu: f64) -> f64 {
    0.5 + 0.5 * mu.signum() * mu.abs().sqrt()
}

fn unit_to_cosine(x: f64) -> f64 {
    let s = 2.0 * x - 1.0;
    s.signum() * s * s
}

impl Default for Atmosphere {
    fn default() -> Self {
        Self::earth()
    }
}

impl Atmosphere {
    /// The Earth's atmosphere (Hillaire's coefficients), its transmittance tabulated.
    pub fn earth() -> Self {
        let height = TOP_RADIUS - GROUND_RADIUS;
        let mut optical_depth = Vec::with_capacity(ALTITUDES * COSINES);
        for row in 0..ALTITUDES {
            let a = row as f64 / (ALTITUDES - 1) as f64;
            let r = GROUND_RADIUS + height * a * a;
            for column in 0..COSINES {
                let mu = unit_to_cosine(column as f64 / (COSINES - 1) as f64);
                optical_depth.push(Self::integrate_depth(r, mu).as_vec3().to_array());
            }
        }
        Self { optical_depth }
    }

    /// The optical depth from radius `r` to space along zenith cosine `mu` (very large if the
    /// ray meets the ground).
    fn integrate_depth(r: f64, mu: f64) -> DVec3 {
        if hits_ground(r, mu) {
            return DVec3::splat(1e4);
        }
        let length = distance_to_sphere(r, mu, TOP_RADIUS).unwrap_or(0.0);
        let step = length / DEPTH_STEPS as f64;
        let mut depth = DVec3::ZERO;
        for i in 0..DEPTH_STEPS {
            let t = (i as f64 + 0.5) * step;
            let radius = (r * r + t * t + 2.0 * r * mu * t).sqrt();
            depth += extinction(radius - GROUND_RADIUS) * step;
        }
        depth
    }

    /// The transmittance from altitude `altitude` (metres) to space along a direction of zenith
    /// cosine `mu` (bilinear in the table).
    pub fn transmittance(&self, altitude: f64, mu: f64) -> DVec3 {
        let height = TOP_RADIUS - GROUND_RADIUS;
        let a = (altitude / height).clamp(0.0, 1.0).sqrt() * (ALTITUDES - 1) as f64;
        let c = cosine_to_unit(mu.clamp(-1.0, 1.0)) * (COSINES - 1) as f64;
        let (a0, c0) = (a.floor().min((ALTITUDES - 2) as f64), c.floor().min((COSINES - 2) as f64));
        let (fa, fc) = (a - a0, c - c0);
        let (a0, c0) = (a0 as usize, c0 as usize);
        let at = |row: usize, column: usize| {
            DVec3::from(self.optical_depth[row * COSINES + column].map(f64::from))
        };
        let depth = (at(a0, c0) * (1.0 - fc) + at(a0, c0 + 1) * fc) * (1.0 - fa)
            + (at(a0 + 1, c0) * (1.0 - fc) + at(a0 + 1, c0 + 1) * fc) * fa;
        (-depth).exp()
    }

    /// The sky's radiance seen from near the ground (200 m up) looking along `view` (unit,
    /// y-up; below the horizon it is taken at the horizon) with the sun toward `sun` (unit),
    /// for a sun of irradiance 1. The sun's disc itself is not included.
    pub fn radiance(&self, view: Vec3, sun: Vec3) -> Vec3 {
        let view = Vec3::new(view.x, view.y.max(0.0), view.z).normalize_or(Vec3::X).as_dvec3();
        let sun = sun.normalize_or(Vec3::Y).as_dvec3();
        let origin = DVec3::new(0.0, GROUND_RADIUS + OBSERVER_ALTITUDE, 0.0);
        let length = distance_to_sphere(origin.y, view.y, TOP_RADIUS).unwrap_or(0.0);
        let cos_angle = view.dot(sun);
        let (phase_r, phase_m) = (phase_rayleigh(cos_angle), phase_mie(cos_angle));
        let rayleigh = DVec3::from_array(RAYLEIGH_SCATTERING);
        let mut radiance = DVec3::ZERO;
        let mut depth = DVec3::ZERO;
        let mut previous_t = 0.0;
        for i in 0..VIEW_STEPS {
            // Steps growing quadratically: short where the air is thick.
            let u = (i as f64 + 0.5) / VIEW_STEPS as f64;
            let t = length * u * u;
            let next = (i as f64 + 1.0) / VIEW_STEPS as f64;
            let step = length * next * next - previous_t;
            previous_t = length * next * next;
            let point = origin + view * t;
            let r = point.length();
            let altitude = r - GROUND_RADIUS;
            let up = point / r;
            let to_sun = self.transmittance(altitude, up.dot(sun));
            let scattering = rayleigh * density_rayleigh(altitude) * phase_r
                + DVec3::splat(MIE_SCATTERING * density_mie(altitude) * phase_m);
            let extinction_here = extinction(altitude);
            let to_eye = (-(depth + extinction_here * step * 0.5)).exp();
            radiance += to_eye * to_sun * scattering * step;
            depth += extinction_here * step;
        }
        radiance.as_vec3()
    }

    /// The sky-view table and the lights for the sun toward `sun` (unit, y-up), scaled by
    /// `exposure` (1: a white surface facing the sun above the atmosphere shows white).
    pub fn sky(&self, sun: Vec3, exposure: f32) -> SkyLight {
        let sun = sun.normalize_or(Vec3::Y);
        let elevation = sun.y.clamp(-1.0, 1.0).asin().to_degrees();
        // The table is laid out with the sun toward +x.
        let local_sun = Vec3::new(sun.x.hypot(sun.z), sun.y, 0.0);
        let scale = std::f32::consts::PI * SKY_GAIN;
        let mut linear = Vec::with_capacity((SKY_VIEW_WIDTH * SKY_VIEW_HEIGHT) as usize);
        let mut sky_light = Vec3::ZERO;
        let mut weight = 0.0;
        for row in 0..SKY_VIEW_HEIGHT {
            let elevation_of_row = row_elevation(row);
            for column in 0..SKY_VIEW_WIDTH {
                let azimuth = column_azimuth(column);
                let view = Vec3::new(
                    elevation_of_row.cos() * azimuth.cos(),
                    elevation_of_row.sin(),
                    elevation_of_row.cos() * azimuth.sin(),
                );
                let value = self.radiance(view, local_sun) * scale;
                linear.push(value);
            }
        }
        // The cosine-weighted mean over the dome: each texel stands for a band of elevation
        // and azimuth; its solid angle is cos(elevation) d(elevation) d(azimuth).
        for row in 0..SKY_VIEW_HEIGHT {
            let low = row_edge(row);
            let high = row_edge(row + 1);
            // Integral of cos(e) sin(e) de over the band (the cosine of incidence on a level
            // surface times the solid angle).
            let band = 0.5 * (high.sin().powi(2) - low.sin().powi(2));
            for column in 0..SKY_VIEW_WIDTH {
                sky_light += linear[(row * SKY_VIEW_WIDTH + column) as usize] * band;
                weight += band;
            }
        }
        let luminance = |c: Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
        let day_sky = sky_light / weight.max(1e-9);
        // Twilight: the eye opens up as the light fades (the night's own light is not adapted).
        let adaptation = (ADAPTED_LUMINANCE / luminance(day_sky).max(1e-9)).sqrt().clamp(1.0, MAX_ADAPTATION);
        let gain = adaptation * exposure;
        let night = smoothstep_f32(MOON_TAKES_OVER_DEGREES, -12.0, elevation);
        let night_sky = Vec3::from_array(NIGHT_SKY) * night;
        let sky_light = day_sky * gain + night_sky;
        // The sun's light through the air, fading as its disc sinks below the horizon.
        let visible = smoothstep_f32(-SUN_RADIUS_DEGREES, SUN_RADIUS_DEGREES, elevation);
        let through = self.transmittance(OBSERVER_ALTITUDE, f64::from(sun.y)).as_vec3();
        let sun_colour = through * gain * visible;
        let texels = linear
            .iter()
            .map(|value| {
                let stored = (*value * gain + night_sky).max(Vec3::ZERO).powf(0.5).min(Vec3::ONE) * 255.0;
                [stored.x.round() as u8, stored.y.round() as u8, stored.z.round() as u8, 255]
            })
            .collect();
        let moon = Vec3::from_array(MOON_LIGHT) * night;
        let (key_direction, key_colour) = if elevation > MOON_TAKES_OVER_DEGREES {
            (sun, sun_colour)
        } else {
            // The full moon, opposite the sun.
            (-sun, moon)
        };
        // Against a sun of exposure 1 at 40 degrees and its sky.
        let daylight = ((luminance(key_colour) * 0.7 + luminance(sky_light)) / 0.75).clamp(0.05, 1.0);
        SkyLight {
            texels,
            sun_direction: sun,
            sun_colour,
            sky_light,
            night,
            key_direction,
            key_colour,
            daylight,
        }
    }
}

/// The elevation (radians) at the centre of a sky-view row.
fn row_elevation(row: u32) -> f32 {
    let v = (row as f32 + 0.5) / SKY_VIEW_HEIGHT as f32;
    v * v * std::f32::consts::FRAC_PI_2
}

/// The elevation (radians) at the lower edge of a sky-view row (`SKY_VIEW_HEIGHT`: the zenith).
fn row_edge(row: u32) -> f32 {
    let v = row as f32 / SKY_VIEW_HEIGHT as f32;
    v * v * std::f32::consts::FRAC_PI_2
}

/// The azimuth from the sun's (radians) at the centre of a sky-view column.
fn column_azimuth(column: u32) -> f32 {
    (column as f32 + 0.5) / SKY_VIEW_WIDTH as f32 * std::f32::consts::PI
}

#[cfg(test)]
mod tests {
    use super::super::sun::direction;
    use super::*;

    fn redness(c: Vec3) -> f32 {
        c.x / c.z.max(1e-9)
    }

    #[test]
    fn the_clear_sky_is_blue_and_the_sun_whiter_than_at_dusk() {
        let atmosphere = Atmosphere::earth();
        let noon = direction(60.0, 180.0);
        let dusk = direction(2.0, 270.0);
        let zenith = atmosphere.radiance(Vec3::Y, noon);
        assert!(zenith.z > zenith.y && zenith.y > zenith.x, "the noon zenith is blue: {zenith}");
        // Noon's zenith is brighter than dusk's.
        let dusk_zenith = atmosphere.radiance(Vec3::Y, dusk);
        assert!(zenith.y > 3.0 * dusk_zenith.y, "{zenith} vs {dusk_zenith}");
        // Near the horizon toward the sun, dusk is redder than noon in the same place.
        let toward_dusk_sun = direction(3.0, 270.0);
        let at_noon = atmosphere.radiance(toward_dusk_sun, noon);
        let at_dusk = atmosphere.radiance(toward_dusk_sun, dusk);
        assert!(redness(at_dusk) > 2.0 * redness(at_noon), "{at_dusk} vs {at_noon}");
        // The sun's own light is reddened by the long path at dusk.
        let high = atmosphere.transmittance(0.0, 0.9);
        let low = atmosphere.transmittance(0.0, 0.03);
        assert!(high.x > 0.8 && high.z > 0.6, "{high}");
        assert!(redness(low.as_vec3()) > 5.0 * redness(high.as_vec3()), "{low} vs {high}");
        // Space is black along a ray into the ground.
        assert!(atmosphere.transmittance(0.0, -0.5).max_element() < 1e-6);
    }

    #[test]
    fn the_transmittance_table_matches_its_integral() {
        let atmosphere = Atmosphere::earth();
        for (altitude, mu) in [(0.0, 1.0), (0.0, 0.2), (3_000.0, 0.05), (20_000.0, -0.1), (500.0, 0.5)] {
            let table = atmosphere.transmittance(altitude, mu);
            let exact = (-Atmosphere::integrate_depth(GROUND_RADIUS + altitude, mu)).exp();
            assert!((table - exact).abs().max_element() < 0.02, "{altitude} {mu}: {table} vs {exact}");
        }
        // Straight up from the ground: Rayleigh's optical depth is scattering x scale height.
        let up = atmosphere.transmittance(0.0, 1.0);
        let expected_blue = (-(33.1e-6_f64 * 8000.0 + 4.44e-6 * 1200.0 + 0.085e-6 * 15_000.0)).exp();
        assert!((up.z - expected_blue).abs() < 0.01, "{up} vs {expected_blue}");
    }

    #[test]
    fn day_dusk_and_night_lights() {
        let atmosphere = Atmosphere::earth();
        let noon = atmosphere.sky(direction(60.0, 180.0), 1.0);
        let dusk = atmosphere.sky(direction(3.0, 270.0), 1.0);
        let night = atmosphere.sky(direction(-30.0, 0.0), 1.0);
        assert_eq!(noon.texels.len(), (SKY_VIEW_WIDTH * SKY_VIEW_HEIGHT) as usize);
        // Brightness falls from noon to dusk to night, but never to black.
        let sum = |c: Vec3| c.x + c.y + c.z;
        assert!(sum(noon.sky_light) > sum(dusk.sky_light) && sum(dusk.sky_light) > sum(night.sky_light));
        assert!(sum(noon.key_colour) > 2.0 * sum(dusk.key_colour));
        assert!(night.sky_light.min_element() > 0.005 && night.key_colour.min_element() > 0.05);
        assert!(redness(dusk.key_colour) > redness(noon.key_colour));
        // At night the moon (opposite the sun, so up) casts the shadows, and it is bluish.
        assert!(night.key_direction.y > 0.0 && night.key_colour.z > night.key_colour.x);
        assert_eq!(night.night, 1.0);
        assert_eq!(noon.night, 0.0);
        assert!(night.sun_colour == Vec3::ZERO);
        assert!(noon.daylight > 0.9 && night.daylight < 0.5, "{} {}", noon.daylight, night.daylight);
        // The night sky's texels are dark blue, not black.
        let texel = night.texels[(SKY_VIEW_WIDTH * 10) as usize];
        assert!(texel[2] > texel[0] && texel[2] > 20 && texel[2] < 90, "{texel:?}");
    }

    #[test]
    fn the_sky_view_table_is_laid_out_as_documented() {
        let atmosphere = Atmosphere::earth();
        let dusk = atmosphere.sky(direction(4.0, 90.0), 1.0);
        let at = |row: u32, column: u32| dusk.texels[(row * SKY_VIEW_WIDTH + column) as usize];
        // Column 0 faces the sun: at the horizon it glows brighter than opposite it.
        let toward = at(0, 0);
        let away = at(0, SKY_VIEW_WIDTH - 1);
        assert!(u32::from(toward[0]) > u32::from(away[0]) + 20, "{toward:?} vs {away:?}");
        // The same table whatever the sun's azimuth (only its elevation counts).
        assert_eq!(atmosphere.sky(direction(4.0, 200.0), 1.0).texels, dusk.texels);
    }
}
