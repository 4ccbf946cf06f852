//! `kick calibrate`: the detector's sensitivity measured with planted kicks
//! of known size (docs/usage.md, "Calibrating the detector"). Each case of
//! the study runs clean (its twin, a matrix case with its own folder) and
//! is checkpointed at the plant time; planted runs restart from that
//! checkpoint with one patch per placement (`[[calibration.patch]]`, well
//! apart, each its own speed) and are judged over the window after it.
//! A patch is found when an event that is not physics (any cause but
//! `impact`) opens within `merge_cells` of its cells inside the window, and
//! the twin has no event of that kind there then. With `bisect`, each
//! placement's smallest speed found is bisected (geometric means) until
//! the bracket's ratio is at most `ratio`; with `dv`, each speed is
//! planted once. The detection table (`detection.{parquet,csv,json}`)
//! gives per case, placement and size the smallest speed found, the
//! largest missed, the delay to detection, and the kicks away from the
//! patches (false alarms) in the twin and in the planted runs.

use crate::output::files::write_atomic;
use crate::output::summary::Summary;
use crate::output::tables;
use crate::run::case::{panic_message, progress_style, watches, with_threads};
use crate::run::matrix::{each_in_parallel, run_matrix, MatrixOptions};
use crate::run::probes::plant_checkpoint::PLANT_CHECKPOINT;
use crate::run::{Rows, RunOptions, Runner, Stepper, Watch};
use crate::study_file::calibration::{CalibrationSpec, PatchSpec};
use crate::study_file::{Case, Study};
use indicatif::{ProgressBar, ProgressStyle};
use monitor::{Cause, CellRange, Event, Geometry};
use polars::prelude::*;
use serde::{Deserialize, Serialize};
use solver::{Perturb, Planted, Solver, Vec2};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

pub mod common_state;
mod placement;
mod prediction;

pub struct CalibrateOptions {
    pub out: PathBuf,
    pub jobs: usize,
    pub threads_per_case: usize,
    /// Keep the twins already run in OUT.
    pub resume: bool,
    pub progress: bool,
}

/// One row of the detection table: a case, a placement and a patch size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DetectionRow {
    pub case: String,
    /// The twin's time at its checkpoint: the patches go in the step from it (s).
    pub t_plant_s: f64,
    pub place: String,
    pub cells: usize,
    /// The smallest speed found (m/s; None: none planted was) ...
    pub dv_found: Option<f64>,
    /// ... and the largest missed (None: none planted was).
    pub dv_missed: Option<f64>,
    /// From the plant to the opening of the event that found `dv_found` (s).
    pub delay_s: Option<f64>,
    /// That event's cause.
    pub cause: Option<String>,
    /// Planted runs of this row's case and size.
    pub runs: usize,
    /// False when no patch qualified for the placement at the plant time.
    pub placed: bool,
    /// The twin logged an event of its own near the patch in the window: no
    /// planted speed can be told from it there, so the site is judged at no
    /// speed (it is neither found nor missed).
    #[serde(default)]
    pub masked: bool,
    /// The index (in `[[calibration.patch]]` order) of an earlier placement
    /// whose patch this one resolved to, or lay within `merge_cells` of, at
    /// the plant: not planted (two patches there would add their speeds and
    /// share every event), `placed` false.
    #[serde(default)]
    pub shares: Option<usize>,
    /// The patch as placed ([x0, y0, x1, y1], m; the same at every speed:
    /// the placement reads the state at the plant) and the step it went in.
    pub region: Option<[f64; 4]>,
    pub step: Option<u64>,
    /// The particles the patch moved (a patch of fewer than
    /// `monitor.min_cluster_particles` is no velocity-jump event).
    #[serde(default)]
    pub particles: Option<usize>,
    /// The smallest speed the jump rule should find there, from the twin's
    /// own step after the plant (`prediction`; None: fewer calm particles
    /// than `monitor.min_cluster_particles` in a judged ring).
    #[serde(default)]
    pub predicted_dv: Option<f64>,
    /// Kicks (events not `impact`) the twin logged over its whole run ...
    pub twin_kicks: usize,
    /// ... and the planted runs away from every patch, that the twin does
    /// not have there then.
    pub false_alarms: usize,
}

