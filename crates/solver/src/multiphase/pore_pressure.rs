//! Pore pressure (docs/physics.md section 6): with it on, the fluid's
//! pressure lives on the grid and follows the volume balance of each node.
//! Grains are incompressible: the solid's particles carry grain volume
//! V_p^0 (their reference volume n_s V_mix). The water's reference volume
//! is the fluid particles' V_p^0. At a node of capacity V_cap = h^2 (walls
//! and periodic edges folded, so every node looks interior) the water
//! fills the room the grains leave, and its volume ratio
//!
//!   J_i = (V_cap - V_i^grains) / V_i^water0
//!
//! gives p_i = max(0, EOS_fluid(J_i)): compressed where more water sits in
//! a node than the grains leave room for, zero at a free surface or where
//! the water is short (pore water holds no tension). Its gradient acts on
//! each particle of both phases by its reference volume, f_p = -V_p^0 grad p
//! (the fluid n grad p, the grains (1 - n) grad p: buoyancy and the
//! effective-stress split in one), spread by N_ip and added to v^{n+1} over
//! the step like the drag. The fluid's own EOS pressure is off (its
//! viscous stress stays); its particles show the grid pressure.
//!
//! Undrained compression of both phases by a volumetric strain e gives
//! p = K_f e / n; so p0 = q / (1 + n M / K_f) under a step load q on a
//! skeleton of constrained modulus M, as in Terzaghi's problem.

// The loops walk the weights and the stencil rows in step.
#![allow(clippy::needless_range_loop)]

use crate::config::Material;
use crate::grid::{Grid, PAD};
use crate::multiphase::boundary_inflow::{add_point, Inflow};
use crate::particles::Vec2;
use crate::Solver;

/// What the nodal pressure stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PoreMode {
    /// The fluid's whole pressure, from each node's volume balance.
    Balance,
    /// The volume constraint n_s + n_f <= 1 only: where a node's grains
    /// (reference volumes) and water (current volumes) overfill it, p_i =
    /// K_f ((V_i^grains + V_i^water) / V_cap - 1), else 0; only at nodes the
    /// grains reach. The fluid keeps its own EOS pressure beside it.
    Constraint,
}

/// Grid arrays of the pore pressure (allocated once) and the pore fluid's EOS.
#[derive(Clone, Debug)]
pub struct PorePressure {
    pub(crate) fluid: Material,
    pub(crate) mode: PoreMode,
    /// The scene's gravity (m/s^2, in -y).
    gravity: f64,
    pressure: Vec<f64>,
    grains: Vec<f64>,
    water: Vec<f64>,
    force: Vec<Vec2>,
    /// Drained walls [axis][low, high]: the pore pressure prescribed there.
    pub(crate) drained: [[Option<f64>; 2]; 2],
    /// Per lattice column along a drained wall: its outermost particles.
    tops: Vec<ColumnTop>,
    /// Per drained wall [axis][side], per node along it: how far in from
    /// the wall the skeleton's surface lies (0 against it).
    gaps: [[Vec<f64>; 2]; 2],
    /// Node-averaged pressure (`Mixture::with_pore_node_average`): each node's pressure
    /// the [1 2 1] / 4 average along each axis, which removes the
    /// node-to-node mode the particles' gradients hardly see.
    pub(crate) node_average: bool,
    scratch: Vec<f64>,
}

impl PorePressure {
    pub fn new(grid: &Grid, fluid: Material, mode: PoreMode, gravity: f64) -> Self {
        let n = grid.dims[0] * grid.dims[1];
        PorePressure {
            fluid,
            mode,
            gravity,
            pressure: vec![0.0; n],
            grains: vec![0.0; n],
            water: vec![0.0; n],
            force: vec![Vec2::zeros(); n],
            drained: [[None; 2]; 2],
            tops: Vec::with_capacity(grid.dims[0].max(grid.dims[1]) * 4),
            gaps: std::array::from_fn(|axis| {
                std::array::from_fn(|_| vec![0.0; grid.dims[1 - axis]])
            }),
            node_average: false,
            scratch: vec![0.0; n],
        }
    }

    /// The prescribed pressure at each drained wall, imposed at the
    /// skeleton's surface where it has settled in from the wall (see
    /// `drained_image`), and beyond it the odd image about it.
    fn impose_drained(&mut self, g: &Grid) {
        for axis in 0..2 {
            for side in 0..2 {
                self.image_drained_wall(g, axis, side);
            }
        }
    }

