//! The job files of `deploy/` on real schedulers: `deploy/slurm/render.sbatch` submitted with
//! `sbatch` to a running Slurm (CI starts a one-node cluster with `deploy/slurm/local-cluster.sh`),
//! and the commands of `deploy/kubernetes/render-job.yaml` run here with the index variables a
//! Kubernetes Indexed Job sets. Every merged image must be the very bytes of a render in one
//! process. Without Slurm the Slurm tests are skipped with a loud message, except under CI.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;
use std::time::{Duration, Instant, SystemTime};

/// Slurm tests run one at a time: they share the cluster's two CPUs.
static SLURM: Mutex<()> = Mutex::new(());

fn rayterra() -> &'static Path {
    Path::new(env!("CARGO_BIN_EXE_rayterra"))
}

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("workspace")
}

/// A fresh folder under `target/tmp` (the Slurm jobs, run by the daemon, must see it).
fn work_dir(name: &str) -> PathBuf {
    let dir = workspace().join("target/tmp/cluster").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("work dir");
    dir
}

fn run(cmd: &mut Command) -> Output {
    let out = cmd.output().unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
    assert!(
        out.status.success(),
        "{cmd:?} failed ({}):\n{}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Renders locally with the same options, returns the image's bytes.
fn local_render(dir: &Path, scene: &Path, args: &[&str]) -> Vec<u8> {
    let out = dir.join("local.png");
    run(Command::new(rayterra()).arg("render").arg(scene).args(args).arg("-q").arg("-o").arg(&out));
    std::fs::read(&out).expect("local render")
}

/// Whether a Slurm cluster takes jobs here; a loud skip (or, under CI, a failure) when not.
fn slurm_available() -> bool {
    let up = Command::new("sinfo").args(["-h", "-o", "%T"]).output().ok().filter(|o| o.status.success()).map(
        |o| {
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .any(|s| ["idle", "mixed", "allocated"].contains(&s.trim()))
        },
    );
    if up == Some(true) {
        return true;
    }
    let message = "no Slurm cluster takes jobs here (start one with `deploy/slurm/local-cluster.sh` as root)";
    if std::env::var_os("CI").is_some() {
        panic!("{message} (required under CI)");
    }
    test_skips::skip("Slurm tests", message);
    false
}

/// `sbatch` of the real job file, with the job's environment; returns the array's job id.
fn submit(dir: &Path, array: &str, env: &[(&str, String)]) -> String {
    let exports: Vec<String> = env.iter().map(|(k, v)| format!("{k}={v}")).collect();
    let out = run(Command::new("sbatch")
        .arg("--parsable")
        .arg(format!("--array={array}"))
        .arg(format!("--chdir={}", dir.display()))
        .arg(format!("--export=ALL,{}", exports.join(",")))
        .arg(workspace().join("deploy/slurm/render.sbatch")));
    String::from_utf8_lossy(&out.stdout).trim().split(';').next().expect("job id").to_owned()
}

/// The states of the jobs whose name starts with `rayterra-` (pending, running...), by job id.
fn queue() -> Vec<(String, String)> {
    let out = run(Command::new("squeue").args(["-h", "-r", "-o", "%i %T %j"]));
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.contains(" rayterra-"))
        .filter_map(|l| {
            let mut words = l.split_whitespace();
            Some((words.next()?.to_owned(), words.next()?.to_owned()))
        })
        .collect()
}

/// Waits until no rayterra job is queued or running.
fn wait_for_queue(timeout: Duration) {
    let start = Instant::now();
    while !queue().is_empty() {
        assert!(start.elapsed() < timeout, "Slurm jobs still queued after {timeout:?}: {:?}", queue());
        std::thread::sleep(Duration::from_millis(500));
    }
}

/// The job logs, for failure messages.
fn logs(dir: &Path) -> String {
    let mut text = String::new();
    for entry in std::fs::read_dir(dir).expect("dir").flatten() {
        if entry.file_name().to_string_lossy().ends_with(".log") {
            text += &format!(
                "--- {}\n{}",
                entry.path().display(),
                std::fs::read_to_string(entry.path()).unwrap_or_default()
            );
        }
    }
    text
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|d| d.flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect())
        .unwrap_or_default();
    names.sort();
    names
}

