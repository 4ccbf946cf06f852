//! The matrix report page: a text summary with links, outcome and
//! late-hydrostatic heatmaps, the stability map, speed against accuracy and
//! the case table. Rows are gathered first (from each case's summary.json,
//! found through summary.parquet's `case_dir`), then rendered.

use crate::output_files::{relative_path, write_atomic};
use crate::plot_common::{err, render, short, ColourScale, Res};
use crate::plot_matrix::{
    pareto_front, HeatCell, HeatKey, HeatPanel, HeatmapFigure, LinesFigure, ParetoFigure,
};
use crate::report::{read_parquet, text_column};
use crate::report_case::case_report;
use crate::report_html::{escape, Cell, Page};
use crate::study_file::ENSEMBLE_KEYS;
use crate::summary::{Status, Summary};
use plotters::style::RGBColor;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// One case of the matrix, with the values of the parameters that vary.
pub struct Row {
    pub summary: Summary,
    pub dir: PathBuf,
    /// Values of `Matrix::axes`, as text.
    pub params: Vec<String>,
    /// Relative link to the case's page, when it rendered.
    link: Option<String>,
}

impl Row {
    fn case(&self) -> &str {
        &self.summary.case
    }

    fn t_end(&self) -> f64 {
        self.summary.t_end
    }

    fn nan(v: Option<f64>) -> f64 {
        v.unwrap_or(f64::NAN)
    }

    fn t_first_kick(&self) -> f64 {
        Row::nan(self.summary.metrics.t_first_kick)
    }

    pub fn hydro_late(&self) -> f64 {
        Row::nan(self.summary.metrics.hydro_rel_rms_late)
    }

    /// Late departure of a completed run, or over the second before a blow-up.
    fn hydro_late_or_pre_failure(&self) -> f64 {
        let m = &self.summary.metrics;
        Row::nan(m.hydro_rel_rms_late.or(m.hydro_rel_rms_pre_failure))
    }

    fn outcome(&self) -> &'static str {
        match self.summary.status {
            Status::BlewUp => "blew_up",
            Status::Failed => "failed",
            Status::Completed if self.summary.kicked() => "kicked",
            Status::Completed => "completed",
        }
    }

    /// The case name, linked to its page when there is one.
    fn link_html(&self) -> String {
        match &self.link {
            Some(l) => format!("<a href=\"{l}\">{}</a>", escape(self.case())),
            None => escape(self.case()),
        }
    }
}

#[cfg(test)]
impl Row {
    pub fn for_test(summary: Summary, params: Vec<String>) -> Self {
        Row {
            summary,
            dir: PathBuf::new(),
            params,
            link: None,
        }
    }
}

/// The outcome heatmap's classes, best to worst: how a run ended when it
/// never kicked, else the cause of its first kick (docs/physics.md 4b).
const CLASSES: [(&str, RGBColor); 6] = [
    ("no kick, survived", RGBColor(90, 170, 90)),
    ("no kick, blew up", RGBColor(235, 175, 175)),
    ("injection first", RGBColor(240, 150, 50)),
    ("inversion first", RGBColor(190, 40, 40)),
    ("anomaly first", RGBColor(140, 60, 170)),
    ("failed", RGBColor(150, 150, 150)),
];

impl Row {
    /// Index into `CLASSES`.
    fn class(&self) -> usize {
        let s = &self.summary;
        if s.status == Status::Failed {
            return 5;
        }
        let first = s
            .events
            .iter()
            .filter(|e| e.is_kick())
            .min_by(|a, b| a.t.total_cmp(&b.t));
        match first {
            None if s.status == Status::Completed => 0,
            None => 1,
            Some(e) if e.is_anomaly() => 4,
            Some(e) if e.cause == monitor::Cause::Inversion => 3,
            Some(_) => 2,
        }
    }
}

/// Median, smallest and largest of the finite values (None when there are none).
/// "m" or "m [lo, hi]" over the finite values ("-" when there are none).
pub fn spread_text(values: impl Iterator<Item = f64>, runs: usize, digits: usize) -> String {
    spread(values).map_or("-".into(), |s| with_spread(s, runs, digits))
}

/// Median of the finite values (None when there are none).
pub fn median(values: &[f64]) -> Option<f64> {
    spread(values.iter().copied()).map(|s| s.0)
}

