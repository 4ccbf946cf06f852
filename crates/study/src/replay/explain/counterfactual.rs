//! `kick explain --counterfactual`: the unchanged control and each single
//! change, replayed from the event's checkpoint as ensembles. Every member
//! moves the checkpoint's particles by a seeded offset of `scene.jitter` h
//! (round-off's size unless the case sets one); member k has the same seed
//! for the control and for every change, so each change is compared with
//! the control on the same noise. Each change is made at the onset window's
//! start (or the quiet window's, `--switch-at quiet`), and the replays go on
//! `AFTER_SECONDS` past the event's last step, so that a change that only
//! delays the event is seen to.

use super::{Loaded, Window};
use crate::output::summary::{method_id, Status};
use crate::run::case::{panic_message, progress_style, toml_to_json, watches, with_threads};
use crate::run::{Probe, Rows, Run, RunOptions, Runner, Simulated, Stepper, Watch};
use crate::study_file::{self, ENSEMBLE_JITTER};
use indicatif::ProgressBar;
use monitor::stats::{median_with_infinities, spread, wilson};
use monitor::{Cause, CellRange, Event};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use solver::{CheckpointError, DtMode, Method, Solver};
use std::path::Path;

/// How long the replays go on after the event's last step (s).
pub const AFTER_SECONDS: f64 = 0.2;
/// Members per row unless `--members` says.
pub const MEMBERS: usize = 5;
/// A kick within this many cells of the event's cells is in its region.
pub const REGION_CELLS: usize = 3;
/// The control reproduces its event when it reopens in at least this share
/// of the members (4 of 5); a change prevents it when it reopens in at most
/// `RARE_SHARE` of them (1 of 5).
pub const REPRODUCED_SHARE: f64 = 0.8;
pub const RARE_SHARE: f64 = 0.2;
/// Next-kick times within this of the control's range are the same time
/// (s): half the onset window, so that round-off in an event's time does
/// not read as a delay.
pub const SAME_TIME: f64 = 0.5 * super::ONSET_SECONDS;

/// One member of one row.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Member {
    pub seed: u64,
    /// An event of the logged kind opened over the event's cells.
    pub event_happens: bool,
    /// The first kick (inversion, injection or jump) in the event's region
    /// after the change was made, in s after the logged event's time;
    /// None when there was none by the window's end.
    pub next_kick_after: Option<f64>,
    /// Largest rise (J/m) of the total the injection test watches above its
    /// running minimum, from the switch to the window's end.
    pub injected: f64,
    pub steps: u64,
    /// `completed` or `blew up: REASON`.
    pub outcome: String,
    /// Non-physical events (cause other than impact) that are not the
    /// event itself: "KIND (CAUSE) at T s".
    pub other_events: Vec<String>,
}

/// One single change over its members.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CounterfactualRow {
    pub change: String,
    /// Why it could not be made (then nothing below was measured).
    pub refused: Option<String>,
    /// The changed method's identity (`summary::method_id`), when the
    /// change is a method the study file can state.
    pub method_id: Option<String>,
    pub members: Vec<Member>,
    /// Members in which the event opened again, and its 95 % Wilson interval
    /// as a share of the members.
    pub reopened: usize,
    pub reopened_interval: [f64; 2],
    pub blew_up: usize,
    /// Members that opened another non-physical event.
    pub moved: usize,
    /// The median member's injection (J/m), and the event's floor.
    pub injected: f64,
    pub floor: f64,
    /// Time from the event to the next kick in its region (s): median,
    /// min and max over the members that had one, and how many had none.
    pub next_kick: [Option<f64>; 3],
    pub no_next_kick: usize,
    /// `control`, `not reproduced` (the control's own row when it reopens
    /// in too few members), `prevented`, `delayed`, `hastened`, `again`,
    /// `moved`, `blew up`, `injected`, `undecided` or `refused`.
    pub verdict: String,
}

/// What the verdict reads of a row.
#[derive(Clone, Debug, Default)]
pub struct Tally {
    pub members: usize,
    pub reopened: usize,
    pub blew_up: usize,
    pub moved: usize,
    pub injected: f64,
    /// The members' next kick times (None: none in the window).
    pub next_kick: Vec<Option<f64>>,
}

