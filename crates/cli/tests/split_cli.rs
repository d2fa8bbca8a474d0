//! `rayterra render --tile/--pass/--checkpoint` and `rayterra merge` from the command line: parts
//! merge into the bytes of one render, a render killed with SIGTERM leaves no file but its
//! checkpoint and goes on from it, and options that do not fit together are refused.

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn rayterra(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .args(args)
        .current_dir(dir)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_ARRAY_TASK_COUNT")
        .env_remove("JOB_COMPLETION_INDEX")
        .output()
        .expect("rayterra runs")
}

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes").join(name).display().to_string()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn tiles_and_passes_from_the_command_line_merge_into_one_render() {
    let dir = tempfile::tempdir().expect("temp dir");
    let cornell = scene("cornell.txt");
    let common = ["render", &cornell, "-q", "--size", "48x40", "--model", "photon", "--photons", "5000"];
    let mut parts = Vec::new();
    for tile in 0..3 {
        for pass in 0..2 {
            let name = format!("part-{tile}-{pass}.exr");
            let (t, p) = (format!("{tile}/3"), format!("{pass}/2"));
            let mut args = common.to_vec();
            args.extend(["--tile", &t, "--pass", &p, "-o", &name]);
            let out = rayterra(&args, dir.path());
            assert!(out.status.success(), "{}", stderr(&out));
            parts.push(name);
        }
    }
    let mut merge = vec!["merge", "-q", "-o", "merged.exr"];
    merge.extend(parts.iter().map(String::as_str));
    assert!(rayterra(&merge, dir.path()).status.success());
    let mut whole = common.to_vec();
    whole.extend(["--passes", "2", "-o", "whole.exr"]);
    assert!(rayterra(&whole, dir.path()).status.success());
    let read = |name: &str| std::fs::read(dir.path().join(name)).expect("image");
    assert!(
        read("merged.exr") == read("whole.exr"),
        "two passes in three tiles are the render of two passes"
    );

    // A part missing, and parts of another render, are refused by name.
    let out = rayterra(&["merge", "part-0-0.exr", "part-1-0.exr", "-o", "x.png"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("missing: tile 0/3 of pass 1/2"), "{}", stderr(&out));
    let mut other = common.to_vec();
    other.extend(["--seed", "7", "--tile", "0/3", "--pass", "0/2", "-o", "other.exr"]);
    assert!(rayterra(&other, dir.path()).status.success());
    let mut mixed = vec!["merge", "-o", "x.png", "other.exr"];
    mixed.extend(parts.iter().skip(1).map(String::as_str));
    let out = rayterra(&mixed, dir.path());
    assert!(
        stderr(&out).contains("settings differ") && stderr(&out).contains("other.exr"),
        "{}",
        stderr(&out)
    );
    assert!(!dir.path().join("x.png").exists());
}

#[test]
fn options_that_do_not_fit_together_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let cornell = scene("cornell.txt");
    let refused = |args: &[&str], expected: &str| {
        let mut all = vec!["render", &cornell, "-q"];
        all.extend(args);
        let out = rayterra(&all, dir.path());
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        assert!(stderr(&out).contains(expected), "{args:?}: {}", stderr(&out));
    };
    refused(&["--tile", "1/4", "-o", "part.png"], "name the output `.exr`");
    // A malformed K/N is a usage error (exit status 2), as the README says of malformed options.
    let out = rayterra(&["render", &cornell, "-q", "--tile", "4/4", "-o", "part.exr"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("numbered from 0 to 3"), "{}", stderr(&out));
    refused(&["--tile", "auto", "-o", "part.exr"], "SLURM_ARRAY_TASK_COUNT is not set");
    refused(&["--pass", "auto/4", "-o", "part.exr"], "JOB_COMPLETION_INDEX");
    refused(&["--pass", "0/4", "--passes", "3", "-o", "part.exr"], "--passes says 3");
    refused(&["--passes", "3", "--runs", "2"], "disagree");
    refused(&["--tile", "0/1000", "--size", "40x30", "-o", "part.exr"], "at most 30 tiles");
    assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 0, "nothing was written");
}

