//! The one run loop. A `Stepper` (one solver, or a mixture of two phases)
//! is stepped under one `Watch` per phase (its monitor and timeseries);
//! `Probe`s attach to the loop: particle files, the checkpoint ring, event
//! frames, a replay's checks and the verification checks. Each probe writes
//! its own files and its own part of the summary. `kick run`, `matrix`,
//! `reproduce` and `bench` all drive this loop.

pub mod case;
pub mod checkpoint;
pub mod matrix;
pub mod mixture;
pub mod probes;
pub mod slurm;
pub mod stepper;
pub mod watch;

pub use stepper::Stepper;
pub use watch::Watch;

use crate::output::summary::{Metrics, PhaseSummary, Status};
use indicatif::ProgressBar;
use monitor::Event;
use std::path::PathBuf;
use std::time::Instant;

/// What a probe sees: the stepper and the phases' watches (read-only).
pub struct Run<'a, S> {
    pub stepper: &'a S,
    pub watches: &'a [Watch],
}

impl<S: Stepper> Run<'_, S> {
    pub fn step(&self) -> u64 {
        self.stepper.step_count()
    }
}

/// Something attached to the run loop. Every hook has a no-op default.
pub trait Probe<S: Stepper> {
    /// Once, after the first timeseries row (step 0, or the restored step).
    fn begin(&mut self, _run: &Run<S>) -> std::io::Result<()> {
        Ok(())
    }

    /// Events opened this step: the checkpoint that precedes them, kept
    /// for good (the checkpoint ring answers; the first answer is used).
    fn pin_checkpoint(&mut self) -> Option<String> {
        None
    }

    /// After a step that ran (the monitors may still stop the run there);
    /// `opened`: the ids of the events opened by it.
    fn after_step(&mut self, _run: &Run<S>, _opened: &[u32]) -> std::io::Result<()> {
        Ok(())
    }

    /// A timeseries row was written at this step.
    fn row(&mut self, _run: &Run<S>) {}

    /// The run goes on after this step.
    fn between_steps(&mut self, _run: &Run<S>) -> std::io::Result<()> {
        Ok(())
    }

    /// This probe's check has its answer and the run may end here (with
    /// `RunOptions::end_when_checked`): why, for the summary's reason.
    fn ends_run(&self) -> Option<String> {
        None
    }

    /// The run ended: the last files, and this probe's part of the outcome.
    fn finish(&mut self, _run: &Run<S>, _outcome: &mut Simulated) -> std::io::Result<()> {
        Ok(())
    }
}

/// When timeseries rows are written.
#[derive(Clone, Copy, Debug)]
pub struct Rows {
    /// When the regular rows come (plus one at each step that opens an
    /// event or stops the run).
    pub cadence: Cadence,
    /// Mark rows written only for an event or the stop (`event_row`).
    pub mark_event_rows: bool,
}

#[derive(Clone, Copy, Debug)]
pub enum Cadence {
    /// Every this many steps.
    Steps(u64),
    /// At each step that crosses a multiple of this simulated time (s).
    Time(f64),
}

impl Rows {
    /// About `rows` rows over a run to `t_end` at the first step's dt.
    pub fn spread(rows: u64, t_end: f64, first_dt: f64) -> Self {
        let expected_steps = (t_end / first_dt).ceil().max(1.0) as u64;
        Rows {
            cadence: Cadence::Steps((expected_steps / rows).max(1)),
            mark_event_rows: true,
        }
    }

    /// About `rows` rows over a run to `t_end`, evenly in simulated time:
    /// for a step that follows the flow, whose first (water at rest, the
    /// gravity-wave limit) can be 15 times the flow's, so that rows spread
    /// by it came at every step (24 738 rows and their field metrics for
    /// the 1000 asked, at h = 0.25 cm).
    pub fn spread_in_time(rows: u64, t_end: f64) -> Self {
        Rows {
            cadence: Cadence::Time(t_end / rows.max(1) as f64),
            mark_event_rows: true,
        }
    }

