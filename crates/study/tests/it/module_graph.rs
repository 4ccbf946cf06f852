//! The workspace's modules import one another without a cycle, and the
//! study library's layers only look down: study files, then outputs, then
//! the run loop, then replays (the report, in the binary, is above them
//! all and cannot be reached from the library: that is a compile error).
//! The graph is read from the source text: every `crate::` and `super::`
//! path names the module file it ends in. A folder's `mod.rs` and its
//! parts are one family and may use one another; test modules (the
//! `#[cfg(test)] mod tests` last in a file, and `tests.rs`) add no edges.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Graph = BTreeMap<String, BTreeSet<String>>;

/// Every `.rs` file under `src/` as its module path (`stages::p2g`,
/// `remedies` for `remedies/mod.rs`, "" for a crate root).
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
        .filter(|f| f.file_name().is_some_and(|n| n != "tests.rs"))
        .map(|f| {
            let rel = f.strip_prefix(src).unwrap().with_extension("");
            let mut parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if matches!(
                parts.last().map(String::as_str),
                Some("mod" | "lib" | "main")
            ) {
                parts.pop();
            }
            (parts.join("::"), f)
        })
        .collect()
}

/// The source without comments and without its test module (last in a
/// file): tests may use any module; the production graph must be acyclic.
fn code(text: &str) -> String {
    let production = match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => &text[..i],
        None => text,
    };
    production
        .lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// `a` is `b`'s folder or one of its parts (`run` and `run::watch`).
fn family(a: &str, b: &str) -> bool {
    let within = |outer: &str, inner: &str| inner.starts_with(&format!("{outer}::"));
    within(a, b) || within(b, a)
}

/// An identifier chain (`a::b::`), then possibly a brace group, expanded.
fn read_path(s: &str) -> Vec<String> {
    let bytes = s.as_bytes();
    let head_len = bytes
        .iter()
        .position(|&c| !(c.is_ascii_alphanumeric() || c == b'_' || c == b':'))
        .unwrap_or(bytes.len());
    let head = &s[..head_len];
    let group = head.is_empty() || head.ends_with("::");
    if bytes.get(head_len) != Some(&b'{') || !group {
        return vec![head.to_string()];
    }
    // Split the group at top-level commas.
    let mut depth = 0;
    let mut start = head_len + 1;
    let mut out = vec![];
    for (j, &c) in bytes.iter().enumerate().skip(head_len) {
        let end_of_item = match c {
            b'{' => {
                depth += 1;
                false
            }
            b'}' => {
                depth -= 1;
                depth == 0
            }
            b',' => depth == 1,
            _ => false,
        };
        if end_of_item {
            let items = read_path(s[start..j].trim_start());
            out.extend(items.into_iter().map(|q| format!("{head}{q}")));
            start = j + 1;
            if depth == 0 {
                break;
            }
        }
    }
    out
}

/// The paths that follow each `prefix` (`crate::` or `super::`), with
/// `{a, b::c}` groups expanded: `["report::data::Matrix", "output", ...]`.
fn paths_after(code: &str, prefix: &str) -> Vec<String> {
    let mut out = vec![];
    let mut rest = code;
    while let Some(i) = rest.find(prefix) {
        let boundary = i == 0 || {
            let c = rest.as_bytes()[i - 1] as char;
            !(c.is_ascii_alphanumeric() || c == '_' || c == ':')
        };
        rest = &rest[i + prefix.len()..];
        if boundary {
            out.extend(read_path(rest));
        }
    }
    out
}

/// The module file a path ends in: its longest prefix that is a module.
fn target(path: &str, known: &BTreeMap<String, PathBuf>) -> Option<String> {
    let parts: Vec<&str> = path.split("::").filter(|s| !s.is_empty()).collect();
    (1..=parts.len())
        .rev()
        .map(|n| parts[..n].join("::"))
        .find(|m| known.contains_key(m))
}

fn parent(module: &str) -> &str {
    module.rsplit_once("::").map_or("", |(p, _)| p)
}

/// Edges between a crate's module files, leaving out the crate root and
/// edges within a family. `super::` in a file `a/b.rs` names `a`, in a
/// folder's `a/b/mod.rs` also `a`.
fn graph(src: &Path) -> Graph {
    let known = modules(src);
    let mut g = Graph::new();
    for (module, file) in &known {
        if module.is_empty() {
            continue;
        }
        let text = code(&std::fs::read_to_string(file).unwrap());
        let base = parent(module);
        let prefix = if base.is_empty() {
            String::new()
        } else {
            format!("{base}::")
        };
        let paths = paths_after(&text, "crate::").into_iter().chain(
            paths_after(&text, "super::")
                .into_iter()
                .map(|p| format!("{prefix}{p}")),
        );
        let edges = g.entry(module.clone()).or_default();
        for p in paths {
            if let Some(t) = target(&p, &known) {
                if !t.is_empty() && t != *module && !family(&t, module) {
                    edges.insert(t);
                }
            }
        }
    }
    g
}

