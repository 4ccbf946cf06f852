//! CPDI: partition of unity and gradient consistency (sum grad S = 0,
//! sum x_i grad S^T = I) for sheared, stretched and capped domains; the
//! weights against the corners' mean of the hats and the gradients
//! against a quadrature of the interpolated hat's gradient over the
//! domain; the cap; and a run's grid mass and determinism.

use std::collections::BTreeMap;

use solver::shapes::{cpdi, Shape};
use solver::*;

use crate::common;

/// Deformation gradients: undeformed, stretched, sheared both ways, rotated,
/// compressed, and ones far past the cap.
fn gradients() -> Vec<Mat2> {
    let (c, s) = (0.6f64.cos(), 0.6f64.sin());
    vec![
        Mat2::identity(),
        Mat2::new(1.7, 0.0, 0.0, 0.6),
        Mat2::new(1.0, 1.3, 0.0, 1.0),
        Mat2::new(1.0, 0.0, -2.1, 1.0),
        Mat2::new(c, -s, s, c),
        Mat2::new(0.5, 0.2, -0.1, 0.4),
        Mat2::new(1.0, 9.0, 0.0, 1.0),
        Mat2::new(6.0, -3.0, 2.5, 0.3),
    ]
}

/// Positions (cells from node 0) across a cell and its boundaries.
fn positions() -> Vec<[f64; 2]> {
    let mut out = vec![[5.0, 5.0], [5.5, 4.999_999_999], [6.0 - 1e-15, 7.25]];
    for k in 0..40 {
        let t = k as f64 * 0.0731;
        out.push([4.0 + (t * 3.1) % 1.0, 9.0 + (t * 1.7) % 1.0]);
    }
    out
}

/// The weights of one particle summed node by node: (weight, gradient).
fn by_node(shape: &Shape, x: [f64; 2], f: &Mat2) -> BTreeMap<[i64; 2], (f64, [f64; 2])> {
    let mut out = BTreeMap::<[i64; 2], (f64, [f64; 2])>::new();
    shape.each_weight(x, f, |n, w, g| {
        let e = out.entry(n).or_default();
        e.0 += w;
        e.1[0] += g[0];
        e.1[1] += g[1];
    });
    out
}

#[test]
fn cpdi_weights_are_a_partition_of_unity_with_consistent_gradients() {
    for ppc in [1, 2, 4] {
        let shape = Shape::new(ShapeKind::Cpdi, ppc);
        for f in gradients() {
            for x in positions() {
                let what = format!("ppc {ppc}, F {f:?}, x {x:?}");
                let (mut sum, mut first) = (0.0, [0.0; 2]);
                let (mut dsum, mut dfirst) = ([0.0; 2], [[0.0; 2]; 2]);
                for ([i, j], (w, g)) in by_node(&shape, x, &f) {
                    assert!(w >= 0.0, "{what}: weight {w} at {i}, {j}");
                    let xi = [i as f64, j as f64];
                    sum += w;
                    for a in 0..2 {
                        first[a] += w * xi[a];
                        dsum[a] += g[a];
                        for b in 0..2 {
                            dfirst[a][b] += xi[a] * g[b];
                        }
                    }
                }
                assert!((sum - 1.0).abs() < 1e-14, "{what}: sum {sum}");
                for a in 0..2 {
                    assert!(
                        (first[a] - x[a]).abs() < 1e-13,
                        "{what}: sum w x = {first:?}"
                    );
                    // Gradients reach 1 / (4 det) per cell: scale the round-off.
                    assert!(dsum[a].abs() < 1e-11, "{what}: sum grad = {dsum:?}");
                    for b in 0..2 {
                        let want = if a == b { 1.0 } else { 0.0 };
                        assert!(
                            (dfirst[a][b] - want).abs() < 1e-10,
                            "{what}: sum x grad^T = {dfirst:?}"
                        );
                    }
                }
            }
        }
    }
}

/// The hat N_i at a point, node (i, j).
fn hat(node: [i64; 2], p: [f64; 2]) -> f64 {
    (0..2)
        .map(|a| (1.0 - (p[a] - node[a] as f64).abs()).max(0.0))
        .product()
}