    /// A drained wall's condition (`drained_image`); false on any other wall.
    fn image_drained_wall(&mut self, g: &Grid, axis: usize, side: usize) -> bool {
        let Some(p_wall) = self.drained[axis][side] else {
            return false;
        };
        let rise = self.hydrostatic_rise(axis, side);
        drained_image(
            &mut self.pressure,
            g,
            axis,
            side,
            p_wall,
            rise,
            &self.gaps[axis][side],
        );
        true
    }

    /// The pressure gained per metre in from a drained wall through the
    /// free water between it and the skeleton (gravity acts in -y).
    fn hydrostatic_rise(&self, axis: usize, side: usize) -> f64 {
        if axis == 1 {
            let out_sign = if side == 1 { 1.0 } else { -1.0 };
            out_sign * self.fluid.rho0 * self.gravity
        } else {
            0.0
        }
    }

    /// Per drained wall and node along it, the gap between the wall and
    /// the skeleton's surface (the plane l/2 beyond each lattice column's
    /// outermost grain particle, interpolated between the columns' centres;
    /// 0 where a column holds no grains).
    fn find_gaps(&mut self, solid: &Solver) {
        let g = solid.grid();
        for axis in 0..2 {
            for side in 0..2 {
                if self.drained[axis][side].is_none() {
                    continue;
                }
                let w = DrainedWall::of(solid, axis, side);
                w.find_tops(solid, axis, &mut self.tops);
                let n = self.tops.len() as i64;
                // Deep enough that the images stay on the grid.
                let deepest = 0.5 * (g.cells[axis] as f64 - PAD as f64 - 2.0) * g.h;
                let gap_of = |c: i64| {
                    let c = if g.periodic[w.along] {
                        c.rem_euclid(n)
                    } else {
                        c.clamp(0, n - 1)
                    };
                    let top = self.tops[c as usize];
                    if top.index == usize::MAX {
                        0.0
                    } else {
                        (w.wall - top.first - 0.5 * w.l).clamp(0.0, deepest)
                    }
                };
                let origin = solid.scene().origin[w.along];
                for (k, slot) in self.gaps[axis][side].iter_mut().enumerate() {
                    let x = g.origin[w.along] + (k as f64 - PAD as f64) * g.h;
                    let u = (x - origin) / w.l - 0.5;
                    let c = u.floor();
                    let t = u - c;
                    let (a, b) = (gap_of(c as i64), gap_of(c as i64 + 1));
                    let gap = a + t * (b - a);
                    // Seeded against the wall, round-off is no gap.
                    *slot = if gap > 1e-9 * g.h { gap } else { 0.0 };
                }
            }
        }
    }

    /// The nodal pressure of the phases' current stencils (ghosts filled).
    /// Tension only where the node is saturated (grains and water fill at
    /// least 0.9 of its support): at a free surface, or where the water is
    /// short or spread thin, the pressure is cut at zero; inside, a wave's
    /// tension is kept, so that the water does not cavitate and open a
    /// drained gap inside a saturated body.
    fn nodal_pressure(&mut self, solid: &Solver, fluid: &Solver, inflow: Option<&Inflow>) {
        let g = fluid.grid();
        let capacity = g.h * g.h;
        if self.mode == PoreMode::Constraint {
            reference_volume(solid, &mut self.grains);
            self.water.fill(0.0);
            crate::multiphase::drag::scatter_folded(&fluid.particles().vol, fluid, &mut self.water);
            let k = self.fluid.k;
            for n in 0..self.pressure.len() {
                let (grains, water) = (self.grains[n], self.water[n]);
                let over = (grains + water) / capacity - 1.0;
                self.pressure[n] = if grains > 0.0 && water > 0.0 && g.is_active(n) {
                    k * over.max(0.0)
                } else {
                    0.0
                };
            }
            g.fill(&mut self.pressure);
            return;
        }
        self.water.fill(0.0);
        crate::multiphase::drag::scatter_raw(&fluid.particles().vol0, fluid, &mut self.water);
        if let Some(inflow) = inflow {
            inflow.add_outside_rows(fluid, &mut self.water);
        }
        add_outer_images(fluid, self.drained, &mut self.tops, &mut self.water);
        g.fold(&mut self.water);
        self.grains.fill(0.0);
        crate::multiphase::drag::scatter_raw(&solid.particles().vol0, solid, &mut self.grains);
        add_outer_images(solid, self.drained, &mut self.tops, &mut self.grains);
        solid.grid().fold(&mut self.grains);
        self.find_gaps(solid);
        for n in 0..self.pressure.len() {
            let w = self.water[n];
            self.pressure[n] = if w > 0.0 && g.is_active(n) {
                let j = (capacity - self.grains[n]) / w;
                let p = self.fluid.pressure(j);
                if self.grains[n] + w >= 0.9 * capacity {
                    p
                } else {
                    p.max(0.0)
                }
            } else {
                0.0
            };
        }
        g.fill(&mut self.pressure);
        if self.node_average {
            self.average_nodes(g);
            g.fill(&mut self.pressure);
        }
        self.impose_drained(g);
        if let Some(inflow) = inflow {
            // Beyond an inflow wall: the odd image about the wall row's own
            // pressure, which carries the gradient through the wall.
            for (axis, sides) in inflow.mask().iter().enumerate() {
                for side in (0..2).filter(|&side| sides[side]) {
                    odd_image(&mut self.pressure, g, axis, side, None);
                }
            }
        }
    }

