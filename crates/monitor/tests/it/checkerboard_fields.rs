//! The checkerboard measures (docs/physics.md section 4) recover a mode
//! planted in the field each one reads, within 10 %: the nodal measure in
//! J-bar's nodal J, in pressure smoothing's nodal p and in the plain
//! projection of the particle pressure; the cell measure in cell
//! dilatation's cell J; the index of the cell means in the particle J
//! (volume relaxation) and the plain particle pressure. An exact
//! hydrostatic layer reads below 0.01 on every measure.
//!
//! The mode is planted in the particles' J about J0 = 0.98 (compressed:
//! no tension cut): +-eps by the parity of the particle's nearest node (a
//! nodal mode) or of its cell (a cell mode). With 2 x 2 particles per cell
//! and quadratic B-splines, the round trip sum N m q / sum N m of a nodal
//! mode keeps kappa = (2 (N(1/4) - N(3/4) - N(5/4)) / 2)^2 = 0.375^2 of it
//! at an interior node. One step of 1 microsecond moves nothing that
//! matters.

use monitor::checkerboard_fields::alternating_amplitude;
use monitor::{Monitor, MonitorConfig};
use solver::remedies::{cell_dilatation, j_bar, pressure_smoothing, volume_relaxation};
use solver::*;

use crate::common;

const H: f64 = 0.01;
const J0: f64 = 0.98;
const EPS: f64 = 1e-3;
const KAPPA: f64 = 0.140625;
const K: f64 = 2e4;
/// The measures' unit: rho0 g h (g = 9.81 without gravity).
const UNIT: f64 = 1000.0 * 9.81 * H;

#[derive(Clone, Copy)]
enum Mode {
    Nodal,
    Cell,
}

fn method(set: impl FnOnce(&mut Method)) -> Method {
    // The modern baseline: quadratic B-splines, APIC, USL.
    let mut m = Method {
        shape: ShapeKind::Bspline2,
        transfer: TransferKind::Apic,
        scheme: SchemeKind::Usl,
        dt: DtMode::Fixed,
        dt_value: Some(1e-6),
        ..Method::baseline()
    };
    set(&mut m);
    m
}

/// A 0.24 m box full of water at J0 with the mode planted, stepped once.
fn planted(mode: Mode, method: Method) -> Solver {
    let scene = common::water_box([0.24, 0.24], [0.0, 0.0, 0.24, 0.24], Material::tait(K), 0.0);
    let mut ps = solver::scene::seed(&scene);
    for p in 0..ps.len() {
        let x = ps.x[p] / H;
        let parity = match mode {
            Mode::Nodal => x.x.round() as i64 + x.y.round() as i64,
            Mode::Cell => x.x.floor() as i64 + x.y.floor() as i64,
        };
        let j = J0 + if parity % 2 == 0 { EPS } else { -EPS };
        ps.j[p] = j;
        ps.f[p] = Mat2::identity() * j.sqrt();
        ps.vol[p] = ps.vol0[p] * j;
    }
    let cfg = SolverConfig {
        scene,
        method,
        perturb: vec![],
    };
    let mut s = Solver::with_particles(cfg, ps);
    s.step().unwrap();
    s
}

/// The pressure amplitude of a +-d mode of J about j.
fn amplitude(j: f64, d: f64) -> f64 {
    let m = Material::tait(K);
    let p = |j: f64| m.cut(m.eos(j).pressure);
    (p(j - d) - p(j + d)).abs() / 2.0
}

fn measures(s: &Solver) -> monitor::FieldMetrics {
    let mut m = Monitor::new(MonitorConfig::default(), &s.view());
    m.field_metrics(&s.view())
}

fn recovered(name: &str, read: Option<f64>, planted: f64) {
    let read = read.unwrap_or_else(|| panic!("{name}: no reading"));
    eprintln!("{name}: read {read:.5}, planted {planted:.5}");
    assert!(
        (read / planted - 1.0).abs() < 0.1,
        "{name}: read {read}, planted {planted}"
    );
}

