//! The four behaviours the bug report saw in the original codes
//! (docs/physics.md section 3), each stated with the numbers of this matrix
//! that show or refute it. Survival counts a completed run as t_end.

use crate::report::data::{
    f64_column, median, read_parquet, BehaviourFigures, Matrix, ParamKey, RecordedRun, Row,
};
use crate::report::html::{Cell, Page};
use crate::report::plot::{err, short, Res};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use study::output::files::write_atomic;
use study::output::summary::{Status, Summary};

/// The behaviour record a matrix report writes (in its `report` folder):
/// every run the per-configuration table scored, one JSON line each, for
/// `kick report --behaviour-runs` once the run folders are gone.
pub const BEHAVIOUR_RECORD: &str = "behaviour_runs.jsonl";

/// The window in which the bug report saw the checkerboard appear (s).
pub const CHECKERBOARD_WINDOW: (f64, f64) = (0.01, 0.1);
/// Behaviour 3 as numbers: above this at K >= 1.5 MPa ...
pub const CHECKERBOARD_HIGH: f64 = 0.3;
/// ... and below this at the smallest K, over the same window.
pub const CHECKERBOARD_LOW: f64 = 0.1;

/// The first parameter of the run whose key `is`, as a number.
fn param(r: &Row, is: fn(&ParamKey) -> bool) -> Option<f64> {
    r.summary
        .params
        .iter()
        .find(|(k, _)| is(&ParamKey::parse(k)))
        .and_then(|(_, v)| v.as_f64())
}

/// Largest checkerboard index over `CHECKERBOARD_WINDOW`, of a case's timeseries.
fn early_checkerboard_of(df: &polars::prelude::DataFrame) -> Option<f64> {
    let (t, cb) = (f64_column(df, "t")?, f64_column(df, "checkerboard_means")?);
    let (lo, hi) = CHECKERBOARD_WINDOW;
    t.iter()
        .zip(&cb)
        .filter(|(t, c)| **t >= lo && **t <= hi && c.is_finite())
        .map(|(_, c)| *c)
        .reduce(f64::max)
}

fn verdict(shown: bool, partly: bool) -> &'static str {
    if shown {
        "<b>reproduced</b>"
    } else if partly {
        "<b>partly reproduced</b>"
    } else {
        "<b>not reproduced</b>"
    }
}

fn count(rows: &[&Row], keep: impl Fn(&Row) -> bool) -> usize {
    rows.iter().filter(|r| keep(r)).count()
}

fn median_of(values: impl Iterator<Item = f64>) -> String {
    let v: Vec<f64> = values.filter(|v| v.is_finite()).collect();
    median(&v).map_or("-".into(), short)
}

/// The rows at the smallest K and at the large ones (K >= 1.5 MPa, or the
/// largest K when none is that large).
struct ByK<'a> {
    k_min: f64,
    small: Vec<&'a Row>,
    large: Vec<&'a Row>,
}

impl<'a> ByK<'a> {
    /// None unless the matrix has at least two values of K.
    fn of(m: &'a Matrix) -> Option<Self> {
        let mut ks: Vec<f64> = m
            .rows
            .iter()
            .filter_map(|r| param(r, ParamKey::is_bulk_modulus))
            .collect();
        ks.sort_by(f64::total_cmp);
        ks.dedup();
        let (&k_min, &k_max) = (ks.first()?, ks.last()?);
        if ks.len() < 2 {
            return None;
        }
        let at = |keep: &dyn Fn(f64) -> bool| -> Vec<&Row> {
            m.rows
                .iter()
                .filter(|r| param(r, ParamKey::is_bulk_modulus).is_some_and(keep))
                .collect()
        };
        Some(ByK {
            k_min,
            small: at(&|k| k == k_min),
            large: at(&|k| k >= 1.5e6 || k == k_max),
        })
    }
}

/// The four behaviours, each with its numbers and whether this matrix
/// reproduces it (a matrix section: `matrix::MATRIX_SECTIONS`); nothing
/// on the page unless K takes at least two values (with the recorded
/// runs), but the record of the scored runs is written always.
pub fn behaviours(m: &Matrix, out: &Path, page: &mut Page) -> Res {
    let scored = ScoredRuns::of(m);
    write_record(&scored, &out.join(BEHAVIOUR_RECORD))?;
    let by_k = ByK::of(m);
    if by_k.is_none() && ByK::of(&scored.matrix).is_none() {
        return Ok(());
    }
    page.h2("The four behaviours of the bug report");
    if let Some(by_k) = by_k {
        page.p(&small_k_blows_up(&by_k, &scored.figures));
        page.p(&large_k_far_from_hydrostatic(&by_k, &scored.figures));
        page.p(&large_k_checkerboards(&by_k, &scored.figures));
        if let Some(text) = less_viscosity_less_stable(m, &scored.figures) {
            page.p(&text);
        }
    }
    behaviours_by_configuration(&scored, page);
    Ok(())
}