    /// Each wet node's pressure becomes the [1 2 1] / 4 average of its
    /// neighbours along x, then along y (linear fields kept, the
    /// node-to-node mode removed). Beyond a wall the odd image about the
    /// wall row (prescribed on a drained wall), so that the walls' values
    /// and slopes stay; dry nodes keep zero.
    fn average_nodes(&mut self, g: &Grid) {
        for axis in (0..2).filter(|&a| !g.periodic[a]) {
            for side in 0..2 {
                if !self.image_drained_wall(g, axis, side) {
                    odd_image(&mut self.pressure, g, axis, side, None);
                }
            }
        }
        let [nx, ny] = g.dims;
        let (p, tmp) = (&mut self.pressure, &mut self.scratch);
        tmp.copy_from_slice(p);
        for j in 0..ny {
            for i in 1..nx - 1 {
                let n = g.index(i, j);
                tmp[n] = 0.25 * (p[n - 1] + 2.0 * p[n] + p[n + 1]);
            }
        }
        for j in 1..ny - 1 {
            for i in 0..nx {
                let n = g.index(i, j);
                p[n] = if self.water[n] > 0.0 && g.is_active(n) {
                    0.25 * (tmp[n - nx] + 2.0 * tmp[n] + tmp[n + nx])
                } else {
                    0.0
                };
            }
        }
    }

    /// Adds each phase's pore-pressure force over `dt` to its v^{n+1} (phase
    /// a held when `fixed_a`; the rows still outside an inflow wall counted
    /// in the balance); returns the kinetic energy each phase gained.
    pub(crate) fn apply(
        &mut self,
        a: &mut Solver,
        b: &mut Solver,
        dt: f64,
        fixed_a: bool,
        inflow: Option<&Inflow>,
    ) -> [f64; 2] {
        self.nodal_pressure(a, b, inflow);
        let mut gained = [0.0; 2];
        for (k, s) in [a, b].into_iter().enumerate() {
            if k == 0 && fixed_a {
                continue;
            }
            let before = crate::multiphase::drag::grid_kinetic(s.grid());
            gradient_force(s, &self.pressure, &mut self.force);
            add_force(s.grid_mut(), &self.force, dt);
            gained[k] = crate::multiphase::drag::grid_kinetic(s.grid()) - before;
        }
        gained
    }

    /// Outflow through a drained wall, gradual (each phase, each step
    /// before P2G): over its last l/2 before the wall, a column's outermost
    /// particle gives its mass and volumes away, keeping 1 - theta of the
    /// share the next particle of its column has (as in the balance's
    /// sums). Deleted whole as it crossed, it took its mass off the nodes
    /// beside the wall at once: their drag per unit mass jumped by half and
    /// sent the column a wave (+1.6 % of p0 at the top of Terzaghi's
    /// column at each row's departure). What it gives away is counted as
    /// drained, and its kinetic and stored energy leave with it.
    pub(crate) fn drain_outflow(&mut self, s: &mut Solver) {
        for axis in 0..2 {
            for side in 0..2 {
                if self.drained[axis][side].is_none() {
                    continue;
                }
                let w = DrainedWall::of(s, axis, side);
                w.find_tops(s, axis, &mut self.tops);
                for top in self.tops.iter().filter(|t| t.drains()) {
                    let keep = 1.0 - top.theta(w.wall, w.l);
                    let (p, full) = (top.index, top.second_index);
                    let ps = s.particles();
                    let (mass, vol0) = (keep * ps.mass[full], keep * ps.vol0[full]);
                    if mass == ps.mass[p] && vol0 == ps.vol0[p] {
                        continue;
                    }
                    s.drain_particle(p, mass, vol0);
                }
            }
        }
    }

