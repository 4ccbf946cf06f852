//! Volumetric remedies applied after the stress stage (docs/physics.md
//! section 5), each off by default:
//! - cell-averaged dilatation (Mast et al. 2012): J_c = sum V / sum V0 over
//!   the particles of a cell, J_p <- (1 - b) J_p + b J_c;
//! - J-bar by particle-grid averaging (Zhao, Jiang & Choo 2023):
//!   J_i = sum N m J / m_i, J_bar = sum N J_i, J_p <- (1 - b) J_p + b J_bar;
//!   with `j_bar_fit = "linear"` each node fits a plane instead of the mean
//!   (mass-weighted least squares over its support), so a linear J field,
//!   the hydrostatic one, is a fixed point up to the material's edges;
//! - volume consistency: J relaxes towards rho0 / (grid density), the
//!   volume the particles' packing gives them;
//! - pressure smoothing through the nodes (CB-Geo): the same round trip for p.
//!
//! J changes scale F by (J_new / J)^(1/2), so that det F = J (2D). Every pass
//! is serial, in particle order: deterministic for any thread count.

// The loops walk several arrays in step (weights, nodes, particles).
#![allow(clippy::needless_range_loop)]

use crate::config::{JBarFit, Material, Method};
use crate::grid::Grid;
use crate::particles::{Mat2, Particles};
use crate::shape::{Shape, Stencil};

/// Scratch arrays, allocated once.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    /// Per cell: sum V, sum V0, and whether it holds an inverted particle.
    cell_volume: Vec<f64>,
    cell_volume0: Vec<f64>,
    cell_bad: Vec<bool>,
    /// Per padded node: sum N m q and sum N m.
    node_sum: Vec<f64>,
    node_mass: Vec<f64>,
    /// Per padded node, for the linear fit: sum w, sum w d (2), sum w d d^T
    /// (3), sum w q, sum w q d (2), with w = N m and d the particle's offset
    /// from the node in cells; then the node's plane (mean, d mean, slope).
    node_moments: Vec<[f64; 9]>,
    /// Per particle: the averaged value.
    averaged: Vec<f64>,
    /// Per particle: its own J and F while the averaged ones set the stress
    /// (`method.carry_averaged_j = false`).
    own_j: Vec<f64>,
    own_f: Vec<Mat2>,
    /// Per particle: this step's volume ratio J_new / J_old
    /// (`method.average_increment`).
    ratio: Vec<f64>,
}

impl Scratch {
    /// `linear_fit`: room for `j_bar_fit = "linear"`'s nodal moments.
    pub fn new(grid: &Grid, particles: usize, linear_fit: bool) -> Self {
        let cells = grid.cells[0] * grid.cells[1];
        let nodes = grid.dims[0] * grid.dims[1];
        Scratch {
            cell_volume: vec![0.0; cells],
            cell_volume0: vec![0.0; cells],
            cell_bad: vec![false; cells],
            node_sum: vec![0.0; nodes],
            node_mass: vec![0.0; nodes],
            node_moments: vec![[0.0; 9]; if linear_fit { nodes } else { 0 }],
            averaged: vec![0.0; particles],
            own_j: vec![0.0; particles],
            own_f: vec![Mat2::zeros(); particles],
            ratio: vec![0.0; particles],
        }
    }

    /// Per-particle room for `n` particles (an inflow appends them); a
    /// scratch not in use (empty) stays empty.
    pub(crate) fn fit_particles(&mut self, n: usize) {
        if self.averaged.is_empty() || self.averaged.len() >= n {
            return;
        }
        self.averaged.resize(n, 0.0);
        self.own_j.resize(n, 0.0);
        self.own_f.resize(n, Mat2::zeros());
        self.ratio.resize(n, 0.0);
    }
}

fn cell_of(grid: &Grid, x: crate::Vec2) -> usize {
    let r = (x - grid.origin) / grid.h;
    let clamp = |v: f64, n: usize| {
        if v.is_finite() {
            (v.max(0.0) as usize).min(n - 1)
        } else {
            0
        }
    };
    clamp(r.x, grid.cells[0]) + grid.cells[0] * clamp(r.y, grid.cells[1])
}

/// Sets J_p to `j_new` (when positive and finite), scaling F and V with it.
#[inline]
fn set_j(ps: &mut Particles, p: usize, j_new: f64) {
    let j = ps.j[p];
    if !(j_new > 0.0 && j_new.is_finite() && j > 0.0) {
        return;
    }
    ps.f[p] *= (j_new / j).sqrt();
    ps.j[p] = j_new;
    ps.vol[p] = ps.vol0[p] * j_new;
}

