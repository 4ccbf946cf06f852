//! `kick`: runs studies of the MPM kinematic anomaly.

mod report;

use study::replay::{bench, calibrate, explain, inf_sup, reproduce};
use study::run::{case, matrix, slurm};
use study::study_file;

use clap::{Args, Parser, Subcommand};
use solver::stages::projection::inf_sup::PairKind;
use solver::{ShapeKind, TransferKind};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "kick", version, about = "Hunts the MPM kinematic anomaly")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run one case of a study (the first, or --case NAME).
    Run(RunArgs),
    /// Run every case of a study, cases in parallel (or join shards with --merge).
    Matrix(MatrixArgs),
    /// Replay a logged event from the checkpoint before it and check it happens again.
    Reproduce(ReproduceArgs),
    /// Why event K kicked: its velocity change split per node, stress and
    /// transfer over the onset window, the mechanisms' shares, and (with
    /// --counterfactual) single changes replayed from the same checkpoint.
    Explain(ExplainArgs),
    /// Write OUT/report/index.html (figures as PNG and SVG) for a case or matrix folder.
    Report(ReportArgs),
    /// List the expanded cases of a study and their parameters.
    List(ListArgs),
    /// Measure particle-steps per second.
    Bench(BenchArgs),
    /// Measure the detector's sensitivity: plant kicks of known size in
    /// each case (the study's [calibration] table), bisect the smallest
    /// found, and write OUT/detection.{parquet,csv,json}.
    Calibrate(CalibrateArgs),
    /// The discrete inf-sup test of the pressure projection's pair on the
    /// study's box (whole box, free slip and no slip, and its bodies at
    /// t = 0) at each --cell; writes OUT/inf_sup.{parquet,csv,json}.
    InfSup(InfSupArgs),
    /// Run a study on a SLURM cluster: an array job (one task per shard,
    /// requeue-safe) and a dependent job that finishes the matrix and its
    /// report; writes OUT/slurm/*.sbatch and submits them.
    Slurm(SlurmArgs),
}

#[derive(Args)]
struct RunArgs {
    /// Study file (TOML).
    study: PathBuf,
    /// Case name (see `kick list`).
    #[arg(long)]
    case: Option<String>,
    /// Output folder; the case is written to OUT/CASE.
    #[arg(long, default_value = "reports")]
    out: PathBuf,
    /// Solver threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Override any study key, e.g. --set materials.water.K=1.5e6
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Also write the timeseries as CSV.
    #[arg(long)]
    csv: bool,
}

#[derive(Args)]
struct MatrixArgs {
    /// Study file (TOML); not needed with --merge.
    #[arg(required_unless_present = "merge")]
    study: Option<PathBuf>,
    /// Output folder: one sub-folder per case, summary.parquet/csv, manifest.json.
    #[arg(long, default_value = "reports/matrix")]
    out: PathBuf,
    /// Cases run at once (default: number of cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Solver threads per case (default: cores / jobs).
    #[arg(long)]
    threads: Option<usize>,
    /// Run only the cases at positions I, I+N, I+2N, ... (0 <= I < N).
    #[arg(long, value_name = "I/N", value_parser = matrix::parse_shard)]
    shard: Option<(usize, usize)>,
    /// Run only the cases whose name contains TEXT (repeat: every one).
    #[arg(long, value_name = "TEXT")]
    only: Vec<String>,
    /// Skip cases whose summary.json is already in OUT.
    #[arg(long)]
    resume: bool,
    /// Skip the cases a behaviour record (a report's behaviour_runs.jsonl,
    /// `kick report --behaviour-runs`) holds with the same parameters
    /// (repeatable): a shard run on several machines goes on where its
    /// record stopped.
    #[arg(long = "skip-recorded", value_name = "FILE")]
    skip_recorded: Vec<PathBuf>,
    /// Join the case folders of these matrix outputs into OUT's tables.
    #[arg(long, num_args = 1.., value_name = "DIR", conflicts_with_all = ["study", "shard", "resume", "only", "skip_recorded"])]
    merge: Vec<PathBuf>,
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Also write each case's timeseries as CSV.
    #[arg(long)]
    csv: bool,
}

