//! Force forensics (`kick explain`): one step taken as `Solver::step` takes
//! it, with chosen particles' velocity change split into what each stencil
//! node and each stress-carrying particle gave it (docs/physics.md section
//! 4c).
//!
//! G2P gives dv_p = sum_i N_ip (v_i^{n+1} - v_i^n) + jump, the jump being
//! the transfer's own: (1 - alpha) sum_i N_ip (v_i^n - v_p) for a FLIP/PIC
//! blend (PIC and APIC: alpha = 0, the affine term is in v_i^n), and
//! sum_i N_ip (v*_i - v_p) under XPIC. Each node's increment is split into
//! internal force, gravity and the rest (wall conditions, ghost images,
//! grid hooks); the internal force into each particle's -V sigma grad N
//! (pressure and deviatoric parts). Under the pressure-implicit
//! formulation the pressure is not a nodal force: the projection's own
//! changes (its hourglass control, the pressure correction, the velocity
//! extrapolation above the surface) are parts of their own, and "walls"
//! keeps only the wall conditions and ghost images. What G2P does not give (after-G2P
//! hooks, `[[perturb]]` impulses) is the particle's `rest`, zero to
//! round-off for a method without them.

// The stencil loops walk the 1D weights of both axes by node offset.
#![allow(clippy::needless_range_loop)]

use crate::grid::Grid;
use crate::particles::{Mat2, Vec2};
use crate::shapes::{with_width, Shape, Stencil};
use crate::{ForceKind, QuadratureKind, Solver, StepError, TransferKind};
use std::collections::HashMap;

/// One stencil node of an explained particle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodePart {
    /// Padded node index, and where it sits.
    pub node: u32,
    pub position: Vec2,
    /// N_ip.
    pub weight: f64,
    /// Folded nodal mass, and its share of a full node rho0 h^2.
    pub mass: f64,
    pub mass_share: f64,
    /// Folded nodal force (internal + gravity; under the pressure-implicit
    /// formulation plus the pressure's, m du / dt of its correction) and
    /// the node's velocity change as G2P reads it.
    pub force: Vec2,
    pub dv_node: Vec2,
    /// N dt (f / m - g): the internal force's part of dv_p.
    pub internal: Vec2,
    /// N dt g (0 at a massless node).
    pub external: Vec2,
    /// N (v^{n+1} - v^n) - N dt f / m less the three projection parts
    /// below: wall conditions, ghost images, hooks.
    pub walls: Vec2,
    /// Pressure-implicit only (else 0): N times the hourglass control's
    /// change of u*, the pressure correction dt M'^-1 G p, and the
    /// extrapolation's change at a node outside the fluid cells.
    pub hourglass: Vec2,
    pub pressure_correction: Vec2,
    pub extrapolation: Vec2,
    /// The transfer's own jump through this node.
    pub jump: Vec2,
    /// N (v^{n+1} - v^n): FLIP's increment through this node (the sum of
    /// the three above), against `interpolated`, N v^n.
    pub flip_increment: Vec2,
    pub interpolated: Vec2,
}

impl NodePart {
    /// The sum of this node's parts of dv_p.
    pub fn own_parts(&self) -> Vec2 {
        self.internal
            + self.external
            + self.walls
            + self.jump
            + self.hourglass
            + self.pressure_correction
            + self.extrapolation
    }

    /// The sum of its parts' sizes (what a closure's round-off is measured against).
    pub fn parts_size(&self) -> f64 {
        [
            self.internal,
            self.external,
            self.walls,
            self.jump,
            self.hourglass,
            self.pressure_correction,
            self.extrapolation,
        ]
        .iter()
        .map(|v| v.norm())
        .sum()
    }
}

/// What one stress-carrying particle gave an explained particle through
/// the latter's stencil nodes: sum_i N_ip dt f_iq / m_i, from its pressure
/// and from the rest of its stress (deviatoric, and any viscous pressure
/// such as bulk damping's).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StressPart {
    pub particle: usize,
    pub pressure: Vec2,
    pub deviatoric: Vec2,
}

