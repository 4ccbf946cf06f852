//! `kick explain`: why an event kicked. Replays from the checkpoint before
//! the event, bit for bit as `kick reproduce` does, taking the steps from
//! `quiet_seconds` (or `--quiet-window`) before onset to the event's last
//! step with the solver's force forensics (`solver::forensics`), and
//! measures the mechanisms (`monitor::mechanisms`, docs/physics.md section
//! 4c) over the onset window (`ONSET_SECONDS` before the event's first step to its last).
//! With `--counterfactual` it restarts from the same checkpoint as an
//! ensemble per single change, applied from the onset window's start, or
//! the quiet window's with `--switch-at quiet` (`counterfactual`).

pub mod precursors;
pub mod record;

use crate::output::summary::Summary;
use crate::output::tables;
use crate::run::case::{watches, with_threads};
use crate::run::checkpoint;
use crate::run::probes::checkpoint_ring::ring_step;
use crate::run::probes::replay::{Found, Replay as ReplayChecks};
use crate::run::{Rows, RunOptions, Runner, Stepper, Watch};
use crate::study_file::{self, Case};
use monitor::mechanisms::{Mechanisms, Shares, StepParts};
use monitor::{CellRange, Event};
use record::{Criteria, ExplainRecord, LargestPart, Leading, Ringing, TimeStep};
use serde::Serialize;
use solver::forensics::ExplainedStep;
use solver::{CheckpointError, Solver, Vec2};
use std::path::{Path, PathBuf};

/// The onset window's length before the event's first step (s): the
/// burst itself, apart from the quiet window before it.
pub const ONSET_SECONDS: f64 = 0.01;

pub struct ExplainOptions {
    pub threads: Option<usize>,
    pub out: Option<PathBuf>,
    pub counterfactual: bool,
    /// Members of each counterfactual row.
    pub members: usize,
    /// Make each change at the quiet window's start, not the onset
    /// window's: the energy window's evidence then postdates the change.
    pub switch_at_quiet: bool,
    /// The quiet window's length (s) when not the monitor's `quiet_seconds`:
    /// a longer look back for the precursors and the ringing.
    pub quiet_seconds: Option<f64>,
}

/// Bad input (exit 2): missing or corrupted files, unknown event, mixtures.
#[derive(Debug)]
pub struct ExplainError(pub String);

pub struct Outcome {
    pub matched: bool,
    pub message: String,
    pub out: PathBuf,
    /// The step before onset and the onset step, for the report's picture.
    pub picture: Option<Picture>,
}

/// What the picture of an explained event shows (drawn by the report).
pub struct Picture {
    pub before: ExplainedStep,
    pub onset: ExplainedStep,
    /// The cell size.
    pub h: f64,
}

/// One explained step's row of the table.
#[derive(Clone, Debug, Serialize)]
pub struct StepRow {
    pub step: u64,
    pub time: f64,
    pub dt: f64,
    /// In the onset window (else: the quiet time before it, M4's window).
    pub onset: bool,
    pub parts: StepParts,
    /// The matched quiet boxes' mean drift |v_p - sum N v_i| (m/s) at a
    /// quiet step (NaN in the onset window): the ringing the event's
    /// `parts.drift_speed` is compared with.
    pub control_drift_speed: f64,
}

/// What the explained replay recorded.
#[derive(Default)]
struct Record {
    rows: Vec<StepRow>,
    /// Ids of the particles explained.
    ids: Vec<u32>,
    /// The explained step at the onset window's start, and at the event's first step.
    before: Option<ExplainedStep>,
    onset: Option<ExplainedStep>,
    /// The matched quiet regions' particle ids (ascending) and boxes, and
    /// the precursor flags counted.
    control_ids: Vec<u32>,
    control_boxes: usize,
    counts: precursors::Counts,
}

/// The window's times and steps.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Window {
    pub explain_from: f64,
    pub onset_from: f64,
    /// When the counterfactuals make their change: `onset_from`, or
    /// `explain_from` with `--switch-at quiet`.
    pub switch_from: f64,
    pub first_step: u64,
    pub last_step: u64,
    pub last_t: f64,
}

