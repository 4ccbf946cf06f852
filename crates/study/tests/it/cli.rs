//! End-to-end tests of the `kick` binary.

use crate::common;

use common::{kick, stderr, SMALL_MATRIX};
use monitor::EventKind;
use std::path::PathBuf;
use std::process::Command;
use study::output::summary::{Status, Summary};
use study::run::probes::surge_front::SurgeFrontFigures;

fn scratch(name: &str) -> common::Scratch {
    common::scratch("cli", name)
}

fn summary(dir: &std::path::Path) -> Summary {
    Summary::read(dir).unwrap()
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
        "--csv",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dir = out.join("dam_break");
    let s = summary(&dir);
    assert_eq!(s.status, Status::Completed);
    assert_eq!(s.params["method.shape"], "bspline2");
    assert!((s.t_end - 0.05).abs() < 1e-12);
    let steps = s.steps;
    assert!(steps > 10);
    assert!(s.wall_s > 0.0);
    assert!(s.particle_steps_per_s > 0.0);
    assert_eq!(s.particles, 3200);
    let csv = std::fs::read_to_string(dir.join("timeseries.csv")).unwrap();
    let last = csv.lines().last().unwrap();
    assert!(last.starts_with(&format!("{steps},")), "{last}");
    // Particle files as .vtu, one ParaView time series (.pvd) listing them all.
    let vtu: Vec<String> = std::fs::read_dir(dir.join("particles"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".vtu"))
        .collect();
    assert!(vtu.len() >= 2, "{vtu:?}");
    let pvd = std::fs::read_to_string(dir.join("particles").join("particles.pvd")).unwrap();
    for f in &vtu {
        assert!(pvd.contains(&format!("file=\"{f}\"")), "{f} in {pvd}");
    }
    assert!(pvd.contains("timestep=\"0\""), "{pvd}");
    let last =
        study::output::vtu::read_file(&dir.join("particles").join(vtu.iter().max().unwrap()))
            .unwrap();
    assert_eq!(last.x.len(), 3200);
    assert_eq!(last.t, s.t_end);
    let parquet = std::fs::read(dir.join("timeseries.parquet")).unwrap();
    assert_eq!(&parquet[..4], b"PAR1");
    let header = csv.lines().next().unwrap();
    for col in [
        "step",
        "e_total",
        "energy_injected",
        "max_accel_g",
        "max_jump",
        "gravity_stepping",
        "checkerboard_means",
        "checkerboard_nodal",
        "checkerboard_cell",
        "budget_closure",
        "booked_j_bar_dissipated",
        "hydro_rel_rms",
        "hydro_floor_rel_rms",
        "hydro_excess_rel_rms",
        "front_x",
        "courant",
        "j_min",
        "j_max",
        "n_outside",
    ] {
        assert!(header.split(',').any(|c| c == col), "{col} in {header}");
    }
    let case_toml = std::fs::read_to_string(dir.join("case.toml")).unwrap();
    assert!(case_toml.contains("bspline2"), "{case_toml}");
    // The file itself: a versioned schema with every metric present (null when undefined).
    let raw = common::summary_json(&dir);
    assert_eq!(
        raw["schema_version"],
        study::output::summary::SCHEMA_VERSION
    );
    for k in [
        "hydro_rel_rms_late",
        "hydro_floor_late",
        "hydro_excess_late",
        "hydro_max_late",
        "checkerboard_means_late",
        "checkerboard_means_peak",
        "checkerboard_nodal_late",
        "budget_closure_max",
        "energy_injected_max",
    ] {
        assert!(
            raw["metrics"]["figures"].get(k).is_some(),
            "figure {k}: {}",
            raw["metrics"]
        );
    }
    assert!(raw["metrics"].get("t_first_kick").is_some());
    assert!(raw["metrics"]["checks"]["surge_front"]
        .get("rms_error")
        .is_some());
    assert!(s.metrics.figure("hydro_rel_rms_late").is_some());
    // 0.05 s is T = 0.5, before the first Martin & Moyce point (T = 0.83).
    let front = s.metrics.check::<SurgeFrontFigures>().unwrap();
    assert_eq!(front.rms_error, None);
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
    assert_eq!(s.status, Status::BlewUp, "{s:?}");
    let steps = s.steps;
    let reason = &s.reason;
    assert!(reason.contains(&format!("step {steps}")), "{reason}");
    assert!(
        reason.contains("left the box") || reason.contains("non-finite") || reason.contains("grid")
    );
    assert!(s.t_end < 1.0);
    // The blow-out is logged as an event at the last step, and the front was
    // compared with Martin & Moyce up to then (Z units).
    let last = s.events.last().unwrap();
    assert_eq!(last.kind, EventKind::BlowOut, "{last:?}");
    assert_eq!(last.first_step, steps);
    let front = s
        .metrics
        .check::<SurgeFrontFigures>()
        .unwrap()
        .rms_error
        .unwrap();
    assert!(front > 0.0 && front < 1.0, "{front}");
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
    // 64 cases x an ensemble of 3.
    assert_eq!(names.len(), 192);
    let unique: std::collections::BTreeSet<_> = names.iter().collect();
    assert_eq!(unique.len(), 192, "case names are unique");
    for member in ["e0", "e1", "e2"] {
        assert!(
            names.contains(&format!("K1.5MPa_tait_mu0.5_fixed_{member}").as_str()),
            "{names:?}"
        );
        assert!(
            names.contains(&format!("K15kPa_power-g1_mu0_dyn_{member}").as_str()),
            "{names:?}"
        );
    }
}

