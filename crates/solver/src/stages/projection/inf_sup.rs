//! A discrete inf-sup test of the projection's velocity-pressure pair
//! (docs/physics.md section 8). The pair is stable when
//! beta^2 = the smallest nonzero eigenvalue of M_p^-1 B A^-1 B^T stays
//! bounded away from 0 as h falls, and the gradient B^T has no kernel but
//! the constants. Here B u = the integral of div u over each fluid cell
//! (the projection's own `CORNERS` stencil: h^2 D), A = the vector
//! Laplacian of the bilinear velocities over the fluid cells (the H1
//! seminorm; a wall pins the normal component, a no-slip wall both), and
//! M_p = h^2 I (cell pressures). The smallest eigenvalue comes from Lanczos
//! with full reorthogonalisation, after the kernel the probes find
//! (constants, the checkerboard) is deflated; A^-1 is applied by
//! Jacobi-preconditioned conjugate gradients.

use super::CORNERS;
use nalgebra::{DMatrix, SymmetricEigen};

/// Which cells are fluid on a uniform grid of `cells` cells of size `h`,
/// in a box with walls on every side.
#[derive(Clone, Debug)]
pub struct Mask {
    pub cells: [usize; 2],
    pub h: f64,
    /// Per cell, x fastest.
    pub fluid: Vec<bool>,
    /// Walls hold both velocity components (else only the normal one).
    pub no_slip: bool,
}

impl Mask {
    /// Every cell of the box is fluid.
    pub fn full(cells: [usize; 2], h: f64) -> Mask {
        Mask {
            cells,
            h,
            fluid: vec![true; cells[0] * cells[1]],
            no_slip: false,
        }
    }

    /// The cells whose centres lie in one of the rectangles
    /// ([x0, y0, x1, y1], m, from the box's lower left corner).
    pub fn of_rects(cells: [usize; 2], h: f64, rects: &[[f64; 4]]) -> Mask {
        let mut fluid = vec![false; cells[0] * cells[1]];
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                let (x, y) = ((i as f64 + 0.5) * h, (j as f64 + 0.5) * h);
                fluid[i + j * cells[0]] = rects
                    .iter()
                    .any(|r| x > r[0] && x < r[2] && y > r[1] && y < r[3]);
            }
        }
        Mask {
            cells,
            h,
            fluid,
            no_slip: false,
        }
    }
}

/// Which velocity-pressure pair is tested.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairKind {
    /// The projection's pair: bilinear nodal velocities, cell pressures (Q1-P0).
    Collocated,
    /// A staggered (MAC) grid: each velocity component on the faces normal
    /// to it, cell pressures.
    Mac,
}

impl PairKind {
    pub fn name(self) -> &'static str {
        match self {
            PairKind::Collocated => "collocated (Q1-P0)",
            PairKind::Mac => "staggered (MAC)",
        }
    }
}

/// How close a probe comes to the kernel: its Rayleigh quotient
/// q^T S q / q^T q (0: B^T q = 0).
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    pub name: &'static str,
    pub quotient: f64,
}

/// What the test found.
#[derive(Clone, Debug, PartialEq)]
pub struct InfSup {
    /// Pressure unknowns (fluid cells) and free velocity components.
    pub pressures: usize,
    pub velocities: usize,
    pub probes: Vec<Probe>,
    /// Probes deflated as kernel (quotient below `KERNEL`).
    pub deflated: usize,
    /// The smallest eigenvalue left, its square root (the inf-sup
    /// constant) and the Lanczos residual bound on it.
    pub lambda_min: f64,
    pub beta: f64,
    pub residual: f64,
    /// The largest eigenvalue seen (the spectrum's top, for scale).
    pub lambda_max: f64,
    pub lanczos_steps: usize,
}

/// A probe whose quotient is below this is in the gradient's kernel.
pub const KERNEL: f64 = 1e-10;

