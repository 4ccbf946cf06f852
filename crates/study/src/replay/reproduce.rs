//! `kick reproduce`: restart a case from the checkpoint logged before event
//! K, replay through the event with dense output (a timeseries row every
//! step, VTK every step in a window around it), and check that the state hash
//! at the event's first step and the event the monitor detects again match
//! the log.

use crate::output::files::write_atomic;
use crate::output::summary::Summary;
use crate::output::vtu;
use crate::run::case::{watches, with_threads};
use crate::run::mixture;
use crate::run::probes::replay::{Found, Replay as ReplayChecks};
use crate::run::{Rows, RunOptions, Runner, Stepper};
use crate::study_file::{self, Case};
use monitor::Event;
use serde_json::json;
use solver::Solver;
use std::path::{Path, PathBuf};

pub struct ReproduceOptions {
    /// The event's phase in a mixture (`solid` or `fluid`).
    pub phase: Option<String>,
    pub threads: Option<usize>,
    pub out: Option<PathBuf>,
    /// VTK every step from this many steps before the event's first step ...
    pub before: u64,
    /// ... to this many steps after its last step (the replay ends there).
    pub after: u64,
}

/// Bad input (exit 2): missing or corrupted files, unknown event.
#[derive(Debug)]
pub struct ReproduceError(pub String);

pub struct Outcome {
    pub matched: bool,
    pub message: String,
    pub out: PathBuf,
}

pub fn reproduce(
    case_dir: &Path,
    id: u32,
    opts: &ReproduceOptions,
) -> Result<Outcome, ReproduceError> {
    let events = Summary::read(case_dir).map_err(ReproduceError)?.events;
    let matching: Vec<&Event> = events
        .iter()
        .filter(|e| e.id == id && (opts.phase.is_none() || e.phase == opts.phase))
        .collect();
    if matching.len() > 1 {
        let phases: Vec<&str> = matching.iter().filter_map(|e| e.phase.as_deref()).collect();
        return Err(ReproduceError(format!(
            "{}: event {id} is logged in phases {}: say which with --phase",
            case_dir.join("summary.json").display(),
            phases.join(" and ")
        )));
    }
    let Some(logged) = matching.first().map(|e| (*e).clone()) else {
        let ids: Vec<String> = events.iter().map(|e| e.id.to_string()).collect();
        return Err(ReproduceError(format!(
            "{}: no event {id} (events: {})",
            case_dir.join("summary.json").display(),
            if ids.is_empty() {
                "none".into()
            } else {
                ids.join(", ")
            }
        )));
    };
    let Some(ckpt_name) = logged.checkpoint.clone() else {
        return Err(ReproduceError(format!(
            "event {id} has no checkpoint (the case ran with output.checkpoint_every = 0)"
        )));
    };
    let study_path = case_dir.join("case.toml");
    let study = study_file::load(&study_path, &[]).map_err(|e| ReproduceError(e.to_string()))?;
    let case = &study.cases[0];
    let ckpt_path = case_dir.join(&ckpt_name);
    let bytes = std::fs::read(&ckpt_path)
        .map_err(|e| ReproduceError(format!("{}: cannot read: {e}", ckpt_path.display())))?;
    let out = opts
        .out
        .clone()
        .unwrap_or_else(|| case_dir.join("reproduce").join(format!("event_{id}")));
    let at_checkpoint = |e: String| ReproduceError(format!("{}: {e}", ckpt_path.display()));
    let run = || match &case.mixture {
        Some(spec) => match mixture::build(case, spec) {
            Ok(mix) => replay(mix, case, &bytes, &logged, opts, &out),
            Err(e) => Ok(Err(e)),
        },
        None => match Solver::new(case.solver.clone()) {
            Ok(solver) => replay(solver, case, &bytes, &logged, opts, &out),
            Err(e) => Ok(Err(format!("setup: {e}"))),
        },
    };
    let replay = with_threads(opts.threads, run)
        .map_err(|e| ReproduceError(format!("{}: {e}", out.display())))?
        .map_err(at_checkpoint)?;
    finish(case_dir, &out, id, &ckpt_name, &logged, replay)
        .map_err(|e| ReproduceError(format!("{}: {e}", out.display())))
}

/// What a replay found: the checkpoint's step, the state hash at the
/// event's first step, and the event as the monitor detected it again.
pub(crate) struct Replayed {
    pub start: u64,
    pub found: Found,
}

