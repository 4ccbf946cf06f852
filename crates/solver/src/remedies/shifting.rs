//! Particle shifting (`[method.shifting] time, surface_share`;
//! docs/physics.md section 5; after Lind et al. 2012 in SPH). A fluid's material points can gather into lines
//! and leave slits between them narrower than the grid's support: the nodes
//! see a full, uniform fluid there and nothing closes the slits. Each step,
//! after G2P, every particle moves down the gradient of the particles'
//! concentration C on an auxiliary grid of the seeding spacing l = h / ppc:
//!
//!   C_k = sum_p (V0_p / l^2) N_k(x_p)   (quadratic B-splines of width l,
//!                                        mirror images at walls included)
//!   dx_p = -(dt / tau) l^2 grad C(x_p),  |dx_p| <= MAX_STEP l.
//!
//! A lattice of spacing l gives C = 1 at every node whatever its offset
//! (the B-splines' partition of unity), so it is a fixed point. Where the
//! particle's (coarse) stencil is not inside the material, the component
//! along the outward normal of the grid mass is removed, so a free surface
//! does not spread. Velocities, J, F and stress stay: mass and momentum are
//! unchanged. Serial, in particle order: deterministic for any thread count.
//!
//! `surface_share`: a particle whose (coarse) stencil has a node below this
//! share of a full node's mass rho0 h^2 does not shift outward. Lower, it
//! tells a surface (nodes near empty) from a depleted region (nodes part
//! full), which a high share would lock against refill.
//!
//! Energy: the gravitational energy the moves change.

// The loop walks particles and their stencils in step.
#![allow(clippy::needless_range_loop)]

use super::{Descriptor, EnergyChange, Remedy, Setup, Step, Supports};
use super::Check;
use crate::grid::{Grid, FULL_NODE_SHARE};
use crate::config_error::ConfigError;
use crate::particles::{Particles, Vec2};
use crate::shapes::{Shape, Stencil};
use crate::shapes::bspline::quadratic;
use serde::{Deserialize, Serialize};

/// The largest shift per step in units of l, a guard against dt / tau near
/// 1 (an explicit diffusion of C stays stable well below it).
pub const MAX_STEP: f64 = 0.25;

/// Scratch arrays, allocated once.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    /// Concentration per fine node, one ghost node on each side.
    conc: Vec<f64>,
    /// Fine node count per axis, ghosts included.
    dims: [usize; 2],
    /// The fine spacing l (m).
    spacing: f64,
    /// The folded coarse mass, ghosts filled (the surface test).
    coarse_mass: Vec<f64>,
}

impl Scratch {
    /// A fine grid of `ppc` nodes per cell over the coarse grid's box.
    pub fn new(grid: &Grid, ppc: usize) -> Self {
        let dims = [grid.cells[0] * ppc + 3, grid.cells[1] * ppc + 3];
        Scratch {
            conc: vec![0.0; dims[0] * dims[1]],
            dims,
            spacing: grid.h / ppc as f64,
            coarse_mass: vec![0.0; grid.mass.len()],
        }
    }

    /// The concentration at fine node (i, j) (physical indices; for tests).
    pub fn concentration(&self, i: usize, j: usize) -> f64 {
        self.conc[(j + 1) * self.dims[0] + i + 1]
    }
}

/// A particle's fine stencil: padded index of its first node and its offset
/// from it in units of l; None outside the fine grid.
fn fine_stencil(s: &Scratch, origin: Vec2, x: Vec2) -> Option<(usize, [f64; 2])> {
    let r = (x - origin) / s.spacing;
    let mut node = [0usize; 2];
    let mut frac = [0.0; 2];
    for d in 0..2 {
        if !r[d].is_finite() {
            return None;
        }
        let base = (r[d] - 0.5).floor();
        // Padded first node base + 1 >= 0, last base + 3 < dims.
        if base < -1.0 || base + 3.0 >= s.dims[d] as f64 {
            return None;
        }
        node[d] = (base + 1.0) as usize;
        frac[d] = r[d] - base;
    }
    Some((node[1] * s.dims[0] + node[0], frac))
}

/// The concentration field of the particles, walls folded in.
pub fn concentration(ps: &Particles, grid: &Grid, s: &mut Scratch) {
    s.conc.fill(0.0);
    let inv_area = 1.0 / (s.spacing * s.spacing);
    let nx = s.dims[0];
    for p in 0..ps.len() {
        let Some((first, frac)) = fine_stencil(s, grid.origin, ps.x[p]) else {
            continue;
        };
        let w = ps.vol0[p] * inv_area;
        for c in 0..3 {
            let wy = quadratic(frac[1] - c as f64).0;
            for a in 0..3 {
                s.conc[first + c * nx + a] += w * wy * quadratic(frac[0] - a as f64).0;
            }
        }
    }
    fold_walls(s);
}

/// Mirror images at the four walls: the wall node doubles, the node next to
/// it takes its ghost, and the ghost then mirrors it (x first, then y, so a
/// corner gets all three images).
fn fold_walls(s: &mut Scratch) {
    let [nx, ny] = s.dims;
    let at = |i: usize, j: usize| j * nx + i;
    for j in 0..ny {
        for (wall, inner, ghost) in [(1, 2, 0), (nx - 2, nx - 3, nx - 1)] {
            s.conc[at(wall, j)] *= 2.0;
            s.conc[at(inner, j)] += s.conc[at(ghost, j)];
            s.conc[at(ghost, j)] = s.conc[at(inner, j)];
        }
    }
    for i in 0..nx {
        for (wall, inner, ghost) in [(1, 2, 0), (ny - 2, ny - 3, ny - 1)] {
            s.conc[at(i, wall)] *= 2.0;
            s.conc[at(i, inner)] += s.conc[at(i, ghost)];
            s.conc[at(i, ghost)] = s.conc[at(i, inner)];
        }
    }
}

