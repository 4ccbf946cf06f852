//! Volumetric remedies applied after the stress stage (docs/physics.md
//! section 5), each off by default:
//! - cell-averaged dilatation (Mast et al. 2012): J_c = sum V / sum V0 over
//!   the particles of a cell, J_p <- (1 - b) J_p + b J_c;
//! - J-bar by particle-grid averaging (Zhao, Jiang & Choo 2023):
//!   J_i = sum N m J / m_i, J_bar = sum N J_i, J_p <- (1 - b) J_p + b J_bar;
//! - pressure smoothing through the nodes (CB-Geo): the same round trip for p.
//!
//! J changes scale F by (J_new / J)^(1/2), so that det F = J (2D). Every pass
//! is serial, in particle order: deterministic for any thread count.

// The loops walk several arrays in step (weights, nodes, particles).
#![allow(clippy::needless_range_loop)]

use crate::config::Material;
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
    pub fn new(grid: &Grid, particles: usize) -> Self {
        let cells = grid.cells[0] * grid.cells[1];
        let nodes = grid.dims[0] * grid.dims[1];
        Scratch {
            cell_volume: vec![0.0; cells],
            cell_volume0: vec![0.0; cells],
            cell_bad: vec![false; cells],
            node_sum: vec![0.0; nodes],
            node_mass: vec![0.0; nodes],
            averaged: vec![0.0; particles],
            own_j: vec![0.0; particles],
            own_f: vec![Mat2::zeros(); particles],
            ratio: vec![0.0; particles],
        }
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
        let st = &stencils[p];
        let (wx, _) = shape.stencil_weights::<W>(st.frac[0], st.half[0]);
        let (wy, _) = shape.stencil_weights::<W>(st.frac[1], st.half[1]);
        let (m, mq) = (ps.mass[p], ps.mass[p] * q[p]);
        for c in 0..W {
            let row = st.node as usize + c * nx;
            for a in 0..W {
                let w = wx[a] * wy[c];
                s.node_sum[row + a] += w * mq;
                s.node_mass[row + a] += w * m;
            }
        }
    }
    for p in 0..ps.len() {
        let st = &stencils[p];
        let (wx, _) = shape.stencil_weights::<W>(st.frac[0], st.half[0]);
        let (wy, _) = shape.stencil_weights::<W>(st.frac[1], st.half[1]);
        let mut sum = 0.0;
        for c in 0..W {
            let row = st.node as usize + c * nx;
            for a in 0..W {
                let n = row + a;
                let w = wx[a] * wy[c];
                if w != 0.0 {
                    sum += w * s.node_sum[n] / s.node_mass[n];
                }
            }
        }
        s.averaged[p] = sum;
    }
}

fn averaged(
    ps: &Particles,
    q: &[f64],
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    s: &mut Scratch,
) {
    match shape.width() {
        2 => round_trip::<2>(ps, q, stencils, shape, grid, s),
        3 => round_trip::<3>(ps, q, stencils, shape, grid, s),
        _ => round_trip::<4>(ps, q, stencils, shape, grid, s),
    }
}

/// J-bar by particle-grid averaging with blend `b`: of J, or with
/// `increment` of this step's J_new / J_old (then J_bar = J_old times the
/// averaged ratio). Skipped for the whole step when some J <= 0: averaging
/// would hide the inversion.
pub fn j_bar(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    b: f64,
    increment: bool,
    s: &mut Scratch,
) {
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
        averaged(ps, &ratio[..n], stencils, shape, grid, s);
        s.ratio = ratio;
        for p in 0..n {
            s.averaged[p] *= s.own_j[p];
        }
    } else {
        let j = std::mem::take(&mut ps.j);
        averaged(ps, &j, stencils, shape, grid, s);
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

/// Pressure smoothing: p <- sum N p_i, the stress following (sigma = viscous - p I).
pub fn smooth_pressure(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    s: &mut Scratch,
) {
    let pressure = std::mem::take(&mut ps.pressure);
    averaged(ps, &pressure, stencils, shape, grid, s);
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
