//! One case end to end: the solver stepped under the monitor's eye, blow-up
//! as a result, timeseries rows, ring checkpoints (solver + monitor) with the
//! one preceding each event kept for good, VTK snapshots and summary.json,
//! every file written atomically.

use crate::case_checkpoint;
use crate::metrics;
use crate::output_files::write_atomic;
use crate::run_mixture;
use crate::snapshot::{self, Snapshot};
use crate::study_file::Case;
use crate::summary::{Metrics, PhaseSummary, Status, Summary, SCHEMA_VERSION};
use crate::tables;
use crate::timeseries::{Peaks, Timeseries};
use indicatif::{ProgressBar, ProgressStyle};
use monitor::{Event, Monitor};
use serde_json::{json, Value};
use solver::{Scene, Solver, StateView};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Ring checkpoints kept per case (besides the step-0 one and event ones).
const CHECKPOINT_RING: usize = 3;
/// Around an event, particle snapshots every EVENT_FRAME_EVERY steps,
/// EVENT_FRAMES before and after it, for the first EVENT_WINDOWS events.
const EVENT_FRAME_EVERY: u64 = 5;
const EVENT_FRAMES: usize = 4;
const EVENT_WINDOWS: usize = 8;

pub struct RunOptions {
    pub threads: Option<usize>,
    /// Progress bar to drive (hidden when None).
    pub bar: Option<ProgressBar>,
    /// Also write the timeseries as CSV.
    pub csv: bool,
}

/// What one step did.
pub enum Stepped {
    Ok,
    /// The run must stop: blown up, with the reason.
    Stop(String),
}

/// Solver and monitor stepped together, with the timeseries they feed.
pub struct Driver {
    pub solver: Solver,
    pub monitor: Monitor,
    pub series: Timeseries,
    peaks: Peaks,
}

impl Driver {
    pub fn new(case: &Case) -> Result<Self, String> {
        let solver = Solver::new(case.solver.clone()).map_err(|e| format!("setup: {e}"))?;
        let monitor = Monitor::new(case.monitor.clone(), &solver.view());
        Ok(Driver {
            solver,
            monitor,
            series: Timeseries::new(),
            peaks: Peaks::default(),
        })
    }

    /// One solver step observed by the monitor.
    pub fn step(&mut self) -> Stepped {
        if let Err(e) = self.solver.step() {
            return Stepped::Stop(format!("step {}: {e}", self.solver.step_count() + 1));
        }
        // The monitor is serial: keep the other worker awake for the next step.
        let (monitor, view) = (&mut self.monitor, self.solver.view());
        solver::par::keep_warm(|| {
            monitor.observe(&view);
        });
        let report = self.monitor.report();
        self.peaks.add(report);
        match &report.blow_out {
            Some(reason) => Stepped::Stop(format!("step {}: {reason}", report.step)),
            None => Stepped::Ok,
        }
    }

    /// A timeseries row at the current step (field metrics computed now);
    /// `event_row` when it is written only because of an event.
    pub fn push_row(&mut self, event_row: bool) {
        if self.series.last_step() == Some(self.solver.step_count()) {
            return;
        }
        let v = self.solver.view();
        let fields = self.monitor.field_metrics(&v);
        let mut report = self.monitor.report().clone();
        if v.step == 0 || report.step != v.step {
            // Before the first observed step: energies from the state itself.
            report = monitor::StepReport::of_state(&v);
        }
        self.series.push(&report, &self.peaks, &fields, event_row);
        self.peaks = Peaks::default();
    }
}

/// Where the surge front meets the far wall (Z units), for dam-break scenes:
/// one body standing on the floor against the left wall, narrower than the box.
pub fn front_wall_z(scene: &Scene) -> Option<f64> {
    let [b] = scene.bodies.as_slice() else {
        return None;
    };
    let a = b.rect[2] - b.rect[0];
    let against_wall = (b.rect[0] - scene.origin[0]).abs() < 1e-9 * scene.size[0]
        && (b.rect[1] - scene.origin[1]).abs() < 1e-9 * scene.size[1];
    (against_wall && a < scene.size[0] && scene.gravity > 0.0).then(|| scene.size[0] / a)
}

