//! Partition of unity and zero gradient sum for every shape family, and the
//! kernel derivative against finite differences; the weights the stages
//! compute (`locate` + `stencil_weights`) against the kernel and the
//! completeness conditions, on and around every stencil boundary.

use solver::shapes::Shape;
use solver::shapes::{CPGIMP_HALF_MAX, CPGIMP_HALF_MIN};
use solver::{Mat2, ShapeKind};

use crate::common;

#[test]
fn partition_of_unity_and_zero_gradient_sum() {
    for kind in common::SHAPES {
        for ppc in [1, 2, 3] {
            let shape = Shape::new(kind, ppc);
            for k in 0..997 {
                let x = 3.0 + k as f64 * 0.001_003;
                let w = shape.weights(x);
                let sum: f64 = w.w.iter().sum();
                let grad: f64 = w.dw.iter().sum();
                assert!(
                    (sum - 1.0).abs() < 1e-14,
                    "{kind:?} ppc {ppc} x {x}: sum {sum}"
                );
                assert!(
                    grad.abs() < 1e-13,
                    "{kind:?} ppc {ppc} x {x}: grad sum {grad}"
                );
                // Linear completeness: sum N_i x_i = x.
                let first: f64 = (0..shape.width())
                    .map(|i| w.w[i] * (w.base + i as i64) as f64)
                    .sum();
                assert!(
                    (first - x).abs() < 1e-12,
                    "{kind:?}: sum N x = {first} at {x}"
                );
                assert!(w.w.iter().all(|&n| n >= 0.0));
            }
        }
    }
}

#[test]
fn kernel_derivative_matches_finite_difference() {
    for kind in common::SHAPES {
        let shape = Shape::new(kind, 2);
        for k in 0..400 {
            let r = -2.2 + k as f64 * 0.011_1;
            let e = 1e-6;
            let fd = (shape.kernel(r + e).0 - shape.kernel(r - e).0) / (2.0 * e);
            let (_, d) = shape.kernel(r);
            // Skip the kinks of the hat, where the derivative jumps.
            if kind == ShapeKind::Linear && (r.abs() < 2e-6 || (r.abs() - 1.0).abs() < 2e-6) {
                continue;
            }
            assert!((fd - d).abs() < 1e-5, "{kind:?} r {r}: fd {fd} vs {d}");
        }
    }
}

#[test]
fn stencil_width_covers_support() {
    for kind in common::SHAPES {
        let shape = Shape::new(kind, 2);
        for k in 0..100 {
            let x = 5.0 + k as f64 * 0.0101;
            let w = shape.weights(x);
            // Nodes just outside the stencil carry no weight.
            let before = shape.kernel(x - (w.base - 1) as f64).0;
            let after = shape.kernel(x - (w.base + shape.width() as i64) as f64).0;
            assert_eq!(before, 0.0, "{kind:?} at {x}");
            assert_eq!(after, 0.0, "{kind:?} at {x}");
        }
    }
}

/// Positions (cell units) on and around every place where a stencil or a
/// kernel piece changes: nodes and half-nodes with their neighbouring
/// floats, the GIMP breakpoints (l, 1 - l, 1 + l from a node), tiny and
/// small offsets, and an even sweep; near the origin and far from it.
fn edge_positions(gimp_half: f64) -> Vec<f64> {
    let mut offsets = vec![0.0, 0.5, gimp_half, 1.0 - gimp_half, 1.0 + gimp_half];
    for d in [1e-15, 1e-12, 1e-9, 1e-6, 1e-3, 0.25] {
        for o in [0.0, 0.5, gimp_half, 1.0 - gimp_half] {
            offsets.extend([o + d, o - d]);
        }
    }
    offsets.extend((0..500).map(|k| k as f64 * 0.002_003));
    let mut out = vec![];
    for node in [2.0, 3.0, 17.0, 1000.0] {
        for &o in &offsets {
            let x: f64 = node + o;
            out.extend([
                x,
                f64::from_bits(x.to_bits() + 1),
                f64::from_bits(x.to_bits() - 1),
            ]);
        }
    }
    out
}