    /// Each fluid particle's pressure set to the grid pressure (of the
    /// step's start) at its current position, so that views and files show
    /// it (the balance only: under the constraint the particles keep their own).
    pub(crate) fn show_on(&self, fluid: &mut Solver) {
        if self.mode == PoreMode::Constraint {
            return;
        }
        crate::shapes::with_width!(fluid.shape(), W => interpolate::<W>(&self.pressure, fluid))
    }
}

/// The two outermost particles of a lattice column along a drained wall
/// (distances measured outward) and their indices.
#[derive(Clone, Copy, Debug)]
struct ColumnTop {
    first: f64,
    second: f64,
    index: usize,
    second_index: usize,
}

impl ColumnTop {
    const EMPTY: ColumnTop = ColumnTop {
        first: f64::NEG_INFINITY,
        second: f64::NEG_INFINITY,
        index: usize::MAX,
        second_index: usize::MAX,
    };

    fn push(&mut self, at: f64, index: usize) {
        if at > self.first {
            self.second = self.first;
            self.second_index = self.index;
            self.first = at;
            self.index = index;
        } else if at > self.second {
            self.second = at;
            self.second_index = index;
        }
    }

    /// The outermost particle's progress over its last l/2 before the
    /// wall: 0 at l/2 from it, 1 on it.
    fn theta(&self, wall: f64, l: f64) -> f64 {
        ((self.first - (wall - 0.5 * l)) / (0.5 * l)).clamp(0.0, 1.0)
    }

    /// Whether the outermost particle drains (a second one in its column
    /// gives its full share).
    fn drains(&self) -> bool {
        self.second_index != usize::MAX
    }
}

/// A drained wall's geometry for a phase: the lattice spacing l, the
/// axis along the wall, the outward sign and the wall's outward distance.
struct DrainedWall {
    l: f64,
    along: usize,
    columns: usize,
    out_sign: f64,
    wall: f64,
}

impl DrainedWall {
    fn of(s: &Solver, axis: usize, side: usize) -> Self {
        let scene = s.scene();
        let l = s.grid().h / scene.ppc as f64;
        let along = 1 - axis;
        let out_sign = if side == 1 { 1.0 } else { -1.0 };
        DrainedWall {
            l,
            along,
            columns: (scene.size[along] / l).round() as usize,
            out_sign,
            wall: out_sign * (scene.origin[axis] + side as f64 * scene.size[axis]),
        }
    }

    fn column(&self, s: &Solver, x: &Vec2) -> usize {
        let origin = s.scene().origin[self.along];
        (((x[self.along] - origin) / self.l).floor().max(0.0) as usize).min(self.columns - 1)
    }

    /// Each lattice column's two outermost particles into `tops`.
    fn find_tops(&self, s: &Solver, axis: usize, tops: &mut Vec<ColumnTop>) {
        tops.clear();
        tops.resize(self.columns, ColumnTop::EMPTY);
        for (p, x) in s.particles().x.iter().enumerate() {
            tops[self.column(s, x)].push(self.out_sign * x[axis], p);
        }
    }
}