/// Runs a case into `dir` and returns its summary (also written as summary.json).
/// Panics inside the solver become status "failed"; nothing else is lost.
pub fn run_case(case: &Case, dir: &Path, opts: &RunOptions) -> std::io::Result<Summary> {
    std::fs::create_dir_all(dir)?;
    write_atomic(
        &dir.join("case.toml"),
        toml::to_string(&case.table)
            .map_err(|e| std::io::Error::other(e.to_string()))?
            .as_bytes(),
    )?;
    let started = Instant::now();
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        with_threads(opts.threads, || match case.mixture {
            Some(_) => run_mixture::simulate(case, dir, opts),
            None => simulate(case, dir, opts),
        })
    }));
    let wall_s = started.elapsed().as_secs_f64();
    // ParaView's time series of what was written, however the run ended.
    snapshot::write_collections(&dir.join("particles"))?;
    let run = match outcome {
        Ok(r) => r?,
        Err(panic) => Simulated::failed(format!("panic: {}", panic_message(panic))),
    };
    let particle_steps = run.particles as f64 * run.steps as f64;
    let summary = Summary {
        schema_version: SCHEMA_VERSION,
        case: case.name.clone(),
        params: case
            .params
            .iter()
            .map(|(k, v)| (k.clone(), toml_to_json(v)))
            .collect(),
        status: run.status,
        reason: run.reason,
        steps: run.steps,
        t_end: run.t_end,
        wall_s,
        particles: run.particles,
        particle_steps_per_s: if wall_s > 0.0 {
            particle_steps / wall_s
        } else {
            0.0
        },
        final_state_hash: format!("{:016x}", run.final_hash),
        events: run.events,
        metrics: run.metrics,
        phases: run.phases,
    };
    summary.write(dir)?;
    Ok(summary)
}

/// Runs `f` inside a rayon pool of `threads` workers (default: all cores).
/// Always inside a pool: parallel loops called from a thread outside any pool
/// hand every loop to the global pool and wait, which costs more than the
/// loop itself on a small scene.
pub fn with_threads<T>(
    threads: Option<usize>,
    f: impl FnOnce() -> std::io::Result<T> + Send,
) -> std::io::Result<T>
where
    T: Send,
{
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n);
    }
    builder
        .build()
        .map_err(|e| std::io::Error::other(e.to_string()))?
        .install(f)
}

pub fn panic_message(panic: Box<dyn std::any::Any + Send>) -> String {
    panic
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "panic".into())
}

/// What a simulation produced, for its summary.
pub(crate) struct Simulated {
    pub status: Status,
    pub reason: String,
    pub steps: u64,
    pub t_end: f64,
    pub particles: usize,
    pub final_hash: u64,
    pub events: Vec<Event>,
    pub metrics: Metrics,
    pub phases: Vec<PhaseSummary>,
}

impl Simulated {
    pub(crate) fn failed(reason: String) -> Self {
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
        }
    }
}

/// A ring checkpoint's path relative to the case folder.
pub fn ring_name(step: u64) -> String {
    format!("checkpoints/ring_{step:09}.ckpt")
}

/// Ring checkpoints every `every` steps (plus step 0), the last
/// `CHECKPOINT_RING` kept, and any that precedes an event kept for good.
/// `save` gives the checkpoint's bytes (a case's solver and monitor, or a
/// mixture's phases and monitors).
pub(crate) struct CheckpointRing<'a> {
    dir: &'a Path,
    every: u64,
    ring: Vec<(u64, PathBuf)>,
    pinned: BTreeSet<u64>,
}

impl<'a> CheckpointRing<'a> {
    /// Writes the step-0 checkpoint, which precedes any event, even one at step 1.
    pub(crate) fn start(
        dir: &'a Path,
        every: u64,
        save: impl FnOnce() -> Vec<u8>,
    ) -> std::io::Result<Self> {
        let mut ring = CheckpointRing {
            dir,
            every,
            ring: vec![],
            pinned: BTreeSet::new(),
        };
        if every > 0 {
            ring.save(0, save())?;
        }
        Ok(ring)
    }

    fn save(&mut self, step: u64, bytes: Vec<u8>) -> std::io::Result<()> {
        let path = self.dir.join(ring_name(step));
        write_atomic(&path, &bytes)?;
        self.ring.push((step, path));
        Ok(())
    }

