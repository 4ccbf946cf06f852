//! The solver's modules import one another without a cycle: a module file
//! may use its own folder's `mod.rs` and the other way round (a folder and
//! its parts are one family), but no two other modules may reach each other,
//! directly or through others. The graph is read from the source text:
//! every `crate::...` and `super::...` path names the module file it ends in.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `src/`, as its module path (`stages::p2g`,
/// `remedies` for `remedies/mod.rs`, "" for `lib.rs`).
fn modules(src: &Path) -> BTreeMap<String, PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    let mut files = vec![];
    walk(src, &mut files);
    files
        .into_iter()
        .map(|f| {
            let rel = f.strip_prefix(src).unwrap().with_extension("");
            let mut parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
                parts.pop();
            }
            (parts.join("::"), f)
        })
        .collect()
}

/// The source without comments (line comments and doc comments).
fn code(text: &str) -> String {
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The paths that follow each `prefix` (`crate::` or `super::`), with
/// `{a, b::c}` groups expanded: `["stages::p2g::Terms", "par", ...]`.
fn paths_after(code: &str, prefix: &str) -> Vec<String> {
    fn read_path(s: &str) -> (Vec<String>, usize) {
        // An identifier chain, then possibly a brace group.
        let bytes = s.as_bytes();
        let mut i = 0;
        let mut head = String::new();
        while i < bytes.len() {
            let c = bytes[i] as char;
            if c.is_ascii_alphanumeric() || c == '_' || c == ':' {
                head.push(c);
                i += 1;
            } else {
                break;
            }
        }
        if i < bytes.len() && bytes[i] == b'{' && head.ends_with("::") {
            // Split the group at top-level commas.
            let mut depth = 0;
            let mut start = i + 1;
            let mut out = vec![];
            let mut j = i;
            while j < bytes.len() {
                match bytes[j] {
                    b'{' => depth += 1,
                    b'}' => {
                        depth -= 1;
                        if depth == 0 {
                            let (p, _) = read_path(s[start..j].trim_start());
                            out.extend(p.into_iter().map(|q| format!("{head}{q}")));
                            return (out, j + 1);
                        }
                    }
                    b',' if depth == 1 => {
                        let (p, _) = read_path(s[start..j].trim_start());
                        out.extend(p.into_iter().map(|q| format!("{head}{q}")));
                        start = j + 1;
                    }
                    _ => {}
                }
                j += 1;
            }
            (out, j)
        } else {
            (vec![head], i)
        }
    }
    let mut out = vec![];
    let mut rest = code;
    while let Some(i) = rest.find(prefix) {
        let boundary = i == 0 || {
            let c = rest.as_bytes()[i - 1] as char;
            !(c.is_ascii_alphanumeric() || c == '_' || c == ':')
        };
        rest = &rest[i + prefix.len()..];
        if boundary {
            out.extend(read_path(rest).0);
        }
    }
    out
}

/// The module file a path ends in: its longest prefix that is a module.
fn target(path: &[&str], known: &BTreeMap<String, PathBuf>) -> Option<String> {
    (1..=path.len())
        .rev()
        .map(|n| path[..n].join("::"))
        .find(|m| known.contains_key(m))
}

fn parent(module: &str) -> &str {
    module.rsplit_once("::").map_or("", |(p, _)| p)
}

/// Edges between module files, leaving out the crate root and each
/// folder's link with its own parts.
fn graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let known = modules(src);
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (module, file) in &known {
        if module.is_empty() {
            continue;
        }
        let text = code(&std::fs::read_to_string(file).unwrap());
        let is_folder = file.ends_with("mod.rs");
        // `super` of a folder's mod.rs is the folder's parent.
        let here = if is_folder {
            module.as_str()
        } else {
            parent(module)
        };
        let mut targets = vec![];
        for p in paths_after(&text, "crate::") {
            let parts: Vec<&str> = p.split("::").filter(|s| !s.is_empty()).collect();
            targets.extend(target(&parts, &known));
        }
        for p in paths_after(&text, "super::") {
            let base = if is_folder { parent(here) } else { here };
            let full = if base.is_empty() {
                p.clone()
            } else {
                format!("{base}::{p}")
            };
            let parts: Vec<&str> = full.split("::").filter(|s| !s.is_empty()).collect();
            targets.extend(target(&parts, &known).or(Some(base.to_string())));
        }
        let edges = g.entry(module.clone()).or_default();
        for t in targets {
            let family = parent(&t) == module || parent(module) == t;
            if !t.is_empty() && t != *module && !family {
                edges.insert(t);
            }
        }
    }
    g
}

/// A cycle of the graph, if any (depth-first search).
fn find_cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        v: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(v.to_string(), 1);
        stack.push(v.to_string());
        for w in g.get(v).into_iter().flatten() {
            match state.get(w.as_str()).copied().unwrap_or(0) {
                1 => {
                    let start = stack.iter().position(|s| s == w).unwrap();
                    let mut cycle = stack[start..].to_vec();
                    cycle.push(w.clone());
                    return Some(cycle);
                }
                0 => {
                    if let Some(c) = visit(w, g, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(v.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for v in g.keys() {
        if state.get(v.as_str()).copied().unwrap_or(0) == 0 {
            let mut stack = vec![];
            if let Some(c) = visit(v, g, &mut state, &mut stack) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn the_solver_modules_import_one_another_without_a_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let g = graph(&src);
    // The reader sees the edges it should: a stage uses the grid, a remedy
    // its helpers, config the remedies' settings.
    assert!(g["stages::p2g"].contains("grid"), "{:?}", g["stages::p2g"]);
    assert!(g["remedies::j_bar"].contains("remedies::averaging"));
    assert!(g["config"].contains("remedies"), "{:?}", g["config"]);
    assert_eq!(find_cycle(&g), None);
}

#[test]
fn the_cycle_finder_finds_a_cycle() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.entry("a".into()).or_default().insert("b".into());
    g.entry("b".into()).or_default().insert("c".into());
    g.entry("c".into()).or_default().insert("a".into());
    assert_eq!(
        find_cycle(&g),
        Some(vec!["a".into(), "b".into(), "c".into(), "a".into()])
    );
    g.get_mut("c").unwrap().clear();
    assert_eq!(find_cycle(&g), None);
}
