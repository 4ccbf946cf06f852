//! `kick calibrate` end to end on a small pool of water at rest: the twins
//! and the detection table, the bisection's bracket, the same patch found at
//! every time step, and bad input.

use crate::common::{self, kick, stderr};
use study::replay::calibrate::Detection;

const STUDY: &str = r#"
name = "tiny_calibration"
[scene]
box = [0.3, 0.2]
cell = 0.01
ppc = 2
t_end = 0.12
gravity = 9.81
initial = "hydrostatic"
[[scene.body]]
rect = [0.0, 0.0, 0.3, 0.15]
material = "water"
[materials.water]
rho0 = 1000.0
eos = "tait"
K = 1.5e6
viscosity = 0.5
[method]
shape = "bspline2"
transfer = "apic"
scheme = "usl"
cfl = 0.2
dt = "dynamic"
[output]
checkpoint_every = 0
[calibration]
plant_t = 0.08
window = 0.04
sizes = [2]
bisect = [0.005, 0.16]
ratio = 1.5
[[calibration.patch]]
place = "bulk"
near = [0.15, 0.07]
[[calibration.patch]]
place = "wall"
near = [0.3, 0.07]
[matrix]
"method" = [{ cfl = 0.1 }, { cfl = 0.4, dt = "fixed" }]
[[matrix.also]]
"method" = [{ formulation = "pressure_implicit" }]
"#;