/// `k` of `n` members reproduce an outcome: at least `REPRODUCED_SHARE`
/// of them (4 of 5, 3 of 3).
pub fn reproduced(k: usize, n: usize) -> bool {
    k as f64 >= REPRODUCED_SHARE * n as f64 - 1e-9
}

/// `k` of `n` members are rare: at most `RARE_SHARE` of them (1 of 5, 0 of 3).
pub fn rare(k: usize, n: usize) -> bool {
    k as f64 <= RARE_SHARE * n as f64 + 1e-9
}

/// The row's verdict, its rules fixed before the runs (docs/physics.md
/// section 4c): nothing is judged unless the control reopens in at least
/// 4 of 5 members; a change prevents when the event reopens in at most 1
/// of 5, no member blows up or opens another non-physical event, and the
/// median member gains less than the control's; when the event reopens in
/// at least 4 of 5, the median time to the next kick in its region against
/// the control's range (widened by `SAME_TIME`) says delayed, hastened or
/// again; in between it is
/// undecided.
pub fn verdict(control: &Tally, change: &Tally) -> &'static str {
    let n = change.members;
    // A control that did not run (refused) reproduces nothing.
    if control.members == 0 || !reproduced(control.reopened, control.members) {
        return "undecided";
    }
    if rare(change.reopened, n) {
        return if change.blew_up > 0 {
            "blew up"
        } else if change.moved > 0 {
            "moved"
        } else if control.injected > 0.0
            && (change.injected >= control.injected || change.injected.is_nan())
        {
            "injected"
        } else {
            "prevented"
        };
    }
    if !reproduced(change.reopened, n) {
        return "undecided";
    }
    let times = |t: &Tally| -> Vec<f64> {
        t.next_kick
            .iter()
            .map(|k| k.unwrap_or(f64::INFINITY))
            .collect()
    };
    let (own, theirs) = (times(change), times(control));
    let (lo, hi) = theirs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    match median_with_infinities(&own) {
        Some(m) if m > hi + SAME_TIME => "delayed",
        Some(m) if m < lo - SAME_TIME => "hastened",
        _ => "again",
    }
}

/// What a counterfactual changes, from `Window::switch_from`.
enum Change {
    /// Study-file overrides of `[method]` (none: the control).
    Overrides(Vec<String>),
    /// The solver's own step halved when the change is made.
    HalfDt,
    /// The method without its remedies (refused when it has none).
    RemediesOff,
    /// The pressure-implicit formulation (docs/physics.md section 8) in
    /// place of the particles' EOS stress, without the method's remedies;
    /// its step from the flow, or fixed at the explicit run's step when the
    /// change is made. Built from the case's method, since its study file
    /// may set keys the formulation refuses.
    PressureImplicit { at_run_dt: bool },
}

/// The default list: (name, change).
fn changes(method: &Method) -> Vec<(String, Change)> {
    let overrides = |keys: &[&str]| Change::Overrides(keys.iter().map(|k| k.to_string()).collect());
    let xpic = if method.transfer == solver::TransferKind::Xpic {
        ("xpic off", overrides(&["method.transfer=\"flip\""]))
    } else {
        (
            "xpic on",
            overrides(&[
                "method.transfer=\"xpic\"",
                "method.xpic_order=5",
                "method.gradient_enhanced=false",
            ]),
        )
    };
    let remedies = remedy_keys(method);
    // It takes no remedy (its controls are its own): the method's go with it.
    let without = if remedies.is_empty() {
        String::new()
    } else {
        format!(" (without {})", remedies.join(", "))
    };
    vec![
        ("unchanged".into(), Change::Overrides(vec![])),
        (
            "pic".into(),
            overrides(&["method.transfer=\"pic\"", "method.gradient_enhanced=false"]),
        ),
        (
            "flip 0.99".into(),
            overrides(&["method.transfer=\"flip\"", "method.flip_alpha=0.99"]),
        ),
        ("half dt".into(), Change::HalfDt),
        (
            "min node mass 0.01".into(),
            overrides(&["method.min_node_mass={ share = 0.01 }"]),
        ),
        ("j-bar".into(), overrides(&["method.j_bar=true"])),
        (
            "pressure smoothing".into(),
            overrides(&["method.pressure_smoothing=true"]),
        ),
        (xpic.0.into(), xpic.1),
        (
            "shifting".into(),
            overrides(&["method.shifting={ time = 0.02 }"]),
        ),
        ("remedies off".into(), Change::RemediesOff),
        (
            format!("pressure implicit{without}"),
            Change::PressureImplicit { at_run_dt: false },
        ),
        (
            format!("pressure implicit at the run's dt{without}"),
            Change::PressureImplicit { at_run_dt: true },
        ),
    ]
}

