//! Injected kicks in the dam break after 3 s, on a method and K where it does
//! not kick by itself (quadratic B-spline APIC, Tait K = 1.5 MPa): each 1 m/s
//! [[perturb]] is logged as a kick at its step within the patch plus two
//! cells, no other event starts outside [s, s + 2L/c], and the same window
//! without a perturbation has no event. Default thresholds throughout.

use solver::*;

use crate::common;

/// Cells holding at least half of ppc^2 particles.
fn filled(v: &StateView) -> Vec<Vec<bool>> {
    let [nx, ny] = v.scene.cells();
    let mut count = vec![vec![0; ny]; nx];
    for x in v.x {
        let (i, j) = ((x.x / v.scene.cell) as usize, (x.y / v.scene.cell) as usize);
        count[i.min(nx - 1)][j.min(ny - 1)] += 1;
    }
    count
        .iter()
        .map(|c| c.iter().map(|&n| n >= 2).collect())
        .collect()
}

fn block_filled(f: &[Vec<bool>], i0: usize, j0: usize, n: usize) -> bool {
    (i0..i0 + n).all(|i| (j0..j0 + n).all(|j| f.get(i).and_then(|c| c.get(j)) == Some(&true)))
}

#[test]
fn injected_kicks_after_three_seconds_of_sloshing() {
    let mut scene = Scene::dam_break(common::tait(1.5e6, 0.0));
    scene.t_end = 5.0;
    let cfg = SolverConfig {
        scene,
        method: common::method(ShapeKind::Bspline2, TransferKind::Apic),
        perturb: vec![],
    };
    let mut s = Solver::new(cfg.clone()).unwrap();
    let mut m = common::fresh_monitor(&s);
    while s.time() < 3.0 {
        s.step().unwrap();
        assert!(m.observe(&s.view()).blow_out.is_none());
    }
    let start_step = s.step_count();
    let start = s.checkpoint();
    let c = cfg.scene.materials[0].wave_speed(1.0);
    let window = (2.0 * 0.8 / c / s.next_dt()).ceil() as u64;
    let at = start_step + 20;
    let steps = 20 + window + 100;

    let (quiet, _) = common::run_window(&cfg, &start, &m, vec![], steps);
    let spurious = common::events_after(&quiet, start_step);
    assert!(spurious.is_empty(), "unperturbed window: {spurious:#?}");

    // Patches placed on the fluid as it is at 3 s.
    let f = filled(&s.view());
    let nx = f.len();
    let mut cases: Vec<([usize; 4], [f64; 2], String)> = vec![];
    let wall = if block_filled(&f, 0, 0, 5) { 0 } else { nx - 5 };
    let into = if wall == 0 { 1.0 } else { -1.0 };
    assert!(block_filled(&f, wall, 0, 5), "fluid at one wall at 3 s");
    cases.push((
        [wall, 0, wall + 5, 5],
        [into, 0.0],
        "wall corner 5x5 into the fluid".into(),
    ));
    let floor_i = (20..nx - 20)
        .find(|&i| block_filled(&f, i, 0, 3))
        .expect("fluid on the floor");
    cases.push((
        [floor_i, 0, floor_i + 3, 3],
        [1.0, 0.0],
        "floor 3x3 along".into(),
    ));
    let deep = (10..nx - 10)
        .find(|&i| block_filled(&f, i, 2, 5))
        .expect("a region five cells deep");
    cases.push((
        [deep + 1, 3, deep + 4, 6],
        [0.0, -1.0],
        "interior 3x3 down".into(),
    ));
    cases.push((
        [deep + 1, 3, deep + 3, 5],
        [-1.0, 0.0],
        "interior 2x2 along".into(),
    ));
    // Free surface: the top filled cell of a column, 3 cells wide, 3 deep.
    let surf_i = (30..nx - 10).find(|&i| block_filled(&f, i, 0, 3)).unwrap();
    let top = (0..f[surf_i].len()).rev().find(|&j| f[surf_i][j]).unwrap();
    let j0 = top.saturating_sub(2);
    cases.push((
        [surf_i, j0, surf_i + 3, top + 1],
        [0.0, -1.0],
        "free surface 3x3 down".into(),
    ));

    for (cells, dv, tag) in cases {
        let perturb = vec![Perturb::at_step(
            at,
            common::region(0.01, cells[0], cells[1], cells[2], cells[3]),
            dv,
        )];
        let (pm, _) = common::run_window(&cfg, &start, &m, perturb, steps);
        let events = common::events_after(&pm, start_step);
        common::assert_detected(&events, at, window, cells, &tag);
    }
}
