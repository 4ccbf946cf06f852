//! `kick slurm`: a study as a SLURM array job, one task per shard, all
//! writing to one shared OUT, and a dependent job that finishes the matrix
//! (joins every case folder, runs any case a failed task left, writes the
//! report). A requeued task resumes: `--resume` skips its finished cases.

use crate::output::files::write_atomic;
use crate::run::matrix::{estimated_cost, finished_summary, shard_cases};
use crate::study_file::Study;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

pub struct SlurmOptions {
    /// The kick binary the tasks run (on a file system every node sees).
    pub kick: PathBuf,
    /// The study file, absolute.
    pub study_file: PathBuf,
    /// The shared output folder, absolute.
    pub out: PathBuf,
    pub shards: usize,
    pub cpus_per_task: usize,
    /// Cases run at once per task (None: as many as CPUs, at most the
    /// shard's cases).
    pub jobs: Option<usize>,
    /// The user's wall time per task (None: estimated).
    pub time: Option<String>,
    pub partition: Option<String>,
    pub account: Option<String>,
    /// `--set KEY=VALUE` overrides passed on to every `kick matrix`.
    pub set: Vec<String>,
}

/// Wall time per task when no case of the study has been measured.
pub const UNMEASURED_TIME_S: u64 = 12 * 3600;
/// The estimate's margin over the measured makespan, and its fixed part.
pub const TIME_MARGIN: f64 = 1.5;
pub const TIME_SLACK_S: f64 = 300.0;

/// The wall time asked per task and how it was reached.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeEstimate {
    pub seconds: u64,
    pub basis: String,
}

/// Each case's measured wall time (s) from the finished case folders of
/// these matrix outputs (the newest folder given wins).
pub fn measured_case_times(dirs: &[PathBuf]) -> BTreeMap<String, f64> {
    let mut times = BTreeMap::new();
    for dir in dirs {
        let Ok(entries) = std::fs::read_dir(dir) else {
            continue;
        };
        for entry in entries.filter_map(Result::ok) {
            if let Some(s) = finished_summary(&entry.path()) {
                times.insert(s.case, s.wall_s);
            }
        }
    }
    times
}

/// Longest-first greedy makespan of `times` on `workers` (how a matrix
/// takes its cases).
pub fn makespan(times: &[f64], workers: usize) -> f64 {
    let mut sorted = times.to_vec();
    sorted.sort_by(|a, b| b.total_cmp(a));
    let mut load = vec![0.0f64; workers.max(1)];
    for t in sorted {
        let least = load
            .iter_mut()
            .min_by(|a, b| a.total_cmp(b))
            .expect("one worker at least");
        *least += t;
    }
    load.into_iter().fold(0.0, f64::max)
}

/// Wall time per task: the slowest shard's makespan at `jobs` cases at
/// once, x `TIME_MARGIN` + `TIME_SLACK_S`, from the measured case times;
/// an unmeasured case is scaled from the measured ones by its estimated
/// cost (particles x steps). With nothing measured, `UNMEASURED_TIME_S`.
pub fn estimate_time(
    study: &Study,
    shards: usize,
    jobs: usize,
    measured: &BTreeMap<String, f64>,
) -> TimeEstimate {
    let cases = study.cases.len();
    let seconds_per_cost: Vec<f64> = study
        .cases
        .iter()
        .filter_map(|c| {
            measured
                .get(&c.name)
                .map(|t| t / estimated_cost(c).max(1.0))
        })
        .collect();
    let known = seconds_per_cost.len();
    let Some(rate) = monitor::stats::median(&seconds_per_cost) else {
        return TimeEstimate {
            seconds: UNMEASURED_TIME_S,
            basis: "no case of the study has been measured: a guess, pass --time".into(),
        };
    };
    let time_of = |c: &crate::study_file::Case| {
        measured
            .get(&c.name)
            .copied()
            .unwrap_or(rate * estimated_cost(c))
    };
    let slowest = (0..shards)
        .map(|i| {
            let times: Vec<f64> = shard_cases(&study.cases, i, shards)
                .into_iter()
                .map(time_of)
                .collect();
            makespan(&times, jobs)
        })
        .fold(0.0, f64::max);
    let seconds = ((slowest * TIME_MARGIN + TIME_SLACK_S) / 60.0).ceil() as u64 * 60;
    TimeEstimate {
        seconds,
        basis: format!(
            "estimated from {known} of {cases} cases' measured wall time (slowest shard {slowest:.0} s, x {TIME_MARGIN} + {TIME_SLACK_S:.0} s)"
        ),
    }
}

/// Seconds as SLURM's D-HH:MM:SS.
pub fn slurm_time(seconds: u64) -> String {
    let (d, rest) = (seconds / 86_400, seconds % 86_400);
    let (h, m, s) = (rest / 3600, rest % 3600 / 60, rest % 60);
    if d > 0 {
        format!("{d}-{h:02}:{m:02}:{s:02}")
    } else {
        format!("{h:02}:{m:02}:{s:02}")
    }
}