/// The study-file keys of the method's remedies.
fn remedy_keys(method: &Method) -> Vec<&'static str> {
    method
        .remedies
        .active()
        .iter()
        .map(|r| r.descriptor().key)
        .collect()
}

/// The case's method under the pressure-implicit formulation: no remedy,
/// and the step from the flow (a fixed explicit step, or an explicit
/// step's floor, would be kept).
fn pressure_implicit(method: &Method) -> Method {
    Method {
        formulation: solver::Formulation::PressureImplicit,
        remedies: Default::default(),
        dt_value: None,
        dt_min: None,
        gradient_enhanced: false,
        ..method.clone()
    }
}

/// How the step is set when the change is made.
#[derive(Clone, Copy, PartialEq)]
enum StepRule {
    Keep,
    /// The solver's own step halved.
    Half,
    /// Fixed at the step the run was taking.
    FixAtCurrent,
}

/// A solver that changes its method once, at `Window::switch_from` (the
/// onset or the quiet window's start), and ends at the window's end.
struct Switching {
    solver: Solver,
    at: f64,
    until: f64,
    method: Option<Method>,
    step_rule: StepRule,
    refused: Option<String>,
    /// The step count when the change was made.
    switched_at: Option<u64>,
}

impl Switching {
    /// The method to switch to, with its step set by the rule.
    fn target(&mut self) -> Option<Method> {
        let s = &self.solver;
        let rule = std::mem::replace(&mut self.step_rule, StepRule::Keep);
        let mut m = self.method.take();
        match rule {
            StepRule::Keep => {}
            StepRule::Half => {
                let mut h = m.unwrap_or_else(|| s.config().method.clone());
                match h.dt {
                    DtMode::Fixed => h.dt_value = Some(s.next_dt() / 2.0),
                    DtMode::Dynamic | DtMode::PerAxis => h.cfl /= 2.0,
                }
                m = Some(h);
            }
            StepRule::FixAtCurrent => {
                if let Some(h) = m.as_mut() {
                    h.dt = DtMode::Fixed;
                    h.dt_value = Some(s.next_dt());
                }
            }
        }
        m
    }
}

impl Stepper for Switching {
    fn advance(&mut self) -> Result<(), String> {
        if self.solver.time() + self.solver.next_dt() >= self.at {
            self.switched_at.get_or_insert(self.solver.step_count());
            if let Some(m) = self.target() {
                if let Err(e) = self.solver.set_method(m) {
                    self.refused = Some(e.to_string());
                    return Err(format!("refused: {e}"));
                }
            }
        }
        Stepper::advance(&mut self.solver)
    }
    fn finished(&self) -> bool {
        self.solver.finished() || self.solver.time() >= self.until
    }
    solver_stepper!();
}

/// What a replay measured over the window: the running minimum of the
/// budget the detector watches, the largest rise above it, and whether
/// the event opened again.
struct Measured {
    min: f64,
    injected: f64,
    happens: bool,
}

struct WindowInjection<'a> {
    from: f64,
    until: f64,
    logged: &'a Event,
    measured: &'a mut Measured,
}

