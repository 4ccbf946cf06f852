//! `kick report` end to end: the page of a case and of a matrix links only
//! files that exist, and in headless Chromium every image loads and the case
//! table has one row per case. A missing Chromium fails the test unless
//! KICK_SKIP_BROWSER=1 (`make test` installs it as root).

mod common;

use common::kick;
use std::path::{Path, PathBuf};
use std::process::Command;

fn scratch(name: &str) -> common::Scratch {
    common::scratch("report", name)
}

/// Every src= and href= target of the page, resolved next to it.
fn links(index: &Path) -> Vec<PathBuf> {
    let html = std::fs::read_to_string(index).unwrap();
    let mut out = vec![];
    for attr in ["src=\"", "href=\""] {
        for part in html.split(attr).skip(1) {
            let target = &part[..part.find('"').unwrap()];
            out.push(index.parent().unwrap().join(target));
        }
    }
    out
}

fn chromium() -> Option<PathBuf> {
    [
        "/usr/bin/chromium",
        "/usr/bin/chromium-browser",
        "/usr/bin/google-chrome",
    ]
    .iter()
    .map(PathBuf::from)
    .find(|p| p.exists())
}

/// Loads a copy of the page with a probe script in headless Chromium and
/// returns (images, images loaded, case rows).
fn probe_in_chromium(browser: &Path, index: &Path) -> (usize, usize, usize) {
    let html = std::fs::read_to_string(index).unwrap();
    let probe = r#"<script>window.addEventListener('load',()=>{const i=[...document.images];document.body.setAttribute('data-probe','images='+i.length+' loaded='+i.filter(x=>x.complete&&x.naturalWidth>0).length+' rows='+document.querySelectorAll('tr.case-row').length+' end')});</script></body>"#;
    let copy = index.with_file_name("probe.html");
    std::fs::write(&copy, html.replace("</body>", probe)).unwrap();
    let profile = index.with_file_name("chromium-profile");
    let o = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--allow-file-access-from-files",
            "--virtual-time-budget=15000",
            &format!("--user-data-dir={}", profile.display()),
            "--dump-dom",
            &format!("file://{}", copy.display()),
        ])
        .output()
        .expect("chromium runs");
    let dom = String::from_utf8_lossy(&o.stdout);
    let start = dom
        .find("data-probe=\"")
        .unwrap_or_else(|| panic!("probe ran: {}", String::from_utf8_lossy(&o.stderr)));
    let probe = &dom[start + 12..];
    let probe = &probe[..probe.find(" end").unwrap()];
    let get = |k: &str| -> usize {
        let v = probe
            .split(' ')
            .find_map(|w| w.strip_prefix(&format!("{k}=")))
            .unwrap();
        v.parse().unwrap()
    };
    let _ = std::fs::remove_file(&copy);
    (get("images"), get("loaded"), get("rows"))
}

const STUDY: &str = r#"
[scene]
t_end = 0.06
[[scene.body]]
rect = [0.0, 0.0, 0.2, 0.4]
material = "water"
[materials.water]
K = 1.5e4
[output]
checkpoint_every = 0
vtk_times = [0.0, 0.03]
[[perturb]]
step = 100
region = [0.05, 0.1, 0.08, 0.13]
dv = [1.0, 0.0]
[matrix]
"materials.water.K" = [1.5e4, 3.0e4]
"materials.water.viscosity" = [0.0, 0.5]
"#;

#[test]
fn case_and_matrix_pages_link_existing_files_and_load_in_chromium() {
    let out = scratch("matrix");
    let study = out.join("tiny.toml");
    std::fs::write(&study, STUDY).unwrap();
    let o = kick(&[
        "matrix",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--jobs",
        "2",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = kick(&["report", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let index = out.join("report").join("index.html");
    assert!(String::from_utf8_lossy(&o.stdout).contains("index.html"));
    let matrix_links = links(&index);
    let html = std::fs::read_to_string(&index).unwrap();
    assert!(
        html.contains("<table id=\"speed_accuracy_cheapest\">"),
        "the cheapest case for each stated error is tabulated"
    );
    for f in [
        "heatmap_outcome.png",
        "heatmap_hydro.png",
        "stability.png",
        "speed_accuracy.png",
    ] {
        assert!(matrix_links.iter().any(|l| l.ends_with(f)), "{f} linked");
    }
    let case_pages: Vec<&PathBuf> = matrix_links
        .iter()
        .filter(|l| l.ends_with("index.html"))
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    assert_eq!(case_pages.len(), 4, "one link per case");
    for l in &matrix_links {
        assert!(l.exists(), "linked file {} exists", l.display());
    }
    for page in &case_pages {
        let case_links = links(page);
        assert!(case_links.iter().any(|l| l.ends_with("timeseries.png")));
        assert!(
            case_links
                .iter()
                .any(|l| l.to_string_lossy().ends_with(".gif")),
            "the push makes a kick with an animation"
        );
        for l in &case_links {
            assert!(l.exists(), "linked file {} exists", l.display());
        }
    }
    match chromium() {
        None if std::env::var_os("KICK_SKIP_BROWSER").is_some_and(|v| v == "1") => {
            eprintln!("SKIPPED the Chromium check (KICK_SKIP_BROWSER=1)")
        }
        None => panic!(
            "no chromium found: `make test` installs Debian's chromium when run as root \
             (or `apt-get install chromium`); to skip this check on purpose, set KICK_SKIP_BROWSER=1"
        ),
        Some(browser) => {
            let (images, loaded, rows) = probe_in_chromium(&browser, &index);
            assert!(images >= 4, "{images}");
            assert_eq!(loaded, images, "every image of the matrix page loaded");
            assert_eq!(rows, 4, "one table row per case");
            let (images, loaded, _) = probe_in_chromium(&browser, case_pages[0]);
            assert!(images >= 3);
            assert_eq!(loaded, images, "every image of a case page loaded");
        }
    }
}
