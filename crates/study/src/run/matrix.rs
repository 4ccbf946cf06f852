//! `kick matrix`: every case of a study, cases in parallel (longest first),
//! a progress bar per running case and one overall, resumable, shardable
//! across a cluster, and joined into OUT/summary.{parquet,csv} + manifest.json.

use crate::output::files::{relative_path, write_atomic};
use crate::output::summary::{Status, Summary};
use crate::output::tables::{self, SummaryRow};
use crate::run::case::{progress_style, run_case, CaseOptions};
use crate::run::probes::darcy::DarcyFigures;
use crate::run::probes::drag_layer::DragLayerFigures;
use crate::study_file::{Case, Study, ENSEMBLE_KEYS};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use serde_json::json;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

pub struct MatrixOptions {
    pub out: PathBuf,
    pub jobs: usize,
    /// (index, count): run the cases whose position in the study is index mod count.
    pub shard: Option<(usize, usize)>,
    /// Run only the cases whose name contains every one of these.
    pub only: Vec<String>,
    pub resume: bool,
    pub csv: bool,
    /// Solver threads per case (cases are the unit of parallelism).
    pub threads_per_case: usize,
    pub progress: bool,
    /// Each case writes `plant.ckpt` at this time (`kick calibrate`).
    pub plant_checkpoint: Option<f64>,
    /// Cases not to run: a behaviour record from an earlier run holds them
    /// (`kick matrix --skip-recorded`), sorted.
    pub recorded: Vec<String>,
}

/// `I/N` with 0 <= I < N.
pub fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let bad = || {
        format!("--shard {s}: expected I/N with 0 <= I < N (e.g. 0/4 for $SLURM_ARRAY_TASK_ID/4)")
    };
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (usize, usize) = (i.parse().map_err(|_| bad())?, n.parse().map_err(|_| bad())?);
    if n == 0 || i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

/// The cases of shard `i` of `n`: those at positions i, i + n, ...
pub fn shard_cases<T>(cases: &[T], i: usize, n: usize) -> Vec<&T> {
    cases
        .iter()
        .enumerate()
        .filter(|(k, _)| k % n == i)
        .map(|(_, c)| c)
        .collect()
}

/// `name` contains every one of `only` (`--only`; true when empty).
pub fn named(only: &[String], name: &str) -> bool {
    only.iter().all(|part| name.contains(part.as_str()))
}

/// Relative cost of a case: particles x steps (sound speed sets the fixed step).
pub fn estimated_cost(case: &Case) -> f64 {
    let s = &case.solver.scene;
    let area: f64 = s
        .bodies
        .iter()
        .map(|b| (b.rect[2] - b.rect[0]) * (b.rect[3] - b.rect[1]))
        .sum();
    let particles = area / (s.cell * s.cell) * (s.ppc * s.ppc) as f64;
    let c = s
        .materials
        .iter()
        .map(|m| (m.k / m.rho0).sqrt())
        .fold(0.0, f64::max);
    let speed = c + (2.0 * s.gravity * s.size[1]).sqrt();
    let dt = case.solver.method.cfl * s.cell / speed.max(1e-12);
    particles * s.t_end / dt
}

/// A finished case's summary, if its folder holds a readable one of this
/// schema version (anything else is run again by `--resume`).
pub fn finished_summary(dir: &Path) -> Option<Summary> {
    Summary::read(dir).ok()
}

pub struct MatrixResult {
    pub ran: usize,
    pub skipped: usize,
    pub rows: Vec<SummaryRow>,
    pub wall_s: f64,
}

pub fn run_matrix(study: &Study, opts: &MatrixOptions) -> std::io::Result<MatrixResult> {
    let started = Instant::now();
    std::fs::create_dir_all(&opts.out)?;
    let selected: Vec<&Case> = match opts.shard {
        Some((i, n)) => shard_cases(&study.cases, i, n),
        None => study.cases.iter().collect(),
    }
    .into_iter()
    .filter(|c| named(&opts.only, &c.name))
    .collect();
    let mut todo: Vec<&Case> = selected
        .iter()
        .copied()
        .filter(|c| !(opts.resume && finished_summary(&opts.out.join(&c.name)).is_some()))
        .filter(|c| opts.recorded.binary_search(&c.name).is_err())
        .collect();
    let skipped = selected.len() - todo.len();
    todo.sort_by(|a, b| estimated_cost(b).total_cmp(&estimated_cost(a)));
    write_manifest(study, opts, &selected, "running", 0.0)?;
    run_cases(&todo, opts)?;
    let rows: Vec<SummaryRow> = selected
        .iter()
        .filter_map(|c| {
            finished_summary(&opts.out.join(&c.name)).map(|summary| SummaryRow {
                case_dir: c.name.clone(),
                summary,
            })
        })
        .collect();
    tables::write_summary(&rows, &opts.out)?;
    write_observed_orders(&rows, &opts.out)?;
    let wall_s = started.elapsed().as_secs_f64();
    write_manifest(study, opts, &selected, "finished", wall_s)?;
    Ok(MatrixResult {
        ran: todo.len(),
        skipped,
        rows,
        wall_s,
    })
}