/// One particle's velocity change over one step, decomposed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Explained {
    pub particle: usize,
    /// v_p(n - 1), and v_p(n) - v_p(n - 1).
    pub v_before: Vec2,
    pub dv: Vec2,
    pub nodes: Vec<NodePart>,
    pub stresses: Vec<StressPart>,
    /// Internal force of the nodes not carried by `stresses` (ghost images
    /// folded in; all of it under mixed quadrature).
    pub internal_unattributed: Vec2,
    /// The `[[perturb]]` impulse it got this step.
    pub impulse: Vec2,
    /// dv minus every node's parts and the impulse: after-G2P hooks (the
    /// null-space filter, shifting's velocity part), round-off. NaN when
    /// the particle was deleted in the step.
    pub rest: Vec2,
}

impl Explained {
    pub fn internal(&self) -> Vec2 {
        self.nodes.iter().map(|n| n.internal).sum()
    }
    pub fn external(&self) -> Vec2 {
        self.nodes.iter().map(|n| n.external).sum()
    }
    pub fn walls(&self) -> Vec2 {
        self.nodes.iter().map(|n| n.walls).sum()
    }
    pub fn jump(&self) -> Vec2 {
        self.nodes.iter().map(|n| n.jump).sum()
    }
    pub fn hourglass(&self) -> Vec2 {
        self.nodes.iter().map(|n| n.hourglass).sum()
    }
    pub fn pressure_correction(&self) -> Vec2 {
        self.nodes.iter().map(|n| n.pressure_correction).sum()
    }
    pub fn extrapolation(&self) -> Vec2 {
        self.nodes.iter().map(|n| n.extrapolation).sum()
    }
    /// The sum of the parts: dv to round-off (with `rest`, exactly).
    pub fn parts_sum(&self) -> Vec2 {
        self.impulse + self.nodes.iter().map(|n| n.own_parts()).sum::<Vec2>()
    }
}

/// An explained step: the particles' decompositions, and every particle's
/// state as this step's P2G used it (what the mechanisms' criteria read).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExplainedStep {
    pub explained: Vec<Explained>,
    /// Per particle at P2G: position, pressure and J of the stress the force used.
    pub x: Vec<Vec2>,
    pub pressure: Vec<f64>,
    pub j: Vec<f64>,
    /// Per particle at P2G: the volume and V0.
    pub volume: Vec<f64>,
    pub volume0: Vec<f64>,
    pub id: Vec<u32>,
    pub dt: f64,
    /// Time at the end of the step.
    pub time: f64,
}

impl Solver {
    /// Sets particle `p`'s J (F scaled isotropically, V = J V0): a defect
    /// planted between steps, for the mechanisms' test scenes. Its stress
    /// follows at its next stress update.
    pub fn plant_j(&mut self, p: usize, j: f64) {
        let factor = j / self.particles.j[p];
        self.particles.scale_j(p, factor);
    }

    /// Moves particle `p` to `x` with velocity `v` between steps (the next
    /// step's sort finds its new stencil).
    pub fn plant_motion(&mut self, p: usize, x: Vec2, v: Vec2) {
        self.particles.x[p] = x;
        self.particles.v[p] = v;
        self.refresh_signal_speed();
    }

    /// Takes one step as `step()` does, explaining the velocity change of
    /// `particles` (indices). Single-phase only.
    pub fn step_explained(&mut self, particles: &[usize]) -> Result<ExplainedStep, StepError> {
        let dt = self.step_dt();
        self.begin_step(dt)?;
        let ps = &self.particles;
        let v_old: Vec<Vec2> = particles.iter().map(|&p| ps.v[p]).collect();
        let ids: Vec<u32> = particles.iter().map(|&p| ps.id[p]).collect();
        let mut step = ExplainedStep {
            x: ps.x.clone(),
            pressure: ps.pressure.clone(),
            j: ps.j.clone(),
            volume: ps.vol.clone(),
            volume0: ps.vol0.clone(),
            id: ps.id.clone(),
            dt,
            ..ExplainedStep::default()
        };
        let mut explained = with_width!(self.shape, W => self.explain_nodes::<W>(particles));
        self.finish_step();
        let xpic = self.cfg.method.transfer == TransferKind::Xpic;
        let deleted = self.particles.len() != step.x.len();
        for ((e, v0), id) in explained.iter_mut().zip(v_old).zip(ids) {
            if xpic {
                let star = self.xpic.v_star();
                for n in &mut e.nodes {
                    n.jump = n.weight * (star[n.node as usize] - v0);
                }
            }
            e.v_before = v0;
            // A deletion in the step shifts the indices after it.
            let now = if deleted {
                self.particles.id.iter().position(|&i| i == id)
            } else {
                Some(e.particle)
            };
            let Some(now) = now else {
                e.dv = Vec2::repeat(f64::NAN);
                e.rest = e.dv;
                continue;
            };
            e.impulse = self.impulse_on(now);
            e.dv = self.particles.v[now] - v0;
            e.rest = e.dv - e.parts_sum();
        }
        step.explained = explained;
        step.time = self.time;
        Ok(step)
    }