/// The runs the per-configuration table scores: this matrix's, and the
/// recorded runs of earlier matrices whose case it does not hold (its own
/// folder wins), with each run's timeseries figures by case.
pub struct ScoredRuns {
    pub matrix: Matrix,
    pub figures: BTreeMap<String, BehaviourFigures>,
    /// How many of them came from a record.
    pub recorded: usize,
    /// What may make the grouping wrong: recorded cases whose name a live
    /// case has with other parameters, keys only some runs carry.
    pub warnings: Vec<String>,
}

impl ScoredRuns {
    pub fn of(m: &Matrix) -> Self {
        let t_end = m.rows.iter().map(|r| r.summary.t_end).fold(0.0, f64::max);
        let mut figures = BTreeMap::new();
        let mut summaries = vec![];
        for r in &m.rows {
            if let Some(f) = measured_figures(r, t_end) {
                figures.insert(r.case().to_string(), f);
                summaries.push((r.dir.clone(), r.summary.clone()));
            }
        }
        let (mut recorded, mut clashes) = (0, vec![]);
        for run in &m.recorded_runs {
            let case = &run.summary.case;
            if let Some((_, live)) = summaries.iter().find(|(_, s)| &s.case == case) {
                if live.params != run.summary.params {
                    clashes.push(case.clone());
                }
            } else {
                figures.insert(case.clone(), run.figures.clone());
                summaries.push((PathBuf::new(), run.summary.clone()));
                recorded += 1;
            }
        }
        let mut warnings = vec![];
        if !clashes.is_empty() {
            warnings.push(format!(
                "{} recorded runs were left out for a live case of the same name with other parameters: {}.",
                clashes.len(),
                clashes.join(", ")
            ));
        }
        if let Some(w) = keys_some_lack(&summaries) {
            warnings.push(w);
        }
        ScoredRuns {
            matrix: Matrix::of(summaries),
            figures,
            recorded,
            warnings,
        }
    }
}

/// The parameters (other than the method's, which read as their default
/// when absent) that some runs carry and others lack, as a warning: an
/// older build did not write them, they read as empty there, and a
/// configuration may split in two rows.
fn keys_some_lack(summaries: &[(PathBuf, Summary)]) -> Option<String> {
    let mut seen: BTreeMap<&str, usize> = BTreeMap::new();
    for (_, s) in summaries {
        for k in s.params.keys() {
            *seen.entry(k.as_str()).or_default() += 1;
        }
    }
    let partial: Vec<&str> = seen
        .into_iter()
        .filter(|(k, n)| *n < summaries.len() && !k.starts_with("method."))
        .map(|(k, _)| k)
        .collect();
    (!partial.is_empty()).then(|| {
        format!(
            "Only some of the runs carry {} (written by builds apart): where absent it reads as empty, which may split a configuration into two rows.",
            partial.join(", ")
        )
    })
}

/// Writes `path`: one `RecordedRun` a line (events left out), in the
/// matrix's row order.
fn write_record(scored: &ScoredRuns, path: &Path) -> Res {
    let mut text = String::new();
    for r in &scored.matrix.rows {
        let Some(figures) = scored.figures.get(r.case()) else {
            continue;
        };
        if !figures.survived.is_finite() {
            continue;
        }
        let mut summary = r.summary.clone();
        summary.events.clear();
        let run = RecordedRun {
            summary,
            figures: figures.clone(),
        };
        text.push_str(&serde_json::to_string(&run).map_err(err)?);
        text.push('\n');
    }
    let named = |e: std::io::Error| format!("{}: {e}", path.display());
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(named)?;
    }
    write_atomic(path, text.as_bytes()).map_err(named)
}

/// Behaviour 1, small K: a kick that blows most particles out within a few steps.
fn small_k_blows_up(by_k: &ByK, figures: &BTreeMap<String, BehaviourFigures>) -> String {
    let ByK { k_min, small, .. } = by_k;
    let blown: Vec<&Row> = small
        .iter()
        .copied()
        .filter(|r| r.summary.status == Status::BlewUp)
        .collect();
    let steps: Vec<f64> = small
        .iter()
        .filter_map(|r| figures.get(r.case())?.blow_out_steps)
        .collect();
    let quick = steps.iter().filter(|s| **s <= BLOW_OUT_STEPS).count();
    let dropped = count(small, |r| r.summary.metrics.events_dropped > 0);
    format!(
        "1. Small K ({} Pa): a clean run ends in a kick that blows most particles out within a few steps. \
         {} of {} runs blew up (median at {} s). {} of {} runs lost half their particles within \
         {BLOW_OUT_STEPS} steps of the kick that began their blow-out (the last kick before {} % of the \
         particles were gone; median {} steps over the {} runs with such a kick that lost half); mass \
         lost when they stopped: median {}, particles escaped: median {}, inverted: median {}. \
         {dropped} of these runs dropped events past monitor.max_events, which may hide that kick. {}",
        short(*k_min),
        blown.len(),
        small.len(),
        median_of(blown.iter().map(|r| r.summary.t_end)),
        quick,
        small.len(),
        100.0 * BLOW_OUT_ONSET,
        median_of(steps.iter().copied()),
        steps.len(),
        median_of(blown.iter().map(|r| r.summary.metrics.losses.mass_lost_fraction)),
        median_of(blown.iter().map(|r| r.summary.metrics.losses.particles_escaped as f64)),
        median_of(blown.iter().map(|r| r.summary.metrics.losses.particles_inverted as f64)),
        verdict(
            2 * quick > small.len(),
            !blown.is_empty()
        )
    )
}