impl<S: Stepper> Probe<S> for WindowInjection<'_> {
    fn after_step(&mut self, run: &Run<S>, opened: &[u32]) -> std::io::Result<()> {
        let t = run.stepper.time();
        if t < self.from || t > self.until + 1e-12 {
            return Ok(());
        }
        let monitor = &run.watches[0].monitor;
        let watched = monitor.report().detector_total;
        let m = &mut *self.measured;
        if watched.is_finite() {
            m.min = m.min.min(watched);
            m.injected = m.injected.max(watched - m.min);
        }
        for id in opened {
            if let Some(e) = monitor.events().iter().find(|e| e.id == *id) {
                if e.kind == self.logged.kind && overlaps(e.cells, self.logged.cells) {
                    m.happens = true;
                }
            }
        }
        Ok(())
    }
}

pub fn overlaps(a: CellRange, b: CellRange) -> bool {
    a.i_min <= b.i_max && b.i_min <= a.i_max && a.j_min <= b.j_max && b.j_min <= a.j_max
}

/// The cells within `REGION_CELLS` of `c`.
fn region(c: CellRange) -> CellRange {
    CellRange {
        i_min: c.i_min.saturating_sub(REGION_CELLS),
        j_min: c.j_min.saturating_sub(REGION_CELLS),
        i_max: c.i_max + REGION_CELLS,
        j_max: c.j_max + REGION_CELLS,
    }
}

/// The members' seeds, derived from the case's seed and the member's
/// number: the same for every row, each unlike the case's own.
fn seeds(loaded: &Loaded, members: usize) -> Vec<u64> {
    let base = loaded.case.solver.scene.seed;
    (1..=members as u64)
        .map(|k| base ^ k.wrapping_mul(0x9e37_79b9_7f4a_7c15))
        .collect()
}

/// Every row, the control first: each change is judged against it.
pub(super) fn counterfactuals(
    loaded: &Loaded,
    window: Window,
    members: usize,
) -> Vec<CounterfactualRow> {
    let seeds = seeds(loaded, members);
    let changes = changes(&loaded.case.solver.method);
    let bar = ProgressBar::new((changes.len() * members) as u64).with_style(progress_style());
    bar.set_prefix("counterfactual replays");
    let mut rows: Vec<CounterfactualRow> = vec![];
    let mut control = Tally::default();
    for (k, (name, change)) in changes.into_iter().enumerate() {
        bar.set_message(name.clone());
        let mut row = counterfactual(loaded, window, name, &change, &seeds, &bar);
        if row.refused.is_none() {
            let tally = tally(&row);
            if k == 0 {
                control = tally.clone();
            }
            row.verdict = if k > 0 {
                verdict(&control, &tally).into()
            } else if reproduced(control.reopened, control.members) {
                "control".into()
            } else {
                "not reproduced".into()
            };
        }
        rows.push(row);
    }
    bar.finish_and_clear();
    rows
}

fn tally(row: &CounterfactualRow) -> Tally {
    Tally {
        members: row.members.len(),
        reopened: row.reopened,
        blew_up: row.blew_up,
        moved: row.moved,
        injected: row.injected,
        next_kick: row.members.iter().map(|m| m.next_kick_after).collect(),
    }
}

fn counterfactual(
    loaded: &Loaded,
    window: Window,
    name: String,
    change: &Change,
    seeds: &[u64],
    bar: &ProgressBar,
) -> CounterfactualRow {
    let mut row = CounterfactualRow {
        change: name,
        refused: None,
        method_id: changed_method_id(loaded, change),
        members: vec![],
        reopened: 0,
        reopened_interval: [0.0, 1.0],
        blew_up: 0,
        moved: 0,
        injected: f64::NAN,
        floor: loaded.logged.evidence.energy_floor,
        next_kick: [None; 3],
        no_next_kick: 0,
        verdict: "refused".into(),
    };
    let replayed: Vec<Result<Member, String>> = seeds
        .par_iter()
        .map(|&seed| {
            // A member that panics refuses its row; the other rows and
            // the event's explanation are kept.
            let done = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                member(loaded, window, change, seed)
            }))
            .unwrap_or_else(|panic| Err(format!("the replay panicked: {}", panic_message(panic))));
            bar.inc(1);
            done
        })
        .collect();
    for r in replayed {
        match r {
            Ok(m) => row.members.push(m),
            Err(why) => {
                row.refused = Some(why);
                row.members.clear();
                return row;
            }
        }
    }
    summarise(&mut row);
    row
}

