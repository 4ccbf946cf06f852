//! The preconditioned conjugate gradient of the pressure solve: the
//! operator's 3 x 3-cell matrix read by probing, its incomplete Cholesky
//! factor (IC(0) or MIC(0)), or Jacobi.

use super::operator::apply_a;
use super::{remove_mean, Scratch, AIR};
use crate::config::{Preconditioner, ProjectionSettings};
use crate::grid::Grid;

/// A row of the incomplete Cholesky factor: its entries left of the
/// diagonal (unknown, value) and the diagonal.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Lower {
    index: [u32; 4],
    value: [f64; 4],
    len: usize,
    diagonal: f64,
    /// 1 / diagonal: the substitutions multiply (a divide's latency would
    /// sit on their dependency chain).
    inverse: f64,
}

/// Preconditioned conjugate gradient (IC(0) on the probed matrix, or
/// Jacobi) from the last step's pressure.
/// `fresh`: read the matrix and factorise it (else this step's pressure
/// matrix and its factor are used: the drift solve by position, whose
/// matrix differs only by the EOS diagonal taken out beforehand).
/// `tolerance`: the relative residual to stop at.
pub(super) fn solve(
    grid: &Grid,
    s: &mut Scratch,
    set: &ProjectionSettings,
    beta: f64,
    fresh: bool,
    tolerance: f64,
) {
    let Some(singular) = prepare(s) else {
        return;
    };
    let incomplete_cholesky = set.preconditioner != Preconditioner::Jacobi && s.probe_exact;
    if incomplete_cholesky && fresh {
        probe_matrix(grid, s, beta);
        factorise(s, fill_share(set));
    }
    let method = Iteration {
        singular,
        incomplete_cholesky,
        tolerance,
        max_iterations: set.max_iterations,
    };
    // The start's residual always from the operator itself; the products
    // from the probed matrix where it was read.
    let product = |s: &mut Scratch| {
        if incomplete_cholesky {
            apply_matrix(s);
        } else {
            apply_a(grid, s, beta, true);
        }
    };
    iterate(s, &method, |s| apply_a(grid, s, beta, false), product);
}

/// Preconditioned conjugate gradient on a matrix already in `s.matrix`
/// (the staggered scheme assembles its rows), from `s.x`.
pub(super) fn solve_assembled(s: &mut Scratch, set: &ProjectionSettings, tolerance: f64) {
    let Some(singular) = prepare(s) else {
        return;
    };
    let incomplete_cholesky = set.preconditioner != Preconditioner::Jacobi;
    if incomplete_cholesky {
        factorise(s, fill_share(set));
    }
    let method = Iteration {
        singular,
        incomplete_cholesky,
        tolerance,
        max_iterations: set.max_iterations,
    };
    let start = |s: &mut Scratch| {
        s.d.copy_from_slice(&s.x);
        apply_matrix(s);
    };
    iterate(s, &method, start, apply_matrix);
}

/// Sizes the iteration's vectors; None when there is no unknown (then
/// converged), else whether the system is singular. No air cell and no
/// compressibility: p is known up to a constant, so the solve is for the
/// mean-free part of a mean-free right-hand side.
fn prepare(s: &mut Scratch) -> Option<bool> {
    let n = s.fluid.len();
    for v in [&mut s.r, &mut s.z, &mut s.d, &mut s.q] {
        v.clear();
        v.resize(n, 0.0);
    }
    if n == 0 {
        s.stats.converged = true;
        return None;
    }
    let singular = s.alpha.iter().all(|&a| a == 0.0) && n == s.unknown.len();
    if singular {
        remove_mean(&mut s.b);
        remove_mean(&mut s.x);
    }
    Some(singular)
}

/// The share of the dropped fill MIC(0) moves onto the diagonal (0: IC(0)).
fn fill_share(set: &ProjectionSettings) -> f64 {
    if set.preconditioner == Preconditioner::Mic0 {
        MIC_SHARE
    } else {
        0.0
    }
}