/// Each phase's images beyond each drained wall, added to its raw nodal
/// sums `out`: each lattice column (particles one spacing l apart along the
/// wall) is mirrored about the plane l/2 beyond its outermost particle,
/// which continues its rows past the wall. At rest that plane is the wall;
/// while water flows out or the skeleton settles it moves with the rows, so
/// that the nodes beside the wall read as full of both phases (a mirror
/// about the wall itself opens a gap of up to 2 l there for the water, and
/// of twice the settlement for the grains).
///
/// Outflow: a particle leaves the sums when it crosses the wall, and the
/// next one's plane then takes over. Over the outermost particle's last
/// l/2 before the wall, both planes blend (weight theta of the next one,
/// 0 at l/2 from the wall, 1 at the wall; the outermost particle itself
/// keeps 1 - theta of its volume, `drain_outflow`), so the sums do not
/// jump when it leaves: a jump of a tenth of a particle's volume is 10 kPa
/// in water.
fn add_outer_images(
    s: &Solver,
    drained: [[Option<f64>; 2]; 2],
    tops: &mut Vec<ColumnTop>,
    out: &mut [f64],
) {
    let g = s.grid();
    let reach = PAD as f64 * g.h + g.h / s.scene().ppc as f64;
    let ps = s.particles();
    let half = s.shape().half_widths(&crate::particles::Mat2::identity());
    let add = |x: Vec2, q: f64, out: &mut [f64]| crate::shapes::with_width!(s.shape(), W => add_point::<W>(g, s.shape(), half, x, q, out));
    for axis in 0..2 {
        for side in 0..2 {
            if drained[axis][side].is_none() {
                continue;
            }
            let w = DrainedWall::of(s, axis, side);
            w.find_tops(s, axis, tops);
            for (p, (x, &v0)) in ps.x.iter().zip(&ps.vol0).enumerate() {
                let top = tops[w.column(s, x)];
                let at = w.out_sign * x[axis];
                let theta = top.theta(w.wall, w.l);
                let mirror = |plane: f64, weight: f64, v0: f64, out: &mut [f64]| {
                    // Measured from the plane, not the wall: a settling
                    // skeleton's rows then enter the images only where
                    // their image stays beyond the wall's reach.
                    if plane - at <= reach {
                        let mut image = *x;
                        image[axis] = w.out_sign * (2.0 * plane - at);
                        add(image, weight * v0, out);
                    }
                };
                let outermost = p == top.index;
                if theta < 1.0 {
                    // A draining particle's own volume is already down to
                    // 1 - theta of its share; its image takes the full one.
                    let v0 = if outermost && top.drains() {
                        ps.vol0[top.second_index]
                    } else {
                        v0
                    };
                    mirror(top.first + 0.5 * w.l, 1.0 - theta, v0, out);
                }
                if theta > 0.0 {
                    if !outermost {
                        mirror(top.second + 0.5 * w.l, theta, v0, out);
                    } else if !top.drains() {
                        add(*x, -theta * v0, out);
                    }
                }
            }
        }
    }
}

/// A drained wall's condition, imposed where the water meets the skeleton.
/// A skeleton that settles away from a drained wall (Terzaghi's column
/// under its load) leaves free water between them, in which the pressure
/// hardly changes; held at the wall instead, the pressure fell across that
/// gap through the grains' drag on the grid, the skeleton's surface stayed
/// above the prescribed value, and the column carried it on top of its
/// load (+2 % of p0 under Terzaghi's ramp). So along each node column the
/// pressure at the surface, `gap` in from the wall row, is the wall's plus
/// the free water's hydrostatic `rise` per metre, and every node at or
/// beyond it takes the odd image about it of the field inside (piecewise
/// linear through the inner nodes and the surface value). Against the wall
/// (gap 0) this is the wall row's value and the odd image about it.
fn drained_image(
    pressure: &mut [f64],
    g: &Grid,
    axis: usize,
    side: usize,
    p_wall: f64,
    rise: f64,
    gaps: &[f64],
) {
    let out: i64 = if side == 1 { 1 } else { -1 };
    let wall = (PAD + side * g.cells[axis]) as i64;
    for (k, (wall_node, pairs)) in wall_rows(g, axis, side).enumerate() {
        let gap = gaps[k];
        if gap == 0.0 {
            pressure[wall_node] = p_wall;
            for (ghost, partner) in pairs {
                pressure[ghost] = 2.0 * p_wall - pressure[partner];
            }
            continue;
        }
        // Node m steps outward from the wall row (m <= 0 inside).
        let node = |m: i64| {
            let i = (wall + out * m) as usize;
            if axis == 0 {
                g.index(i, k)
            } else {
                g.index(k, i)
            }
        };
        let p_surface = p_wall + rise * gap;
        let s = -gap / g.h;
        let m0 = s.ceil() as i64 - 1;
        let p_m0 = pressure[node(m0)];
        let inside = |y: f64, pressure: &[f64]| {
            if y >= m0 as f64 {
                p_m0 + (y - m0 as f64) / (s - m0 as f64) * (p_surface - p_m0)
            } else {
                let j = y.floor();
                let (a, b) = (pressure[node(j as i64)], pressure[node(j as i64 + 1)]);
                a + (y - j) * (b - a)
            }
        };
        for m in m0 + 1..=PAD as i64 {
            let mirrored = inside(2.0 * s - m as f64, pressure);
            pressure[node(m)] = 2.0 * p_surface - mirrored;
        }
    }
}