    /// The `[[perturb]]` impulse of the step just taken on particle `p`
    /// (as `apply_perturbations` chose it: by its position after G2P).
    fn impulse_on(&self, p: usize) -> Vec2 {
        let x = self.particles.x[p];
        let id = self.particles.id[p];
        let impulses: Vec2 = self
            .planted
            .iter()
            .filter(|pl| pl.step == self.step && pl.duration == 0.0)
            .filter(|pl| crate::perturb::covers(pl.region, x))
            .map(|pl| Vec2::from(pl.dv))
            .sum();
        let sustained: Vec2 = self
            .sustained
            .iter()
            .filter(|s| s.last_step == self.step && s.holds(id))
            .map(|s| s.last_dv)
            .sum();
        impulses + sustained
    }

    fn explain_nodes<const W: usize>(&self, particles: &[usize]) -> Vec<Explained> {
        let (grid, ps, dt) = (&self.grid, &self.particles, self.dt);
        let g = self.gravity;
        let implicit = self.implicit();
        let full = self.cfg.first_rho0() * grid.h * grid.h;
        let alpha = match self.cfg.method.transfer {
            TransferKind::Flip => self.remedies.flip_fraction(dt, self.cfg.method.flip_alpha),
            TransferKind::Xpic => 1.0,
            TransferKind::Pic | TransferKind::Apic => 0.0,
        };
        // Which explained particle's node slots each padded node feeds.
        let mut feeds: HashMap<u32, Vec<(usize, usize)>> = HashMap::new();
        let mut out: Vec<Explained> = Vec::with_capacity(particles.len());
        for (k, &p) in particles.iter().enumerate() {
            let st = &self.stencils[p];
            let weights = stencil_nodes::<W>(&self.shape, st, grid);
            let vp = ps.v[p];
            let mut nodes = Vec::with_capacity(W * W);
            for (slot, &(node, w, _, _)) in weights.iter().enumerate() {
                let n = node as usize;
                let m = grid.mass[n];
                let dv_node = grid.vel_new[n] - grid.vel[n];
                let changes = if implicit && m > 0.0 {
                    self.projection.node_changes(grid, dt, n)
                } else {
                    [Vec2::zeros(); 3]
                };
                let [hourglass, pressure_correction, extrapolation] = changes.map(|c| w * c);
                let projected = hourglass + pressure_correction + extrapolation;
                let (internal, external, walls) = if m > 0.0 {
                    let by_force = dt * grid.force[n] / m;
                    (
                        w * (by_force - dt * g),
                        w * dt * g,
                        w * (dv_node - by_force) - projected,
                    )
                } else {
                    (Vec2::zeros(), Vec2::zeros(), w * dv_node)
                };
                nodes.push(NodePart {
                    node,
                    position: grid.position(n),
                    weight: w,
                    mass: m,
                    mass_share: m / full,
                    // With the pressure's (the momentum its correction gave the node).
                    force: grid.force[n] + m * changes[1] / dt,
                    dv_node,
                    internal,
                    external,
                    walls,
                    hourglass,
                    pressure_correction,
                    extrapolation,
                    jump: (1.0 - alpha) * w * (grid.vel[n] - vp),
                    flip_increment: w * dv_node,
                    interpolated: w * grid.vel[n],
                });
                feeds.entry(node).or_default().push((k, slot));
            }
            out.push(Explained {
                particle: p,
                nodes,
                ..Explained::default()
            });
        }
        self.attribute_stresses::<W>(&feeds, &mut out);
        out
    }

