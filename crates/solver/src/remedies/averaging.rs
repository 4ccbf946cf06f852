//! Particle-grid averaging shared by the volumetric remedies: the round trip
//! q_i = sum N m q / m_i, q_bar_p = sum N q_i (or a least-squares plane per
//! node), and J changes that keep det F = J. Serial, in particle order:
//! deterministic for any thread count.

// The loops walk several arrays in step (weights, nodes, particles).
#![allow(clippy::needless_range_loop)]

use crate::choices::JBarFit;
use crate::grid::Grid;
use crate::particles::Particles;
use crate::shapes::{Shape, Stencil};

/// Nodal sums and the averaged value per particle, allocated once.
#[derive(Clone, Debug, Default)]
pub struct Averager {
    /// Per padded node: sum N m q and sum N m.
    pub(super) node_sum: Vec<f64>,
    pub(super) node_mass: Vec<f64>,
    /// Per padded node, for the linear fit: sum w, sum w d (2), sum w d d^T
    /// (3), sum w q, sum w q d (2), with w = N m and d the particle's offset
    /// from the node in cells; then the node's plane (mean, d mean, slope).
    node_moments: Vec<[f64; 9]>,
    /// Per particle: the averaged value.
    pub averaged: Vec<f64>,
}

impl Averager {
    /// `linear_fit`: room for the linear fit's nodal moments.
    pub fn new(grid: &Grid, particles: usize, linear_fit: bool) -> Self {
        let nodes = grid.dims[0] * grid.dims[1];
        Averager {
            node_sum: vec![0.0; nodes],
            node_mass: vec![0.0; nodes],
            node_moments: vec![[0.0; 9]; if linear_fit { nodes } else { 0 }],
            averaged: vec![0.0; particles],
        }
    }

    pub fn fit_particles(&mut self, n: usize) {
        if self.averaged.len() < n {
            self.averaged.resize(n, 0.0);
        }
    }

    /// Padded node count.
    pub fn nodes(&self) -> usize {
        self.node_mass.len()
    }

    /// The last round trip's nodal value at padded node `i` (the plane's
    /// value at the node under the linear fit), and its weight sum N m;
    /// None where no particle reached the node.
    pub fn node_value(&self, i: usize) -> Option<(f64, f64)> {
        if self.node_moments.is_empty() {
            let m = self.node_mass[i];
            (m > 0.0).then(|| (self.node_sum[i] / m, m))
        } else {
            let f = &self.node_moments[i];
            (f[5] > 0.0).then(|| (f[0] - f[3] * f[1] - f[4] * f[2], f[5]))
        }
    }
}

