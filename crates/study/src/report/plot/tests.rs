//! Every plot kind rendered from small synthetic data: valid PNG/SVG/GIF of
//! the expected size, PNGs not blank, SVGs carrying their axis labels as text.

use super::case::{
    animate, FrontFigure, MapsFigure, Marker, Outline, PressureDepthFigure, Series,
    TimeseriesFigure,
};
use super::matrix::{
    pareto_front, HeatCell, HeatKey, HeatPanel, HeatmapFigure, LinesFigure, ParetoFigure,
    RefinementFigure,
};
use super::{
    decade_label, log_decades, log_label, log_minors, log_range, log_ticks, render, wrap_words,
    ColourScale, Figure, LogAxis,
};
use crate::report::matrix::speed::cheapest_for_error;
use plotters::style::RGBColor;
use solver::Vec2;
use std::path::Path;
use study::output::vtu::Snapshot;

/// A fresh folder for one test's figures, removed when the test passes.
struct Scratch(std::path::PathBuf);

impl std::ops::Deref for Scratch {
    type Target = std::path::PathBuf;
    fn deref(&self) -> &std::path::PathBuf {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

fn scratch(name: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("kick-plots-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Scratch(dir)
}

/// Renders, then checks both files: PNG size and ink, SVG labels; returns
/// the SVG's text elements.
fn check(fig: &impl Figure, dir: &Path, stem: &str, labels: &[&str]) -> Vec<String> {
    let [png, svg] = render(fig, dir, stem).unwrap();
    let img = image::open(dir.join(&png)).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), fig.size(), "{png}");
    let inked = img.pixels().filter(|p| p.0 != [255, 255, 255]).count();
    let fraction = inked as f64 / (img.width() * img.height()) as f64;
    assert!(fraction > 0.02, "{png} is nearly blank: {fraction}");
    let text = std::fs::read_to_string(dir.join(&svg)).unwrap();
    assert!(text.starts_with("<svg"), "{svg}");
    let (w, h) = fig.size();
    assert!(
        text.contains(&format!("width=\"{w}\"")) && text.contains(&format!("height=\"{h}\"")),
        "{svg}"
    );
    let texts: Vec<&str> = text
        .split("<text")
        .skip(1)
        .filter_map(|t| Some(t[t.find('>')? + 1..t.find("</text>")?].trim()))
        .collect();
    for l in labels {
        assert!(texts.contains(l), "{svg} lacks the text element {l:?}");
    }
    texts_fit(&text, w, &svg);
    texts.into_iter().map(String::from).collect()
}

/// Every horizontal text of an SVG (titles, labels, legends) lies within
/// the figure's width: its extent from its x, anchor and size, measured
/// with the embedded font (a browser cannot see into the PNG).
fn texts_fit(svg_text: &str, width: u32, name: &str) {
    use plotters::style::IntoFont;
    super::fonts();
    let attr = |head: &str, key: &str| -> Option<String> {
        let at = head.find(&format!(" {key}=\""))? + key.len() + 3;
        Some(head[at..at + head[at..].find('"')?].to_string())
    };
    for element in svg_text.split("<text").skip(1) {
        let (Some(close), Some(end)) = (element.find('>'), element.find("</text>")) else {
            continue;
        };
        let (head, body) = (&element[..close], element[close + 1..end].trim());
        if head.contains("transform=") || body.is_empty() {
            continue; // a rotated axis description runs along the height
        }
        let body = body
            .replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&amp;", "&");
        let x: f64 = attr(head, "x")
            .and_then(|v| v.parse().ok())
            .expect("text x");
        let size: f64 = attr(head, "font-size")
            .and_then(|v| v.parse().ok())
            .expect("font-size");
        let font = (super::SANS, size * 1.24).into_font();
        let w = font
            .box_size(&body)
            .expect("the embedded font measures text")
            .0 as f64;
        let (left, right) = match attr(head, "text-anchor").as_deref() {
            Some("middle") => (x - w / 2.0, x + w / 2.0),
            Some("end") => (x - w, x),
            _ => (x, x + w),
        };
        assert!(
            left >= -0.5 && right <= width as f64 + 0.5,
            "{name}: the text {body:?} spans {left:.0}..{right:.0} px, outside the figure's 0..{width}"
        );
    }
}

/// A log figure's SVG: its decades labelled "10ᵏ" in superscript digits and
/// no tick label in the old "1e0.5" style (nor any other non-decade label).
fn check_log_ticks(texts: &[String], stem: &str, decades: &[&str]) {
    for d in decades {
        assert!(
            texts.iter().any(|t| t == d),
            "{stem}.svg lacks the decade label {d:?}: {texts:?}"
        );
    }
    let old_style = |t: &str| {
        t.strip_prefix("1e")
            .is_some_and(|r| r.starts_with(|c: char| c.is_ascii_digit() || c == '-'))
    };
    assert!(
        !texts.iter().any(|t| old_style(t)),
        "{stem}.svg has 1e-style tick labels: {texts:?}"
    );
    assert!(
        !texts
            .iter()
            .any(|t| t.contains("1e0.5") || t.contains("1e2.5")),
        "{stem}.svg: {texts:?}"
    );
}

fn column_snapshot(step: u64, kick: bool) -> Snapshot {
    let mut s = Snapshot {
        step,
        t: step as f64 * 1e-4,
        ..Default::default()
    };
    for i in 0..20 {
        for j in 0..40 {
            let (x, y) = (0.005 + 0.01 * i as f64, 0.005 + 0.01 * j as f64);
            s.x.push(Vec2::new(x, y));
            s.v.push(Vec2::zeros());
            s.pressure.push(1000.0 * 9.81 * (0.4 - y));
            let a = if kick && (8..11).contains(&i) && (3..6).contains(&j) {
                500.0
            } else {
                1.0 + (i + j) as f64 * 0.1
            };
            s.accel.push(a * 9.81);
            s.j.push(1.0);
            s.id.push((i * 40 + j) as u32);
        }
    }
    s
}

#[test]
fn timeseries_plots_render_as_png_and_svg() {
    let dir = scratch("timeseries");
    let t: Vec<f64> = (0..200).map(|k| k as f64 * 0.005).collect();
    let wave = |a: f64| t.iter().map(|x| a * (3.0 * x).sin()).collect::<Vec<_>>();
    let names = [
        "e_kin",
        "e_grav",
        "e_int",
        "d_visc",
        "e_total",
        "energy_injected",
        "max_accel_g",
        "max_jump",
        "checkerboard_means",
        "checkerboard_nodal",
        "hydro_rel_rms",
        "hydro_max",
    ];
    let series = Series {
        t: t.clone(),
        columns: names
            .iter()
            .map(|n| {
                (
                    n.to_string(),
                    wave(1.0).iter().map(|v| v.abs() + 0.01).collect(),
                )
            })
            .collect(),
    };
    let markers = [
        Marker {
            id: 1,
            t: 0.3,
            colour: RGBColor(200, 30, 30),
            note: "*".into(),
        },
        Marker {
            id: 2,
            t: 0.7,
            colour: RGBColor(120, 120, 120),
            note: String::new(),
        },
    ];
    let fig = TimeseriesFigure {
        series: &series,
        markers: &markers,
        title: "synthetic".into(),
    };
    let texts = check(
        &fig,
        &dir,
        "timeseries",
        &[
            "time t (s)",
            "energy change (J/m)",
            "checkerboard",
            "#1*",
            "#2",
            "a/g, jump m/s (log)",
            "departure (of rho g depth, log)",
        ],
    );
    // |sin| + 0.01 spans 0.01..1.01: the log panels run 10⁻²..10¹.
    check_log_ticks(&texts, "timeseries", &["10⁻²", "10⁻¹", "10⁰", "10¹"]);
}

#[test]
fn surge_front_plots_render_as_png_and_svg() {
    let dir = scratch("front");
    let tt: Vec<f64> = (0..50).map(|k| k as f64 * 0.1).collect();
    let zz: Vec<f64> = tt.iter().map(|x| 1.0 + 0.6 * x).collect();
    let data = study::output::metrics::martin_moyce();
    let fig = FrontFigure {
        t: &tt,
        z: &zz,
        data: &data,
        z_wall: 4.0,
        title: "front".into(),
    };
    check(
        &fig,
        &dir,
        "front",
        &[
            "T = t sqrt(2g/a)",
            "Z = x_front / a",
            "Martin &amp; Moyce 1952",
        ],
    );
}

#[test]
fn pressure_depth_plots_render_as_png_and_svg() {
    let dir = scratch("pressure_depth");
    let snap = column_snapshot(10, false);
    let fig = PressureDepthFigure {
        snap: &snap,
        level: 0.4,
        rho0: 1000.0,
        gravity: 9.81,
        title: "p(d)".into(),
    };
    check(
        &fig,
        &dir,
        "pressure_depth",
        &["pressure p (kPa)", "depth below settled surface (m)"],
    );
}

#[test]
fn particle_maps_and_their_animation_render() {
    let dir = scratch("maps");
    let (a, b, c) = (
        column_snapshot(5, false),
        column_snapshot(10, true),
        column_snapshot(15, false),
    );
    let fig = MapsFigure {
        snaps: vec![
            (&a, "before".into()),
            (&b, "at".into()),
            (&c, "after".into()),
        ],
        bbox: [0.0, 0.0, 0.8, 0.6],
        outline: Some(Outline {
            x0: 0.08,
            y0: 0.03,
            x1: 0.11,
            y1: 0.06,
        }),
        gravity: 9.81,
        title: "maps".into(),
    };
    let texts = check(
        &fig,
        &dir,
        "maps",
        &["x (m)", "y (m)", "pressure (kPa)", "a/g (log)"],
    );
    // a/g from about 1.1 to 7 (the kick is under 1 %) holds no whole
    // decade: the bar widens to 10⁰..10¹.
    check_log_ticks(&texts, "maps", &["10⁰", "10¹"]);

    let gif = dir.join("kick.gif");
    animate(
        &[a.clone(), b.clone(), c.clone()],
        [0.0, 0.0, 0.8, 0.6],
        None,
        "kick",
        &gif,
        9.81,
    )
    .unwrap();
    let bytes = std::fs::read(&gif).unwrap();
    assert_eq!(&bytes[..6], b"GIF89a");
    let decoder = image::codecs::gif::GifDecoder::new(std::io::Cursor::new(&bytes)).unwrap();
    use image::AnimationDecoder;
    let frames = decoder.into_frames().collect_frames().unwrap();
    assert_eq!(frames.len(), 3, "one frame per snapshot");
    let w = u16::from_le_bytes([bytes[6], bytes[7]]);
    assert_eq!(w, 760);
}

#[test]
fn heatmaps_render_as_png_and_svg() {
    let dir = scratch("heatmaps");
    let x_cats: Vec<String> = ["15 kPa", "150 kPa", "1.5 MPa"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let y_cats: Vec<String> = ["power 1", "power 7", "tait"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let panel = |title: &str| HeatPanel {
        title: title.into(),
        cells: (0..3)
            .flat_map(|x| (0..3).map(move |y| (x, y)))
            .map(|(x, y)| HeatCell {
                x,
                y,
                colour: RGBColor(40 * x as u8 + 50, 80, 60 * y as u8 + 40),
                text: format!("{x}{y}"),
            })
            .collect(),
    };
    let fig = HeatmapFigure {
        title: "outcome".into(),
        x_label: "materials.water.K".into(),
        y_label: "eos".into(),
        x_cats: x_cats.clone(),
        y_cats: y_cats.clone(),
        panels: vec![panel("mu = 0"), panel("mu = 0.5")],
        key: HeatKey::Legend(vec![
            ("survived".into(), RGBColor(0, 150, 0)),
            ("blew up".into(), RGBColor(200, 0, 0)),
        ]),
    };
    check(
        &fig,
        &dir,
        "heatmap_outcome",
        &["materials.water.K", "15 kPa", "tait", "survived"],
    );
    let fig = HeatmapFigure {
        title: "hydro".into(),
        x_label: "K".into(),
        y_label: "eos".into(),
        x_cats,
        y_cats,
        panels: vec![panel("")],
        key: HeatKey::Bar(
            ColourScale {
                lo: 1e-3,
                hi: 1.0,
                log: true,
            },
            "log10 rel. RMS".into(),
        ),
    };
    let texts = check(&fig, &dir, "heatmap_hydro", &["log10 rel. RMS"]);
    check_log_ticks(&texts, "heatmap_hydro", &["10⁻³", "10⁻²", "10⁻¹", "10⁰"]);
}

/// The narrowest matrix (one case per panel) with the matrix page's longest
/// title: the title wraps onto lines inside the figure instead of losing
/// its ends, and a map with no value carries its reason.
#[test]
fn long_titles_wrap_inside_a_narrow_heatmap() {
    let dir = scratch("narrow");
    let title = "Outcome by the cause of the first kick; time of first kick and blow-up (s)";
    let grey = RGBColor(220, 220, 220);
    let fig = HeatmapFigure {
        title: title.into(),
        x_label: "K".into(),
        y_label: "eos".into(),
        x_cats: vec!["1.5e6".into()],
        y_cats: vec!["tait".into()],
        panels: vec![HeatPanel {
            title: "materials.water.viscosity = 0.5".into(),
            cells: vec![HeatCell {
                x: 0,
                y: 0,
                colour: grey,
                text: "blew up".into(),
            }],
        }],
        key: HeatKey::Legend(vec![("no case completed".into(), grey)]),
    };
    let (w, _) = fig.size();
    assert!(w < 600, "the figure is narrower than its title's one line");
    let texts = check(
        &fig,
        &dir,
        "heatmap_narrow",
        &["no case completed", "blew up"],
    );
    let lines: Vec<&String> = texts
        .iter()
        .filter(|t| title.contains(t.as_str()))
        .collect();
    assert!(lines.len() >= 2, "the title wraps: {texts:?}");
    let joined = lines
        .iter()
        .map(|t| t.as_str())
        .collect::<Vec<_>>()
        .join(" ");
    assert_eq!(joined, title, "no word of the title is lost");
}

#[test]
fn words_wrap_greedily_and_a_long_word_stands_alone() {
    let width = |s: &str| 10 * s.chars().count() as u32;
    assert_eq!(wrap_words("aa bb cc", 50, width), ["aa bb", "cc"]);
    assert_eq!(
        wrap_words("aa bbbbbbbbbb cc", 50, width),
        ["aa", "bbbbbbbbbb", "cc"]
    );
    assert!(wrap_words("   ", 50, width).is_empty());
}

#[test]
fn stability_lines_render_as_png_and_svg() {
    let dir = scratch("stability");
    let fig = LinesFigure {
        title: "stability".into(),
        x_label: "K (Pa, log)".into(),
        y_label: "time survived (s)".into(),
        lines: vec![
            (
                "power 7".into(),
                vec![(1.5e4, 0.5), (1.5e5, 0.6), (1.5e6, 5.0)],
            ),
            (
                "tait".into(),
                vec![(1.5e4, 0.4), (1.5e5, 5.0), (1.5e6, 5.0)],
            ),
        ],
        spread: vec![vec![(1.5e4, 0.45, 0.55), (1.5e5, 0.5, 0.8)], vec![]],
        x_log: true,
        y_max: 5.0,
    };
    let texts = check(
        &fig,
        &dir,
        "stability",
        &["K (Pa, log)", "time survived (s)", "power 7"],
    );
    check_log_ticks(&texts, "stability", &["10⁴", "10⁵", "10⁶"]);
}

#[test]
fn speed_accuracy_plots_render_as_png_and_svg() {
    let dir = scratch("speed");
    let fig = ParetoFigure {
        title: "speed".into(),
        x_label: "wall seconds per simulated second".into(),
        y_label: "late hydrostatic rel. RMS".into(),
        points: vec![
            ("a".into(), 1.0, 0.5),
            ("b".into(), 10.0, 0.01),
            ("c".into(), 20.0, 0.2),
            ("d".into(), 3.0, 0.1),
        ],
    };
    let texts = check(
        &fig,
        &dir,
        "speed_accuracy",
        &["wall seconds per simulated second", "Pareto front"],
    );
    // x 1..20, y 0.01..0.5, both with 0.3 of padding.
    check_log_ticks(&texts, "speed_accuracy", &["10⁰", "10¹", "10⁻²", "10⁻¹"]);
}

#[test]
fn refinement_plots_render_as_png_and_svg() {
    let dir = scratch("refinement");
    let fig = RefinementFigure {
        title: "Refinement".into(),
        y_label: "late hydrostatic departure".into(),
        lines: vec![
            (
                "first".into(),
                vec![(0.02, 0.016), (0.01, 0.008), (0.005, 0.004)],
            ),
            (
                "second".into(),
                vec![(0.02, 0.04), (0.01, 0.01), (0.005, 0.0025)],
            ),
        ],
    };
    let texts = check(
        &fig,
        &dir,
        "refinement",
        &["cell size h (m)", "slope 1", "slope 2", "second"],
    );
    check_log_ticks(&texts, "refinement", &["10⁻²"]);
}

/// The reference lines have slopes 1 and 2 in log-log, pass through the
/// mean of the data's log10 points and span its h range.
#[test]
fn refinement_reference_slopes_pass_through_the_data_centre() {
    let pts = [(0.02, 0.04), (0.01, 0.01), (0.005, 0.0025)];
    let fig = RefinementFigure {
        title: String::new(),
        y_label: String::new(),
        lines: vec![
            ("a".into(), pts.to_vec()),
            ("unusable".into(), vec![(0.01, 0.0), (0.02, f64::NAN)]),
        ],
    };
    let refs = fig.reference_lines();
    assert_eq!(refs.len(), 2);
    let n = pts.len() as f64;
    let cx = pts.iter().map(|p| p.0.log10()).sum::<f64>() / n;
    let cy = pts.iter().map(|p| p.1.log10()).sum::<f64>() / n;
    for (slope, [a, b]) in refs {
        assert!(((b.1 - a.1) / (b.0 - a.0) - slope).abs() < 1e-12);
        assert!((a.1 + slope * (cx - a.0) - cy).abs() < 1e-12);
        assert!((a.0 - 0.005f64.log10()).abs() < 1e-12 && (b.0 - 0.02f64.log10()).abs() < 1e-12);
    }
}

#[test]
fn pareto_front_keeps_the_non_dominated_points() {
    let pts = [
        (1.0, 0.5),
        (10.0, 0.01),
        (20.0, 0.2),
        (3.0, 0.1),
        (3.0, 0.3),
    ];
    assert_eq!(pareto_front(&pts), vec![0, 3, 1]);
}

#[test]
fn the_cheapest_case_for_each_stated_error_is_on_the_front_cheapest_first() {
    let pts: Vec<(String, f64, f64)> = [
        (1.0, 0.5),
        (10.0, 0.01),
        (f64::NAN, 0.001),
        (0.5, f64::INFINITY),
        (20.0, 0.2),
        (3.0, 0.1),
        (3.0, 0.3),
        (0.0, 0.05),
    ]
    .iter()
    .enumerate()
    .map(|(i, &(x, y))| (format!("c{i}"), x, y))
    .collect();
    let front = cheapest_for_error(&pts);
    assert_eq!(front, vec![0, 5, 1]);
    // Brute force: for every stated error, the cheapest usable case within it.
    for target in [0.005, 0.01, 0.05, 0.1, 0.2, 0.5, 1.0] {
        let cheapest = (0..pts.len())
            .filter(|&i| pts[i].1 > 0.0 && pts[i].1.is_finite() && pts[i].2 <= target)
            .min_by(|&a, &b| pts[a].1.total_cmp(&pts[b].1));
        let first_within = front.iter().copied().find(|&i| pts[i].2 <= target);
        assert_eq!(cheapest, first_within, "target {target}");
    }
}

#[test]
fn decade_labels_are_powers_of_ten_in_superscript() {
    assert_eq!(decade_label(&0.0), "10⁰");
    assert_eq!(decade_label(&-0.0), "10⁰");
    assert_eq!(decade_label(&1.0), "10¹");
    assert_eq!(decade_label(&3.0), "10³");
    assert_eq!(decade_label(&-2.0), "10⁻²");
    assert_eq!(decade_label(&12.0), "10¹²");
    assert_eq!(decade_label(&-10.0), "10⁻¹⁰");
    // A whole decade computed in floating point still gets its label.
    assert_eq!(decade_label(&(0.1f64 * 3.0 * 10.0 / 3.0)), "10¹");
    for v in [0.5, 2.5, -0.3, 2f64.log10(), f64::NAN, f64::INFINITY] {
        assert_eq!(decade_label(&v), "", "{v}");
    }
}

#[test]
fn log_axes_mark_decades_and_the_minors_between() {
    let (lo, hi) = (-2.3, 1.7);
    assert_eq!(log_decades(lo, hi), vec![-2.0, -1.0, 0.0, 1.0]);
    let mut want = vec![];
    for k in -3..=1 {
        for m in 2..=9 {
            let v = k as f64 + (m as f64).log10();
            if (lo..=hi).contains(&v) {
                want.push(v);
            }
        }
    }
    // 6..9 x 10⁻³, all of 10⁻², 10⁻¹, 10⁰, then 2..5 x 10¹.
    assert_eq!(want.len(), 4 + 3 * 8 + 4);
    let got = log_minors(lo, hi);
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() < 1e-12, "{got:?}");
    }
    assert!(got.iter().all(|v| decade_label(v).is_empty()));

    // The axis: decades are the key points (labelled), minors the light ones.
    use plotters::prelude::Ranged;
    let axis = LogAxis::new(lo, hi);
    assert_eq!(axis.range(), lo..hi);
    assert_eq!(axis.decades(), log_decades(lo, hi).as_slice());
    assert_eq!(axis.minors(), got.as_slice());
    for d in axis.decades() {
        assert!(!decade_label(d).is_empty());
    }

    // A range inside one decade is widened to it, so there are labelled
    // ticks; one holding a decade and a 2 or 5 is kept; one holding a decade
    // alone is widened; a lone decade gets one each side.
    assert_eq!(log_range(0.2, 0.8), (0.0, 1.0));
    assert_eq!(log_range(-1.7, -1.2), (-2.0, -1.0));
    assert_eq!(log_range(-0.2, 0.4), (-0.2, 0.4));
    assert_eq!(log_range(-0.2, 0.3), (-1.0, 1.0));
    assert_eq!(log_range(2.0, 2.0), (1.0, 3.0));
    assert_eq!(log_range(0.5, 0.5), (0.0, 1.0));
    assert_eq!(log_range(f64::NAN, 1.0), (0.0, 1.0));
    let axis = LogAxis::new(0.2, 0.8);
    assert_eq!(axis.decades(), &[0.0, 1.0]);
    assert_eq!(axis.minors().len(), 8);
    assert!(log_decades(0.2, 0.8).is_empty());

    // Fewer than two decades: 2 and 5 times each are labelled too.
    let ticks = log_ticks(-0.2, 0.4);
    assert_eq!(ticks.len(), 2, "{ticks:?}");
    let labels: Vec<String> = ticks.iter().map(log_label).collect();
    assert_eq!(labels, ["10⁰", "2"]);
    let labels: Vec<String> = log_ticks(-1.5, -0.1).iter().map(log_label).collect();
    assert_eq!(labels, ["0.05", "10⁻¹", "0.2", "0.5"]);
    assert_eq!(log_ticks(-2.3, 1.7), log_decades(-2.3, 1.7));
    assert_eq!(log_label(&3f64.log10()), "");
}