/// Beyond the wall normal to `axis` on `side`, each node takes the odd
/// image 2 p_wall - p_partner about its wall node, whose pressure is set to
/// `wall_value` when given (a drained wall) or kept (an inflow wall).
fn odd_image(pressure: &mut [f64], g: &Grid, axis: usize, side: usize, wall_value: Option<f64>) {
    for (wall, pairs) in wall_rows(g, axis, side) {
        if let Some(p) = wall_value {
            pressure[wall] = p;
        }
        let p_wall = pressure[wall];
        for (ghost, partner) in pairs {
            pressure[ghost] = 2.0 * p_wall - pressure[partner];
        }
    }
}

/// Every node of the wall row normal to `axis` on `side` (0 low, 1 high),
/// with its (ghost, partner) pairs outward: the nodes d beyond the wall and
/// d inside it, d = 1..PAD.
fn wall_rows(
    g: &Grid,
    axis: usize,
    side: usize,
) -> impl Iterator<Item = (usize, [(usize, usize); PAD])> + '_ {
    let wall = (PAD + side * g.cells[axis]) as i64;
    let out = if side == 1 { 1 } else { -1 };
    (0..g.dims[1 - axis]).map(move |k| {
        let at = |i: i64| {
            if axis == 0 {
                g.index(i as usize, k)
            } else {
                g.index(k, i as usize)
            }
        };
        let pairs = std::array::from_fn(|d| {
            let d = d as i64 + 1;
            (at(wall + out * d), at(wall - out * d))
        });
        (at(wall), pairs)
    })
}

/// sum_p N_ip V_p^0 on the raw nodes, folded.
/// Zeroed whole first: the pressure reads the grains' sums at the fluid's
/// nodes, which the solid's active set need not cover.
fn reference_volume(s: &Solver, out: &mut [f64]) {
    out.fill(0.0);
    crate::multiphase::drag::scatter_folded(&s.particles().vol0, s, out);
}

fn interpolate<const W: usize>(field: &[f64], s: &mut Solver) {
    let (g, ps, _, shape) = s.grid_and_particles();
    let (inv_h, pad, nx) = (1.0 / g.h, crate::grid::PAD as i64, g.dims[0] as i64);
    for p in 0..ps.len() {
        let r = (ps.x[p] - g.origin) * inv_h;
        let (bx, fx) = shape.locate(r.x);
        let (by, fy) = shape.locate(r.y);
        let (i, j) = (bx.saturating_add(pad), by.saturating_add(pad));
        let w = W as i64;
        if !(i >= 0 && j >= 0 && i + w <= nx && j + w <= g.dims[1] as i64) {
            continue;
        }
        let half = shape.half_widths(&ps.f[p]);
        let (wx, _) = shape.stencil_weights::<W>(fx, half[0]);
        let (wy, _) = shape.stencil_weights::<W>(fy, half[1]);
        let mut sum = 0.0;
        for c in 0..W {
            let row = (i + (j + c as i64) * nx) as usize;
            for a in 0..W {
                sum += wx[a] * wy[c] * field[row + a];
            }
        }
        ps.pressure[p] = sum;
    }
}

/// f_i = -sum_p N_ip V_p^0 grad p(x_p) on the raw nodes, folded.
fn gradient_force(s: &Solver, pressure: &[f64], force: &mut [Vec2]) {
    crate::shapes::with_width!(s.shape(), W => spread::<W>(s, pressure, force));
    s.grid().fold(force);
}

fn spread<const W: usize>(s: &Solver, pressure: &[f64], force: &mut [Vec2]) {
    let g = s.grid();
    let (nx, inv_h) = (g.dims[0], 1.0 / g.h);
    for &n in &g.active {
        force[n as usize] = Vec2::zeros();
    }
    for (p, st) in s.stencils().iter().enumerate() {
        let (wx, dwx) = s.shape().stencil_weights::<W>(st.frac[0], st.half[0]);
        let (wy, dwy) = s.shape().stencil_weights::<W>(st.frac[1], st.half[1]);
        let mut sum = Vec2::zeros();
        for c in 0..W {
            let row = st.node as usize + c * nx;
            for a in 0..W {
                let q = pressure[row + a];
                sum += Vec2::new(dwx[a] * wy[c], wx[a] * dwy[c]) * (q * inv_h);
            }
        }
        let f = -s.particles().vol0[p] * sum;
        for c in 0..W {
            let row = st.node as usize + c * nx;
            for a in 0..W {
                force[row + a] += (wx[a] * wy[c]) * f;
            }
        }
    }
}