/// A compressed sparse row matrix.
#[derive(Clone, Debug, Default)]
struct Csr {
    start: Vec<usize>,
    col: Vec<usize>,
    val: Vec<f64>,
}

impl Csr {
    fn from_rows(rows: Vec<Vec<(usize, f64)>>) -> Csr {
        let mut m = Csr {
            start: vec![0],
            ..Default::default()
        };
        for mut row in rows {
            row.sort_by_key(|e| e.0);
            let mut merged: Vec<(usize, f64)> = vec![];
            for (c, v) in row {
                match merged.last_mut() {
                    Some(last) if last.0 == c => last.1 += v,
                    _ => merged.push((c, v)),
                }
            }
            for (c, v) in merged {
                m.col.push(c);
                m.val.push(v);
            }
            m.start.push(m.col.len());
        }
        m
    }

    fn rows(&self) -> usize {
        self.start.len() - 1
    }

    /// y = M x.
    fn mul(&self, x: &[f64], y: &mut [f64]) {
        for (r, y) in y.iter_mut().enumerate() {
            let k = self.start[r]..self.start[r + 1];
            *y = self.col[k.clone()]
                .iter()
                .zip(&self.val[k])
                .map(|(&c, v)| v * x[c])
                .sum();
        }
    }

    /// y = M^T x.
    fn mul_transpose(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for (r, &xr) in x.iter().enumerate() {
            for k in self.start[r]..self.start[r + 1] {
                y[self.col[k]] += self.val[k] * xr;
            }
        }
    }

    fn diagonal(&self) -> Vec<f64> {
        (0..self.rows())
            .map(|r| {
                (self.start[r]..self.start[r + 1])
                    .find(|&k| self.col[k] == r)
                    .map_or(0.0, |k| self.val[k])
            })
            .collect()
    }
}

/// The pair's operators on a mask: B (fluid cells x free components) and A.
struct Pair {
    b: Csr,
    a: Csr,
    /// Each fluid cell's (i, j).
    cells: Vec<(usize, usize)>,
    h: f64,
}

/// No unknown here.
const NONE: usize = usize::MAX;

/// The bilinear element's Laplacian on a square, in `CORNERS` order
/// (SW, SE, NW, NE): 2/3 on the diagonal, -1/6 along an edge, -1/3 across.
fn element_stiffness(a: usize, b: usize) -> f64 {
    let (ca, cb) = (CORNERS[a], CORNERS[b]);
    match (ca.0 != cb.0) as usize + (ca.1 != cb.1) as usize {
        0 => 2.0 / 3.0,
        1 => -1.0 / 6.0,
        _ => -1.0 / 3.0,
    }
}

impl Pair {
    /// The collocated pair the projection solves: bilinear nodal
    /// velocities, one pressure per fluid cell (Q1-P0).
    fn collocated(mask: &Mask) -> Result<Pair, String> {
        let [nx, ny] = mask.cells;
        if mask.fluid.len() != nx * ny {
            return Err(format!("mask: {} cells for {nx} x {ny}", mask.fluid.len()));
        }
        let node = |i: usize, j: usize| i + j * (nx + 1);
        // Free components: at a node of a fluid cell, not pinned by a wall.
        let mut dof = vec![NONE; 2 * (nx + 1) * (ny + 1)];
        let mut velocities = 0;
        let mut cells = vec![];
        for j in 0..ny {
            for i in 0..nx {
                if !mask.fluid[i + j * nx] {
                    continue;
                }
                cells.push((i, j));
                for &(di, dj, _, _) in &CORNERS {
                    let (ni, nj) = (i + di, j + dj);
                    let wall = [ni == 0 || ni == nx, nj == 0 || nj == ny];
                    for d in 0..2 {
                        let pinned = wall[d] || (mask.no_slip && (wall[0] || wall[1]));
                        let k = 2 * node(ni, nj) + d;
                        if !pinned && dof[k] == NONE {
                            dof[k] = velocities;
                            velocities += 1;
                        }
                    }
                }
            }
        }
        if cells.is_empty() {
            return Err("mask: no fluid cell".into());
        }
        let half_h = 0.5 * mask.h;
        let mut b_rows = Vec::with_capacity(cells.len());
        let mut a_rows = vec![vec![]; velocities];
        for &(i, j) in &cells {
            let corner = |c: usize| node(i + CORNERS[c].0, j + CORNERS[c].1);
            let mut row = vec![];
            for (c, &(_, _, sx, sy)) in CORNERS.iter().enumerate() {
                for (d, s) in [(0, sx), (1, sy)] {
                    let k = dof[2 * corner(c) + d];
                    if k != NONE {
                        row.push((k, half_h * s));
                    }
                }
            }
            b_rows.push(row);
            for a in 0..4 {
                for b in 0..4 {
                    for d in 0..2 {
                        let (ka, kb) = (dof[2 * corner(a) + d], dof[2 * corner(b) + d]);
                        if ka != NONE && kb != NONE {
                            a_rows[ka].push((kb, element_stiffness(a, b)));
                        }
                    }
                }
            }
        }
        Ok(Pair {
            b: Csr::from_rows(b_rows),
            a: Csr::from_rows(a_rows),
            cells,
            h: mask.h,
        })
    }
}