/// Cell-averaged dilatation with blend `b`. A cell holding a particle with
/// J <= 0 (or non-finite) is left alone: a positive J_c would hide it.
pub fn cell_dilatation(ps: &mut Particles, grid: &Grid, b: f64, s: &mut Scratch) {
    s.cell_volume.fill(0.0);
    s.cell_volume0.fill(0.0);
    s.cell_bad.fill(false);
    for p in 0..ps.len() {
        let c = cell_of(grid, ps.x[p]);
        if !(ps.j[p] > 0.0 && ps.j[p].is_finite()) {
            s.cell_bad[c] = true;
        }
        s.cell_volume[c] += ps.vol[p];
        s.cell_volume0[c] += ps.vol0[p];
    }
    for p in 0..ps.len() {
        let c = cell_of(grid, ps.x[p]);
        if s.cell_bad[c] {
            continue;
        }
        let j_c = s.cell_volume[c] / s.cell_volume0[c];
        let j_new = if b == 1.0 {
            j_c
        } else {
            (1.0 - b) * ps.j[p] + b * j_c
        };
        set_j(ps, p, j_new);
    }
}

/// Calls `f(node, N, dx, dy)` for every node of a particle's stencil: its
/// padded index, the weight and the particle's offset from it in cells.
#[inline(always)]
fn each_node<const W: usize>(
    st: &Stencil,
    shape: &Shape,
    nx: usize,
    mut f: impl FnMut(usize, f64, f64, f64),
) {
    let (wx, _) = shape.stencil_weights::<W>(st.frac[0], st.half[0]);
    let (wy, _) = shape.stencil_weights::<W>(st.frac[1], st.half[1]);
    for c in 0..W {
        let row = st.node as usize + c * nx;
        let dy = st.frac[1] - c as f64;
        for a in 0..W {
            f(row + a, wx[a] * wy[c], st.frac[0] - a as f64, dy);
        }
    }
}

/// The round trip q_i = sum N m q / m_i, q_bar_p = sum N q_i into
/// `s.averaged` (sum_p m_p q_bar_p = sum_p m_p q_p for any arrangement).
fn round_trip<const W: usize>(
    ps: &Particles,
    q: &[f64],
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    s: &mut Scratch,
) {
    s.node_sum.fill(0.0);
    s.node_mass.fill(0.0);
    let nx = grid.dims[0];
    for p in 0..ps.len() {
        let (m, mq) = (ps.mass[p], ps.mass[p] * q[p]);
        each_node::<W>(&stencils[p], shape, nx, |n, w, _, _| {
            s.node_sum[n] += w * mq;
            s.node_mass[n] += w * m;
        });
    }
    for p in 0..ps.len() {
        let mut sum = 0.0;
        each_node::<W>(&stencils[p], shape, nx, |n, w, _, _| {
            if w != 0.0 {
                sum += w * s.node_sum[n] / s.node_mass[n];
            }
        });
        s.averaged[p] = sum;
    }
}

/// Below this variance (cells^2) along a direction a node's data do not
/// determine a slope there (a single row of particles): the plane is flat
/// along it. A full quadratic B-spline support has 1/4.
const MIN_FIT_VARIANCE: f64 = 1e-4;

/// The round trip with a plane per node: q_i(d) = qm_i + b_i . (d - dm_i)
/// fitted by least squares with weights N m over the node's particles,
/// q_bar_p = sum N q_i(d_ip). The fit's first normal equation makes
/// sum_p m_p q_bar_p = sum_p m_p q_p for any arrangement; a linear q is
/// returned exactly where every node's data span the directions it varies in.
fn round_trip_linear<const W: usize>(
    ps: &Particles,
    q: &[f64],
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    s: &mut Scratch,
) {
    s.node_moments.fill([0.0; 9]);
    let nx = grid.dims[0];
    for p in 0..ps.len() {
        let (m, qp) = (ps.mass[p], q[p]);
        each_node::<W>(&stencils[p], shape, nx, |i, w, dx, dy| {
            let w = w * m;
            let n = &mut s.node_moments[i];
            n[0] += w;
            n[1] += w * dx;
            n[2] += w * dy;
            n[3] += w * dx * dx;
            n[4] += w * dx * dy;
            n[5] += w * dy * dy;
            n[6] += w * qp;
            n[7] += w * qp * dx;
            n[8] += w * qp * dy;
        });
    }
    for n in s.node_moments.iter_mut() {
        *n = node_plane(n);
    }
    for p in 0..ps.len() {
        let mut sum = 0.0;
        each_node::<W>(&stencils[p], shape, nx, |i, w, dx, dy| {
            if w != 0.0 {
                let f = &s.node_moments[i];
                sum += w * (f[0] + f[3] * (dx - f[1]) + f[4] * (dy - f[2]));
            }
        });
        s.averaged[p] = sum;
    }
}