/// The stepper and its monitors restored from `checkpoint`, stepped by the
/// run loop through the event's last step (and `opts.after` more), with a
/// timeseries row every step and particle files every step from
/// `opts.before` steps before the event. Err: the checkpoint does not
/// restore, or is not before the event.
fn replay<S: Stepper>(
    mut stepper: S,
    case: &Case,
    checkpoint: &[u8],
    logged: &Event,
    opts: &ReproduceOptions,
    out: &Path,
) -> std::io::Result<Result<Replayed, String>> {
    let mut watches = watches(&stepper, case);
    if let Err(e) = stepper.load(checkpoint, &mut watches) {
        return Ok(Err(e.to_string()));
    }
    let start = stepper.step_count();
    if start >= logged.first_step {
        return Ok(Err(format!(
            "taken at step {start}, not before event {} (step {})",
            logged.id, logged.first_step
        )));
    }
    let phase = (0..stepper.phase_count())
        .find(|&k| stepper.phase_name(k) == logged.phase.as_deref())
        .unwrap_or(stepper.primary_phase());
    let mut run_opts = RunOptions::new(Some(out.to_path_buf()), Rows::every_step());
    run_opts.csv = true;
    run_opts.until_step = Some(logged.last_step + opts.after);
    let mut found = Found::default();
    let mut runner = Runner::new(stepper, watches, run_opts);
    runner.attach(ReplayChecks {
        files_from: logged.first_step.saturating_sub(opts.before).max(start),
        files: out.join("particles"),
        event: logged,
        phase,
        found: &mut found,
    });
    runner.run()?;
    drop(runner);
    Ok(Ok(Replayed { start, found }))
}

/// Compares a replay with the logged event and writes reproduce.json.
fn finish(
    case_dir: &Path,
    out: &Path,
    id: u32,
    ckpt_name: &str,
    logged: &Event,
    replay: Replayed,
) -> std::io::Result<Outcome> {
    let Replayed {
        start,
        found: Found {
            hash_at_first,
            replayed,
        },
    } = replay;
    vtu::write_collections(&out.join("particles"))?;
    let diverged = divergences(logged, hash_at_first.as_deref(), replayed.as_ref());
    let matched = diverged.is_empty();
    let message = if matched {
        format!(
            "reproduced event {id} at step {}: hash match",
            logged.first_step
        )
    } else {
        format!("event {id} diverged: {}", diverged.join("; "))
    };
    let record = json!({
        "case_dir": case_dir.display().to_string(),
        "event": id,
        "phase": logged.phase,
        "checkpoint": ckpt_name,
        "checkpoint_step": start,
        "first_step": logged.first_step,
        "last_step": logged.last_step,
        "logged_state_hash": logged.state_hash,
        "replayed_state_hash": hash_at_first,
        "replayed_event": replayed,
        "matched": matched,
        "message": message,
    });
    write_atomic(
        &out.join("reproduce.json"),
        serde_json::to_string_pretty(&record)?.as_bytes(),
    )?;
    Ok(Outcome {
        matched,
        message,
        out: out.to_path_buf(),
    })
}

/// How a replay differs from the logged event: the state hash at its first
/// step, and the event's first step, region and particles.
fn divergences(
    logged: &Event,
    hash_at_first: Option<&str>,
    replayed: Option<&Event>,
) -> Vec<String> {
    let id = logged.id;
    let mut diverged = vec![];
    match (hash_at_first, &logged.state_hash) {
        (Some(h), Some(l)) if h == l => {}
        (h, l) => diverged.push(format!(
            "state hash at step {}: replayed {}, logged {}",
            logged.first_step,
            h.unwrap_or("(step not reached)"),
            l.as_deref().unwrap_or("(none)")
        )),
    }
    let Some(e) = replayed else {
        diverged.push(format!("the monitor did not detect event {id} again"));
        return diverged;
    };
    if e.first_step != logged.first_step {
        diverged.push(format!(
            "event {id} first step: replayed {}, logged {}",
            e.first_step, logged.first_step
        ));
    }
    if e.kind != logged.kind || e.cells != logged.cells {
        diverged.push(format!(
            "event {id} region: replayed {:?} {:?}, logged {:?} {:?}",
            e.kind, e.cells, logged.kind, logged.cells
        ));
    }
    if e.particles != logged.particles || e.n_particles != logged.n_particles {
        diverged.push(format!(
            "event {id} particles: replayed {} ids, logged {}",
            e.n_particles, logged.n_particles
        ));
    }
    diverged
}
