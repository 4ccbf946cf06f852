//! XPIC(m) (Hammerquist & Nairn 2017). On the grid,
//! v* = sum_{k=1..m} (-1)^(k+1) C(m, k) (M_L^-1 M_C)^(k-1) v^n,
//! where M_L^-1 M_C is the grid -> particle -> grid round trip (interpolate,
//! then mass-weighted P2G with the wall folds). The particle velocity is then
//! S v* plus FLIP's increment S (v^{n+1} - v^n): XPIC(1) is PIC, and for
//! particle velocities V = S u it returns S (I - A^m) u with A = I - M_L^-1 M_C.
//! Serial, in particle order: deterministic for any thread count.

// The loops walk several arrays in step (weights, nodes, particles).
#![allow(clippy::needless_range_loop)]

use crate::grid::Grid;
use crate::particles::{Particles, Vec2};
use crate::shapes::{Shape, Stencil};
use crate::transfers::serial::{gather, scatter_mass_weighted};

/// Grid and particle scratch, allocated once.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    v_star: Vec<Vec2>,
    prev: Vec<Vec2>,
    next: Vec<Vec2>,
    /// Per particle: the interpolated `prev`.
    at_particles: Vec<Vec2>,
}

impl Scratch {
    pub fn new(grid: &Grid, particles: usize) -> Self {
        let nodes = grid.dims[0] * grid.dims[1];
        Scratch {
            v_star: vec![Vec2::zeros(); nodes],
            prev: vec![Vec2::zeros(); nodes],
            next: vec![Vec2::zeros(); nodes],
            at_particles: vec![Vec2::zeros(); particles],
        }
    }

    /// v* of the last step per padded node (forensics).
    pub(crate) fn v_star(&self) -> &[Vec2] {
        &self.v_star
    }

    /// Per-particle room for `n` particles (an inflow appends them); a
    /// scratch not in use (empty) stays empty.
    pub(crate) fn fit_particles(&mut self, n: usize) {
        if !self.at_particles.is_empty() && self.at_particles.len() < n {
            self.at_particles.resize(n, Vec2::zeros());
        }
    }
}

/// field_i = sum_p m_p N_ip u_p / m_i (folded like momentum, ghosts refilled).
fn project<const W: usize>(
    u: &[Vec2],
    ps: &Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    out: &mut [Vec2],
) {
    scatter_mass_weighted::<W>(u, &ps.mass, stencils, shape, grid, out);
    grid.fold(out);
    for &n in &grid.inside {
        let n = n as usize;
        let m = grid.mass[n];
        out[n] = if m > 0.0 { out[n] / m } else { Vec2::zeros() };
    }
    grid.fill(out);
}

fn run<const W: usize>(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    order: u32,
    s: &mut Scratch,
) {
    let nx = grid.dims[0];
    let m = order as f64;
    for &n in &grid.active {
        let n = n as usize;
        // The k = 1 term, C(m, 1) v^n; each next term is C(m, k) (M_L^-1 M_C)^(k-1) v^n.
        s.v_star[n] = m * grid.vel[n];
        s.prev[n] = s.v_star[n];
    }
    let n_particles = ps.len();
    let mut sign = -1.0;
    for k in 2..=order {
        // C(m, k) / C(m, k - 1) = (m - k + 1) / k.
        let scale = (m - k as f64 + 1.0) / k as f64;
        gather::<W>(
            &s.prev,
            stencils,
            shape,
            nx,
            &mut s.at_particles[..n_particles],
        );
        project::<W>(
            &s.at_particles[..n_particles],
            ps,
            stencils,
            shape,
            grid,
            &mut s.next,
        );
        for &n in &grid.active {
            let n = n as usize;
            s.next[n] *= scale;
            s.v_star[n] += sign * s.next[n];
        }
        std::mem::swap(&mut s.prev, &mut s.next);
        sign = -sign;
    }
    gather::<W>(&s.v_star, stencils, shape, nx, &mut ps.v[..n_particles]);
}

/// Sets every particle's velocity to S v* (G2P then adds FLIP's increment).
pub fn smooth(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    order: u32,
    s: &mut Scratch,
) {
    crate::shapes::with_width!(shape, W => run::<W>(ps, stencils, shape, grid, order, s))
}