fn spread(values: impl Iterator<Item = f64>) -> Option<(f64, f64, f64)> {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    Some((median, v[0], v[n - 1]))
}

/// "m" for one run, "m [lo, hi]" for several.
fn with_spread(s: (f64, f64, f64), runs: usize, digits: usize) -> String {
    if runs <= 1 {
        format!("{:.*}", digits, s.0)
    } else {
        format!(
            "{:.*} [{:.*}, {:.*}]",
            digits, s.0, digits, s.1, digits, s.2
        )
    }
}

/// Heatmap form: the median, with ± half the range when the runs differ.
fn compact(s: (f64, f64, f64)) -> String {
    let half = 0.5 * (s.2 - s.1);
    if half < 0.005 {
        format!("{:.2}", s.0)
    } else {
        format!("{:.2}±{:.2}", s.0, half)
    }
}

/// Numbers compare as numbers, the rest as text.
fn by_value(a: &String, b: &String) -> std::cmp::Ordering {
    match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(x), Ok(y)) => x.total_cmp(&y),
        _ => a.cmp(b),
    }
}

fn param_text(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Number(n) => n.as_f64().map(short).unwrap_or_else(|| n.to_string()),
        other => other.to_string(),
    }
}

/// The default method, as the params of a summary hold it.
fn method_defaults() -> serde_json::Value {
    serde_json::to_value(solver::Method::default()).unwrap_or_default()
}

/// A param as text. A summary written before a method key existed lacks
/// it and ran with its default, so it reads as the default ("" for other
/// keys).
fn param_or_default(
    params: &BTreeMap<String, serde_json::Value>,
    key: &str,
    defaults: &serde_json::Value,
) -> String {
    params
        .get(key)
        .or_else(|| defaults.get(key.strip_prefix("method.")?))
        .map(param_text)
        .unwrap_or_default()
}

/// A param as the matrix labels it: a material's `eos` by its own
/// parameters (`labels::eos_label_of_params`: "power gamma=7", "tait
/// C=0.0894", "linear"), its `gamma` as "-" unless it is a power law (only
/// the power law has one); any other key as `param_or_default`.
fn axis_text(
    params: &BTreeMap<String, serde_json::Value>,
    key: &str,
    defaults: &serde_json::Value,
) -> String {
    let material = key
        .strip_prefix("materials.")
        .and_then(|k| k.rsplit_once('.'))
        .map(|(name, field)| (format!("materials.{name}"), field));
    let raw = |k: &str| param_or_default(params, k, defaults);
    match material {
        Some((m, "eos")) => {
            let (eos, gamma) = (raw(&format!("{m}.eos")), raw(&format!("{m}.gamma")));
            crate::labels::eos_label_of_params(Some(&eos), Some(&gamma)).unwrap_or(eos)
        }
        Some((m, "gamma")) if !matches!(raw(&format!("{m}.eos")).as_str(), "" | "power") => {
            "-".into()
        }
        _ => raw(key),
    }
}

/// The rows of a matrix, sorted by the varying parameters, and those parameters' keys.
pub struct Matrix {
    pub axes: Vec<String>,
    pub rows: Vec<Row>,
}

