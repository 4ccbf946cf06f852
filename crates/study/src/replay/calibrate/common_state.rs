//! One flow for every method (`[calibration] common_state`): the named
//! case runs clean to `switch_lead` seconds before the plant; every case's
//! twin restarts from that state, switched to its own method and material
//! constants, and runs on through the window, checkpointed at the plant as
//! a matrix twin is. After seconds of a violent flow each method's state
//! is its own, so planting in each method's own flow compares flows as
//! much as detectors; from a common state the patches, the particles they
//! move and the flow around them are the same but for `switch_lead`
//! seconds of each method's own dynamics.

use super::CalibrateOptions;
use crate::output::summary::Summary;
use crate::output::tables::{self, SummaryRow};
use crate::run::case::{
    panic_message, run_case, summary, with_threads, write_case_table, CaseOptions,
};
use crate::run::matrix::each_in_parallel;
use crate::run::probes::plant_checkpoint::{PlantCheckpoint, PLANT_CHECKPOINT};
use crate::run::{Rows, RunOptions, Runner, Simulated};
use crate::study_file::calibration::CalibrationSpec;
use crate::study_file::{Case, Study};
use std::path::Path;
use std::time::Instant;

/// Where the common state's own run goes, beside the cases' folders.
pub const COMMON_DIR: &str = "common_state";

/// The study key that names the common state, for errors.
const KEY: &str = "calibration.common_state";

/// Checks that the named case exists and that every case differs from it
/// in its method and material constants only, with the same shape (the
/// stencils are the shape's); Err: (key, message).
pub fn check(study: &Study, spec: &CalibrationSpec) -> Result<(), (String, String)> {
    let Some(name) = &spec.common_state else {
        return Ok(());
    };
    let bad = |m: String| Err((KEY.to_string(), m));
    let Some(reference) = study.cases.iter().find(|c| &c.name == name) else {
        let names: Vec<&str> = study.cases.iter().map(|c| c.name.as_str()).collect();
        return bad(format!(
            "\"{name}\" is not a case (allowed: {})",
            names.join(", ")
        ));
    };
    if study.cases.iter().any(|c| c.name == COMMON_DIR) {
        return bad(format!(
            "a case named \"{COMMON_DIR}\" would share the common state's folder"
        ));
    }
    for case in &study.cases {
        // The names and densities: the particles hold materials by index,
        // with masses from rho0.
        let names = |c: &Case| -> Vec<(String, u64)> {
            let m = &c.solver.scene.materials;
            m.iter()
                .map(|m| (m.name.clone(), m.rho0.to_bits()))
                .collect()
        };
        let mut switched = reference.solver.clone();
        switched.method = case.solver.method.clone();
        switched.scene.materials = case.solver.scene.materials.clone();
        if names(case) != names(reference) {
            return bad(format!(
                "case {} has other materials than case {name}: only their constants other than rho0 may differ",
                case.name
            ));
        }
        if let Err(e) = switched.validate() {
            return bad(format!(
                "case {}'s method and materials cannot follow case {name}'s state: {e}",
                case.name
            ));
        }
        let mut same = case.solver.clone();
        same.method = reference.solver.method.clone();
        same.scene.materials = reference.solver.scene.materials.clone();
        let differs = if case.mixture.is_some() {
            Some("is a mixture")
        } else if case.solver.method.shape != reference.solver.method.shape {
            Some("has another shape (method.shape cannot change mid-run)")
        } else if same != reference.solver || case.monitor != reference.monitor {
            Some("differs in more than its method and material constants")
        } else {
            None
        };
        if let Some(why) = differs {
            return bad(format!(
                "case {} {why}: it cannot start from case {name}'s state",
                case.name
            ));
        }
    }
    Ok(())
}