#[cfg(unix)]
#[test]
fn a_render_killed_with_sigterm_resumes_from_its_checkpoint() {
    let dir = tempfile::tempdir().expect("temp dir");
    let cornell = scene("cornell.txt");
    let args =
        ["render", &cornell, "-q", "--size", "96x96", "--model", "path", "--spp", "48", "--threads", "1"];
    let mut uninterrupted = args.to_vec();
    uninterrupted.extend(["-o", "expected.png"]);
    assert!(rayterra(&uninterrupted, dir.path()).status.success());

    let mut checkpointed = args.to_vec();
    checkpointed.extend(["-o", "out.png", "--checkpoint", "render.checkpoint"]);
    let mut child = Command::new(env!("CARGO_BIN_EXE_rayterra"))
        .args(&checkpointed)
        .current_dir(dir.path())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("starts");
    // Killed once a few chunks of rows are saved.
    let checkpoint = dir.path().join("render.checkpoint");
    let start = Instant::now();
    while std::fs::metadata(&checkpoint).map_or(0, |m| m.len()) < 3 * 96 * 3 * 48 {
        assert!(start.elapsed() < Duration::from_secs(120), "no chunk was saved");
        assert!(child.try_wait().expect("wait").is_none(), "the render finished before it could be killed");
        std::thread::sleep(Duration::from_millis(20));
    }
    let status = Command::new("kill").args(["-TERM", &child.id().to_string()]).status().expect("kill");
    assert!(status.success());
    let killed = child.wait_with_output().expect("exits");
    assert_eq!(killed.status.code(), Some(130), "{}", stderr(&killed));
    let mut left: Vec<String> = std::fs::read_dir(dir.path())
        .expect("dir")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["expected.png", "render.checkpoint"], "no output and no temporary file");

    let resumed = rayterra(&checkpointed, dir.path());
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    assert!(stderr(&resumed).contains("note: resuming from `render.checkpoint`"), "{}", stderr(&resumed));
    let read = |name: &str| std::fs::read(dir.path().join(name)).expect("image");
    assert!(read("out.png") == read("expected.png"), "the resumed render differs from the uninterrupted one");
    assert!(!checkpoint.exists(), "the checkpoint is removed once the image is written");
}

#[test]
fn merge_refuses_a_damaged_part_and_an_output_that_is_an_input() {
    let dir = tempfile::tempdir().expect("temp dir");
    let cornell = scene("cornell.txt");
    for tile in ["0/2", "1/2"] {
        let name = format!("part-{}.exr", &tile[..1]);
        let args = ["render", &cornell, "-q", "--size", "32x24", "--spp", "1", "--tile", tile, "-o", &name];
        let out = rayterra(&args, dir.path());
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let part = dir.path().join("part-1.exr");
    let original = std::fs::read(&part).expect("part");
    // `-o` naming one of the inputs, as another string: refused, the part untouched.
    for output in ["./part-1.exr", "part-1.exr"] {
        let out = rayterra(&["merge", "part-0.exr", "part-1.exr", "-o", output], dir.path());
        assert_eq!(out.status.code(), Some(1), "{output}");
        assert!(stderr(&out).contains("would overwrite one of its own inputs"), "{}", stderr(&out));
        assert_eq!(std::fs::read(&part).expect("part"), original, "{output}");
    }
    // One flipped bit in the last byte of pixel data (the end of the file): refused by name.
    let mut damaged = original.clone();
    let last = damaged.len() - 1;
    damaged[last] ^= 0x01;
    std::fs::write(&part, &damaged).expect("damaged");
    let out = rayterra(&["merge", "part-0.exr", "part-1.exr", "-o", "merged.png"], dir.path());
    assert_eq!(out.status.code(), Some(1));
    let message = stderr(&out);
    // (A flip the decoder notices is "cannot read"; one it does not, the checksum's "damaged".)
    let named = message.contains("`part-1.exr`");
    assert!(named && (message.contains("damaged") || message.contains("cannot read")), "{message}");
    assert!(!dir.path().join("merged.png").exists());
    std::fs::write(&part, &original).expect("repaired");
    let out = rayterra(&["merge", "part-0.exr", "part-1.exr", "-o", "merged.png", "-q"], dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
}