/// grad C at x (1/m); None outside the fine grid.
fn gradient(s: &Scratch, origin: Vec2, x: Vec2) -> Option<Vec2> {
    let (first, frac) = fine_stencil(s, origin, x)?;
    let nx = s.dims[0];
    let mut g = Vec2::zeros();
    for c in 0..3 {
        let (ny, dny) = quadratic(frac[1] - c as f64);
        for a in 0..3 {
            let (nxw, dnx) = quadratic(frac[0] - a as f64);
            let q = s.conc[first + c * nx + a];
            g += q * Vec2::new(dnx * ny, nxw * dny);
        }
    }
    Some(g / s.spacing)
}

/// Shifts every particle with `rate` = dt / tau (see the module's
/// documentation). `stencils` are this step's coarse stencils.
pub fn shift(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    rate: f64,
    surface_share: f64,
    s: &mut Scratch,
) {
    crate::shapes::with_width!(shape, W => shift_w::<W>(ps, stencils, shape, grid, rate, surface_share, s))
}

fn shift_w<const W: usize>(
    ps: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    rate: f64,
    surface_share: f64,
    s: &mut Scratch,
) {
    concentration(ps, grid, s);
    s.coarse_mass.copy_from_slice(&grid.mass);
    grid.fill(&mut s.coarse_mass);
    let l = s.spacing;
    let lo = grid.origin;
    let hi = grid.origin + Vec2::new(grid.cells[0] as f64 * grid.h, grid.cells[1] as f64 * grid.h);
    let area = grid.h * grid.h;
    for p in 0..ps.len() {
        let Some(g) = gradient(s, lo, ps.x[p]) else {
            continue;
        };
        let mut dx = -rate * l * l * g;
        let len = dx.norm();
        if len > MAX_STEP * l {
            dx *= MAX_STEP * l / len;
        }
        let full = surface_share * ps.mass[p] / ps.vol0[p] * area;
        let (inside, inward) = coarse_surface::<W>(&stencils[p], shape, grid, &s.coarse_mass, full);
        if !inside {
            let norm = inward.norm();
            if norm == 0.0 {
                continue;
            }
            let outward = -inward / norm;
            let out = dx.dot(&outward);
            if out > 0.0 {
                dx -= out * outward;
            }
        }
        let x = ps.x[p] + dx;
        for d in 0..2 {
            if x[d] > lo[d] && x[d] < hi[d] {
                ps.x[p][d] = x[d];
            }
        }
    }
}

/// Whether every node of the coarse stencil holds at least `full`, and the
/// gradient of the coarse mass at the particle (pointing into the material).
fn coarse_surface<const W: usize>(
    st: &Stencil,
    shape: &Shape,
    grid: &Grid,
    mass: &[f64],
    full: f64,
) -> (bool, Vec2) {
    let (wx, dwx) = shape.stencil_weights::<W>(st.frac[0], st.half[0]);
    let (wy, dwy) = shape.stencil_weights::<W>(st.frac[1], st.half[1]);
    let nx = grid.dims[0];
    let (mut inside, mut g) = (true, Vec2::zeros());
    for c in 0..W {
        let row = st.node as usize + c * nx;
        for a in 0..W {
            let w = wx[a] * wy[c];
            let m = mass[row + a];
            if w != 0.0 {
                inside &= m >= full;
            }
            g += m * Vec2::new(dwx[a] * wy[c], wx[a] * dwy[c]);
        }
    }
    (inside, g)
}

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "shifting",
    main: Some(("time", 0.02)),
    old_keys: &[("time", "shift_time"), ("surface_share", "shift_surface_share")],
};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// The shifting time tau (s): each step moves by -(dt / tau) l^2 grad C.
    pub time: f64,
    /// The free-surface test's share of a full node's mass (0.05 ..= 1).
    pub surface_share: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            time: 0.02,
            surface_share: FULL_NODE_SHARE,
        }
    }
}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn supports(&self) -> Supports {
        Supports {
            mixtures: false,
            solids: false,
            // The shifting grid mirrors at walls only.
            periodic: false,
            // It reads per-axis weights.
            shapes: crate::shapes::TENSOR_PRODUCT,
            ..Supports::ALL
        }
    }
    fn validate(&self, _cfg: &Check) -> Result<(), ConfigError> {
        super::positive_up_to(self.time, 1e3, "method.shifting.time")?;
        if !(self.surface_share >= 0.05 && self.surface_share <= 1.0) {
            return Err(ConfigError {
                key: "method.shifting.surface_share".into(),
                message: format!(
                    "{} is out of range (allowed 0.05 ..= 1)",
                    self.surface_share
                ),
            });
        }
        Ok(())
    }
    fn build(&self, setup: &Setup) -> Box<dyn Remedy> {
        Box::new(Shifting {
            settings: self.clone(),
            scratch: Scratch::new(setup.grid, setup.ppc),
        })
    }
}

#[derive(Clone)]
struct Shifting {
    settings: Settings,
    scratch: Scratch,
}

impl Remedy for Shifting {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }
    fn after_g2p(&mut self, s: &mut Step) -> EnergyChange {
        let height = |ps: &Particles| -> f64 { ps.mass.iter().zip(&ps.x).map(|(m, x)| m * x.y).sum() };
        let before = height(s.particles);
        let rate = s.dt / self.settings.time;
        let share = self.settings.surface_share;
        shift(s.particles, s.stencils, s.shape, s.grid, rate, share, &mut self.scratch);
        EnergyChange {
            gravitational: s.gravity * (height(s.particles) - before),
            ..EnergyChange::default()
        }
    }
}