    /// Splits the nodes' internal force among the particles whose stress
    /// made it (gradient force, particle quadrature; otherwise all of it is
    /// unattributed).
    fn attribute_stresses<const W: usize>(
        &self,
        feeds: &HashMap<u32, Vec<(usize, usize)>>,
        out: &mut [Explained],
    ) {
        let (grid, ps, dt) = (&self.grid, &self.particles, self.dt);
        let mls = match self.cfg.method.force {
            ForceKind::Mls => self.shape.apic_inverse_inertia(),
            ForceKind::Gradient => None,
        };
        let particle_forces = self.cfg.method.quadrature != QuadratureKind::Mixed;
        let mut attributed = vec![Vec2::zeros(); out.len()];
        if particle_forces {
            let mut parts: Vec<HashMap<usize, StressPart>> = vec![HashMap::new(); out.len()];
            for q in 0..ps.len() {
                let st = &self.stencils[q];
                let grads = node_force_gradients::<W>(&self.shape, st, grid, mls);
                let vol = ps.vol[q];
                let pressure = -ps.pressure[q] * Mat2::identity();
                let deviatoric = ps.stress[q] - pressure;
                for &(node, grad) in &grads {
                    let Some(slots) = feeds.get(&node) else {
                        continue;
                    };
                    let m = grid.mass[node as usize];
                    if m <= 0.0 {
                        continue;
                    }
                    // f_iq = -V sigma grad N (grad in 1/m), split by stress part.
                    let f_p = -vol * (pressure * grad);
                    let f_d = -vol * (deviatoric * grad);
                    for &(k, slot) in slots {
                        let w = out[k].nodes[slot].weight * dt / m;
                        let e = parts[k].entry(q).or_insert(StressPart {
                            particle: q,
                            ..StressPart::default()
                        });
                        e.pressure += w * f_p;
                        e.deviatoric += w * f_d;
                        attributed[k] += w * (f_p + f_d);
                    }
                }
            }
            for (e, p) in out.iter_mut().zip(parts) {
                let mut list: Vec<StressPart> = p.into_values().collect();
                list.sort_by_key(|s| s.particle);
                e.stresses = list;
            }
        }
        for (e, a) in out.iter_mut().zip(attributed) {
            e.internal_unattributed = e.internal() - a;
        }
    }
}

/// (node, N_ip, grad N_ip, (x_i - x_p) / h) over a particle's stencil.
fn stencil_nodes<const W: usize>(
    shape: &Shape,
    st: &Stencil,
    grid: &Grid,
) -> Vec<(u32, f64, Vec2, Vec2)> {
    let (inv_h, nx) = (1.0 / grid.h, grid.dims[0]);
    let mut out = Vec::with_capacity(W * W);
    // CPDI: one slot per corner's node, a node possibly in several.
    shape.each_piece::<W>(st, nx, |p| {
        p.each_node(nx, |node, [a, c], w, [gx, gy]| {
            let offset = Vec2::new(a as f64 - p.frac[0], c as f64 - p.frac[1]);
            out.push((node as u32, w, Vec2::new(gx, gy) * inv_h, offset));
        })
    });
    out
}

/// (node, g) with f_iq = -V_q sigma_q g: grad N_iq for the gradient force,
/// MLS's D^-1 (x_i - x_q) N_iq for the MLS force.
fn node_force_gradients<const W: usize>(
    shape: &Shape,
    st: &Stencil,
    grid: &Grid,
    mls: Option<f64>,
) -> Vec<(u32, Vec2)> {
    let inv_h = 1.0 / grid.h;
    stencil_nodes::<W>(shape, st, grid)
        .into_iter()
        .map(|(node, w, grad, offset)| match mls {
            Some(inertia) => (node, w * inertia * inv_h * offset),
            None => (node, grad),
        })
        .collect()
}