/// Whether a run survived to its end, as the per-configuration table
/// reads it (without losing `SURVIVAL_LOSS` of its mass: a run that does
/// not stop on lost mass completes emptied); without a timeseries, by its
/// status.
fn survived_to_end(r: &Row, figures: &BTreeMap<String, BehaviourFigures>) -> bool {
    figures
        .get(r.case())
        .map_or(r.summary.status == Status::Completed, |f| f.survived_to_end)
}

/// How long a run survived, as the per-configuration table reads it.
fn survived(r: &Row, figures: &BTreeMap<String, BehaviourFigures>) -> f64 {
    figures
        .get(r.case())
        .map_or(r.summary.t_end, |f| f.survived)
}

/// Behaviour 2: larger K survives but is far from hydrostatic.
fn large_k_far_from_hydrostatic(
    by_k: &ByK,
    figures: &BTreeMap<String, BehaviourFigures>,
) -> String {
    let large = &by_k.large;
    let survivors: Vec<&Row> = large
        .iter()
        .copied()
        .filter(|r| survived_to_end(r, figures))
        .collect();
    let late: Vec<f64> = survivors.iter().map(|r| r.hydro_late()).collect();
    let far = count(&survivors, |r| r.hydro_late() >= 10.0);
    format!(
        "2. Larger K (K &ge; {} Pa) survives to t_end with a pressure orders of magnitude off hydrostatic. \
         {} of {} runs survived to t_end (completed, with less than {} % of the mass lost); their late \
         hydrostatic departure (relative RMS over the last second): median {}, {} of them &ge; 10. {}",
        short(large.iter().filter_map(|r| param(r, ParamKey::is_bulk_modulus)).fold(f64::INFINITY, f64::min)),
        survivors.len(),
        large.len(),
        100.0 * SURVIVAL_LOSS,
        median_of(late.iter().copied()),
        far,
        verdict(
            !survivors.is_empty() && 2 * far > survivors.len(),
            !survivors.is_empty() && median(&late).is_some_and(|h| h >= 1.0)
        )
    )
}

/// Behaviour 3: larger K checkerboards immediately; the smallest K does not.
fn large_k_checkerboards(by_k: &ByK, figures: &BTreeMap<String, BehaviourFigures>) -> String {
    let early = |rows: &[&Row]| -> Vec<f64> {
        rows.iter()
            .filter_map(|r| figures.get(r.case())?.early_checkerboard)
            .collect()
    };
    let (cb_large, cb_small) = (early(&by_k.large), early(&by_k.small));
    let high = cb_large.iter().filter(|c| **c > CHECKERBOARD_HIGH).count();
    let low = cb_small.iter().filter(|c| **c < CHECKERBOARD_LOW).count();
    format!(
        "3. Larger K: the pressure checkerboards at once (t in {}-{} s). Largest checkerboard index \
         over that window: above {CHECKERBOARD_HIGH} in {high} of {} runs at K &ge; 1.5 MPa (median {}); \
         below {CHECKERBOARD_LOW} in {low} of {} runs at {} Pa (median {}). {}",
        CHECKERBOARD_WINDOW.0,
        CHECKERBOARD_WINDOW.1,
        cb_large.len(),
        median_of(cb_large.iter().copied()),
        cb_small.len(),
        short(by_k.k_min),
        median_of(cb_small.iter().copied()),
        verdict(
            2 * high > cb_large.len() && 2 * low > cb_small.len(),
            2 * high > cb_large.len() || 2 * low > cb_small.len()
        )
    )
}

/// Behaviour 4: less viscosity, less stable; every case paired with its
/// viscous twin (None without a viscosity axis).
fn less_viscosity_less_stable(
    m: &Matrix,
    figures: &BTreeMap<String, BehaviourFigures>,
) -> Option<String> {
    let mu_axis = m.axis(ParamKey::is_viscosity)?;
    let mut pairs: BTreeMap<Vec<String>, [Vec<f64>; 2]> = BTreeMap::new();
    for r in &m.rows {
        let Some(mu) = param(r, ParamKey::is_viscosity) else {
            continue;
        };
        let mut key = r.params.clone();
        key.remove(mu_axis);
        pairs.entry(key).or_default()[usize::from(mu > 0.0)].push(survived(r, figures));
    }
    let (mut shorter, mut longer, mut same) = (0, 0, 0);
    for [inviscid, viscous] in pairs.values() {
        let (Some(a), Some(b)) = (median(inviscid), median(viscous)) else {
            continue;
        };
        if a < 0.99 * b {
            shorter += 1;
        } else if a > 1.01 * b {
            longer += 1;
        } else {
            same += 1;
        }
    }
    let total = shorter + longer + same;
    Some(format!(
        "4. Less viscosity, less stable. Of {total} cases paired by everything but the viscosity, the \
         inviscid one survived a shorter time (until it lost {} % of its mass, else to its end; median \
         over its runs, 1 % margin) in {shorter}, longer in {longer}, as long in {same}. {}",
        100.0 * SURVIVAL_LOSS,
        verdict(2 * shorter > total, shorter > longer)
    ))
}