/// A cycle of the graph, if any (depth-first search).
fn find_cycle(g: &Graph) -> Option<Vec<String>> {
    fn visit(
        v: &str,
        g: &Graph,
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

fn crate_src(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(name)
        .join("src")
}

#[test]
fn no_module_of_any_crate_is_on_an_import_cycle() {
    for name in ["solver", "monitor", "study"] {
        let g = graph(&crate_src(name));
        assert_eq!(find_cycle(&g), None, "crates/{name}");
    }
}

#[test]
fn the_reader_sees_the_edges_it_should() {
    let solver = graph(&crate_src("solver"));
    assert!(solver["stages::p2g"].contains("grid"));
    assert!(solver["remedies::j_bar"].contains("remedies::averaging"));
    assert!(
        solver["config"].contains("remedies"),
        "{:?}",
        solver["config"]
    );
    let monitor = graph(&crate_src("monitor"));
    assert!(monitor["detector"].contains("clustering"));
    let study = graph(&crate_src("study"));
    for user in ["replay::explain", "replay::reproduce", "replay::bench"] {
        assert!(study[user].contains("run"), "{user}: {:?}", study[user]);
    }
    assert!(study["run::stepper"].contains("run::checkpoint"));
    assert!(!study["run"].iter().any(|m| m.starts_with("run::probes")));
    assert!(study["run::probes::checkpoint_ring"].contains("output::files"));
    assert!(study["report::matrix"].contains("report::case"));
    assert!(study["report::matrix::methods"].contains("report::data"));
    assert!(study["report::case"].contains("report::plot::case"));
    // The leaf the report's sections share imports no other report module
    // but the plots' number format.
    let report_deps: Vec<&String> = study["report::data"]
        .iter()
        .filter(|m| m.starts_with("report") && *m != "report::plot")
        .collect();
    assert!(report_deps.is_empty(), "{report_deps:?}");
}

#[test]
fn the_study_library_layers_only_look_down() {
    const LAYERS: [&str; 4] = ["study_file", "output", "run", "replay"];
    let layer = |m: &str| {
        LAYERS
            .iter()
            .position(|l| m == *l || m.starts_with(&format!("{l}::")))
    };
    let g = graph(&crate_src("study"));
    for (module, edges) in &g {
        let Some(from) = layer(module) else {
            continue;
        };
        for t in edges {
            let to = layer(t).unwrap_or_else(|| panic!("{module} uses {t}, outside the library"));
            assert!(
                to <= from,
                "{module} ({}) uses {t} ({})",
                LAYERS[from],
                LAYERS[to]
            );
        }
    }
}

fn synthetic(edges: &[(&str, &str)]) -> Graph {
    let mut g = Graph::new();
    for (a, b) in edges {
        g.entry(a.to_string()).or_default().insert(b.to_string());
        g.entry(b.to_string()).or_default();
    }
    g
}

#[test]
fn the_cycle_finder_finds_a_cycle() {
    let g = synthetic(&[("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")]);
    assert_eq!(
        find_cycle(&g),
        Some(vec!["a".into(), "b".into(), "c".into(), "a".into()])
    );
    let dag = synthetic(&[("a", "b"), ("b", "c"), ("a", "c")]);
    assert_eq!(find_cycle(&dag), None);
}

#[test]
fn families_and_test_modules_are_no_edges() {
    assert!(family("run", "run::watch") && family("run::watch", "run"));
    assert!(!family("run", "replay") && !family("run::probes::a", "run::probes::b"));
    let text = "use crate::a;\n#[cfg(test)]\nmod tests {\n    use crate::b;\n}\n";
    assert_eq!(paths_after(&code(text), "crate::"), ["a"]);
}

#[test]
fn the_reader_expands_groups_and_nested_paths() {
    let text = "use crate::report::data::{median, Matrix};\nuse crate::{report_a, report_b::{x, y}};\nlet v = crate::labels::f(); // crate::not_this\n";
    let mut found = paths_after(&code(text), "crate::");
    found.sort();
    assert_eq!(
        found,
        [
            "labels::f",
            "report::data::Matrix",
            "report::data::median",
            "report_a",
            "report_b::x",
            "report_b::y",
        ]
    );
}