    /// A row after every step (a replay's dense output).
    pub fn every_step() -> Self {
        Rows {
            cadence: Cadence::Steps(1),
            mark_event_rows: false,
        }
    }

    /// Whether a step from `t_before` to `t_after`, numbered `step`, takes a regular row.
    fn regular(&self, step: u64, t_before: f64, t_after: f64) -> bool {
        match self.cadence {
            Cadence::Steps(every) => step.is_multiple_of(every),
            Cadence::Time(interval) => (t_after / interval).floor() > (t_before / interval).floor(),
        }
    }
}

/// A time step below this share of the first, held for `COLLAPSE_STEPS`
/// steps in a row, has collapsed: no stable run's step falls that far
/// (Uintah's per-axis first step is sqrt(gamma) = 2.65 times its next at
/// gamma = 7; a surge adds |v| to c), while a blow-out's runaway particles
/// shrink it by orders of magnitude; one that leaves the box within the
/// steps lets the run go on.
pub const COLLAPSE_SHARE: f64 = 0.01;
pub const COLLAPSE_STEPS: u64 = 20_000;

/// The step a run's collapse is judged against (`RunOptions::collapse_from`):
/// `first_dt`, unless the method holds a floor (`method.dt_min`). A floor
/// raises the stable step instead of letting it shrink, as Uintah's
/// `delt_min` does, so a step at the floor has not collapsed: the run goes
/// on, as Uintah's does, until a monitor calls a blow-out or it ends.
pub fn collapse_reference(first_dt: f64, method: &solver::Method) -> Option<f64> {
    method.dt_min.is_none().then_some(first_dt)
}

pub struct RunOptions {
    /// Where the timeseries tables go (none are written without it).
    pub dir: Option<PathBuf>,
    pub rows: Rows,
    /// Also write the timeseries as CSV.
    pub csv: bool,
    /// Stop after this step even if t_end is not reached.
    pub until_step: Option<u64>,
    /// The run's first time step: a run whose step stays below
    /// `COLLAPSE_SHARE` of it for `COLLAPSE_STEPS` steps in a row has
    /// collapsed its time step and stops as blown up (None: never).
    pub collapse_from: Option<f64>,
    /// Stop when a monitor calls a blow-out (a benchmark only records it).
    pub stop_on_blow_out: bool,
    /// End the run once a probe's check has its answer (`Probe::ends_run`).
    pub end_when_checked: bool,
    /// Progress bar to drive (its position in thousandths of t_end).
    pub bar: Option<ProgressBar>,
}

impl RunOptions {
    pub fn new(dir: Option<PathBuf>, rows: Rows) -> Self {
        RunOptions {
            dir,
            rows,
            csv: false,
            until_step: None,
            collapse_from: None,
            stop_on_blow_out: true,
            end_when_checked: false,
            bar: None,
        }
    }
}

/// Seconds spent in the solver's steps, the monitors' observation and
/// the timeseries rows (field metrics), for `kick bench`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Clock {
    pub solver_s: f64,
    pub monitor_s: f64,
    pub rows_s: f64,
}

/// What a run produced, for its summary.
#[derive(Clone, Debug)]
pub struct Simulated {
    pub status: Status,
    pub reason: String,
    pub steps: u64,
    pub t_end: f64,
    pub particles: usize,
    pub final_hash: u64,
    pub events: Vec<Event>,
    pub metrics: Metrics,
    pub phases: Vec<PhaseSummary>,
    /// The first blow-out a monitor called (also when it did not stop the run).
    pub first_blow_out: Option<String>,
}

impl Simulated {
    pub fn failed(reason: String) -> Self {
        Simulated {
            status: Status::Failed,
            reason,
            steps: 0,
            t_end: 0.0,
            particles: 0,
            final_hash: 0,
            events: vec![],
            metrics: Metrics::default(),
            phases: vec![],
            first_blow_out: None,
        }
    }
}