/// What `detection.json` holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Detection {
    pub spec: CalibrationSpec,
    /// Wall time of the twins and of the planted runs (s).
    pub twins_wall_s: f64,
    pub planted_wall_s: f64,
    pub rows: Vec<DetectionRow>,
}

impl Detection {
    pub const FILE: &'static str = "detection.json";

    pub fn read(dir: &Path) -> Option<Detection> {
        let bytes = std::fs::read(dir.join(Self::FILE)).ok()?;
        serde_json::from_slice(&bytes).ok()
    }
}

/// Runs the twins, then the planted runs; writes the detection table.
pub fn calibrate(study: &Study, opts: &CalibrateOptions) -> std::io::Result<Detection> {
    let spec = study.calibration.clone().ok_or_else(|| {
        std::io::Error::other(format!("{}: no [calibration] table", study.file.display()))
    })?;
    let started = Instant::now();
    let matrix = MatrixOptions {
        out: opts.out.clone(),
        jobs: opts.jobs,
        shard: None,
        only: vec![],
        resume: opts.resume,
        csv: false,
        threads_per_case: opts.threads_per_case,
        progress: opts.progress,
        plant_checkpoint: Some(spec.plant_t),
        recorded: vec![],
    };
    if spec.common_state.is_some() {
        common_state::run_twins(study, &spec, opts)?;
    } else {
        run_matrix(study, &matrix)?;
    }
    let twins_wall_s = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let tasks: Vec<(&Case, usize)> = study
        .cases
        .iter()
        .flat_map(|c| spec.sizes.iter().map(move |&s| (c, s)))
        .collect();
    let rows = run_tasks(&tasks, &spec, opts)?;
    let detection = Detection {
        spec,
        twins_wall_s,
        planted_wall_s: started.elapsed().as_secs_f64(),
        rows,
    };
    write_detection(&detection, &opts.out)?;
    Ok(detection)
}

/// The tasks on `opts.jobs` workers; rows in the tasks' order.
fn run_tasks(
    tasks: &[(&Case, usize)],
    spec: &CalibrationSpec,
    opts: &CalibrateOptions,
) -> std::io::Result<Vec<DetectionRow>> {
    let bar = if opts.progress {
        ProgressBar::new(tasks.len() as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{prefix:>24} [{elapsed_precise}] {wide_bar} {pos}/{len} {msg}",
        )
        .unwrap_or_else(|_| progress_style()),
    );
    bar.set_prefix("planted runs");
    let done = Mutex::new(Vec::<(usize, Result<Vec<DetectionRow>, String>)>::new());
    each_in_parallel(tasks, opts.jobs, |k, &(case, size)| {
        let dir = opts.out.join(&case.name);
        let rows = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            with_threads(Some(opts.threads_per_case), || {
                Ok(calibrate_case(case, &dir, size, spec))
            })
            .map_err(|e| e.to_string())
            .and_then(|r| r)
        }))
        .unwrap_or_else(|p| Err(format!("panic: {}", panic_message(p))));
        bar.set_message(format!("last: {} {size}x{size}", case.name));
        done.lock().expect("not poisoned").push((k, rows));
        bar.inc(1);
    });
    bar.finish_and_clear();
    let mut done = done.into_inner().expect("not poisoned");
    done.sort_by_key(|(k, _)| *k);
    let mut rows = vec![];
    for (k, r) in done {
        match r {
            Ok(r) => rows.extend(r),
            Err(why) => {
                let (case, size) = tasks[k];
                eprintln!("kick calibrate: {} {size}x{size}: {why}", case.name);
            }
        }
    }
    Ok(rows)
}

/// The twin's restart point and what it logged.
struct Twin {
    checkpoint: Vec<u8>,
    t_plant: f64,
    events: Vec<Event>,
}