/// The row's counts and spreads from its members.
fn summarise(row: &mut CounterfactualRow) {
    let ms = &row.members;
    row.reopened = ms.iter().filter(|m| m.event_happens).count();
    row.reopened_interval = wilson(row.reopened, ms.len());
    row.blew_up = ms.iter().filter(|m| m.outcome != "completed").count();
    row.moved = ms.iter().filter(|m| !m.other_events.is_empty()).count();
    let injected: Vec<f64> = ms.iter().map(|m| m.injected).collect();
    row.injected = median_with_infinities(&injected).unwrap_or(f64::NAN);
    let next: Vec<f64> = ms.iter().filter_map(|m| m.next_kick_after).collect();
    row.no_next_kick = ms.len() - next.len();
    row.next_kick =
        spread(next.iter().copied()).map_or([None; 3], |(m, lo, hi)| [Some(m), Some(lo), Some(hi)]);
    row.verdict = String::new();
}

/// One member: the replay with its seed's jitter, and what it did.
fn member(loaded: &Loaded, window: Window, change: &Change, seed: u64) -> Result<Member, String> {
    let (measured, replay) = replay_with_change(loaded, window, change, seed)?;
    let logged = &loaded.logged;
    let after =
        |e: &&Event| e.first_step > replay.switched_at + 1 && e.t <= window_end(window) + 1e-12;
    let near = region(logged.cells);
    let next_kick_after = replay
        .simulated
        .events
        .iter()
        .filter(after)
        .filter(|e| e.is_kick() && overlaps(e.cells, near))
        .map(|e| e.t - logged.t)
        .reduce(f64::min);
    let other_events = replay
        .simulated
        .events
        .iter()
        .filter(after)
        .filter(|e| e.cause != Cause::Impact)
        .filter(|e| !(e.kind == logged.kind && overlaps(e.cells, logged.cells)))
        .map(|e| format!("{} ({}) at {:.4} s", e.kind.name(), e.cause.name(), e.t))
        .collect();
    let blew_up = replay.simulated.status == Status::BlewUp;
    Ok(Member {
        seed,
        event_happens: measured.happens,
        next_kick_after,
        injected: measured.injected,
        steps: replay.steps,
        outcome: if blew_up {
            format!("blew up: {}", replay.simulated.reason)
        } else {
            "completed".into()
        },
        other_events,
    })
}

/// The replays' end: `AFTER_SECONDS` past the event's last step.
pub fn window_end(window: Window) -> f64 {
    window.last_t + AFTER_SECONDS
}

/// How a replay ran: what it simulated, its steps, and the step of its
/// switch (events at the switch's own step are not counted: a new transfer
/// counts the kinetic energy and the transfer loss its own way from there,
/// and the budget's step at the switch reads as an injection).
struct ChangedReplay {
    simulated: Simulated,
    steps: u64,
    switched_at: u64,
}

/// The method a change switches to (None: the case's own), and how its
/// step is set.
fn switch_to(loaded: &Loaded, change: &Change) -> Result<(Option<Method>, StepRule), String> {
    let method = &loaded.case.solver.method;
    Ok(match change {
        Change::Overrides(o) if o.is_empty() => (None, StepRule::Keep),
        Change::Overrides(o) => (Some(changed_method(&loaded.study_path, o)?), StepRule::Keep),
        Change::HalfDt => (None, StepRule::Half),
        Change::RemediesOff if remedy_keys(method).is_empty() => {
            return Err("the method has no remedy to switch off".into())
        }
        Change::RemediesOff => {
            let m = Method {
                remedies: Default::default(),
                ..method.clone()
            };
            (Some(m), StepRule::Keep)
        }
        Change::PressureImplicit { at_run_dt } => (
            Some(pressure_implicit(method)),
            if *at_run_dt {
                StepRule::FixAtCurrent
            } else {
                StepRule::Keep
            },
        ),
    })
}

