//! One case end to end: solver loop, blow-up detection, timeseries, ring
//! checkpoints, VTK snapshots and summary.json (all written atomically).

use crate::output_files::{vtk_particles, write_atomic};
use crate::study_file::Case;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{json, Value};
use solver::{Solver, StateView};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Ring checkpoints kept per case.
const CHECKPOINT_RING: usize = 3;

pub struct RunOptions {
    pub threads: Option<usize>,
    pub progress: bool,
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

/// One timeseries row (solver-level figures; the monitor adds its own).
#[derive(Clone, Debug)]
struct Row {
    step: u64,
    t: f64,
    dt: f64,
    e_kin: f64,
    e_grav: f64,
    e_int: f64,
    d_visc: f64,
    e_total: f64,
    energy_injected: f64,
    courant: f64,
    j_min: f64,
    j_max: f64,
    max_speed: f64,
    n_outside: usize,
}

const ROW_HEADER: &str =
    "step,t,dt,e_kin,e_grav,e_int,d_visc,e_total,energy_injected,courant,j_min,j_max,max_speed,n_outside";

impl Row {
    fn of(v: &StateView, injected: f64) -> Row {
        let (j_min, j_max) =
            v.j.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &j| {
                    (lo.min(j), hi.max(j))
                });
        Row {
            step: v.step,
            t: v.time,
            dt: v.dt,
            e_kin: v.energy.kinetic,
            e_grav: v.energy.gravitational,
            e_int: v.energy.stored,
            d_visc: v.energy.dissipated,
            e_total: v.energy.total(),
            energy_injected: injected,
            courant: v.courant,
            j_min,
            j_max,
            max_speed: v.v.iter().map(|u| u.norm()).fold(0.0, f64::max),
            n_outside: v.n_outside,
        }
    }

    fn csv(&self) -> String {
        format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            self.step,
            self.t,
            self.dt,
            self.e_kin,
            self.e_grav,
            self.e_int,
            self.d_visc,
            self.e_total,
            self.energy_injected,
            self.courant,
            self.j_min,
            self.j_max,
            self.max_speed,
            self.n_outside
        )
    }
}

/// Runs a case into `dir` and returns its summary (also written as summary.json).
/// Panics inside the solver become status "failed"; nothing else is lost.
pub fn run_case(case: &Case, dir: &Path, opts: &RunOptions) -> std::io::Result<Value> {
    std::fs::create_dir_all(dir)?;
    let started = Instant::now();
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match opts.threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| std::io::Error::other(e.to_string()))?
            .install(|| simulate(case, dir, opts)),
        None => simulate(case, dir, opts),
    }));
    let wall_s = started.elapsed().as_secs_f64();
    let run = match outcome {
        Ok(r) => r?,
        Err(panic) => {
            let msg = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "panic".into());
            Simulated {
                status: Status::Failed,
                reason: format!("panic: {msg}"),
                steps: 0,
                t_end: 0.0,
                particles: 0,
                final_hash: 0,
                injected_max: 0.0,
                courant_max: 0.0,
            }
        }
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
        "events": [],
        "metrics": {
            "energy_injected_max": run.injected_max,
            "courant_max": run.courant_max,
            "t_first_kick": Value::Null,
        },
    });
    write_atomic(
        &dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    Ok(summary)
}

struct Simulated {
    status: Status,
    reason: String,
    steps: u64,
    t_end: f64,
    particles: usize,
    final_hash: u64,
    injected_max: f64,
    courant_max: f64,
}