/// OUT/manifest.json: the study, the state of the matrix and its cases.
fn write_manifest(
    study: &Study,
    opts: &MatrixOptions,
    selected: &[&Case],
    state: &str,
    wall_s: f64,
) -> std::io::Result<()> {
    let m = json!({
        "study": study.file.display().to_string(),
        "state": state,
        "shard": opts.shard.map(|(i, n)| format!("{i}/{n}")),
        "only": opts.only,
        "jobs": opts.jobs,
        "threads_per_case": opts.threads_per_case,
        "cases": selected.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
        "wall_s": wall_s,
        "kick_version": env!("CARGO_PKG_VERSION"),
    });
    write_atomic(
        &opts.out.join("manifest.json"),
        serde_json::to_string_pretty(&m)?.as_bytes(),
    )
}

/// Runs `todo` on `opts.jobs` workers, taking cases in order, a progress
/// bar per running case and one overall. Err: the cases whose folders
/// could not be written (a case that blew up or failed is a result).
fn run_cases(todo: &[&Case], opts: &MatrixOptions) -> std::io::Result<()> {
    let multi = if opts.progress {
        MultiProgress::new()
    } else {
        MultiProgress::with_draw_target(indicatif::ProgressDrawTarget::hidden())
    };
    let overall = multi.add(ProgressBar::new(todo.len() as u64));
    overall.set_style(
        ProgressStyle::with_template(
            "{prefix:>24} [{elapsed_precise}] {wide_bar} {pos}/{len} cases {msg}",
        )
        .expect("valid template"),
    );
    overall.set_prefix("matrix");
    let failures = Mutex::new(Vec::<String>::new());
    each_in_parallel(todo, opts.jobs, |_, case| {
        let bar = multi.insert_before(&overall, ProgressBar::new(1000));
        bar.set_style(progress_style());
        let ro = CaseOptions {
            threads: Some(opts.threads_per_case),
            bar: Some(bar.clone()),
            csv: opts.csv,
            plant_checkpoint: opts.plant_checkpoint,
        };
        let dir = opts.out.join(&case.name);
        match run_case(case, &dir, &ro) {
            Ok(s) => overall.set_message(format!("last: {} {}", case.name, s.status.as_str())),
            Err(e) => failures
                .lock()
                .expect("not poisoned")
                .push(format!("{}: {e}", dir.display())),
        }
        bar.finish_and_clear();
        multi.remove(&bar);
        overall.inc(1);
    });
    overall.finish_and_clear();
    let failures = failures.into_inner().expect("not poisoned");
    if failures.is_empty() {
        Ok(())
    } else {
        Err(std::io::Error::other(failures.join("; ")))
    }
}

/// Calls `work` on every item, on `jobs` workers taking the items in order
/// (each worker the next one free): the matrix's cases, the calibration's
/// planted runs.
pub fn each_in_parallel<T: Sync>(items: &[T], jobs: usize, work: impl Fn(usize, &T) + Sync) {
    let next = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for _ in 0..jobs.max(1).min(items.len().max(1)) {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::SeqCst);
                let Some(item) = items.get(k) else { break };
                work(k, item);
            });
        }
    });
}

/// Joins the case folders of several matrix outputs (e.g. shards) into OUT's
/// summary table; `case_dir` is each case's folder relative to OUT.
pub fn merge(dirs: &[PathBuf], out: &Path) -> std::io::Result<Vec<SummaryRow>> {
    std::fs::create_dir_all(out)?;
    let mut rows: Vec<SummaryRow> = vec![];
    for d in dirs {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(d)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_dir())
            .collect();
        entries.sort();
        for case_dir in entries {
            if case_dir.join(Summary::FILE).exists() {
                if let Err(e) = Summary::read(&case_dir) {
                    eprintln!("kick matrix --merge: left out: {e}");
                }
            }
            if let Some(summary) = finished_summary(&case_dir) {
                rows.retain(|r| r.summary.case != summary.case);
                rows.push(SummaryRow {
                    case_dir: relative_path(out, &case_dir),
                    summary,
                });
            }
        }
    }
    tables::write_summary(&rows, out)?;
    write_observed_orders(&rows, out)?;
    let m = json!({
        "state": "merged",
        "merged_from": dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>(),
        "cases": rows.iter().map(|r| r.summary.case.clone()).collect::<Vec<_>>(),
    });
    write_atomic(
        &out.join("manifest.json"),
        serde_json::to_string_pretty(&m)?.as_bytes(),
    )?;
    Ok(rows)
}

