//! End-to-end tests of the `kick` binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn kick(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kick"))
        .args(args)
        .current_dir(repo())
        .output()
        .expect("kick runs")
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kick-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn run_completes_and_writes_the_case_folder() {
    let out = scratch("run");
    let o = kick(&[
        "run",
        "studies/dam_break.toml",
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "2",
        "--set",
        "scene.t_end=0.05",
        "--set",
        "method.shape=\"bspline2\"",
        "--set",
        "output.vtk_times=[0.0, 0.05]",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dir = out.join("dam_break");
    let s = summary(&dir);
    assert_eq!(s["status"], "completed");
    assert_eq!(s["params"]["method.shape"], "bspline2");
    assert!((s["t_end"].as_f64().unwrap() - 0.05).abs() < 1e-12);
    let steps = s["steps"].as_u64().unwrap();
    assert!(steps > 10);
    assert!(s["wall_s"].as_f64().unwrap() > 0.0);
    assert!(s["particle_steps_per_s"].as_f64().unwrap() > 0.0);
    assert_eq!(s["particles"], 3200);
    let csv = std::fs::read_to_string(dir.join("timeseries.csv")).unwrap();
    let last = csv.lines().last().unwrap();
    assert!(last.starts_with(&format!("{steps},")), "{last}");
    let vtk: Vec<_> = std::fs::read_dir(dir.join("particles")).unwrap().collect();
    assert!(vtk.len() >= 2);
}

#[test]
fn blow_up_is_a_result_with_step_and_reason() {
    let out = scratch("blowup");
    // The default study: baseline method at K = 15 kPa kicks near t = 0.5 s.
    let o = kick(&[
        "run",
        "studies/dam_break.toml",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "scene.t_end=1.0",
        "--set",
        "output.vtk_times=[]",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out.join("dam_break"));
    assert_eq!(s["status"], "blew_up", "{s}");
    let steps = s["steps"].as_u64().unwrap();
    let reason = s["reason"].as_str().unwrap();
    assert!(reason.contains(&format!("step {steps}")), "{reason}");
    assert!(
        reason.contains("left the box") || reason.contains("non-finite") || reason.contains("grid")
    );
    assert!(s["t_end"].as_f64().unwrap() < 1.0);
}

#[test]
fn list_expands_the_bug_report_matrix() {
    let o = kick(&["list", "studies/bug_report.toml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    let names: Vec<&str> = text
        .lines()
        .map(|l| l.split('\t').next().unwrap())
        .collect();
    assert_eq!(names.len(), 32);
    let unique: std::collections::BTreeSet<_> = names.iter().collect();
    assert_eq!(unique.len(), 32, "case names are unique");
    assert!(names.contains(&"K1.5MPa_tait_mu0.5"), "{names:?}");
    assert!(names.contains(&"K15kPa_power-g1_mu0"), "{names:?}");
}

fn bad(study_text: &str, extra: &[&str]) -> String {
    let dir = scratch("bad");
    let path = dir.join("bad.toml");
    std::fs::write(&path, study_text).unwrap();
    let mut args = vec![
        "run",
        path.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = kick(&args);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!dir.join("bad").join("summary.json").exists());
    let err = stderr(&o);
    assert!(err.contains("bad.toml"), "names the file: {err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

const GOOD: &str = r#"
[scene]
t_end = 0.01
[[scene.body]]
rect = [0.0, 0.0, 0.2, 0.4]
material = "water"
[materials.water]
K = 1.5e5
"#;

#[test]
fn bad_study_files_exit_2_naming_file_key_and_range() {
    let e = bad("[scene\nbox = 1", &[]);
    assert!(e.contains("not valid TOML"), "{e}");
    let e = bad(&GOOD.replace("K = 1.5e5", "K = -3"), &[]);
    assert!(
        e.contains("materials.water.K") && e.contains("allowed"),
        "{e}"
    );
    let e = bad(
        &GOOD.replace("t_end = 0.01", "t_end = 0.01\nbogus = 1"),
        &[],
    );
    assert!(
        e.contains("scene.bogus") && e.contains("unknown key"),
        "{e}"
    );
    let e = bad(&format!("{GOOD}\n[method]\nshape = \"quartic\"\n"), &[]);
    assert!(e.contains("method.shape") && e.contains("bspline2"), "{e}");
    let e = bad(&format!("{GOOD}\n[method]\ncfl = 3.0\n"), &[]);
    assert!(e.contains("method.cfl") && e.contains("allowed"), "{e}");
    let e = bad(
        &GOOD.replace("material = \"water\"", "material = \"oil\""),
        &[],
    );
    assert!(
        e.contains("scene.body[0].material") && e.contains("oil"),
        "{e}"
    );
    let e = bad(
        &GOOD.replace("[0.0, 0.0, 0.2, 0.4]", "[0.0, 0.0, 0.2]"),
        &[],
    );
    assert!(e.contains("scene.body[0].rect"), "{e}");
    let e = bad(
        &GOOD.replace("[0.0, 0.0, 0.2, 0.4]", "[0.0, 0.0, 0.2, 0.9]"),
        &[],
    );
    assert!(
        e.contains("scene.body[0].rect") && e.contains("inside the box"),
        "{e}"
    );
    let e = bad(GOOD, &["--set", "scene.ppc=99"]);
    assert!(e.contains("scene.ppc") && e.contains("1 ..= 8"), "{e}");
    let e = bad(GOOD, &["--case", "nope"]);
    assert!(e.contains("unknown case"), "{e}");
    let e = bad(
        &format!("{GOOD}\n[[perturb]]\nregion = [0, 0, 1, 1]\ndv = [1, 0]\n"),
        &[],
    );
    assert!(
        e.contains("perturb[0].step") && e.contains("required"),
        "{e}"
    );
}

#[test]
fn missing_study_file_exits_2() {
    let o = kick(&["run", "studies/does_not_exist.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("does_not_exist.toml"));
}

#[test]
fn bench_prints_one_json_line() {
    let o = kick(&[
        "bench",
        "--scene",
        "mpm88",
        "--steps",
        "20",
        "--threads",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    assert_eq!(text.lines().count(), 1);
    let v: serde_json::Value = serde_json::from_str(text.trim()).unwrap();
    assert_eq!(v["scene"], "mpm88");
    assert_eq!(v["particles"], 8192);
    assert_eq!(v["steps"], 20);
    assert_eq!(v["threads"], 1);
    assert!(v["particle_steps_per_s"].as_f64().unwrap() > 0.0);
    assert!(v["seconds"].as_f64().unwrap() > 0.0);
}