/// Runs the common state, then every case's twin from it, and the summary table.
pub fn run_twins(
    study: &Study,
    spec: &CalibrationSpec,
    opts: &CalibrateOptions,
) -> std::io::Result<()> {
    let Some(name) = &spec.common_state else {
        return Ok(());
    };
    let reference = study
        .cases
        .iter()
        .find(|c| &c.name == name)
        .ok_or_else(|| std::io::Error::other(format!("{KEY}: no case {name}")))?;
    let t_switch = spec.plant_t - spec.switch_lead;
    let common_dir = opts.out.join(COMMON_DIR);
    let checkpoint_path = common_dir.join(PLANT_CHECKPOINT);
    if !(opts.resume && checkpoint_path.exists()) {
        let mut run = reference.clone();
        run.solver.scene.t_end = spec.plant_t;
        let case_opts = CaseOptions {
            threads: Some(opts.threads_per_case.max(opts.jobs)),
            bar: None,
            csv: false,
            plant_checkpoint: Some(t_switch),
        };
        let s = run_case(&run, &common_dir, &case_opts)?;
        if !checkpoint_path.exists() {
            return Err(std::io::Error::other(format!(
                "{KEY}: case {name} ended {} at t = {:.4} s before {t_switch} s: {}",
                s.status.as_str(),
                s.t_end,
                s.reason
            )));
        }
    }
    let checkpoint = std::fs::read(&checkpoint_path)?;
    let todo: Vec<&Case> = study
        .cases
        .iter()
        .filter(|c| !(opts.resume && Summary::read(&opts.out.join(&c.name)).is_ok()))
        .collect();
    each_in_parallel(&todo, opts.jobs, |_, case| {
        let dir = opts.out.join(&case.name);
        if let Err(e) = twin(
            reference,
            &checkpoint,
            case,
            &dir,
            spec,
            opts.threads_per_case,
        ) {
            eprintln!("kick calibrate: {}: {e}", case.name);
        }
    });
    // The matrix table `kick report` reads, as a matrix of the twins.
    let rows: Vec<SummaryRow> = study
        .cases
        .iter()
        .filter_map(|c| {
            let summary = Summary::read(&opts.out.join(&c.name)).ok()?;
            Some(SummaryRow {
                case_dir: c.name.clone(),
                summary,
            })
        })
        .collect();
    tables::write_summary(&rows, &opts.out)
}

/// One case's twin from the common state, written as a matrix twin is
/// (summary.json, plant.ckpt); a panic or a refused switch is its result.
fn twin(
    reference: &Case,
    checkpoint: &[u8],
    case: &Case,
    dir: &Path,
    spec: &CalibrationSpec,
    threads: usize,
) -> std::io::Result<()> {
    write_case_table(case, dir)?;
    let started = Instant::now();
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        with_threads(Some(threads), || {
            switched_run(reference, checkpoint, case, dir, spec)
        })
    }));
    let mut run = match outcome {
        Ok(r) => r?,
        Err(panic) => Simulated::failed(format!("panic: {}", panic_message(panic))),
    };
    // The restored monitor holds the common state's events: those that
    // ended before the switch are not this case's.
    let t_switch = spec.plant_t - spec.switch_lead;
    run.events.retain(|e| e.last_t >= t_switch);
    summary(case, run, started.elapsed().as_secs_f64()).write(dir)
}

/// The common state restored under the reference's configuration, then
/// switched to the case's method and materials, run to the case's end.
fn switched_run(
    reference: &Case,
    checkpoint: &[u8],
    case: &Case,
    dir: &Path,
    spec: &CalibrationSpec,
) -> std::io::Result<Simulated> {
    let mut cfg = reference.solver.clone();
    cfg.scene.t_end = case.solver.scene.t_end;
    let (mut solver, watches) = match super::restored(case, cfg, checkpoint) {
        Ok(restored) => restored,
        Err(e) => return Ok(Simulated::failed(format!("common state: {e}"))),
    };
    let method = match fixed_step_method(case) {
        Ok(m) => m,
        Err(e) => return Ok(Simulated::failed(format!("setup: {e}"))),
    };
    // The method first (K = inf is valid only under the pressure-implicit
    // one), or the materials first when the method needs them (`check`
    // validated the pair).
    let materials = case.solver.scene.materials.clone();
    let switched = solver
        .set_method(method.clone())
        .and_then(|()| solver.set_materials(materials.clone()))
        .or_else(|_| {
            solver
                .set_materials(materials)
                .and_then(|()| solver.set_method(method))
        });
    if let Err(e) = switched {
        return Ok(Simulated::failed(format!("switch: {e}")));
    }
    let rows = Rows::spread_in_time(case.output.timeseries_rows, case.solver.scene.t_end);
    let mut runner = Runner::new(
        solver,
        watches,
        RunOptions::new(Some(dir.to_path_buf()), rows),
    );
    runner.attach(PlantCheckpoint::new(dir.to_path_buf(), spec.plant_t));
    runner.run()
}

/// The case's method, with a fixed step that the state at t = 0 sets (a
/// CFL step taken once) made explicit: the step the case takes from t = 0,
/// not one taken from the common state.
fn fixed_step_method(case: &Case) -> Result<solver::Method, solver::ConfigError> {
    let mut method = case.solver.method.clone();
    let fixed = method.dt == solver::DtMode::Fixed
        && method.dt_value.is_none()
        && method.formulation != solver::Formulation::PressureImplicit;
    if fixed {
        method.dt_value = Some(solver::Solver::new(case.solver.clone())?.next_dt());
    }
    Ok(method)
}
