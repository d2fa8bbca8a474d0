//! The built-in procedural textures (`texture= builtin:NAME`), so that the project's own scenes
//! need no image files.
//!
//! Each texture is generated once, deterministically, into a [`Texture`] that tiles seamlessly in
//! both directions (noise is sampled on a torus), and is then looked up like an image. Texture
//! space follows the course: `u` runs along the rows (bottom to top), `v` along the columns.

use std::f64::consts::TAU;

use glam::DVec3;
use noise::{NoiseFn, Perlin};
use rayon::prelude::*;

use crate::texture::{Builtin, Texture};

/// Side of the generated marble and wood textures, in texels.
const NOISE_TEXTURE_SIDE: u32 = 512;
/// Texels per cell of the checker and stripes textures.
const TEXELS_PER_CELL: u32 = 32;
/// Largest side of a generated pattern texture.
const MAX_PATTERN_SIDE: u32 = 2048;

/// Generates a built-in texture.
pub fn generate(builtin: Builtin) -> Texture {
    match builtin {
        Builtin::Marble => render(NOISE_TEXTURE_SIDE, NOISE_TEXTURE_SIDE, marble),
        Builtin::Wood => render(NOISE_TEXTURE_SIDE, NOISE_TEXTURE_SIDE, wood),
        Builtin::Checker(n) => {
            let side = pattern_side(n);
            render(side, side, move |u, v| {
                let parity = ((u * n as f64).floor() as i64 + (v * n as f64).floor() as i64) & 1;
                DVec3::splat(parity as f64)
            })
        }
        Builtin::Stripes(n) => {
            let side = pattern_side(n);
            render(side, side, move |u, _| DVec3::splat(((u * n as f64).floor() as i64 & 1) as f64))
        }
    }
}

/// A texture side that gives every cell the same whole number of texels.
fn pattern_side(cells: u32) -> u32 {
    let per_cell = (MAX_PATTERN_SIDE / cells).clamp(1, TEXELS_PER_CELL);
    cells * per_cell
}

/// Evaluates `f(u, v)` at every texel centre; `u` for rows from the bottom, `v` for columns.
fn render(width: u32, height: u32, f: impl Fn(f64, f64) -> DVec3 + Sync) -> Texture {
    let top_down: Vec<[u8; 3]> = (0..height)
        .into_par_iter()
        .flat_map_iter(|row_from_top| {
            let u = (height - 1 - row_from_top) as f64 / height as f64;
            let f = &f;
            (0..width).map(move |c| {
                let v = c as f64 / width as f64;
                // The course's 8-bit scale: byte b stands for b / 256.
                let color = f(u, v) * 256.0;
                color.to_array().map(|x| x.floor().clamp(0.0, 255.0) as u8)
            })
        })
        .collect();
    Texture::from_top_down(width, height, &top_down)
}

/// Perlin noise on a torus: periodic with period 1 in `u` and `v`, with about `freq_u` and
/// `freq_v` features per period.
fn torus_noise(perlin: &Perlin, u: f64, v: f64, freq_u: f64, freq_v: f64, offset: f64) -> f64 {
    let (a, b) = (TAU * u, TAU * v);
    let (ru, rv) = (freq_u / TAU, freq_v / TAU);
    perlin.get([ru * a.cos() + offset, ru * a.sin(), rv * b.cos(), rv * b.sin() - offset])
}

/// Fractal sum of `octaves` torus-noise layers, each twice the frequency and half the amplitude;
/// roughly in [-1, 1].
fn fbm(perlin: &Perlin, u: f64, v: f64, freq_u: f64, freq_v: f64, octaves: u32) -> f64 {
    let (mut sum, mut amp, mut norm) = (0.0, 1.0, 0.0);
    for k in 0..octaves {
        let scale = (1u32 << k) as f64;
        sum += amp * torus_noise(perlin, u, v, freq_u * scale, freq_v * scale, k as f64 * 7.31);
        norm += amp;
        amp *= 0.5;
    }
    sum / norm
}

/// White marble with grey-blue veins (in the spirit of the course's `marble.bmp`).
fn marble(u: f64, v: f64) -> DVec3 {
    thread_local! {
        static NOISE: Perlin = Perlin::new(7);
    }
    NOISE.with(|p| {
        let turbulence = fbm(p, u, v, 3.0, 3.0, 5);
        let cloud = fbm(p, u + 0.37, v + 0.11, 4.0, 4.0, 3);
        // Veins: where a slanted sine, bent by the turbulence, crosses zero; their strength
        // varies along them with the cloud noise, and a second, fainter and more turbulent set
        // crosses the first.
        let phase = TAU * (2.0 * u + 3.0 * v) + 10.0 * turbulence;
        let strength = (0.55 + 0.9 * cloud).clamp(0.15, 1.0);
        let vein = (1.0 - phase.sin().abs()).powi(8) * strength;
        let phase2 = TAU * (4.0 * u - 3.0 * v) + 16.0 * turbulence + 6.0 * cloud;
        let fine = (1.0 - phase2.sin().abs()).powi(30) * (1.0 - strength);
        let base = DVec3::new(0.87, 0.88, 0.95) - DVec3::new(0.10, 0.09, 0.05) * (0.5 - 0.5 * cloud).powi(2);
        let vein_color = DVec3::new(0.36, 0.39, 0.54);
        let darkness = (0.9 * vein + 0.35 * fine).min(1.0);
        base * (1.0 - darkness) + vein_color * darkness
    })
}