/// How `iterate` runs: whether the system is singular (mean-free), the
/// preconditioner, and when to stop.
struct Iteration {
    singular: bool,
    incomplete_cholesky: bool,
    tolerance: f64,
    max_iterations: u32,
}

/// The conjugate-gradient iterations from `s.x`, to the relative residual
/// or the iteration limit; the outcome in `s.stats`. `start` sets
/// `s.q` = A `s.x`, `product` sets `s.q` = A `s.d`.
fn iterate(
    s: &mut Scratch,
    it: &Iteration,
    start: impl FnOnce(&mut Scratch),
    mut product: impl FnMut(&mut Scratch),
) {
    let n = s.fluid.len();
    start(s);
    for k in 0..n {
        s.r[k] = s.b[k] - s.q[k];
    }
    let b_norm = dot(&s.b, &s.b).sqrt();
    let goal = it.tolerance * b_norm.max(f64::MIN_POSITIVE);
    let mut r_norm = dot(&s.r, &s.r).sqrt();
    let mut rz = 0.0;
    let mut iterations = 0;
    while r_norm > goal && iterations < it.max_iterations {
        if it.incomplete_cholesky {
            precondition(s);
        } else {
            for k in 0..n {
                s.z[k] = s.r[k] / s.diag[k];
            }
        }
        if it.singular {
            remove_mean(&mut s.z);
        }
        let rz_new = dot(&s.r, &s.z);
        if iterations == 0 {
            s.d.copy_from_slice(&s.z);
        } else {
            let ratio = rz_new / rz;
            for k in 0..n {
                s.d[k] = s.z[k] + ratio * s.d[k];
            }
        }
        rz = rz_new;
        product(s);
        let dq = dot(&s.d, &s.q);
        if dq.is_nan() || dq <= 0.0 {
            break;
        }
        let step = rz / dq;
        for k in 0..n {
            s.x[k] += step * s.d[k];
            s.r[k] -= step * s.q[k];
        }
        r_norm = dot(&s.r, &s.r).sqrt();
        iterations += 1;
    }
    s.stats.iterations = iterations;
    s.stats.residual = if b_norm > 0.0 {
        r_norm / b_norm
    } else {
        r_norm
    };
    s.stats.converged = r_norm <= goal;
}

/// Reads the matrix row by row with nine probes: the cells of one colour
/// (i mod 3, j mod 3) are three apart, so each cell's 3 x 3 block holds
/// one of them and A times the colour's indicator is that column's entry.
fn probe_matrix(grid: &Grid, s: &mut Scratch, beta: f64) {
    let n = s.fluid.len();
    s.matrix.clear();
    s.matrix.resize(n, [0.0; 9]);
    let colour = |s: &Scratch, k: usize| {
        let c = s.fluid[k] as usize;
        (c % s.cells[0]) % 3 + 3 * ((c / s.cells[0]) % 3)
    };
    for probe in 0..9 {
        for k in 0..n {
            s.d[k] = if colour(s, k) == probe { 1.0 } else { 0.0 };
        }
        apply_a(grid, s, beta, true);
        for k in 0..n {
            if colour(s, k) != probe {
                continue;
            }
            for slot in 0..9 {
                let m = s.neighbours[k][slot];
                if m != AIR {
                    s.matrix[m as usize][8 - slot] = s.q[m as usize];
                }
            }
        }
    }
    s.d.fill(0.0);
}

/// The share of the dropped fill MIC(0) moves onto the diagonals (below 1,
/// which would make L L^T exactly row-sum preserving and singular on a
/// closed incompressible box: the usual 0.97).
const MIC_SHARE: f64 = 0.97;

