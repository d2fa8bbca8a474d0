//! The procedural island's erosion at start-up: `cargo bench -p terrain --bench erosion_time`
//! erodes the island at its default size (512 samples a side) and at 1025 with the island's
//! default strength, sea included (as `rayterra terrain` does), in the global rayon pool
//! (`RAYON_NUM_THREADS` sets its size), and prints the wall time and the process's CPU time of
//! each, and a digest of the eroded heights (the same code gives the same digest at any thread
//! count). `RAYTERRA_EROSION_SIDES=512,1025,4097` chooses the sizes (a comma-separated list).
//! Nothing is asserted: speed is measured, not tested.

use std::time::Instant;

use terrain::SceneConfig;
use terrain::world::erosion::{self, ErosionParams, HeightGrid};
use terrain::world::heightfield::Heightfield;
use terrain::world::procedural::island_heightmap;

/// The CPU time (user and system) this process has used so far, in seconds, from
/// /proc/self/stat (Linux; 0 elsewhere).
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else { return 0.0 };
    // Fields after the command's closing parenthesis; utime and stime are the 14th and 15th.
    let rest = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| fields.get(i).and_then(|f| f.parse::<f64>().ok()).unwrap_or(0.0);
    // Fields are counted from the state (3rd field) here; the kernel's clock ticks are 100 Hz.
    (ticks(11) + ticks(12)) / 100.0
}

fn main() {
    let config = SceneConfig::default();
    let threads = rayon::current_num_threads();
    let sides = std::env::var("RAYTERRA_EROSION_SIDES").unwrap_or_else(|_| "512,1025".into());
    let sides: Vec<u32> = sides
        .split(',')
        .map(|side| side.trim().parse().expect("RAYTERRA_EROSION_SIDES: a comma-separated list of sizes"))
        .collect();
    for side in sides {
        let map = island_heightmap(1, side, &config, &mut |_| {}).expect("a valid size");
        let mut params = ErosionParams::with_strength(erosion::ISLAND_STRENGTH, 1).expect("a valid strength");
        params.sea_level = config.sea.then_some(0.0);
        let (wall, cpu) = (Instant::now(), cpu_seconds());
        // As `erosion::erode_heightmap` does, keeping the eroded heights as floats for the digest.
        let grid = HeightGrid {
            columns: side,
            rows: side,
            cell_size: Heightfield::cell_size_of(&map, &config),
            heights: map.levels().map(|level| config.height_of_level(level)).collect(),
        };
        let eroded = erosion::erode(&grid, &params, &mut |_| {}).expect("erodes");
        let (wall, cpu) = (wall.elapsed().as_secs_f64(), cpu_seconds() - cpu);
        // A digest of the eroded heights' bits, to tell whether a change to the code changed them.
        let digest = eroded.grid.heights.iter().fold(0xcbf2_9ce4_8422_2325u64, |hash, height| {
            (hash ^ u64::from(height.to_bits())).wrapping_mul(0x0100_0000_01b3)
        });
        println!(
            "island {side}x{side}, strength {}: {wall:.2} s wall, {cpu:.2} s CPU ({threads} threads), heights {digest:016x}",
            erosion::ISLAND_STRENGTH
        );
    }
}