/// The 1D and 2D (tensor-product) weights the stages compute, `locate` then
/// `stencil_weights`, at a particle `x` cells from node 0.
fn check_stage_weights<const W: usize>(shape: &Shape, x: f64) -> [f64; 4] {
    let eps = f64::EPSILON;
    let what = format!("{shape:?} at x = {x:e}");
    let (base, f) = shape.locate(x);
    let half = shape.half_widths(&Mat2::identity())[0];
    let (w, dw) = shape.stencil_weights::<W>(f, half);
    // The stencil's first node and the offset range it implies.
    let lo = match shape.kind {
        ShapeKind::Linear => 0.0,
        ShapeKind::Gimp | ShapeKind::Bspline2 => 0.5,
        ShapeKind::Bspline3 | ShapeKind::Cpgimp | ShapeKind::Cpdi => 1.0,
    };
    assert!((lo..lo + 1.0).contains(&f), "{what}: offset {f}");
    assert_eq!(base as f64 + f, x, "{what}: base {base} + {f}");
    // Nodes just outside the stencil carry nothing.
    assert_eq!(shape.kernel(f + 1.0), (0.0, 0.0), "{what}");
    assert_eq!(shape.kernel(f - W as f64), (0.0, 0.0), "{what}");
    let mut err = [0.0f64; 4];
    // Agreement with the kernel node by node (its argument f - k may round).
    for k in 0..W {
        let (n, dn) = shape.kernel(f - k as f64);
        err[0] = err[0].max((w[k] - n).abs()).max((dw[k] - dn).abs());
        assert!(w[k] >= 0.0, "{what}: N_{k} = {}", w[k]);
    }
    // Partition of unity, zero gradient sum, linear completeness: sums of
    // W terms of size <= 1 (times k < W for the moments).
    let sum: f64 = w.iter().sum();
    let dsum: f64 = dw.iter().sum();
    let moment: f64 = (0..W).map(|k| w[k] * k as f64).sum();
    let dmoment: f64 = (0..W).map(|k| dw[k] * k as f64).sum();
    err[1] = err[1].max((sum - 1.0).abs()).max(dsum.abs());
    err[2] = err[2].max((moment - f).abs()).max((dmoment - 1.0).abs());
    // In absolute node coordinates: sum N_i x_i = x to round-off of x.
    let absolute: f64 = (0..W).map(|k| w[k] * (base + k as i64) as f64).sum();
    assert!(
        (absolute - x).abs() <= 4.0 * eps * x,
        "{what}: sum N x = {absolute}"
    );
    // 2D as the stages take it: N = Nx Ny, grad N = (dNx Ny, Nx dNy).
    let (mut sum2, mut grad2, mut moment2) = (0.0, [0.0; 2], [[0.0; 2]; 2]);
    for c in 0..W {
        for a in 0..W {
            let n = w[a] * w[c];
            let g = [dw[a] * w[c], w[a] * dw[c]];
            let xi = [a as f64, c as f64];
            sum2 += n;
            for r in 0..2 {
                grad2[r] += g[r];
                for s in 0..2 {
                    // sum_i grad N_i x_i^T = I.
                    moment2[r][s] += g[r] * xi[s];
                }
            }
        }
    }
    err[3] = err[3]
        .max((sum2 - 1.0).abs())
        .max(grad2[0].abs().max(grad2[1].abs()));
    for (r, row) in moment2.iter().enumerate() {
        for (s, m) in row.iter().enumerate() {
            let id = if r == s { 1.0 } else { 0.0 };
            err[3] = err[3].max((m - id).abs());
        }
    }
    for (e, bound, name) in [
        (err[0], 2.0, "kernel agreement"),
        (err[1], 4.0, "unity / gradient sum"),
        (err[2], 8.0, "linear completeness"),
        (err[3], 16.0, "2D sums"),
    ] {
        assert!(e <= bound * eps, "{what}: {name} off by {e:e}");
    }
    err
}

/// What P2G, G2P and the stress stage use (`locate`, then the closed-form
/// `stencil_weights`) for every shape: partition of unity, zero gradient
/// sum, sum N_i x_i = x_p and sum dN_i x_i = 1 (in 2D: sum grad N_i x_i^T =
/// I), and the same values and derivatives as `kernel` node by node, at
/// positions on and around every stencil and kernel-piece boundary.
#[test]
fn stage_weights_are_complete_and_match_the_kernel() {
    for kind in common::SHAPES {
        for ppc in [1, 2, 3] {
            let shape = Shape::new(kind, ppc);
            let positions = edge_positions(0.5 / ppc as f64);
            let mut worst = [0.0f64; 4];
            for &x in &positions {
                let err = match shape.width() {
                    2 => check_stage_weights::<2>(&shape, x),
                    3 => check_stage_weights::<3>(&shape, x),
                    _ => check_stage_weights::<4>(&shape, x),
                };
                for (w, e) in worst.iter_mut().zip(err) {
                    *w = w.max(e / f64::EPSILON);
                }
            }
            eprintln!(
                "{kind:?} ppc {ppc}: {} positions, max error in ulps: kernel {:.1}, unity {:.1}, completeness {:.1}, 2D {:.1}",
                positions.len(),
                worst[0],
                worst[1],
                worst[2],
                worst[3]
            );
        }
    }
}