/// Incomplete Cholesky on the 3 x 3 pattern, column by column
/// (right-looking): each pivot's column updates the Schur complement of
/// the rows below it, and an update that falls outside the pattern (fill)
/// is dropped (IC(0), `tau` = 0) or moved, times `tau`, onto the diagonals
/// of the two rows it would have coupled (MIC(0)), so that L L^T keeps A's
/// row sums to within 1 - tau: the smooth error that IC(0) resolves slowly
/// is what the pressure's conjugate gradient spends its iterations on. A
/// pivot below a quarter of A's diagonal is replaced by that diagonal (the
/// factor always exists). A row keeps at most four entries left of its
/// diagonal (its 3 x 3 block's cells before it; more only across a
/// periodic edge, where the rest is dropped).
fn factorise(s: &mut Scratch, tau: f64) {
    let n = s.fluid.len();
    s.schur.clear();
    s.schur.extend_from_slice(&s.matrix);
    s.lower.clear();
    s.lower.resize(n, Lower::default());
    for k in 0..n {
        let pivot = s.schur[k][4];
        let d = if pivot > 0.25 * s.matrix[k][4] {
            pivot.sqrt()
        } else {
            s.matrix[k][4].sqrt()
        };
        s.lower[k].diagonal = d;
        s.lower[k].inverse = 1.0 / d;
        // The pivot's column below the diagonal: L's entries (m, k).
        let mut below = [(0u32, 0.0f64); 8];
        let mut count = 0;
        for (slot, &m) in s.neighbours[k].iter().enumerate() {
            if m != AIR && m as usize > k && count < below.len() {
                below[count] = (m, s.schur[k][slot] / d);
                count += 1;
            }
        }
        for &(m, l) in &below[..count] {
            let row = &mut s.lower[m as usize];
            if row.len < 4 {
                row.index[row.len] = k as u32;
                row.value[row.len] = l;
                row.len += 1;
            }
        }
        for a in 0..count {
            let (i, li) = below[a];
            s.schur[i as usize][4] -= li * li;
            for &(j, lj) in &below[..a] {
                let update = li * lj;
                match s.neighbours[i as usize].iter().position(|&m| m == j) {
                    Some(slot) => {
                        s.schur[i as usize][slot] -= update;
                        s.schur[j as usize][8 - slot] -= update;
                    }
                    None => {
                        s.schur[i as usize][4] -= tau * update;
                        s.schur[j as usize][4] -= tau * update;
                    }
                }
            }
        }
    }
}

/// z = (L L^T)^-1 r: forward by rows of L, backward by its columns.
fn precondition(s: &mut Scratch) {
    let n = s.fluid.len();
    for i in 0..n {
        let row = &s.lower[i];
        let mut sum = s.r[i];
        for a in 0..row.len {
            sum -= row.value[a] * s.z[row.index[a] as usize];
        }
        s.z[i] = sum * row.inverse;
    }
    for i in (0..n).rev() {
        let row = &s.lower[i];
        let zi = s.z[i] * row.inverse;
        s.z[i] = zi;
        for a in 0..row.len {
            s.z[row.index[a] as usize] -= row.value[a] * zi;
        }
    }
}

