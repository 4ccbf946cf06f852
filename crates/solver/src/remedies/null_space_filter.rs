//! Null-space filter (Gritton & Berzins 2017), `[method.null_space_filter]`: the consistent-mass
//! least-squares projection of the particle velocities onto the span of the
//! shape functions,
//!
//! ```text
//! v <- S (S^T W S)^-1 S^T W v,   S_pi = N_i(x_p),  W = diag(m_p),
//! ```
//!
//! so any S u is kept and any z with S^T W z = 0 (a velocity pattern the grid
//! cannot see: FLIP's ringing noise) is removed. Gritton & Berzins solve it
//! with local SVDs; here the consistent-mass system M_C u = S^T W v is solved
//! globally by conjugate gradients preconditioned with the lumped mass, on the
//! raw nodes of this step's stencils (no wall images: the filter acts in
//! particle space; the walls act in the grid update; on a periodic axis the
//! seam's ghost nodes are unknowns of their own, so the span is a little
//! wider there than the periodic grid's). Applied after G2P, to
//! FLIP velocities only (PIC, APIC and XPIC velocities are S u already).
//! Serial, in particle order, with a fixed stopping rule: deterministic for
//! any thread count.
//!
//! Energy: the kinetic energy the projection changes.

// The loops walk several arrays in step (weights, nodes, particles).
#![allow(clippy::needless_range_loop)]

use super::{Descriptor, EnergyChange, Remedy, Setup, Step, Supports};
use crate::choices::TransferKind;
use crate::grid::Grid;
use crate::particles::{Particles, Vec2};
use crate::shapes::{Shape, Stencil};
use crate::transfers::serial::{gather, scatter_mass_weighted};

/// Conjugate-gradient stop: residual below this fraction of the right-hand side.
pub const TOLERANCE: f64 = 1e-12;
/// And at most this many iterations (a step's cost is bounded).
pub const MAX_ITERATIONS: usize = 1000;

/// Node and particle scratch, allocated once.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    /// Per node: solution, residual, search direction, M p.
    u: Vec<Vec2>,
    r: Vec<Vec2>,
    d: Vec<Vec2>,
    md: Vec<Vec2>,
    /// Per particle: an interpolated node field.
    at_particles: Vec<Vec2>,
    /// Iterations of the last solve (diagnostic).
    pub last_iterations: usize,
}

impl Scratch {
    pub fn new(grid: &Grid, particles: usize) -> Self {
        let nodes = grid.dims[0] * grid.dims[1];
        Scratch {
            u: vec![Vec2::zeros(); nodes],
            r: vec![Vec2::zeros(); nodes],
            d: vec![Vec2::zeros(); nodes],
            md: vec![Vec2::zeros(); nodes],
            at_particles: vec![Vec2::zeros(); particles],
            last_iterations: 0,
        }
    }

    /// Per-particle room for `n` particles (an inflow appends them); a
    /// scratch not in use (empty) stays empty.
    pub(crate) fn fit_particles(&mut self, n: usize) {
        if !self.at_particles.is_empty() && self.at_particles.len() < n {
            self.at_particles.resize(n, Vec2::zeros());
        }
    }
}

/// out_i = (M_C field)_i = sum_p m_p N_ip sum_j N_jp field_j, through the
/// particles (`at_particles` is scratch).
fn consistent_mass<const W: usize>(
    field: &[Vec2],
    ps: &Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    at_particles: &mut [Vec2],
    out: &mut [Vec2],
) {
    gather::<W>(field, stencils, shape, grid.dims[0], at_particles);
    scatter_mass_weighted::<W>(at_particles, &ps.mass, stencils, shape, grid, out);
}

fn dot(grid: &Grid, a: &[Vec2], b: &[Vec2]) -> f64 {
    grid.active
        .iter()
        .map(|&n| a[n as usize].dot(&b[n as usize]))
        .sum()
}

