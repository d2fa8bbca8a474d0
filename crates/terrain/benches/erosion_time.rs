//! The procedural island's erosion at start-up: `cargo bench -p terrain --bench erosion_time`
//! erodes the island at its default size (512 samples a side) and at 1025 with the island's
//! default strength, sea included (as `rayterra terrain` does), in the global rayon pool
//! (`RAYON_NUM_THREADS` sets its size), and prints the wall time and the process's CPU time of
//! each. `RAYTERRA_EROSION_SIDES=512,1025,4097` chooses the sizes (a comma-separated list).
//! Nothing is asserted: speed is measured, not tested.

use std::time::Instant;

use terrain::SceneConfig;
use terrain::world::erosion::{self, ErosionParams};
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
        let (eroded, _) = erosion::erode_heightmap(&map, &config, &params, &mut |_| {}).expect("erodes");
        let (wall, cpu) = (wall.elapsed().as_secs_f64(), cpu_seconds() - cpu);
        assert_eq!(eroded.columns(), side);
        println!(
            "island {side}x{side}, strength {}: {wall:.2} s wall, {cpu:.2} s CPU ({threads} threads)",
            erosion::ISLAND_STRENGTH
        );
    }
}