/// q = A d with the probed matrix (the same operator as `apply_a`, nine
/// products a row).
fn apply_matrix(s: &mut Scratch) {
    for i in 0..s.fluid.len() {
        let mut sum = 0.0;
        for (slot, &k) in s.neighbours[i].iter().enumerate() {
            if k != AIR {
                sum += s.matrix[i][slot] * s.d[k as usize];
            }
        }
        s.q[i] = sum;
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 9-point SPD system on a walled 4 x 3 block of fluid cells:
    /// -1 to the edge neighbours, -1/4 to the diagonal ones, and the
    /// diagonal alpha plus the off-diagonal row sum.
    fn system(alpha: f64) -> Scratch {
        let mut s = Scratch {
            cells: [4, 3],
            ..Scratch::default()
        };
        let n = 12;
        s.unknown = (0..n as u32).collect();
        s.fluid = (0..n as u32).collect();
        super::super::surface::fill_neighbour_rows(&mut s);
        for k in 0..n {
            let mut row = [0.0; 9];
            for (slot, &m) in s.neighbours[k].iter().enumerate() {
                if m != AIR && slot != 4 {
                    row[slot] = if slot % 2 == 1 { -1.0 } else { -0.25 };
                }
            }
            row[4] = alpha - row.iter().sum::<f64>();
            s.matrix.push(row);
            s.diag.push(row[4]);
            s.alpha.push(alpha);
        }
        s.b = (0..n)
            .map(|k| ((k * 7 + 3) % 5) as f64 - 2.0 + 0.1 * k as f64)
            .collect();
        s.x = vec![0.0; n];
        for v in [&mut s.r, &mut s.z, &mut s.d, &mut s.q] {
            v.resize(n, 0.0);
        }
        s
    }

    fn dense(s: &Scratch) -> Vec<Vec<f64>> {
        let n = s.fluid.len();
        let mut a = vec![vec![0.0; n]; n];
        for (k, row) in a.iter_mut().enumerate() {
            for (slot, &m) in s.neighbours[k].iter().enumerate() {
                if m != AIR {
                    row[m as usize] = s.matrix[k][slot];
                }
            }
        }
        a
    }

    /// x = A^-1 b by a dense Cholesky factor A = L L^T.
    #[allow(clippy::needless_range_loop)] // the textbook's indices
    fn cholesky_solve(a: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
        let n = b.len();
        let mut l = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in 0..=i {
                let sum: f64 = (0..j).map(|k| l[i][k] * l[j][k]).sum();
                l[i][j] = if i == j {
                    (a[i][i] - sum).sqrt()
                } else {
                    (a[i][j] - sum) / l[j][j]
                };
            }
        }
        let mut y = vec![0.0; n];
        for i in 0..n {
            y[i] = (b[i] - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
        }
        let mut x = vec![0.0; n];
        for i in (0..n).rev() {
            x[i] = (y[i] - (i + 1..n).map(|k| l[k][i] * x[k]).sum::<f64>()) / l[i][i];
        }
        x
    }

    #[test]
    fn pcg_matches_a_dense_cholesky_solve_with_every_preconditioner() {
        for (incomplete_cholesky, tau) in [(false, 0.0), (true, 0.0), (true, MIC_SHARE)] {
            let mut s = system(0.5);
            let a = dense(&s);
            let exact = cholesky_solve(&a, &s.b);
            if incomplete_cholesky {
                factorise(&mut s, tau);
            }
            let it = Iteration {
                singular: false,
                incomplete_cholesky,
                tolerance: 1e-13,
                max_iterations: 100,
            };
            iterate(
                &mut s,
                &it,
                |s| {
                    let x = s.x.clone();
                    for (q, row) in s.q.iter_mut().zip(&a) {
                        *q = row.iter().zip(&x).map(|(a, x)| a * x).sum();
                    }
                },
                apply_matrix,
            );
            assert!(
                s.stats.converged,
                "tau {tau}: residual {}",
                s.stats.residual
            );
            // Conjugate gradients end within n steps in exact arithmetic.
            assert!(
                s.stats.iterations <= 12,
                "{} iterations",
                s.stats.iterations
            );
            for (x, e) in s.x.iter().zip(&exact) {
                assert!((x - e).abs() <= 1e-11 * e.abs().max(1.0), "{x} against {e}");
            }
        }
    }

    #[test]
    fn the_incomplete_factor_is_exact_where_the_pattern_holds_no_fill() {
        // A single row of cells: a tridiagonal matrix, whose Cholesky factor
        // has no fill, so IC(0) is the exact factor and one iteration solves.
        let mut s = Scratch {
            cells: [5, 1],
            ..Scratch::default()
        };
        s.unknown = (0..5).collect();
        s.fluid = (0..5).collect();
        super::super::surface::fill_neighbour_rows(&mut s);
        for k in 0..5 {
            let mut row = [0.0; 9];
            for slot in [3, 5] {
                if s.neighbours[k][slot] != AIR {
                    row[slot] = -1.0;
                }
            }
            row[4] = 3.0;
            s.matrix.push(row);
        }
        factorise(&mut s, 0.0);
        s.r = vec![1.0, -2.0, 0.5, 4.0, 1.0];
        s.z = vec![0.0; 5];
        precondition(&mut s);
        let exact = cholesky_solve(&dense(&s), &s.r);
        for (z, e) in s.z.iter().zip(&exact) {
            assert!((z - e).abs() < 1e-14, "{z} against {e}");
        }
    }
}