#[derive(Args)]
struct CalibrateArgs {
    /// Study file (TOML) with a [calibration] table.
    study: PathBuf,
    /// Output folder: the clean twins as a matrix, and the detection table.
    #[arg(long, default_value = "reports/calibration")]
    out: PathBuf,
    /// Runs at once (default: number of cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Solver threads per run (default: cores / jobs).
    #[arg(long)]
    threads: Option<usize>,
    /// Keep the twins whose summary.json is already in OUT.
    #[arg(long)]
    resume: bool,
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

#[derive(Args)]
struct SlurmArgs {
    /// Study file (TOML).
    study: PathBuf,
    /// Output folder, on a file system every node sees (default: reports/STUDY).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Array tasks; task I runs the cases at positions I, I+N, ... (default: min(cases, 8)).
    #[arg(long)]
    shards: Option<usize>,
    /// CPUs per task; --jobs and --threads follow from them.
    #[arg(long, default_value_t = 2)]
    cpus_per_task: usize,
    /// Cases run at once per task (default: the task's CPUs, at most its cases).
    #[arg(long)]
    jobs: Option<usize>,
    /// Wall time per task, HH:MM:SS or D-HH:MM:SS (default: estimated from measured case times).
    #[arg(long, value_parser = slurm::parse_time)]
    time: Option<String>,
    /// Earlier matrix outputs of this study whose case wall times feed the estimate (OUT is read too).
    #[arg(long, value_name = "DIR")]
    times_from: Vec<PathBuf>,
    #[arg(long)]
    partition: Option<String>,
    #[arg(long)]
    account: Option<String>,
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Write the scripts and print how to submit them, without submitting.
    #[arg(long)]
    dry_run: bool,
}

#[derive(Args)]
struct ReproduceArgs {
    /// A case folder written by `kick run` or `kick matrix`.
    case_dir: PathBuf,
    /// Event id (see summary.json).
    #[arg(long)]
    event: u32,
    /// In a mixture, the event's phase (solid or fluid): each phase's
    /// monitor numbers its events from 1.
    #[arg(long)]
    phase: Option<String>,
    #[arg(long)]
    threads: Option<usize>,
    /// Output folder (default CASE_DIR/reproduce/event_K).
    #[arg(long)]
    out: Option<PathBuf>,
    /// VTK every step from this many steps before the event ...
    #[arg(long, default_value_t = 20)]
    before: u64,
    /// ... to this many after its last step.
    #[arg(long, default_value_t = 20)]
    after: u64,
}

#[derive(Args)]
struct ExplainArgs {
    /// A case folder written by `kick run` or `kick matrix`.
    case_dir: PathBuf,
    /// Event id (see summary.json).
    #[arg(long)]
    event: u32,
    #[arg(long)]
    threads: Option<usize>,
    /// Output folder (default CASE_DIR/explain/event_K).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also replay the unchanged control and each single change (PIC, FLIP
    /// 0.99, half dt, minimum nodal mass, J-bar, pressure smoothing, XPIC
    /// on/off, shifting, the remedies off, the pressure-implicit
    /// formulation at its own step and at the run's) as ensembles, each
    /// member jittered by scene.jitter from the same checkpoint, on to 0.2 s
    /// past the event.
    #[arg(long)]
    counterfactual: bool,
    /// Members of each counterfactual row (1 to 64).
    #[arg(long, default_value_t = explain::counterfactual::MEMBERS)]
    members: usize,
    /// When each change is made: at the onset window's start (10 ms before
    /// the event) or at the quiet window's (before the energy window's
    /// evidence of an injection).
    #[arg(long, value_enum, default_value_t = SwitchAt::Onset, requires = "counterfactual")]
    switch_at: SwitchAt,
    /// Start the quiet window SECONDS before the event's first step
    /// (default: the case's monitor.quiet_seconds; it ends where the onset
    /// window begins): the precursors, the ringing and M4 are measured
    /// over it, and the replay starts from the latest checkpoint before
    /// it. Not with --counterfactual, whose members start from the
    /// monitor's own window.
    #[arg(long, conflicts_with = "counterfactual")]
    quiet_window: Option<f64>,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum SwitchAt {
    Onset,
    Quiet,
}

#[derive(Args)]
struct ReportArgs {
    /// A case folder (summary.json) or a matrix folder (summary.parquet).
    dir: PathBuf,
    /// Matrix folders of studies/viscous_decay.toml, slosh.toml, surge_front.toml:
    /// the Methods table gains each method's yardsticks (repeatable).
    #[arg(long = "yardsticks", value_name = "MATRIX_DIR")]
    yardsticks: Vec<PathBuf>,
    /// A case of the matrix whose method is the Methods table's baseline
    /// (default: the most common value of each varying method key).
    #[arg(long, value_name = "CASE")]
    baseline: Option<String>,
    /// Behaviour records of earlier matrices (report/behaviour_runs.jsonl):
    /// their runs join the four-behaviour table where this matrix lacks the
    /// case (repeatable; the written record then holds them too).
    #[arg(long = "behaviour-runs", value_name = "FILE")]
    behaviour_runs: Vec<PathBuf>,
}

#[derive(Args)]
struct ListArgs {
    study: PathBuf,
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

#[derive(Args)]
struct BenchArgs {
    #[arg(long, value_enum, default_value = "dam-break")]
    scene: bench::BenchScene,
    #[arg(long, default_value_t = 2000)]
    steps: u64,
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Shape function (dam_break only).
    #[arg(long, value_parser = parse_choice::<ShapeKind>, default_value = "linear")]
    shape: ShapeKind,
    /// Transfer (dam_break only).
    #[arg(long, value_parser = parse_choice::<TransferKind>, default_value = "flip")]
    transfer: TransferKind,
    /// Cell size in metres (dam_break only; 0.0025 gives 51 200 particles).
    #[arg(long, default_value_t = 0.01)]
    cell: f64,
    /// Any `method.*` study key, e.g. --set method.f_reset=true (a remedy's cost).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum InfSupPair {
    Collocated,
    Mac,
}

#[derive(Args)]
struct InfSupArgs {
    /// Study file (TOML): its first case's box and bodies.
    study: PathBuf,
    /// Cell sizes (m); each must divide the box.
    #[arg(long = "cell", required = true)]
    cells: Vec<f64>,
    /// Pairs to test: collocated (the projection's, Q1-P0) and mac (staggered).
    #[arg(long = "pair", value_enum, default_values_t = [InfSupPair::Collocated, InfSupPair::Mac])]
    pairs: Vec<InfSupPair>,
    /// Lanczos steps at most (1 to 5000).
    #[arg(long, default_value_t = 400)]
    max_steps: usize,
    #[arg(long, default_value = "reports/inf_sup")]
    out: PathBuf,
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

/// A method choice by its study-file name (the serde spelling is the only one).
fn parse_choice<T: serde::de::DeserializeOwned>(s: &str) -> Result<T, String> {
    serde_json::from_value(serde_json::Value::String(s.into())).map_err(|e| {
        // serde's "unknown variant `x`, expected one of `a`, `b`" without the line and column.
        let message = e.to_string();
        message
            .split(" at line")
            .next()
            .unwrap_or(&message)
            .to_string()
    })
}

/// Exit code for bad input (study files, keys, values, case names).
const BAD_INPUT: u8 = 2;

fn main() -> ExitCode {
    match Cli::parse().command {
        Command::Run(a) => run_command(a),
        Command::Matrix(a) => matrix_command(a),
        Command::Reproduce(a) => reproduce_command(a),
        Command::Explain(a) => explain_command(a),
        Command::Report(a) => report_command(a),
        Command::List(a) => list_command(a),
        Command::Bench(a) => bench_command(a),
        Command::Calibrate(a) => calibrate_command(a),
        Command::InfSup(a) => inf_sup_command(a),
        Command::Slurm(a) => slurm_command(a),
    }
}

fn run_command(args: RunArgs) -> ExitCode {
    let RunArgs {
        study,
        case,
        out,
        threads,
        set,
        csv,
    } = args;
    let study = match study_file::load(&study, &set) {
        Ok(s) => s,
        Err(e) => return bad_input(&e.to_string()),
    };
    let chosen = match &case {
        None => &study.cases[0],
        Some(name) => match study.cases.iter().find(|c| &c.name == name) {
            Some(c) => c,
            None => {
                let names: Vec<&str> = study.cases.iter().map(|c| c.name.as_str()).collect();
                return bad_input(&format!(
                    "{}: unknown case \"{name}\" (cases: {})",
                    study.file.display(),
                    names.join(", ")
                ));
            }
        },
    };
    if threads == Some(0) {
        return bad_input("--threads: 0 is out of range (allowed >= 1)");
    }
    let dir = out.join(&chosen.name);
    let opts = case::CaseOptions {
        threads,
        bar: Some(indicatif::ProgressBar::new(1000).with_style(case::progress_style())),
        csv,
        plant_checkpoint: None,
    };
    match case::run_case(chosen, &dir, &opts) {
        Ok(s) => {
            println!(
                "case {}: {} after {} steps, t = {:.4} s ({}), wall {:.1} s, {:.2} M particle-steps/s",
                chosen.name,
                s.status.as_str(),
                s.steps,
                s.t_end,
                if s.reason.is_empty() { "no fault" } else { &s.reason },
                s.wall_s,
                s.particle_steps_per_s / 1e6
            );
            println!("results in {}", dir.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("kick: writing {} failed: {e}", dir.display());
            ExitCode::FAILURE
        }
    }
}

fn matrix_command(args: MatrixArgs) -> ExitCode {
    let MatrixArgs {
        study,
        out,
        jobs,
        threads,
        shard,
        only,
        resume,
        skip_recorded,
        merge,
        set,
        csv,
    } = args;
    if !merge.is_empty() {
        return match matrix::merge(&merge, &out) {
            Ok(rows) => {
                println!("{}", matrix::describe(&rows));
                println!("merged tables in {}", out.display());
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("kick matrix --merge: {e}");
                ExitCode::FAILURE
            }
        };
    }
    let Some(study) = study else {
        return bad_input("matrix: a study file is required (or --merge DIR...)");
    };
    let study = match study_file::load(&study, &set) {
        Ok(s) => s,
        Err(e) => return bad_input(&e.to_string()),
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs = jobs.unwrap_or(cores);
    if jobs == 0 || threads == Some(0) {
        return bad_input("--jobs and --threads: 0 is out of range (allowed >= 1)");
    }
    if !only.is_empty() && !study.cases.iter().any(|c| matrix::named(&only, &c.name)) {
        return bad_input(&format!(
            "{}: --only {}: no case's name contains it (kick list shows the names)",
            study.file.display(),
            only.join(" --only ")
        ));
    }
    let recorded = match recorded_cases(&study, &skip_recorded) {
        Ok(names) => names,
        Err(e) => return bad_input(&format!("--skip-recorded: {e}")),
    };
    let opts = matrix::MatrixOptions {
        out: out.clone(),
        jobs,
        shard,
        only,
        resume,
        csv,
        threads_per_case: threads.unwrap_or((cores / jobs).max(1)),
        progress: true,
        plant_checkpoint: None,
        recorded,
    };
    match matrix::run_matrix(&study, &opts) {
        Ok(r) => {
            println!("{}", matrix::describe(&r.rows));
            println!(
                "ran {} cases ({} already done), wall {:.1} s; tables in {}",
                r.ran,
                r.skipped,
                r.wall_s,
                out.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("kick matrix: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The cases the behaviour records `files` hold with the parameters the
/// study gives them, sorted; a case recorded with other parameters is
/// named and runs again.
fn recorded_cases(study: &study_file::Study, files: &[PathBuf]) -> Result<Vec<String>, String> {
    let mut names = vec![];
    for file in files {
        for run in report::data::read_recorded_runs(file)? {
            let s = &run.summary;
            let Some(live) = study.cases.iter().find(|c| c.name == s.case) else {
                continue;
            };
            if case::json_params(live) == s.params {
                names.push(s.case.clone());
            } else {
                eprintln!(
                    "kick matrix: {}: {} is recorded with other parameters; it runs again",
                    file.display(),
                    s.case
                );
            }
        }
    }
    names.sort();
    names.dedup();
    Ok(names)
}

fn calibrate_command(args: CalibrateArgs) -> ExitCode {
    let study = match study_file::load(&args.study, &args.set) {
        Ok(s) => s,
        Err(e) => return bad_input(&e.to_string()),
    };
    let Some(spec) = &study.calibration else {
        return bad_input(&format!(
            "{}: key `calibration`: a [calibration] table is required (see docs/usage.md)",
            args.study.display()
        ));
    };
    let t_end = study
        .cases
        .iter()
        .map(|c| c.solver.scene.t_end)
        .fold(f64::INFINITY, f64::min);
    let fits = spec
        .fits(t_end)
        .and_then(|()| calibrate::common_state::check(&study, spec));
    if let Err((key, message)) = fits {
        return bad_input(&format!("{}: key `{key}`: {message}", args.study.display()));
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs = args.jobs.unwrap_or(cores);
    if jobs == 0 || args.threads == Some(0) {
        return bad_input("--jobs and --threads: 0 is out of range (allowed >= 1)");
    }
    let opts = calibrate::CalibrateOptions {
        out: args.out.clone(),
        jobs,
        threads_per_case: args.threads.unwrap_or((cores / jobs).max(1)),
        resume: args.resume,
        progress: true,
    };
    match calibrate::calibrate(&study, &opts) {
        Ok(d) => {
            println!(
                "{} rows; twins {:.1} s, planted runs {:.1} s (wall); table in {}",
                d.rows.len(),
                d.twins_wall_s,
                d.planted_wall_s,
                args.out.join("detection.csv").display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("kick calibrate: {e}");
            ExitCode::FAILURE
        }
    }
}

fn inf_sup_command(args: InfSupArgs) -> ExitCode {
    let study = match study_file::load(&args.study, &args.set) {
        Ok(s) => s,
        Err(e) => return bad_input(&e.to_string()),
    };
    if let Some(h) = args.cells.iter().find(|h| !(h.is_finite() && **h > 0.0)) {
        return bad_input(&format!("--cell {h} is out of range (allowed > 0 m)"));
    }
    if !(1..=5000).contains(&args.max_steps) {
        return bad_input(&format!(
            "--max-steps {} is out of range (allowed 1 to 5000)",
            args.max_steps
        ));
    }
    let Some(case) = study.cases.first() else {
        return bad_input(&format!("{}: no case", args.study.display()));
    };
    let pairs: Vec<PairKind> = args
        .pairs
        .iter()
        .map(|p| match p {
            InfSupPair::Collocated => PairKind::Collocated,
            InfSupPair::Mac => PairKind::Mac,
        })
        .collect();
    match inf_sup::run(
        &case.solver.scene,
        &pairs,
        &args.cells,
        args.max_steps,
        &args.out,
    ) {
        Ok(rows) => {
            println!("pair, mask, h (m): pressures, kernel probes deflated, beta, lambda_min (residual), checkerboard quotient, Lanczos steps");
            for r in rows {
                println!(
                    "{}, {}, {}: {}, {}, {:.4e}, {:.4e} ({:.1e}), {:.3e}, {}",
                    r.pair,
                    r.mask,
                    r.h,
                    r.pressures,
                    r.kernel,
                    r.beta,
                    r.lambda_min,
                    r.residual,
                    r.checkerboard_quotient,
                    r.lanczos_steps
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) if e.starts_with("--cell") => bad_input(&format!("{}: {e}", args.study.display())),
        Err(e) => {
            eprintln!("kick inf-sup: {e}");
            ExitCode::FAILURE
        }
    }
}

/// An absolute path (the batch scripts run from another directory).
fn absolute(path: &std::path::Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

fn slurm_command(args: SlurmArgs) -> ExitCode {
    let study = match study_file::load(&args.study, &args.set) {
        Ok(s) => s,
        Err(e) => return bad_input(&e.to_string()),
    };
    let cases = study.cases.len();
    let shards = args.shards.unwrap_or(cases.min(8));
    if shards == 0 || shards > cases {
        return bad_input(&format!(
            "--shards {shards}: out of range for {} (allowed 1 to {cases}, its cases)",
            args.study.display()
        ));
    }
    if args.cpus_per_task == 0 || args.jobs == Some(0) {
        return bad_input("--cpus-per-task and --jobs: 0 is out of range (allowed >= 1)");
    }
    let stem = args.study.file_stem().unwrap_or_default();
    let out = absolute(
        &args
            .out
            .unwrap_or_else(|| PathBuf::from("reports").join(stem)),
    );
    let opts = slurm::SlurmOptions {
        kick: std::env::current_exe().map_or_else(|_| PathBuf::from("kick"), |p| absolute(&p)),
        study_file: absolute(&args.study),
        out: out.clone(),
        shards,
        cpus_per_task: args.cpus_per_task,
        jobs: args.jobs,
        time: args.time,
        partition: args.partition,
        account: args.account,
        set: args.set,
    };
    let mut sources = args.times_from;
    sources.push(out.clone());
    let plan = slurm::plan(&study, &opts, &slurm::measured_case_times(&sources));
    let (array, finish) = match slurm::write_scripts(&plan, &out) {
        Ok(paths) => paths,
        Err(e) => {
            eprintln!(
                "kick slurm: writing {} failed: {e}",
                out.join("slurm").display()
            );
            return ExitCode::FAILURE;
        }
    };
    println!(
        "{cases} cases in {shards} array tasks of {} CPU(s); wall time per task {} ({})",
        args.cpus_per_task, plan.time, plan.basis
    );
    println!("scripts: {} and {}", array.display(), finish.display());
    if args.dry_run {
        println!(
            "submit: id=$(sbatch --parsable {}) && sbatch --dependency=afterany:$id {}",
            array.display(),
            finish.display()
        );
        return ExitCode::SUCCESS;
    }
    submit_slurm(&array, &finish, &out)
}

fn submit_slurm(
    array: &std::path::Path,
    finish: &std::path::Path,
    out: &std::path::Path,
) -> ExitCode {
    match slurm::submit(array, finish) {
        Ok((array_id, finish_id)) => {
            println!("submitted: array job {array_id}, finishing job {finish_id} after it");
            println!(
                "follow: squeue -j {array_id},{finish_id}   logs: {}   results: {}",
                out.join("slurm").display(),
                out.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("kick slurm: {e} (the scripts are written; submit them by hand)");
            ExitCode::FAILURE
        }
    }
}

fn reproduce_command(args: ReproduceArgs) -> ExitCode {
    let ReproduceArgs {
        case_dir,
        event,
        phase,
        threads,
        out,
        before,
        after,
    } = args;
    if threads == Some(0) {
        return bad_input("--threads: 0 is out of range (allowed >= 1)");
    }
    let opts = reproduce::ReproduceOptions {
        phase,
        threads,
        out,
        before,
        after,
    };
    match reproduce::reproduce(&case_dir, event, &opts) {
        Ok(o) => {
            println!("{}", o.message);
            println!("dense output in {}", o.out.display());
            if o.matched {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            }
        }
        Err(e) => bad_input(&e.0),
    }
}

fn explain_command(args: ExplainArgs) -> ExitCode {
    let ExplainArgs {
        case_dir,
        event,
        threads,
        out,
        counterfactual,
        members,
        switch_at,
        quiet_window,
    } = args;
    if threads == Some(0) {
        return bad_input("--threads: 0 is out of range (allowed >= 1)");
    }
    if let Some(q) = quiet_window.filter(|q| !(q.is_finite() && *q > explain::ONSET_SECONDS)) {
        return bad_input(&format!(
            "--quiet-window: {q} is out of range (allowed: seconds above the onset window's {})",
            explain::ONSET_SECONDS
        ));
    }
    if !(1..=64).contains(&members) {
        return bad_input(&format!(
            "--members: {members} is out of range (allowed 1 to 64)"
        ));
    }
    let opts = explain::ExplainOptions {
        threads,
        out,
        counterfactual,
        members,
        switch_at_quiet: switch_at == SwitchAt::Quiet,
        quiet_seconds: quiet_window,
    };
    match explain::explain(&case_dir, event, &opts) {
        Ok(o) => {
            if let Some(p) = &o.picture {
                if let Err(e) = report::explain_picture::write(&p.before, &p.onset, p.h, &o.out) {
                    eprintln!("kick explain: the picture in {}: {e}", o.out.display());
                    return ExitCode::FAILURE;
                }
            }
            println!("{}", o.message);
            println!(
                "explain.json, explain_steps and explain_cells in {}",
                o.out.display()
            );
            if o.matched {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            }
        }
        Err(e) => bad_input(&e.0),
    }
}

fn report_command(args: ReportArgs) -> ExitCode {
    let ReportArgs {
        dir,
        yardsticks,
        baseline,
        behaviour_runs,
    } = args;
    for d in std::iter::once(&dir).chain(&yardsticks) {
        if !d.is_dir() {
            return bad_input(&format!("{}: no such folder", d.display()));
        }
    }
    if let Some(d) = yardsticks
        .iter()
        .find(|d| !d.join("summary.parquet").exists())
    {
        return bad_input(&format!(
            "--yardsticks {}: not a matrix folder (no summary.parquet)",
            d.display()
        ));
    }
    if let Some(name) = &baseline {
        let problem = match report::data::Matrix::case_names(&dir) {
            Ok(names) if names.contains(name) => None,
            Ok(_) => Some(format!(
                "no such case in {} (allowed: a case of its summary.parquet)",
                dir.display()
            )),
            Err(e) => Some(format!(
                "{} is not a readable matrix folder: {e}",
                dir.display()
            )),
        };
        if let Some(p) = problem {
            return bad_input(&format!("--baseline {name}: {p}"));
        }
    }
    if let Some(file) = behaviour_runs.first() {
        if !dir.join("summary.parquet").exists() {
            return bad_input(&format!(
                "--behaviour-runs {}: {} is not a matrix folder (no summary.parquet)",
                file.display(),
                dir.display()
            ));
        }
    }
    let mut recorded = vec![];
    for file in &behaviour_runs {
        match report::data::read_recorded_runs(file) {
            Ok(runs) => recorded.extend(runs),
            Err(e) => return bad_input(&format!("--behaviour-runs: {e}")),
        }
    }
    match report::report(&dir, &yardsticks, baseline.as_deref(), recorded) {
        Ok(index) => {
            println!("report: {}", index.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("kick report: {e}");
            ExitCode::FAILURE
        }
    }
}

fn list_command(args: ListArgs) -> ExitCode {
    let ListArgs { study, set } = args;
    let study = match study_file::load(&study, &set) {
        Ok(s) => s,
        Err(e) => return bad_input(&e.to_string()),
    };
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    for case in &study.cases {
        let m = &case.solver.method;
        let mats: Vec<String> = case
            .solver
            .scene
            .materials
            .iter()
            .map(study::study_file::labels::named_material_label)
            .collect();
        // The pressure-implicit step has its own order and a flow step.
        let stepping = match m.formulation {
            solver::Formulation::Explicit => format!("{:?} cfl={} dt={:?}", m.scheme, m.cfl, m.dt),
            solver::Formulation::PressureImplicit => {
                format!("pressure_implicit cfl={} (flow)", m.cfl)
            }
        };
        let line = writeln!(
            out,
            "{}\t{:?} {:?} {stepping}\t{}",
            case.name,
            m.shape,
            m.transfer,
            mats.join("; ")
        );
        // A closed pipe (`kick list | head`) ends the listing quietly.
        if line.is_err() {
            break;
        }
    }
    ExitCode::SUCCESS
}

fn bench_command(args: BenchArgs) -> ExitCode {
    let BenchArgs {
        scene,
        steps,
        threads,
        shape,
        transfer,
        cell,
        set,
    } = args;
    if threads == 0 || steps == 0 {
        return bad_input("--threads and --steps must be >= 1");
    }
    if !(cell.is_finite() && (1e-4..=0.1).contains(&cell)) {
        return bad_input("--cell must lie in [0.0001, 0.1] metres");
    }
    let opts = bench::BenchOptions {
        scene,
        steps,
        threads,
        shape,
        transfer,
        cell,
        method_sets: set,
    };
    if let Err(e) = bench::validate(&opts) {
        return bad_input(&e);
    }
    match bench::run(&opts) {
        Ok(line) => {
            println!("{line}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("kick bench: {e}");
            ExitCode::FAILURE
        }
    }
}

fn bad_input(message: &str) -> ExitCode {
    eprintln!("kick: {message}");
    ExitCode::from(BAD_INPUT)
}