    /// The latest checkpoint (it precedes an event opened now), kept for good.
    pub(crate) fn pin_latest(&mut self) -> Option<String> {
        let (step, _) = self.ring.last()?;
        self.pinned.insert(*step);
        Some(ring_name(*step))
    }

    pub(crate) fn after_step(
        &mut self,
        step: u64,
        save: impl FnOnce() -> Vec<u8>,
    ) -> std::io::Result<()> {
        if self.every == 0 || !step.is_multiple_of(self.every) {
            return Ok(());
        }
        self.save(step, save())?;
        if self.ring.len() > CHECKPOINT_RING {
            let (old, path) = self.ring.remove(0);
            if !self.pinned.contains(&old) {
                let _ = std::fs::remove_file(path);
            }
        }
        Ok(())
    }
}

/// Particle frames around the first `EVENT_WINDOWS` events: every
/// `EVENT_FRAME_EVERY` steps, `EVENT_FRAMES` before (from a ring of recent
/// frames) to `EVENT_FRAMES` after, into `particles/event_K/`.
struct EventFrames {
    dir: PathBuf,
    recent: Vec<Snapshot>,
    next: usize,
    now: Snapshot,
    /// (event id, last step of its window)
    open: Vec<(u32, u64)>,
    opened: usize,
}

impl EventFrames {
    fn new(dir: PathBuf, particles: usize) -> Self {
        EventFrames {
            dir,
            recent: (0..EVENT_FRAMES)
                .map(|_| Snapshot::with_capacity(particles))
                .collect(),
            next: 0,
            now: Snapshot::with_capacity(particles),
            open: vec![],
            opened: 0,
        }
    }

    fn write(dir: &Path, id: u32, snap: &Snapshot) -> std::io::Result<()> {
        snapshot::write_file(&dir.join(format!("event_{id}")), "particles", snap)
    }

    /// Events `ids` opened at `step`: the recent frames and this one.
    fn opened(&mut self, ids: &[u32], v: &StateView, step: u64) -> std::io::Result<()> {
        self.now.capture(v);
        for &id in ids {
            if self.opened >= EVENT_WINDOWS {
                break;
            }
            self.opened += 1;
            for f in self
                .recent
                .iter()
                .filter(|f| !f.x.is_empty() && f.step < step)
            {
                Self::write(&self.dir, id, f)?;
            }
            Self::write(&self.dir, id, &self.now)?;
            self.open
                .push((id, step + EVENT_FRAME_EVERY * EVENT_FRAMES as u64));
        }
        Ok(())
    }

    fn after_step(&mut self, v: &StateView, step: u64) -> std::io::Result<()> {
        if !step.is_multiple_of(EVENT_FRAME_EVERY) {
            return Ok(());
        }
        let f = &mut self.recent[self.next];
        f.capture(v);
        self.next = (self.next + 1) % EVENT_FRAMES;
        self.open.retain(|&(_, until)| until >= step);
        for &(id, _) in &self.open {
            Self::write(&self.dir, id, f)?;
        }
        Ok(())
    }
}

/// Particle files at the study's times (`output.vtk_times`), in order.
struct VtkSchedule {
    dir: PathBuf,
    times: Vec<f64>,
    next: usize,
}

impl VtkSchedule {
    fn new(dir: PathBuf, mut times: Vec<f64>) -> Self {
        times.sort_by(f64::total_cmp);
        VtkSchedule {
            dir,
            times,
            next: 0,
        }
    }

    fn write(&self, s: &Solver) -> std::io::Result<()> {
        snapshot::write_file(&self.dir, "particles", &Snapshot::of(&s.view()))
    }

    /// Writes one file per time reached since the last call.
    fn catch_up(&mut self, s: &Solver) -> std::io::Result<()> {
        while self.next < self.times.len() && self.times[self.next] <= s.time() {
            self.write(s)?;
            self.next += 1;
        }
        Ok(())
    }
}

/// Stamps the events opened this step with the state hash and the
/// checkpoint before them; returns their ids.
fn stamp_new_events(d: &mut Driver, ring: &mut CheckpointRing, opened: usize) -> Vec<u32> {
    let hash = format!("{:016x}", d.solver.state_hash());
    let checkpoint = ring.pin_latest();
    let n = d.monitor.events().len();
    d.monitor.events_mut()[n - opened..]
        .iter_mut()
        .map(|e| {
            e.state_hash = Some(hash.clone());
            e.checkpoint = checkpoint.clone();
            e.id
        })
        .collect()
}