/// A node's moments -> [mean q, mean dx, mean dy, slope x, slope y]: the
/// slope solves C b = cov(d, q) on the directions where the weighted
/// covariance C of the offsets has variance above `MIN_FIT_VARIANCE` (a
/// pseudo-inverse by C's eigenvectors), zero along the others.
fn node_plane(n: &[f64; 9]) -> [f64; 9] {
    let s0 = n[0];
    if s0 <= 0.0 {
        return [0.0; 9];
    }
    let (mx, my, qm) = (n[1] / s0, n[2] / s0, n[6] / s0);
    let cxx = n[3] / s0 - mx * mx;
    let cxy = n[4] / s0 - mx * my;
    let cyy = n[5] / s0 - my * my;
    let gx = n[7] / s0 - qm * mx;
    let gy = n[8] / s0 - qm * my;
    // Eigenvectors of the symmetric 2 x 2 C.
    let half_trace = 0.5 * (cxx + cyy);
    let root = (0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy).sqrt();
    let (l1, l2) = (half_trace + root, half_trace - root);
    // The first eigenvector, (l1 - cyy, cxy) or (cxy, l1 - cxx), written
    // without the cancellation of l1 - cyy when C is nearly isotropic.
    let (vx, vy) = if cxx >= cyy {
        (0.5 * (cxx - cyy) + root, cxy)
    } else {
        (cxy, 0.5 * (cyy - cxx) + root)
    };
    let len = (vx * vx + vy * vy).sqrt();
    let (ex, ey) = if len > 0.0 {
        (vx / len, vy / len)
    } else {
        (1.0, 0.0)
    };
    let mut b = [0.0; 2];
    for (l, (ux, uy)) in [(l1, (ex, ey)), (l2, (-ey, ex))] {
        if l > MIN_FIT_VARIANCE {
            let along = (ux * gx + uy * gy) / l;
            b[0] += along * ux;
            b[1] += along * uy;
        }
    }
    [qm, mx, my, b[0], b[1], 0.0, 0.0, 0.0, 0.0]
}

/// The round trip of `q` into `s.averaged` with the nodal `fit`,
/// monomorphised on the stencil width.
fn averaged(
    ps: &Particles,
    q: &[f64],
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    fit: JBarFit,
    s: &mut Scratch,
) {
    use JBarFit::{Constant, Linear};
    match (shape.width(), fit) {
        (2, Constant) => round_trip::<2>(ps, q, stencils, shape, grid, s),
        (3, Constant) => round_trip::<3>(ps, q, stencils, shape, grid, s),
        (_, Constant) => round_trip::<4>(ps, q, stencils, shape, grid, s),
        (2, Linear) => round_trip_linear::<2>(ps, q, stencils, shape, grid, s),
        (3, Linear) => round_trip_linear::<3>(ps, q, stencils, shape, grid, s),
        (_, Linear) => round_trip_linear::<4>(ps, q, stencils, shape, grid, s),
    }
}

/// J-bar by particle-grid averaging with `method.j_bar`'s blend b and
/// `j_bar_fit`: of J, or with `average_increment` of this step's J_new /
/// J_old (then J_bar = J_old times the averaged ratio). Skipped for the whole step when some J <= 0: averaging
/// would hide the inversion.
pub fn j_bar(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    method: &Method,
    s: &mut Scratch,
) {
    let (b, increment, fit) = (method.j_bar, method.average_increment, method.j_bar_fit);
    if ps.j.iter().any(|j| !(*j > 0.0 && j.is_finite())) {
        return;
    }
    if increment {
        // Average this step's volume ratio, not J (the J before the stress
        // stage was saved by `save_own`): a state at rest is left alone.
        let n = ps.len();
        for p in 0..n {
            s.ratio[p] = ps.j[p] / s.own_j[p];
        }
        let ratio = std::mem::take(&mut s.ratio);
        averaged(ps, &ratio[..n], stencils, shape, grid, fit, s);
        s.ratio = ratio;
        for p in 0..n {
            s.averaged[p] *= s.own_j[p];
        }
    } else {
        let j = std::mem::take(&mut ps.j);
        averaged(ps, &j, stencils, shape, grid, fit, s);
        ps.j = j;
    }
    for p in 0..ps.len() {
        let j_new = if b == 1.0 {
            s.averaged[p]
        } else {
            (1.0 - b) * ps.j[p] + b * s.averaged[p]
        };
        set_j(ps, p, j_new);
    }
}