/// Replays the event's window from its checkpoint, the particles moved by
/// the member's jitter, with `change` made at `window.switch_from`.
fn replay_with_change(
    loaded: &Loaded,
    window: Window,
    change: &Change,
    seed: u64,
) -> Result<(Measured, ChangedReplay), String> {
    let (method, step_rule) = switch_to(loaded, change)?;
    let case = &loaded.case;
    let mut config = case.solver.clone();
    // The window may end after the case did.
    config.scene.t_end = config.scene.t_end.max(window_end(window));
    let solver = Solver::new(config).map_err(|e| format!("setup: {e}"))?;
    let mut watches = watches(&solver, case);
    let mut stepper = Switching {
        solver,
        at: window.switch_from,
        until: window_end(window),
        method,
        step_rule,
        refused: None,
        switched_at: None,
    };
    stepper
        .load(&loaded.checkpoint, &mut watches)
        .map_err(|e| e.to_string())?;
    let jitter = match case.solver.scene.jitter {
        j if j > 0.0 => j,
        _ => ENSEMBLE_JITTER,
    };
    stepper.solver.jitter(jitter, seed);
    let start = stepper.step_count();
    let mut measured = Measured {
        min: f64::INFINITY,
        injected: 0.0,
        happens: false,
    };
    // A change whose step collapses stops as a blow-up, as a case does,
    // instead of crawling to the window's end (not under a floor).
    let mut opts = RunOptions::new(None, Rows::every_step());
    let floored = [Some(&case.solver.method), stepper.method.as_ref()]
        .into_iter()
        .flatten()
        .find(|m| m.dt_min.is_some())
        .unwrap_or(&case.solver.method);
    opts.collapse_from = crate::run::collapse_reference(stepper.solver.next_dt(), floored);
    let mut runner = Runner::new(stepper, watches, opts);
    runner.attach(WindowInjection {
        from: window.switch_from,
        until: window_end(window),
        logged: &loaded.logged,
        measured: &mut measured,
    });
    let ran = runner.run();
    let steps = runner.stepper().step_count().saturating_sub(start);
    let why_refused = runner.stepper().refused.clone();
    let switched_at = runner.stepper().switched_at.unwrap_or(start);
    drop(runner);
    if let Some(why) = why_refused {
        return Err(why);
    }
    let simulated = ran.map_err(|e| e.to_string())?;
    let replay = ChangedReplay {
        simulated,
        steps,
        switched_at,
    };
    Ok((measured, replay))
}

/// The case's method with `overrides` applied to its study file.
fn changed_method(study_path: &Path, overrides: &[String]) -> Result<Method, String> {
    let study = study_file::load(study_path, overrides).map_err(|e| e.to_string())?;
    Ok(study.cases[0].solver.method.clone())
}

/// The changed method's identity, when the study file can state it: the
/// overrides, or the remedies switched off by their keys (the
/// pressure-implicit rows also set the formulation; at the run's own dt,
/// and with a halved dt, the step is not a study-file value).
fn changed_method_id(loaded: &Loaded, change: &Change) -> Option<String> {
    let off: Vec<String> = remedy_keys(&loaded.case.solver.method)
        .iter()
        .map(|k| format!("method.{k}=false"))
        .collect();
    let overrides: Vec<String> = match change {
        Change::Overrides(o) => o.clone(),
        Change::RemediesOff => off,
        Change::PressureImplicit { at_run_dt: false } => {
            let mut o = off;
            o.push("method.formulation=\"pressure_implicit\"".into());
            o
        }
        Change::HalfDt | Change::PressureImplicit { at_run_dt: true } => return None,
    };
    let study = study_file::load(&loaded.study_path, &overrides).ok()?;
    let params = study.cases[0]
        .params
        .iter()
        .map(|(k, v)| (k.clone(), toml_to_json(v)))
        .collect();
    Some(method_id(&params))
}

/// With members in parallel on the pool of `threads`.
pub(super) fn run(
    loaded: &Loaded,
    window: Window,
    members: usize,
    threads: Option<usize>,
) -> std::io::Result<Vec<CounterfactualRow>> {
    with_threads(threads, || Ok(counterfactuals(loaded, window, members)))
}

