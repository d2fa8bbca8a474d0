//! The path tracer against Mitsuba 3 (`pip install mitsuba`, variant `scalar_rgb`), the
//! renderer of reference: three scenes of ours (`scenes/cornell-box.txt`, `absorbing-glass.txt`,
//! `glossy.txt`) rendered by `--model path` and by Mitsuba's `path` integrator (`volpath` for
//! the absorbing glass) through `tools/mitsuba/rayterra_mitsuba.py`, at the same size, depth
//! (10) and sample count. Every 16x16 block's mean agrees within 2% in each channel, or within
//! four standard deviations of the two images' own noise (measured by rendering each image as two
//! halves with different seeds), and the whole image within 1%.
//!
//! Skipped loudly when Mitsuba is not installed, except under CI (`.ci/run` installs it).

mod support;

use support::pbr::{compare, mitsuba_halves, mitsuba_python, path_halves};
use support::{load, workspace};

/// Block side, relative tolerance of a block, of the whole image.
const BLOCK: u32 = 16;
const BLOCK_TOLERANCE: f64 = 0.02;
const WHOLE_TOLERANCE: f64 = 0.01;
/// Block means below this (both images) are black in both.
const FLOOR: f64 = 1e-4;

fn agree_with_mitsuba(scene: &str, size: (u32, u32), spp: u32) {
    let Some(python) = mitsuba_python() else { return };
    let path = workspace().join("scenes").join(format!("{scene}.txt"));
    let prepared = load(&path);
    let started = std::time::Instant::now();
    let ours = path_halves(&prepared, size, spp);
    let our_seconds = started.elapsed().as_secs_f64();
    let (theirs, their_seconds) = mitsuba_halves(&python, &path, size, spp, scene);
    let a = compare(&ours, &theirs, BLOCK, BLOCK_TOLERANCE, FLOOR, |_, _| true);
    eprintln!(
        "{scene} {}x{} at {spp} spp: {} of {} block channels within {:.0}%, the rest within {:.1} sigma; \
         whole image {:+.3}% {:+.3}% {:+.3}% (ours {our_seconds:.1} s unoptimised, Mitsuba {their_seconds:.1} s)",
        size.0,
        size.1,
        a.within_tolerance,
        a.blocks,
        BLOCK_TOLERANCE * 100.0,
        a.worst_sigmas,
        a.whole[0] * 100.0,
        a.whole[1] * 100.0,
        a.whole[2] * 100.0,
    );
    assert!(a.failures.is_empty(), "{scene}: blocks disagree with Mitsuba:\n{}", a.failures.join("\n"));
    assert!(
        a.whole.iter().all(|w| w.abs() <= WHOLE_TOLERANCE),
        "{scene}: the whole image differs from Mitsuba's by {:?}",
        a.whole
    );
    // Most blocks must meet the tolerance itself, not only the noise bound.
    assert!(
        a.within_tolerance * 10 >= a.blocks * 7,
        "{scene}: only {} of {} blocks within {}%: too noisy a comparison",
        a.within_tolerance,
        a.blocks,
        BLOCK_TOLERANCE * 100.0
    );
}

#[test]
fn cornell_box_agrees_with_mitsuba() {
    agree_with_mitsuba("cornell-box", (64, 64), 512);
}

#[test]
fn absorbing_glass_agrees_with_mitsuba() {
    agree_with_mitsuba("absorbing-glass", (64, 48), 512);
}

#[test]
fn glossy_surfaces_agree_with_mitsuba() {
    agree_with_mitsuba("glossy", (64, 48), 512);
}