/// A particle's stencil counts as inside the material when every node it
/// weighs holds at least this share of a full node's mass rho0 h^2: near a
/// free surface the grid density says nothing about the particles' volume.
pub(crate) const FULL_NODE_SHARE: f64 = 0.75;

/// Volume consistency with blend `b`: J_geo = rho0 / sum N rho_i, with the
/// grid density rho_i = m_i / h^2 of the folded nodal mass (mirror images
/// at walls included), J_p <- (1 - b) J_p + b J_geo where the stencil is
/// inside the material. The particles' J then follows how closely they
/// actually pack, so particles that crowd (more of them per node than their
/// J says) are pressed apart by the pressure.
pub fn volume_consistency(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    b: f64,
    s: &mut Scratch,
) {
    match shape.width() {
        2 => volume_consistency_w::<2>(ps, stencils, shape, grid, b, s),
        3 => volume_consistency_w::<3>(ps, stencils, shape, grid, b, s),
        _ => volume_consistency_w::<4>(ps, stencils, shape, grid, b, s),
    }
}

fn volume_consistency_w<const W: usize>(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    b: f64,
    s: &mut Scratch,
) {
    s.node_mass.copy_from_slice(&grid.mass);
    grid.fill(&mut s.node_mass);
    let nx = grid.dims[0];
    let area = grid.h * grid.h;
    for p in 0..ps.len() {
        let rho0 = ps.mass[p] / ps.vol0[p];
        let full = FULL_NODE_SHARE * rho0 * area;
        let (mut sum, mut inside) = (0.0, true);
        each_node::<W>(&stencils[p], shape, nx, |n, w, _, _| {
            if w != 0.0 {
                let m = s.node_mass[n];
                inside &= m >= full;
                sum += w * m;
            }
        });
        if inside {
            let j_geo = rho0 * area / sum;
            set_j(ps, p, (1.0 - b) * ps.j[p] + b * j_geo);
        }
    }
}

/// Pressure smoothing: p <- sum N p_i, the stress following (sigma = viscous - p I).
pub fn smooth_pressure(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    s: &mut Scratch,
) {
    let pressure = std::mem::take(&mut ps.pressure);
    averaged(ps, &pressure, stencils, shape, grid, JBarFit::Constant, s);
    ps.pressure = pressure;
    for p in 0..ps.len() {
        let p_new = s.averaged[p];
        if p_new.is_finite() {
            ps.stress[p] += Mat2::identity() * (ps.pressure[p] - p_new);
            ps.pressure[p] = p_new;
        }
    }
}

/// Pressure, wave speed, stored energy and stress again after J changed.
pub fn reevaluate_eos(ps: &mut Particles, materials: &[Material]) {
    for p in 0..ps.len() {
        let m = &materials[ps.material[p] as usize];
        let j = ps.j[p];
        let state = m.eos(j);
        let p_new = m.cut(state.pressure);
        ps.stress[p] += Mat2::identity() * (ps.pressure[p] - p_new);
        ps.pressure[p] = p_new;
        ps.wave_speed[p] = m.wave_speed_of(&state, j);
        ps.stored_energy[p] = ps.vol0[p] * state.energy;
    }
}

/// Keeps each particle's own J and F aside (`method.carry_averaged_j = false`).
pub fn save_own(ps: &Particles, s: &mut Scratch) {
    let n = ps.len();
    s.own_j[..n].copy_from_slice(&ps.j);
    s.own_f[..n].copy_from_slice(&ps.f);
}

/// Gives each particle its own J and F back; the pressure, stress and
/// volume set from the averaged J stay for this step.
pub fn restore_own(ps: &mut Particles, s: &Scratch) {
    let n = ps.len();
    ps.j.copy_from_slice(&s.own_j[..n]);
    ps.f.copy_from_slice(&s.own_f[..n]);
}
