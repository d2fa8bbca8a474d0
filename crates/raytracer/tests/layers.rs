//! The crates' layers (`docs/architecture.md`): each module belongs to a tier, and no module
//! imports from a tier above its own; nor do two files import each other, directly or round a
//! longer circle.
//!
//! The check reads the sources: every `crate::` and `super::` path in code that is not a test
//! (comments, `#[cfg(test)]` modules and test-only files are left out), use trees expanded. A
//! module's re-exports of its own children (`pub use child::Item`, the facades that keep the
//! public paths) are not imports. Items imported from the crate root must be imported from the
//! module that defines them.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The ray tracer's tiers, bottom up: module path prefixes (the longest that matches decides).
const RAYTRACER_TIERS: &[(&str, u32)] = &[
    ("base", 0),
    ("geometry", 1),
    ("accel", 1),
    ("scene", 2),
    ("material", 2),
    ("light", 2),
    ("scene::course", 3),
    ("scene::mitsuba", 3),
    ("texture", 4),
    ("procedural", 4),
    ("camera", 4),
    ("prepare", 4),
    ("integrator", 5),
    ("render", 6),
    ("parts", 6),
];

/// The names of the ray tracer's tiers, for messages.
const RAYTRACER_TIER_NAMES: &[&str] = &[
    "base",
    "geometry and acceleration",
    "scene description",
    "scene formats",
    "preparation",
    "integrators",
    "render and parts",
];

/// The terrain engine's tiers, bottom up: pure state and arithmetic (the camera, file output,
/// the allocator's settings), the scene's numbers, the world's data (no GPU), the look and the
/// key bindings, the renderer, what draws with it, the panel, and the window.
const TERRAIN_TIERS: &[(&str, u32)] = &[
    ("heap", 0),
    ("output", 0),
    ("camera", 0),
    ("config", 1),
    ("world", 2),
    ("settings", 3),
    ("controls", 3),
    ("render", 4),
    ("headless", 5),
    ("overlay", 5),
    ("panel", 6),
    ("window", 7),
];

/// The names of the terrain engine's tiers, for messages.
const TERRAIN_TIER_NAMES: &[&str] = &[
    "base",
    "scene numbers",
    "world data",
    "look and controls",
    "renderer",
    "off-screen and overlay",
    "panel",
    "window",
];

#[test]
fn no_ray_tracer_module_imports_from_a_tier_above_its_own() {
    let problems = check(&crate_src("raytracer"), RAYTRACER_TIERS, RAYTRACER_TIER_NAMES);
    assert!(problems.is_empty(), "layer violations in crates/raytracer:\n{}", problems.join("\n"));
}

#[test]
fn no_terrain_module_imports_from_a_tier_above_its_own() {
    let problems = check(&crate_src("terrain"), TERRAIN_TIERS, TERRAIN_TIER_NAMES);
    assert!(problems.is_empty(), "layer violations in crates/terrain:\n{}", problems.join("\n"));
}

#[test]
fn an_upward_import_is_found() {
    let dir = tempfile::tempdir().expect("temp dir");
    let src = dir.path();
    std::fs::create_dir_all(src.join("base")).expect("mkdir");
    std::fs::write(src.join("lib.rs"), "pub mod base;\npub mod render;\n").expect("write");
    std::fs::write(src.join("base/mod.rs"), "//! Base.\npub mod rows;\n").expect("write");
    std::fs::write(
        src.join("base/rows.rs"),
        "// crate::render::Nothing in a comment is no import.\nuse crate::{render::{Settings, Stage}};\n\
         #[cfg(test)]\nmod tests {\n    use crate::render::Anything;\n}\n",
    )
    .expect("write");
    std::fs::write(src.join("render.rs"), "pub struct Settings;\n").expect("write");
    let problems = check(src, &[("base", 0), ("render", 1)], &["base", "render"]);
    assert_eq!(problems.len(), 2, "{problems:#?}");
    assert!(problems[0].contains("base/rows.rs imports `crate::render::Settings`"), "{}", problems[0]);
    assert!(problems[0].contains("tier `render`"), "{}", problems[0]);
    assert!(problems[1].contains("crate::render::Stage"), "{}", problems[1]);

    // A circle of two files of one tier.
    std::fs::write(src.join("base/rows.rs"), "use super::tiles::Tile;\n").expect("write");
    std::fs::write(src.join("base/tiles.rs"), "use crate::base::rows::Rows;\n").expect("write");
    std::fs::write(src.join("base/mod.rs"), "pub mod rows;\npub mod tiles;\n").expect("write");
    let problems = check(src, &[("base", 0), ("render", 1)], &["base", "render"]);
    assert_eq!(problems.len(), 1, "{problems:#?}");
    assert!(problems[0].contains("import each other"), "{}", problems[0]);
}