impl Twin {
    fn read(dir: &Path) -> Result<Twin, String> {
        let summary = Summary::read(dir)?;
        let path = dir.join(PLANT_CHECKPOINT);
        let checkpoint = std::fs::read(&path).map_err(|e| {
            format!(
                "{}: {e} (the twin ended {} at t = {:.4} s: {})",
                path.display(),
                summary.status.as_str(),
                summary.t_end,
                summary.reason
            )
        })?;
        let (_, t_plant) = crate::run::checkpoint::clock(&checkpoint)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(Twin {
            checkpoint,
            t_plant,
            events: summary.events,
        })
    }

    fn kicks(&self) -> usize {
        self.events
            .iter()
            .filter(|e| e.cause != Cause::Impact)
            .count()
    }
}

/// A solver of `cfg` and the case's monitors holding `checkpoint`'s state
/// (the checkpoint replaces the state: no relaxation to equilibrium first).
fn restored(
    case: &Case,
    mut cfg: solver::SolverConfig,
    checkpoint: &[u8],
) -> Result<(Solver, Vec<Watch>), String> {
    cfg.scene.initial = solver::InitialState::ZeroStress;
    let mut solver = Solver::new(cfg).map_err(|e| format!("setup: {e}"))?;
    let mut watches = watches(&solver, case);
    solver
        .load(checkpoint, &mut watches)
        .map_err(|e| e.to_string())?;
    Ok((solver, watches))
}

/// The twin restored with `perturb` and one step taken from its checkpoint
/// (None: the twin ended there).
fn stepped_once(
    case: &Case,
    twin: &Twin,
    perturb: Vec<Perturb>,
) -> Result<Option<(Solver, Vec<Watch>)>, String> {
    let mut cfg = case.solver.clone();
    cfg.perturb = perturb;
    let (mut solver, watches) = restored(case, cfg, &twin.checkpoint)?;
    if solver.finished() {
        return Ok(None);
    }
    Stepper::advance(&mut solver)?;
    Ok(Some((solver, watches)))
}

/// Where a placement stands: its bracket, and the event that found its
/// smallest speed.
#[derive(Clone, Debug, Default)]
struct Bracket {
    found: Option<f64>,
    missed: Option<f64>,
    delay: Option<f64>,
    cause: Option<Cause>,
    placed: bool,
    masked: bool,
    /// The earlier placement whose patch this one resolves to (or lies
    /// beside): it is not planted, since both would act as one.
    shares: Option<usize>,
    region: Option<[f64; 4]>,
    step: Option<u64>,
    particles: Option<usize>,
    /// The plant's unit direction, and the speed `prediction` expects.
    direction: Option<[f64; 2]>,
    predicted: Option<f64>,
}

/// One case and patch size: its placements' rows (one per placement when
/// bisecting, one per placement and speed otherwise).
fn calibrate_case(
    case: &Case,
    dir: &Path,
    size: usize,
    spec: &CalibrationSpec,
) -> Result<Vec<DetectionRow>, String> {
    let twin = Twin::read(dir)?;
    let fresh = || {
        vec![
            Bracket {
                placed: true,
                ..Default::default()
            };
            spec.patch.len()
        ]
    };
    let shared = placement::shared(case, &twin, spec, size)?;
    let fresh = || {
        let mut b = fresh();
        for (b, &s) in b.iter_mut().zip(&shared) {
            b.shares = s;
            b.placed = s.is_none();
        }
        b
    };
    let Some(range) = spec.bisect else {
        let mut rows = vec![];
        for &dv in &spec.dv {
            let mut brackets = fresh();
            let speeds: Vec<Option<f64>> =
                shared.iter().map(|s| s.is_none().then_some(dv)).collect();
            let alarms = plant_and_record(case, &twin, spec, size, &speeds, &mut brackets)?;
            predict(case, &twin, spec, &mut brackets);
            rows.extend(rows_of(case, spec, size, &brackets, &twin, (1, alarms)));
        }
        return Ok(rows);
    };
    let mut brackets = fresh();
    let (mut runs, mut alarms) = (0, 0);
    while let Some(speeds) = next_speeds(range, spec.ratio, &brackets) {
        alarms += plant_and_record(case, &twin, spec, size, &speeds, &mut brackets)?;
        runs += 1;
        if runs >= 64 {
            return Err("more than 64 planted runs: the bracket does not close".into());
        }
    }
    predict(case, &twin, spec, &mut brackets);
    Ok(rows_of(case, spec, size, &brackets, &twin, (runs, alarms)))
}