impl Matrix {
    fn read(dir: &Path) -> Res<Self> {
        let df = read_parquet(&dir.join("summary.parquet"))?;
        let dirs = text_column(&df, "case_dir").ok_or("summary.parquet lacks case_dir")?;
        let summaries: Vec<(PathBuf, Summary)> = dirs
            .iter()
            .map(|d| {
                let case_dir = dir.join(d);
                Summary::read(&case_dir).map(|s| (case_dir, s))
            })
            .collect::<Res<_>>()?;
        // Ensemble members differ only in their seed: one case, several runs.
        let keys: BTreeSet<&String> = summaries
            .iter()
            .flat_map(|(_, s)| s.params.keys())
            .filter(|k| !ENSEMBLE_KEYS.contains(&k.as_str()))
            .collect();
        let defaults = method_defaults();
        let text = |s: &Summary, k: &String| axis_text(&s.params, k, &defaults);
        let varying: Vec<String> = keys
            .into_iter()
            .filter(|k| {
                summaries
                    .iter()
                    .map(|(_, s)| text(s, k))
                    .collect::<BTreeSet<_>>()
                    .len()
                    > 1
            })
            .cloned()
            .collect();
        // A material's `eos` axis is labelled with its gamma (power law
        // only): its `gamma` axis would repeat it.
        let axes: Vec<String> = varying
            .iter()
            .filter(|k| {
                !k.strip_suffix(".gamma")
                    .is_some_and(|m| varying.contains(&format!("{m}.eos")))
            })
            .cloned()
            .collect();
        let mut rows: Vec<Row> = summaries
            .into_iter()
            .map(|(dir, summary)| Row {
                params: axes.iter().map(|k| text(&summary, k)).collect(),
                summary,
                dir,
                link: None,
            })
            .collect();
        rows.sort_by(|a, b| {
            a.params
                .iter()
                .zip(&b.params)
                .map(|(x, y)| by_value(x, y))
                .find(|o| o.is_ne())
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        Ok(Matrix { axes, rows })
    }

    pub fn axis(&self, suffix: &str) -> Option<usize> {
        self.axes.iter().position(|n| n.ends_with(suffix))
    }
}

/// The matrix page (and every case's page); returns its path.
pub fn matrix_report(dir: &Path) -> Res<PathBuf> {
    let out = dir.join("report");
    let mut m = Matrix::read(dir)?;
    std::fs::create_dir_all(&out).map_err(err)?;
    // Case pages first, so the matrix page can link them.
    for r in &mut m.rows {
        match case_report(&r.dir) {
            Ok(index) => r.link = Some(relative_path(&out, &index)),
            Err(e) => eprintln!("kick report: {}: {e}", r.case()),
        }
    }
    std::fs::create_dir_all(&out).map_err(err)?;
    let mut page = Page::default();
    verdict(&m, &mut page);
    if !m.axes.is_empty() {
        crate::report_behaviours::behaviours(&m, &mut page);
        crate::report_ablation::ablation_table(&m, &mut page);
        crate::report_refinement::refinement_table(&m, &out, &mut page)?;
        crate::report_mixture::mixture_section(&m, &out, &mut page)?;
        heatmaps(&m, &out, &mut page)?;
        stability_map(&m, &out, &mut page)?;
    }
    speed_accuracy(&m, &out, &mut page)?;
    ensemble_table(&m, &mut page);
    case_table(&m, &mut page);
    let title = format!(
        "kick matrix report: {}",
        dir.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let index = out.join("index.html");
    write_atomic(&index, page.finish(&title).as_bytes()).map_err(err)?;
    Ok(index)
}

/// At most this many cases are named in one sentence of the verdict.
const NAMED: usize = 6;

/// "a (x), b (y) and 3 more" over the first `NAMED` items.
fn named_list(items: Vec<String>) -> String {
    let n = items.len();
    let mut shown: Vec<String> = items.into_iter().take(NAMED).collect();
    if n > NAMED {
        shown.push(format!("and {} more", n - NAMED));
    }
    shown.join(", ")
}

fn failed_none(rows: &[Row]) -> bool {
    rows.iter()
        .all(|r| !matches!(r.summary.status, Status::Failed | Status::BlewUp))
}

/// The page opens with what failed, what kicked and the best methods.
fn verdict(m: &Matrix, page: &mut Page) {
    let rows = &m.rows;
    page.begin_section("verdict");
    page.h2("Verdict");
    let count = |o: &str| rows.iter().filter(|r| r.outcome() == o).count();
    let kicked: Vec<&Row> = rows.iter().filter(|r| r.summary.kicked()).collect();
    page.p(&format!(
        "{} cases ran: {} survived without a kick, {} kicked at least once ({} of them then completed), {} blew up, {} failed.",
        rows.len(),
        count("completed"),
        kicked.len(),
        count("kicked"),
        count("blew_up"),
        count("failed")
    ));
    // What failed.
    let failed: Vec<String> = rows
        .iter()
        .filter(|r| r.summary.status == Status::Failed)
        .map(|r| format!("{} ({})", r.link_html(), escape(&r.summary.reason)))
        .collect();
    if !failed.is_empty() {
        page.p(&format!("<b>Failed to run</b>: {}.", named_list(failed)));
    }
    let mut blew: Vec<&Row> = rows
        .iter()
        .filter(|r| r.summary.status == Status::BlewUp)
        .collect();
    blew.sort_by(|a, b| a.t_end().total_cmp(&b.t_end()));
    if !blew.is_empty() {
        page.p(&format!(
            "<b>Blew up</b>, earliest first: {}.",
            named_list(
                blew.iter()
                    .map(|r| format!("{} at t = {:.3} s", r.link_html(), r.t_end()))
                    .collect()
            )
        ));
    }
    if failed_none(rows) {
        page.p("<b>No case failed or blew up.</b>");
    }
    // What kicked.
    if kicked.is_empty() {
        page.p("<b>No case kicked.</b>");
    } else {
        let first_by = |c: usize| rows.iter().filter(|r| r.class() == c).count();
        let mut by_time = kicked.clone();
        by_time.sort_by(|a, b| a.t_first_kick().total_cmp(&b.t_first_kick()));
        page.p(&format!(
            "<b>Kicked</b>: {} of {} cases; the first kick was an injection in {}, an inversion in {} and had the hallmark (the anomaly) in {}. Earliest first: {}.",
            kicked.len(),
            rows.len(),
            first_by(2),
            first_by(3),
            first_by(4),
            named_list(
                by_time
                    .iter()
                    .map(|r| format!("{} at t = {:.3} s", r.link_html(), r.t_first_kick()))
                    .collect()
            )
        ));
    }
    // The best methods (or cases, when no method key varies).
    let best = crate::report_ablation::best_methods(m, 3);
    if !best.is_empty() {
        let items: Vec<String> = best
            .iter()
            .map(|b| {
                format!(
                    "<b>{}</b> ({} of {} runs completed without a kick, median late departure {})",
                    escape(&b.label),
                    b.clean,
                    b.runs,
                    b.late.map_or("-".into(), short)
                )
            })
            .collect();
        page.p(&format!(
            "<b>Best methods</b> (most runs completed without a kick, then the lowest late hydrostatic departure): {}.",
            items.join("; ")
        ));
    }
    let mut ranked: Vec<&Row> = rows
        .iter()
        .filter(|r| r.summary.status == Status::Completed && r.hydro_late().is_finite())
        .collect();
    ranked.sort_by(|a, b| {
        (a.summary.kicked(), a.hydro_late())
            .partial_cmp(&(b.summary.kicked(), b.hydro_late()))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    if !ranked.is_empty() {
        page.p(&format!(
            "<b>Best cases</b> (completed, without a kick first, then closest to hydrostatic at the end, late rel. RMS): {}.",
            ranked
                .iter()
                .take(3)
                .map(|r| format!(
                    "{} ({}{})",
                    r.link_html(),
                    short(r.hydro_late()),
                    if r.summary.kicked() { ", kicked" } else { "" }
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    page.end_section();
}

/// Heatmap layout: x = K (or the first axis), one panel per viscosity, y = the other axes.
struct HeatLayout<'a> {
    m: &'a Matrix,
    x_axis: usize,
    panel_axis: Option<usize>,
    y_axes: Vec<usize>,
    x_cats: Vec<String>,
    y_cats: Vec<String>,
    p_cats: Vec<String>,
}

impl<'a> HeatLayout<'a> {
    fn new(m: &'a Matrix) -> Self {
        let x_axis = m.axis(".K").unwrap_or(0);
        let panel_axis = m.axis(".viscosity").filter(|&p| p != x_axis);
        let y_axes: Vec<usize> = (0..m.axes.len())
            .filter(|&k| k != x_axis && Some(k) != panel_axis)
            .collect();
        let mut layout = HeatLayout {
            m,
            x_axis,
            panel_axis,
            y_axes,
            x_cats: vec![],
            y_cats: vec![],
            p_cats: vec![String::new()],
        };
        layout.x_cats = layout.cats(|r| r.params[x_axis].clone());
        layout.y_cats = layout.cats(|r| layout.y_of(r));
        if let Some(p) = panel_axis {
            layout.p_cats = layout.cats(|r| r.params[p].clone());
        }
        layout
    }

    fn y_of(&self, r: &Row) -> String {
        self.y_axes
            .iter()
            .map(|&k| r.params[k].clone())
            .collect::<Vec<_>>()
            .join(" ")
    }

    fn cats(&self, f: impl Fn(&Row) -> String) -> Vec<String> {
        let mut v: Vec<String> = self
            .m
            .rows
            .iter()
            .map(f)
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        v.sort_by(by_value);
        v
    }

    fn y_label(&self) -> String {
        self.y_axes
            .iter()
            .map(|&k| self.m.axes[k].as_str())
            .collect::<Vec<_>>()
            .join(" / ")
    }

    /// One cell per case; `cell` sees every run of the case (one, or an ensemble).
    fn figure(
        &self,
        title: &str,
        key: HeatKey,
        cell: impl Fn(&[&Row]) -> (RGBColor, String),
    ) -> HeatmapFigure {
        let panels = self
            .p_cats
            .iter()
            .map(|p| {
                let mut groups: Vec<((usize, usize), Vec<&Row>)> = vec![];
                for r in self
                    .m
                    .rows
                    .iter()
                    .filter(|r| self.panel_axis.is_none_or(|a| &r.params[a] == p))
                {
                    let at = (
                        self.x_cats
                            .iter()
                            .position(|c| *c == r.params[self.x_axis])
                            .unwrap_or(0),
                        self.y_cats
                            .iter()
                            .position(|c| *c == self.y_of(r))
                            .unwrap_or(0),
                    );
                    match groups.iter_mut().find(|(g, _)| *g == at) {
                        Some((_, rows)) => rows.push(r),
                        None => groups.push((at, vec![r])),
                    }
                }
                HeatPanel {
                    title: match self.panel_axis {
                        Some(a) => format!("{} = {p}", self.m.axes[a]),
                        None => String::new(),
                    },
                    cells: groups
                        .iter()
                        .map(|((x, y), rows)| {
                            let (colour, text) = cell(rows);
                            HeatCell {
                                x: *x,
                                y: *y,
                                colour,
                                text,
                            }
                        })
                        .collect(),
                }
            })
            .collect();
        HeatmapFigure {
            title: title.into(),
            x_label: self.m.axes[self.x_axis].clone(),
            y_label: self.y_label(),
            x_cats: self.x_cats.clone(),
            y_cats: self.y_cats.clone(),
            panels,
            key,
        }
    }
}

/// The case's outcome: the most frequent among its runs (ties: the worse),
/// with the median first-kick and survival times, and their range over an ensemble.
fn outcome_cell(runs: &[&Row]) -> (RGBColor, String) {
    let count = |o: &str| runs.iter().filter(|r| r.outcome() == o).count();
    // CLASSES runs from best to worst and max_by_key keeps the last maximum.
    let class = (0..CLASSES.len())
        .max_by_key(|&c| runs.iter().filter(|r| r.class() == c).count())
        .expect("six classes");
    let kick = spread(runs.iter().map(|r| r.t_first_kick()));
    let blew = runs.iter().any(|r| r.outcome() == "blew_up");
    let end = spread(runs.iter().map(|r| r.t_end())).filter(|_| blew);
    let n = runs.len();
    let mut parts = vec![];
    // Median ± half range over an ensemble (the Ensembles table has min and max).
    if let Some(k) = kick {
        parts.push(format!("k {}", compact(k)));
    }
    if let Some(e) = end {
        parts.push(format!("x {}", compact(e)));
    }
    let text = if !parts.is_empty() {
        parts.join(" ")
    } else if count("failed") == n {
        "failed".into()
    } else {
        "ok".into()
    };
    (CLASSES[class].1, text)
}

fn heatmaps(m: &Matrix, out: &Path, page: &mut Page) -> Res {
    let layout = HeatLayout::new(m);
    let outcome = layout.figure(
        "Outcome by the cause of the first kick; time of first kick and blow-up (s)",
        HeatKey::Legend(CLASSES.iter().map(|c| (c.0.to_string(), c.1)).collect()),
        outcome_cell,
    );
    page.h2("Outcome");
    page.figure(
        &render(&outcome, out, "heatmap_outcome")?,
        "Colour: the cause of the first kick (a kick is an injection or an inversion; the anomaly is a kick with the hallmark), or how a run that never kicked ended; over an ensemble the most frequent class (ties: the worse). Text: k t = first kick at t (s), x t = blew up at t (s), the median ± half the range over an ensemble",
    );
    let hydro: Vec<f64> = m.rows.iter().map(|r| r.hydro_late()).collect();
    let scale = ColourScale::robust(&hydro, true);
    let hydro_map = layout.figure(
        "Late hydrostatic departure (relative RMS, last second of completed runs)",
        HeatKey::Bar(scale, "rel. RMS (log)".into()),
        |runs| match spread(runs.iter().map(|r| r.hydro_late()).filter(|h| *h > 0.0)) {
            Some((h, _, _)) => (scale.colour(h), short(h)),
            None => (RGBColor(220, 220, 220), "-".into()),
        },
    );
    page.figure(
        &render(&hydro_map, out, "heatmap_hydro")?,
        "Late hydrostatic departure (log colour scale)",
    );
    Ok(())
}

/// Survival time against K, one line per combination of the other axes.
fn stability_map(m: &Matrix, out: &Path, page: &mut Page) -> Res {
    let Some(kx) = m.axis(".K") else {
        return Ok(());
    };
    let short_key = |k: usize| m.axes[k].rsplit('.').next().unwrap_or(&m.axes[k]);
    let family = |r: &Row| {
        (0..m.axes.len())
            .filter(|&k| k != kx)
            .map(|k| format!("{}={}", short_key(k), r.params[k]))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let families: BTreeSet<String> = m.rows.iter().map(family).collect();
    // Per family and K: the median survival, and its range over an ensemble.
    let mut lines = vec![];
    let mut spreads = vec![];
    for f in &families {
        let mut by_k: Vec<(f64, Vec<f64>)> = vec![];
        for r in m.rows.iter().filter(|r| &family(r) == f) {
            let Ok(k) = r.params[kx].parse::<f64>() else {
                continue;
            };
            match by_k.iter_mut().find(|(x, _)| *x == k) {
                Some((_, v)) => v.push(r.t_end()),
                None => by_k.push((k, vec![r.t_end()])),
            }
        }
        by_k.sort_by(|a, b| a.0.total_cmp(&b.0));
        let stats: Vec<(f64, (f64, f64, f64), usize)> = by_k
            .iter()
            .filter_map(|(k, v)| Some((*k, spread(v.iter().copied())?, v.len())))
            .collect();
        let name = if f.is_empty() {
            "all".into()
        } else {
            f.clone()
        };
        lines.push((name, stats.iter().map(|(k, s, _)| (*k, s.0)).collect()));
        spreads.push(
            stats
                .iter()
                .filter(|(_, _, n)| *n > 1)
                .map(|(k, s, _)| (*k, s.1, s.2))
                .collect(),
        );
    }
    let fig = LinesFigure {
        spread: spreads,
        title: "Stability map: time survived (median; bars: ensemble range)".into(),
        x_label: format!("{} (Pa, log)", m.axes[kx]),
        y_label: "time survived (s)".into(),
        lines,
        x_log: true,
        y_max: m.rows.iter().map(|r| r.t_end()).fold(0.1, f64::max),
    };
    page.figure(
        &render(&fig, out, "stability")?,
        "Time survived against K, one line per combination of the other axes",
    );
    Ok(())
}

/// The accuracy figures the speed-accuracy front is drawn against: the late
/// hydrostatic departure always, the surge front's early error (shifted)
/// when the study tracks a front.
fn speed_accuracy(m: &Matrix, out: &Path, page: &mut Page) -> Res {
    page.h2("Speed against accuracy");
    let rows = &m.rows;
    pareto(
        m,
        out,
        page,
        (
            "speed_accuracy",
            "late hydrostatic rel. RMS",
            "late hydrostatic departure",
        ),
        Row::hydro_late_or_pre_failure,
    )?;
    let front = |r: &Row| Row::nan(r.summary.metrics.front_rms_error_early_shifted);
    if rows.iter().any(|r| front(r).is_finite()) {
        pareto(
            m,
            out,
            page,
            (
                "speed_accuracy_front",
                "surge front, early shifted RMS error (Z)",
                "the surge front's early error after the best time shift",
            ),
            front,
        )?;
    }
    Ok(())
}

/// Cost (wall seconds per simulated second) against `error`, one point per
/// case, with the Pareto front: completed cases when at least two completed;
/// otherwise every case that ran (a blown-up one's accuracy then over the
/// second before it blew up). `names`: file stem, axis label, caption.
fn pareto(
    m: &Matrix,
    out: &Path,
    page: &mut Page,
    names: (&str, &str, &str),
    error: impl Fn(&Row) -> f64,
) -> Res {
    let (stem, label, caption) = names;
    let rows = &m.rows;
    let point = |r: &Row| (r.case().to_string(), r.summary.wall_s / r.t_end(), error(r));
    let ran = |r: &&Row| r.summary.status != Status::Failed && r.t_end() > 0.0;
    let completed: Vec<_> = rows
        .iter()
        .filter(ran)
        .filter(|r| r.summary.status == Status::Completed)
        .map(point)
        .collect();
    let (points, which) = if completed.len() >= 2 {
        (completed, "completed cases")
    } else {
        (
            rows.iter().filter(ran).map(point).collect(),
            "all cases, blown-up ones over the second before failure; fewer than two completed",
        )
    };
    if points.len() < 2 {
        return Ok(());
    }
    let fig = ParetoFigure {
        title: format!("Speed against accuracy ({which})"),
        x_label: "wall seconds per simulated second".into(),
        y_label: label.into(),
        points,
    };
    page.figure(
        &render(&fig, out, stem)?,
        &format!("Cost against {caption}, Pareto front in red"),
    );
    cheapest_table(m, &fig.points, stem, label, page);
    Ok(())
}

/// The Pareto front as a table: for an error of at most each front point's,
/// that point is the cheapest case that ran.
fn cheapest_table(
    m: &Matrix,
    points: &[(String, f64, f64)],
    stem: &str,
    label: &str,
    page: &mut Page,
) {
    let front = cheapest_for_error(points);
    if front.is_empty() {
        return;
    }
    page.p(&format!(
        "The cheapest case for a stated {label}: for an error of at most the first column, no case that ran costs less than the one named (its name gives its parameters; the cost is as measured on the machine and under the load the matrix ran with)."
    ));
    let headers = [
        "error at most",
        "cheapest case",
        "wall s per simulated s",
        "M particle-steps/s",
    ]
    .map(String::from);
    let rows: Vec<(String, Vec<Cell>)> = front
        .iter()
        .filter_map(|&i| {
            let (case, cost, error) = &points[i];
            let row = m.rows.iter().find(|r| r.case() == case)?;
            let cells = vec![
                Cell::Num(format!("{error:.4}")),
                Cell::Text(row.link_html()),
                Cell::Num(format!("{cost:.3}")),
                Cell::Num(format!("{:.2}", row.summary.particle_steps_per_s / 1e6)),
            ];
            Some((String::new(), cells))
        })
        .collect();
    page.table(&format!("{stem}_cheapest"), &headers, &rows);
}

/// Indices of the Pareto front of (name, cost, error) points with positive
/// finite cost and error, cheapest first: each is the cheapest point whose
/// error is at most its own.
pub fn cheapest_for_error(points: &[(String, f64, f64)]) -> Vec<usize> {
    let usable: Vec<usize> = (0..points.len())
        .filter(|&i| {
            let (_, x, y) = points[i];
            x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite()
        })
        .collect();
    let xy: Vec<(f64, f64)> = usable.iter().map(|&i| (points[i].1, points[i].2)).collect();
    pareto_front(&xy).into_iter().map(|k| usable[k]).collect()
}

/// Per case of an ensemble: survival and first kick as median [min, max] over its runs.
fn ensemble_table(m: &Matrix, page: &mut Page) {
    let mut groups: Vec<(&Vec<String>, Vec<&Row>)> = vec![];
    for r in &m.rows {
        match groups.iter_mut().find(|(p, _)| **p == r.params) {
            Some((_, rows)) => rows.push(r),
            None => groups.push((&r.params, vec![r])),
        }
    }
    if groups.iter().all(|(_, rows)| rows.len() < 2) {
        return;
    }
    page.h2("Ensembles");
    page.p("Each case ran as several members whose initial positions differ by a seeded jitter of at most scene.jitter h (scene.seed per member): survival and first-kick time as median [min, max] over the members.");
    let mut headers = m.axes.clone();
    headers.extend(
        [
            "runs",
            "blew up",
            "kicked",
            "survived (s)",
            "first kick (s)",
        ]
        .map(String::from),
    );
    let text =
        |v: Option<(f64, f64, f64)>, n: usize| v.map_or("-".into(), |s| with_spread(s, n, 3));
    let rows: Vec<(String, Vec<Cell>)> = groups
        .iter()
        .map(|(params, runs)| {
            let n = runs.len();
            let kicked: Vec<f64> = runs
                .iter()
                .map(|r| r.t_first_kick())
                .filter(|t| t.is_finite())
                .collect();
            let mut cells: Vec<Cell> = params.iter().map(|p| Cell::Num(escape(p))).collect();
            cells.extend([
                Cell::Num(n.to_string()),
                Cell::Num(
                    runs.iter()
                        .filter(|r| r.outcome() == "blew_up")
                        .count()
                        .to_string(),
                ),
                Cell::Num(kicked.len().to_string()),
                Cell::Num(text(spread(runs.iter().map(|r| r.t_end())), n)),
                Cell::Num(text(spread(kicked.iter().copied()), kicked.len())),
            ]);
            (String::new(), cells)
        })
        .collect();
    page.table("ensembles", &headers, &rows);
}

fn case_table(m: &Matrix, page: &mut Page) {
    page.h2("Cases");
    let mut headers = vec!["case".to_string()];
    headers.extend(m.axes.iter().cloned());
    headers.extend(
        [
            "status",
            "t end (s)",
            "first kick (s)",
            "hydro late",
            "of it not explained by accelerations",
            "checkerboard late",
            "front error (Z)",
            "wall (s)",
        ]
        .map(String::from),
    );
    let cell = |v: Option<f64>| Cell::Num(v.filter(|v| v.is_finite()).map_or("-".into(), short));
    let rows: Vec<(String, Vec<Cell>)> = m
        .rows
        .iter()
        .map(|r| {
            let s = &r.summary;
            let mut cells = vec![Cell::Text(r.link_html())];
            cells.extend(r.params.iter().map(|p| Cell::Num(escape(p))));
            cells.extend([
                Cell::Text(s.status.as_str().into()),
                Cell::Num(format!("{:.3}", s.t_end)),
                cell(s.metrics.t_first_kick),
                cell(s.metrics.hydro_rel_rms_late),
                cell(s.metrics.hydro_unexplained_rel_rms_late),
                cell(s.metrics.checkerboard_late),
                cell(s.metrics.front_rms_error),
                Cell::Num(format!("{:.1}", s.wall_s)),
            ]);
            (format!("case-row {}", r.outcome()), cells)
        })
        .collect();
    page.table("cases", &headers, &rows);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_method_key_missing_from_an_older_summary_reads_as_its_default() {
        let defaults = method_defaults();
        let mut params = BTreeMap::new();
        params.insert("method.cfl".to_string(), serde_json::json!(0.4));
        let text = |k: &str| param_or_default(&params, k, &defaults);
        assert_eq!(text("method.cfl"), param_text(&serde_json::json!(0.4)));
        assert_eq!(text("method.xpic_order"), param_text(&serde_json::json!(2)));
        // A remedy missing from a summary was off: no setting to show.
        assert_eq!(text("method.shifting.time"), "");
        assert_eq!(text("method.transfer"), "flip");
        assert_eq!(text("materials.water.K"), "");
        assert_eq!(text("method.no_such_key"), "");
    }

    /// A Tait or linear material never reads "gamma 7": its `eos` axis
    /// carries its own parameter and its `gamma` does not apply.
    #[test]
    fn materials_are_labelled_by_their_own_eos_parameters() {
        let defaults = method_defaults();
        let params = |eos: Option<&str>, gamma: f64| {
            let mut p = BTreeMap::new();
            if let Some(eos) = eos {
                p.insert("materials.water.eos".to_string(), serde_json::json!(eos));
            }
            p.insert(
                "materials.water.gamma".to_string(),
                serde_json::json!(gamma),
            );
            p.insert("materials.water.K".to_string(), serde_json::json!(1.5e4));
            p
        };
        let text = |p: &BTreeMap<String, serde_json::Value>, k: &str| axis_text(p, k, &defaults);
        let tait = params(Some("tait"), 7.0);
        assert_eq!(text(&tait, "materials.water.eos"), "tait C=0.0894");
        assert_eq!(text(&tait, "materials.water.gamma"), "-");
        let power = params(Some("power"), 4.0);
        assert_eq!(text(&power, "materials.water.eos"), "power gamma=4");
        assert_eq!(text(&power, "materials.water.gamma"), "4");
        let default = params(None, 7.0);
        assert_eq!(text(&default, "materials.water.eos"), "power gamma=7");
        let linear = params(Some("linear"), 7.0);
        assert_eq!(text(&linear, "materials.water.eos"), "linear");
        assert_eq!(text(&linear, "materials.water.K"), "1.5e4");
    }
}