/// A 4-task array on a scene of ours, then the merge job, against a local render.
fn slurm_round_trip(name: &str, mode: &str, array_args: &str, local_args: &[&str]) {
    let Ok(_guard) = SLURM.lock() else { panic!("an earlier Slurm test failed") };
    if !slurm_available() {
        return;
    }
    let dir = work_dir(name);
    let scene = workspace().join("scenes/cornell.txt");
    let output = dir.join("final.png");
    submit(
        &dir,
        "0-3",
        &[
            ("SCENE", scene.display().to_string()),
            ("OUTPUT", output.display().to_string()),
            ("MODE", mode.to_owned()),
            ("RAYTERRA", rayterra().display().to_string()),
            ("RAYTERRA_ARGS", array_args.to_owned()),
        ],
    );
    wait_for_queue(Duration::from_secs(300));
    let merged = std::fs::read(&output).unwrap_or_else(|_| panic!("no merged image; logs:\n{}", logs(&dir)));
    assert_eq!(files_in(&dir.join("parts")), ["part-0.exr", "part-1.exr", "part-2.exr", "part-3.exr"]);
    assert!(
        merged == local_render(&dir, &scene, local_args),
        "{mode}: the merged image differs from the local render"
    );
}

#[test]
fn slurm_tiles_merge_into_the_local_render() {
    slurm_round_trip("tiles", "tile", "--size 96x96", &["--size", "96x96"]);
}

#[test]
fn slurm_passes_merge_into_the_local_render() {
    // Four passes of 2 samples are the render of 8.
    slurm_round_trip(
        "passes",
        "pass",
        "--size 64x64 --model path --spp 2",
        &["--size", "64x64", "--model", "path", "--spp", "8"],
    );
}