/// The brackets' predicted speeds; a failure leaves them unset (the
/// bisection's results stand). A push spread over a duration has none: the
/// prediction reads one step.
fn predict(case: &Case, twin: &Twin, spec: &CalibrationSpec, brackets: &mut [Bracket]) {
    if spec.duration.is_some() {
        return;
    }
    if let Err(e) = prediction::fill(case, twin, brackets) {
        eprintln!("kick calibrate: {}: no prediction: {e}", case.name);
    }
}

/// One planted run, its verdicts recorded in the brackets; its false alarms.
fn plant_and_record(
    case: &Case,
    twin: &Twin,
    spec: &CalibrationSpec,
    size: usize,
    speeds: &[Option<f64>],
    brackets: &mut [Bracket],
) -> Result<usize, String> {
    let judged = planted_run(case, twin, spec, size, speeds)?;
    for (k, verdict) in judged.patches.into_iter().enumerate() {
        if let Some(dv) = speeds[k] {
            record(&mut brackets[k], dv, verdict);
        }
    }
    Ok(judged.false_alarms)
}

/// A patch's verdict in one planted run.
#[derive(Clone, Copy, Debug)]
enum Verdict {
    NotPlaced,
    /// The twin logged an event near the patch in the window.
    Masked,
    Missed,
    Found {
        delay: f64,
        cause: Cause,
    },
}

/// Where a patch went: its region, step, particle count and dv, when it was placed.
type Placed = Option<([f64; 4], u64, usize, [f64; 2])>;

fn record(b: &mut Bracket, dv: f64, (verdict, placed): (Verdict, Placed)) {
    if let Some((region, step, particles, dv)) = placed {
        b.region = Some(region);
        b.step = Some(step);
        b.particles = Some(particles);
        let norm = dv[0].hypot(dv[1]);
        if norm > 0.0 {
            b.direction = Some([dv[0] / norm, dv[1] / norm]);
        }
    }
    match verdict {
        Verdict::NotPlaced => b.placed = false,
        Verdict::Masked => b.masked = true,
        Verdict::Missed => b.missed = Some(b.missed.map_or(dv, |m: f64| m.max(dv))),
        Verdict::Found { delay, cause } => {
            if b.found.is_none_or(|f| dv < f) {
                b.found = Some(dv);
                b.delay = Some(delay);
                b.cause = Some(cause);
            }
        }
    }
}

/// The speed each placement is planted at next (None: it is settled):
/// the bracket's top, then its bottom, then geometric means; None when
/// every placement is settled.
fn next_speeds([lo, hi]: [f64; 2], ratio: f64, brackets: &[Bracket]) -> Option<Vec<Option<f64>>> {
    let speeds: Vec<Option<f64>> = brackets
        .iter()
        .map(|b| match (b.placed && !b.masked, b.found, b.missed) {
            (false, _, _) => None,
            (true, None, None) => Some(hi),
            (true, Some(f), None) if f > lo => Some(lo),
            (true, Some(f), Some(m)) if f / m > ratio => Some((f * m).sqrt()),
            _ => None,
        })
        .collect();
    speeds.iter().any(Option::is_some).then_some(speeds)
}

fn rows_of(
    case: &Case,
    spec: &CalibrationSpec,
    size: usize,
    brackets: &[Bracket],
    twin: &Twin,
    (runs, false_alarms): (usize, usize),
) -> Vec<DetectionRow> {
    spec.patch
        .iter()
        .zip(brackets)
        .map(|(p, b)| DetectionRow {
            case: case.name.clone(),
            t_plant_s: twin.t_plant,
            place: place_name(p),
            cells: size,
            dv_found: b.found,
            dv_missed: b.missed,
            delay_s: b.delay,
            cause: b.cause.map(|c| c.name().to_string()),
            runs,
            placed: b.placed,
            masked: b.masked,
            shares: b.shares,
            region: b.region,
            step: b.step,
            particles: b.particles,
            predicted_dv: b.predicted,
            twin_kicks: twin.kicks(),
            false_alarms,
        })
        .collect()
}