/// A figure of a case's summary.
type Figure = fn(&Summary) -> Option<f64>;

/// Figures whose observed order of convergence under `scene.cell` a
/// matrix reports (those that go to zero with h).
const CONVERGING: [(&str, Figure); 3] = [
    ("drag_layer_error", |s| {
        s.metrics.check::<DragLayerFigures>().map(|f| f.error)
    }),
    ("darcy_flux_rel_error", |s| {
        s.metrics.check::<DarcyFigures>().map(|f| f.flux_rel_error)
    }),
    ("darcy_dp_rel_error", |s| {
        s.metrics.check::<DarcyFigures>().map(|f| f.dp_rel_error)
    }),
];

/// For a matrix with a `scene.cell` axis: per case (every other parameter
/// fixed, ensemble members pooled by their median) and figure, the errors
/// against h and the observed order (least-squares slope of ln error
/// against ln h), as OUT/observed_order.json; nothing without such rows.
pub fn write_observed_orders(rows: &[SummaryRow], out: &Path) -> std::io::Result<()> {
    // A case is named by the parameters that vary across the matrix.
    let varies = |k: &str| {
        let mut values = rows.iter().map(|r| r.summary.params.get(k));
        let first = values.next().flatten();
        values.any(|v| v != first)
    };
    let key = |s: &Summary| -> String {
        s.params
            .iter()
            .filter(|(k, _)| {
                k.as_str() != "scene.cell" && !ENSEMBLE_KEYS.contains(&k.as_str()) && varies(k)
            })
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let cell = |s: &Summary| s.params.get("scene.cell").and_then(|v| v.as_f64());
    let mut entries = vec![];
    for (figure, of) in CONVERGING {
        let mut groups: BTreeMap<String, BTreeMap<u64, Vec<f64>>> = BTreeMap::new();
        for r in rows {
            let (Some(h), Some(e)) = (cell(&r.summary), of(&r.summary)) else {
                continue;
            };
            groups
                .entry(key(&r.summary))
                .or_default()
                .entry(h.to_bits())
                .or_default()
                .push(e);
        }
        for (case, by_h) in groups {
            if by_h.len() < 2 {
                continue;
            }
            let h: Vec<f64> = by_h.keys().map(|b| f64::from_bits(*b)).collect();
            let error: Vec<f64> = by_h
                .values()
                .map(|v| monitor::stats::median(v).unwrap_or(f64::NAN))
                .collect();
            let order = crate::output::metrics::observed_order(&h, &error);
            entries.push(json!({
                "case": case, "figure": figure, "h": h, "error": error, "observed_order": order,
            }));
        }
    }
    if entries.is_empty() {
        return Ok(());
    }
    write_atomic(
        &out.join("observed_order.json"),
        serde_json::to_string_pretty(&entries)?.as_bytes(),
    )
}

/// The one-paragraph matrix summary printed at the end.
pub fn describe(rows: &[SummaryRow]) -> String {
    let count = |st: Status| rows.iter().filter(|r| r.summary.status == st).count();
    let kicked = rows.iter().filter(|r| r.summary.kicked()).count();
    let mut text = format!(
        "{} cases: {} completed, {} blew up, {} failed; {} kicked",
        rows.len(),
        count(Status::Completed),
        count(Status::BlewUp),
        count(Status::Failed),
        kicked
    );
    for r in rows {
        let s = &r.summary;
        text.push_str(&format!(
            "\n  {:<32} {:<9} t = {:>6.3} s  first kick {:>8}  hydro late {:>9}  wall {:>7.1} s",
            s.case,
            s.status.as_str(),
            s.t_end,
            s.metrics
                .t_first_kick
                .map_or("-".into(), |t| format!("{t:.3} s")),
            s.metrics
                .figure("hydro_rel_rms_late")
                .map_or("-".into(), |h| format!("{h:.3e}")),
            s.wall_s,
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::parse_shard;

    #[test]
    fn shards_are_i_of_n_with_i_below_n() {
        assert_eq!(parse_shard("0/4"), Ok((0, 4)));
        assert_eq!(parse_shard("3/4"), Ok((3, 4)));
        for bad in ["4/4", "1/0", "x/2", "1", "-1/2", "1/2/3", ""] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }
}