/// The `Stepper` methods a wrapper of one `solver` hands to it.
macro_rules! solver_stepper {
    () => {
        fn step_count(&self) -> u64 {
            self.solver.step_count()
        }
        fn time(&self) -> f64 {
            self.solver.time()
        }
        fn state_hash(&self) -> u64 {
            self.solver.state_hash()
        }
        fn phase_count(&self) -> usize {
            1
        }
        fn phase(&self, _k: usize) -> &Solver {
            &self.solver
        }
        fn phase_name(&self, _k: usize) -> Option<&'static str> {
            None
        }
        fn primary_phase(&self) -> usize {
            0
        }
        fn timeseries_stem(&self, _k: usize) -> String {
            "timeseries".into()
        }
        fn save(&self, watches: &[Watch]) -> Vec<u8> {
            Stepper::save(&self.solver, watches)
        }
        fn load(&mut self, bytes: &[u8], watches: &mut [Watch]) -> Result<(), CheckpointError> {
            Stepper::load(&mut self.solver, bytes, watches)
        }
    };
}

pub mod counterfactual;
pub use counterfactual::CounterfactualRow;

/// A solver whose steps in the window are explained.
struct Explaining<'a> {
    solver: Solver,
    window: Window,
    cells: CellRange,
    mechanisms: Mechanisms,
    primed: bool,
    /// The cells of the run's other events in the window.
    others: Vec<CellRange>,
    record: &'a mut Record,
}

impl Explaining<'_> {
    /// The explained particles: the event's, then the controls' (chosen
    /// at the first explained step).
    fn indices(&mut self) -> Vec<usize> {
        let v = self.solver.view();
        if !self.primed {
            let geometry = monitor::Geometry::from_scene(v.scene);
            let mut count = vec![0usize; geometry.cells[0] * geometry.cells[1]];
            for &x in v.x.iter() {
                let (i, j) = geometry.cell_of(x);
                count[j * geometry.cells[0] + i] += 1;
            }
            let boxes = precursors::control_boxes(
                self.cells,
                geometry.cells[0],
                |i, j| count[j * geometry.cells[0] + i] > 0,
                &self.others,
            );
            self.record.control_boxes = boxes.len();
            self.record.control_ids = (0..v.x.len())
                .filter(|&p| {
                    let (i, j) = geometry.cell_of(v.x[p]);
                    boxes.iter().any(|b| {
                        (b.i_min..=b.i_max).contains(&i) && (b.j_min..=b.j_max).contains(&j)
                    })
                })
                .map(|p| v.id[p])
                .collect();
            self.record.control_ids.sort_unstable();
        }
        if self.record.ids.is_empty() {
            // An energy event names no particle: those in its cells, by
            // the monitor's own cell rule.
            let geometry = monitor::Geometry::from_scene(v.scene);
            let c = self.cells;
            for (p, &x) in v.x.iter().enumerate() {
                let (i, j) = geometry.cell_of(x);
                if (c.i_min..=c.i_max).contains(&i) && (c.j_min..=c.j_max).contains(&j) {
                    self.record.ids.push(v.id[p]);
                }
            }
        }
        let (ids, controls) = (&self.record.ids, &self.record.control_ids);
        (0..v.id.len())
            .filter(|&p| {
                ids.binary_search(&v.id[p]).is_ok() || controls.binary_search(&v.id[p]).is_ok()
            })
            .collect()
    }

    /// Counts the precursor flags of a quiet step or of the onset step;
    /// the controls' mean drift at a quiet step (m/s; NaN otherwise).
    fn count_flags(&mut self, step: u64, explained: &ExplainedStep, onset: bool) -> f64 {
        let quiet = !onset;
        if !(quiet || step == self.window.first_step) {
            return f64::NAN;
        }
        let (ids, controls) = (&self.record.ids, &self.record.control_ids);
        let event = self
            .mechanisms
            .flags(explained, |q| ids.binary_search(&explained.id[q]).is_ok());
        let control = self.mechanisms.flags(explained, |q| {
            controls.binary_search(&explained.id[q]).is_ok()
        });
        let c = &mut self.record.counts;
        if quiet {
            c.quiet_event.add(&event);
            c.quiet_control.add(&control);
            c.quiet_steps += 1;
            control.mean_drift()
        } else {
            c.onset_event = event;
            c.onset_control = control;
            f64::NAN
        }
    }
}