fn place_name(p: &PatchSpec) -> String {
    match p.place {
        solver::Placement::Bulk => "bulk",
        solver::Placement::Surface => "surface",
        solver::Placement::Wall => "wall",
    }
    .to_string()
}

/// One planted run's verdicts, per placement, and its false alarms.
struct Judged {
    patches: Vec<(Verdict, Placed)>,
    false_alarms: usize,
}

/// Placement k's patch, planted at `speed` in the step after `t`.
fn perturb_of(
    (case, spec): (&Case, &CalibrationSpec),
    k: usize,
    t: f64,
    size: usize,
    speed: Option<f64>,
) -> Perturb {
    let least = spec
        .min_particles
        .unwrap_or(case.monitor.min_cluster_particles);
    Perturb {
        step: None,
        t: Some(t),
        region: None,
        place: Some(spec.patch[k].place),
        cells: size,
        near: Some(spec.patch[k].near),
        min_particles: Some(least.max(1)),
        dv: None,
        speed,
        direction: Some(spec.direction),
        duration: spec.duration,
        j_scale: None,
        dx: None,
    }
}

/// Restarts the twin at the plant with a patch per placement that has a
/// speed, runs the window and judges it.
fn planted_run(
    case: &Case,
    twin: &Twin,
    spec: &CalibrationSpec,
    size: usize,
    speeds: &[Option<f64>],
) -> Result<Judged, String> {
    let mut cfg = case.solver.clone();
    let entries: Vec<usize> = (0..speeds.len()).filter(|&k| speeds[k].is_some()).collect();
    cfg.perturb = entries
        .iter()
        .map(|&k| perturb_of((case, spec), k, twin.t_plant, size, speeds[k]))
        .collect();
    cfg.scene.t_end = twin.t_plant + spec.window;
    let (solver, watches) = restored(case, cfg, &twin.checkpoint)?;
    let opts = RunOptions::new(None, Rows::spread_in_time(10, twin.t_plant + spec.window));
    let mut runner = Runner::new(solver, watches, opts);
    let simulated = runner.run().map_err(|e| e.to_string())?;
    let (solver, _) = runner.into_parts();
    let geom = Geometry::from_scene(&case.solver.scene);
    let planted: Vec<(usize, CellRange, Placed)> = solver
        .planted()
        .iter()
        .map(|p: &Planted| {
            let placed = Some((p.region, p.step, p.particles, p.dv));
            (entries[p.entry], cells_of(&geom, p.region), placed)
        })
        .collect();
    let reach = case.monitor.merge_cells;
    let merge = (reach, case.monitor.merge_seconds);
    let window = (twin.t_plant, twin.t_plant + spec.window);
    let patches = (0..speeds.len())
        .map(|k| match planted.iter().find(|(e, ..)| *e == k) {
            _ if speeds[k].is_none() => (Verdict::Missed, None),
            None => (Verdict::NotPlaced, None),
            Some(&(_, cells, placed)) if twin_kicked_near(twin, cells, merge, window) => {
                (Verdict::Masked, placed)
            }
            Some(&(_, cells, placed)) => {
                (find(&simulated.events, twin, cells, reach, window), placed)
            }
        })
        .collect();
    let false_alarms = simulated
        .events
        .iter()
        .filter(|e| is_kick_in(e, window))
        .filter(|e| {
            planted
                .iter()
                .all(|(_, c, ..)| !e.cells.near(c, 2 * reach + size))
        })
        .filter(|e| !twin_has(twin, e.kind, e.cells, reach, window))
        .count();
    Ok(Judged {
        patches,
        false_alarms,
    })
}

fn is_kick_in(e: &Event, (from, to): (f64, f64)) -> bool {
    e.cause != Cause::Impact && e.t >= from && e.t <= to + 1e-12
}

/// The twin logged an event of this kind near these cells in the window.
fn twin_has(
    twin: &Twin,
    kind: monitor::EventKind,
    cells: CellRange,
    reach: usize,
    window: (f64, f64),
) -> bool {
    twin.events.iter().any(|e| {
        e.kind == kind && e.cells.near(&cells, reach) && e.last_t >= window.0 && e.t <= window.1
    })
}

