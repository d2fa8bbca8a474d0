//! The command line of split renders: `--tile` and `--pass` (`K/N`, or `auto` from a batch
//! scheduler's task index), and what a part file says of the render it belongs to.

use std::path::{Path, PathBuf};

use raytracer::parts::{SceneDigest, Split};
use raytracer::render::Rows;
use raytracer::render::checkpoint::Checkpoint;
use raytracer::scene::SourceFile;
use raytracer::{RenderSettings, Sampling};

/// Variables that hold a task's index, in the order they are looked for: a Slurm array task's,
/// then a Kubernetes Indexed Job's.
const INDEX_VARIABLES: [&str; 2] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"];
/// The variable that holds the number of tasks of a Slurm array.
const COUNT_VARIABLE: &str = "SLURM_ARRAY_TASK_COUNT";

/// Reads `--tile` or `--pass` (`flag`): `K/N`; `auto`, with `K` and `N` from the Slurm array
/// task's variables; or `auto/N`, with `K` from Slurm's or Kubernetes' task index.
pub fn resolve(spec: &str, flag: &str, env: impl Fn(&str) -> Option<String>) -> Result<Split, String> {
    let Some(rest) = spec.strip_prefix("auto") else {
        return Split::parse(spec).map_err(|e| format!("--{flag}: {e}"));
    };
    let count =
        match rest {
            "" => {
                let text = env(COUNT_VARIABLE).ok_or_else(|| {
                format!(
                    "--{flag} auto: {COUNT_VARIABLE} is not set (not a Slurm array task?); give the number \
                     of parts as --{flag} auto/N"
                )
            })?;
                text.trim()
                    .parse::<u32>()
                    .map_err(|_| format!("--{flag} auto: {COUNT_VARIABLE} is `{text}`, not a count"))?
            }
            _ => rest.strip_prefix('/').and_then(|n| n.parse::<u32>().ok()).filter(|&n| n > 0).ok_or_else(
                || format!("--{flag}: expected K/N, auto or auto/N (N at least 1), not `{spec}`"),
            )?,
        };
    let (variable, text) =
        INDEX_VARIABLES.iter().find_map(|v| env(v).map(|value| (*v, value))).ok_or_else(|| {
            format!(
                "--{flag} {spec}: none of {} is set (not a Slurm array or Kubernetes Indexed Job task?)",
                INDEX_VARIABLES.join(", ")
            )
        })?;
    let index = text
        .trim()
        .parse::<u32>()
        .map_err(|_| format!("--{flag} {spec}: {variable} is `{text}`, not an index"))?;
    Split::new(index, count).ok_or_else(|| {
        format!(
            "--{flag} {spec}: {variable} is {index}, but there are {count} parts, numbered from 0 (submit the \
             array as --array=0-{})",
            count - 1
        )
    })
}

/// Checks the form of a `--tile` or `--pass` value without the environment: `K/N` (K below N),
/// `auto` or `auto/N` (N at least 1).
pub fn check_form(spec: &str) -> Result<(), String> {
    match spec.strip_prefix("auto") {
        None => Split::parse(spec).map(drop),
        Some("") => Ok(()),
        Some(rest) => rest
            .strip_prefix('/')
            .and_then(|n| n.parse::<u32>().ok())
            .filter(|&n| n > 0)
            .map(drop)
            .ok_or_else(|| format!("expected K/N, auto or auto/N (N at least 1), not `{spec}`")),
    }
}

/// Everything in `settings` that shapes the pixels, as one line of words (the worker threads do
/// not): part files and checkpoints keep it, and `merge` shows it when parts disagree.
pub fn settings_line(settings: &RenderSettings) -> String {
    let sampling = match settings.sampling {
        Sampling::Adaptive => "adaptive".to_string(),
        Sampling::Uniform(n) => format!("{n} samples a pixel"),
    };
    let or_scene = |value: Option<u64>| value.map_or_else(|| "the scene's".to_string(), |n| n.to_string());
    format!(
        "rayterra {}; model {}; size {}x{}; sampling {sampling}; seed {}; max depth {}; photons {}; sppm passes {}; runs {}",
        env!("CARGO_PKG_VERSION"),
        settings.model.name(),
        settings.width,
        settings.height,
        settings.seed,
        settings.max_depth,
        or_scene(settings.photons),
        or_scene(settings.passes),
        settings.runs
    )
}