fn simulate(case: &Case, dir: &Path, opts: &RunOptions) -> std::io::Result<Simulated> {
    let mut d = match Driver::new(case) {
        Ok(d) => d,
        Err(reason) => return Ok(Simulated::failed(reason)),
    };
    let t_end = case.solver.scene.t_end;
    let expected_steps = (t_end / d.solver.next_dt()).ceil().max(1.0) as u64;
    let row_every = (expected_steps / case.output.timeseries_rows).max(1);
    let bar = opts.bar.clone().unwrap_or_else(ProgressBar::hidden);
    bar.set_length(1000);
    bar.set_prefix(case.name.clone());
    let particles_dir = dir.join("particles");
    let mut vtk = VtkSchedule::new(particles_dir.clone(), case.output.vtk_times.clone());
    let mut frames = EventFrames::new(particles_dir, d.solver.particle_count());
    vtk.catch_up(&d.solver)?;
    d.push_row(false);
    let mut ring = CheckpointRing::start(dir, case.output.checkpoint_every, || {
        case_checkpoint::save(&d.solver, &d.monitor)
    })?;
    let (status, reason) = loop {
        if d.solver.finished() {
            break (Status::Completed, String::new());
        }
        let stepped = d.step();
        let step = d.solver.step_count();
        let opened = d.monitor.report().events_opened;
        if opened > 0 {
            let ids = stamp_new_events(&mut d, &mut ring, opened);
            frames.opened(&ids, &d.solver.view(), step)?;
        }
        frames.after_step(&d.solver.view(), step)?;
        let regular = step % row_every == 0;
        let stopped = matches!(stepped, Stepped::Stop(_));
        if regular || opened > 0 || stopped {
            d.push_row(!regular || stopped);
            let t = d.solver.time();
            bar.set_position((1000.0 * t / t_end) as u64);
            bar.set_message(format!("t = {t:.3} s, {} events", d.monitor.events().len()));
        }
        if let Stepped::Stop(reason) = stepped {
            break (Status::BlewUp, reason);
        }
        vtk.catch_up(&d.solver)?;
        ring.after_step(step, || case_checkpoint::save(&d.solver, &d.monitor))?;
    };
    d.push_row(status != Status::Completed);
    vtk.write(&d.solver)?;
    tables::write_timeseries(&d.series, dir, opts.csv)?;
    let events = d.monitor.events().to_vec();
    let mut metrics = metrics::summarise(
        &d.series,
        &events,
        front_wall_z(&case.solver.scene),
        status == Status::Completed,
    );
    metrics.events_dropped = d.monitor.events_dropped();
    let losses = d.solver.losses();
    metrics.particles_escaped = losses.escaped;
    metrics.particles_inverted = losses.inverted;
    metrics.mass_lost_fraction = losses.mass() / d.monitor.initial_mass();
    metrics.t_first_loss = losses.t_first;
    Ok(Simulated {
        status,
        reason,
        steps: d.solver.step_count(),
        t_end: d.solver.time(),
        particles: d.solver.initial_particle_count(),
        final_hash: d.solver.state_hash(),
        metrics,
        events,
        phases: vec![],
    })
}

pub fn progress_style() -> ProgressStyle {
    ProgressStyle::with_template("{prefix:>24} [{elapsed_precise}] {wide_bar} {percent:>3}% {msg}")
        .expect("valid template")
}

pub fn toml_to_json(v: &toml::Value) -> Value {
    match v {
        toml::Value::String(s) => json!(s),
        toml::Value::Integer(i) => json!(i),
        toml::Value::Float(f) => json!(f),
        toml::Value::Boolean(b) => json!(b),
        toml::Value::Datetime(d) => json!(d.to_string()),
        toml::Value::Array(a) => Value::Array(a.iter().map(toml_to_json).collect()),
        toml::Value::Table(t) => Value::Object(
            t.iter()
                .map(|(k, v)| (k.clone(), toml_to_json(v)))
                .collect(),
        ),
    }
}