/// The twin logged an event (any kind and cause: `find` credits no planted
/// event of a kind the twin has there) that a cluster at these cells would
/// join: its extent within `reach` of them, open in the window or within
/// `merge_seconds` before it (the monitor's merge rule).
fn twin_kicked_near(
    twin: &Twin,
    cells: CellRange,
    (reach, merge_seconds): (usize, f64),
    window: (f64, f64),
) -> bool {
    twin.events.iter().any(|e| {
        e.extent.near(&cells, reach)
            && e.last_t + merge_seconds >= window.0
            && e.t <= window.1 + 1e-12
    })
}

/// The first kick near the patch in the window that the twin lacks.
fn find(
    events: &[Event],
    twin: &Twin,
    cells: CellRange,
    reach: usize,
    window: (f64, f64),
) -> Verdict {
    events
        .iter()
        .filter(|e| is_kick_in(e, window) && e.cells.near(&cells, reach))
        .find(|e| !twin_has(twin, e.kind, e.cells, reach, window))
        .map_or(Verdict::Missed, |e| Verdict::Found {
            delay: e.t - window.0,
            cause: e.cause,
        })
}

/// The cells of a planted region (a block of whole cells): those holding
/// its first and its last cell's centres.
fn cells_of(geom: &Geometry, r: [f64; 4]) -> CellRange {
    let half = 0.5 * geom.cell;
    let (i_min, j_min) = geom.cell_of(Vec2::new(r[0] + half, r[1] + half));
    let (i_max, j_max) = geom.cell_of(Vec2::new(r[2] - half, r[3] - half));
    CellRange {
        i_min,
        j_min,
        i_max: i_max.max(i_min),
        j_max: j_max.max(j_min),
    }
}

