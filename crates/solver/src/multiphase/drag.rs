//! Interaction (drag) between two phases' grid velocity fields
//! (docs/physics.md section 6). Each phase is stepped to v* = v^{n+1} on its
//! own grid; the drag then corrects v* at every node both phases occupy,
//! keeping the node's total momentum m_a v_a + m_b v_b, so action equals
//! reaction node by node. Only the relative velocity dv = v_b - v_a changes:
//!
//! - explicit: dv' = dv* - dt k dv^n (stable for dt < 2 / k);
//! - implicit (backward Euler): dv' = dv* / (1 + dt k);
//! - exponential: dv' = dv^n exp(-dt k) + (dv* - dv^n) (1 - exp(-dt k)) / (dt k),
//!   the exact solution of d(dv)/dt = a - k dv with the other forces'
//!   a = (dv* - dv^n) / dt held over the step (pure decay: dv^n exp(-dt k)),
//!   stable at any dt like the implicit one;
//!
//! with k = B V_i (1/m_a + 1/m_b), B the drag coefficient per mixture volume
//! and V_i = V_i^a + V_i^b the nodal volume sum_p N_ip V_p of both phases
//! (folded like the masses, so a wall node looks like an interior one).

use crate::grid::Grid;
use crate::particles::Vec2;
use crate::transfers::serial::scatter_scalar;
use crate::Solver;
use serde::{Deserialize, Serialize};

/// Which interaction model (the slides' list; the volume constraint against
/// over-saturation is not a model of its own yet).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DragModel {
    /// chi_i = 1 where both phases have mass: f_i^a = -f_i^b = B V_i (v_i^b - v_i^a).
    #[default]
    BangBangNode,
    /// Each particle inside the other phase (every node of its stencil
    /// carries that phase) feels f_p = B V_p^mix (v^other(x_p) - v_p), spread
    /// by N_ip; the nodal equilibrium correction then makes f_i^a = -f_i^b.
    /// Explicit update only.
    BangBangParticle,
    /// Smooth volume fractions at the node: the drag acts on the volume both
    /// phases share there, V_i^cap phi_i^a phi_i^b, with phi_i = sum_p N_ip
    /// V_p / n_p / V_i^cap the share of the node's support a phase's bodies
    /// cover and V_i^cap = h^2; no chi_i.
    SvfNode,
    /// As `SvfNode` with each phi_i capped at 1 (the smooth fraction loses
    /// its smoothness where the quadrature overshoots 1).
    SvfCapped,
    /// The other phase's smooth fraction interpolated to the particle:
    /// f_p = B V_p^mix phi^other(x_p) (v^other(x_p) - v_p), phi^other(x_p) =
    /// sum_i N_ip phi_i^other, spread by N_ip with the nodal equilibrium
    /// correction; no inside test. Explicit update only.
    SvfParticle,
}

impl DragModel {
    /// The particle-based models, which take the explicit update only.
    pub fn is_particle_based(self) -> bool {
        matches!(self, DragModel::BangBangParticle | DragModel::SvfParticle)
    }

    /// The models that need each phase's smooth nodal presence.
    pub(super) fn uses_presence(self) -> bool {
        matches!(
            self,
            DragModel::SvfNode | DragModel::SvfCapped | DragModel::SvfParticle
        )
    }
}

/// How the nodal drag is integrated over a step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DragUpdate {
    Explicit,
    #[default]
    Implicit,
    Exponential,
}

/// The interaction between the two phases of a mixture.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Drag {
    /// B = n^2 mu / k (kg m^-3 s^-1): drag force per mixture volume per unit
    /// relative velocity.
    pub coefficient: f64,
    /// Kozeny-Carman: Some(n0) makes the coefficient that of porosity n0 and
    /// scales it with the node's porosity n = V_i^b / V_i (phase b is the
    /// fluid) as B(n) = n^2 mu / k(n), k(n) = k0 [n^3 / (1-n)^2] / [n0^3 / (1-n0)^2].
    pub kozeny_carman: Option<f64>,
    pub model: DragModel,
    pub update: DragUpdate,
}