fn run<const W: usize>(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    s: &mut Scratch,
) {
    let n = ps.len();
    let nx = grid.dims[0];
    let lumped = &grid.mass_raw;
    // Lumped-mass preconditioner; a node no particle weighs is left out (u = 0).
    let precondition = |r: Vec2, node: usize| {
        if lumped[node] > 0.0 {
            r / lumped[node]
        } else {
            Vec2::zeros()
        }
    };
    // b = S^T W v, kept in r; the start u = M_L^-1 b is PIC's answer.
    scatter_mass_weighted::<W>(&ps.v[..n], &ps.mass, stencils, shape, grid, &mut s.r);
    let b_norm = dot(grid, &s.r, &s.r).sqrt();
    for &node in &grid.active {
        let node = node as usize;
        s.u[node] = precondition(s.r[node], node);
    }
    let at_particles = &mut s.at_particles[..n];
    consistent_mass::<W>(&s.u, ps, stencils, shape, grid, at_particles, &mut s.md);
    for &node in &grid.active {
        let node = node as usize;
        s.r[node] -= s.md[node];
        s.d[node] = precondition(s.r[node], node);
    }
    let mut rz: f64 = grid
        .active
        .iter()
        .map(|&node| s.r[node as usize].dot(&s.d[node as usize]))
        .sum();
    let mut iterations = 0;
    while iterations < MAX_ITERATIONS && dot(grid, &s.r, &s.r).sqrt() > TOLERANCE * b_norm {
        let at_particles = &mut s.at_particles[..n];
        consistent_mass::<W>(&s.d, ps, stencils, shape, grid, at_particles, &mut s.md);
        let dmd = dot(grid, &s.d, &s.md);
        if dmd.is_nan() || dmd <= 0.0 {
            break;
        }
        let alpha = rz / dmd;
        for &node in &grid.active {
            let node = node as usize;
            s.u[node] += alpha * s.d[node];
            s.r[node] -= alpha * s.md[node];
        }
        let rz_new: f64 = grid
            .active
            .iter()
            .map(|&node| {
                let node = node as usize;
                s.r[node].dot(&precondition(s.r[node], node))
            })
            .sum();
        let beta = rz_new / rz;
        rz = rz_new;
        for &node in &grid.active {
            let node = node as usize;
            s.d[node] = precondition(s.r[node], node) + beta * s.d[node];
        }
        iterations += 1;
    }
    s.last_iterations = iterations;
    gather::<W>(&s.u, stencils, shape, nx, &mut ps.v[..n]);
}

/// Replaces every particle velocity by its consistent-mass projection S u.
pub fn filter(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    s: &mut Scratch,
) {
    crate::shapes::with_width!(shape, W => run::<W>(ps, stencils, shape, grid, s))
}

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "null_space_filter",
    main: None,
    old_keys: &[],
};

#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Settings {}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn supports(&self) -> Supports {
        // PIC, APIC and XPIC velocities are already in the shape functions'
        // span: the filter would change nothing.
        Supports {
            transfers: &[TransferKind::Flip],
            // It reads per-axis weights.
            shapes: crate::shapes::TENSOR_PRODUCT,
            ..Supports::ALL
        }
    }
    fn build(&self, setup: &Setup) -> Box<dyn Remedy> {
        Box::new(Filter(Scratch::new(setup.grid, setup.particles)))
    }
}

#[derive(Clone)]
struct Filter(Scratch);

impl Remedy for Filter {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }
    fn fit_particles(&mut self, n: usize) {
        self.0.fit_particles(n);
    }
    fn after_g2p(&mut self, s: &mut Step) -> EnergyChange {
        let before = super::kinetic_energy(s.particles);
        filter(s.particles, s.stencils, s.shape, s.grid, &mut self.0);
        EnergyChange {
            kinetic: super::kinetic_energy(s.particles) - before,
            ..EnergyChange::default()
        }
    }
}
