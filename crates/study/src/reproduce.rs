//! `kick reproduce`: restart a case from the checkpoint logged before event
//! K, replay through the event with dense output (a timeseries row every
//! step, VTK every step in a window around it), and check that the state hash
//! at the event's first step and the event the monitor detects again match
//! the log.

use crate::case_checkpoint;
use crate::output_files::write_atomic;
use crate::run_case::{with_threads, Driver, Stepped};
use crate::snapshot::{self, Snapshot};
use crate::study_file;
use crate::summary::Summary;
use crate::tables;
use monitor::Event;
use serde_json::json;
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
    if case.mixture.is_some() {
        let run = || {
            crate::run_mixture::replay(case, &bytes, &logged, opts, &out)
                .map(|r| r.map_err(|e| ReproduceError(format!("{}: {e}", ckpt_path.display()))))
        };
        let replay = with_threads(opts.threads, run)
            .map_err(|e| ReproduceError(format!("{}: {e}", out.display())))??;
        return finish(case_dir, &out, id, &ckpt_name, &logged, replay)
            .map_err(|e| ReproduceError(format!("{}: {e}", out.display())));
    }
    let run = || -> std::io::Result<Result<Outcome, ReproduceError>> {
        let mut d = match Driver::new(case) {
            Ok(d) => d,
            Err(e) => return Ok(Err(ReproduceError(e))),
        };
        if let Err(e) = case_checkpoint::load(&bytes, &mut d.solver, &mut d.monitor) {
            return Ok(Err(ReproduceError(format!("{}: {e}", ckpt_path.display()))));
        }
        let start = d.solver.step_count();
        if start >= logged.first_step {
            return Ok(Err(ReproduceError(format!(
                "{}: taken at step {start}, not before event {id} (step {})",
                ckpt_path.display(),
                logged.first_step
            ))));
        }
        let vtk_from = logged.first_step.saturating_sub(opts.before).max(start);
        let end = logged.last_step + opts.after;
        let mut hash_at_first = None;
        let mut replayed: Option<Event> = None;
        d.push_row(false);
        while !d.solver.finished() && d.solver.step_count() < end {
            let stepped = d.step();
            let step = d.solver.step_count();
            d.push_row(false);
            if step >= vtk_from {
                let v = d.solver.view();
                snapshot::write_file(&out.join("particles"), "particles", &Snapshot::of(&v))?;
            }
            if step == logged.first_step {
                hash_at_first = Some(format!("{:016x}", d.solver.state_hash()));
            }
            if step == logged.last_step {
                replayed = d.monitor.events().iter().find(|e| e.id == id).cloned();
            }
            if let Stepped::Stop(_) = stepped {
                break;
            }
        }
        tables::write_timeseries(&d.series, &out, true)?;
        let replay = Replay {
            start,
            hash_at_first,
            replayed,
        };
        finish(case_dir, &out, id, &ckpt_name, &logged, replay).map(Ok)
    };
    with_threads(opts.threads, run)
        .map_err(|e| ReproduceError(format!("{}: {e}", out.display())))?
}

/// What a replay found: the checkpoint's step, the state hash at the
/// event's first step, and the event as the monitor detected it again.
pub(crate) struct Replay {
    pub start: u64,
    pub hash_at_first: Option<String>,
    pub replayed: Option<Event>,
}

/// Compares a replay with the logged event and writes reproduce.json.
fn finish(
    case_dir: &Path,
    out: &Path,
    id: u32,
    ckpt_name: &str,
    logged: &Event,
    replay: Replay,
) -> std::io::Result<Outcome> {
    let Replay {
        start,
        hash_at_first,
        replayed,
    } = replay;
    snapshot::write_collections(&out.join("particles"))?;
    let mut diverged = vec![];
    match (&hash_at_first, &logged.state_hash) {
        (Some(h), Some(l)) if h == l => {}
        (h, l) => diverged.push(format!(
            "state hash at step {}: replayed {}, logged {}",
            logged.first_step,
            h.as_deref().unwrap_or("(step not reached)"),
            l.as_deref().unwrap_or("(none)")
        )),
    }
    match &replayed {
        None => diverged.push(format!("the monitor did not detect event {id} again")),
        Some(e) => {
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
        }
    }
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