/// v^{n+1} += dt f / m and a += f / m on the inside nodes with mass; ghosts refilled.
pub(crate) fn add_force(g: &mut Grid, force: &[Vec2], dt: f64) {
    for &n in &g.inside {
        let n = n as usize;
        let m = g.mass[n];
        if m > 0.0 {
            let a = force[n] / m;
            g.vel_new[n] += dt * a;
            g.accel[n] += a;
        }
    }
    crate::multiphase::drag::refill(g);
}

/// A uniform traction q (Pa, downward) on the top surface of the solid: the
/// solid particles seeded in its top row carry it, each over its lattice
/// spacing l = h / ppc, ramped from 0 over `ramp` seconds as q (1 - cos(pi
/// t / ramp)) / 2 (a step load, or a linear ramp's kinks, ring the column
/// with waves for a long time).
#[derive(Clone, Debug)]
pub struct TopLoad {
    pub traction: f64,
    pub ramp: f64,
    /// By particle id: in the top row at t = 0.
    loaded: Vec<bool>,
    force: Vec<Vec2>,
}

impl TopLoad {
    pub fn new(solid: &Solver, traction: f64, ramp: f64) -> Self {
        let ps = solid.particles();
        let l = solid.grid().h / solid.scene().ppc as f64;
        let top = ps.x.iter().map(|x| x.y).fold(f64::NEG_INFINITY, f64::max);
        let ids = ps.id.iter().map(|&i| i as usize + 1).max().unwrap_or(0);
        let mut loaded = vec![false; ids];
        for (x, &id) in ps.x.iter().zip(&ps.id) {
            loaded[id as usize] = x.y > top - 0.5 * l;
        }
        TopLoad {
            traction,
            ramp,
            loaded,
            force: vec![Vec2::zeros(); solid.grid().dims[0] * solid.grid().dims[1]],
        }
    }

    /// The traction at time t.
    pub fn at(&self, t: f64) -> f64 {
        self.traction * ramp_share(t, self.ramp)
    }

    /// Adds the load of time `t` over `dt` to the solid's v^{n+1}; returns
    /// the kinetic energy it gave.
    pub(crate) fn apply(&mut self, s: &mut Solver, t: f64, dt: f64) -> f64 {
        let before = crate::multiphase::drag::grid_kinetic(s.grid());
        let per_particle = Vec2::new(0.0, -self.at(t) * s.grid().h / s.scene().ppc as f64);
        crate::shapes::with_width!(s.shape(), W => self.spread::<W>(s, per_particle));
        s.grid().fold(&mut self.force);
        add_force(s.grid_mut(), &self.force, dt);
        crate::multiphase::drag::grid_kinetic(s.grid()) - before
    }

    fn spread<const W: usize>(&mut self, s: &Solver, f: Vec2) {
        let nx = s.grid().dims[0];
        for &n in &s.grid().active {
            self.force[n as usize] = Vec2::zeros();
        }
        for (p, st) in s.stencils().iter().enumerate() {
            if !self
                .loaded
                .get(s.particles().id[p] as usize)
                .copied()
                .unwrap_or(false)
            {
                continue;
            }
            let (wx, _) = s.shape().stencil_weights::<W>(st.frac[0], st.half[0]);
            let (wy, _) = s.shape().stencil_weights::<W>(st.frac[1], st.half[1]);
            for c in 0..W {
                let row = st.node as usize + c * nx;
                for a in 0..W {
                    self.force[row + a] += (wx[a] * wy[c]) * f;
                }
            }
        }
    }
}

/// The share of a load ramped over `ramp` seconds applied at t: (1 -
/// cos(pi t / ramp)) / 2 until `ramp`, then 1 (a step when ramp = 0).
pub fn ramp_share(t: f64, ramp: f64) -> f64 {
    if ramp > 0.0 && t < ramp {
        0.5 * (1.0 - (std::f64::consts::PI * t.max(0.0) / ramp).cos())
    } else if t >= 0.0 {
        1.0
    } else {
        0.0
    }
}