/// A wall time as the user may give it: HH:MM:SS or D-HH:MM:SS.
pub fn parse_time(s: &str) -> Result<String, String> {
    let bad = || format!("--time {s}: expected HH:MM:SS or D-HH:MM:SS (e.g. 02:30:00)");
    let (days, clock) = match s.split_once('-') {
        Some((d, c)) => (Some(d), c),
        None => (None, s),
    };
    if days.is_some_and(|d| d.parse::<u32>().is_err()) {
        return Err(bad());
    }
    let parts: Vec<&str> = clock.split(':').collect();
    let number = |p: &str| !p.is_empty() && p.len() <= 4 && p.chars().all(|c| c.is_ascii_digit());
    let ok = parts.len() == 3
        && parts.iter().all(|p| number(p))
        && parts[1..]
            .iter()
            .all(|p| p.parse::<u32>().is_ok_and(|v| v <= 59));
    if ok {
        Ok(s.to_string())
    } else {
        Err(bad())
    }
}

/// One shell word (single-quoted unless plainly safe).
pub fn shell_word(s: &str) -> String {
    let safe = |c: char| c.is_ascii_alphanumeric() || "/._-+=:,@%".contains(c);
    if !s.is_empty() && s.chars().all(safe) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// The two batch scripts and the wall time they ask.
pub struct SlurmPlan {
    pub array_script: String,
    pub finish_script: String,
    pub time: String,
    pub basis: String,
}

/// `kick matrix STUDY --out OUT [--set ...]`, quoted for the shell.
fn matrix_command(opts: &SlurmOptions) -> String {
    let mut words = vec![
        shell_word(&opts.kick.display().to_string()),
        "matrix".into(),
        shell_word(&opts.study_file.display().to_string()),
        "--out".into(),
        shell_word(&opts.out.display().to_string()),
    ];
    for s in &opts.set {
        words.push("--set".into());
        words.push(shell_word(s));
    }
    words.join(" ")
}

/// The `#SBATCH` lines both scripts share.
fn header(opts: &SlurmOptions, name: &str, log: &str, time: &str) -> String {
    let mut h = format!(
        "#!/bin/bash\n#SBATCH --job-name={name}\n#SBATCH --cpus-per-task={}\n#SBATCH --time={time}\n#SBATCH --output={}\n#SBATCH --open-mode=append\n",
        opts.cpus_per_task,
        // SLURM expands % in --output: the folder's own % are doubled.
        shell_word(&format!(
            "{}/{log}",
            opts.out.join("slurm").display().to_string().replace('%', "%%")
        )),
    );
    for (key, value) in [("partition", &opts.partition), ("account", &opts.account)] {
        if let Some(v) = value {
            h.push_str(&format!("#SBATCH --{key}={}\n", shell_word(v)));
        }
    }
    h
}

/// Shell lines that set `jobs` and `threads` from the allocation's CPUs.
fn allocation(opts: &SlurmOptions, most_cases: usize) -> String {
    let jobs = match opts.jobs {
        Some(j) => format!("jobs={j}\n"),
        None => format!("jobs=$(( cpus < {most_cases} ? cpus : {most_cases} ))\n"),
    };
    format!(
        "cpus=${{SLURM_CPUS_PER_TASK:-{}}}\n{jobs}threads=$(( cpus / jobs > 0 ? cpus / jobs : 1 ))\n",
        opts.cpus_per_task
    )
}

/// The array script (one task per shard, requeue-safe) and the finishing
/// script (every finished case joined, any missing one run, the report).
/// Unless `--time` was given, a task asks its shard's estimate from the
/// `measured` case times, and the finishing job that of every case on one
/// allocation (the worst case: every task failed).
pub fn plan(study: &Study, opts: &SlurmOptions, measured: &BTreeMap<String, f64>) -> SlurmPlan {
    let cases = study.cases.len();
    let most_cases = cases.div_ceil(opts.shards);
    // The jobs the scripts take at the allocation's CPUs (`allocation`).
    let jobs_for = |most: usize| opts.jobs.unwrap_or(opts.cpus_per_task.min(most));
    let estimate = estimate_time(study, opts.shards, jobs_for(most_cases), measured);
    let finish = estimate_time(study, 1, jobs_for(cases), measured);
    let time = opts
        .time
        .clone()
        .unwrap_or_else(|| slurm_time(estimate.seconds));
    let basis = match &opts.time {
        Some(_) => "given with --time".to_string(),
        None => estimate.basis.clone(),
    };
    // A job name SLURM's #SBATCH parsing keeps whole.
    let name: String = study
        .file
        .file_stem()
        .map_or("study".into(), |s| s.to_string_lossy().to_string())
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    let matrix = matrix_command(opts);
    let n = opts.shards;
    let array_script = format!(
        "{}#SBATCH --array=0-{}\n#SBATCH --requeue\n# Written by kick slurm for {} ({cases} cases): array task I runs shard I/{n}.\n# Wall time per task: {time}, {basis}.\n# A requeued task resumes: --resume skips the cases it finished.\nset -euo pipefail\n{}echo \"shard ${{SLURM_ARRAY_TASK_ID}}/{n} on $(hostname), start ${{SLURM_RESTART_COUNT:-0}}: --jobs $jobs --threads $threads\"\nexec {matrix} --shard \"${{SLURM_ARRAY_TASK_ID}}/{n}\" --jobs \"$jobs\" --threads \"$threads\" --resume\n",
        header(opts, &format!("kick-{name}"), "shard-%a.log", &time),
        n - 1,
        opts.study_file.display(),
        allocation(opts, most_cases),
    );
    let finish_script = format!(
        "{}# Written by kick slurm: after every shard of {} has ended, joins every finished\n# case of OUT into its tables, runs any case a failed task left, writes the report.\nset -euo pipefail\n{}{matrix} --jobs \"$jobs\" --threads \"$threads\" --resume\n{} report {}\n",
        header(
            opts,
            &format!("kick-{name}-finish"),
            "finish.log",
            opts.time.as_deref().unwrap_or(&slurm_time(finish.seconds)),
        ),
        opts.study_file.display(),
        allocation(opts, cases),
        shell_word(&opts.kick.display().to_string()),
        shell_word(&opts.out.display().to_string()),
    );
    SlurmPlan {
        array_script,
        finish_script,
        time,
        basis,
    }
}

/// Writes OUT/slurm/{array,finish}.sbatch; returns their paths.
pub fn write_scripts(plan: &SlurmPlan, out: &Path) -> std::io::Result<(PathBuf, PathBuf)> {
    let dir = out.join("slurm");
    let (array, finish) = (dir.join("array.sbatch"), dir.join("finish.sbatch"));
    write_atomic(&array, plan.array_script.as_bytes())?;
    write_atomic(&finish, plan.finish_script.as_bytes())?;
    Ok((array, finish))
}

/// `sbatch --parsable ARGS`: the job id it printed.
fn sbatch(args: &[&str]) -> Result<String, String> {
    let out = Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .output()
        .map_err(|e| {
            format!("sbatch could not be started ({e}): is SLURM on this machine's PATH?")
        })?;
    if !out.status.success() {
        return Err(format!(
            "sbatch {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    // --parsable prints "id" or "id;cluster".
    let id = text.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        return Err(format!("sbatch printed no job id: {:?}", text.trim()));
    }
    Ok(id)
}

/// Submits the array job, then the finishing job after it (whatever the
/// tasks' exit): (array id, finishing id).
pub fn submit(array: &Path, finish: &Path) -> Result<(String, String), String> {
    let array_id = sbatch(&[&array.display().to_string()])?;
    let after = format!("--dependency=afterany:{array_id}");
    let finish_id = sbatch(&[&after, &finish.display().to_string()]).map_err(|e| {
        format!("{e}; array job {array_id} was submitted without its finishing job (scancel {array_id}, or submit it by hand)")
    })?;
    Ok((array_id, finish_id))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_greedy_makespan_puts_the_longest_first() {
        // Longest first is not optimal (6): it is what a matrix does.
        assert_eq!(makespan(&[3.0, 3.0, 2.0, 2.0, 2.0], 2), 7.0);
        assert_eq!(makespan(&[5.0, 1.0, 1.0], 3), 5.0);
        assert_eq!(makespan(&[1.0, 2.0], 1), 3.0);
        assert_eq!(makespan(&[], 2), 0.0);
    }

    #[test]
    fn shards_take_every_nth_case_as_the_matrix_does() {
        let cases = [0, 1, 2, 3, 4];
        assert_eq!(shard_cases(&cases, 0, 2), [&0, &2, &4]);
        assert_eq!(shard_cases(&cases, 1, 2), [&1, &3]);
    }

    #[test]
    fn times_are_slurm_clock_times() {
        assert_eq!(slurm_time(59), "00:00:59");
        assert_eq!(slurm_time(3600 + 120), "01:02:00");
        assert_eq!(slurm_time(86_400 + 7200), "1-02:00:00");
        for good in ["02:30:00", "1-00:00:00", "100:00:00"] {
            assert_eq!(parse_time(good).as_deref(), Ok(good));
        }
        for bad in ["2h", "02:60:00", "1-", "x-01:00:00", "01:00", ""] {
            assert!(parse_time(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn shell_words_survive_spaces_and_quotes() {
        assert_eq!(shell_word("/a/b.toml"), "/a/b.toml");
        assert_eq!(shell_word("method.cfl=0.2"), "method.cfl=0.2");
        assert_eq!(shell_word("my dir"), "'my dir'");
        assert_eq!(shell_word("it's"), r"'it'\''s'");
        assert_eq!(shell_word(""), "''");
    }
}
