//! Renders split into tiles and passes (issue: past one machine) merge into the very bytes of
//! the render in one process, in every model: the parts go through their files and `merge`.

mod support;

use std::path::PathBuf;

use raytracer::integrator::Model;
use raytracer::parts::{self, Part, PartHeader, Split};
use raytracer::render::checkpoint::Checkpoint;
use raytracer::render::{
    PortionPixels, Progress, RenderSettings, Rows, Sampling, Stage, render_portion, render_portion_resumable,
};
use raytracer::{PreparedScene, render};
use support::{load, workspace};

/// Every part of a render split into `tiles` x `passes`, written to files, read back and merged.
fn split_and_merge(
    scene: &PreparedScene,
    settings: &RenderSettings,
    tiles: u32,
    passes: u32,
) -> Vec<[f32; 3]> {
    let dir = tempfile::tempdir().expect("temp dir");
    let settings = RenderSettings { runs: passes, ..settings.clone() };
    let mut parts = Vec::new();
    for t in 0..tiles {
        let tile = Split { index: t, count: tiles };
        let rows = Rows::tile(settings.width, settings.height, tile).expect("tile");
        for p in 0..passes {
            let runs = if passes == 1 { 0..1 } else { p..p + 1 };
            let portion = render_portion(scene, &settings, &rows, runs, &|_| {}).expect("renders");
            let header = PartHeader {
                width: settings.width,
                height: settings.height,
                scene: "test".into(),
                settings: format!("{:?}", settings.model),
                tile,
                pass: Split { index: p, count: passes },
                samples: 1,
            };
            let path: PathBuf = dir.path().join(format!("part-{t}-{p}.exr"));
            parts::write_part(&Part::from_portion(header, &rows, portion.pixels), &path).expect("written");
            parts.push((path.clone(), parts::read_part(&path).expect("read back")));
        }
    }
    parts::merge(&parts).expect("merged").pixels().to_vec()
}

fn whole(scene: &PreparedScene, settings: &RenderSettings) -> Vec<[f32; 3]> {
    render(scene, settings, &|_| {}).expect("renders").image.pixels().to_vec()
}

fn settings(scene: &PreparedScene, model: Model, width: u32, height: u32) -> RenderSettings {
    RenderSettings {
        width,
        height,
        model,
        photons: Some(20_000),
        passes: Some(3),
        sampling: if model == Model::Path { Sampling::Uniform(2) } else { Sampling::Adaptive },
        ..RenderSettings::for_scene(scene)
    }
}

#[test]
fn tiles_merge_into_the_same_bytes_in_every_model() {
    let scene = load(&workspace().join("scenes/caustics.txt"));
    for model in [Model::Classic, Model::Photon, Model::Path, Model::Sppm] {
        let settings = settings(&scene, model, 48, 29);
        let expected = whole(&scene, &settings);
        for tiles in [2, 5] {
            assert!(split_and_merge(&scene, &settings, tiles, 1) == expected, "{model:?}, {tiles} tiles");
        }
    }
}

#[test]
fn passes_merge_into_the_render_of_as_many_runs() {
    let scene = load(&workspace().join("scenes/caustics.txt"));
    for model in [Model::Classic, Model::Photon, Model::Path, Model::Sppm] {
        let settings = settings(&scene, model, 32, 19);
        let expected = whole(&scene, &RenderSettings { runs: 3, ..settings.clone() });
        assert!(split_and_merge(&scene, &settings, 1, 3) == expected, "{model:?}: passes");
        assert!(split_and_merge(&scene, &settings, 2, 3) == expected, "{model:?}: tiles of passes");
        // Runs are independent estimates: the image changes with their number.
        assert!(whole(&scene, &settings) != expected, "{model:?}: one run is not three");
    }
}

#[test]
fn path_passes_are_ranges_of_samples() {
    // Three passes of 2 samples are the render of 6 samples, bit for bit.
    let scene = load(&workspace().join("scenes/caustics.txt"));
    let settings = settings(&scene, Model::Path, 32, 19);
    let six = whole(&scene, &RenderSettings { sampling: Sampling::Uniform(6), ..settings.clone() });
    assert!(split_and_merge(&scene, &settings, 1, 3) == six);
}

/// Pass 1 of 2 of a render of `rows`, kept in the checkpoint at `path`: its pixels, the rays this
/// process traced and the SPPM passes it reported done.
fn checkpointed(
    scene: &PreparedScene,
    settings: &RenderSettings,
    rows: &Rows,
    path: &std::path::Path,
) -> (Vec<[f32; 3]>, u64, Vec<u64>) {
    let mut checkpoint = Checkpoint::open(path, "test render", rows).expect("checkpoint");
    checkpoint.sppm_interval = std::time::Duration::ZERO;
    let passes = std::sync::Mutex::new(Vec::new());
    let report = |p: Progress| {
        if p.stage == Stage::Passes {
            passes.lock().expect("lock").push(p.done);
        }
    };
    let portion = render_portion_resumable(scene, settings, rows, 1..2, &report, Some(&mut checkpoint))
        .expect("renders");
    let passes = passes.into_inner().expect("lock");
    (pass_values(portion.pixels), portion.stats.rays, passes)
}

fn pass_values(pixels: PortionPixels) -> Vec<[f32; 3]> {
    let PortionPixels::Sums { sums, count } = pixels else { panic!("a pass of two gives sums") };
    sums.iter().map(|s| s.mean(count).as_vec3().to_array()).collect()
}

#[test]
fn a_checkpointed_render_resumed_after_a_kill_gives_the_same_bytes() {
    let scene = load(&workspace().join("scenes/caustics.txt"));
    for model in [Model::Classic, Model::Photon, Model::Path, Model::Sppm] {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("part.checkpoint");
        let settings = RenderSettings { runs: 2, ..settings(&scene, model, 40, 64) };
        let rows = Rows::tile(40, 64, Split { index: 1, count: 2 }).expect("tile");
        let expected =
            pass_values(render_portion(&scene, &settings, &rows, 1..2, &|_| {}).expect("renders").pixels);
        if model == Model::Sppm {
            // A render of two passes leaves the state after its first; one of three goes on from it.
            checkpointed(&scene, &RenderSettings { passes: Some(2), ..settings.clone() }, &rows, &path);
            let three = RenderSettings { passes: Some(3), ..settings.clone() };
            let expected =
                pass_values(render_portion(&scene, &three, &rows, 1..2, &|_| {}).expect("renders").pixels);
            let (resumed, _, passes) = checkpointed(&scene, &three, &rows, &path);
            assert!(resumed == expected, "sppm: resumed from a pass");
            assert_eq!(passes, [1, 2, 3], "sppm: the saved pass is not rendered again");
            continue;
        }
        let (full_run, all_rays, _) = checkpointed(&scene, &settings, &rows, &path);
        assert!(full_run == expected, "{model:?}: a checkpointed render");
        // Killed in the middle of appending a chunk: the file is cut short.
        let bytes = std::fs::read(&path).expect("read");
        std::fs::write(&path, &bytes[..bytes.len() / 2]).expect("cut");
        let (resumed, rays, _) = checkpointed(&scene, &settings, &rows, &path);
        assert!(resumed == expected, "{model:?}: resumed");
        // Ray counts are deterministic: fewer rays means saved chunks were not rendered again.
        assert!(
            rays < all_rays,
            "{model:?}: the saved chunks were rendered again ({rays} of {all_rays} rays)"
        );
    }
}
