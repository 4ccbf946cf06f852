//! One case end to end: its stepper (a solver, or a mixture) driven by the
//! one run loop (`crate::run`) with the case's probes attached (particle
//! files, event frames, the checkpoint ring, the verification checks its
//! scene allows); blow-up and panics as results; summary.json. Every file
//! is written atomically.

use crate::output::files::write_atomic;
use crate::output::summary::{Summary, SCHEMA_VERSION};
use crate::output::vtu;
use crate::run::mixture;
use crate::run::probes::checkpoint_ring::CheckpointRing;
use crate::run::probes::energy_gain::EnergyGain;
use crate::run::probes::event_frames::EventFrames;
use crate::run::probes::mode_decay::ModeDecay;
use crate::run::probes::particle_files::ParticleFiles;
use crate::run::probes::plant_checkpoint::PlantCheckpoint;
use crate::run::probes::ringing::Ringing;
use crate::run::probes::slosh::Slosh;
use crate::run::probes::sound_wave::SoundWave;
use crate::run::probes::surge_front::SurgeFront;
use crate::run::{Rows, RunOptions, Runner, Simulated, Stepper, Watch};
use crate::study_file::Case;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{json, Value};
use solver::Solver;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

pub struct CaseOptions {
    pub threads: Option<usize>,
    /// Progress bar to drive (hidden when None).
    pub bar: Option<ProgressBar>,
    /// Also write the timeseries as CSV.
    pub csv: bool,
    /// Write `plant.ckpt` at the first step ending at or after this time
    /// (`kick calibrate`'s restart point).
    pub plant_checkpoint: Option<f64>,
}

/// Runs a case into `dir` and returns its summary (also written as summary.json).
/// Panics inside the solver become status "failed"; nothing else is lost.
pub fn run_case(case: &Case, dir: &Path, opts: &CaseOptions) -> std::io::Result<Summary> {
    write_case_table(case, dir)?;
    let started = Instant::now();
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        with_threads(opts.threads, || simulate(case, dir, opts))
    }));
    let wall_s = started.elapsed().as_secs_f64();
    // ParaView's time series of what was written, however the run ended.
    vtu::write_collections(&dir.join("particles"))?;
    let run = match outcome {
        Ok(r) => r?,
        Err(panic) => Simulated::failed(format!("panic: {}", panic_message(panic))),
    };
    let summary = summary(case, run, wall_s);
    summary.write(dir)?;
    Ok(summary)
}

/// Creates the case's folder and writes its resolved table as case.toml.
pub(crate) fn write_case_table(case: &Case, dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    write_atomic(
        &dir.join("case.toml"),
        toml::to_string(&case.table)
            .map_err(|e| std::io::Error::other(e.to_string()))?
            .as_bytes(),
    )
}

/// The case's parameters as its summary records them.
pub fn json_params(case: &Case) -> BTreeMap<String, Value> {
    case.params
        .iter()
        .map(|(k, v)| (k.clone(), toml_to_json(v)))
        .collect()
}

pub(crate) fn summary(case: &Case, run: Simulated, wall_s: f64) -> Summary {
    let particle_steps = run.particles as f64 * run.steps as f64;
    Summary {
        schema_version: SCHEMA_VERSION,
        case: case.name.clone(),
        params: json_params(case),
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
    }
}

/// The case's stepper under the run loop, with the probes that apply.
fn simulate(case: &Case, dir: &Path, opts: &CaseOptions) -> std::io::Result<Simulated> {
    match &case.mixture {
        Some(spec) => {
            let mix = match mixture::build(case, spec) {
                Ok(m) => m,
                Err(reason) => return Ok(Simulated::failed(reason)),
            };
            let first_dt = mix.next_dt();
            let mut runner = case_runner(mix, first_dt, case, dir, opts);
            mixture::attach_checks(&mut runner, case, spec);
            runner.run()
        }
        None => {
            let solver = match Solver::new(case.solver.clone()) {
                Ok(s) => s,
                Err(e) => return Ok(Simulated::failed(format!("setup: {e}"))),
            };
            let (first_dt, particles) = (solver.next_dt(), solver.particle_count());
            let mut runner = case_runner(solver, first_dt, case, dir, opts);
            runner.attach(EventFrames::new(dir.join("particles"), particles));
            if let Some(front) = SurgeFront::new(&case.solver.scene) {
                runner.attach(front);
            }
            if let Some(decay) = ModeDecay::new(&case.solver.scene, dir.to_path_buf(), opts.csv) {
                runner.attach(decay);
            }
            if let Some(slosh) = Slosh::new(&case.solver.scene, dir.to_path_buf(), opts.csv) {
                runner.attach(slosh);
            }
            if let Some(gain) = EnergyGain::new(&case.solver) {
                runner.attach(gain);
            }
            if let Some(sound) = SoundWave::new(&case.solver.scene, dir.to_path_buf(), opts.csv) {
                runner.attach(sound);
            }
            if let Some(ringing) = Ringing::new(&case.solver.scene, dir.to_path_buf(), opts.csv) {
                runner.attach(ringing);
            }
            runner.run()
        }
    }
}

/// A runner over `stepper` with a watch per phase, the case's rows, and
/// its particle files and checkpoint ring.
fn case_runner<'p, S: Stepper>(
    stepper: S,
    first_dt: f64,
    case: &Case,
    dir: &Path,
    opts: &CaseOptions,
) -> Runner<'p, S> {
    let watches = watches(&stepper, case);
    let rows = if case.solver.method.formulation == solver::Formulation::PressureImplicit {
        Rows::spread_in_time(case.output.timeseries_rows, case.solver.scene.t_end)
    } else {
        Rows::spread(
            case.output.timeseries_rows,
            case.solver.scene.t_end,
            first_dt,
        )
    };
    let mut run_opts = RunOptions::new(Some(dir.to_path_buf()), rows);
    run_opts.csv = opts.csv;
    run_opts.end_when_checked = case.output.end_when_checked;
    run_opts.collapse_from = crate::run::collapse_reference(first_dt, &case.solver.method);
    let bar = opts.bar.clone().unwrap_or_else(ProgressBar::hidden);
    bar.set_length(1000);
    bar.set_prefix(case.name.clone());
    run_opts.bar = Some(bar);
    let mut runner = Runner::new(stepper, watches, run_opts);
    runner.attach(ParticleFiles::new(
        dir.join("particles"),
        case.output.vtk_times.clone(),
    ));
    runner.attach(CheckpointRing::new(
        dir.to_path_buf(),
        case.output.checkpoint_every,
        case.monitor.quiet_seconds,
    ));
    if let Some(at) = opts.plant_checkpoint {
        runner.attach(PlantCheckpoint::new(dir.to_path_buf(), at));
    }
    runner
}

/// One monitor per phase, as the case configures it.
pub(crate) fn watches<S: Stepper>(stepper: &S, case: &Case) -> Vec<Watch> {
    (0..stepper.phase_count())
        .map(|k| Watch::new(case.monitor.clone(), &stepper.phase(k).view()))
        .collect()
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