/// The stepper, its watches and probes, stepped together.
pub struct Runner<'p, S: Stepper> {
    pub stepper: S,
    pub watches: Vec<Watch>,
    probes: Vec<Box<dyn Probe<S> + 'p>>,
    opts: RunOptions,
    pub clock: Clock,
    last_row_step: Option<u64>,
    first_blow_out: Option<String>,
}

/// How one step ended.
struct Stepped {
    /// The step itself ran (the monitors observed it).
    ran: bool,
    opened: Vec<u32>,
    stop: Option<String>,
}

impl<'p, S: Stepper> Runner<'p, S> {
    pub fn new(stepper: S, watches: Vec<Watch>, opts: RunOptions) -> Self {
        Runner {
            stepper,
            watches,
            probes: vec![],
            opts,
            clock: Clock::default(),
            last_row_step: None,
            first_blow_out: None,
        }
    }

    pub fn options(&self) -> &RunOptions {
        &self.opts
    }

    /// The stepper and its watches, once the run is over.
    pub fn into_parts(self) -> (S, Vec<Watch>) {
        (self.stepper, self.watches)
    }

    /// Attaches a probe; probes are called in the order they were attached.
    /// The stepper being run.
    pub fn stepper(&self) -> &S {
        &self.stepper
    }

    pub fn attach(&mut self, probe: impl Probe<S> + 'p) -> &mut Self {
        self.probes.push(Box::new(probe));
        self
    }

    /// Steps to t_end (or `until_step`, or a stop), then finishes every probe.
    pub fn run(&mut self) -> std::io::Result<Simulated> {
        self.row(false);
        self.each(|p, run| p.begin(run))?;
        let mut collapsed_since: Option<u64> = None;
        let (status, reason) = loop {
            let limit = self.opts.until_step;
            if self.stepper.finished() || limit.is_some_and(|n| self.stepper.step_count() >= n) {
                break (Status::Completed, String::new());
            }
            let stepped = self.step()?;
            if let Some(reason) = stepped.stop {
                break (Status::BlewUp, reason);
            }
            if let Some(first) = self.opts.collapse_from {
                let dt = self.stepper.phase(self.stepper.primary_phase()).next_dt();
                let step = self.stepper.step_count();
                if dt >= COLLAPSE_SHARE * first {
                    collapsed_since = None;
                } else if step + 1 - *collapsed_since.get_or_insert(step) >= COLLAPSE_STEPS {
                    break (
                        Status::BlewUp,
                        format!(
                            "time step collapsed: below {COLLAPSE_SHARE} of the first ({first:.3e} s) for {COLLAPSE_STEPS} steps, {dt:.3e} s at t = {:.4} s",
                            self.stepper.time()
                        ),
                    );
                }
            }
            self.each(|p, run| p.between_steps(run))?;
            if self.opts.end_when_checked {
                if let Some(reason) = self.probes.iter().find_map(|p| p.ends_run()) {
                    break (Status::Completed, reason);
                }
            }
        };
        self.row(status != Status::Completed);
        self.finish(status, reason)
    }

    fn each(
        &mut self,
        mut hook: impl FnMut(&mut dyn Probe<S>, &Run<S>) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        let run = Run {
            stepper: &self.stepper,
            watches: &self.watches,
        };
        for p in self.probes.iter_mut() {
            hook(p.as_mut(), &run)?;
        }
        Ok(())
    }

