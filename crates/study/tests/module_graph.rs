//! The study crate's modules import one another without a cycle, read from
//! the source text as in crates/solver/tests/module_graph.rs: every
//! `crate::...` path names the module file it ends in. The crate is flat
//! (one file per module), so a `super::` path names the file itself (from
//! its test module) or the crate root, and adds no edge.
//!
//! For now only the report and plot modules are held to it (`in_scope`):
//! no cycle may pass through one of them, whatever modules it runs through
//! (run_case, run_mixture and reproduce still import one another). Once
//! that cycle is gone, `in_scope` widens to the whole crate.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Graph = BTreeMap<String, BTreeSet<String>>;

/// The modules the test holds to "no cycle through me": the whole crate.
fn in_scope(_module: &str) -> bool {
    true
}

/// Every `.rs` file under `src/`, as its module path (`report_case`,
/// "" for `lib.rs`). The binary's `main.rs` uses the library through
/// `study::`, so it has no edges here.
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

/// The source without comments (line comments and doc comments) and
/// without its test module (`#[cfg(test)] mod tests`, last in a file):
/// tests may use any module; the production graph is what must be acyclic.
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

/// `a` is `b`'s folder or one of its parts (`runner` and `runner::watch`):
/// a folder and its parts are one family and may use one another.
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
/// `{a, b::c}` groups expanded: `["report_data::Matrix", "summary", ...]`.
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

/// Edges between the crate's module files, leaving out the crate root and
/// edges within a family; `super::` in `a::b` names `a`.
fn graph(src: &Path) -> Graph {
    let known = modules(src);
    let mut g = Graph::new();
    for (module, file) in &known {
        if module.is_empty() {
            continue;
        }
        let text = code(&std::fs::read_to_string(file).unwrap());
        let parent = match module.rsplit_once("::") {
            Some((p, _)) => format!("{p}::"),
            None => String::new(),
        };
        let paths = paths_after(&text, "crate::").into_iter().chain(
            paths_after(&text, "super::")
                .into_iter()
                .map(|p| format!("{parent}{p}")),
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

/// A cycle through some module that `in_scope` holds, if any: for each
/// such module, a depth-first search for a path back to it.
fn find_cycle(g: &Graph, in_scope: impl Fn(&str) -> bool) -> Option<Vec<String>> {
    fn path_to(
        from: &str,
        to: &str,
        g: &Graph,
        seen: &mut BTreeSet<String>,
        path: &mut Vec<String>,
    ) -> bool {
        for w in g.get(from).into_iter().flatten() {
            if w == to {
                path.push(w.clone());
                return true;
            }
            if seen.insert(w.clone()) {
                path.push(w.clone());
                if path_to(w, to, g, seen, path) {
                    return true;
                }
                path.pop();
            }
        }
        false
    }
    g.keys().filter(|v| in_scope(v)).find_map(|v| {
        let mut path = vec![v.clone()];
        path_to(v, v, g, &mut BTreeSet::new(), &mut path).then_some(path)
    })
}

#[test]
fn no_module_is_on_an_import_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let g = graph(&src);
    assert_eq!(find_cycle(&g, in_scope), None);
    // The run loop's users and its probes.
    for user in ["run_case", "reproduce", "bench", "run_mixture"] {
        assert!(g[user].contains("runner"), "{user}: {:?}", g[user]);
    }
    assert!(g["probes::checkpoint_ring"].contains("runner"));
    assert!(g["runner::stepper"].contains("case_checkpoint"));
    assert!(!g["runner"].iter().any(|m| m.starts_with("probes")));
    // The reader sees the edges it should.
    assert!(g["report"].contains("report_matrix"), "{:?}", g["report"]);
    assert!(g["report_matrix"].contains("report_ablation"));
    assert!(g["report_ablation"].contains("report_data"));
    assert!(g["report_case"].contains("plot_case"));
    assert!(g["plot_case"].contains("plot_common"));
    assert!(g["report_data"].contains("summary"));
    // The leaf the sections share imports no other report module.
    let report_deps: Vec<&String> = g["report_data"]
        .iter()
        .filter(|m| m.starts_with("report"))
        .collect();
    assert!(report_deps.is_empty(), "{report_deps:?}");
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
fn the_cycle_finder_finds_a_cycle_through_a_module_in_scope() {
    let everything = |_: &str| true;
    let g = synthetic(&[("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")]);
    assert_eq!(
        find_cycle(&g, everything),
        Some(vec!["a".into(), "b".into(), "c".into(), "a".into()])
    );
    assert_eq!(find_cycle(&g, |m: &str| m == "d"), None);
    assert_eq!(
        find_cycle(&g, |m: &str| m == "c"),
        Some(vec!["c".into(), "a".into(), "b".into(), "c".into()])
    );
    let dag = synthetic(&[("a", "b"), ("b", "c"), ("a", "c")]);
    assert_eq!(find_cycle(&dag, everything), None);
    // A cycle among other modules, reached from one in scope, is not one
    // through it.
    let g = synthetic(&[
        ("report", "run_case"),
        ("run_case", "run_mixture"),
        ("run_mixture", "run_case"),
    ]);
    assert_eq!(find_cycle(&g, |m: &str| m == "report"), None);
    assert!(find_cycle(&g, in_scope).is_some());
}

#[test]
fn families_and_test_modules_are_no_edges() {
    assert!(family("runner", "runner::watch") && family("runner::watch", "runner"));
    assert!(!family("runner", "run_case") && !family("probes::a", "probes::b"));
    let text = "use crate::a;\n#[cfg(test)]\nmod tests {\n    use crate::b;\n}\n";
    assert_eq!(paths_after(&code(text), "crate::"), ["a"]);
}

#[test]
fn the_reader_expands_groups_and_nested_paths() {
    let text = "use crate::report_data::{median, Matrix};\nuse crate::{report_a, report_b::{x, y}};\nlet v = crate::labels::f(); // crate::not_this\n";
    let mut found = paths_after(&code(text), "crate::");
    found.sort();
    assert_eq!(
        found,
        [
            "labels::f",
            "report_a",
            "report_b::x",
            "report_b::y",
            "report_data::Matrix",
            "report_data::median"
        ]
    );
}
