//! The module structure (issue 24): no import cycle between modules of `src/` (a module
//! may use its ancestors and descendants; any other pair must not use each other, directly
//! or through others), and no library module imports the CLI. Reads the sources as text:
//! `crate::a::b` and `super::a` paths outside `#[cfg(test)]` and comments.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

fn modules() -> BTreeMap<String, String> {
    fn walk(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    walk(&src, &mut files);
    let mut mods = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix(&src).unwrap().with_extension("");
        let mut parts: Vec<String> = rel
            .iter()
            .map(|p| p.to_string_lossy().to_string())
            .collect();
        if parts.last().is_some_and(|p| p == "mod") {
            parts.pop();
        }
        if parts == ["lib"] || parts == ["main"] {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap_or("");
        let code: String = code
            .lines()
            .map(|l| l.split("//").next().unwrap_or(""))
            .collect::<Vec<_>>()
            .join("\n");
        mods.insert(parts.join("::"), code);
    }
    mods
}

/// Module paths named in `code` after `prefix` (`crate::` or `super::`).
fn paths_after(code: &str, prefix: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find(prefix) {
        let before = rest[..i].chars().last();
        rest = &rest[i + prefix.len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let path: Vec<String> = rest
            .split("::")
            .map(|seg| {
                seg.chars()
                    .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_')
                    .collect::<String>()
            })
            .take_while(|seg| !seg.is_empty())
            .collect();
        out.push(path);
    }
    out
}

fn edges(mods: &BTreeMap<String, String>) -> BTreeMap<String, BTreeSet<String>> {
    let resolve = |parts: &[String]| -> Option<String> {
        (1..=parts.len())
            .rev()
            .map(|k| parts[..k].join("::"))
            .find(|m| mods.contains_key(m))
    };
    let mut out = BTreeMap::new();
    for (m, code) in mods {
        let base: Vec<String> = m.split("::").map(String::from).collect();
        let mut to = BTreeSet::new();
        let mut targets: Vec<Vec<String>> = paths_after(code, "crate::");
        for p in paths_after(code, "super::") {
            let mut full = base[..base.len() - 1].to_vec();
            full.extend(p);
            targets.push(full);
        }
        for t in targets {
            if let Some(t) = resolve(&t) {
                let related =
                    t == *m || m.starts_with(&format!("{t}::")) || t.starts_with(&format!("{m}::"));
                if !related {
                    to.insert(t);
                }
            }
        }
        out.insert(m.clone(), to);
    }
    out
}

#[test]
fn no_import_cycles_and_the_library_below_the_cli() {
    let mods = modules();
    let g = edges(&mods);
    // Every module that reaches itself through another: a cycle.
    let mut cycles = Vec::new();
    for start in g.keys() {
        let mut seen = BTreeSet::new();
        let mut stack: Vec<&String> = g[start].iter().collect();
        while let Some(v) = stack.pop() {
            if v == start {
                cycles.push(start.clone());
                break;
            }
            if seen.insert(v.clone()) {
                stack.extend(g.get(v).into_iter().flatten());
            }
        }
    }
    assert!(cycles.is_empty(), "modules on an import cycle: {cycles:?}");
    let up: Vec<(&String, &String)> = g
        .iter()
        .filter(|(m, _)| !m.starts_with("cli"))
        .flat_map(|(m, to)| {
            to.iter()
                .filter(|t| t.starts_with("cli"))
                .map(move |t| (m, t))
        })
        .collect();
    assert!(up.is_empty(), "library modules importing the CLI: {up:?}");
    assert!(mods.len() > 50, "{} modules read", mods.len());
}

/// Issue 24: no source file in `src/` over 800 lines (tests included: a long test module
/// moves to a `tests.rs` of its own).
#[test]
fn no_source_file_over_800_lines() {
    fn walk(dir: &Path, out: &mut Vec<(String, usize)>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let n = std::fs::read_to_string(&p).unwrap().lines().count();
                out.push((p.display().to_string(), n));
            }
        }
    }
    let mut files = Vec::new();
    walk(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
        &mut files,
    );
    let long: Vec<_> = files.iter().filter(|(_, n)| *n > 800).collect();
    assert!(long.is_empty(), "files over 800 lines: {long:?}");
    assert!(files.len() > 50, "{} files read", files.len());
}
