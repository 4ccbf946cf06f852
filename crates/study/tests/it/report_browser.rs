//! `kick report` end to end: the page of a case and of a matrix links only
//! files that exist, and in headless Chromium every image loads and the case
//! table has one row per case; a case page's first screen (its verdict,
//! before the first figure and within the first 1000 px) states the status
//! and the first kick's time and place, and no metric row is empty. A
//! missing Chromium fails the test unless KICK_SKIP_BROWSER=1 (`make test`
//! installs it as root).

use crate::common;

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

/// What the probe script saw of a page in Chromium (1280 x 1000 window).
struct Probe {
    images: usize,
    loaded: usize,
    case_rows: usize,
    /// The text of `section#verdict` ("" when there is none).
    verdict: String,
    /// Page coordinates (px) of the verdict's bottom and the first figure's top.
    verdict_bottom: f64,
    figure_top: f64,
    metric_rows: usize,
    /// Rows of `table#metrics` with an empty cell.
    empty_metric_rows: usize,
}

/// Decodes JavaScript's encodeURIComponent.
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = std::str::from_utf8(&b[i + 1..i + 3]).unwrap();
            out.push(u8::from_str_radix(hex, 16).unwrap());
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).unwrap()
}

/// Loads a copy of the page with a probe script in headless Chromium.
fn probe_in_chromium(browser: &Path, index: &Path) -> Probe {
    let html = std::fs::read_to_string(index).unwrap();
    let probe = r#"<script>window.addEventListener('load',()=>{
const i=[...document.images];
const v=document.getElementById('verdict');
const f=document.querySelector('figure');
const top=e=>e?Math.round(e.getBoundingClientRect().top+window.scrollY):-1;
const bottom=e=>e?Math.round(e.getBoundingClientRect().bottom+window.scrollY):-1;
const m=[...document.querySelectorAll('#metrics tr')].filter(r=>r.querySelector('td'));
const empty=m.filter(r=>[...r.querySelectorAll('td')].some(c=>c.innerText.trim()==='')).length;
document.body.setAttribute('data-verdict',encodeURIComponent(v?v.innerText:''));
document.body.setAttribute('data-probe','images='+i.length+' loaded='+i.filter(x=>x.complete&&x.naturalWidth>0).length+' rows='+document.querySelectorAll('tr.case-row').length+' verdict_bottom='+bottom(v)+' figure_top='+top(f)+' metric_rows='+m.length+' empty_metric_rows='+empty+' end')});</script></body>"#;
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
            "--window-size=1280,1000",
            "--virtual-time-budget=15000",
            &format!("--user-data-dir={}", profile.display()),
            "--dump-dom",
            &format!("file://{}", copy.display()),
        ])
        .output()
        .expect("chromium runs");
    let dom = String::from_utf8_lossy(&o.stdout);
    let attr = |name: &str| -> String {
        let key = format!("{name}=\"");
        let start = dom
            .find(&key)
            .unwrap_or_else(|| panic!("probe ran: {}", String::from_utf8_lossy(&o.stderr)))
            + key.len();
        dom[start..start + dom[start..].find('"').unwrap()].to_string()
    };
    let probe = attr("data-probe");
    let probe = &probe[..probe.find(" end").unwrap()];
    let get = |k: &str| -> f64 {
        let v = probe
            .split(' ')
            .find_map(|w| w.strip_prefix(&format!("{k}=")))
            .unwrap();
        v.parse().unwrap()
    };
    let _ = std::fs::remove_file(&copy);
    Probe {
        images: get("images") as usize,
        loaded: get("loaded") as usize,
        case_rows: get("rows") as usize,
        verdict: percent_decode(&attr("data-verdict")),
        verdict_bottom: get("verdict_bottom"),
        figure_top: get("figure_top"),
        metric_rows: get("metric_rows") as usize,
        empty_metric_rows: get("empty_metric_rows") as usize,
    }
}

/// What a case page's verdict must state, from the case's summary.json:
/// the status word, and the first kick's time and place (its region's x
/// range as the page writes it).
fn expected_verdict(page: &Path) -> Vec<String> {
    let case_dir = page.parent().unwrap().parent().unwrap();
    let s = study::output::summary::Summary::read(case_dir).unwrap();
    let status = match s.status {
        study::output::summary::Status::Completed => "Completed",
        study::output::summary::Status::BlewUp => "Blew up",
        study::output::summary::Status::Failed => "Failed",
    };
    let first = s
        .events
        .iter()
        .filter(|e| e.is_kick())
        .min_by(|a, b| a.t.total_cmp(&b.t))
        .expect("the push makes a kick");
    let r = &first.region;
    vec![
        status.to_string(),
        format!("t = {:.4} s", first.t),
        format!(
            "x {:.3}–{:.3} m, y {:.3}–{:.3} m",
            r.x_min, r.x_max, r.y_min, r.y_max
        ),
    ]
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
        // The verdict comes before the first figure and states the status
        // and the first kick's time and place; no metric row is empty.
        let html = std::fs::read_to_string(page).unwrap();
        let first_screen = &html[..html.find("<figure").expect("a figure")];
        assert!(first_screen.contains("<section id=\"verdict\">"));
        for want in expected_verdict(page) {
            assert!(
                first_screen.contains(&want),
                "{want} before the first figure of {}",
                page.display()
            );
        }
        let metrics = &html[html
            .find("<table id=\"metrics\">")
            .expect("a metrics table")..];
        let metrics = &metrics[..metrics.find("</table>").unwrap()];
        assert!(
            !metrics.contains("<td></td>") && !metrics.contains("<td class=l></td>"),
            "{metrics}"
        );
        assert!(
            !metrics.contains("darcy")
                && !metrics.contains("Darcy")
                && !metrics.contains("Terzaghi"),
            "{metrics}"
        );
        assert!(!html.contains("{\"injection\""), "causes not as raw JSON");
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
            let p = probe_in_chromium(&browser, &index);
            assert!(p.images >= 4, "{}", p.images);
            assert_eq!(p.loaded, p.images, "every image of the matrix page loaded");
            assert_eq!(p.case_rows, 4, "one table row per case");
            assert!(p.verdict.contains("cases ran") && p.verdict.contains("Kicked"), "{}", p.verdict);
            for page in &case_pages {
                let p = probe_in_chromium(&browser, page);
                assert!(p.images >= 3);
                assert_eq!(p.loaded, p.images, "every image of a case page loaded");
                // The first screen: the verdict ends within the first 1000 px,
                // above the first figure, and states status, time and place.
                assert!(p.verdict_bottom > 0.0 && p.verdict_bottom <= 1000.0, "verdict ends at {} px", p.verdict_bottom);
                assert!(p.verdict_bottom <= p.figure_top, "{} > {}", p.verdict_bottom, p.figure_top);
                for want in expected_verdict(page) {
                    assert!(p.verdict.contains(&want), "{want} in the verdict: {}", p.verdict);
                }
                assert!(p.metric_rows >= 1);
                assert_eq!(p.empty_metric_rows, 0, "no empty metric row");
            }
        }
    }
}