/// Behaviour 1 per run: half of the particles deleted within this many
/// steps of the kick that began the blow-out (the replica grid's measure).
pub const BLOW_OUT_STEPS: f64 = 100.0;
/// The blow-out begins when this share of the particles is deleted: a
/// lone deletion (a splash particle inverted at the front) is not one.
pub const BLOW_OUT_ONSET: f64 = 0.01;

/// The kick that began a run's blow-out: the last kick opened at or before
/// the first row where `BLOW_OUT_ONSET` of the particles are gone. Not
/// the first kick: under the calibrated detector a surge meeting the far
/// wall opens one at 0.2-0.3 s in runs that fail seconds later, and the
/// bug report's run "ends in" its kick. Its time and first step.
fn blow_out_kick(r: &Row, t: &[f64], lost: &[f64]) -> Option<(f64, u64)> {
    let n = r.summary.particles as f64;
    let onset = t
        .iter()
        .zip(lost)
        .find(|(_, l)| **l >= BLOW_OUT_ONSET * n)
        .map(|(t, _)| *t)?;
    r.summary
        .events
        .iter()
        .filter(|e| e.is_kick() && e.t <= onset)
        .max_by(|a, b| a.t.total_cmp(&b.t))
        .map(|e| (e.t, e.first_step))
}

/// Steps from the kick that began the blow-out to the first row where
/// half of the particles are gone, counted by the rows' step numbers
/// (not each row's span over its last step, which a step collapsing
/// within the row inflated without bound); None without that kick or
/// without losing half.
fn blow_out_steps(r: &Row, t: &[f64], step: &[f64], lost: &[f64]) -> Option<f64> {
    let (tk, kick_step) = blow_out_kick(r, t, lost)?;
    let n = r.summary.particles as f64;
    let i = (0..t.len()).find(|&i| lost[i] >= 0.5 * n)?;
    Some(if t[i] > tk {
        (step[i] - kick_step as f64).max(0.0)
    } else {
        0.0
    })
}

/// Behaviour 2 per run: a late hydrostatic departure of at least this.
pub const LATE_DEPARTURE: f64 = 1.0;
/// A run survives while it has lost less than this share of its mass (the
/// harness's own blow-up threshold, whatever `scene.lost_mass_limit` let
/// the run go on to).
pub const SURVIVAL_LOSS: f64 = 0.1;

/// One run's figures for the per-configuration table.
struct RunFigures {
    k: f64,
    viscous: bool,
    /// Half of its particles deleted within `BLOW_OUT_STEPS` of the kick
    /// that began its blow-out (`blow_out_kick`).
    blown_out: bool,
    /// Steps from that kick to half of the particles gone (`blow_out_steps`).
    blow_out_steps: Option<f64>,
    /// Time at which it had lost `SURVIVAL_LOSS` of its mass (else its end).
    survived: f64,
    /// Ran to t_end without losing `SURVIVAL_LOSS` of its mass.
    survived_to_end: bool,
    hydro_late: f64,
    early_checkerboard: Option<f64>,
}

/// What the table reads of a run's timeseries (None without one); the
/// survival is judged against the matrix's `t_end`.
fn measured_figures(r: &Row, t_end: f64) -> Option<BehaviourFigures> {
    let df = read_parquet(&r.dir.join("timeseries.parquet")).ok()?;
    let t = f64_column(&df, "t")?;
    let step = f64_column(&df, "step")?;
    let lost = f64_column(&df, "particles_lost")?;
    let mass_lost = f64_column(&df, "mass_lost_fraction")?;
    let loss_at = t
        .iter()
        .zip(&mass_lost)
        .find(|(_, m)| **m >= SURVIVAL_LOSS)
        .map(|(t, _)| *t);
    let end = r.summary.t_end;
    Some(BehaviourFigures {
        blow_out_steps: blow_out_steps(r, &t, &step, &lost),
        survived: loss_at.unwrap_or(end),
        survived_to_end: loss_at.is_none()
            && r.summary.status == Status::Completed
            && end >= t_end * (1.0 - 1e-9),
        early_checkerboard: early_checkerboard_of(&df),
    })
}

impl RunFigures {
    fn of(r: &Row, f: &BehaviourFigures) -> Option<Self> {
        Some(RunFigures {
            k: param(r, ParamKey::is_bulk_modulus)?,
            viscous: param(r, ParamKey::is_viscosity).is_some_and(|mu| mu > 0.0),
            blown_out: f.blow_out_steps.is_some_and(|s| s <= BLOW_OUT_STEPS),
            blow_out_steps: f.blow_out_steps,
            survived: f.survived,
            survived_to_end: f.survived_to_end,
            hydro_late: r.hydro_late(),
            early_checkerboard: f.early_checkerboard,
        })
    }
}