/// Plank layout of the wood floor: columns across `v`, planks along `u`.
const PLANK_COLUMNS: u32 = 6;
/// Planks per column in one tile.
const PLANKS_PER_COLUMN: u32 = 2;

/// A floor of staggered light-wood planks with grain (in the spirit of the course's
/// `floor.bmp`).
fn wood(u: f64, v: f64) -> DVec3 {
    thread_local! {
        static NOISE: Perlin = Perlin::new(11);
    }
    NOISE.with(|p| {
        let column = ((v * PLANK_COLUMNS as f64).floor() as u32).min(PLANK_COLUMNS - 1);
        let across = v * PLANK_COLUMNS as f64 - column as f64; // 0..1 across the plank
        let stagger = hash01(column, 0) / PLANKS_PER_COLUMN as f64;
        let along_tile = (u + stagger).rem_euclid(1.0) * PLANKS_PER_COLUMN as f64;
        let plank = (along_tile.floor() as u32).min(PLANKS_PER_COLUMN - 1);
        let along = along_tile - plank as f64; // 0..1 along the plank
        let id = column * PLANKS_PER_COLUMN + plank;
        // Each plank has its own tone; grain runs along u.
        let tone = hash01(id, 1);
        let grain = fbm(p, u, v, 2.0, 90.0, 4);
        let figure = (TAU * (7.0 * v + 1.5 * grain + 0.6 * fbm(p, u, v, 1.0, 6.0, 2))).sin();
        let light = DVec3::new(0.97, 0.66, 0.33);
        let dark = DVec3::new(0.86, 0.50, 0.22);
        let mut color = light * (1.0 - 0.55 * tone) + dark * (0.55 * tone);
        color *= 1.0 + 0.06 * grain + 0.035 * figure;
        // Thin dark seams between planks.
        let seam = smooth_edge(across.min(1.0 - across), 0.012) * smooth_edge(along.min(1.0 - along), 0.006);
        color * (0.55 + 0.45 * seam)
    })
}

/// 0 at distance 0 from an edge, rising smoothly to 1 at `width`.
fn smooth_edge(distance: f64, width: f64) -> f64 {
    let t = (distance / width).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A deterministic number in [0, 1) from two integers.
fn hash01(a: u32, b: u32) -> f64 {
    let mut x = (a as u64) << 32 | b as u64;
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^= x >> 31;
    (x >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mean(t: &Texture) -> DVec3 {
        let mut sum = DVec3::ZERO;
        for r in 0..t.height() {
            for c in 0..t.width() {
                sum += DVec3::from_array(t.texel(r, c).map(f64::from));
            }
        }
        sum / (t.width() * t.height()) as f64
    }

    #[test]
    fn generation_is_deterministic() {
        assert_eq!(generate(Builtin::Marble), generate(Builtin::Marble));
        assert_eq!(generate(Builtin::Wood), generate(Builtin::Wood));
    }

    #[test]
    fn noise_textures_tile_seamlessly() {
        for b in [Builtin::Marble, Builtin::Wood] {
            let t = generate(b);
            // Neighbouring texels across the wrap differ about as much as neighbours inside.
            let diff = |a: [f32; 3], b: [f32; 3]| (0..3).map(|i| (a[i] - b[i]).abs()).sum::<f32>();
            let (w, h) = (t.width(), t.height());
            let mut across = 0.0;
            let mut inside = 0.0;
            for r in 0..h {
                across += diff(t.texel(r, w - 1), t.texel(r, 0));
                inside += diff(t.texel(r, w / 2 - 1), t.texel(r, w / 2));
            }
            assert!(across < 3.0 * inside + 1.0, "{b:?}: seam {across} vs {inside}");
        }
    }

    #[test]
    fn colours_look_like_their_names() {
        let m = mean(&generate(Builtin::Marble));
        assert!(m.min_element() > 0.6 && m.z > m.x, "marble is light and bluish: {m}");
        let w = mean(&generate(Builtin::Wood));
        assert!(w.x > w.y && w.y > w.z && w.x > 0.7, "wood is orange-brown: {w}");
        let c = mean(&generate(Builtin::Checker(8)));
        assert!((c.x - 0.5 * 255.0 / 256.0).abs() < 1e-3, "half the checker is white: {c}");
    }

    #[test]
    fn checker_cells_alternate() {
        let t = generate(Builtin::Checker(4));
        assert_eq!(t.width() % 4, 0);
        let cell = t.width() / 4;
        assert_eq!(t.texel(0, 0)[0], 0.0);
        assert!(t.texel(0, cell)[0] > 0.9);
        assert!(t.texel(cell, cell)[0] == 0.0);
        let s = generate(Builtin::Stripes(2));
        assert_eq!(s.texel(0, 0), s.texel(0, s.width() - 1), "stripes run along v");
        assert_ne!(s.texel(0, 0), s.texel(s.height() / 2, 0));
    }
}