fn crate_src(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(name).join("src")
}

/// A source file as a module: its path segments (`scene::course::lexer`; the crate root is empty).
#[derive(Debug)]
struct Module {
    file: String,
    path: Vec<String>,
    code: String,
}

/// Every layer problem of the crate whose sources are in `src`.
fn check(src: &Path, tiers: &[(&str, u32)], names: &[&str]) -> Vec<String> {
    let modules = read_modules(src);
    let known: BTreeSet<Vec<String>> = modules.iter().map(|m| m.path.clone()).collect();
    let mut problems = Vec::new();
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let by_path: BTreeMap<Vec<String>, &Module> = modules.iter().map(|m| (m.path.clone(), m)).collect();
    for m in &modules {
        let own = tier_of(&m.path, tiers);
        for target in imports(&m.code, &m.path) {
            let Some(first) = target.first() else { continue };
            if !known.iter().any(|k| k.first() == Some(first)) {
                problems.push(format!(
                    "{} imports `crate::{}` from the crate root: import it from the module that defines it",
                    m.file,
                    target.join("::")
                ));
                continue;
            }
            let theirs = tier_of(&target, tiers);
            if let (Some(own), Some(theirs)) = (own, theirs)
                && theirs > own
            {
                problems.push(format!(
                    "{} imports `crate::{}`: tier `{}` is above its own tier `{}`",
                    m.file,
                    target.join("::"),
                    names[theirs as usize],
                    names[own as usize]
                ));
            }
            // The file the path leads to: the longest module prefix of it.
            if let Some(to) = (1..=target.len()).rev().find_map(|n| by_path.get(&target[..n]))
                && to.file != m.file
            {
                edges.entry(m.file.clone()).or_default().insert(to.file.clone());
            }
        }
        if own.is_none() && !m.path.is_empty() {
            problems.push(format!("{} is in no tier: add its module to the table", m.file));
        }
    }
    for (a, targets) in &edges {
        for b in targets {
            if a < b && reaches(&edges, b, a) {
                problems.push(format!("{a} and {b} import each other (directly or round a circle)"));
            }
        }
    }
    problems
}

/// Whether `from` reaches `to` along import edges.
fn reaches(edges: &BTreeMap<String, BTreeSet<String>>, from: &str, to: &str) -> bool {
    let mut seen = BTreeSet::new();
    let mut stack = vec![from.to_string()];
    while let Some(f) = stack.pop() {
        if f == to {
            return true;
        }
        if seen.insert(f.clone())
            && let Some(next) = edges.get(&f)
        {
            stack.extend(next.iter().cloned());
        }
    }
    false
}

/// The tier of a module path: that of the longest table prefix that matches it.
fn tier_of(path: &[String], tiers: &[(&str, u32)]) -> Option<u32> {
    tiers
        .iter()
        .filter(|(prefix, _)| {
            let p: Vec<&str> = prefix.split("::").collect();
            p.len() <= path.len() && p.iter().zip(path).all(|(a, b)| *a == b)
        })
        .max_by_key(|(prefix, _)| prefix.len())
        .map(|&(_, tier)| tier)
}

/// The crate's source files as modules, without their test code.
fn read_modules(src: &Path) -> Vec<Module> {
    let mut files = Vec::new();
    collect(src, &mut files);
    let mut test_only: BTreeSet<PathBuf> = BTreeSet::new();
    let mut modules = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).expect("source file");
        let dir = f.parent().expect("folder");
        let own_dir = if is_folder_root(f) { dir.to_path_buf() } else { f.with_extension("") };
        for name in test_module_files(&text) {
            test_only.insert(own_dir.join(format!("{name}.rs")));
            test_only.insert(own_dir.join(&name).join("mod.rs"));
        }
    }
    for f in files {
        if test_only.contains(&f) {
            continue;
        }
        let text = std::fs::read_to_string(&f).expect("source file");
        let rel = f.strip_prefix(src).expect("under src");
        let mut path: Vec<String> =
            rel.with_extension("").iter().map(|s| s.to_string_lossy().into_owned()).collect();
        if is_folder_root(&f) {
            path.pop();
        }
        modules.push(Module { file: rel.to_string_lossy().into_owned(), path, code: code_of(&text) });
    }
    modules
}