/// A configuration's label and its runs with their figures.
type Configuration<'a> = (String, Vec<(&'a Row, RunFigures)>);

/// A behaviour's score in one configuration: runs that show it of those it
/// concerns.
#[derive(Clone, Copy, Default)]
struct Score {
    shown: usize,
    of: usize,
}

impl Score {
    fn add(&mut self, shown: bool) {
        self.of += 1;
        self.shown += usize::from(shown);
    }
    fn holds(&self) -> bool {
        self.of > 0 && 2 * self.shown > self.of
    }
    fn share(&self) -> f64 {
        if self.of == 0 {
            0.0
        } else {
            self.shown as f64 / self.of as f64
        }
    }
    fn text(&self) -> String {
        let mark = if self.holds() { "yes" } else { "no" };
        format!("{mark} ({} of {})", self.shown, self.of)
    }
}

/// The four behaviours scored per configuration (every axis but K and the
/// viscosity, members pooled; a matrix section through `behaviours`):
/// (1) at the smallest K, half of the particles deleted within 100 steps
/// of the kick that began the blow-out (`blow_out_kick`); (2) at K >= 1.5 MPa, survival to t_end (less than
/// 10 % of the mass lost) with a late departure of at least 1; (3) the
/// cell-means checkerboard index above 0.3 within 0.1 s at K >= 1.5 MPa
/// and below 0.1 at the smallest K; (4) the inviscid run survives a
/// shorter time than its viscous twin in most pairs. A behaviour holds in
/// a configuration when most of the runs it concerns show it.
pub fn behaviours_by_configuration(scored: &ScoredRuns, page: &mut Page) {
    let m = &scored.matrix;
    let (Some(kx), Some(mux)) = (
        m.axis(ParamKey::is_bulk_modulus),
        m.axis(ParamKey::is_viscosity),
    ) else {
        return;
    };
    let Some((by_config, k_min)) = configurations(scored, kx, mux) else {
        return;
    };
    let mut rows = vec![];
    let mut best: Option<(usize, f64, String)> = None;
    for (name, runs) in by_config.values() {
        let (s, high, low) = score(runs, k_min, mux);
        let held = s.iter().filter(|x| x.holds()).count();
        let closeness = s.iter().map(Score::share).sum::<f64>();
        if best.as_ref().is_none_or(|b| (held, closeness) > (b.0, b.1)) {
            best = Some((held, closeness, name.clone()));
        }
        let steps = small_k_steps(runs, k_min);
        rows.push(score_row(name, &s, high, low, &steps));
    }
    let headers: Vec<String> = [
        "configuration",
        "1. half the particles deleted within 100 steps of the kick that began the blow-out (smallest K)",
        "2. survives to t_end with late departure ≥ 1 (K ≥ 1.5 MPa)",
        "3. cell-means checkerboard within 0.1 s",
        "4. inviscid survives shorter (pairs)",
        "behaviours shown",
    ]
    .map(String::from)
    .to_vec();
    page.p(&format!(
        "Per configuration (every axis but K and the viscosity; runs pooled). Survival: until {:.0} % of the mass is deleted. A behaviour is shown when most of the runs it concerns show it. {} of its {} runs are from behaviour records (<code>--behaviour-runs</code>), scored from their recorded figures; every run it scored is in <code>{BEHAVIOUR_RECORD}</code> beside this page.",
        100.0 * SURVIVAL_LOSS,
        scored.recorded,
        scored.figures.len()
    ));
    for w in &scored.warnings {
        page.p(&format!(
            "<b>Warning:</b> {}",
            crate::report::html::escape(w)
        ));
    }
    page.table("behaviours_by_configuration", &headers, &rows);
    if let Some((held, _, name)) = best {
        page.p(&format!(
            "Closest to the bug report: <b>{}</b> ({held} of 4 behaviours).",
            crate::report::html::escape(&name)
        ));
    }
}

/// The runs grouped by configuration (every axis but K and the viscosity,
/// labelled by the axes that name it), and the smallest K; None without
/// another axis.
fn configurations(
    scored: &ScoredRuns,
    kx: usize,
    mux: usize,
) -> Option<(BTreeMap<Vec<String>, Configuration<'_>>, f64)> {
    let m = &scored.matrix;
    let others: Vec<usize> = (0..m.axes.len()).filter(|&a| a != kx && a != mux).collect();
    if others.is_empty() {
        return None;
    }
    let k_min = m
        .rows
        .iter()
        .filter_map(|r| param(r, ParamKey::is_bulk_modulus))
        .fold(f64::INFINITY, f64::min);
    // A remedy's settings are axes of their own (`artificial_viscosity.linear`)
    // beside its switch: the label names the switch only, and only when on.
    let label_axes: Vec<usize> = others
        .iter()
        .copied()
        .filter(|&a| {
            let f = m.axes[a].field();
            !f.split_once('.')
                .is_some_and(|(head, _)| others.iter().any(|&b| m.axes[b].field() == head))
        })
        .collect();
    let config = |r: &Row| -> String {
        let parts: Vec<String> = label_axes
            .iter()
            .filter_map(|&a| {
                let (f, v) = (m.axes[a].field(), r.params[a].as_str());
                match v {
                    "" | "-" | "false" => None,
                    "true" => Some(f.to_string()),
                    _ => Some(format!("{f}={v}")),
                }
            })
            .collect();
        parts.join(" ")
    };
    // Grouped by every other axis; labelled by `config`.
    let full = |r: &Row| -> Vec<String> { others.iter().map(|&a| r.params[a].clone()).collect() };
    let mut by_config: BTreeMap<Vec<String>, Configuration> = BTreeMap::new();
    for r in &m.rows {
        if let Some(f) = scored
            .figures
            .get(r.case())
            .and_then(|f| RunFigures::of(r, f))
        {
            by_config
                .entry(full(r))
                .or_insert_with(|| (config(r), vec![]))
                .1
                .push((r, f));
        }
    }
    Some((by_config, k_min))
}