impl Drag {
    /// B = n^2 mu / k for a fluid of viscosity mu (Pa s) through a skeleton of
    /// permeability k (m^2) at porosity n.
    pub fn from_permeability(viscosity: f64, permeability: f64, porosity: f64) -> f64 {
        porosity * porosity * viscosity / permeability
    }

    /// The coefficient at a node of porosity n.
    pub fn coefficient_at(&self, n: f64) -> f64 {
        match self.kozeny_carman {
            None => self.coefficient,
            Some(n0) => {
                let r = (1.0 - n) / (1.0 - n0);
                self.coefficient * (n0 / n) * r * r
            }
        }
    }
}

/// What one coupling did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Coupling {
    /// Nodes both phases occupy.
    pub nodes: usize,
    /// Kinetic energy the drag took from the grid velocities v^{n+1}
    /// (real particle masses, like the grid kinetic energy of P2G): the sum
    /// of what it took from each phase, which each phase's `dissipated` counts.
    pub dissipated: f64,
    /// Largest |m_a dv_a + m_b dv_b| over the coupled nodes relative to the
    /// node's momentum m_a |v_a*| + m_b |v_b*| (action against reaction; round-off).
    pub momentum_residual: f64,
    /// The explicit update's stability limit min_i 2 / k_i (infinite without coupled nodes).
    pub stable_dt: f64,
}

/// Per-phase nodal volumes, presences and particle-drag forces (full grid
/// arrays, allocated once) and per-particle values (grown when the particle
/// count grows).
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    pub(crate) volume: [Vec<f64>; 2],
    pub(crate) presence: [Vec<f64>; 2],
    pub(crate) force: [Vec<Vec2>; 2],
    pub(crate) per_particle: Vec<f64>,
}

impl Scratch {
    pub fn new(grid: &Grid) -> Self {
        let n = grid.dims[0] * grid.dims[1];
        Scratch {
            volume: [vec![0.0; n], vec![0.0; n]],
            presence: [vec![0.0; n], vec![0.0; n]],
            force: [vec![Vec2::zeros(); n], vec![Vec2::zeros(); n]],
            per_particle: vec![],
        }
    }
}

/// A particle's mixture volume V_p / n_p (its lattice cell, deformed): the
/// volume its body covers whatever its phase's fraction.
pub(crate) fn mixture_volume(s: &Solver, p: usize) -> f64 {
    let l = s.grid().h / s.scene().ppc as f64;
    s.particles().vol[p] / s.particles().vol0[p] * l * l
}

/// sum_p N_ip V_p / n_p on the raw nodes, folded, ghosts filled: the volume
/// the phase's bodies cover in each node's support.
pub(super) fn nodal_presence(s: &Solver, per_particle: &mut Vec<f64>, out: &mut [f64]) {
    per_particle.clear();
    per_particle.extend((0..s.particles().len()).map(|p| mixture_volume(s, p)));
    scatter_folded(per_particle, s, out);
    s.grid().fill(out);
}

/// sum_p N_ip q_p over a phase's particles on its active raw nodes, folded
/// (a wall or periodic node then looks like an interior one).
pub(crate) fn scatter_folded(q: &[f64], s: &Solver, out: &mut [f64]) {
    scatter_raw(q, s, out);
    s.grid().fold(out);
}

/// sum_p N_ip q_p over a phase's particles on its active raw nodes (zeroed
/// first), not folded.
pub(crate) fn scatter_raw(q: &[f64], s: &Solver, out: &mut [f64]) {
    let (st, shape, g) = (s.stencils(), s.shape(), s.grid());
    crate::shapes::with_width!(shape, W => scatter_scalar::<W>(q, st, shape, g, out))
}

/// V_i = sum_p N_ip V_p on the raw nodes, folded, ghosts filled (particles
/// near a periodic edge or wall read them).
pub(super) fn nodal_volume(s: &Solver, out: &mut [f64]) {
    scatter_folded(&s.particles().vol, s, out);
    s.grid().fill(out);
}