/// The digest of a scene: its text and the bytes of every file it read (in the scene's order;
/// by content, not by path, so that machines that mount the files elsewhere agree).
pub fn scene_digest(source: &SourceFile, inputs: &[PathBuf]) -> Result<String, String> {
    let mut digest = SceneDigest::new();
    digest.add("scene", source.text().as_bytes());
    for (i, path) in inputs.iter().enumerate() {
        let bytes = atomic_file::read_regular(path)
            .map_err(|e| format!("cannot read `{}` again: {e}", path.display()))?;
        digest.add(&format!("input {i}"), &bytes);
    }
    Ok(digest.finish())
}

/// Opens (or starts) the checkpoint at `path` of the render of `rows` that `key` describes, and
/// says what it resumes.
pub fn open_checkpoint(path: &Path, key: &str, rows: &Rows) -> Result<Checkpoint, String> {
    let checkpoint = Checkpoint::open(path, key, rows).map_err(|e| e.to_string())?;
    match checkpoint.resumed() {
        (0, 0) => {}
        (chunks, 0) => {
            errln!("note: resuming from `{}`: {chunks} chunks of rows were done", path.display())
        }
        (_, passes) => errln!("note: resuming from `{}` after {passes} SPPM passes", path.display()),
    }
    Ok(checkpoint)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| vars.iter().find(|(k, _)| *k == name).map(|(_, v)| v.to_string())
    }

    #[test]
    fn the_settings_line_has_no_debug_formatting() {
        let mut settings = RenderSettings {
            width: 4,
            height: 3,
            sampling: Sampling::Adaptive,
            threads: None,
            seed: 7,
            model: raytracer::integrator::Model::Classic,
            photons: None,
            memory_limit: 1 << 30,
            max_depth: 5,
            passes: None,
            runs: 1,
        };
        let line = settings_line(&settings);
        assert!(line.contains("sampling adaptive") && line.contains("photons the scene's"), "{line}");
        settings.sampling = Sampling::Uniform(16);
        settings.photons = Some(1000);
        let line = settings_line(&settings);
        assert!(line.contains("sampling 16 samples a pixel") && line.contains("photons 1000"), "{line}");
        assert!(!line.contains("Some") && !line.contains("None") && !line.contains("Uniform"), "{line}");
    }

    #[test]
    fn malformed_splits_are_found_without_the_environment() {
        for good in ["0/1", "2/8", "auto", "auto/4"] {
            assert_eq!(check_form(good), Ok(()), "{good}");
        }
        for bad in ["3/2", "1", "a/b", "auto/0", "auto/", "autox", "2/0"] {
            assert!(check_form(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn explicit_and_automatic_parts() {
        let none = env(&[]);
        assert_eq!(resolve("2/5", "tile", &none), Ok(Split { index: 2, count: 5 }));
        assert!(resolve("5/5", "tile", &none).is_err());
        let slurm = env(&[("SLURM_ARRAY_TASK_ID", "3"), ("SLURM_ARRAY_TASK_COUNT", "4")]);
        assert_eq!(resolve("auto", "tile", &slurm), Ok(Split { index: 3, count: 4 }));
        assert_eq!(resolve("auto/8", "pass", &slurm), Ok(Split { index: 3, count: 8 }));
        let k8s = env(&[("JOB_COMPLETION_INDEX", "1")]);
        assert_eq!(resolve("auto/2", "pass", &k8s), Ok(Split { index: 1, count: 2 }));
        let error = resolve("auto", "pass", &k8s).expect_err("no count");
        assert!(error.contains("auto/N"), "{error}");
        assert!(resolve("auto/2", "pass", &none).expect_err("no index").contains("JOB_COMPLETION_INDEX"));
        let one_based = env(&[("SLURM_ARRAY_TASK_ID", "4"), ("SLURM_ARRAY_TASK_COUNT", "4")]);
        assert!(resolve("auto", "tile", &one_based).expect_err("4 of 4").contains("--array=0-3"));
        for bad in ["auto/0", "auto/x", "autox", "auto/"] {
            assert!(resolve(bad, "tile", &slurm).is_err(), "{bad}");
        }
    }
}
