//! `kick slurm` without a scheduler: the scripts it writes, the `sbatch`
//! calls it makes (a stand-in `sbatch` on PATH records them), and the
//! scripts themselves run by bash as SLURM would run them: the shards,
//! then the finishing job, give every case once and the report.

use crate::common::{self, kick, stderr};
use std::path::Path;
use std::process::Command;

/// Three small cases (K = 15, 20 and 25 kPa).
fn three_cases() -> String {
    common::SMALL_MATRIX.replace("[1.5e4, 1.5e5]", "[1.5e4, 2.0e4, 2.5e4]")
}

/// A stand-in `sbatch` that appends its arguments to OUT/calls and prints
/// job ids 101, 102, ... as `--parsable` does.
fn fake_sbatch(dir: &Path) {
    let script = dir.join("sbatch");
    std::fs::write(
        &script,
        format!(
            "#!/bin/sh\necho \"$@\" >> {0}/calls\nn=$(wc -l < {0}/calls)\necho $((100 + n))\n",
            dir.display()
        ),
    )
    .unwrap();
    Command::new("chmod")
        .arg("+x")
        .arg(&script)
        .status()
        .unwrap();
}

fn kick_with_path(args: &[&str], bin: &Path) -> std::process::Output {
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    Command::new(env!("CARGO_BIN_EXE_kick"))
        .args(args)
        .current_dir(common::repo())
        .env("PATH", path)
        .output()
        .unwrap()
}

/// Runs a batch script with bash as SLURM would, with these variables.
fn run_script(script: &Path, vars: &[(&str, &str)]) {
    let o = Command::new("bash")
        .arg(script)
        .envs(vars.iter().copied())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}: {}", script.display(), stderr(&o));
}

#[test]
fn slurm_submits_the_array_then_the_finishing_job_after_it() {
    let dir = common::scratch("slurm", "submit");
    let study = dir.join("three.toml");
    std::fs::write(&study, three_cases()).unwrap();
    fake_sbatch(&dir);
    let out = dir.join("out");
    let (s, o) = (study.to_str().unwrap(), out.to_str().unwrap());
    let run = kick_with_path(
        &[
            "slurm",
            s,
            "--out",
            o,
            "--shards",
            "2",
            "--cpus-per-task",
            "1",
        ],
        &dir,
    );
    assert!(run.status.success(), "{}", stderr(&run));
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(
        text.contains("submitted: array job 101, finishing job 102 after it"),
        "{text}"
    );
    assert!(
        text.contains("no case of the study has been measured"),
        "{text}"
    );
    let calls = std::fs::read_to_string(dir.join("calls")).unwrap();
    let calls: Vec<&str> = calls.lines().collect();
    let array = out.join("slurm/array.sbatch");
    let finish = out.join("slurm/finish.sbatch");
    assert_eq!(
        calls,
        [
            format!("--parsable {}", array.display()),
            format!("--parsable --dependency=afterany:101 {}", finish.display()),
        ]
    );
    let script = std::fs::read_to_string(&array).unwrap();
    for line in [
        "#SBATCH --array=0-1",
        "#SBATCH --requeue",
        "#SBATCH --cpus-per-task=1",
        "#SBATCH --time=12:00:00",
    ] {
        assert!(script.contains(line), "{line} in {script}");
    }
    assert!(
        script.contains("--shard \"${SLURM_ARRAY_TASK_ID}/2\""),
        "{script}"
    );
    assert!(script.contains(" --resume\n"), "{script}");
}

/// The scripts work as written: shard 1, shard 0 killed before it starts
/// and run again (a requeue), then the finishing job; every case once, the
/// requeued shard's finished case untouched, the report written; and a
/// second `kick slurm` estimates its time from the measured cases.
#[test]
fn the_scripts_run_the_shards_and_finish_the_matrix() {
    let dir = common::scratch("slurm", "scripts");
    let study = dir.join("three.toml");
    std::fs::write(&study, three_cases()).unwrap();
    let out = dir.join("out");
    let (s, o) = (study.to_str().unwrap(), out.to_str().unwrap());
    let dry = kick(&[
        "slurm",
        s,
        "--out",
        o,
        "--shards",
        "2",
        "--cpus-per-task",
        "2",
        "--dry-run",
    ]);
    assert!(dry.status.success(), "{}", stderr(&dry));
    let (array, finish) = (
        out.join("slurm/array.sbatch"),
        out.join("slurm/finish.sbatch"),
    );
    run_script(
        &array,
        &[("SLURM_ARRAY_TASK_ID", "0"), ("SLURM_CPUS_PER_TASK", "2")],
    );
    let first = std::fs::read(out.join("K15kPa/summary.json")).unwrap();
    run_script(
        &array,
        &[
            ("SLURM_ARRAY_TASK_ID", "0"),
            ("SLURM_CPUS_PER_TASK", "2"),
            ("SLURM_RESTART_COUNT", "1"),
        ],
    );
    assert_eq!(
        std::fs::read(out.join("K15kPa/summary.json")).unwrap(),
        first,
        "not redone"
    );
    let script = std::fs::read_to_string(&array).unwrap();
    assert!(
        script.contains("jobs=$(( cpus < 2 ? cpus : 2 ))"),
        "{script}"
    );
    assert!(
        !out.join("K20kPa/summary.json").exists(),
        "shard 1 has not run"
    );
    // Shard 1 never ran (its task failed): the finishing job runs its case.
    run_script(&finish, &[("SLURM_CPUS_PER_TASK", "2")]);
    let table = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    let mut cases: Vec<&str> = table
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    cases.sort();
    assert_eq!(cases, ["K15kPa", "K20kPa", "K25kPa"]);
    assert!(out.join("report/index.html").exists());
    let again = kick(&["slurm", s, "--out", o, "--shards", "2", "--dry-run"]);
    let text = String::from_utf8_lossy(&again.stdout);
    assert!(
        text.contains("estimated from 3 of 3 cases' measured wall time"),
        "{text}"
    );
}

#[test]
fn slurm_refuses_shards_and_times_out_of_range_with_exit_2() {
    let dir = common::scratch("slurm", "bad");
    let study = dir.join("three.toml");
    std::fs::write(&study, three_cases()).unwrap();
    let s = study.to_str().unwrap();
    for args in [
        vec!["--shards", "0"],
        vec!["--shards", "4"],
        vec!["--time", "2h"],
        vec!["--cpus-per-task", "0"],
    ] {
        let mut all = vec!["slurm", s, "--dry-run"];
        all.extend(args.iter());
        let o = kick(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let message = stderr(&o);
        assert!(message.contains(args[0]), "{args:?}: {message}");
    }
}