/// The rows as a Markdown table (`counterfactual.md`).
pub fn markdown(rows: &[CounterfactualRow]) -> String {
    let mut s = String::from("| change | reopened (95 % interval) | next kick in its region, s after the event: median [min, max] (none) | median injected (J/m) | blew up | other events | verdict |\n|---|---|---|---|---|---|---|\n");
    let t = |v: Option<f64>| v.map_or("-".into(), |x| format!("{x:.3}"));
    for r in rows {
        if let Some(why) = &r.refused {
            s += &format!("| {} | - | - | - | - | - | refused: {why} |\n", r.change);
            continue;
        }
        let n = r.members.len();
        s += &format!(
            "| {} | {} of {n} [{:.2}, {:.2}] | {} [{}, {}] ({}) | {:.3e} | {} | {} | {} |\n",
            r.change,
            r.reopened,
            r.reopened_interval[0],
            r.reopened_interval[1],
            t(r.next_kick[0]),
            t(r.next_kick[1]),
            t(r.next_kick[2]),
            r.no_next_kick,
            r.injected,
            r.blew_up,
            r.moved,
            r.verdict
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tally(reopened: usize, next: &[Option<f64>]) -> Tally {
        Tally {
            members: 5,
            reopened,
            injected: 0.5,
            next_kick: next.to_vec(),
            ..Tally::default()
        }
    }

    #[test]
    fn a_change_prevents_only_a_reproduced_event_it_does_not_move_hasten_or_hide() {
        let at = |t: f64| [Some(t); 5].to_vec();
        let control = Tally {
            injected: 1.0,
            ..tally(5, &at(0.0))
        };
        let none = [None; 5].to_vec();
        assert_eq!(verdict(&control, &tally(0, &none)), "prevented");
        assert_eq!(verdict(&control, &tally(1, &none)), "prevented");
        assert_eq!(verdict(&control, &tally(2, &none)), "undecided");
        assert_eq!(verdict(&control, &tally(3, &none)), "undecided");
        assert_eq!(verdict(&control, &tally(4, &at(0.0))), "again");
        // Within 5 ms of the control's range: the same time; beyond it, not.
        assert_eq!(verdict(&control, &tally(5, &at(0.004))), "again");
        assert_eq!(verdict(&control, &tally(5, &at(0.006))), "delayed");
        assert_eq!(verdict(&control, &tally(5, &at(-0.006))), "hastened");
        // A refused control (no members) decides nothing.
        assert_eq!(verdict(&Tally::default(), &tally(0, &none)), "undecided");
        assert_eq!(verdict(&control, &tally(5, &at(0.1))), "delayed");
        assert_eq!(verdict(&control, &tally(5, &at(-0.01))), "hastened");
        let with = |f: &dyn Fn(&mut Tally)| {
            let mut t = tally(0, &none);
            f(&mut t);
            verdict(&control, &t)
        };
        assert_eq!(with(&|t| t.blew_up = 1), "blew up");
        assert_eq!(with(&|t| t.moved = 2), "moved");
        assert_eq!(with(&|t| t.injected = 1.0), "injected");
        assert_eq!(with(&|t| t.injected = f64::NAN), "injected");
        // A control that reopens in 3 of 5 decides nothing.
        assert_eq!(verdict(&tally(3, &at(0.0)), &tally(0, &none)), "undecided");
        // A member with no next kick reads as later than any time.
        let spread = [Some(0.0), Some(0.01), Some(0.02), Some(0.0), Some(0.01)].to_vec();
        let late = [Some(0.01), None, None, None, Some(0.0)].to_vec();
        assert_eq!(verdict(&tally(5, &spread), &tally(5, &late)), "delayed");
    }

    #[test]
    fn reproduced_and_rare_are_shares_of_the_members() {
        assert!(reproduced(4, 5) && !reproduced(3, 5));
        assert!(reproduced(3, 3) && !reproduced(2, 3));
        assert!(rare(1, 5) && !rare(2, 5));
        assert!(rare(0, 3) && !rare(1, 3));
    }
}