impl Stepper for Explaining<'_> {
    fn advance(&mut self) -> Result<(), String> {
        let step = self.solver.step_count() + 1;
        let ends_at = self.solver.time() + self.solver.next_dt();
        if ends_at < self.window.explain_from || step > self.window.last_step {
            return Stepper::advance(&mut self.solver);
        }
        let particles = self.indices();
        let explained = self
            .solver
            .step_explained(&particles)
            .map_err(|e| format!("step {step}: {e}"))?;
        let onset = explained.time >= self.window.onset_from;
        // The picture shows the event's particles, not the controls'.
        let event_only = || {
            let mut only = explained.clone();
            let ids = &self.record.ids;
            only.explained
                .retain(|e| ids.binary_search(&explained.id[e.particle]).is_ok());
            only
        };
        if onset && self.record.before.is_none() {
            self.record.before = Some(event_only());
        }
        if step == self.window.first_step {
            self.record.onset = Some(event_only());
        }
        if !self.primed {
            self.mechanisms.prime(&explained);
            self.primed = true;
            return Ok(());
        }
        let control_drift_speed = self.count_flags(step, &explained, onset);
        let ids = &self.record.ids;
        let parts = self
            .mechanisms
            .add_where(&explained, |q| ids.binary_search(&explained.id[q]).is_ok());
        self.record.rows.push(StepRow {
            step,
            time: explained.time,
            dt: explained.dt,
            onset,
            parts,
            control_drift_speed,
        });
        Ok(())
    }
    fn finished(&self) -> bool {
        self.solver.finished()
    }
    solver_stepper!();
}

/// The logged event, its case and its checkpoint's bytes.
struct Loaded {
    study_path: PathBuf,
    logged: Event,
    case: Case,
    checkpoint: Vec<u8>,
    checkpoint_name: String,
    /// The time the replays start from.
    checkpoint_t: f64,
    /// The cells of the run's other events that overlap the quiet and
    /// onset windows in time (kept clear of the precursors' controls).
    others: Vec<CellRange>,
}

fn load(case_dir: &Path, id: u32, quiet_seconds: Option<f64>) -> Result<Loaded, ExplainError> {
    let summary_path = case_dir.join("summary.json");
    let events = Summary::read(case_dir).map_err(ExplainError)?.events;
    let Some(logged) = events.iter().find(|e| e.id == id).cloned() else {
        let ids: Vec<String> = events.iter().map(|e| e.id.to_string()).collect();
        return Err(ExplainError(format!(
            "{}: no event {id} (events: {})",
            summary_path.display(),
            if ids.is_empty() {
                "none".into()
            } else {
                ids.join(", ")
            }
        )));
    };
    let Some(checkpoint_name) = logged.checkpoint.clone() else {
        return Err(ExplainError(format!(
            "{}: event {id} has no checkpoint (the case ran with output.checkpoint_every = 0)",
            summary_path.display()
        )));
    };
    let study_path = case_dir.join("case.toml");
    let study = study_file::load(&study_path, &[]).map_err(|e| ExplainError(e.to_string()))?;
    let case = study.cases[0].clone();
    if case.mixture.is_some() {
        return Err(ExplainError(format!(
            "{}: kick explain takes single-phase cases (this one is a mixture)",
            study_path.display()
        )));
    }
    let from = logged.t - quiet_seconds.unwrap_or(case.monitor.quiet_seconds);
    let (checkpoint_name, checkpoint, checkpoint_t) =
        replay_checkpoint(case_dir, &checkpoint_name, from)?;
    let others = events
        .iter()
        .filter(|e| e.id != id && e.last_t >= from && e.t <= logged.last_t)
        .map(|e| e.extent)
        .collect();
    Ok(Loaded {
        others,
        study_path,
        logged,
        case,
        checkpoint,
        checkpoint_name,
        checkpoint_t,
    })
}