/// A configuration's scores of behaviours 1-4, and behaviour 3's two halves
/// (high at K >= 1.5 MPa, low at the smallest K).
fn score(runs: &[(&Row, RunFigures)], k_min: f64, mux: usize) -> ([Score; 4], Score, Score) {
    let mut s = [Score::default(); 4];
    for (_, f) in runs {
        if f.k == k_min {
            s[0].add(f.blown_out);
        }
        if f.k >= 1.5e6 {
            s[1].add(f.survived_to_end && f.hydro_late >= LATE_DEPARTURE);
        }
    }
    let (mut high, mut low) = (Score::default(), Score::default());
    for (_, f) in runs {
        match f.early_checkerboard {
            Some(c) if f.k >= 1.5e6 => high.add(c > CHECKERBOARD_HIGH),
            Some(c) if f.k == k_min => low.add(c < CHECKERBOARD_LOW),
            _ => {}
        }
    }
    s[2] = Score {
        shown: usize::from(high.holds() && low.holds()),
        of: 1,
    };
    // Pairs: the same run but for the viscosity (member by member).
    let twin_key = |r: &Row| {
        let mut k = r.params.clone();
        k.remove(mux);
        (k, r.summary.params.get("scene.seed").map(|v| v.to_string()))
    };
    let mut pairs: BTreeMap<_, [Option<f64>; 2]> = BTreeMap::new();
    for (r, f) in runs {
        pairs.entry(twin_key(r)).or_default()[usize::from(f.viscous)] = Some(f.survived);
    }
    for [inviscid, viscous] in pairs.values() {
        if let (Some(a), Some(b)) = (inviscid, viscous) {
            s[3].add(*a < 0.99 * b);
        }
    }
    (s, high, low)
}

/// A configuration's row of the table.
/// Behaviour 1's steps per run at the smallest K, for its cell: each
/// run's steps from its blow-out kick to half the particles gone, "-"
/// for a run with no such kick or that never lost half.
fn small_k_steps(runs: &[(&Row, RunFigures)], k_min: f64) -> String {
    let steps: Vec<String> = runs
        .iter()
        .filter(|(_, f)| f.k == k_min)
        .map(|(_, f)| f.blow_out_steps.map_or("-".into(), |s| format!("{s:.0}")))
        .collect();
    steps.join(", ")
}