#[test]
fn a_cancelled_task_resubmitted_alone_completes_the_image() {
    let Ok(_guard) = SLURM.lock() else { panic!("an earlier Slurm test failed") };
    if !slurm_available() {
        return;
    }
    let dir = work_dir("cancelled");
    let parts = dir.join("parts");
    let scene = workspace().join("scenes/cornell.txt");
    let output = dir.join("final.png");
    // Slow enough (one thread) that a task can be cancelled while it renders.
    let args = "--size 160x160 --model path --spp 128";
    let env = |parts_total: &str| {
        vec![
            ("SCENE", scene.display().to_string()),
            ("OUTPUT", output.display().to_string()),
            ("PARTS", parts_total.to_owned()),
            ("RAYTERRA", rayterra().display().to_string()),
            ("RAYTERRA_ARGS", args.to_owned()),
        ]
    };
    let job = submit(&dir, "0-3", &env("4"));
    let victim = format!("{job}_1");
    let start = Instant::now();
    while !queue().iter().any(|(id, state)| *id == victim && state == "RUNNING") {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "task 1 never ran: {:?}\n{}",
            queue(),
            logs(&dir)
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    // Cancelled once it has saved some of its work in its checkpoint.
    let checkpoint = parts.join("part-1.checkpoint");
    while std::fs::metadata(&checkpoint).map_or(0, |m| m.len()) < 20_000 {
        assert!(start.elapsed() < Duration::from_secs(180), "task 1 saved nothing\n{}", logs(&dir));
        std::thread::sleep(Duration::from_millis(50));
    }
    run(Command::new("scancel").arg(&victim));
    wait_for_queue(Duration::from_secs(300));
    // The cancelled task left no part and no temporary file, only its checkpoint; the others
    // left their parts, and the merge job was cancelled with the array.
    assert_eq!(
        files_in(&parts),
        ["part-0.exr", "part-1.checkpoint", "part-2.exr", "part-3.exr"],
        "logs:\n{}",
        logs(&dir)
    );
    assert!(!output.exists(), "the merge job ran although a part is missing");
    let stamps = |names: &[&str]| -> Vec<SystemTime> {
        names
            .iter()
            .map(|n| std::fs::metadata(parts.join(n)).and_then(|m| m.modified()).expect("part"))
            .collect()
    };
    let before = stamps(&["part-0.exr", "part-2.exr", "part-3.exr"]);

    submit(&dir, "1", &env("4"));
    wait_for_queue(Duration::from_secs(300));
    let merged = std::fs::read(&output).unwrap_or_else(|_| panic!("no merged image; logs:\n{}", logs(&dir)));
    assert_eq!(
        stamps(&["part-0.exr", "part-2.exr", "part-3.exr"]),
        before,
        "a finished part was rendered again"
    );
    assert_eq!(files_in(&parts), ["part-0.exr", "part-1.exr", "part-2.exr", "part-3.exr"]);
    assert!(logs(&dir).contains("note: resuming from"), "task 1 started again from nothing");
    let local = local_render(&dir, &scene, &["--size", "160x160", "--model", "path", "--spp", "128"]);
    assert!(merged == local, "the completed image differs from the local render");
}

/// The container of the Job named `name` in the manifest: its environment and its shell script.
fn container(docs: &[yaml_rust2::Yaml], name: &str) -> (Vec<(String, String)>, String) {
    let job = docs
        .iter()
        .find(|d| d["kind"].as_str() == Some("Job") && d["metadata"]["name"].as_str() == Some(name))
        .unwrap_or_else(|| panic!("no Job {name} in the manifest"));
    let c = &job["spec"]["template"]["spec"]["containers"][0];
    assert_eq!(c["command"][0].as_str(), Some("sh"), "{name}: the command is a shell script");
    let env = c["env"]
        .as_vec()
        .expect("env")
        .iter()
        .map(|e| {
            (e["name"].as_str().expect("name").to_owned(), e["value"].as_str().expect("value").to_owned())
        })
        .collect();
    (env, c["args"][0].as_str().expect("script").to_owned())
}

#[test]
fn the_kubernetes_jobs_commands_render_and_merge_the_image() {
    let text =
        std::fs::read_to_string(workspace().join("deploy/kubernetes/render-job.yaml")).expect("manifest");
    let docs = yaml_rust2::YamlLoader::load_from_str(&text).expect("valid YAML");
    let render_job = docs
        .iter()
        .find(|d| d["metadata"]["name"].as_str() == Some("rayterra-render"))
        .expect("the render Job");
    let spec = &render_job["spec"];
    assert_eq!(spec["completionMode"].as_str(), Some("Indexed"));
    let parts = spec["completions"].as_i64().expect("completions");
    assert_eq!(spec["parallelism"].as_i64(), Some(parts));

    let dir = work_dir("kubernetes");
    let scene = workspace().join("scenes/cornell.txt");
    let bin_dir = rayterra().parent().expect("bin dir").to_path_buf();
    let path = format!("{}:{}", bin_dir.display(), std::env::var("PATH").unwrap_or_default());
    // The manifest's values, with the volume's paths moved here and a small image.
    let local = |env: Vec<(String, String)>| -> Vec<(String, String)> {
        env.into_iter()
            .map(|(k, v)| match k.as_str() {
                "SCENE" => (k, scene.display().to_string()),
                "PARTS_DIR" => (k, dir.join("parts").display().to_string()),
                "OUTPUT" => (k, dir.join("final.png").display().to_string()),
                "RAYTERRA_ARGS" => (k, "--size 80x80".into()),
                _ => (k, v),
            })
            .collect()
    };
    let (env, script) = container(&docs, "rayterra-render");
    let env = local(env);
    assert!(env.iter().any(|(k, v)| k == "PARTS" && *v == parts.to_string()), "PARTS matches completions");
    for index in 0..parts {
        run(Command::new("sh")
            .arg("-c")
            .arg(&script)
            .envs(env.clone())
            .env("JOB_COMPLETION_INDEX", index.to_string())
            .env("PATH", &path));
    }
    let (merge_env, merge_script) = container(&docs, "rayterra-merge");
    run(Command::new("sh").arg("-c").arg(&merge_script).envs(local(merge_env)).env("PATH", &path));
    let merged = std::fs::read(dir.join("final.png")).expect("merged image");
    assert!(
        merged == local_render(&dir, &scene, &["--size", "80x80"]),
        "the merged image differs from the local render"
    );
}