fn is_folder_root(f: &Path) -> bool {
    matches!(f.file_name().and_then(|n| n.to_str()), Some("mod.rs" | "lib.rs" | "main.rs"))
}

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> =
        std::fs::read_dir(dir).expect("source folder").map(|e| e.expect("entry").path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            collect(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The names of modules a file declares for tests only (`#[cfg(test)] mod name;`).
fn test_module_files(text: &str) -> Vec<String> {
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    let mut names = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        if *line != "#[cfg(test)]" {
            continue;
        }
        let next = lines[i + 1..].iter().find(|l| !l.starts_with("#["));
        if let Some(decl) = next.and_then(|l| l.strip_prefix("mod ").or_else(|| l.strip_prefix("pub mod ")))
            && let Some(name) = decl.strip_suffix(';')
        {
            names.push(name.trim().to_string());
        }
    }
    names
}

/// The code of a file: comments removed, and everything from its first inline `#[cfg(test)]`
/// module on.
fn code_of(text: &str) -> String {
    let mut out = String::new();
    let lines: Vec<&str> = text.lines().collect();
    for (i, line) in lines.iter().enumerate() {
        if line.trim() == "#[cfg(test)]" {
            let next = lines[i + 1..].iter().map(|l| l.trim()).find(|l| !l.starts_with("#["));
            if next.is_some_and(|l| (l.starts_with("mod ") || l.starts_with("pub mod ")) && l.ends_with('{'))
            {
                break;
            }
        }
        let code = match line.find("//") {
            Some(at) if !line[..at].contains('"') => &line[..at],
            _ => line,
        };
        out.push_str(code);
        out.push('\n');
    }
    out
}

/// Every path that `code` (of the module at `here`) imports from its crate, as segments from the
/// crate root; use trees are expanded.
fn imports(code: &str, here: &[String]) -> Vec<Vec<String>> {
    let bytes = code.as_bytes();
    let mut found = Vec::new();
    let mut i = 0;
    while i < code.len() {
        let rest = &code[i..];
        let starts_word =
            i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_' || bytes[i - 1] == b':');
        let (base, after) = if starts_word && rest.starts_with("crate::") {
            (Vec::new(), i + "crate::".len())
        } else if starts_word && rest.starts_with("super::") {
            let mut at = i;
            let mut path = here.to_vec();
            while code[at..].starts_with("super::") {
                path.pop();
                at += "super::".len();
            }
            (path, at)
        } else {
            i += rest.chars().next().map_or(1, char::len_utf8);
            continue;
        };
        let (paths, end) = tree(code, after);
        for p in paths {
            let mut full = base.clone();
            full.extend(p);
            found.push(full);
        }
        i = end.max(i + 1);
    }
    found
}

/// The paths of the use tree (or plain path) starting at byte `at`, and where it ends.
fn tree(code: &str, mut at: usize) -> (Vec<Vec<String>>, usize) {
    let mut prefix = Vec::new();
    loop {
        let rest = &code[at..];
        let rest_trim = rest.trim_start();
        at += rest.len() - rest_trim.len();
        if rest_trim.starts_with('{') {
            let mut out = Vec::new();
            at += 1;
            loop {
                let r = &code[at..];
                let t = r.trim_start();
                at += r.len() - t.len();
                if t.starts_with('}') {
                    at += 1;
                    break;
                }
                if t.starts_with(',') {
                    at += 1;
                    continue;
                }
                if t.is_empty() {
                    break;
                }
                let (paths, end) = tree(code, at);
                for p in paths {
                    let mut full = prefix.clone();
                    full.extend(p);
                    out.push(full);
                }
                if end == at {
                    at += 1;
                } else {
                    at = end;
                }
            }
            return (out, at);
        }
        let ident_len =
            rest_trim.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(rest_trim.len());
        if ident_len == 0 {
            return (if prefix.is_empty() { Vec::new() } else { vec![prefix] }, at);
        }
        let ident = &rest_trim[..ident_len];
        at += ident_len;
        if ident != "self" {
            prefix.push(ident.to_string());
        }
        if code[at..].starts_with("::") {
            at += 2;
        } else {
            return (vec![prefix], at);
        }
    }
}
