//! One case end to end: the solver stepped under the monitor's eye, blow-up
//! as a result, timeseries rows, ring checkpoints (solver + monitor) with the
//! one preceding each event kept for good, VTK snapshots and summary.json,
//! every file written atomically.

use crate::case_checkpoint;
use crate::metrics;
use crate::output_files::write_atomic;
use crate::snapshot::Snapshot;
use crate::study_file::Case;
use crate::tables;
use crate::timeseries::{Peaks, Timeseries};
use indicatif::{ProgressBar, ProgressStyle};
use monitor::{Event, Monitor};
use serde_json::{json, Value};
use solver::{Scene, Solver};
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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    Completed,
    BlewUp,
    Failed,
}

impl Status {
    pub fn as_str(&self) -> &'static str {
        match self {
            Status::Completed => "completed",
            Status::BlewUp => "blew_up",
            Status::Failed => "failed",
        }
    }
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

    /// A timeseries row at the current step (field metrics computed now).
    pub fn push_row(&mut self) {
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
        self.series.push(&report, &self.peaks, &fields);
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
pub fn run_case(case: &Case, dir: &Path, opts: &RunOptions) -> std::io::Result<Value> {
    std::fs::create_dir_all(dir)?;
    write_atomic(
        &dir.join("case.toml"),
        toml::to_string(&case.table)
            .map_err(|e| std::io::Error::other(e.to_string()))?
            .as_bytes(),
    )?;
    let started = Instant::now();
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        with_threads(opts.threads, || simulate(case, dir, opts))
    }));
    let wall_s = started.elapsed().as_secs_f64();
    let run = match outcome {
        Ok(r) => r?,
        Err(panic) => Simulated::failed(format!("panic: {}", panic_message(panic))),
    };
    let params: serde_json::Map<String, Value> = case
        .params
        .iter()
        .map(|(k, v)| (k.clone(), toml_to_json(v)))
        .collect();
    let particle_steps = run.particles as f64 * run.steps as f64;
    let summary = json!({
        "case": case.name,
        "params": params,
        "status": run.status.as_str(),
        "reason": run.reason,
        "steps": run.steps,
        "t_end": run.t_end,
        "wall_s": wall_s,
        "particles": run.particles,
        "particle_steps_per_s": if wall_s > 0.0 { particle_steps / wall_s } else { 0.0 },
        "final_state_hash": format!("{:016x}", run.final_hash),
        "events": run.events,
        "metrics": run.metrics,
    });
    write_atomic(
        &dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
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

struct Simulated {
    status: Status,
    reason: String,
    steps: u64,
    t_end: f64,
    particles: usize,
    final_hash: u64,
    events: Vec<Event>,
    metrics: Value,
}

impl Simulated {
    fn failed(reason: String) -> Self {
        Simulated {
            status: Status::Failed,
            reason,
            steps: 0,
            t_end: 0.0,
            particles: 0,
            final_hash: 0,
            events: vec![],
            metrics: json!({}),
        }
    }
}

/// A ring checkpoint's path relative to the case folder.
pub fn ring_name(step: u64) -> String {
    format!("checkpoints/ring_{step:09}.ckpt")
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
    let mut vtk_times: Vec<f64> = case.output.vtk_times.clone();
    vtk_times.sort_by(f64::total_cmp);
    let mut next_vtk = 0;
    let particles_dir = dir.join("particles");
    let write_vtk = |s: &Solver| -> std::io::Result<()> {
        let v = s.view();
        write_atomic(
            &particles_dir.join(format!("particles_{:09}.vtk", v.step)),
            &Snapshot::of(&v).vtk(),
        )
    };
    let event_frame = |id: u32, snap: &Snapshot| -> std::io::Result<()> {
        write_atomic(
            &particles_dir
                .join(format!("event_{id}"))
                .join(format!("particles_{:09}.vtk", snap.step)),
            &snap.vtk(),
        )
    };
    let n = d.solver.particle_count();
    let mut ring_frames: Vec<Snapshot> = (0..EVENT_FRAMES)
        .map(|_| Snapshot::with_capacity(n))
        .collect();
    let mut frame_next = 0;
    let mut now = Snapshot::with_capacity(n);
    // (event id, last step of its window)
    let mut windows: Vec<(u32, u64)> = vec![];
    let mut windows_opened = 0;
    while next_vtk < vtk_times.len() && vtk_times[next_vtk] <= 0.0 {
        write_vtk(&d.solver)?;
        next_vtk += 1;
    }
    d.push_row();
    // The step-0 checkpoint precedes any event, even one at step 1.
    let mut ring: Vec<(u64, PathBuf)> = vec![];
    let mut pinned: BTreeSet<u64> = BTreeSet::new();
    let every = case.output.checkpoint_every;
    if every > 0 {
        let path = dir.join(ring_name(0));
        write_atomic(&path, &case_checkpoint::save(&d.solver, &d.monitor))?;
        ring.push((0, path));
    }
    let (status, reason) = loop {
        if d.solver.finished() {
            break (Status::Completed, String::new());
        }
        let stepped = d.step();
        let step = d.solver.step_count();
        let opened = d.monitor.report().events_opened;
        if opened > 0 {
            let hash = format!("{:016x}", d.solver.state_hash());
            let n = d.monitor.events().len();
            let mut new_ids = vec![];
            for e in &mut d.monitor.events_mut()[n - opened..] {
                e.state_hash = Some(hash.clone());
                // The latest ring checkpoint precedes the event: keep it for good.
                if let Some((ring_step, _)) = ring.last() {
                    e.checkpoint = Some(ring_name(*ring_step));
                    pinned.insert(*ring_step);
                }
                new_ids.push(e.id);
            }
            now.capture(&d.solver.view());
            for id in new_ids {
                if windows_opened >= EVENT_WINDOWS {
                    break;
                }
                windows_opened += 1;
                for f in ring_frames
                    .iter()
                    .filter(|f| !f.x.is_empty() && f.step < step)
                {
                    event_frame(id, f)?;
                }
                event_frame(id, &now)?;
                windows.push((id, step + EVENT_FRAME_EVERY * EVENT_FRAMES as u64));
            }
        }
        if step % EVENT_FRAME_EVERY == 0 {
            let f = &mut ring_frames[frame_next];
            f.capture(&d.solver.view());
            frame_next = (frame_next + 1) % EVENT_FRAMES;
            windows.retain(|&(_, until)| until >= step);
            for &(id, _) in &windows {
                event_frame(id, f)?;
            }
        }
        if step % row_every == 0 || opened > 0 || matches!(stepped, Stepped::Stop(_)) {
            d.push_row();
            let t = d.solver.time();
            bar.set_position((1000.0 * t / t_end) as u64);
            bar.set_message(format!("t = {t:.3} s, {} events", d.monitor.events().len()));
        }
        if let Stepped::Stop(reason) = stepped {
            break (Status::BlewUp, reason);
        }
        while next_vtk < vtk_times.len() && vtk_times[next_vtk] <= d.solver.time() {
            write_vtk(&d.solver)?;
            next_vtk += 1;
        }
        if every > 0 && step % every == 0 {
            let path = dir.join(ring_name(step));
            write_atomic(&path, &case_checkpoint::save(&d.solver, &d.monitor))?;
            ring.push((step, path));
            if ring.len() > CHECKPOINT_RING {
                let (old, path) = ring.remove(0);
                if !pinned.contains(&old) {
                    let _ = std::fs::remove_file(path);
                }
            }
        }
    };
    d.push_row();
    write_vtk(&d.solver)?;
    tables::write_timeseries(&d.series, dir, opts.csv)?;
    let events = d.monitor.events().to_vec();
    let scene = &case.solver.scene;
    Ok(Simulated {
        status,
        reason,
        steps: d.solver.step_count(),
        t_end: d.solver.time(),
        particles: d.solver.particle_count(),
        final_hash: d.solver.state_hash(),
        metrics: {
            let mut m = metrics::summarise(&d.series, &events, front_wall_z(scene));
            m["events_dropped"] = json!(d.monitor.events_dropped());
            m
        },
        events,
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