    fn step(&mut self) -> std::io::Result<Stepped> {
        let t_before = self.stepper.time();
        let t0 = Instant::now();
        let advanced = self.stepper.advance();
        self.clock.solver_s += t0.elapsed().as_secs_f64();
        let mut stepped = Stepped {
            ran: advanced.is_ok(),
            opened: vec![],
            stop: advanced.err(),
        };
        if stepped.ran {
            let t1 = Instant::now();
            self.observe(&mut stepped);
            self.clock.monitor_s += t1.elapsed().as_secs_f64();
            let opened = std::mem::take(&mut stepped.opened);
            self.each(|p, run| p.after_step(run, &opened))?;
            stepped.opened = opened;
        }
        let step = self.stepper.step_count();
        let regular = self.opts.rows.regular(step, t_before, self.stepper.time());
        let stopping = stepped.stop.is_some();
        if regular || !stepped.opened.is_empty() || stopping {
            self.row(self.opts.rows.mark_event_rows && (!regular || stopping));
            self.show_progress();
        }
        Ok(stepped)
    }

    /// Each phase's monitor observes the step; events opened are stamped
    /// with the phase, the state hash and the checkpoint before them.
    fn observe(&mut self, stepped: &mut Stepped) {
        let step = self.stepper.step_count();
        let mut opened = [0usize; 2];
        for (k, w) in self.watches.iter_mut().enumerate() {
            let (n, blow_out) = w.observe(&self.stepper.phase(k).view());
            opened[k] = n;
            if let Some(r) = blow_out {
                let reason = match self.stepper.phase_name(k) {
                    Some(phase) => format!("{phase} phase, step {step}: {r}"),
                    None => format!("step {step}: {r}"),
                };
                self.first_blow_out.get_or_insert(reason.clone());
                if self.opts.stop_on_blow_out {
                    stepped.stop.get_or_insert(reason);
                }
            }
        }
        if opened.iter().all(|&n| n == 0) {
            return;
        }
        let hash = format!("{:016x}", self.stepper.state_hash());
        let checkpoint = self.probes.iter_mut().find_map(|p| p.pin_checkpoint());
        for (k, w) in self.watches.iter_mut().enumerate() {
            let phase = self.stepper.phase_name(k);
            let ids = w.stamp_latest(opened[k], phase, &hash, checkpoint.as_deref());
            stepped.opened.extend(ids);
        }
    }

    /// A row at the current step in every watch, once per step.
    fn row(&mut self, event_row: bool) {
        let step = self.stepper.step_count();
        if self.last_row_step == Some(step) {
            return;
        }
        self.last_row_step = Some(step);
        let t0 = Instant::now();
        for (k, w) in self.watches.iter_mut().enumerate() {
            w.push_row(&self.stepper.phase(k).view(), event_row);
        }
        self.clock.rows_s += t0.elapsed().as_secs_f64();
        let run = Run {
            stepper: &self.stepper,
            watches: &self.watches,
        };
        for p in self.probes.iter_mut() {
            p.row(&run);
        }
    }

    fn show_progress(&self) {
        let Some(bar) = &self.opts.bar else { return };
        let t = self.stepper.time();
        let t_end = self.stepper.phase(0).view().scene.t_end;
        bar.set_position((1000.0 * t / t_end) as u64);
        let events: usize = self.watches.iter().map(|w| w.monitor.events().len()).sum();
        bar.set_message(format!("t = {t:.3} s, {events} events"));
    }

