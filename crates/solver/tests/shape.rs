//! Partition of unity and zero gradient sum for every shape family, and the
//! kernel derivative against finite differences.

use solver::shape::Shape;
use solver::ShapeKind;

mod common;

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