#[test]
fn cpdi_weights_are_the_corner_mean_and_gradients_the_domain_mean() {
    let shape = Shape::new(ShapeKind::Cpdi, 2);
    for f in gradients() {
        let [r1x, r1y, r2x, r2y] = shape.domain(&f);
        let det = r1x * r2y - r1y * r2x;
        let point = |x: [f64; 2], xi: f64, eta: f64| {
            [x[0] + xi * r1x + eta * r2x, x[1] + xi * r1y + eta * r2y]
        };
        for x in positions() {
            for (node, (w, g)) in by_node(&shape, x, &f) {
                let corners: f64 = cpdi::CORNERS
                    .iter()
                    .map(|&[xi, eta]| hat(node, point(x, xi, eta)))
                    .sum();
                assert!(
                    (w - 0.25 * corners).abs() < 1e-15,
                    "F {f:?} x {x:?} node {node:?}"
                );
                // The mean over the domain of grad of the corners' bilinear
                // interpolant, by 2 x 2 Gauss points (exact: each partial
                // derivative is linear in the other coordinate).
                let q = 1.0 / 3f64.sqrt();
                let mut mean = [0.0; 2];
                for (s, t) in [(-q, -q), (q, -q), (q, q), (-q, q)] {
                    // d/dxi and d/deta of sum M_c(xi, eta) N_i(x_c).
                    let (mut dxi, mut deta) = (0.0, 0.0);
                    for &[xc, ec] in &cpdi::CORNERS {
                        let n = hat(node, point(x, xc, ec));
                        dxi += 0.25 * xc * (1.0 + ec * t) * n;
                        deta += 0.25 * ec * (1.0 + xc * s) * n;
                    }
                    // grad = J^-T (d/dxi, d/deta), J = [r1 r2].
                    mean[0] += 0.25 * (r2y * dxi - r1y * deta) / det;
                    mean[1] += 0.25 * (-r2x * dxi + r1x * deta) / det;
                }
                for a in 0..2 {
                    assert!(
                        (g[a] - mean[a]).abs() < 1e-12 * (1.0 + mean[a].abs()),
                        "F {f:?} x {x:?} node {node:?}: {g:?} vs {mean:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn cpdi_domains_follow_f_up_to_the_cap_and_keep_their_shape_past_it() {
    let shape = Shape::new(ShapeKind::Cpdi, 2);
    let l = 0.25;
    assert_eq!(shape.domain(&Mat2::identity()), [l, 0.0, 0.0, l]);
    let f = Mat2::new(1.7, 0.3, -0.2, 0.6);
    assert_eq!(shape.domain(&f), [1.7 * l, -0.2 * l, 0.3 * l, 0.6 * l]);
    // F_xy = 9: r2 = (2.25, 0.25) cells, 2.5 cells of reach along x.
    let sheared = Mat2::new(1.0, 9.0, 0.0, 1.0);
    let d = shape.domain(&sheared);
    let reach = (d[0].abs() + d[2].abs()).max(d[1].abs() + d[3].abs());
    assert!((reach - cpdi::CORNER_REACH).abs() < 1e-15, "{d:?}");
    assert!((d[2] / d[0] - 9.0).abs() < 1e-12 && d[1] == 0.0 && (d[3] - d[0]).abs() < 1e-15);
    // Every node a capped particle touches lies in its stencil.
    let reach = 0..cpdi::REACH_NODES as i64;
    for x in positions() {
        let base = x.map(|v| (v - cpdi::CORNER_REACH).floor() as i64);
        for ([i, j], _) in by_node(&shape, x, &sheared) {
            assert!(
                reach.contains(&(i - base[0])) && reach.contains(&(j - base[1])),
                "{x:?}: {i}, {j}"
            );
        }
    }
    // A collapsed particle takes the undeformed square.
    assert_eq!(shape.domain(&Mat2::zeros()), [l, 0.0, 0.0, l]);
}

/// A sheared block in a periodic box, no gravity (the conservation tests'
/// swirl): CPDI's grid mass is the particles' every step, its domains
/// shear, and the run is the same for one and two threads.
#[test]
fn a_cpdi_run_keeps_its_grid_mass_and_is_deterministic() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut s = crate::transfer_conservation::periodic_swirl(
            ShapeKind::Cpdi,
            TransferKind::Flip,
            SchemeKind::Usl,
        );
        pool.install(|| {
            for _ in 0..300 {
                s.step().unwrap();
                let v = s.view();
                let particles: f64 = v.mass.iter().sum();
                let grid = v.grid_mass_p2g;
                assert!(
                    (grid - particles).abs() < 1e-12 * particles,
                    "{grid} vs {particles}"
                );
            }
        });
        let shear = s
            .view()
            .deformation
            .iter()
            .map(|f| f[(0, 1)].abs())
            .fold(0.0, f64::max);
        assert!(shear > 0.05, "largest F_xy {shear}");
        s.state_hash()
    };
    assert_eq!(run(1), run(2));
}

/// The paths that read per-axis weights refuse CPDI by key.
#[test]
fn cpdi_is_refused_where_weights_are_read_per_axis() {
    let scene = || common::box_scene([1.0, 1.0], [0.4, 0.4, 0.6, 0.6], Material::tait(1e5), 9.81);
    let mut xpic = common::method(ShapeKind::Cpdi, TransferKind::Xpic, SchemeKind::Usl);
    xpic.xpic_order = 2;
    let err = common::refusal(scene(), xpic).expect("CPDI with XPIC accepted");
    assert_eq!(err.key, "method.transfer", "{err:?}");
    let mut shifting = common::method(ShapeKind::Cpdi, TransferKind::Flip, SchemeKind::Usl);
    shifting.remedies.j_bar = Some(Default::default());
    let err = common::refusal(scene(), shifting).expect("CPDI with J-bar accepted");
    assert_eq!(err.key, "method.j_bar", "{err:?}");
    assert!(err.message.contains("\"cpdi\""), "{err:?}");
    let mut implicit = common::method(ShapeKind::Cpdi, TransferKind::Apic, SchemeKind::Usl);
    implicit.formulation = solver::config::Formulation::PressureImplicit;
    let err = common::refusal(scene(), implicit).expect("CPDI pressure-implicit accepted");
    assert_eq!(err.key, "method.formulation", "{err:?}");
}