/// The checkpoint the replays start from: the latest of the case's ring
/// checkpoints, up to the event's own, whose time is at or before `from`
/// (the quiet window's start). The event's own checkpoint is only the last
/// one before the event: with a dense ring it falls inside the window, and
/// a replay from it would shorten the quiet window and switch every
/// counterfactual late. Without one early enough, the earliest there is.
fn replay_checkpoint(
    case_dir: &Path,
    logged: &str,
    from: f64,
) -> Result<(String, Vec<u8>, f64), ExplainError> {
    let read = |name: &str| {
        let path = case_dir.join(name);
        let bytes = std::fs::read(&path)
            .map_err(|e| ExplainError(format!("{}: cannot read: {e}", path.display())))?;
        let (_, t) = checkpoint::clock(&bytes)
            .map_err(|e| ExplainError(format!("{}: {e}", path.display())))?;
        Ok::<_, ExplainError>((bytes, t))
    };
    let mut candidates: Vec<(u64, String)> = vec![];
    if let (Some(last), Ok(entries)) = (
        ring_step(logged),
        std::fs::read_dir(case_dir.join("checkpoints")),
    ) {
        for entry in entries.flatten() {
            let name = format!("checkpoints/{}", entry.file_name().to_string_lossy());
            if let Some(step) = ring_step(&name).filter(|&s| s <= last) {
                candidates.push((step, name));
            }
        }
    }
    candidates.sort();
    for (_, name) in candidates.iter().rev() {
        let (bytes, t) = read(name)?;
        if t <= from + 1e-12 {
            return Ok((name.clone(), bytes, t));
        }
    }
    let name = candidates
        .first()
        .map_or(logged.to_string(), |(_, n)| n.clone());
    let (bytes, t) = read(&name)?;
    Ok((name, bytes, t))
}

pub fn explain(case_dir: &Path, id: u32, opts: &ExplainOptions) -> Result<Outcome, ExplainError> {
    if opts.counterfactual && opts.quiet_seconds.is_some() {
        return Err(ExplainError(
            "--quiet-window: not with --counterfactual (its members start from the monitor's own window)".into(),
        ));
    }
    let loaded = load(case_dir, id, opts.quiet_seconds)?;
    let out = opts
        .out
        .clone()
        .unwrap_or_else(|| case_dir.join("explain").join(format!("event_{id}")));
    let logged = &loaded.logged;
    let mcfg = &loaded.case.monitor;
    let quiet_seconds = opts.quiet_seconds.unwrap_or(mcfg.quiet_seconds);
    let (explain_from, onset_from) = (logged.t - quiet_seconds, logged.t - ONSET_SECONDS);
    let window = Window {
        explain_from,
        onset_from,
        // The replays cannot switch before their checkpoint.
        switch_from: if opts.switch_at_quiet {
            explain_from.min(onset_from)
        } else {
            onset_from
        }
        .max(loaded.checkpoint_t),
        first_step: logged.first_step,
        last_step: logged.last_step,
        last_t: logged.last_t,
    };
    let at = |e: String| ExplainError(format!("{}: {e}", out.display()));
    let mut record = Record {
        ids: {
            let mut ids = logged.particles.clone();
            ids.sort_unstable();
            ids
        },
        ..Record::default()
    };
    let found = with_threads(opts.threads, || {
        explained_replay(&loaded, window, &out, &mut record)
    })
    .map_err(|e| at(e.to_string()))?
    .map_err(|e| {
        ExplainError(format!(
            "{}: {e}",
            case_dir.join(&loaded.checkpoint_name).display()
        ))
    })?;
    let counterfactual = if opts.counterfactual {
        counterfactual::run(&loaded, window, opts.members, opts.threads)
            .map_err(|e| at(e.to_string()))?
    } else {
        vec![]
    };
    finish(
        case_dir,
        &out,
        &loaded,
        window,
        &record,
        found,
        &counterfactual,
    )
    .map_err(|e| at(e.to_string()))
}

fn explained_replay(
    loaded: &Loaded,
    window: Window,
    out: &Path,
    record: &mut Record,
) -> std::io::Result<Result<Found, String>> {
    let case = &loaded.case;
    let solver = match Solver::new(case.solver.clone()) {
        Ok(s) => s,
        Err(e) => return Ok(Err(format!("setup: {e}"))),
    };
    let mut watches = watches(&solver, case);
    let scene = &case.solver.scene;
    let mut stepper = Explaining {
        mechanisms: Mechanisms::new(
            Vec2::from(scene.origin),
            scene.cell,
            case.solver.first_rho0(),
            scene.gravity,
        ),
        solver,
        window,
        cells: loaded.logged.cells,
        primed: false,
        others: loaded.others.clone(),
        record,
    };
    if let Err(e) = stepper.load(&loaded.checkpoint, &mut watches) {
        return Ok(Err(e.to_string()));
    }
    let start = stepper.step_count();
    if start >= window.first_step {
        return Ok(Err(format!(
            "taken at step {start}, not before event {} (step {})",
            loaded.logged.id, window.first_step
        )));
    }
    let mut run_opts = RunOptions::new(Some(out.to_path_buf()), Rows::every_step());
    run_opts.csv = true;
    run_opts.until_step = Some(window.last_step);
    let mut found = Found::default();
    let mut runner = Runner::new(stepper, watches, run_opts);
    runner.attach(ReplayChecks {
        files_from: u64::MAX,
        files: out.join("particles"),
        event: &loaded.logged,
        phase: 0,
        found: &mut found,
    });
    runner.run()?;
    drop(runner);
    Ok(Ok(found))
}