#[test]
fn the_nodal_measure_reads_j_bars_nodal_j() {
    let s = planted(
        Mode::Nodal,
        method(|m| m.remedies.j_bar = Some(j_bar::Settings::default())),
    );
    let f = measures(&s);
    recovered(
        "J-bar nodal J",
        f.checkerboard_nodal,
        amplitude(J0, EPS * KAPPA) / UNIT,
    );
    // The cell means of the particles' pressure, read back from those
    // nodes, do not see it: two particles of a cell read it with opposite
    // signs.
    let v = s.view();
    let cells = [24usize, 24];
    let mut sum = vec![0.0; 24 * 24];
    let mut count = vec![0.0; 24 * 24];
    for (x, p) in v.x.iter().zip(v.pressure) {
        let c = (x.x / H) as usize + 24 * (x.y / H) as usize;
        sum[c] += p;
        count[c] += 1.0;
    }
    let means =
        alternating_amplitude(cells, |i, j| Some(sum[i + 24 * j] / count[i + 24 * j])).unwrap();
    assert!(
        means < 1e-3 * f.checkerboard_nodal.unwrap() * UNIT,
        "cell means carry {means} Pa of it"
    );
}

#[test]
fn the_nodal_measure_reads_pressure_smoothings_nodal_p() {
    let s = planted(
        Mode::Nodal,
        method(|m| m.remedies.pressure_smoothing = Some(pressure_smoothing::Settings {})),
    );
    recovered(
        "pressure smoothing nodal p",
        measures(&s).checkerboard_nodal,
        KAPPA * amplitude(J0, EPS) / UNIT,
    );
}

#[test]
fn the_nodal_measure_reads_the_projection_of_the_particle_pressure() {
    let s = planted(Mode::Nodal, method(|_| {}));
    let f = measures(&s);
    recovered(
        "projection",
        f.checkerboard_nodal,
        KAPPA * amplitude(J0, EPS) / UNIT,
    );
    assert_eq!(f.checkerboard_cell, None, "no cell pressure");
}

#[test]
fn the_cell_measure_reads_cell_dilatations_cell_j() {
    let s = planted(
        Mode::Cell,
        method(|m| m.remedies.cell_dilatation = Some(cell_dilatation::Settings::default())),
    );
    recovered(
        "cell dilatation cell J",
        measures(&s).checkerboard_cell,
        amplitude(J0, EPS) / UNIT,
    );
}

#[test]
fn the_cell_means_read_a_mode_of_the_particle_j() {
    for (name, m) in [
        ("plain", method(|_| {})),
        (
            "volume relaxation",
            method(|m| {
                m.remedies.volume_relaxation = Some(volume_relaxation::Settings { time: 0.16 })
            }),
        ),
    ] {
        let s = planted(Mode::Cell, m);
        // A pure mode on a uniform field: the whole variance is the mode.
        recovered(name, measures(&s).checkerboard_means, 1.0);
    }
}

#[test]
fn a_hydrostatic_layer_reads_below_a_hundredth_on_every_measure() {
    let methods = [
        ("plain", method(|_| {})),
        (
            "j_bar",
            method(|m| m.remedies.j_bar = Some(j_bar::Settings::default())),
        ),
        (
            "pressure_smoothing",
            method(|m| m.remedies.pressure_smoothing = Some(pressure_smoothing::Settings {})),
        ),
        (
            "cell_dilatation",
            method(|m| m.remedies.cell_dilatation = Some(cell_dilatation::Settings::default())),
        ),
    ];
    for (name, method) in methods {
        let mut scene = common::water_box(
            [0.2, 0.2],
            [0.0, 0.0, 0.2, 0.15],
            Material::tait(1.5e5),
            9.81,
        );
        scene.initial = InitialState::Hydrostatic;
        // The seeding's exact hydrostatic J (no relaxation), one step of
        // 1 microsecond.
        let particles = solver::scene::seed(&scene);
        let cfg = SolverConfig {
            scene,
            method,
            perturb: vec![],
        };
        let mut s = Solver::with_particles(cfg, particles);
        s.step().unwrap();
        let f = measures(&s);
        eprintln!(
            "{name}: means {:?}, nodal {:?}, cell {:?}",
            f.checkerboard_means, f.checkerboard_nodal, f.checkerboard_cell
        );
        for (measure, v) in [
            ("means", f.checkerboard_means),
            ("nodal", f.checkerboard_nodal),
            ("cell", f.checkerboard_cell),
        ] {
            assert!(v.unwrap_or(0.0) < 0.01, "{name}: {measure} reads {v:?}");
        }
        assert!(
            f.checkerboard_nodal.is_some(),
            "{name}: the nodal measure read nothing"
        );
    }
}
