use super::droplet::DropletParams;
use super::*;
use crate::world::procedural::island_heightmap;

/// The procedural island of `seed` at `side` samples, as a grid in world units.
fn island(seed: u32, side: u32) -> HeightGrid {
    let config = SceneConfig::default();
    let map = island_heightmap(seed, side, &config, &mut |_| {}).expect("valid");
    HeightGrid {
        columns: side,
        rows: side,
        cell_size: Heightfield::cell_size_of(&map, &config),
        heights: map.levels().map(|level| config.height_of_level(level)).collect(),
    }
}

fn erode_in_pool(threads: usize, grid: &HeightGrid, params: &ErosionParams) -> Eroded {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
    pool.install(|| erode(grid, params, &mut |_| {})).expect("erodes")
}

#[test]
fn the_same_heights_bit_for_bit_at_one_and_two_threads() {
    // 300 samples: several tiles, some cut short by the map's edge.
    let grid = island(4, 300);
    let params = ErosionParams::with_strength(1.0, 9).expect("valid");
    let one = erode_in_pool(1, &grid, &params);
    let two = erode_in_pool(2, &grid, &params);
    let bits = |v: &[f32]| v.iter().map(|h| h.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&one.grid.heights), bits(&two.grid.heights));
    assert_eq!(bits(&one.maps.flow), bits(&two.maps.flow));
    assert_eq!(bits(&one.maps.deposition), bits(&two.maps.deposition));
    assert_ne!(one.grid.heights, grid.heights, "nothing eroded");
    // Another seed gives other heights.
    let other = erode_in_pool(2, &grid, &ErosionParams { seed: 10, ..params });
    assert_ne!(other.grid.heights, one.grid.heights);
}

#[test]
fn erosion_carves_channels() {
    let grid = island(1, 257);
    let before = flow::accumulation(&grid.heights, grid.columns, grid.rows);
    let eroded =
        erode(&grid, &ErosionParams::with_strength(1.0, 1).expect("valid"), &mut |_| {}).expect("erodes");
    // Cells through which more than 100 cells drain: channels.
    let (was, is) = (flow::channel_share(&before, 100.0), flow::channel_share(&eroded.maps.flow, 100.0));
    assert!(is > was * 1.2, "share of channel cells {was} -> {is}");
    assert!(eroded.maps.deposition.iter().any(|&d| d > 0.0));
    assert!(eroded.maps.deposition.iter().all(|&d| d >= 0.0));
}

#[test]
fn pure_hydraulic_transport_conserves_soil() {
    let grid = island(2, 200);
    let params = ErosionParams { thermal_passes: 0, ..ErosionParams::with_strength(2.0, 5).expect("valid") };
    let eroded = erode(&grid, &params, &mut |_| {}).expect("erodes");
    let cell = f64::from(grid.cell_size).powi(2);
    let volume = |h: &[f32]| h.iter().map(|&h| f64::from(h)).sum::<f64>() * cell;
    let moved: f64 =
        grid.heights.iter().zip(&eroded.grid.heights).map(|(a, b)| f64::from((a - b).abs())).sum::<f64>()
            * cell;
    let change = (volume(&eroded.grid.heights) - volume(&grid.heights)).abs();
    assert!(moved > 0.0);
    assert!(change < 1e-3 * moved, "volume changed by {change}, {moved} moved");
}

#[test]
fn thermal_erosion_brings_slopes_under_the_talus_angle() {
    // A 40-cell tower on a plain: far steeper than 30 degrees.
    let side = 48u32;
    let mut heights = vec![0.0f32; (side * side) as usize];
    for y in 20..28 {
        for x in 20..28 {
            heights[(y * side + x) as usize] = 40.0;
        }
    }
    let grid = HeightGrid { columns: side, rows: side, cell_size: 1.0, heights };
    let params = ErosionParams {
        droplets_per_cell: 0.0,
        thermal_passes: 800,
        talus_degrees: 30.0,
        ..ErosionParams::default()
    };
    let talus = 30f32.to_radians().tan();
    let steepest_before = thermal::steepest(&grid.heights, side, side);
    assert!(steepest_before > 10.0 * talus);
    let eroded = erode(&grid, &params, &mut |_| {}).expect("erodes");
    let steepest = thermal::steepest(&eroded.grid.heights, side, side);
    assert!(steepest <= talus * 1.02, "steepest slope {steepest}, talus {talus}");
    // Nothing is made or lost by sliding.
    let sum = |v: &[f32]| v.iter().map(|&h| f64::from(h)).sum::<f64>();
    assert!((sum(&eroded.grid.heights) - sum(&grid.heights)).abs() < 1e-2);
}

#[test]
fn progress_runs_from_zero_to_one() {
    let grid = island(1, 64);
    let mut seen = Vec::new();
    erode(&grid, &ErosionParams::default(), &mut |done| seen.push(done)).expect("erodes");
    assert_eq!(seen.first(), Some(&0.0));
    assert_eq!(seen.last(), Some(&1.0));
    assert!(seen.windows(2).all(|w| w[0] <= w[1]));
}

#[test]
fn bad_parameters_and_grids_are_refused() {
    for strength in [0.0, -1.0, f32::NAN, f32::INFINITY, 10.5] {
        let error = ErosionParams::with_strength(strength, 1).expect_err("refused");
        assert!(error.to_string().contains("strength"), "{error}");
    }
    assert!(ErosionParams::with_strength(10.0, 1).is_ok());
    let grid = island(1, 16);
    let bad = |params: ErosionParams| erode(&grid, &params, &mut |_| {}).expect_err("refused").to_string();
    assert!(bad(ErosionParams { talus_degrees: 95.0, ..Default::default() }).contains("talus_degrees"));
    assert!(bad(ErosionParams { thermal_rate: 0.9, ..Default::default() }).contains("thermal_rate"));
    let droplet = DropletParams { inertia: 1.0, ..Default::default() };
    assert!(bad(ErosionParams { droplet, ..Default::default() }).contains("inertia"));
    let droplet = DropletParams { radius: 0, ..Default::default() };
    assert!(bad(ErosionParams { droplet, ..Default::default() }).contains("radius"));
    let short = HeightGrid { heights: vec![0.0; 5], ..grid.clone() };
    assert!(matches!(
        erode(&short, &ErosionParams::default(), &mut |_| {}),
        Err(ErosionError::BadGrid { .. })
    ));
}

#[test]
fn a_heightmap_erodes_and_keeps_its_storage() {
    let config = SceneConfig::default();
    let map = island_heightmap(3, 65, &config, &mut |_| {}).expect("valid");
    let (eroded, maps) =
        erode_heightmap(&map, &config, &ErosionParams::default(), &mut |_| {}).expect("erodes");
    assert_eq!((eroded.columns(), eroded.rows()), (65, 65));
    assert_eq!(eroded.bytes_per_sample(), map.bytes_per_sample());
    assert_eq!(maps.flow.len(), 65 * 65);
    assert_ne!(eroded, map);
}