/// The mechanisms' shares over the rows of the onset window.
fn window_shares(rows: &[StepRow]) -> Shares {
    let mut sum = Shares::default();
    let mut dv2 = 0.0;
    for r in rows.iter().filter(|r| r.onset) {
        sum.add(&r.parts.projected);
        dv2 += r.parts.dv2;
    }
    sum.over(dv2)
}

fn finish(
    case_dir: &Path,
    out: &Path,
    loaded: &Loaded,
    window: Window,
    record: &Record,
    found: Found,
    counterfactual: &[CounterfactualRow],
) -> std::io::Result<Outcome> {
    let explained = explain_record(case_dir, loaded, window, record, found, counterfactual);
    std::fs::create_dir_all(out)?;
    explained.write(out)?;
    if !counterfactual.is_empty() {
        let table = counterfactual::markdown(counterfactual);
        crate::output::files::write_atomic(&out.join("counterfactual.md"), table.as_bytes())?;
    }
    write_steps(&record.rows, out)?;
    let (lead, part) = (&explained.leading, &explained.largest_part);
    let mut message = format!(
        "event {}: {} from {} (hash {}); largest part {} {:.3}; leading mechanism {} {:.3} (cancellation {:.2}); precursor {} ({:+.2} over {} control boxes); closure {:.1e}",
        explained.event,
        if explained.matched { "replayed" } else { "DIVERGED" },
        loaded.checkpoint_name,
        explained.replayed_state_hash.as_deref().unwrap_or("-"),
        part.part,
        part.share.unwrap_or(f64::NAN),
        lead.mechanism,
        lead.share.unwrap_or(f64::NAN),
        explained.cancellation,
        explained.precursors.named,
        explained.precursors.excess,
        explained.precursors.control_boxes,
        explained.closure_rest_max
    );
    if loaded.checkpoint_t > window.explain_from + 1e-12 {
        message += &format!(
            "; note: no checkpoint precedes the quiet window (from t = {:.4} s): the replays start at t = {:.4} s",
            window.explain_from, loaded.checkpoint_t
        );
    }
    let picture = match (&record.before, &record.onset) {
        (Some(before), Some(onset)) => Some(Picture {
            before: before.clone(),
            onset: onset.clone(),
            h: loaded.case.solver.scene.cell,
        }),
        _ => None,
    };
    Ok(Outcome {
        matched: explained.matched,
        message,
        out: out.to_path_buf(),
        picture,
    })
}

/// M4 over the steps before onset: the drift over the particles' speed,
/// and the drift in m/s over sqrt(g H) (NaN without gravity).
fn m4_ringing(record: &Record, scene: &solver::Scene, window: &Window) -> Ringing {
    let before: Vec<&StepRow> = record.rows.iter().filter(|r| !r.onset).collect();
    let mean_before = |of: fn(&StepRow) -> f64| {
        if before.is_empty() {
            f64::NAN
        } else {
            before.iter().map(|r| of(r)).sum::<f64>() / before.len() as f64
        }
    };
    let gravity_wave = gravity_wave(scene);
    Ringing {
        drift_over_speed: mean_before(|r| r.parts.drift),
        drift_over_gravity_wave: if gravity_wave > 0.0 {
            mean_before(|r| r.parts.drift_speed) / gravity_wave
        } else {
            f64::NAN
        },
        steps: before.len(),
        window_s: window.onset_from - window.explain_from,
    }
}

/// sqrt(g H), H the scene's column height (m/s): M4's unit.
fn gravity_wave(scene: &solver::Scene) -> f64 {
    let column = monitor::geometry::Geometry::from_scene(scene).column_height;
    (scene.gravity.abs() * column).sqrt()
}