/// Every shipped study file is valid: each case passes the solver's checks
/// (a bad combination in a matrix exits 2), and case names are unique.
#[test]
fn every_shipped_study_lists_its_cases() {
    let mut studies: Vec<_> = std::fs::read_dir(common::repo().join("studies"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    studies.sort();
    assert!(studies.len() >= 10, "{studies:?}");
    for study in studies {
        let o = kick(&["list", study.to_str().unwrap()]);
        assert!(o.status.success(), "{}: {}", study.display(), stderr(&o));
        let text = String::from_utf8(o.stdout).unwrap();
        let names: Vec<&str> = text
            .lines()
            .map(|l| l.split('\t').next().unwrap())
            .collect();
        let unique: std::collections::BTreeSet<_> = names.iter().collect();
        assert!(!names.is_empty(), "{}", study.display());
        assert_eq!(
            unique.len(),
            names.len(),
            "{}: names unique",
            study.display()
        );
    }
}

fn bad(study_text: &str, extra: &[&str]) -> String {
    // One folder per call: tests run in parallel.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    let dir = scratch(&format!("bad{call}"));
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
    // The unified model's softening: a fluid has no shear modulus to soften.
    let e = bad(
        &GOOD.replace("K = 1.5e5", "K = 1.5e5\nsoftening_strain = 0.01"),
        &[],
    );
    assert!(
        e.contains("materials.water.softening_strain") && e.contains("shear_modulus > 0"),
        "{e}"
    );
    let e = bad(
        &GOOD.replace(
            "K = 1.5e5",
            "K = 1.5e5\nshear_modulus = 1e4\nsoftening_strain = -1",
        ),
        &[],
    );
    assert!(
        e.contains("materials.water.softening_strain") && e.contains("allowed 0 ..= 1000000"),
        "{e}"
    );
    // A gate must stand on a cell line.
    let e = bad(
        &GOOD
            .replace(
                "t_end = 0.01",
                "t_end = 0.01\ninitial = \"hydrostatic_gate\"",
            )
            .replace("[0.0, 0.0, 0.2, 0.4]", "[0.0, 0.0, 0.205, 0.4]"),
        &[],
    );
    assert!(
        e.contains("scene.initial") && e.contains("not on a cell line"),
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
    // A push at a time and a step both, and a relative push without its direction.
    let e = bad(
        &format!("{GOOD}\n[[perturb]]\nstep = 3\nt = 0.1\nregion = [0, 0, 1, 1]\ndv = [1, 0]\n"),
        &[],
    );
    assert!(
        e.contains("perturb[0].step | t") && e.contains("got both"),
        "{e}"
    );
    let e = bad(
        &format!("{GOOD}\n[[perturb]]\nt = 0.1\nplace = \"bulk\"\ncells = 2\nspeed = 0.05\n"),
        &[],
    );
    assert!(
        e.contains("perturb[0].direction") && e.contains("required"),
        "{e}"
    );
    // A planted stress outlier's J factor out of range, and a plant of nothing.
    let e = bad(
        &format!("{GOOD}\n[[perturb]]\nt = 0.1\nregion = [0, 0, 1, 1]\nj_scale = 3.0\n"),
        &[],
    );
    assert!(
        e.contains("perturb[0].j_scale") && e.contains("0.5 ..= 2"),
        "{e}"
    );
    let e = bad(
        &format!("{GOOD}\n[[perturb]]\nt = 0.1\nregion = [0, 0, 1, 1]\n"),
        &[],
    );
    assert!(
        e.contains("perturb[0].dv | speed | j_scale | dx") && e.contains("at least one"),
        "{e}"
    );
    let e = bad(
        &format!(
            "{GOOD}\n[[perturb]]\nt = 0.1\nplace = \"middle\"\nspeed = 0.05\ndirection = \"up\"\n"
        ),
        &[],
    );
    assert!(e.contains("perturb") && e.contains("place"), "{e}");
}

/// A TOML syntax error names the file, the line and the column (toml's span,
/// counted from the text), quotes the line, and exits 2.
#[test]
fn toml_syntax_errors_name_file_line_and_column() {
    // A malformed table header on line 3: toml stops at column 12, after `[scene.body`.
    let e = bad(
        "[scene]\nt_end = 0.01\n[scene.body\nrect = [0, 0, 1, 1]\n",
        &[],
    );
    assert!(e.contains("not valid TOML"), "{e}");
    assert!(e.contains("line 3, column 12"), "{e}");
    assert!(e.contains("[scene.body"), "quotes the line: {e}");
    // A bad value further down, after a multi-byte character on the same line.
    let e = bad(&format!("{GOOD}\n[method]\nshape = \"é\" x\n"), &[]);
    let line = GOOD.lines().count() + 3;
    assert!(e.contains(&format!("line {line}, column 13")), "{e}");
}

/// The flat remedy keys of older study files exit 2 and name the sub-table
/// that replaced them; a remedy's own table is checked like any section.
#[test]
fn old_flat_remedy_keys_exit_2_naming_the_new_key() {
    for (method, key, new) in [
        (
            "j_bar = 1.0",
            "`method.j_bar`",
            "[method.j_bar] blend = 1.0",
        ),
        (
            "j_bar_fit = \"linear\"",
            "`method.j_bar_fit`",
            "[method.j_bar] fit",
        ),
        (
            "volume_relaxation_time = 0.16",
            "`method.volume_relaxation_time`",
            "[method.volume_relaxation] time",
        ),
        (
            "shift_time = 0.02",
            "`method.shift_time`",
            "[method.shifting] time",
        ),
        (
            "pic_damping_time = 5e-5",
            "`method.pic_damping_time`",
            "[method.pic_damping] time",
        ),
        (
            "bulk_damping = 0.3",
            "`method.bulk_damping`",
            "[method.bulk_damping] coefficient = 0.3",
        ),
    ] {
        let e = bad(&format!("{GOOD}\n[method]\n{method}\n"), &[]);
        assert!(e.contains(key) && e.contains(new), "{method}: {e}");
    }
    let e = bad(&format!("{GOOD}\n[method.j_bar]\nblend = 2.0\n"), &[]);
    assert!(
        e.contains("method.j_bar.blend") && e.contains("allowed"),
        "{e}"
    );
    let e = bad(
        &format!("{GOOD}\n[method.shifting]\n"),
        &["--set", "scene.periodic=[true, false]"],
    );
    assert!(
        e.contains("`method.shifting`") && e.contains("walls"),
        "{e}"
    );
}

#[test]
fn an_unknown_key_in_any_section_exits_2_naming_it_and_the_allowed_keys() {
    let perturb = "[[perturb]]\nstep = 1\nregion = [0, 0, 1, 1]\ndv = [1, 0]\n";
    for (text, key, allowed) in [
        (format!("colour = 1\n{GOOD}"), "colour", "materials"),
        (
            GOOD.replace("t_end = 0.01", "t_end = 0.01\nbogus = 1"),
            "scene.bogus",
            "ppc",
        ),
        (
            GOOD.replace("material = \"water\"", "material = \"water\"\nspin = 1"),
            "scene.body[0].spin",
            "velocity",
        ),
        (
            GOOD.replace("K = 1.5e5", "K = 1.5e5\nmu = 1"),
            "materials.water.mu",
            "viscosity",
        ),
        (
            format!("{GOOD}\n[method]\nflip = 1\n"),
            "method.flip",
            "flip_alpha",
        ),
        (
            format!("{GOOD}\n[monitor]\njump = 1\n"),
            "monitor.jump",
            "jump_speed",
        ),
        (
            format!("{GOOD}\n[output]\nrows = 1\n"),
            "output.rows",
            "timeseries_rows",
        ),
        (
            format!("{GOOD}\n{perturb}size = 1\n"),
            "perturb[0].size",
            "region",
        ),
    ] {
        let e = bad(&text, &[]);
        assert!(
            e.contains(&format!("`{key}`")) && e.contains("unknown key") && e.contains(allowed),
            "{key}: {e}"
        );
    }
    // A value of the wrong type or out of range in the typed sections.
    let e = bad(&format!("{GOOD}\n[monitor]\njump_z = -1.0\n"), &[]);
    assert!(e.contains("monitor.jump_z") && e.contains("allowed"), "{e}");
    let e = bad(&format!("{GOOD}\n[output]\ntimeseries_rows = 0\n"), &[]);
    assert!(
        e.contains("output.timeseries_rows") && e.contains("allowed"),
        "{e}"
    );
    let e = bad(&GOOD.replace("K = 1.5e5", "K = \"stiff\""), &[]);
    assert!(
        e.contains("materials.water.K") && e.contains("a number in Pa, or \"inf\""),
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
fn report_yardsticks_must_be_matrix_folders() {
    let dir = scratch("yardsticks");
    let d = dir.to_str().unwrap();
    let o = kick(&["report", d, "--yardsticks", "no/such/folder"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("no/such/folder"), "{}", stderr(&o));
    let o = kick(&["report", d, "--yardsticks", d]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not a matrix folder"), "{}", stderr(&o));
}

#[test]
fn report_behaviour_runs_must_be_records_beside_a_matrix() {
    let dir = scratch("behaviour_runs");
    let d = dir.to_str().unwrap();
    let o = kick(&["report", d, "--behaviour-runs", "no/such.jsonl"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not a matrix folder"), "{}", stderr(&o));
    std::fs::write(dir.join("summary.parquet"), b"").unwrap();
    let o = kick(&["report", d, "--behaviour-runs", "no/such.jsonl"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("no/such.jsonl"), "{}", stderr(&o));
    let bad = dir.join("bad.jsonl");
    std::fs::write(&bad, "{\"summary\": 1}\n").unwrap();
    let o = kick(&["report", d, "--behaviour-runs", bad.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("line 1"), "{}", stderr(&o));
}

#[test]
fn report_baseline_must_be_a_case_of_the_matrix() {
    let dir = scratch("baseline");
    let d = dir.to_str().unwrap();
    let o = kick(&["report", d, "--baseline", "no_such_case"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--baseline no_such_case"),
        "{}",
        stderr(&o)
    );
    assert!(
        stderr(&o).contains("not a readable matrix folder"),
        "{}",
        stderr(&o)
    );
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
    // The monitor is timed apart from the solver.
    assert!(v["monitor_seconds"].as_f64().unwrap() > 0.0);
    let with = v["particle_steps_per_s_with_monitor"].as_f64().unwrap();
    assert!(with > 0.0 && with < v["particle_steps_per_s"].as_f64().unwrap());
    assert_eq!(v["particles_outside_max"], 0);
    assert!(v["blow_out"].is_null());
}

#[test]
fn bench_set_times_a_remedy_and_refuses_a_bad_key() {
    let args = |set: &str| -> Vec<String> {
        [
            "bench",
            "--scene",
            "dam-break",
            "--steps",
            "5",
            "--shape",
            "bspline2",
            "--transfer",
            "apic",
            "--set",
            set,
        ]
        .map(String::from)
        .to_vec()
    };
    let run = |set: &str| {
        let a = args(set);
        kick(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let o = run("method.f_reset=true");
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value =
        serde_json::from_str(String::from_utf8(o.stdout).unwrap().trim()).unwrap();
    assert_eq!(v["method_sets"][0], "method.f_reset=true");
    // MLS on linear shapes, an unknown key, a scene key: exit 2, named.
    let o = kick(&[
        "bench",
        "--scene",
        "dam-break",
        "--steps",
        "5",
        "--set",
        "method.force=mls",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("method.force"), "{}", stderr(&o));
    for bad in ["method.no_such_key=1", "scene.cell=0.02"] {
        let o = run(bad);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", stderr(&o));
    }
}

fn rows(csv: &str) -> Vec<Vec<String>> {
    csv.lines()
        .map(|l| l.split(',').map(|c| c.to_string()).collect())
        .collect()
}

#[test]
fn matrix_runs_cases_in_parallel_and_writes_the_tables() {
    let out = scratch("matrix");
    let study = out.join("small.toml");
    std::fs::write(&study, SMALL_MATRIX).unwrap();
    let o = kick(&[
        "matrix",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--jobs",
        "2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("2 cases: 2 completed"), "{text}");
    let table = rows(&std::fs::read_to_string(out.join("summary.csv")).unwrap());
    assert_eq!(table.len(), 3, "header + one row per case");
    let header = &table[0];
    for col in [
        "case",
        "materials.water.K",
        "method.shape",
        "method.transfer",
        "method.cfl",
        "status",
        "steps",
        "wall_s",
        "particle_steps_per_s",
        "t_first_kick",
        "figures.hydro_rel_rms_late",
        "causes.injection.count",
    ] {
        assert!(header.iter().any(|c| c == col), "{col} in {header:?}");
    }
    let k = header
        .iter()
        .position(|c| c == "materials.water.K")
        .unwrap();
    let shape = header.iter().position(|c| c == "method.shape").unwrap();
    let mut ks: Vec<f64> = table[1..].iter().map(|r| r[k].parse().unwrap()).collect();
    ks.sort_by(f64::total_cmp);
    assert_eq!(ks, vec![1.5e4, 1.5e5]);
    assert!(table[1..].iter().all(|r| r[shape] == "linear"));
    assert_eq!(
        &std::fs::read(out.join("summary.parquet")).unwrap()[..4],
        b"PAR1"
    );
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["state"], "finished");
    assert_eq!(manifest["cases"].as_array().unwrap().len(), 2);
    // Shards: 0/2 and 1/2 split the cases, --merge joins them.
    let (a, b) = (out.join("shard0"), out.join("shard1"));
    for (i, dir) in [(0, &a), (1, &b)] {
        let shard = format!("{i}/2");
        let o = kick(&[
            "matrix",
            study.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
            "--shard",
            &shard,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(
            rows(&std::fs::read_to_string(dir.join("summary.csv")).unwrap()).len(),
            2
        );
    }
    let merged = out.join("merged");
    let o = kick(&[
        "matrix",
        "--merge",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        rows(&std::fs::read_to_string(merged.join("summary.csv")).unwrap()).len(),
        3
    );
    let o = kick(&["matrix", study.to_str().unwrap(), "--shard", "2/2"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

#[test]
fn report_of_a_one_case_shard_reads_its_case() {
    // A one-row summary's case_dir reads back as an owned string, which
    // the report once quoted into the path.
    let out = scratch("one_case");
    let study = out.join("small.toml");
    std::fs::write(&study, SMALL_MATRIX).unwrap();
    let d = out.to_str().unwrap();
    let o = kick(&[
        "matrix",
        study.to_str().unwrap(),
        "--out",
        d,
        "--shard",
        "0/2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = kick(&["report", d]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("report").join("index.html").exists());
}

#[test]
fn matrix_skips_the_cases_a_behaviour_record_holds_with_the_same_parameters() {
    let out = scratch("skip_recorded");
    let study = out.join("small.toml");
    std::fs::write(&study, SMALL_MATRIX).unwrap();
    let (st, first) = (study.to_str().unwrap(), out.join("first"));
    let f = first.to_str().unwrap();
    let o = kick(&["matrix", st, "--out", f, "--jobs", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = kick(&["report", f]);
    assert!(o.status.success(), "{}", stderr(&o));
    let lines = std::fs::read_to_string(first.join("report").join("behaviour_runs.jsonl")).unwrap();
    assert_eq!(lines.lines().count(), 2, "{lines}");
    // A record of one of the two cases.
    let record = out.join("one.jsonl");
    std::fs::write(&record, format!("{}\n", lines.lines().next().unwrap())).unwrap();
    let r = record.to_str().unwrap();
    // The recorded case is skipped, the other runs.
    let second = out.join("second");
    let s = second.to_str().unwrap();
    let o = kick(&[
        "matrix",
        st,
        "--out",
        s,
        "--skip-recorded",
        r,
        "--jobs",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("ran 1 cases (1 already done)"), "{text}");
    // Recorded with other parameters, it runs again, and says why.
    let third = out.join("third");
    let t = third.to_str().unwrap();
    let o = kick(&[
        "matrix",
        st,
        "--out",
        t,
        "--skip-recorded",
        r,
        "--jobs",
        "1",
        "--set",
        "scene.t_end=0.04",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("ran 2 cases (0 already done)"));
    assert!(
        stderr(&o).contains("recorded with other parameters"),
        "{}",
        stderr(&o)
    );
    // Every case recorded: the matrix runs none, and its report scores
    // the four behaviours from the record alone.
    let full = out.join("full.jsonl");
    std::fs::write(&full, &lines).unwrap();
    let fourth = out.join("fourth");
    let (full, f4) = (full.to_str().unwrap(), fourth.to_str().unwrap());
    let o = kick(&["matrix", st, "--out", f4, "--skip-recorded", full]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("ran 0 cases (2 already done)"));
    let o = kick(&["report", f4, "--behaviour-runs", full]);
    assert!(o.status.success(), "{}", stderr(&o));
    let page = std::fs::read_to_string(fourth.join("report").join("index.html")).unwrap();
    assert!(
        page.contains("The four behaviours of the bug report"),
        "{page}"
    );
    let again =
        std::fs::read_to_string(fourth.join("report").join("behaviour_runs.jsonl")).unwrap();
    assert_eq!(again.lines().count(), 2, "{again}");
    // A record that is not one is bad input, named by file and line.
    let bad = out.join("bad.jsonl");
    std::fs::write(&bad, "{\"summary\": 1}\n").unwrap();
    let o = kick(&[
        "matrix",
        st,
        "--out",
        t,
        "--skip-recorded",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--skip-recorded") && stderr(&o).contains("line 1"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn matrix_resumes_after_sigkill_without_redoing_finished_cases() {
    let out = scratch("resume");
    let study = out.join("three.toml");
    std::fs::write(
        &study,
        SMALL_MATRIX
            .replace("t_end = 0.05", "t_end = 0.25")
            .replace("[1.5e4, 1.5e5]", "[1.5e4, 2.0e4, 2.5e4]"),
    )
    .unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_kick"))
        .args([
            "matrix",
            study.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--jobs",
            "1",
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let case_dirs: Vec<PathBuf> = ["K15kPa", "K20kPa", "K25kPa"]
        .iter()
        .map(|n| out.join(n))
        .collect();
    let started = std::time::Instant::now();
    while !case_dirs.iter().any(|d| d.join("summary.json").exists()) {
        assert!(started.elapsed().as_secs() < 120, "no case finished");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let done: Vec<(PathBuf, Vec<u8>)> = case_dirs
        .iter()
        .filter_map(|d| {
            std::fs::read(d.join("summary.json"))
                .ok()
                .map(|b| (d.clone(), b))
        })
        .collect();
    assert!(
        !done.is_empty() && done.len() < 3,
        "killed mid-matrix: {} done",
        done.len()
    );
    for (_, bytes) in &done {
        let v: Summary = serde_json::from_slice(bytes).expect("finished summaries are whole");
        assert_eq!(v.status, Status::Completed);
    }
    let o = kick(&[
        "matrix",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--resume",
        "--jobs",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(&format!(
            "ran {} cases ({} already done)",
            3 - done.len(),
            done.len()
        )),
        "{text}"
    );
    for (dir, bytes) in &done {
        assert_eq!(
            &std::fs::read(dir.join("summary.json")).unwrap(),
            bytes,
            "not redone"
        );
    }
    assert_eq!(
        rows(&std::fs::read_to_string(out.join("summary.csv")).unwrap()).len(),
        4
    );
}

#[test]
fn ensemble_members_differ_by_their_seed_and_each_reproduces() {
    let out = scratch("ensemble");
    let study = out.join("ens.toml");
    std::fs::write(
        &study,
        r#"
[scene]
t_end = 0.06
[[scene.body]]
rect = [0.0, 0.0, 0.2, 0.4]
[materials.water]
K = 1.5e5
eos = "tait"
[output]
checkpoint_every = 100
[[perturb]]
step = 300
region = [0.06, 0.1, 0.09, 0.13]
dv = [1.0, 0.0]
[matrix]
ensemble = 2
"#,
    )
    .unwrap();
    let o = kick(&[
        "matrix",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--jobs",
        "2",
        "--threads",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let members: Vec<Summary> = ["ens_e0", "ens_e1"]
        .iter()
        .map(|m| summary(&out.join(m)))
        .collect();
    assert_ne!(
        members[0].final_state_hash, members[1].final_state_hash,
        "the jitter seeds the members apart"
    );
    assert_eq!(members[1].params["scene.seed"], 1);
    let o = kick(&["report", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let page = std::fs::read_to_string(out.join("report").join("index.html")).unwrap();
    assert!(page.contains("<h2>Ensembles</h2>"), "an ensemble table");
    // A baseline must be a case of this matrix.
    let o = kick(&["report", out.to_str().unwrap(), "--baseline", "ens_e7"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("no such case"), "{}", stderr(&o));
    let o = kick(&["report", out.to_str().unwrap(), "--baseline", "ens_e1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for (m, s) in ["ens_e0", "ens_e1"].iter().zip(&members) {
        let e = s
            .events
            .iter()
            // The push, or the event it joined (a kick nearby within merge_seconds).
            .find(|e| e.kind == EventKind::Kick && e.first_step <= 301 && e.last_step >= 300)
            .unwrap_or_else(|| panic!("{m}: the push is logged: {:?}", s.events));
        let o = kick(&[
            "reproduce",
            out.join(m).to_str().unwrap(),
            "--event",
            &e.id.to_string(),
            "--threads",
            "2",
        ]);
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success() && text.contains("hash match"),
            "{m}: {text}{}",
            stderr(&o)
        );
    }
}

/// A 1 m/s push into a quadratic B-spline APIC column at step 300, with
/// checkpoints every 100 steps: the study file, written into `out`.
fn push_study(out: &std::path::Path, t_end: f64) -> std::path::PathBuf {
    let study = out.join("push.toml");
    let text = r#"
[scene]
t_end = T_END
[[scene.body]]
rect = [0.0, 0.0, 0.2, 0.4]
material = "water"
[materials.water]
K = 1.5e5
eos = "tait"
[method]
shape = "bspline2"
transfer = "apic"
[output]
checkpoint_every = 100
[[perturb]]
step = 300
region = [0.06, 0.1, 0.09, 0.13]
dv = [1.0, 0.0]
"#;
    std::fs::write(&study, text.replace("T_END", &t_end.to_string())).unwrap();
    study
}

#[test]
fn reproduce_replays_an_injected_kick_bit_for_bit_on_one_thread() {
    let out = scratch("reproduce");
    // A 1 m/s push into the water at step 300, in a run on 2 threads with
    // checkpoints every 100 steps (so the replay starts at step 200).
    let study = push_study(&out, 0.08);
    let o = kick(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dir = out.join("push");
    let s = summary(&dir);
    assert_eq!(s.status, Status::Completed, "{s:?}");
    let kick_event = s
        .events
        .iter()
        .find(|e| e.kind == EventKind::Kick && e.first_step >= 300)
        .unwrap_or_else(|| panic!("the push is logged: {:?}", s.events));
    let first = kick_event.first_step;
    assert!(first <= 301, "{kick_event:?}");
    let id = kick_event.id.to_string();
    let o = kick(&[
        "reproduce",
        dir.to_str().unwrap(),
        "--event",
        &id,
        "--threads",
        "1",
    ]);
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        stderr(&o)
    );
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(&format!(
            "reproduced event {id} at step {first}: hash match"
        )),
        "{text}"
    );
    let replay = dir.join("reproduce").join(format!("event_{id}"));
    let dense = rows(&std::fs::read_to_string(replay.join("timeseries.csv")).unwrap());
    let steps: Vec<u64> = dense[1..].iter().map(|r| r[0].parse().unwrap()).collect();
    assert_eq!(
        steps.first(),
        Some(&200),
        "starts at the checkpoint before the event"
    );
    assert!(
        steps.windows(2).all(|w| w[1] == w[0] + 1),
        "a row every step"
    );
    assert!(replay
        .join("particles")
        .join(format!("particles_{first:09}.vtu"))
        .exists());

    // Unknown event and a corrupted checkpoint: clear errors, exit 2.
    let o = kick(&["reproduce", dir.to_str().unwrap(), "--event", "999"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no event 999"), "{}", stderr(&o));
    let ckpt = dir.join(kick_event.checkpoint.as_deref().unwrap());
    let mut bytes = std::fs::read(&ckpt).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x40;
    std::fs::write(&ckpt, bytes).unwrap();
    let o = kick(&["reproduce", dir.to_str().unwrap(), "--event", &id]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("corrupted"), "{}", stderr(&o));
}

/// Water at rest (hydrostatic start, linear shapes, FLIP, USL), with one
/// plant at t = 0.05 s: `PLANT` is its region and what it plants.
fn planted_study(out: &std::path::Path, name: &str, plant: &str) -> std::path::PathBuf {
    let study = out.join(format!("{name}.toml"));
    let text = format!(
        r#"
[scene]
box = [0.4, 0.3]
t_end = 0.1
initial = "hydrostatic"
[[scene.body]]
rect = [0.0, 0.0, 0.4, 0.2]
material = "water"
[materials.water]
K = 1.5e5
eos = "tait"
[method]
shape = "linear"
transfer = "flip"
scheme = "usl"
[output]
checkpoint_every = 100
[[perturb]]
t = 0.05
{plant}
"#
    );
    std::fs::write(&study, text).unwrap();
    study
}

/// Runs a planted study and explains its first kick: explain.json.
fn explain_first_kick(out: &std::path::Path, name: &str, plant: &str) -> serde_json::Value {
    let study = planted_study(out, name, plant);
    let o = kick(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dir = out.join(name);
    let s = summary(&dir);
    let event = s
        .events
        .iter()
        .find(|e| e.kind == EventKind::Kick)
        .unwrap_or_else(|| panic!("{name}: the plant kicks: {:?}", s.events));
    let id = event.id.to_string();
    let o = kick(&["explain", dir.to_str().unwrap(), "--event", &id]);
    assert!(o.status.success(), "{}", stderr(&o));
    let file = dir
        .join("explain")
        .join(format!("event_{id}"))
        .join("explain.json");
    serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap()
}

/// The number at `path` in an explain.json (NaN when absent or null).
fn json_f64(j: &serde_json::Value, path: &[&str]) -> f64 {
    path.iter()
        .fold(j, |v, k| &v[*k])
        .as_f64()
        .unwrap_or(f64::NAN)
}

/// The sliver-node plant: the top row's 4 particles of two cells moved
/// 0.2 mm across the surface's node line, their stress untouched.
const SLIVER: &str = "region = [0.19, 0.195, 0.21, 0.2]\ndx = [0.0, 0.00395]";

#[test]
fn explain_names_a_planted_stress_outlier_and_a_planted_sliver_node() {
    let f = json_f64;
    let out = scratch("planted");
    // A stress outlier: one cell of the bulk compressed 5 % (7.5 kPa
    // against the neighbours' 1 kPa). It kicks its neighbours at once:
    // the burst's shares name M3, with no light node and no quiet precursor.
    let j = explain_first_kick(
        &out,
        "outlier",
        "region = [0.2, 0.1, 0.21, 0.11]\nj_scale = 0.95",
    );
    assert_eq!(j["leading"]["mechanism"], "M3 stress outlier", "{j}");
    assert_eq!(f(&j, &["shares", "small_mass_node"]), 0.0, "{j}");
    assert!(f(&j, &["cancellation"]) < 2.0, "{j}");
    assert_eq!(j["precursors"]["named"], "none", "{j}");
    assert!(
        f(&j, &["precursors", "onset_event", "m3_stress_outlier"]) > 0.0,
        "{j}"
    );
    assert_eq!(
        f(&j, &["precursors", "onset_control", "m3_stress_outlier"]),
        0.0
    );
    // A sliver node: the top row's 4 particles of two cells moved 0.2 mm
    // across the surface's node line, their stress untouched. Nothing
    // happens for about 0.04 s, while the light nodes above them drive
    // their velocity gradient; then they kick, as stress outliers (measured:
    // M3 1.0 of the burst, M1 0.45). The precursor over the quiet window
    // is M1, absent from the matched surface boxes.
    let j = explain_first_kick(&out, "sliver", SLIVER);
    assert_eq!(j["precursors"]["named"], "M1 small-mass node", "{j}");
    assert!(
        j["precursors"]["control_boxes"].as_u64().unwrap() >= 2,
        "{j}"
    );
    assert_eq!(
        f(&j, &["precursors", "quiet_control", "m1_light_node"]),
        0.0,
        "{j}"
    );
    assert!(f(&j, &["shares", "small_mass_node"]) > 0.3, "{j}");
    // The kick came at least 0.02 s after the plant (its onset window is
    // the 0.01 s before its first step).
    assert!(f(&j, &["window", "onset_from"]) > 0.06, "{j}");
    // The light nodes drive the sliver's particles off the grid's velocity:
    // in the quiet window they ring more than the matched surface boxes
    // (measured 2.1e-4 against 8.5e-5 of sqrt(g H)).
    let (ringing, control) = (
        f(&j, &["precursors", "ringing_event"]),
        f(&j, &["precursors", "ringing_control"]),
    );
    assert!(control > 0.0 && ringing > 2.0 * control, "{j}");
}

/// `--quiet-window` starts the quiet window where asked, and is refused
/// when no longer than the onset window or with `--counterfactual`.
#[test]
fn explain_takes_the_quiet_window_asked_for() {
    let out = scratch("quiet_window");
    let f = json_f64;
    let j = explain_first_kick(&out, "sliver", SLIVER);
    // Asked for 0.03 s: it starts 0.03 s before the event (0.02 s before
    // the onset window), with fewer quiet steps than the default 0.05 s.
    let dir = out.join("sliver");
    let id = j["event"].to_string();
    let short = out.join("sliver_short");
    let o = kick(&[
        "explain",
        dir.to_str().unwrap(),
        "--event",
        &id,
        "--quiet-window",
        "0.03",
        "--out",
        short.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let k: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(short.join("explain.json")).unwrap())
            .unwrap();
    let quiet =
        |j: &serde_json::Value| f(j, &["window", "onset_from"]) - f(j, &["window", "explain_from"]);
    assert!((quiet(&k) - 0.02).abs() < 1e-9, "{k}");
    assert!((quiet(&j) - 0.04).abs() < 1e-9, "{j}");
    let steps = |j: &serde_json::Value| j["precursors"]["quiet_steps"].as_u64().unwrap();
    assert!(steps(&k) < steps(&j), "{k}");
    // A window no longer than the onset window's is refused, and so is
    // one with the counterfactuals.
    for extra in [["0.01", "--threads"], ["0.5", "--counterfactual"]] {
        let mut args = vec![
            "explain",
            dir.to_str().unwrap(),
            "--event",
            &id,
            "--quiet-window",
        ];
        args.extend(extra);
        if extra[1] == "--threads" {
            args.push("1");
        }
        let o = kick(&args);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("quiet-window"), "{}", stderr(&o));
    }
}

#[test]
fn explain_splits_an_injected_kick_and_replays_single_changes() {
    let out = scratch("explain");
    // The reproduce test's push: 1 m/s into the water at step 300.
    let study = push_study(&out, 0.06);
    let o = kick(&[
        "run",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dir = out.join("push");
    let s = summary(&dir);
    let event = s
        .events
        .iter()
        .find(|e| e.first_step == 300)
        .unwrap_or_else(|| panic!("the push is logged: {:?}", s.events));
    let id = event.id.to_string();
    let o = kick(&[
        "explain",
        dir.to_str().unwrap(),
        "--event",
        &id,
        "--counterfactual",
        "--members",
        "2",
    ]);
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        stderr(&o)
    );
    let folder = dir.join("explain").join(format!("event_{id}"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("explain.json")).unwrap())
            .unwrap();
    assert_eq!(json["matched"], true, "{json}");
    // The event's own checkpoint (step 200 or 300, checkpoints every 100
    // steps) lies inside its quiet window: the replays start from the
    // latest one before it, here step 0's.
    assert_eq!(
        json["checkpoint"], "checkpoints/ring_000000000.ckpt",
        "{json}"
    );
    assert_ne!(
        event.checkpoint.as_deref(),
        Some("checkpoints/ring_000000000.ckpt")
    );
    let explain_from = json["window"]["explain_from"].as_f64().unwrap();
    assert!(
        json["checkpoint_t"].as_f64().unwrap() <= explain_from.max(0.0),
        "{json}"
    );
    // The parts close to round-off, and the push is the impulse. The event
    // grows over the next steps into the neighbours the transfer passes the
    // push on to (measured: impulse 0.83, the transfer's jump 0.16, the
    // internal force 0.015 of sum |dv|^2 over its 9 steps).
    assert!(json["closure_rest_max"].as_f64().unwrap() < 1e-9, "{json}");
    assert_eq!(json["largest_part"]["part"], "impulse", "{json}");
    let share = |k: &str| json["shares"][k].as_f64().unwrap();
    assert!(share("impulse") > 0.8 && share("internal") < 0.05, "{json}");
    let sum: f64 = ["internal", "external", "walls", "jump", "impulse", "rest"]
        .iter()
        .map(|k| json["shares"][k].as_f64().unwrap())
        .sum();
    assert!((sum - 1.0).abs() < 1e-9, "shares sum to {sum}");
    // The control row reproduces the event in both members, each jittered
    // by round-off, with the event's injection.
    let rows = json["counterfactual"].as_array().unwrap();
    let control = &rows[0];
    assert_eq!(control["change"], "unchanged");
    assert_eq!(control["reopened"], 2, "{control}");
    assert_eq!(control["verdict"], "control", "{control}");
    let members = control["members"].as_array().unwrap();
    assert_eq!(members.len(), 2);
    assert_ne!(members[0]["seed"], members[1]["seed"]);
    assert!(
        members.iter().all(|m| m["outcome"] == "completed"),
        "{control}"
    );
    let injected = control["injected"].as_f64().unwrap();
    assert!(
        (injected - event.energy_injected).abs() <= 1e-9 * event.energy_injected,
        "{injected} vs {}",
        event.energy_injected
    );
    // The replays go on 0.2 s past the event, beyond the case's t_end: the
    // push is the first kick in its region, at the event's own time.
    assert!(
        members[0]["steps"].as_u64().unwrap() > event.last_step + 1000,
        "{control}"
    );
    assert_eq!(control["next_kick"][0], 0.0, "{control}");
    // Each change's members carry the control's seeds, and a row is
    // "prevented" only when the event reopened in no member (0 of 2), none
    // blew up or opened another non-physical event, and the median member
    // gained less than the control.
    for r in rows.iter().filter(|r| r["refused"].is_null()) {
        let seeds: Vec<_> = r["members"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| &m["seed"])
            .collect();
        assert_eq!(seeds, [&members[0]["seed"], &members[1]["seed"]], "{r}");
        let prevented = r["reopened"] == 0
            && r["blew_up"] == 0
            && r["moved"] == 0
            && r["injected"].as_f64().unwrap() < injected;
        assert_eq!(r["verdict"] == "prevented", prevented, "{r}");
    }
    let steps = |r: &serde_json::Value| r["members"][0]["steps"].as_u64().unwrap();
    let half = rows.iter().find(|r| r["change"] == "half dt").unwrap();
    assert!(steps(half) > steps(control));
    assert_eq!(rows.len(), 12, "{rows:?}");
    // No remedy to switch off: that row says so.
    let off = rows.iter().find(|r| r["change"] == "remedies off").unwrap();
    assert_eq!(off["verdict"], "refused", "{off}");
    // The pressure-implicit formulation is switched to mid-run: its step
    // follows the flow, so it crosses the window in fewer steps; at the
    // run's own step it takes the control's count.
    let implicit = rows
        .iter()
        .find(|r| r["change"] == "pressure implicit")
        .unwrap();
    assert!(implicit["refused"].is_null(), "{implicit}");
    assert!(steps(implicit) < steps(control), "{implicit}");
    let at_dt = rows
        .iter()
        .find(|r| r["change"] == "pressure implicit at the run's dt")
        .unwrap();
    assert!(at_dt["refused"].is_null(), "{at_dt}");
    assert_eq!(steps(at_dt), steps(control), "{at_dt}");
    // Switched at the quiet window's start, the control is the same replay
    // and the half step covers that window too, so it takes more steps.
    let quiet_out = out.join("switch_at_quiet");
    let o = kick(&[
        "explain",
        dir.to_str().unwrap(),
        "--event",
        &id,
        "--counterfactual",
        "--members",
        "1",
        "--switch-at",
        "quiet",
        "--out",
        quiet_out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let quiet: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(quiet_out.join("explain.json")).unwrap())
            .unwrap();
    // Never before the replay's checkpoint (here t = 0, before the quiet
    // window's start).
    let checkpoint_t = json["checkpoint_t"].as_f64().unwrap();
    assert_eq!(
        quiet["window"]["switch_from"].as_f64().unwrap(),
        explain_from.max(checkpoint_t)
    );
    assert_eq!(json["window"]["switch_from"], json["window"]["onset_from"]);
    let quiet_rows = quiet["counterfactual"].as_array().unwrap();
    let row = |name: &str| quiet_rows.iter().find(|r| r["change"] == name).unwrap();
    assert_eq!(steps(row("unchanged")), steps(control));
    assert!(steps(row("half dt")) > steps(half), "{}", row("half dt"));
    for f in [
        "explain_steps.csv",
        "explain_steps.parquet",
        "explain_cells.png",
        "counterfactual.md",
    ] {
        assert!(folder.join(f).exists(), "{f}");
    }
    // An unknown event: a clear error, exit 2.
    let o = kick(&["explain", dir.to_str().unwrap(), "--event", "999"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no event 999"), "{}", stderr(&o));
    let o = kick(&[
        "explain",
        dir.to_str().unwrap(),
        "--event",
        &id,
        "--members",
        "0",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--members: 0 is out of range"),
        "{}",
        stderr(&o)
    );
}
