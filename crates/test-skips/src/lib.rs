//! Skipped test groups. Tests that need what a machine may lack (a GPU, a display, the course's
//! test data) call [`skip`] instead of running: it prints a loud banner past the test harness's
//! output capture and records the skip under `target/test-skips/`, keyed by the `cargo test`
//! process, so that this package's `skip_report` test, which Cargo runs after the other
//! members' tests, ends the run with one line counting them.
//!
//! Whether a skip is allowed at all (it is not under CI) is the caller's decision.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

/// The folder where the skips of the `cargo test` process that ran this test binary are
/// recorded: `target/test-skips/<process id of cargo>`.
pub fn run_folder() -> Option<PathBuf> {
    // Test binaries live in target/<profile>/deps/.
    let exe = std::env::current_exe().ok()?;
    let target = exe.parent()?.parent()?.parent()?;
    Some(target.join("test-skips").join(run_id().to_string()))
}

/// The environment variable that hands a test's run on to a process it starts (a test that
/// re-runs itself under `xvfb-run`): set it to [`run_id`] on the child.
pub const RUN_VARIABLE: &str = "TEST_SKIPS_RUN";

/// The run this process belongs to: [`RUN_VARIABLE`] if set, else the process that runs the test
/// binaries (`cargo test`, or a shell when a binary is run by hand).
pub fn run_id() -> u32 {
    std::env::var(RUN_VARIABLE).ok().and_then(|v| v.parse().ok()).unwrap_or_else(parent_id)
}

#[cfg(unix)]
fn parent_id() -> u32 {
    std::os::unix::process::parent_id()
}

/// Without a parent process id, all runs share one record.
#[cfg(not(unix))]
fn parent_id() -> u32 {
    0
}

/// The folder `shared/SUB` of the shared test data, found beside the repository whose crate is at
/// `manifest_dir` (`env!("CARGO_MANIFEST_DIR")` of the caller) or in the nearest folder above it
/// (so that a git worktree in a subfolder finds it too), known by its `SOURCES.md`. Without it,
/// the test group `group` is skipped loudly and `None` returned; under CI (`CI=true`) that is a
/// failure instead.
pub fn shared_data(manifest_dir: &Path, sub: &str, group: &str) -> Option<PathBuf> {
    let root = manifest_dir.join("../..");
    let found = root
        .ancestors()
        .skip(1)
        .map(|dir| dir.join("shared").join(sub))
        .find(|dir| dir.join("SOURCES.md").is_file());
    if found.is_some() {
        return found;
    }
    let reason = format!("the test data is not in shared/{sub} beside {} or above it", root.display());
    assert!(std::env::var("CI").as_deref() != Ok("true"), "CI=true, so this cannot be skipped: {reason}");
    skip(group, &reason);
    None
}

/// Skips a test group: prints `==== SKIPPED group: reason ====` to the terminal (not through the
/// harness's capture, so it is seen even when the test passes) and records it for the count at
/// the end of the run.
pub fn skip(group: &str, reason: &str) {
    let _ = writeln!(std::io::stderr(), "\n==== SKIPPED {group}: {reason} ====\n");
    record(group, reason);
}

/// Records a skip without printing it.
fn record(group: &str, reason: &str) {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let Some(dir) = run_folder() else { return };
    if std::fs::create_dir_all(&dir).is_err() {
        return;
    }
    let name = format!("{}-{}.txt", std::process::id(), NEXT.fetch_add(1, Ordering::Relaxed));
    let first_line = reason.lines().next().unwrap_or("");
    let _ = std::fs::write(dir.join(name), format!("{group}: {first_line}\n"));
}

/// The skips recorded in `run_folder()`, one `group: reason` line each, sorted.
pub fn recorded() -> Vec<String> {
    let Some(dir) = run_folder() else { return Vec::new() };
    let Ok(entries) = std::fs::read_dir(&dir) else { return Vec::new() };
    let mut skips: Vec<String> = entries
        .filter_map(Result::ok)
        .filter_map(|e| std::fs::read_to_string(e.path()).ok())
        .map(|text| text.trim_end().to_owned())
        .collect();
    skips.sort();
    skips
}

/// The closing line for `skips`: how many groups were skipped, and for which reasons.
pub fn summary(skips: &[String]) -> Option<String> {
    if skips.is_empty() {
        return None;
    }
    let mut groups: Vec<&str> = skips.iter().map(|s| s.split(": ").next().unwrap_or(s)).collect();
    groups.dedup();
    let s = if skips.len() == 1 { "" } else { "s" };
    Some(format!(
        "==== {} test group{s} SKIPPED in this run ({}); see the SKIPPED banners above ====",
        skips.len(),
        groups.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_counts_and_names_the_groups() {
        assert_eq!(summary(&[]), None);
        let skips =
            ["a GPU test: no adapter".to_owned(), "a GPU test: no adapter".into(), "window: no Xvfb".into()];
        assert_eq!(
            summary(&skips).as_deref(),
            Some(
                "==== 3 test groups SKIPPED in this run (a GPU test, window); see the SKIPPED banners above ===="
            )
        );
    }
}