fn score_row(
    name: &str,
    s: &[Score; 4],
    high: Score,
    low: Score,
    steps: &str,
) -> (String, Vec<Cell>) {
    let held = s.iter().filter(|x| x.holds()).count();
    let three = format!(
            "{} (&gt; {CHECKERBOARD_HIGH}: {} of {} at K &ge; 1.5 MPa; &lt; {CHECKERBOARD_LOW}: {} of {} at the smallest K)",
            if s[2].holds() { "yes" } else { "no" },
            high.shown,
            high.of,
            low.shown,
            low.of
        );
    (
        String::new(),
        vec![
            Cell::Text(crate::report::html::escape(name)),
            Cell::Num(format!("{}; steps: {steps}", s[0].text())),
            Cell::Num(s[1].text()),
            Cell::Num(three),
            Cell::Num(s[3].text()),
            Cell::Num(format!("{held} of 4")),
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use monitor::Cause;
    use study::output::summary::{sample_event, Metrics, Summary, SCHEMA_VERSION};

    /// A 1000-particle run with kicks at `kicks` (s).
    fn run_with_kicks(kicks: &[(f64, Cause)]) -> Row {
        let events = kicks
            .iter()
            .map(|&(t, cause)| {
                let mut e = sample_event();
                (e.t, e.cause) = (t, cause);
                // The rows' step: 1e-3 s a step.
                e.first_step = (t * 1e3).round() as u64;
                e
            })
            .collect();
        let summary = Summary {
            schema_version: SCHEMA_VERSION,
            case: "c".into(),
            params: Default::default(),
            status: Status::BlewUp,
            reason: String::new(),
            steps: 1000,
            t_end: 1.0,
            wall_s: 1.0,
            particles: 1000,
            particle_steps_per_s: 1.0,
            final_state_hash: "0".into(),
            events,
            metrics: Metrics::default(),
            phases: vec![],
        };
        Row::for_test(summary, vec![])
    }

    /// A recorded run of configuration `scheme` at (K, viscosity), member
    /// `seed`, that survived until `survived` (to the end when 5 s) with
    /// the early checkerboard `cb` and late departure 30.
    fn recorded(scheme: &str, k: f64, mu: f64, seed: u64, survived: f64, cb: f64) -> RecordedRun {
        let mut summary = run_with_kicks(&[]).summary;
        let k_text = if k < 1e6 { "K15kPa" } else { "K1.5MPa" };
        summary.case = format!("{k_text}_mu{mu}_{scheme}_e{seed}");
        summary.params = [
            ("materials.water.K", serde_json::json!(k)),
            ("materials.water.viscosity", serde_json::json!(mu)),
            ("method.scheme", serde_json::json!(scheme)),
            ("scene.seed", serde_json::json!(seed)),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        let completed = survived >= 5.0;
        summary.status = if completed {
            Status::Completed
        } else {
            Status::BlewUp
        };
        summary.t_end = survived;
        let late = completed.then_some(30.0);
        summary
            .metrics
            .figures
            .insert("hydro_rel_rms_late".into(), late);
        RecordedRun {
            summary,
            figures: BehaviourFigures {
                blow_out_steps: None,
                survived,
                survived_to_end: completed,
                early_checkerboard: Some(cb),
            },
        }
    }

    /// Two configurations over 2 K x 2 viscosities x 2 members: `musl`'s
    /// inviscid runs fail first and it checkerboards at 1.5 MPa (behaviours
    /// 3 and 4), `usl` survives far from hydrostatic at 1.5 MPa (2).
    fn recorded_matrix() -> Vec<RecordedRun> {
        let mut runs = vec![];
        for seed in 0..2 {
            for (k, mu) in [(1.5e4, 0.0), (1.5e4, 0.5), (1.5e6, 0.0), (1.5e6, 0.5)] {
                let high = k > 1e6;
                // A survival time whose shortest decimal needs all 17
                // digits: the record must read it back to the bit.
                let musl_end = if mu > 0.0 {
                    3.7407619232532596
                } else {
                    1.0 + seed as f64
                };
                let musl_cb = if high { 0.5 } else { 0.05 };
                runs.push(recorded("musl", k, mu, seed, musl_end, musl_cb));
                runs.push(recorded("usl", k, mu, seed, 5.0, 0.05));
            }
        }
        runs
    }

    /// The table scores recorded runs (no run folder left) by their
    /// figures, and the record it writes reads back as the same runs.
    #[test]
    fn recorded_runs_are_scored_without_their_folders_and_round_trip() {
        let runs = recorded_matrix();
        let m = Matrix {
            recorded_runs: runs.clone(),
            ..Matrix::of(vec![])
        };
        let scored = ScoredRuns::of(&m);
        assert_eq!((scored.recorded, scored.figures.len()), (16, 16));
        let mut page = Page::default();
        behaviours_by_configuration(&scored, &mut page);
        let html = page.finish("t");
        assert!(
            html.contains("Closest to the bug report: <b>scheme=musl</b> (2 of 4"),
            "{html}"
        );
        assert!(
            html.contains("yes (4 of 4)"),
            "usl survives at 1.5 MPa: {html}"
        );
        assert!(
            html.contains("16 runs are from behaviour records"),
            "{html}"
        );
        let path = std::env::temp_dir().join(format!("kick-record-{}.jsonl", std::process::id()));
        write_record(&scored, &path).unwrap();
        let mut back = crate::report::data::read_recorded_runs(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        let mut expected = runs;
        expected.sort_by(|a, b| a.summary.case.cmp(&b.summary.case));
        back.sort_by(|a, b| a.summary.case.cmp(&b.summary.case));
        assert_eq!(back, expected);
    }

    /// Runs that complete emptied (a run that does not stop on lost mass)
    /// neither survive for behaviour 2 nor tie for behaviour 4: the
    /// paragraphs read survival as the per-configuration table does.
    #[test]
    fn runs_that_complete_emptied_are_read_by_their_loss() {
        let mut figures = BTreeMap::new();
        let summaries: Vec<(PathBuf, Summary)> = recorded_matrix()
            .into_iter()
            .filter(|r| r.summary.case.contains("_usl_"))
            .map(|mut r| {
                let inviscid = r.summary.case.contains("mu0_");
                r.figures.survived = if inviscid { 1.0 } else { 2.0 };
                r.figures.survived_to_end = false;
                figures.insert(r.summary.case.clone(), r.figures);
                (PathBuf::new(), r.summary)
            })
            .collect();
        let m = Matrix::of(summaries);
        assert!(m.rows.iter().all(|r| r.summary.status == Status::Completed));
        let by_k = ByK::of(&m).unwrap();
        let two = large_k_far_from_hydrostatic(&by_k, &figures);
        assert!(two.contains("0 of 4 runs survived to t_end"), "{two}");
        let four = less_viscosity_less_stable(&m, &figures).unwrap();
        assert!(four.contains("shorter time"), "{four}");
        assert!(four.contains(") in 2, longer in 0, as long in 0"), "{four}");
        // Without their figures, the statuses decide, as before.
        let none = BTreeMap::new();
        let two = large_k_far_from_hydrostatic(&by_k, &none);
        assert!(two.contains("4 of 4 runs survived to t_end"), "{two}");
        let four = less_viscosity_less_stable(&m, &none).unwrap();
        assert!(four.contains("as long in 2"), "{four}");
    }

    /// A case recorded twice counts once; with other parameters the second
    /// is left out with a warning, and a key only some runs carry is named.
    #[test]
    fn a_case_recorded_twice_counts_once_and_mismatches_are_named() {
        let mut runs = recorded_matrix();
        runs.push(runs[0].clone());
        let mut other = runs[1].clone();
        other
            .summary
            .params
            .insert("method.cfl".into(), serde_json::json!(0.4));
        runs.push(other);
        runs[2]
            .summary
            .params
            .insert("scene.on_nonfinite".into(), serde_json::json!("stop"));
        let m = Matrix {
            recorded_runs: runs,
            ..Matrix::of(vec![])
        };
        let scored = ScoredRuns::of(&m);
        assert_eq!((scored.recorded, scored.matrix.rows.len()), (16, 16));
        assert_eq!(scored.warnings.len(), 2, "{:?}", scored.warnings);
        assert!(
            scored.warnings[0].starts_with("1 recorded runs"),
            "{:?}",
            scored.warnings
        );
        assert!(
            scored.warnings[1].contains("scene.on_nonfinite"),
            "{:?}",
            scored.warnings
        );
    }

    /// A record line that is not a run names the file and the line.
    #[test]
    fn a_bad_record_line_names_its_file_and_line() {
        let path =
            std::env::temp_dir().join(format!("kick-bad-record-{}.jsonl", std::process::id()));
        let good = serde_json::to_string(&recorded("usl", 1.5e4, 0.0, 0, 5.0, 0.05)).unwrap();
        std::fs::write(&path, format!("{good}\n{{\"summary\": 1}}\n")).unwrap();
        let e = crate::report::data::read_recorded_runs(&path).unwrap_err();
        let _ = std::fs::remove_file(&path);
        assert!(
            e.contains(&path.display().to_string()) && e.contains("line 2"),
            "{e}"
        );
    }

    /// Rows every 0.01 s at dt = 1e-3 s (10 steps a row; the rows' step
    /// numbers): one particle deleted at 0.3 s (a lone splash), 50 by
    /// 0.6 s, 600 by 0.65 s.
    fn blow_out_rows() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..=70).map(|i| 0.01 * i as f64).collect();
        let lost = t
            .iter()
            .map(|&t| match t {
                t if t >= 0.645 => 600.0,
                t if t >= 0.595 => 50.0,
                t if t >= 0.295 => 1.0,
                _ => 0.0,
            })
            .collect();
        let step = t.iter().map(|t| (t * 1e3).round()).collect();
        (t, step, lost)
    }

    /// The blow-out is timed from the last kick before 1 % of the particles
    /// are gone, not from an early one: the early wall kick at 0.2 s is
    /// 450 steps before half are gone, the kick at 0.58 s 70.
    #[test]
    fn the_blow_out_is_timed_from_the_last_kick_before_it_began() {
        let (t, step, lost) = blow_out_rows();
        let early_and_late = run_with_kicks(&[(0.2, Cause::Jump), (0.58, Cause::Injection)]);
        assert_eq!(blow_out_kick(&early_and_late, &t, &lost), Some((0.58, 580)));
        let steps = blow_out_steps(&early_and_late, &t, &step, &lost).unwrap();
        assert!((steps - 70.0).abs() < 1e-6, "{steps}");
        // Only the early kick: the same loss is 450 steps after it.
        let early = run_with_kicks(&[(0.2, Cause::Jump)]);
        let steps = blow_out_steps(&early, &t, &step, &lost).unwrap();
        assert!((steps - 450.0).abs() < 1e-6, "{steps}");
        assert!(steps > BLOW_OUT_STEPS);
        // A kick after the blow-out began, or an event that is not a kick,
        // does not anchor it.
        let after = run_with_kicks(&[(0.62, Cause::Jump), (0.5, Cause::Impact)]);
        assert_eq!(blow_out_kick(&after, &t, &lost), None);
        // A run that never loses half has no blow-out time.
        let (t65, step65) = (&t[..65], &step[..65]);
        assert_eq!(
            blow_out_steps(&early_and_late, t65, step65, &lost[..65]),
            None
        );
        // The step collapsing within the last row (12 steps in it, not 10)
        // counts those steps, whatever the step it ended on.
        let mut collapsed = step.clone();
        for s in collapsed.iter_mut().skip(65) {
            *s += 2.0;
        }
        let steps = blow_out_steps(&early_and_late, &t, &collapsed, &lost).unwrap();
        assert!((steps - 72.0).abs() < 1e-6, "{steps}");
    }
}