/// The faces of a staggered grid over a mask: component d's face (i, j)
/// is a u face (i in 0..=nx, j < ny) or a v face (i < nx, j in 0..=ny).
struct Faces<'m> {
    mask: &'m Mask,
    /// Each face's unknown (NONE: pinned by a wall, or beside no fluid cell).
    dof: Vec<usize>,
    velocities: usize,
}

impl<'m> Faces<'m> {
    fn new(mask: &'m Mask) -> Faces<'m> {
        let [nx, ny] = mask.cells;
        let mut faces = Faces {
            mask,
            dof: vec![NONE; (nx + 1) * ny + nx * (ny + 1)],
            velocities: 0,
        };
        for (i, j) in faces.fluid_cells() {
            // The cell's faces: west, east (u), south, north (v).
            for (d, fi, fj) in [(0, i, j), (0, i + 1, j), (1, i, j), (1, i, j + 1)] {
                let wall = if d == 0 {
                    fi == 0 || fi == nx
                } else {
                    fj == 0 || fj == ny
                };
                let k = faces.index(d, fi, fj);
                if !wall && faces.dof[k] == NONE {
                    faces.dof[k] = faces.velocities;
                    faces.velocities += 1;
                }
            }
        }
        faces
    }

    fn fluid(&self, i: usize, j: usize) -> bool {
        let [nx, ny] = self.mask.cells;
        i < nx && j < ny && self.mask.fluid[i + j * nx]
    }

    fn fluid_cells(&self) -> Vec<(usize, usize)> {
        let [nx, ny] = self.mask.cells;
        (0..ny)
            .flat_map(|j| (0..nx).map(move |i| (i, j)))
            .filter(|&(i, j)| self.fluid(i, j))
            .collect()
    }

    /// How many faces of component d there are along x and y.
    fn span(&self, d: usize) -> [usize; 2] {
        let [nx, ny] = self.mask.cells;
        if d == 0 {
            [nx + 1, ny]
        } else {
            [nx, ny + 1]
        }
    }

    fn index(&self, d: usize, i: usize, j: usize) -> usize {
        let [nx, ny] = self.mask.cells;
        if d == 0 {
            i + j * (nx + 1)
        } else {
            (nx + 1) * ny + i + j * nx
        }
    }

    /// The face exists and borders a fluid cell.
    fn present(&self, d: usize, i: usize, j: usize) -> bool {
        let [si, sj] = self.span(d);
        let before = if d == 0 {
            (i.wrapping_sub(1), j)
        } else {
            (i, j.wrapping_sub(1))
        };
        i < si && j < sj && (self.fluid(before.0, before.1) || self.fluid(i, j))
    }

    /// The five-point Laplacian of each component: sum over neighbouring
    /// faces of (u_a - u_b)^2 (the bilinear Laplacian's scaling), a pinned
    /// face held at 0, across a fluid cell or between two faces of fluid
    /// cells; a no-slip wall h / 2 away adds 2 u^2.
    fn stiffness(&self) -> Csr {
        let mut rows = vec![vec![]; self.velocities];
        let mut couple = |ka: usize, kb: usize, w: f64| {
            for (k, other) in [(ka, kb), (kb, ka)] {
                if k != NONE {
                    rows[k].push((k, w));
                    if other != NONE {
                        rows[k].push((other, -w));
                    }
                }
            }
        };
        let no_slip = self.mask.no_slip;
        for d in 0..2 {
            let [si, sj] = self.span(d);
            for (i, j) in (0..sj).flat_map(|j| (0..si).map(move |i| (i, j))) {
                if !self.present(d, i, j) {
                    continue;
                }
                let k = self.dof[self.index(d, i, j)];
                // Along the component: across the cell beyond this face.
                let (ai, aj) = if d == 0 { (i + 1, j) } else { (i, j + 1) };
                if self.fluid(i, j) && self.present(d, ai, aj) {
                    couple(k, self.dof[self.index(d, ai, aj)], 1.0);
                }
                // Across it: the next face of the component, or a wall.
                let (ci, cj) = if d == 0 { (i, j + 1) } else { (i + 1, j) };
                let (first, last) = if d == 0 {
                    (j == 0, j + 1 == sj)
                } else {
                    (i == 0, i + 1 == si)
                };
                if !last && self.present(d, ci, cj) {
                    couple(k, self.dof[self.index(d, ci, cj)], 1.0);
                }
                for _ in 0..(usize::from(first) + usize::from(last)) * usize::from(no_slip) {
                    couple(k, NONE, 2.0);
                }
            }
        }
        Csr::from_rows(rows)
    }

    /// B: the flux out of each fluid cell.
    fn divergence(&self, cells: &[(usize, usize)]) -> Csr {
        let h = self.mask.h;
        let rows = cells
            .iter()
            .map(|&(i, j)| {
                [
                    (0, i, j, -h),
                    (0, i + 1, j, h),
                    (1, i, j, -h),
                    (1, i, j + 1, h),
                ]
                .into_iter()
                .map(|(d, fi, fj, c)| (self.dof[self.index(d, fi, fj)], c))
                .filter(|&(k, _)| k != NONE)
                .collect()
            })
            .collect();
        Csr::from_rows(rows)
    }
}

impl Pair {
    /// The staggered pair: u on the vertical faces, v on the horizontal
    /// ones, of every fluid cell; a wall pins the normal component
    /// (`Faces::stiffness` for A).
    fn mac(mask: &Mask) -> Result<Pair, String> {
        let [nx, ny] = mask.cells;
        if mask.fluid.len() != nx * ny {
            return Err(format!("mask: {} cells for {nx} x {ny}", mask.fluid.len()));
        }
        let faces = Faces::new(mask);
        let cells = faces.fluid_cells();
        if cells.is_empty() {
            return Err("mask: no fluid cell".into());
        }
        Ok(Pair {
            b: faces.divergence(&cells),
            a: faces.stiffness(),
            cells,
            h: mask.h,
        })
    }
}

/// The Schur operator S = M_p^-1 B A^-1 B^T with its scratch.
struct Schur<'a> {
    pair: &'a Pair,
    inv_diag: Vec<f64>,
    w: Vec<f64>,
    z: Vec<f64>,
    r: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
}