fn simulate(case: &Case, dir: &Path, opts: &RunOptions) -> std::io::Result<Simulated> {
    let mut solver = match Solver::new(case.solver.clone()) {
        Ok(s) => s,
        Err(e) => {
            return Ok(Simulated {
                status: Status::Failed,
                reason: format!("setup: {e}"),
                steps: 0,
                t_end: 0.0,
                particles: 0,
                final_hash: 0,
                injected_max: 0.0,
                courant_max: 0.0,
            })
        }
    };
    let t_end = case.solver.scene.t_end;
    let expected_steps = (t_end / solver.next_dt()).ceil().max(1.0) as u64;
    let row_every = (expected_steps / case.output.timeseries_rows).max(1);
    let bar = if opts.progress {
        let bar = ProgressBar::new(1000);
        bar.set_style(
            ProgressStyle::with_template(
                "{prefix} [{elapsed_precise}] {wide_bar} {percent}% {msg}",
            )
            .expect("valid template"),
        );
        bar.set_prefix(case.name.clone());
        bar
    } else {
        ProgressBar::hidden()
    };
    let mut rows = vec![Row::of(&solver.view(), 0.0)];
    let mut e_min = solver.energy().total();
    let mut injected_max: f64 = 0.0;
    let mut courant_max: f64 = 0.0;
    let mut vtk_times: Vec<f64> = case.output.vtk_times.clone();
    vtk_times.sort_by(f64::total_cmp);
    let mut next_vtk = 0;
    let mut ring: Vec<PathBuf> = vec![];
    let particles_dir = dir.join("particles");
    let write_vtk = |v: &StateView| -> std::io::Result<()> {
        write_atomic(
            &particles_dir.join(format!("particles_{:09}.vtk", v.step)),
            &vtk_particles(v),
        )
    };
    while next_vtk < vtk_times.len() && vtk_times[next_vtk] <= 0.0 {
        write_vtk(&solver.view())?;
        next_vtk += 1;
    }
    let (status, reason) = loop {
        if solver.finished() {
            break (Status::Completed, String::new());
        }
        if let Err(e) = solver.step() {
            break (
                Status::BlewUp,
                format!("step {}: {e}", solver.step_count() + 1),
            );
        }
        let v = solver.view();
        let e = v.energy.total();
        e_min = e_min.min(e);
        injected_max = injected_max.max(e - e_min);
        courant_max = courant_max.max(v.courant);
        if v.step % row_every == 0 {
            rows.push(Row::of(&v, e - e_min));
            bar.set_position((1000.0 * v.time / t_end) as u64);
            bar.set_message(format!("t = {:.3} s", v.time));
        }
        while next_vtk < vtk_times.len() && vtk_times[next_vtk] <= v.time {
            write_vtk(&v)?;
            next_vtk += 1;
        }
        if v.n_nonfinite > 0 {
            break (
                Status::BlewUp,
                format!(
                    "step {}: non-finite state in {} particles",
                    v.step, v.n_nonfinite
                ),
            );
        }
        if v.n_outside > 0 {
            break (
                Status::BlewUp,
                format!("step {}: {} particles left the box", v.step, v.n_outside),
            );
        }
        let every = case.output.checkpoint_every;
        if every > 0 && v.step % every == 0 {
            let path = dir
                .join("checkpoints")
                .join(format!("ring_{:09}.ckpt", v.step));
            write_atomic(&path, &solver.checkpoint())?;
            ring.push(path);
            if ring.len() > CHECKPOINT_RING {
                let _ = std::fs::remove_file(ring.remove(0));
            }
        }
    };
    bar.finish_and_clear();
    let v = solver.view();
    if rows.last().map(|r| r.step) != Some(v.step) {
        rows.push(Row::of(&v, v.energy.total() - e_min));
    }
    write_vtk(&v)?;
    let mut csv = String::from(ROW_HEADER);
    csv.push('\n');
    for r in &rows {
        csv.push_str(&r.csv());
    }
    write_atomic(&dir.join("timeseries.csv"), csv.as_bytes())?;
    Ok(Simulated {
        status,
        reason,
        steps: v.step,
        t_end: v.time,
        particles: v.x.len(),
        final_hash: solver.state_hash(),
        injected_max,
        courant_max,
    })
}

fn toml_to_json(v: &toml::Value) -> Value {
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