/// The node-based models (bang-bang, SVF, SVF-capped): one relative-velocity
/// update per node both phases occupy.
pub(super) fn couple_nodes(
    a: &mut Solver,
    b: &mut Solver,
    drag: &Drag,
    scratch: &Scratch,
    dt: f64,
    fixed_a: bool,
    out: &mut Coupling,
) {
    let [va, vb] = &scratch.volume;
    let [pa, pb] = &scratch.presence;
    let capacity = a.grid().h * a.grid().h;
    let (ga, gb) = (a.grid_mut(), b.grid_mut());
    for k in 0..ga.inside.len() {
        let n = ga.inside[k] as usize;
        let (ma, mb) = (ga.mass[n], gb.mass[n]);
        // chi_i: both phases at the node.
        if !(gb.is_active(n) && ma > 0.0 && mb > 0.0) {
            continue;
        }
        out.nodes += 1;
        let (inv_a, inv_b) = (if fixed_a { 0.0 } else { 1.0 / ma }, 1.0 / mb);
        let volume = va[n] + vb[n];
        let shared = match drag.model {
            DragModel::SvfNode => capacity * (pa[n] / capacity) * (pb[n] / capacity),
            DragModel::SvfCapped => {
                capacity * (pa[n] / capacity).min(1.0) * (pb[n] / capacity).min(1.0)
            }
            _ => volume,
        };
        let k = drag.coefficient_at(vb[n] / volume) * shared * (inv_a + inv_b);
        out.stable_dt = out.stable_dt.min(2.0 / k);
        let (sa, sb) = (ga.vel_new[n], gb.vel_new[n]);
        let rel = sb - sa;
        let rel_new = match drag.update {
            DragUpdate::Explicit => rel - (dt * k) * (gb.vel[n] - ga.vel[n]),
            DragUpdate::Implicit => rel / (1.0 + dt * k),
            DragUpdate::Exponential => {
                // Exact for d(dv)/dt = a - k dv with the other forces' a =
                // (dv* - dv^n) / dt held over the step.
                let x = dt * k;
                let start = gb.vel[n] - ga.vel[n];
                let forced = if x > 0.0 { -(-x).exp_m1() / x } else { 1.0 };
                start * (-x).exp() + (rel - start) * forced
            }
        };
        // The centre of mass keeps its velocity; each phase takes the share
        // of the relative change its inverse mass gives it.
        let inv = inv_a + inv_b;
        let centre = (inv_b * sa + inv_a * sb) / inv;
        let (na, nb) = (
            centre - (inv_a / inv) * rel_new,
            centre + (inv_b / inv) * rel_new,
        );
        set_pair(ga, gb, n, [na, nb], dt, fixed_a, out);
    }
}

/// Sets node n's corrected v^{n+1} of both phases (their accelerations
/// take the change over dt) and records the pair's momentum residual
/// |m_a dv_a + m_b dv_b| over the node's momentum (not for a fixed a).
pub(crate) fn set_pair(
    ga: &mut Grid,
    gb: &mut Grid,
    n: usize,
    [na, nb]: [Vec2; 2],
    dt: f64,
    fixed_a: bool,
    out: &mut Coupling,
) {
    let (ma, mb) = (ga.mass[n], gb.mass[n]);
    let (sa, sb) = (ga.vel_new[n], gb.vel_new[n]);
    let (da, db) = (na - sa, nb - sb);
    let scale = ma * sa.norm() + mb * sb.norm();
    if scale > 0.0 && !fixed_a {
        let residual = (ma * da + mb * db).norm() / scale;
        out.momentum_residual = out.momentum_residual.max(residual);
    }
    ga.vel_new[n] = na;
    gb.vel_new[n] = nb;
    ga.accel[n] += da / dt;
    gb.accel[n] += db / dt;
}

pub(crate) use crate::stages::grid_update::updated_kinetic as grid_kinetic;

/// Ghost nodes take their partners' corrected values again.
pub(crate) fn refill(g: &mut Grid) {
    let mut vel_new: Vec<Vec2> = std::mem::take(&mut g.vel_new);
    g.fill(&mut vel_new);
    g.vel_new = vel_new;
    let mut accel = std::mem::take(&mut g.accel);
    g.fill(&mut accel);
    g.accel = accel;
}