impl<'a> Schur<'a> {
    fn new(pair: &'a Pair) -> Result<Self, String> {
        let diag = pair.a.diagonal();
        if diag.iter().any(|&d| d <= 0.0) {
            return Err("a free velocity component with no stiffness".into());
        }
        let n = pair.a.rows();
        Ok(Schur {
            pair,
            inv_diag: diag.iter().map(|d| 1.0 / d).collect(),
            w: vec![0.0; n],
            z: vec![0.0; n],
            r: vec![0.0; n],
            p: vec![0.0; n],
            q: vec![0.0; n],
        })
    }

    /// y = S x.
    fn apply(&mut self, x: &[f64], y: &mut [f64]) -> Result<(), String> {
        self.pair.b.mul_transpose(x, &mut self.w);
        self.solve_a()?;
        self.pair.b.mul(&self.z, y);
        let inv_area = 1.0 / (self.pair.h * self.pair.h);
        y.iter_mut().for_each(|v| *v *= inv_area);
        Ok(())
    }

    /// z = A^-1 w by Jacobi-preconditioned conjugate gradients.
    fn solve_a(&mut self) -> Result<(), String> {
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        self.z.fill(0.0);
        self.r.copy_from_slice(&self.w);
        let norm_b = dot(&self.w, &self.w).sqrt();
        if norm_b == 0.0 {
            return Ok(());
        }
        for (p, (r, d)) in self.p.iter_mut().zip(self.r.iter().zip(&self.inv_diag)) {
            *p = r * d;
        }
        let mut rz = dot(&self.r, &self.p);
        for _ in 0..20 * self.w.len().max(100) {
            self.pair.a.mul(&self.p, &mut self.q);
            let alpha = rz / dot(&self.p, &self.q);
            for k in 0..self.z.len() {
                self.z[k] += alpha * self.p[k];
                self.r[k] -= alpha * self.q[k];
            }
            if dot(&self.r, &self.r).sqrt() <= 1e-13 * norm_b {
                return Ok(());
            }
            let rz_new: f64 = self
                .r
                .iter()
                .zip(&self.inv_diag)
                .map(|(r, d)| r * r * d)
                .sum();
            let beta = rz_new / rz;
            rz = rz_new;
            for k in 0..self.p.len() {
                self.p[k] = self.r[k] * self.inv_diag[k] + beta * self.p[k];
            }
        }
        Err("the velocity solve did not converge (is A singular: no wall?)".into())
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Removes from `v` its components along the orthonormal `basis`.
fn orthogonalise(v: &mut [f64], basis: &[Vec<f64>]) {
    // Twice: one pass loses orthogonality in round-off.
    for _ in 0..2 {
        for u in basis {
            let c = dot(v, u);
            v.iter_mut().zip(u).for_each(|(x, y)| *x -= c * y);
        }
    }
}

/// The probes: the constant and the checkerboard over the fluid cells.
fn probes(pair: &Pair) -> Vec<(&'static str, Vec<f64>)> {
    let constant = vec![1.0; pair.cells.len()];
    let checkerboard = pair
        .cells
        .iter()
        .map(|&(i, j)| if (i + j) % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    vec![("constant", constant), ("checkerboard", checkerboard)]
}

/// Runs the test on a mask for the collocated pair, with at most
/// `max_steps` Lanczos steps.
pub fn collocated(mask: &Mask, max_steps: usize) -> Result<InfSup, String> {
    test(mask, PairKind::Collocated, max_steps)
}

/// Runs the test on a mask for a pair, with at most `max_steps` Lanczos steps.
pub fn test(mask: &Mask, kind: PairKind, max_steps: usize) -> Result<InfSup, String> {
    let pair = match kind {
        PairKind::Collocated => Pair::collocated(mask)?,
        PairKind::Mac => Pair::mac(mask)?,
    };
    let mut schur = Schur::new(&pair)?;
    let n = pair.cells.len();
    let mut y = vec![0.0; n];
    let mut kernel: Vec<Vec<f64>> = vec![];
    let mut found = vec![];
    for (name, mut q) in probes(&pair) {
        let norm = dot(&q, &q).sqrt();
        q.iter_mut().for_each(|x| *x /= norm);
        schur.apply(&q, &mut y)?;
        let quotient = dot(&q, &y);
        if quotient < KERNEL {
            orthogonalise(&mut q, &kernel);
            let norm = dot(&q, &q).sqrt();
            if norm > 1e-8 {
                q.iter_mut().for_each(|x| *x /= norm);
                kernel.push(q);
            }
        }
        found.push(Probe { name, quotient });
    }
    let (lambda_min, lambda_max, residual, steps) =
        smallest_eigenvalue(&mut schur, &kernel, n, max_steps)?;
    Ok(InfSup {
        pressures: n,
        velocities: pair.a.rows(),
        probes: found,
        deflated: kernel.len(),
        lambda_min,
        beta: lambda_min.max(0.0).sqrt(),
        residual,
        lambda_max,
        lanczos_steps: steps,
    })
}

/// Lanczos on S in the complement of `kernel`, from a fixed start vector:
/// (smallest Ritz value, largest, residual bound on the smallest, steps).
fn smallest_eigenvalue(
    schur: &mut Schur,
    kernel: &[Vec<f64>],
    n: usize,
    max_steps: usize,
) -> Result<(f64, f64, f64, usize), String> {
    let room = n.saturating_sub(kernel.len());
    if room == 0 {
        return Err("no pressure mode outside the kernel".into());
    }
    let steps = max_steps.clamp(1, room);
    // A fixed, aperiodic start vector (no random numbers: determinism).
    let mut v: Vec<f64> = (0..n)
        .map(|k| 1.0 + ((k as f64 + 1.0) * 0.618_033_988_749_895).fract())
        .collect();
    orthogonalise(&mut v, kernel);
    let norm = dot(&v, &v).sqrt();
    v.iter_mut().for_each(|x| *x /= norm);
    let mut basis: Vec<Vec<f64>> = vec![];
    let (mut alpha, mut beta) = (vec![], vec![]);
    let mut w = vec![0.0; n];
    let mut best = (f64::NAN, f64::NAN, f64::INFINITY);
    for k in 0..steps {
        schur.apply(&v, &mut w)?;
        let a = dot(&v, &w);
        alpha.push(a);
        basis.push(v.clone());
        let before = dot(&w, &w).sqrt();
        orthogonalise(&mut w, kernel);
        orthogonalise(&mut w, &basis);
        orthogonalise(&mut w, kernel);
        let b = dot(&w, &w).sqrt();
        // What is left is round-off: the Krylov space is invariant (an
        // eigenvalue of several modes counts once), and w / b would carry
        // the kernel back in.
        let last = k + 1 == steps || b <= 1e-8 * before;
        if last || (k + 1) % 10 == 0 {
            best = ritz(&alpha, &beta, b);
            if last || best.2 <= 1e-6 * best.0.abs().max(1e-12) {
                return Ok((best.0, best.1, best.2, k + 1));
            }
        }
        // Lanczos grows any kernel part (the lowest eigenvalue) from
        // round-off: every new vector is cleared of it again.
        v.iter_mut().zip(&w).for_each(|(x, y)| *x = y / b);
        orthogonalise(&mut v, kernel);
        let norm = dot(&v, &v).sqrt();
        v.iter_mut().for_each(|x| *x /= norm);
        beta.push(b);
    }
    Ok((best.0, best.1, best.2, steps))
}

/// The tridiagonal matrix's smallest and largest eigenvalues and the
/// residual bound |b s_last| of the smallest.
fn ritz(alpha: &[f64], beta: &[f64], b_next: f64) -> (f64, f64, f64) {
    let m = alpha.len();
    let t = DMatrix::from_fn(m, m, |r, c| {
        if r == c {
            alpha[r]
        } else if r + 1 == c {
            beta[r]
        } else if c + 1 == r {
            beta[c]
        } else {
            0.0
        }
    });
    let eig = SymmetricEigen::new(t);
    let (mut lo, mut hi) = (0, 0);
    for k in 0..m {
        if eig.eigenvalues[k] < eig.eigenvalues[lo] {
            lo = k;
        }
        if eig.eigenvalues[k] > eig.eigenvalues[hi] {
            hi = k;
        }
    }
    let residual = (b_next * eig.eigenvectors[(m - 1, lo)]).abs();
    (eig.eigenvalues[lo], eig.eigenvalues[hi], residual)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::Vec2;

    /// S as a dense matrix, from A inverted densely.
    fn dense_schur(pair: &Pair) -> DMatrix<f64> {
        let nu = pair.a.rows();
        let dense = |m: &Csr, cols: usize| {
            let mut d = DMatrix::<f64>::zeros(m.rows(), cols);
            for r in 0..m.rows() {
                for k in m.start[r]..m.start[r + 1] {
                    d[(r, m.col[k])] += m.val[k];
                }
            }
            d
        };
        let (a, b) = (dense(&pair.a, nu), dense(&pair.b, nu));
        let a_inv = a.try_inverse().expect("A is invertible");
        &b * a_inv * b.transpose() / (pair.h * pair.h)
    }

    #[test]
    fn lanczos_finds_the_dense_smallest_eigenvalue_past_the_kernel() {
        // A full box (checkerboard and constant in the kernel) and a
        // column in its corner (a free surface: neither is).
        let masks = [
            Mask::full([6, 5], 0.1),
            Mask::of_rects([8, 6], 0.1, &[[0.0, 0.0, 0.4, 0.45]]),
        ];
        let mut no_slip = masks[1].clone();
        no_slip.no_slip = true;
        let cases = [
            (PairKind::Collocated, &masks[0]),
            (PairKind::Collocated, &masks[1]),
            (PairKind::Mac, &masks[0]),
            (PairKind::Mac, &masks[1]),
            (PairKind::Mac, &no_slip),
        ];
        for (kind, mask) in cases {
            let pair = match kind {
                PairKind::Collocated => Pair::collocated(mask).unwrap(),
                PairKind::Mac => Pair::mac(mask).unwrap(),
            };
            let s = dense_schur(&pair);
            let mut eig: Vec<f64> = SymmetricEigen::new(s).eigenvalues.iter().copied().collect();
            eig.sort_by(f64::total_cmp);
            let got = test(mask, kind, 200).unwrap();
            let zeros = eig.iter().filter(|&&e| e < KERNEL).count();
            assert_eq!(got.deflated, zeros, "{got:?} {eig:?}");
            let expected = eig[zeros];
            assert!(
                (got.lambda_min - expected).abs() <= 1e-8 * expected.max(1e-6),
                "{got:?} against {expected}"
            );
            let top = eig[eig.len() - 1];
            assert!((got.lambda_max - top).abs() <= 1e-8, "{got:?} {top}");
        }
    }

    #[test]
    fn the_full_box_checkerboard_is_seen_only_through_free_slip_walls() {
        // No slip: the gradient cannot see the checkerboard (nor the
        // constant), the classic spurious mode of Q1-P0.
        let mut mask = Mask::full([10, 8], 0.05);
        mask.no_slip = true;
        let held = collocated(&mask, 300).unwrap();
        let names: Vec<&str> = held.probes.iter().map(|p| p.name).collect();
        assert_eq!(names, ["constant", "checkerboard"]);
        assert!(held.probes.iter().all(|p| p.quotient < 1e-20), "{held:?}");
        assert_eq!(held.deflated, 2);
        // Free slip: the walls' tangential components feel it, and that
        // grip weakens as the walls' share of the nodes falls with h.
        let coarse = collocated(&Mask::full([10, 8], 0.05), 300).unwrap();
        let fine = collocated(&Mask::full([20, 16], 0.025), 300).unwrap();
        let grip = |r: &InfSup| r.probes[1].quotient;
        assert_eq!((coarse.deflated, fine.deflated), (1, 1));
        assert!(grip(&fine) < 0.6 * grip(&coarse), "{coarse:?} {fine:?}");
        // |div u|^2 <= 2 |grad u|^2 pointwise, and a cell mean's square is
        // at most the mean square: every eigenvalue is at most 2.
        for r in [&held, &coarse, &fine] {
            assert!(r.lambda_max <= 2.0 + 1e-9 && r.lambda_min > 0.0, "{r:?}");
        }
    }

    #[test]
    fn the_staggered_pair_keeps_its_constant_as_h_falls() {
        let coarse = test(&Mask::full([16, 12], 0.05), PairKind::Mac, 400).unwrap();
        let fine = test(&Mask::full([32, 24], 0.025), PairKind::Mac, 400).unwrap();
        for r in [&coarse, &fine] {
            // Only the constant is in the closed box's kernel.
            assert_eq!(r.deflated, 1, "{r:?}");
            assert!(r.probes[1].quotient > 0.5, "{r:?}");
            assert!(r.beta > 0.2, "{r:?}");
        }
        let ratio = fine.beta / coarse.beta;
        assert!((0.9..1.1).contains(&ratio), "{coarse:?} {fine:?}");
        // No slip: bounded too, well above the collocated pair's.
        let held = |cells, h| {
            let mut m = Mask::full(cells, h);
            m.no_slip = true;
            test(&m, PairKind::Mac, 400).unwrap().beta
        };
        let (c, f) = (held([16, 12], 0.05), held([32, 24], 0.025));
        assert!(f > 0.3 && (0.9..1.1).contains(&(f / c)), "{c} {f}");
        // The collocated pair on the same boxes halves.
        let q1 = |cells, h| {
            test(&Mask::full(cells, h), PairKind::Collocated, 400)
                .unwrap()
                .beta
        };
        let halved = q1([32, 24], 0.025) / q1([16, 12], 0.05);
        assert!((0.45..0.55).contains(&halved), "{halved}");
    }

    #[test]
    fn b_is_the_projections_divergence_times_the_cell_area() {
        let mask = Mask::of_rects([7, 6], 0.02, &[[0.0, 0.0, 0.1, 0.08]]);
        let pair = Pair::collocated(&mask).unwrap();
        let [nx, _] = mask.cells;
        // A nodal field, zero on the components the walls pin.
        let nodes = (nx + 1) * (mask.cells[1] + 1);
        let u: Vec<Vec2> = (0..nodes)
            .map(|n| {
                let (i, j) = (n % (nx + 1), n / (nx + 1));
                let x = if i == 0 || i == nx {
                    0.0
                } else {
                    (n as f64 * 0.37).sin()
                };
                let y = if j == 0 || j == mask.cells[1] {
                    0.0
                } else {
                    (n as f64 * 0.71).cos()
                };
                Vec2::new(x, y)
            })
            .collect();
        // The same field on the free components, in B's numbering.
        let mut free = vec![0.0; pair.a.rows()];
        let mut k = 0;
        let mut seen = vec![false; 2 * nodes];
        for &(i, j) in &pair.cells {
            for &(di, dj, _, _) in &CORNERS {
                let n = (i + di) + (j + dj) * (nx + 1);
                for d in 0..2 {
                    let wall = if d == 0 {
                        i + di == 0 || i + di == nx
                    } else {
                        j + dj == 0 || j + dj == mask.cells[1]
                    };
                    if !wall && !seen[2 * n + d] {
                        seen[2 * n + d] = true;
                        free[k] = u[n][d];
                        k += 1;
                    }
                }
            }
        }
        assert_eq!(k, free.len());
        let mut bu = vec![0.0; pair.cells.len()];
        pair.b.mul(&free, &mut bu);
        for (c, &(i, j)) in pair.cells.iter().enumerate() {
            let corners = CORNERS.map(|(di, dj, _, _)| ((i + di) + (j + dj) * (nx + 1)) as u32);
            let d = super::super::operator::divergence(
                &corners,
                &super::super::operator::UNWEIGHTED,
                &u,
                mask.h,
            );
            assert!(
                (bu[c] - d * mask.h * mask.h).abs() < 1e-15,
                "{c}: {} {d}",
                bu[c]
            );
        }
    }
}
