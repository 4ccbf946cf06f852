//! `kick report`: turns a case folder or a matrix folder into
//! `report/index.html` (self-contained, relative links) with every figure as
//! PNG and SVG, and an animated GIF around each kick.

use crate::metrics::martin_moyce;
use crate::output_files::write_atomic;
use crate::plot_case::{
    animate, FrontFigure, MapsFigure, Marker, Outline, PressureDepthFigure, Series,
    TimeseriesFigure,
};
use crate::plot_common::{err, render, short, ColourScale, Res};
use crate::plot_matrix::{HeatCell, HeatKey, HeatPanel, HeatmapFigure, LinesFigure, ParetoFigure};
use crate::run_case::front_wall_z;
use crate::snapshot::Snapshot;
use crate::study_file;
use plotters::style::RGBColor;
use polars::prelude::*;
use serde_json::Value;
use std::collections::BTreeSet;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Writes the report of `dir` (a case or a matrix) and returns the page's path.
pub fn report(dir: &Path) -> Res<PathBuf> {
    if dir.join("summary.parquet").exists() {
        matrix_report(dir)
    } else if dir.join("summary.json").exists() {
        case_report(dir)
    } else {
        Err(format!(
            "{}: neither a matrix folder (summary.parquet) nor a case folder (summary.json)",
            dir.display()
        ))
    }
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1400px;margin:1em auto;padding:0 1em;color:#222}\
img{max-width:100%;border:1px solid #ddd;margin:.3em 0}table{border-collapse:collapse;font-size:13px}\
td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}th{background:#eee}td.l{text-align:left}\
.blew_up{background:#f8d0d0}.failed{background:#ddd}.kicked{background:#fde3c0}.completed{background:#d8f0d8}\
figure{margin:0 0 1.2em 0}figcaption{font-size:13px;color:#555}";

fn page(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{STYLE}</style></head>\n<body>\n<h1>{}</h1>\n{body}</body></html>\n",
        html_escape(title),
        html_escape(title)
    )
}

fn figure(files: &[String; 2], caption: &str) -> String {
    format!(
        "<figure><img src=\"{0}\" alt=\"{1}\"><figcaption>{1} (<a href=\"{2}\">SVG</a>)</figcaption></figure>\n",
        files[0],
        html_escape(caption),
        files[1]
    )
}

fn read_json(path: &Path) -> Res<Value> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_slice(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

fn read_parquet(path: &Path) -> Res<DataFrame> {
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    ParquetReader::new(file)
        .finish()
        .map_err(|e| format!("{}: {e}", path.display()))
}

fn f64_column(df: &DataFrame, name: &str) -> Option<Vec<f64>> {
    let c = df.column(name).ok()?.cast(&DataType::Float64).ok()?;
    Some(
        c.f64()
            .ok()?
            .into_iter()
            .map(|v| v.unwrap_or(f64::NAN))
            .collect(),
    )
}

fn text_column(df: &DataFrame, name: &str) -> Option<Vec<String>> {
    let c = df.column(name).ok()?;
    Some(
        (0..c.len())
            .map(|i| match c.get(i) {
                Ok(AnyValue::String(s)) => s.to_string(),
                Ok(AnyValue::Null) => String::new(),
                Ok(AnyValue::Float64(f)) => short(f),
                Ok(other) => other.to_string(),
                Err(_) => String::new(),
            })
            .collect(),
    )
}

fn vtk_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|r| {
            r.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "vtk"))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

fn load_snapshot(path: &Path) -> Res<Snapshot> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    Snapshot::from_vtk(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// The per-case page.
pub fn case_report(dir: &Path) -> Res<PathBuf> {
    let out = dir.join("report");
    let summary = read_json(&dir.join("summary.json"))?;
    let name = summary["case"].as_str().unwrap_or("case").to_string();
    let study = study_file::load(&dir.join("case.toml"), &[]).map_err(|e| e.to_string())?;
    let scene = &study.cases[0].solver.scene;
    let g = if scene.gravity > 0.0 {
        scene.gravity
    } else {
        9.81
    };
    let bbox = [
        scene.origin[0],
        scene.origin[1],
        scene.origin[0] + scene.size[0],
        scene.origin[1] + scene.size[1],
    ];
    let events = summary["events"].as_array().cloned().unwrap_or_default();
    let mut body = String::new();

    // Summary and events.
    let status = summary["status"].as_str().unwrap_or("?");
    let _ = writeln!(
        body,
        "<p>Status <b>{}</b>{} after {} steps, t = {:.4} s; wall {:.1} s, {:.2} M particle-steps/s.</p>",
        status,
        summary["reason"].as_str().filter(|r| !r.is_empty()).map(|r| format!(" ({})", html_escape(r))).unwrap_or_default(),
        summary["steps"],
        summary["t_end"].as_f64().unwrap_or(0.0),
        summary["wall_s"].as_f64().unwrap_or(0.0),
        summary["particle_steps_per_s"].as_f64().unwrap_or(0.0) / 1e6
    );
    body.push_str("<h2>Metrics</h2><table>");
    if let Some(m) = summary["metrics"].as_object() {
        for (k, v) in m {
            let shown = v.as_f64().map(short).unwrap_or_else(|| {
                if v.is_null() {
                    "-".into()
                } else {
                    v.to_string()
                }
            });
            let _ = write!(body, "<tr><td class=l>{k}</td><td>{shown}</td></tr>");
        }
    }
    body.push_str("</table>\n<h2>Events</h2>\n");
    if events.is_empty() {
        body.push_str("<p>No event.</p>\n");
    } else {
        body.push_str("<table><tr><th>id</th><th>kind</th><th>first step</th><th>t (s)</th><th>region (m)</th><th>particles</th><th>peak a/g</th><th>peak z</th><th>Courant</th><th>quiescent before</th><th>previously deformed</th><th>rules</th></tr>\n");
        for e in &events {
            let r = &e["region"];
            let _ = writeln!(
                body,
                "<tr><td>{}</td><td class=l>{}</td><td>{}</td><td>{:.4}</td><td class=l>x {:.3}-{:.3}, y {:.3}-{:.3}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.2}</td><td>{}</td><td>{}</td><td class=l>{}</td></tr>",
                e["id"], e["kind"].as_str().unwrap_or(""), e["first_step"], e["t"].as_f64().unwrap_or(0.0),
                r["x_min"].as_f64().unwrap_or(0.0), r["x_max"].as_f64().unwrap_or(0.0),
                r["y_min"].as_f64().unwrap_or(0.0), r["y_max"].as_f64().unwrap_or(0.0),
                e["n_particles"], short(e["peak_accel_g"].as_f64().unwrap_or(0.0)), short(e["peak_z"].as_f64().unwrap_or(0.0)),
                e["courant"].as_f64().unwrap_or(0.0), e["quiescent_before"], e["previously_deformed"],
                e["rules"].as_array().map(|a| a.iter().filter_map(|v| v.as_str()).collect::<Vec<_>>().join(", ")).unwrap_or_default()
            );
        }
        body.push_str("</table>\n");
    }

    // Time series and front.
    let df = read_parquet(&dir.join("timeseries.parquet"))?;
    let t = f64_column(&df, "t").ok_or("timeseries lacks t")?;
    let columns = df
        .get_column_names()
        .iter()
        .filter_map(|n| f64_column(&df, n).map(|v| (n.to_string(), v)))
        .collect();
    let series = Series { t, columns };
    let markers: Vec<Marker> = events
        .iter()
        .filter(|e| {
            e["kind"] == "kick" || e["kind"] == "blow_out" || e["kind"] == "energy_injection"
        })
        .map(|e| Marker {
            id: e["id"].as_u64().unwrap_or(0) as u32,
            t: e["t"].as_f64().unwrap_or(0.0),
        })
        .collect();
    body.push_str("<h2>Time series</h2>\n");
    let fig = TimeseriesFigure {
        series: &series,
        markers: &markers,
        title: format!("{name}: energy, kicks, checkerboard, hydrostatic departure"),
    };
    body.push_str(&figure(&render(&fig, &out, "timeseries")?, "Energy budget, injected energy, max a/g and outlier score, checkerboard index and hydrostatic departure; red lines mark events"));
    if let (Some(z_wall), Some(ft), Some(fz)) = (
        front_wall_z(scene),
        series.get("front_t"),
        series.get("front_z"),
    ) {
        let data = martin_moyce();
        let fig = FrontFigure {
            t: ft,
            z: fz,
            data: &data,
            z_wall,
            title: format!("{name}: surge front"),
        };
        body.push_str(&figure(
            &render(&fig, &out, "front")?,
            "Surge front Z(T) against Martin & Moyce (1952)",
        ));
    }

    // Particle maps at the study's times, and late pressure against depth.
    let snaps_files = vtk_files(&dir.join("particles"));
    if !snaps_files.is_empty() {
        let pick: BTreeSet<usize> = (0..4).map(|k| k * (snaps_files.len() - 1) / 3).collect();
        let snaps: Vec<Snapshot> = pick
            .iter()
            .map(|&k| load_snapshot(&snaps_files[k]))
            .collect::<Res<_>>()?;
        let fig = MapsFigure {
            snaps: snaps
                .iter()
                .map(|s| (s, format!("t = {:.3} s", s.t)))
                .collect(),
            bbox,
            outline: None,
            gravity: g,
            title: format!("{name}: pressure (top) and a/g (bottom)"),
        };
        body.push_str("<h2>Particles</h2>\n");
        body.push_str(&figure(
            &render(&fig, &out, "maps")?,
            "Particles coloured by pressure and by acceleration over g",
        ));
        let last = load_snapshot(snaps_files.last().expect("non-empty"))?;
        let area: f64 = scene
            .bodies
            .iter()
            .map(|b| (b.rect[2] - b.rect[0]) * (b.rect[3] - b.rect[1]))
            .sum();
        let rho0 = scene.materials.first().map_or(1000.0, |m| m.rho0);
        let fig = PressureDepthFigure {
            snap: &last,
            level: scene.origin[1] + area / scene.size[0],
            rho0,
            gravity: g,
            title: format!(
                "{name}, t = {:.2} s: late hydrostatic rel. RMS {}",
                last.t,
                summary["metrics"]["hydro_rel_rms_late"]
                    .as_f64()
                    .map(short)
                    .unwrap_or("-".into())
            ),
        };
        body.push_str(&figure(
            &render(&fig, &out, "pressure_depth")?,
            "Pressure against depth at the last snapshot, with the hydrostatic line",
        ));
    }

    // Each event: before, at and after, and an animation.
    for e in &events {
        let id = e["id"].as_u64().unwrap_or(0);
        let frames_files = vtk_files(&dir.join("particles").join(format!("event_{id}")));
        if frames_files.is_empty() {
            continue;
        }
        let frames: Vec<Snapshot> = frames_files
            .iter()
            .map(|p| load_snapshot(p))
            .collect::<Res<_>>()?;
        let first = e["first_step"].as_u64().unwrap_or(0);
        let r = &e["region"];
        let outline = Some(Outline {
            x0: r["x_min"].as_f64().unwrap_or(0.0),
            y0: r["y_min"].as_f64().unwrap_or(0.0),
            x1: r["x_max"].as_f64().unwrap_or(0.0),
            y1: r["y_max"].as_f64().unwrap_or(0.0),
        });
        let at = frames.iter().position(|f| f.step == first).unwrap_or(0);
        let mut chosen = vec![];
        if at > 0 {
            chosen.push((&frames[at - 1], "before"));
        }
        chosen.push((&frames[at], "at"));
        if at + 1 < frames.len() {
            chosen.push((frames.last().expect("non-empty"), "after"));
        }
        let kind = e["kind"].as_str().unwrap_or("event");
        let fig = MapsFigure {
            snaps: chosen
                .iter()
                .map(|(s, w)| (*s, format!("{w}: step {}, t = {:.4} s", s.step, s.t)))
                .collect(),
            bbox,
            outline,
            gravity: g,
            title: format!("{name}: {kind} #{id} (region outlined)"),
        };
        let _ = writeln!(body, "<h2>Event {id} ({kind}, step {first})</h2>");
        body.push_str(&figure(
            &render(&fig, &out, &format!("event_{id}_maps"))?,
            "Before, at and after the event: pressure (top), a/g (bottom)",
        ));
        let gif = format!("event_{id}.gif");
        animate(
            &frames,
            bbox,
            outline,
            &format!("{kind} #{id}"),
            &out.join(&gif),
            g,
        )?;
        let _ = writeln!(body, "<figure><img src=\"{gif}\" alt=\"animation of event {id}\"><figcaption>Animation around event {id} (every 5 steps)</figcaption></figure>");
    }
    let index = out.join("index.html");
    write_atomic(
        &index,
        page(&format!("kick report: {name}"), &body).as_bytes(),
    )
    .map_err(err)?;
    Ok(index)
}

/// The relative path from directory `from` to `to` (both made absolute).
fn relative(from: &Path, to: &Path) -> String {
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let (from, to) = (abs(from), abs(to));
    let a: Vec<_> = from.components().collect();
    let b: Vec<_> = to.components().collect();
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut parts: Vec<String> = vec!["..".into(); a.len() - common];
    parts.extend(
        b[common..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy().into_owned()),
    );
    parts.join("/")
}

struct Row {
    case: String,
    dir: PathBuf,
    status: String,
    t_end: f64,
    t_first_kick: f64,
    hydro_late: f64,
    cb_late: f64,
    front_error: f64,
    wall_s: f64,
    params: Vec<String>,
}

impl Row {
    fn outcome(&self) -> &'static str {
        match self.status.as_str() {
            "blew_up" => "blew_up",
            "failed" => "failed",
            _ if self.t_first_kick.is_finite() => "kicked",
            _ => "completed",
        }
    }
}

const OUTCOMES: [(&str, &str, RGBColor); 4] = [
    ("completed", "survived", RGBColor(90, 170, 90)),
    ("kicked", "kicked", RGBColor(240, 160, 60)),
    ("blew_up", "blew up", RGBColor(200, 50, 50)),
    ("failed", "failed", RGBColor(150, 150, 150)),
];

/// The matrix page (and every case's page).
pub fn matrix_report(dir: &Path) -> Res<PathBuf> {
    let out = dir.join("report");
    let df = read_parquet(&dir.join("summary.parquet"))?;
    let names = df
        .get_column_names()
        .iter()
        .map(|s| s.to_string())
        .collect::<Vec<_>>();
    let param_keys: Vec<String> = names
        .iter()
        .filter(|n| n.contains('.') && !n.starts_with("metric."))
        .cloned()
        .collect();
    let texts: Vec<Vec<String>> = param_keys
        .iter()
        .map(|k| text_column(&df, k).unwrap_or_default())
        .collect();
    let varying: Vec<usize> = (0..param_keys.len())
        .filter(|&k| texts[k].iter().collect::<BTreeSet<_>>().len() > 1)
        .collect();
    let col = |n: &str| f64_column(&df, n).unwrap_or_else(|| vec![f64::NAN; df.height()]);
    let (t_end, kick, hydro, cb, front, wall) = (
        col("t_end"),
        col("t_first_kick"),
        col("hydro_rel_rms_late"),
        col("checkerboard_late"),
        col("front_rms_error"),
        col("wall_s"),
    );
    let cases = text_column(&df, "case").ok_or("summary lacks case")?;
    let status = text_column(&df, "status").ok_or("summary lacks status")?;
    let dirs = text_column(&df, "case_dir").ok_or("summary lacks case_dir")?;
    let mut rows: Vec<Row> = (0..df.height())
        .map(|i| Row {
            case: cases[i].clone(),
            dir: {
                let d = PathBuf::from(&dirs[i]);
                if d.is_absolute() || d.exists() {
                    d
                } else {
                    dir.join(&cases[i])
                }
            },
            status: status[i].clone(),
            t_end: t_end[i],
            t_first_kick: kick[i],
            hydro_late: hydro[i],
            cb_late: cb[i],
            front_error: front[i],
            wall_s: wall[i],
            params: varying.iter().map(|&k| texts[k][i].clone()).collect(),
        })
        .collect();
    // Grouped by axis: numbers compare as numbers, the rest as text.
    let by_value = |a: &String, b: &String| match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(x), Ok(y)) => x.total_cmp(&y),
        _ => a.cmp(b),
    };
    rows.sort_by(|a, b| {
        a.params
            .iter()
            .zip(&b.params)
            .map(|(x, y)| by_value(x, y))
            .find(|o| o.is_ne())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let vnames: Vec<&str> = varying.iter().map(|&k| param_keys[k].as_str()).collect();

    // Case pages first, so the matrix page can link them.
    let mut case_links = vec![];
    for r in &rows {
        let link = match case_report(&r.dir) {
            Ok(index) => Some(relative(&out, &index)),
            Err(e) => {
                eprintln!("kick report: {}: {e}", r.case);
                None
            }
        };
        case_links.push(link);
    }
    std::fs::create_dir_all(&out).map_err(err)?;
    let mut body = String::new();
    let count = |o: &str| rows.iter().filter(|r| r.outcome() == o).count();
    let kicked = rows.iter().filter(|r| r.t_first_kick.is_finite()).count();
    let link = |k: usize| match &case_links[k] {
        Some(l) => format!("<a href=\"{l}\">{}</a>", html_escape(&rows[k].case)),
        None => html_escape(&rows[k].case),
    };
    let _ = writeln!(
        body,
        "<p>{} cases ran: {} survived without a kick, {} kicked at least once ({} of them then completed), {} blew up, {} failed.</p>",
        rows.len(),
        count("completed"),
        kicked,
        count("kicked"),
        count("blew_up"),
        count("failed")
    );
    let ranked: Vec<usize> = {
        let mut v: Vec<usize> = (0..rows.len())
            .filter(|&k| rows[k].status == "completed" && rows[k].hydro_late.is_finite())
            .collect();
        v.sort_by(|&a, &b| rows[a].hydro_late.total_cmp(&rows[b].hydro_late));
        v
    };
    if let (Some(&best), Some(&worst)) = (ranked.first(), ranked.last()) {
        let _ = writeln!(
            body,
            "<p>Closest to hydrostatic at the end: {} (late rel. RMS {}). Furthest among completed cases: {} ({}).</p>",
            link(best), short(rows[best].hydro_late), link(worst), short(rows[worst].hydro_late)
        );
    }
    if let Some(k) = (0..rows.len())
        .filter(|&k| rows[k].status == "blew_up")
        .min_by(|&a, &b| rows[a].t_end.total_cmp(&rows[b].t_end))
    {
        let _ = writeln!(
            body,
            "<p>Earliest blow-up: {} at t = {:.3} s.</p>",
            link(k),
            rows[k].t_end
        );
    }

    // Heatmaps.
    let find = |suffix: &str| vnames.iter().position(|n| n.ends_with(suffix));
    if !vnames.is_empty() {
        let x_axis = find(".K").unwrap_or(0);
        let panel_axis = find(".viscosity").filter(|&p| p != x_axis);
        let y_axes: Vec<usize> = (0..vnames.len())
            .filter(|&k| k != x_axis && Some(k) != panel_axis)
            .collect();
        let y_of = |r: &Row| {
            y_axes
                .iter()
                .map(|&k| r.params[k].clone())
                .collect::<Vec<_>>()
                .join(" ")
        };
        let cats = |f: &dyn Fn(&Row) -> String| -> Vec<String> {
            let mut v: Vec<String> = rows
                .iter()
                .map(f)
                .collect::<BTreeSet<_>>()
                .into_iter()
                .collect();
            v.sort_by(by_value);
            v
        };
        let x_cats = cats(&|r: &Row| r.params[x_axis].clone());
        let y_cats = cats(&y_of);
        let p_cats = match panel_axis {
            Some(p) => cats(&|r: &Row| r.params[p].clone()),
            None => vec![String::new()],
        };
        let y_label = if y_axes.is_empty() {
            String::new()
        } else {
            y_axes
                .iter()
                .map(|&k| vnames[k])
                .collect::<Vec<_>>()
                .join(" / ")
        };
        let hydro_scale =
            ColourScale::robust(&rows.iter().map(|r| r.hydro_late).collect::<Vec<_>>(), true);
        let heat = |cell: &dyn Fn(&Row) -> (RGBColor, String)| -> Vec<HeatPanel> {
            p_cats
                .iter()
                .map(|p| HeatPanel {
                    title: match panel_axis {
                        Some(a) => format!("{} = {p}", vnames[a]),
                        None => String::new(),
                    },
                    cells: rows
                        .iter()
                        .filter(|r| panel_axis.is_none_or(|a| &r.params[a] == p))
                        .map(|r| {
                            let (colour, text) = cell(r);
                            HeatCell {
                                x: x_cats
                                    .iter()
                                    .position(|c| *c == r.params[x_axis])
                                    .unwrap_or(0),
                                y: y_cats.iter().position(|c| *c == y_of(r)).unwrap_or(0),
                                colour,
                                text,
                            }
                        })
                        .collect(),
                })
                .collect()
        };
        let outcome = HeatmapFigure {
            title: "Outcome and time of first kick (s)".into(),
            x_label: vnames[x_axis].into(),
            y_label: y_label.clone(),
            x_cats: x_cats.clone(),
            y_cats: y_cats.clone(),
            panels: heat(&|r: &Row| {
                let colour = OUTCOMES
                    .iter()
                    .find(|o| o.0 == r.outcome())
                    .map_or(RGBColor(150, 150, 150), |o| o.2);
                let text = match r.outcome() {
                    "blew_up" if r.t_first_kick.is_finite() => {
                        format!("k {:.2} x {:.2}", r.t_first_kick, r.t_end)
                    }
                    "blew_up" => format!("x {:.2}", r.t_end),
                    "failed" => "failed".into(),
                    _ if r.t_first_kick.is_finite() => format!("k {:.2}", r.t_first_kick),
                    _ => "ok".into(),
                };
                (colour, text)
            }),
            key: HeatKey::Legend(OUTCOMES.iter().map(|o| (o.1.to_string(), o.2)).collect()),
        };
        body.push_str("<h2>Outcome</h2>\n");
        body.push_str(&figure(
            &render(&outcome, &out, "heatmap_outcome")?,
            "Outcome per case: k t = first kick at t (s), x t = blew up at t (s)",
        ));
        let hydro_map = HeatmapFigure {
            title: "Late hydrostatic departure (relative RMS, last second)".into(),
            x_label: vnames[x_axis].into(),
            y_label,
            x_cats: x_cats.clone(),
            y_cats: y_cats.clone(),
            panels: heat(&|r: &Row| {
                if r.hydro_late.is_finite() && r.hydro_late > 0.0 {
                    (hydro_scale.colour(r.hydro_late), short(r.hydro_late))
                } else {
                    (RGBColor(220, 220, 220), "-".into())
                }
            }),
            key: HeatKey::Bar(hydro_scale, "log10 rel. RMS".into()),
        };
        body.push_str(&figure(
            &render(&hydro_map, &out, "heatmap_hydro")?,
            "Late hydrostatic departure (log colour scale)",
        ));

        // Stability map: survival time against K, one line per family.
        if let Some(kx) = find(".K") {
            let short_key = |k: usize| vnames[k].rsplit('.').next().unwrap_or(vnames[k]);
            let family = |r: &Row| {
                (0..vnames.len())
                    .filter(|&k| k != kx)
                    .map(|k| format!("{}={}", short_key(k), r.params[k]))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            let fams: BTreeSet<String> = rows.iter().map(family).collect();
            let lines = fams
                .iter()
                .map(|f| {
                    let mut pts: Vec<(f64, f64)> = rows
                        .iter()
                        .filter(|r| &family(r) == f)
                        .filter_map(|r| Some((r.params[kx].parse::<f64>().ok()?, r.t_end)))
                        .collect();
                    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                    (
                        if f.is_empty() {
                            "all".to_string()
                        } else {
                            f.clone()
                        },
                        pts,
                    )
                })
                .collect();
            let fig = LinesFigure {
                title: "Stability map: time survived".into(),
                x_label: format!("{} (Pa, log)", vnames[kx]),
                y_label: "time survived (s)".into(),
                lines,
                x_log: true,
                y_max: rows.iter().map(|r| r.t_end).fold(0.1, f64::max),
            };
            body.push_str(&figure(
                &render(&fig, &out, "stability")?,
                "Time survived against K, one line per combination of the other axes",
            ));
        }
    }

    // Speed against accuracy.
    // Completed cases when at least two completed; otherwise every case that ran
    // (its accuracy then measured over its last second before blowing up).
    let point = |r: &Row| (r.case.clone(), r.wall_s / r.t_end, r.hydro_late);
    let ran = |r: &&Row| r.status != "failed" && r.t_end > 0.0;
    let completed: Vec<_> = rows
        .iter()
        .filter(ran)
        .filter(|r| r.status == "completed")
        .map(point)
        .collect();
    let (points, which) = if completed.len() >= 2 {
        (completed, "completed cases")
    } else {
        (
            rows.iter().filter(ran).map(point).collect(),
            "all cases; fewer than two completed",
        )
    };
    if points.len() >= 2 {
        let fig = ParetoFigure {
            title: format!("Speed against accuracy ({which})"),
            x_label: "wall seconds per simulated second".into(),
            y_label: "late hydrostatic rel. RMS".into(),
            points,
        };
        body.push_str("<h2>Speed against accuracy</h2>\n");
        body.push_str(&figure(
            &render(&fig, &out, "speed_accuracy")?,
            "Cost against late hydrostatic departure, Pareto front in red",
        ));
    }

    // The table.
    body.push_str("<h2>Cases</h2>\n<table id=\"cases\"><tr><th>case</th>");
    for n in &vnames {
        let _ = write!(body, "<th>{}</th>", html_escape(n));
    }
    body.push_str("<th>status</th><th>t end (s)</th><th>first kick (s)</th><th>hydro late</th><th>checkerboard late</th><th>front error (Z)</th><th>wall (s)</th></tr>\n");
    let cell = |v: f64| if v.is_finite() { short(v) } else { "-".into() };
    for (k, r) in rows.iter().enumerate() {
        let _ = write!(
            body,
            "<tr class=\"case-row {}\"><td class=l>{}</td>",
            r.outcome(),
            link(k)
        );
        for p in &r.params {
            let _ = write!(body, "<td>{}</td>", html_escape(p));
        }
        let _ = writeln!(
            body,
            "<td class=l>{}</td><td>{:.3}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.1}</td></tr>",
            r.status, r.t_end, cell(r.t_first_kick), cell(r.hydro_late), cell(r.cb_late), cell(r.front_error), r.wall_s
        );
    }
    body.push_str("</table>\n");
    let title = format!(
        "kick matrix report: {}",
        dir.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let index = out.join("index.html");
    write_atomic(&index, page(&title, &body).as_bytes()).map_err(err)?;
    Ok(index)
}