pub(super) fn cell_of(grid: &Grid, x: crate::Vec2) -> usize {
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
pub(super) fn set_j(ps: &mut Particles, p: usize, j_new: f64) {
    let j = ps.j[p];
    if !(j_new > 0.0 && j_new.is_finite() && j > 0.0) {
        return;
    }
    ps.f[p] *= (j_new / j).sqrt();
    ps.j[p] = j_new;
    ps.vol[p] = ps.vol0[p] * j_new;
}

/// Calls `f(node, N, dx, dy)` for every node of a particle's stencil: its
/// padded index, the weight and the particle's offset from it in cells.
#[inline(always)]
pub(super) fn each_node<const W: usize>(
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
    s: &mut Averager,
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
    s: &mut Averager,
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

/// A node's moments -> [mean q, mean dx, mean dy, slope x, slope y, sum w]: the
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
    [qm, mx, my, b[0], b[1], s0, 0.0, 0.0, 0.0]
}

/// The round trip of `q` into `s.averaged` with the nodal `fit`,
/// monomorphised on the stencil width.
pub(super) fn averaged(
    ps: &Particles,
    q: &[f64],
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    fit: JBarFit,
    s: &mut Averager,
) {
    crate::shapes::with_width!(shape, W => match fit {
        JBarFit::Constant => round_trip::<W>(ps, q, stencils, shape, grid, s),
        JBarFit::Linear => round_trip_linear::<W>(ps, q, stencils, shape, grid, s),
    })
}

/// `set_j`, returning the stored energy it changed, V0 (U(J_new) - U(J_old)).
pub(super) fn set_j_booked(
    ps: &mut Particles,
    materials: &[crate::material::Material],
    p: usize,
    j_new: f64,
) -> f64 {
    let j_old = ps.j[p];
    set_j(ps, p, j_new);
    let j = ps.j[p];
    if j == j_old {
        0.0
    } else {
        super::stored_energy_at(ps, materials, p, j)
            - super::stored_energy_at(ps, materials, p, j_old)
    }
}

/// A particle's own J, F and pressure, kept while an averaged J sets this
/// step's pressure only (`carry = false`), or its J before the stress update
/// (`average_increment`).
#[derive(Clone, Debug, Default)]
pub(super) struct Own {
    pub j: Vec<f64>,
    pub f: Vec<crate::particles::Mat2>,
    pub vol: Vec<f64>,
    pub stress: Vec<crate::particles::Mat2>,
}

impl Own {
    pub fn new(particles: usize) -> Self {
        Own {
            j: vec![0.0; particles],
            f: vec![crate::particles::Mat2::zeros(); particles],
            vol: vec![0.0; particles],
            stress: vec![crate::particles::Mat2::zeros(); particles],
        }
    }

    pub fn fit_particles(&mut self, n: usize) {
        if self.j.len() < n {
            self.j.resize(n, 0.0);
            self.f.resize(n, crate::particles::Mat2::zeros());
            self.vol.resize(n, 0.0);
            self.stress.resize(n, crate::particles::Mat2::zeros());
        }
    }

    pub fn save(&mut self, ps: &Particles) {
        let n = ps.len();
        self.j[..n].copy_from_slice(&ps.j);
        self.f[..n].copy_from_slice(&ps.f);
        self.vol[..n].copy_from_slice(&ps.vol);
        self.stress[..n].copy_from_slice(&ps.stress);
    }

    /// Gives each particle its own J and F back; the pressure, stress and
    /// volume set from the averaged J stay for this step.
    pub fn restore(&self, ps: &mut Particles) {
        let n = ps.len();
        ps.j.copy_from_slice(&self.j[..n]);
        ps.f.copy_from_slice(&self.f[..n]);
    }
}

/// `carry = false` of an averaged J: the particle's own J and F are kept
/// while the average sets this step's pressure and volume, and the work of
/// that stress change is booked at the grid update that uses it. With
/// `carry = true` it does nothing and the average's stored energy is booked.
#[derive(Clone, Debug, Default)]
pub(super) struct Uncarried {
    on: bool,
    own: Own,
    work: super::stress_work::StressWork,
}

impl Uncarried {
    pub fn new(carry: bool, particles: usize) -> Self {
        let n = if carry { 0 } else { particles };
        Uncarried {
            on: !carry,
            own: Own::new(n),
            work: super::stress_work::StressWork::new(n),
        }
    }

    pub fn fit_particles(&mut self, n: usize) {
        if self.on {
            self.own.fit_particles(n);
            self.work.fit_particles(n);
        }
    }

    /// Before the average: the particle's own state.
    pub fn keep(&mut self, ps: &Particles) {
        if self.on {
            self.own.save(ps);
        }
    }

    /// What the average changed: its stored energy when carried (the EOS
    /// is evaluated again either way).
    pub fn averaged(&self, stored: f64) -> (super::EnergyChange, bool) {
        let stored = if self.on { 0.0 } else { stored };
        let change = super::EnergyChange {
            stored,
            ..super::EnergyChange::default()
        };
        (change, true)
    }

    /// After the pressure: the stress change kept, the own J and F back.
    pub fn restore(&mut self, ps: &mut Particles) {
        if self.on {
            self.work.record(ps, &self.own.vol, &self.own.stress);
            self.own.restore(ps);
        }
    }

    pub fn book(&mut self, g: &super::GridStep) -> super::EnergyChange {
        super::EnergyChange {
            work: self.work.book(g),
            ..super::EnergyChange::default()
        }
    }
}