    /// The watches' tables and figures, then each probe's part.
    fn finish(&mut self, status: Status, reason: String) -> std::io::Result<Simulated> {
        let completed = status == Status::Completed;
        let mut outcome = Simulated {
            status,
            reason,
            steps: self.stepper.step_count(),
            t_end: self.stepper.time(),
            particles: 0,
            final_hash: self.stepper.state_hash(),
            events: vec![],
            metrics: Metrics::default(),
            phases: vec![],
            first_blow_out: self.first_blow_out.clone(),
        };
        watch::summarise(
            &self.stepper,
            &self.watches,
            &self.opts,
            completed,
            &mut outcome,
        )?;
        let run = Run {
            stepper: &self.stepper,
            watches: &self.watches,
        };
        for p in self.probes.iter_mut() {
            p.finish(&run, &mut outcome)?;
        }
        Ok(outcome)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::probes::checkpoint_ring::{ring_name, ring_step, CheckpointRing};
    use monitor::MonitorConfig;
    use solver::{ShapeKind, Solver, SolverConfig, TransferKind};

    fn solver() -> Solver {
        let cfg = SolverConfig::benchmark_dam_break(ShapeKind::Linear, TransferKind::Flip, 0.02);
        Solver::new(cfg).unwrap()
    }

    #[test]
    fn under_a_step_floor_no_step_is_judged_collapsed() {
        let mut method = solver().config().method.clone();
        assert_eq!(collapse_reference(2e-3, &method), Some(2e-3));
        // drop.ups's delt_min: a step held there is 0.005 of the first.
        method.dt_min = Some(1e-5);
        assert_eq!(collapse_reference(2e-3, &method), None);
    }

    fn runner<'p>(until: u64, rows_every: u64) -> Runner<'p, Solver> {
        let s = solver();
        let watch = Watch::new(MonitorConfig::default(), &s.view());
        let mut opts = RunOptions::new(
            None,
            Rows {
                cadence: Cadence::Steps(rows_every),
                mark_event_rows: true,
            },
        );
        opts.until_step = Some(until);
        Runner::new(s, vec![watch], opts)
    }

    /// Counts each hook's calls.
    #[derive(Default)]
    struct Calls {
        begin: usize,
        after_step: usize,
        rows: usize,
        between: usize,
        finish: usize,
    }

    impl Probe<Solver> for &mut Calls {
        fn begin(&mut self, run: &Run<Solver>) -> std::io::Result<()> {
            assert_eq!(run.watches[0].series.step.len(), 1, "after the first row");
            self.begin += 1;
            Ok(())
        }
        fn after_step(&mut self, _: &Run<Solver>, _: &[u32]) -> std::io::Result<()> {
            self.after_step += 1;
            Ok(())
        }
        fn row(&mut self, _: &Run<Solver>) {
            self.rows += 1;
        }
        fn between_steps(&mut self, _: &Run<Solver>) -> std::io::Result<()> {
            self.between += 1;
            Ok(())
        }
        fn finish(&mut self, run: &Run<Solver>, outcome: &mut Simulated) -> std::io::Result<()> {
            assert_eq!(outcome.steps, run.step());
            self.finish += 1;
            Ok(())
        }
    }

    /// Rows spread in time come at even times whatever the step does: a
    /// step that shrinks fifteenfold after the first (the pressure-implicit
    /// step from rest into the flow) still gives the rows asked for, where
    /// spreading by the first step's count gave one at every step.
    #[test]
    fn rows_spread_in_time_follow_the_clock_not_the_step_count() {
        let (t_end, rows) = (5.0, 1000u64);
        let in_time = Rows::spread_in_time(rows, t_end);
        let by_first_step = Rows::spread(rows, t_end, 3.2e-3);
        let (mut t, mut step) = (0.0f64, 0u64);
        let (mut timed, mut counted) = (0u64, 0u64);
        while t < t_end {
            let dt = if step == 0 { 3.2e-3 } else { 2.1e-4 };
            let before = t;
            t = (t + dt).min(t_end);
            step += 1;
            timed += in_time.regular(step, before, t) as u64;
            counted += by_first_step.regular(step, before, t) as u64;
        }
        assert!((rows - 1..=rows).contains(&timed), "{timed} rows in time");
        assert_eq!(counted, step, "one row a step");
    }

    /// Every hook is called as documented: one row at the start, one per
    /// `every` steps (the last one not repeated at the end), a step hook
    /// per step, and the run ends at `until_step`.
    #[test]
    fn hooks_are_called_once_per_their_occasion() {
        let mut calls = Calls::default();
        let mut r = runner(30, 10);
        r.attach(&mut calls);
        let outcome = r.run().unwrap();
        assert_eq!(outcome.status, Status::Completed);
        assert_eq!(outcome.steps, 30);
        assert_eq!(r.watches[0].series.step, [0, 10, 20, 30]);
        drop(r);
        assert_eq!(
            (
                calls.begin,
                calls.after_step,
                calls.rows,
                calls.between,
                calls.finish
            ),
            (1, 30, 4, 30, 1)
        );
    }

    /// A time step held below 1 % of the first for COLLAPSE_STEPS steps
    /// stops the run as blown up at exactly that step; a run whose step
    /// stays near its first goes on.
    #[test]
    fn a_collapsed_time_step_stops_the_run() {
        let mut r = runner(COLLAPSE_STEPS + 100, 1000);
        let dt = r.stepper.next_dt();
        r.opts.collapse_from = Some(1000.0 * dt);
        let out = r.run().unwrap();
        assert_eq!(out.status, Status::BlewUp);
        assert!(
            out.reason.starts_with("time step collapsed"),
            "{}",
            out.reason
        );
        assert_eq!(out.steps, COLLAPSE_STEPS);
        let mut r = runner(200, 100);
        r.opts.collapse_from = Some(dt);
        assert_eq!(r.run().unwrap().status, Status::Completed);
    }

    /// Besides step 0 and the 3 newest, the ring keeps the latest checkpoint
    /// at least `keep_seconds` older than the newest (where an event's quiet
    /// window would start), and no older one.
    #[test]
    fn the_ring_keeps_a_checkpoint_from_before_the_quiet_window() {
        let dir = std::env::temp_dir().join(format!("kick-ring-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut r = runner(60, 10);
        let keep = 22.0 * r.stepper.next_dt();
        r.attach(CheckpointRing::new(dir.clone(), 5, keep));
        r.run().unwrap();
        let mut kept: Vec<(u64, f64)> = std::fs::read_dir(dir.join("checkpoints"))
            .unwrap()
            .map(|e| {
                let bytes = std::fs::read(e.unwrap().path()).unwrap();
                crate::run::checkpoint::clock(&bytes).unwrap()
            })
            .collect();
        kept.sort_by_key(|k| k.0);
        let steps: Vec<u64> = kept.iter().map(|k| k.0).collect();
        assert_eq!(steps[0], 0);
        assert_eq!(ring_step(&ring_name(steps[1])), Some(steps[1]));
        assert_eq!(&steps[steps.len() - 3..], [50, 55, 60]);
        let newest = kept.last().unwrap().1;
        let (early, next) = (kept[1], kept[2]);
        assert!(early.1 <= newest - keep, "{kept:?}");
        assert!(next.1 > newest - keep, "{kept:?}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A run restarted from a ring checkpoint continues bit for bit: the
    /// same state hash, events and timeseries rows as the run it came from.
    #[test]
    fn a_restart_from_the_ring_continues_bit_for_bit() {
        let dir = std::env::temp_dir().join(format!("kick-runner-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut whole = runner(60, 10);
        whole.attach(CheckpointRing::new(dir.clone(), 20, 0.0));
        let a = whole.run().unwrap();
        let bytes = std::fs::read(dir.join(ring_name(40))).unwrap();
        let mut resumed = runner(60, 10);
        let (stepper, watches) = (&mut resumed.stepper, &mut resumed.watches);
        stepper.load(&bytes, watches).unwrap();
        assert_eq!(resumed.stepper.step_count(), 40);
        let b = resumed.run().unwrap();
        assert_eq!(a.final_hash, b.final_hash);
        assert_eq!(a.events, b.events);
        let (sa, sb) = (&whole.watches[0].series, &resumed.watches[0].series);
        assert_eq!(sb.step, [40, 50, 60]);
        for (ca, cb) in sa.columns.iter().zip(&sb.columns) {
            let (ta, tb) = (&ca[ca.len() - 2..], &cb[1..]);
            let same = ta.iter().zip(tb).all(|(x, y)| x.to_bits() == y.to_bits());
            assert!(same, "{ta:?} vs {tb:?}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