/// cpGIMP at any half-width it may take: partition of unity, zero gradient
/// sum, linear completeness, the derivative against finite differences,
/// nothing outside the 4-node stencil, and uGIMP's kernel where the widths
/// agree (the general convolution equals the closed form for l <= 1/2).
#[test]
fn cpgimp_any_half_width() {
    let cp = Shape::new(ShapeKind::Cpgimp, 2);
    for ppc in [1, 2, 3, 4] {
        let u = Shape::new(ShapeKind::Gimp, ppc);
        let l = u.half_widths(&Mat2::identity())[0];
        for k in 0..801 {
            let r = -2.0 + k as f64 * 0.005;
            let (a, b) = (u.kernel(r), cp.kernel_with_half(r, l));
            assert!(
                (a.0 - b.0).abs() < 1e-14 && (a.1 - b.1).abs() < 1e-13,
                "l {l} r {r}: uGIMP {a:?} vs cpGIMP {b:?}"
            );
        }
    }
    let mut l = CPGIMP_HALF_MIN;
    while l <= CPGIMP_HALF_MAX {
        for k in 0..613 {
            let x = 7.0 + k as f64 * 0.001_63;
            let w = cp.weights_with_half(x, l);
            let sum: f64 = w.w.iter().sum();
            let grad: f64 = w.dw.iter().sum();
            let first: f64 = (0..4).map(|i| w.w[i] * (w.base + i as i64) as f64).sum();
            let slope: f64 = (0..4).map(|i| w.dw[i] * (w.base + i as i64) as f64).sum();
            assert!((sum - 1.0).abs() < 1e-13, "l {l} x {x}: sum {sum}");
            assert!(grad.abs() < 1e-13, "l {l} x {x}: grad sum {grad}");
            assert!((first - x).abs() < 1e-12, "l {l} x {x}: sum N x {first}");
            assert!((slope - 1.0).abs() < 1e-12, "l {l} x {x}: sum dN x {slope}");
            assert!(w.w.iter().all(|&n| n >= 0.0));
            for node in [w.base - 1, w.base + 4] {
                assert_eq!(cp.kernel_with_half(x - node as f64, l), (0.0, 0.0));
            }
        }
        for k in 0..400 {
            let r = -2.2 + k as f64 * 0.011_1;
            let e = 1e-7;
            let fd =
                (cp.kernel_with_half(r + e, l).0 - cp.kernel_with_half(r - e, l).0) / (2.0 * e);
            let d = cp.kernel_with_half(r, l).1;
            assert!((fd - d).abs() < 1e-5, "l {l} r {r}: fd {fd} vs {d}");
        }
        l += 0.0137;
    }
}

/// cpGIMP's half-widths follow F's diagonal from the undeformed h / (2 ppc),
/// within their bounds; uGIMP's never move.
#[test]
fn cpgimp_half_widths_follow_f() {
    let (cp, u) = (
        Shape::new(ShapeKind::Cpgimp, 2),
        Shape::new(ShapeKind::Gimp, 2),
    );
    let f = Mat2::new(1.6, 0.3, -0.2, 0.5);
    assert_eq!(cp.half_widths(&Mat2::identity()), [0.25, 0.25]);
    assert_eq!(cp.half_widths(&f), [0.25 * 1.6, 0.25 * 0.5]);
    assert_eq!(u.half_widths(&f), [0.25, 0.25]);
    let stretched = Mat2::new(9.0, 0.0, 0.0, 1e-4);
    assert_eq!(
        cp.half_widths(&stretched),
        [CPGIMP_HALF_MAX, CPGIMP_HALF_MIN]
    );
}

/// The F reset would reshape cpGIMP's particle domains: refused by key.
#[test]
fn cpgimp_with_f_reset_is_refused() {
    use solver::{Material, SchemeKind, TransferKind};
    let scene = common::box_scene([1.0, 1.0], [0.4, 0.4, 0.6, 0.6], Material::tait(1e5), 9.81);
    let mut method = common::method(ShapeKind::Cpgimp, TransferKind::Flip, SchemeKind::Usf);
    method.remedies.f_reset = Some(solver::remedies::f_reset::Settings {});
    let err = common::refusal(scene, method).expect("cpGIMP with f_reset accepted");
    assert_eq!(err.key, "method.f_reset", "{err:?}");
    // The message names the shape it got (as its Rust variant, `Cpgimp`).
    assert!(err.message.to_lowercase().contains("cpgimp"), "{err:?}");
}