#[test]
fn calibration_bisects_each_placement_and_finds_the_same_patch_at_every_step() {
    let dir = common::scratch("calibrate", "tiny");
    let study = dir.join("tiny.toml");
    std::fs::write(&study, STUDY).unwrap();
    let out = dir.join("out");
    let o = kick(&[
        "calibrate",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--jobs",
        "2",
        "--threads",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for file in [
        "detection.json",
        "detection.parquet",
        "detection.csv",
        "summary.parquet",
    ] {
        assert!(out.join(file).is_file(), "{file}");
    }
    let d = Detection::read(&out).expect("detection.json reads back");
    // 3 methods x 2 placements x 1 size.
    assert_eq!(d.rows.len(), 6, "{:?}", d.rows);
    for r in &d.rows {
        assert!(r.placed, "{r:?}");
        assert!(r.t_plant_s >= 0.08 && r.t_plant_s < 0.085, "{r:?}");
        let (found, missed) = (r.dv_found.expect("found"), r.dv_missed.expect("a miss"));
        // The bracket closed to the ratio asked, with the miss below the find.
        assert!(found > missed && found / missed <= 1.5 + 1e-12, "{r:?}");
        assert!(
            r.delay_s.unwrap() >= 0.0 && r.delay_s.unwrap() <= 0.04,
            "{r:?}"
        );
        assert_eq!((r.twin_kicks, r.false_alarms), (0, 0), "{r:?}");
        let [x0, y0, x1, y1] = r.region.unwrap();
        assert!(
            ((x1 - x0) - 0.02).abs() < 1e-9 && ((y1 - y0) - 0.02).abs() < 1e-9,
            "{r:?}"
        );
    }
    // The same instrument: each placement's smallest speed found within 2
    // times across the steps (CFL 0.1 dynamic, 0.4 fixed, the implicit step).
    for place in ["bulk", "wall"] {
        let found: Vec<f64> = d
            .rows
            .iter()
            .filter(|r| r.place == place)
            .map(|r| r.dv_found.unwrap())
            .collect();
        let (lo, hi) = found
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(hi / lo <= 2.0, "{place}: {found:?}");
    }
    // The report shows the table.
    let o = kick(&["report", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let page = std::fs::read_to_string(out.join("report/index.html")).unwrap();
    assert!(
        page.contains("<table id=\"detection\">"),
        "no detection table"
    );
}

#[test]
fn calibrate_refuses_a_study_without_its_table_and_a_bad_key() {
    let dir = common::scratch("calibrate", "bad");
    let plain = dir.join("plain.toml");
    let cut = STUDY.find("[calibration]").unwrap();
    let matrix = STUDY.find("[matrix]").unwrap();
    std::fs::write(&plain, format!("{}{}", &STUDY[..cut], &STUDY[matrix..])).unwrap();
    let o = kick(&[
        "calibrate",
        plain.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("key `calibration`"), "{}", stderr(&o));
    let late = dir.join("late.toml");
    std::fs::write(&late, STUDY.replace("plant_t = 0.08", "plant_t = 0.1")).unwrap();
    let o = kick(&[
        "calibrate",
        late.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("calibration.window"), "{}", stderr(&o));
    assert!(stderr(&o).contains("late.toml"), "{}", stderr(&o));
}

/// STUDY planting 0.1 m/s once, every method from the CFL 0.1 case's
/// state 0.03 s before the plant.
fn common_study() -> String {
    STUDY
        .replace("bisect = [0.005, 0.16]\nratio = 1.5", "dv = [0.1]")
        .replace(
            "[calibration]\n",
            "[calibration]\ncommon_state = \"cfl0.1\"\nswitch_lead = 0.03\n",
        )
}

#[test]
fn a_common_state_starts_every_method_from_one_flow() {
    let dir = common::scratch("calibrate", "common");
    let study = dir.join("common.toml");
    std::fs::write(&study, common_study()).unwrap();
    let out = dir.join("out");
    let args = |out: &std::path::Path| {
        vec![
            "calibrate".to_string(),
            study.display().to_string(),
            "--out".into(),
            out.display().to_string(),
            "--jobs".into(),
            "2".into(),
            "--threads".into(),
            "1".into(),
        ]
    };
    let run = |a: Vec<String>| kick(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let o = run(args(&out));
    assert!(o.status.success(), "{}", stderr(&o));
    // The common state was saved at the switch, 0.03 s before the plant.
    let ckpt = std::fs::read(out.join("common_state/plant.ckpt")).unwrap();
    let (_, t_switch) = study::run::checkpoint::clock(&ckpt).unwrap();
    assert!((0.05..0.052).contains(&t_switch), "{t_switch}");
    let d = Detection::read(&out).unwrap();
    assert_eq!(d.rows.len(), 6, "{:?}", d.rows);
    for r in &d.rows {
        assert_eq!(r.dv_found, Some(0.1), "{r:?}");
        assert_eq!((r.twin_kicks, r.false_alarms), (0, 0), "{r:?}");
        // One flow: each placement's patch is the same block under every method.
        let first = d.rows.iter().find(|q| q.place == r.place).unwrap();
        assert_eq!(r.region, first.region, "{r:?}");
    }
    // The common state's own case, switched to its own method, runs on
    // bit for bit as it does from t = 0.
    let plain = dir.join("plain");
    let o = kick(&[
        "matrix",
        study.to_str().unwrap(),
        "--out",
        plain.to_str().unwrap(),
        "--only",
        "cfl0.1",
        "--threads",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let hash = |d: &std::path::Path| {
        study::output::summary::Summary::read(&d.join("cfl0.1"))
            .unwrap()
            .final_state_hash
    };
    assert_eq!(hash(&out), hash(&plain));
    // Resumed, nothing runs again and the table is the same.
    let mut again = args(&out);
    again.push("--resume".into());
    let o = run(again);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(Detection::read(&out).unwrap().rows, d.rows);
}

#[test]
fn a_common_state_must_name_a_case_the_others_can_start_from() {
    let dir = common::scratch("calibrate", "common_bad");
    let refuse = |name: &str, text: String, says: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let o = kick(&[
            "calibrate",
            path.to_str().unwrap(),
            "--out",
            dir.join("o").to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("calibration.common_state"),
            "{}",
            stderr(&o)
        );
        assert!(stderr(&o).contains(says), "{}", stderr(&o));
    };
    refuse(
        "nameless.toml",
        common_study().replace("\"cfl0.1\"", "\"cfl9\""),
        "allowed: cfl0.1",
    );
    let linear = common_study().replace(
        "{ cfl = 0.4, dt = \"fixed\" }",
        "{ shape = \"linear\", transfer = \"flip\" }",
    );
    refuse("linear.toml", linear, "another shape");
    // A case with more particles per cell is another scene.
    let deeper = format!(
        "{}\n[[matrix.also]]\n\"method\" = [{{ cfl = 0.2 }}]\n\"scene.ppc\" = [3]\n",
        common_study()
            .replace("[matrix]\n", "[matrix]\n\"scene.ppc\" = [2]\n")
            .replace("\"cfl0.1\"", "\"ppc2_cfl0.1\"")
    );
    refuse("deeper.toml", deeper, "more than its method");
}