/// detection.json (typed), and the table as Parquet and CSV.
fn write_detection(d: &Detection, out: &Path) -> std::io::Result<()> {
    write_atomic(
        &out.join(Detection::FILE),
        serde_json::to_string_pretty(d)?.as_bytes(),
    )?;
    let r = &d.rows;
    let col_f = |name: &str, f: fn(&DetectionRow) -> Option<f64>| {
        Column::new(name.into(), r.iter().map(f).collect::<Vec<_>>())
    };
    let col_u = |name: &str, f: fn(&DetectionRow) -> usize| {
        Column::new(
            name.into(),
            r.iter().map(|x| f(x) as u64).collect::<Vec<_>>(),
        )
    };
    let cols = vec![
        Column::new(
            "case".into(),
            r.iter().map(|x| x.case.clone()).collect::<Vec<_>>(),
        ),
        Column::new(
            "place".into(),
            r.iter().map(|x| x.place.clone()).collect::<Vec<_>>(),
        ),
        col_u("cells", |x| x.cells),
        col_f("dv_found", |x| x.dv_found),
        col_f("dv_missed", |x| x.dv_missed),
        col_f("delay_s", |x| x.delay_s),
        Column::new(
            "cause".into(),
            r.iter().map(|x| x.cause.clone()).collect::<Vec<_>>(),
        ),
        col_u("runs", |x| x.runs),
        Column::new(
            "placed".into(),
            r.iter().map(|x| x.placed).collect::<Vec<_>>(),
        ),
        Column::new(
            "masked".into(),
            r.iter().map(|x| x.masked).collect::<Vec<_>>(),
        ),
        Column::new(
            "shares".into(),
            r.iter()
                .map(|x| x.shares.map(|k| k as u64))
                .collect::<Vec<_>>(),
        ),
        col_f("x0", |x| x.region.map(|r| r[0])),
        col_f("y0", |x| x.region.map(|r| r[1])),
        col_f("x1", |x| x.region.map(|r| r[2])),
        col_f("y1", |x| x.region.map(|r| r[3])),
        Column::new("step".into(), r.iter().map(|x| x.step).collect::<Vec<_>>()),
        Column::new(
            "particles".into(),
            r.iter()
                .map(|x| x.particles.map(|n| n as u64))
                .collect::<Vec<_>>(),
        ),
        col_f("predicted_dv", |x| x.predicted_dv),
        col_u("twin_kicks", |x| x.twin_kicks),
        col_u("false_alarms", |x| x.false_alarms),
    ];
    let mut df = DataFrame::new(cols).map_err(|e| std::io::Error::other(e.to_string()))?;
    tables::write_frame(&mut df, out, "detection", true)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bisects a detector that finds every speed from `threshold` up.
    fn bisect(threshold: f64) -> (Bracket, usize) {
        let mut b = vec![Bracket {
            placed: true,
            ..Default::default()
        }];
        let mut runs = 0;
        while let Some(speeds) = next_speeds([0.005, 0.32], 1.2, &b) {
            let dv = speeds[0].unwrap();
            let verdict = if dv >= threshold {
                Verdict::Found {
                    delay: 0.0,
                    cause: Cause::Jump,
                }
            } else {
                Verdict::Missed
            };
            record(&mut b[0], dv, (verdict, None));
            runs += 1;
        }
        (b.remove(0), runs)
    }

    #[test]
    fn a_patch_a_twin_event_would_absorb_is_masked() {
        // The twin's event opened at cells 20-21 and grew to 10-21; it
        // last moved 0.01 s before the window.
        let mut e = crate::output::summary::sample_event();
        (e.t, e.last_t) = (1.9, 1.99);
        e.cells = CellRange {
            i_min: 20,
            j_min: 0,
            i_max: 21,
            j_max: 1,
        };
        e.extent = CellRange {
            i_min: 10,
            j_min: 0,
            i_max: 21,
            j_max: 1,
        };
        let twin = Twin {
            checkpoint: vec![],
            t_plant: 2.0,
            events: vec![e],
        };
        let patch = |i: usize| CellRange {
            i_min: i,
            j_min: 0,
            i_max: i + 1,
            j_max: 1,
        };
        let window = (2.0, 2.1);
        // Beside the extent (not the opening cells), within its merge time.
        assert!(twin_kicked_near(&twin, patch(6), (3, 0.02), window));
        // Beyond the merge distance, or after the merge time ran out.
        assert!(!twin_kicked_near(&twin, patch(4), (3, 0.02), window));
        assert!(!twin_kicked_near(&twin, patch(6), (3, 0.005), window));
        // An event that opens after the window masks nothing.
        assert!(!twin_kicked_near(&twin, patch(6), (3, 0.02), (1.0, 1.1)));
    }

    /// A patch holds at least the detector's cluster minimum unless the
    /// study asks otherwise: the case's `min_cluster_particles` by
    /// default, `[calibration] min_particles` when set.
    #[test]
    fn a_patch_defaults_to_the_detectors_cluster_minimum() {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../studies/calibration_rest.toml");
        let study = crate::study_file::load(&file, &[]).unwrap();
        let mut spec = study.calibration.clone().unwrap();
        let case = &study.cases[0];
        spec.min_particles = None;
        let least =
            |spec: &CalibrationSpec| perturb_of((case, spec), 0, 1.0, 1, Some(0.1)).min_particles;
        assert_eq!(least(&spec), Some(case.monitor.min_cluster_particles));
        assert_eq!(case.monitor.min_cluster_particles, 4);
        spec.min_particles = Some(9);
        assert_eq!(least(&spec), Some(9));
    }

    #[test]
    fn the_bracket_closes_to_its_ratio_around_the_threshold() {
        for threshold in [0.006, 0.02, 0.05, 0.3] {
            let (b, runs) = bisect(threshold);
            let (f, m) = (b.found.unwrap(), b.missed.unwrap());
            assert!(
                m < threshold && threshold <= f && f / m <= 1.2,
                "{threshold}: {b:?}"
            );
            // The top, the bottom and log2(ln 64 / ln 1.2) = 4.5 halvings.
            assert!(runs <= 7, "{threshold}: {runs} runs");
        }
        // Found at the bottom: settled there; missed at the top: settled too.
        let (b, runs) = bisect(0.001);
        assert_eq!((b.found, b.missed, runs), (Some(0.005), None, 2));
        let (b, runs) = bisect(1.0);
        assert_eq!((b.found, b.missed, runs), (None, Some(0.32), 1));
    }
}