/// The record of an explained replay.
fn explain_record(
    case_dir: &Path,
    loaded: &Loaded,
    window: Window,
    record: &Record,
    found: Found,
    counterfactual: &[CounterfactualRow],
) -> ExplainRecord {
    let logged = &loaded.logged;
    let matched = found.hash_at_first.as_deref() == logged.state_hash.as_deref()
        && found
            .replayed
            .as_ref()
            .is_some_and(|e| e.first_step == logged.first_step);
    let shares = window_shares(&record.rows);
    let m4_ringing = m4_ringing(record, &loaded.case.solver.scene, &window);
    let rest_max = record
        .rows
        .iter()
        .map(|r| r.parts.rest_max)
        .fold(0.0, f64::max);
    let cancellation = monitor::mechanisms::cancellation(&shares);
    let (leading, leading_share) = match shares.leading() {
        _ if cancellation > monitor::mechanisms::CANCELLING => ("undecided", f64::NAN),
        (_, share) if share < monitor::mechanisms::NAMED_SHARE => ("none", share),
        named => named,
    };
    let (largest, largest_share) = shares.largest_part();
    let ev = &logged.evidence;
    ExplainRecord {
        case_dir: case_dir.display().to_string(),
        event: logged.id,
        checkpoint: loaded.checkpoint_name.clone(),
        checkpoint_t: loaded.checkpoint_t,
        replayed_state_hash: found.hash_at_first,
        logged_state_hash: logged.state_hash.clone(),
        matched,
        window,
        particles: record.ids.clone(),
        steps_explained: record.rows.len(),
        closure_rest_max: rest_max,
        shares,
        cancellation,
        precursors: precursors::Precursors::new(
            &record.counts,
            record.control_boxes,
            record.control_ids.len(),
            gravity_wave(&loaded.case.solver.scene),
        ),
        leading: Leading {
            mechanism: leading.into(),
            share: Some(leading_share),
        },
        largest_part: LargestPart {
            part: largest.into(),
            share: Some(largest_share),
        },
        m4_ringing,
        m5_time_step: TimeStep {
            courant_before: ev.courant_before,
            advection_before: ev.advection_before,
            critical_courant: ev.critical_courant,
        },
        criteria: Criteria {
            small_node_share: monitor::mechanisms::SMALL_NODE_SHARE,
            outlier_sigmas: monitor::mechanisms::OUTLIER_SIGMAS,
            outlier_floor_rho0_g_h: monitor::mechanisms::OUTLIER_FLOOR,
        },
        counterfactual: counterfactual.to_vec(),
    }
}

fn write_steps(rows: &[StepRow], out: &Path) -> std::io::Result<()> {
    let col = |f: &dyn Fn(&StepRow) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let share = |f: &dyn Fn(&Shares) -> f64| {
        rows.iter()
            .map(|r| {
                if r.parts.dv2 > 0.0 {
                    f(&r.parts.projected) / r.parts.dv2
                } else {
                    0.0
                }
            })
            .collect::<Vec<f64>>()
    };
    let columns: Vec<(&str, Vec<f64>)> = vec![
        ("step", col(&|r| r.step as f64)),
        ("t", col(&|r| r.time)),
        ("dt", col(&|r| r.dt)),
        ("onset", col(&|r| r.onset as u8 as f64)),
        ("dv2", col(&|r| r.parts.dv2)),
        ("share_internal", share(&|s| s.internal)),
        ("share_external", share(&|s| s.external)),
        ("share_walls", share(&|s| s.walls)),
        ("share_jump", share(&|s| s.jump)),
        ("share_hourglass", share(&|s| s.hourglass)),
        (
            "share_pressure_correction",
            share(&|s| s.pressure_correction),
        ),
        ("share_extrapolation", share(&|s| s.extrapolation)),
        ("share_impulse", share(&|s| s.impulse)),
        ("share_rest", share(&|s| s.rest)),
        ("share_m1_small_mass_node", share(&|s| s.small_mass_node)),
        ("share_m2_cell_crossing", share(&|s| s.cell_crossing)),
        ("share_m3_stress_outlier", share(&|s| s.stress_outlier)),
        ("m4_drift", col(&|r| r.parts.drift)),
        ("m4_drift_speed", col(&|r| r.parts.drift_speed)),
        ("m4_drift_speed_control", col(&|r| r.control_drift_speed)),
        ("rest_max", col(&|r| r.parts.rest_max)),
        ("crossers", col(&|r| r.parts.crossers as f64)),
        ("outliers", col(&|r| r.parts.outliers as f64)),
        ("min_node_share", col(&|r| r.parts.min_node_share)),
    ];
    let refs: Vec<(&str, &[f64])> = columns.iter().map(|(n, v)| (*n, v.as_slice())).collect();
    tables::write_columns(&refs, out, "explain_steps", true)
}
