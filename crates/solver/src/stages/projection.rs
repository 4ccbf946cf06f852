//! The pressure-implicit step (`method.formulation = "pressure_implicit"`,
//! docs/physics.md section 8): one fluid's pressure lives on the cells the
//! particles fill and is solved each step, so that the time step follows
//! the flow and not the sound.
//!
//! With D the bilinear element's divergence at the cell centre, G = h^2 D^T
//! the nodal force of a cell pressure (folded like every nodal force: a
//! wall keeps the tangential part of its image, a periodic edge wraps) and
//! M the folded nodal mass, the cell pressure solves
//!
//!   h^2 p / (K_t dt^2) + G^T M^-1 G p + S p
//!       = h^2 p(J^n) / (K_t dt^2) - h^2 D u* / dt + h^2 r / dt
//!
//! on the fluid cells (air cells: p = 0; walls: Neumann through the fold),
//! then u^{n+1} = u* + dt M^-1 G p. K_t = infinity drops the first terms:
//! the incompressible projection. S = (beta / rho0) C^T C, with C the 2 x 2
//! alternating sums around the nodes, controls the cell checkerboard that
//! G cannot see; r = drift (packing J - 1) / dt in the cells whose nodes
//! are full moves the particles back to the packing their J says. The
//! cells' J rate is e = D u^{n+1} + (dt / h^2) S p - r, so that
//! p^{n+1} = p(J^n) - K_t dt e exactly as the particles' J^{n+1} = J^n (1 + dt e).
//!
//! Everything here is serial, in cell and node order: bit-identical for any
//! thread count. The solved pressure is the next step's starting guess (it
//! is in the checkpoint).

use crate::config::{
    Advection, AirNodes, DriftCorrection, FreeSurface, Material, Preconditioner, ProjectionSettings,
};
use crate::grid::{Grid, FULL_NODE_SHARE, PAD};
use crate::par::{Pieces, CHUNK};
use crate::particles::{Mat2, Particles, Vec2};
use crate::shapes::{Shape, Stencil};
use crate::viscosity;
use rayon::prelude::*;

/// No unknown: an air cell.
const AIR: u32 = u32::MAX;

/// The least share of the way to an air cell's centre at which the ghost
/// surface may sit: 1 / theta scales a corner's pressure force, and a
/// surface on the fluid cell's centre would make it unbounded.
const MIN_SURFACE_SHARE: f64 = 0.05;

/// The corners of a cell as (x offset, y offset, sign of x, sign of y) of
/// the bilinear gradient at its centre: grad N = (sx, sy) / (2 h).
const CORNERS: [(usize, usize, f64, f64); 4] = [
    (0, 0, -1.0, -1.0),
    (1, 0, 1.0, -1.0),
    (0, 1, -1.0, 1.0),
    (1, 1, 1.0, 1.0),
];

/// The hourglass pattern over the corners (in `CORNERS` order): the nodal
/// velocity mode the centre divergence and gradient cannot see.
const HOURGLASS: [f64; 4] = [1.0, -1.0, -1.0, 1.0];

/// A row of the incomplete Cholesky factor: its entries left of the
/// diagonal (unknown, value) and the diagonal.
#[derive(Clone, Copy, Debug, Default)]
struct Lower {
    index: [u32; 4],
    value: [f64; 4],
    len: usize,
    diagonal: f64,
    /// 1 / diagonal: the substitutions multiply (a divide's latency would
    /// sit on their dependency chain).
    inverse: f64,
}

/// What the last solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveStats {
    pub fluid_cells: usize,
    pub iterations: u32,
    /// |b - A p| / |b| at the end.
    pub residual: f64,
    pub converged: bool,
    /// Energy the projection removed: minus its velocity change's work at
    /// the time-centred velocity, less what the step's mean pressure put
    /// into the stored energy (the compression's backward-Euler loss
    /// counted), plus the gravitational energy the drift correction by
    /// position took out (J/m).
    pub dissipated_projection: f64,
    /// Energy the hourglass control removed: minus its velocity change's
    /// work at the time-centred velocity (J/m).
    pub dissipated_hourglass: f64,
    /// Mean of packing J - 1 over the cells whose nodes are full (before the step's correction).
    pub packing_error: f64,
    /// Conjugate-gradient iterations of the drift correction by position.
    pub shift_iterations: u32,
    /// The change of the nodes' kinetic energy 1/2 sum M' |u|^2 (the
    /// operator's masses: P2G's, the slaved air nodes' shares in) that the
    /// pressure correction du made, before the velocities beyond the fluid
    /// are extrapolated (J/m): sum M' du . u^{n+1} - 1/2 sum M' |du|^2.
    pub kinetic_change: f64,
    /// Its first part, sum M' du . u^{n+1} (J/m): zero to the solve's
    /// residual for a projection orthogonal in the nodal masses (the cell
    /// and `ghost_orthogonal` surfaces, without the checkerboard control,
    /// whose exchange lets D u depart from 0, and with no light node
    /// floored); what an oblique one can add.
    pub cross_work: f64,
}

#[derive(Clone, Debug, Default)]
pub struct Scratch {
    cells: [usize; 2],
    periodic: [bool; 2],
    /// Per cell: its unknown, or `AIR`.
    unknown: Vec<u32>,
    /// Per unknown: its cell.
    fluid: Vec<u32>,
    /// Per cell: the solved pressure (air: 0), the next solve's starting guess.
    pub pressure: Vec<f64>,
    /// Per cell: the J rate e of the last step (air: 0).
    rate: Vec<f64>,
    /// Per cell: the pressure gradient the particles read their pressure
    /// with (`reconstruct`).
    gradient: Vec<Vec2>,
    /// Per cell: sum V, sum V0 of its particles.
    vol: Vec<f64>,
    vol0: Vec<f64>,
    /// Per particle: its cell at the start of the step.
    particle_cell: Vec<u32>,
    /// Per unknown: the corner nodes (padded indices).
    corners: Vec<[u32; 4]>,
    /// Per cell: the grid's fluid fraction less a half (the free surface's
    /// level; the ghost surfaces only).
    level: Vec<f64>,
    /// Per unknown and corner: 1 / theta where the cell diagonally across
    /// that corner is air (theta the share of the way to its centre at
    /// which the surface lies), else 1. The corner's pressure force is
    /// scaled by it: the air cell's ghost pressure p (theta - 1) / theta.
    ghost: Vec<[f64; 4]>,
    /// Whether the divergence takes the ghost weights too (`ghost_orthogonal`).
    orthogonal: bool,
    /// Per unknown: h^2 / (K_t dt^2) (0 at K = infinity), and the drift target r.
    alpha: Vec<f64>,
    target: Vec<f64>,
    /// Per unknown: the drift rate the positions are corrected by (under
    /// `drift_correction = "position"`; the velocity's target is then 0).
    shift: Vec<f64>,
    /// The nodes around which all four cells are fluid: their unknowns in
    /// `CORNERS` order of the node's cells (SW, SE, NW, NE).
    quads: Vec<[u32; 4]>,
    /// Per node: 1 / M' (folded mass, the slaved air nodes' shares added,
    /// light nodes floored).
    inv_mass: Vec<f64>,
    /// Per node: the folded mass with the slaved air nodes' shares; those
    /// shares and the u* momentum they bring, in the box's own masses.
    operator_mass: Vec<f64>,
    slaved_mass: Vec<f64>,
    slaved_momentum: Vec<Vec2>,
    /// Per node: a corner of a fluid cell (else it takes the velocity of
    /// its fluid neighbours).
    fluid_node: Vec<bool>,
    /// Per node: G p, then M^-1 G p.
    nodal: Vec<Vec2>,
    /// Per node: u* as the grid update left it, after the air nodes'
    /// momentum joined (`AirNodes::Slaved`), and after the hourglass control.
    before_merge: Vec<Vec2>,
    before_hourglass: Vec<Vec2>,
    before_projection: Vec<Vec2>,
    /// Conjugate-gradient vectors, one entry per unknown.
    x: Vec<f64>,
    b: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    d: Vec<f64>,
    q: Vec<f64>,
    diag: Vec<f64>,
    /// Per unknown: the unknowns of its 3 x 3 cells (slot (dx + 1) +
    /// 3 (dy + 1); `AIR` where none), the matrix row over them, and its
    /// incomplete Cholesky factor's row.
    neighbours: Vec<[u32; 9]>,
    matrix: Vec<[f64; 9]>,
    /// MIC(0)'s working copy of the matrix (its Schur complements).
    schur: Vec<[f64; 9]>,
    lower: Vec<Lower>,
    /// Whether the probing by 3 x 3 colours reads the matrix exactly (no
    /// periodic axis whose cell count is not a multiple of 3).
    probe_exact: bool,
    /// Per chunk of particles: the viscous work of the particle update.
    partials: Vec<f64>,
    pub stats: SolveStats,
}

impl Scratch {
    pub fn new(grid: &Grid, particles: usize) -> Self {
        let n_cells = grid.cells[0] * grid.cells[1];
        let n_nodes = grid.dims[0] * grid.dims[1];
        Scratch {
            cells: grid.cells,
            periodic: grid.periodic,
            unknown: vec![AIR; n_cells],
            fluid: Vec::with_capacity(n_cells),
            pressure: vec![0.0; n_cells],
            rate: vec![0.0; n_cells],
            gradient: vec![Vec2::zeros(); n_cells],
            vol: vec![0.0; n_cells],
            vol0: vec![0.0; n_cells],
            particle_cell: vec![0; particles],
            corners: Vec::with_capacity(n_cells),
            level: vec![0.0; n_cells],
            ghost: Vec::with_capacity(n_cells),
            orthogonal: false,
            alpha: Vec::with_capacity(n_cells),
            target: Vec::with_capacity(n_cells),
            shift: Vec::with_capacity(n_cells),
            quads: Vec::with_capacity(n_cells),
            inv_mass: vec![0.0; n_nodes],
            operator_mass: vec![0.0; n_nodes],
            slaved_mass: vec![0.0; n_nodes],
            slaved_momentum: vec![Vec2::zeros(); n_nodes],
            fluid_node: vec![false; n_nodes],
            nodal: vec![Vec2::zeros(); n_nodes],
            before_merge: vec![Vec2::zeros(); n_nodes],
            before_hourglass: vec![Vec2::zeros(); n_nodes],
            before_projection: vec![Vec2::zeros(); n_nodes],
            x: Vec::with_capacity(n_cells),
            b: Vec::with_capacity(n_cells),
            r: Vec::with_capacity(n_cells),
            z: Vec::with_capacity(n_cells),
            d: Vec::with_capacity(n_cells),
            q: Vec::with_capacity(n_cells),
            diag: Vec::with_capacity(n_cells),
            neighbours: Vec::with_capacity(n_cells),
            matrix: Vec::with_capacity(n_cells),
            schur: Vec::with_capacity(n_cells),
            lower: Vec::with_capacity(n_cells),
            probe_exact: (0..2).all(|a| !grid.periodic[a] || grid.cells[a].is_multiple_of(3)),
            partials: vec![0.0; crate::par::chunk_count(particles)],
            stats: SolveStats::default(),
        }
    }

    /// What this step's projection did to active node `n`'s velocity, for
    /// the force forensics: the hourglass control's change of u*, the
    /// pressure correction dt M'^-1 G p, and the extrapolation's (a node
    /// outside the fluid cells set to its fluid neighbours' mean, ghosts
    /// filled from it; a fluid node's share of the air nodes' momentum).
    /// Valid between `project` and the next step.
    pub fn node_changes(&self, grid: &Grid, dt: f64, n: usize) -> [Vec2; 3] {
        let hourglass = self.before_projection[n] - self.before_hourglass[n];
        let pressure = dt * self.nodal[n];
        let extrapolation = grid.vel_new[n] - self.before_merge[n] - hourglass - pressure;
        [hourglass, pressure, extrapolation]
    }

    /// Per cell: the V0 of the particles it held at the last step.
    pub fn cell_volume0(&self) -> &[f64] {
        &self.vol0
    }

    pub fn fit_particles(&mut self, n: usize) {
        if self.particle_cell.len() < n {
            self.particle_cell.resize(n, 0);
        }
        let chunks = crate::par::chunk_count(n);
        if self.partials.len() < chunks {
            self.partials.resize(chunks, 0.0);
        }
    }

    /// The cell holding `x` (periodic axes wrap; others clamp to the box).
    fn cell_of(&self, grid: &Grid, x: Vec2) -> usize {
        let r = (x - grid.origin) / grid.h;
        let index = |v: f64, axis: usize| {
            let n = self.cells[axis];
            if !v.is_finite() {
                0
            } else if self.periodic[axis] {
                (v.floor() as i64).rem_euclid(n as i64) as usize
            } else {
                (v.max(0.0) as usize).min(n - 1)
            }
        };
        index(r.x, 0) + self.cells[0] * index(r.y, 1)
    }

    /// The share theta of the way from fluid cell `c`'s centre to air cell
    /// `o`'s at which the fluid fraction, interpolated linearly, crosses a
    /// half: where the free surface's p = 0 sits (ghost fluid). Floored at
    /// `MIN_SURFACE_SHARE`; 1 (the air centre) where `o` reads fuller than
    /// a half (an air cell without particles).
    fn surface_share(&self, c: usize, o: usize) -> f64 {
        let (inside, outside) = (self.level[c].max(0.0), self.level[o]);
        if outside >= 0.0 {
            return 1.0;
        }
        (inside / (inside - outside)).clamp(MIN_SURFACE_SHARE, 1.0)
    }

    /// Whether every cell within `reach` cells of `c` (off a walled box:
    /// the wall's image) is fluid.
    fn deep(&self, c: usize, reach: i64) -> bool {
        let (ci, cj) = ((c % self.cells[0]) as i64, (c / self.cells[0]) as i64);
        (-reach..=reach).all(|dj| {
            (-reach..=reach).all(|di| {
                self.cell_at(ci + di, cj + dj)
                    .is_none_or(|o| self.unknown[o] != AIR)
            })
        })
    }

    /// Whether one of the cells with padded node `n` as a corner holds a particle.
    fn holds_material_around(&self, grid: &Grid, n: usize) -> bool {
        let (i, j) = grid.coords(n);
        let (i, j) = (i as i64 - PAD as i64, j as i64 - PAD as i64);
        [(-1, -1), (0, -1), (-1, 0), (0, 0)]
            .iter()
            .any(|&(di, dj)| {
                self.cell_at(i + di, j + dj)
                    .is_some_and(|c| self.vol0[c] > 0.0)
            })
    }

    fn divergence_weights(&self, k: usize) -> &[f64; 4] {
        if self.orthogonal {
            &self.ghost[k]
        } else {
            &UNWEIGHTED
        }
    }

    /// Cell (i, j) with periodic wrap; None off a walled box.
    fn cell_at(&self, i: i64, j: i64) -> Option<usize> {
        let wrap = |v: i64, axis: usize| {
            let n = self.cells[axis] as i64;
            if self.periodic[axis] {
                Some(v.rem_euclid(n) as usize)
            } else {
                (0..n).contains(&v).then_some(v as usize)
            }
        };
        Some(wrap(i, 0)? + self.cells[0] * wrap(j, 1)?)
    }
}

/// The inputs of the solve.
pub struct Inputs<'a> {
    pub particles: &'a Particles,
    pub material: &'a Material,
    pub settings: &'a ProjectionSettings,
    pub dt: f64,
}

/// Marks the fluid cells, applies the hourglass control to u* and solves
/// for the cell pressure; `grid.vel_new` then holds u^{n+1} (ghosts
/// filled) and `grid.accel` its acceleration.
pub fn project(inputs: &Inputs, grid: &mut Grid, s: &mut Scratch) {
    let (ps, mat, set, dt) = (
        inputs.particles,
        inputs.material,
        inputs.settings,
        inputs.dt,
    );
    let h = grid.h;
    let full_mass = mat.rho0 * h * h;
    mark_fluid(ps, grid, s, set.free_surface, full_mass);
    let light = set.light_node_share * full_mass;
    for &n in &grid.active {
        let n = n as usize;
        s.operator_mass[n] = grid.mass[n];
        s.before_merge[n] = grid.vel_new[n];
    }
    if set.air_nodes == AirNodes::Slaved {
        slave_air_nodes(grid, s, light);
    }
    // 1 / M' on every active node (ghosts hold their partner's mass).
    for &n in &grid.active {
        let n = n as usize;
        s.inv_mass[n] = 1.0 / s.operator_mass[n].max(light);
    }
    s.stats = SolveStats {
        fluid_cells: s.fluid.len(),
        ..SolveStats::default()
    };
    // u* before and after the hourglass control, for the energy booked below.
    for &n in &grid.active {
        s.before_hourglass[n as usize] = grid.vel_new[n as usize];
    }
    if set.hourglass > 0.0 {
        damp_hourglass(grid, s, set.hourglass);
    }
    for &n in &grid.active {
        let n = n as usize;
        s.before_projection[n] = grid.vel_new[n];
        grid.accel[n] += (s.before_projection[n] - s.before_merge[n]) / dt;
    }
    assemble(grid, s, mat, set, dt, full_mass);
    solve(
        grid,
        s,
        set,
        set.checkerboard / mat.rho0,
        true,
        set.tolerance,
    );
    // u^{n+1} = u* + dt M^-1 G p.
    for (k, &c) in s.fluid.iter().enumerate() {
        s.pressure[c as usize] = s.x[k];
    }
    apply_g(grid, s, |s, k| s.x[k]);
    for &n in &grid.active {
        let n = n as usize;
        let a = s.nodal[n];
        grid.vel_new[n] += dt * a;
        grid.accel[n] += a;
    }
    // In the masses the solve used (the slaved air nodes' shares in), over
    // the padded nodes as P2G left them (the fold's images included).
    let (mut kinetic_change, mut cross_work) = (0.0, 0.0);
    for &n in &grid.active {
        let n = n as usize;
        let raw = grid.mass_raw[n];
        let m = if grid.mass[n] > 0.0 {
            raw + raw * (s.operator_mass[n] - grid.mass[n]) / grid.mass[n]
        } else {
            0.0
        };
        let du = dt * s.nodal[n];
        let cross = m * du.dot(&grid.vel_new[n]);
        cross_work += cross;
        kinetic_change += cross - 0.5 * m * du.norm_squared();
    }
    s.stats.kinetic_change = kinetic_change;
    s.stats.cross_work = cross_work;
    extrapolate(grid, s, dt, light, set.air_nodes == AirNodes::Slaved);
    // The J rate e = D u^{n+1} + (dt / h^2) S p - r, and the pressure's work.
    let n = s.fluid.len();
    s.q[..n].fill(0.0);
    add_checkerboard(&s.quads, &s.x, set.checkerboard / mat.rho0, &mut s.q);
    let (mut pressure_work, mut compression_loss) = (0.0, 0.0);
    for (k, &c) in s.fluid.iter().enumerate() {
        let c = c as usize;
        let div = divergence(&s.corners[k], s.divergence_weights(k), &grid.vel_new, h);
        let e = div + dt / (h * h) * s.q[k] - s.target[k];
        s.rate[c] = e;
        pressure_work += s.x[k] * s.vol[c] * dt * e;
        // The stored energy gains the mean pressure's work over the step,
        // p^{n+1} + K_t dt e / 2: the end pressure's work exceeds it by
        // K_t (dt e)^2 V / 2 (backward Euler's loss, the sound it damps).
        if s.alpha[k] > 0.0 {
            compression_loss += h * h * s.vol[c] * e * e / (2.0 * s.alpha[k]);
        }
    }
    // The work of each velocity change at the time-centred velocity
    // (v^n + v^{n+1}) / 2: the kinetic energy's change telescopes exactly
    // over gravity and viscosity, the hourglass control and the projection.
    // (Against u* itself, the projection would be booked the kinetic energy
    // of the weight it cancels, 1/2 M (g dt)^2 a step for water at rest.)
    // The air nodes' momentum joining their fluid neighbours' is booked
    // with the projection (it is the extrapolation's constraint).
    let (mut work_hourglass, mut work_projection) = (0.0, 0.0);
    for &n in &grid.active {
        let n = n as usize;
        let m = grid.mass_raw[n];
        let mean = 0.5 * (grid.vel[n] + grid.vel_new[n]);
        let hourglass = s.before_projection[n] - s.before_hourglass[n];
        work_hourglass += m * hourglass.dot(&mean);
        work_projection += m * (grid.vel_new[n] - s.before_merge[n] - hourglass).dot(&mean);
    }
    s.stats.dissipated_hourglass = -work_hourglass;
    // What the pressure's work did not put into stored energy.
    s.stats.dissipated_projection = -work_projection + pressure_work + compression_loss;
    reconstruct(s, h, set.free_surface != FreeSurface::Cell);
}

/// The gradient of the cell pressure at each fluid cell, by central
/// differences where both neighbours are fluid, one-sided at a wall (no
/// neighbour), and against -p of the cell itself at an air neighbour (p = 0
/// on the face between; under the ghost surfaces against the ghost
/// pressure p (theta - 1) / theta, p = 0 where the surface is): each
/// particle reads p_c + grad . (x - x_c), exact for a linear field, so a
/// resting layer's particles read the hydrostatic pressure where they
/// stand and not their cell centre's (a sampling error of rho0 g h / 4).
fn reconstruct(s: &mut Scratch, h: f64, ghost: bool) {
    for k in 0..s.fluid.len() {
        let c = s.fluid[k] as usize;
        let p0 = s.x[k];
        let row = s.neighbours[k];
        let side = |slot: usize, di: i64, dj: i64| -> Option<f64> {
            let m = row[slot];
            if m != AIR {
                return Some(s.x[m as usize]);
            }
            let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
            s.cell_at(ci + di, cj + dj).map(|o| {
                if ghost {
                    let theta = s.surface_share(c, o);
                    p0 * (theta - 1.0) / theta
                } else {
                    -p0
                }
            })
        };
        let slope = |minus: Option<f64>, plus: Option<f64>| match (minus, plus) {
            (Some(a), Some(b)) => (b - a) / (2.0 * h),
            (None, Some(b)) => (b - p0) / h,
            (Some(a), None) => (p0 - a) / h,
            (None, None) => 0.0,
        };
        // Slots: (dx + 1) + 3 (dy + 1).
        s.gradient[c] = Vec2::new(
            slope(side(3, -1, 0), side(5, 1, 0)),
            slope(side(1, 0, -1), side(7, 0, 1)),
        );
    }
}

/// Whether in-box node `n` is an air node: in no fluid cell, so that it
/// takes its fluid neighbours' velocity after the solve (`extrapolate`).
/// A corner of a cell that holds material but is counted as air (the
/// ghost surface's thin surface cells and spray; under the cell surface
/// every such cell is fluid) carries its own momentum and keeps u*, in
/// free flight: overwriting it with its neighbours' velocity drove the
/// ghost surface's injections (session 38).
fn is_air_node(grid: &Grid, s: &Scratch, n: usize, light: f64) -> bool {
    let free_flight = grid.mass[n] >= light && s.holds_material_around(grid, n);
    !s.fluid_node[n] && !free_flight
}

/// The fluid nodes an air node's velocity is the mean of: among the eight
/// padded nodes around in-box node `n`, each whose in-box node is a fluid
/// node, as (padded node, in-box node). Under `mirrored` a node beyond a
/// wall counts as its mirror partner (the wall's symmetry, as the fold
/// has it); else only across a periodic edge (the step to session 39).
fn masters(grid: &Grid, s: &Scratch, n: usize, mirrored: bool) -> ([(usize, usize); 8], usize) {
    let nx = grid.dims[0] as i64;
    let (mut found, mut count) = ([(0, 0); 8], 0);
    for dj in -1..=1i64 {
        for di in -1..=1i64 {
            if (di, dj) == (0, 0) {
                continue;
            }
            let m = (n as i64 + di + dj * nx) as usize;
            let o = if mirrored {
                grid.partner_image(m, 0.0).0
            } else {
                owner(grid, m)
            };
            if s.fluid_node[o] {
                found[count] = (m, o);
                count += 1;
            }
        }
    }
    (found, count)
}

/// The air nodes' velocity is a constraint, v = the mean of their fluid
/// neighbours' (`extrapolate`); as for any node slaved to others, each of
/// those neighbours takes an equal share of its mass and of its u*
/// momentum (gravity's impulse included) before the solve, lumped. Without
/// it the weight of the material the B-spline carries above the top fluid
/// cells is lost when their velocity is overwritten, and a wave's
/// restoring force is short by the share of the mass it lifts that lands
/// there. The shares are taken in the box's own masses (a wall node owns
/// half its folded mass) and a neighbour beyond a wall is its partner's
/// image, so that a flat layer gives every surface node the same share.
/// A node on a no-slip wall is held at rest by the wall, not by its
/// neighbours: the wall takes its momentum. (The share is one mass for
/// both directions: a slave on a free-slip wall also hands its neighbours
/// the wall-normal inertia the wall holds.)
fn slave_air_nodes(grid: &mut Grid, s: &mut Scratch, light: f64) {
    for &n in &grid.active {
        s.slaved_mass[n as usize] = 0.0;
        s.slaved_momentum[n as usize] = Vec2::zeros();
    }
    for &n in &grid.inside {
        let n = n as usize;
        if !is_air_node(grid, s, n, light) || grid.is_pinned(n) {
            continue;
        }
        let (found, count) = masters(grid, s, n, true);
        if count == 0 {
            continue;
        }
        let mass = grid.own_share(n) * grid.mass[n] / count as f64;
        let momentum = mass * grid.vel_new[n];
        for &(m, o) in &found[..count] {
            s.slaved_mass[o] += mass;
            s.slaved_momentum[o] += grid.partner_image(m, momentum).1;
        }
    }
    for &n in &grid.inside {
        let n = n as usize;
        if s.slaved_mass[n] == 0.0 {
            continue;
        }
        // Back to folded values.
        let share = grid.own_share(n);
        let mass = grid.mass[n] + s.slaved_mass[n] / share;
        let v = (grid.mass[n] * grid.vel_new[n] + s.slaved_momentum[n] / share) / mass;
        s.operator_mass[n] = mass;
        grid.vel_new[n] = grid.project_walls(n, v);
    }
    grid.fill_vel_new(false);
    grid.fill(&mut s.operator_mass);
}

/// The nodes a particle reaches beyond its cell's corners (B-splines) are
/// in no fluid cell: no pressure holds them, and left alone they would fall
/// freely and drag the surface particles with them. Each takes the mean
/// velocity of its fluid neighbours (`masters`), as fluid codes
/// extrapolate the velocity into the air band (`is_air_node` says which).
fn extrapolate(grid: &mut Grid, s: &Scratch, dt: f64, light: f64, mirrored: bool) {
    let mut changed = false;
    for &n in &grid.inside {
        let n = n as usize;
        if !is_air_node(grid, s, n, light) {
            continue;
        }
        let (found, count) = masters(grid, s, n, mirrored);
        let mut sum = Vec2::zeros();
        for &(m, o) in &found[..count] {
            sum += if mirrored {
                grid.partner_image(m, grid.vel_new[o]).1
            } else {
                grid.vel_new[m]
            };
        }
        if count > 0 {
            let v = grid.project_walls(n, sum / count as f64);
            grid.accel[n] = (v - grid.vel[n]) / dt;
            grid.vel_new[n] = v;
            changed = true;
        }
    }
    if changed {
        grid.fill_vel_new(true);
    }
}

/// Fluid cells (those holding a particle; under the ghost surface also at
/// least half full), each particle's cell, the cells' volumes, the
/// unknowns' corners and their ghost weights.
fn mark_fluid(ps: &Particles, grid: &Grid, s: &mut Scratch, surface: FreeSurface, full_mass: f64) {
    for c in s.fluid.drain(..) {
        s.unknown[c as usize] = AIR;
        s.rate[c as usize] = 0.0;
    }
    s.vol.fill(0.0);
    s.vol0.fill(0.0);
    for p in 0..ps.len() {
        let c = s.cell_of(grid, ps.x[p]);
        s.particle_cell[p] = c as u32;
        s.vol[c] += ps.vol[p];
        s.vol0[c] += ps.vol0[p];
    }
    let nx = grid.dims[0];
    let corners_of = |c: usize| {
        let (ci, cj) = (c % s.cells[0], c / s.cells[0]);
        let base = (ci + PAD) + (cj + PAD) * nx;
        CORNERS.map(|(a, b, _, _)| (base + a + b * nx) as u32)
    };
    let ghost = surface != FreeSurface::Cell;
    s.orthogonal = surface == FreeSurface::GhostOrthogonal;
    if ghost {
        // The fluid fraction: the corners' folded mass over four full
        // nodes' (the B-spline smears the surface over about a cell, evenly
        // about it, so a half marks where it is), times J for the volume.
        for c in 0..s.level.len() {
            let mass: f64 = corners_of(c)
                .iter()
                .map(|&n| {
                    let n = n as usize;
                    if grid.is_active(n) {
                        grid.mass[n]
                    } else {
                        0.0
                    }
                })
                .sum();
            let j = if s.vol0[c] > 0.0 {
                s.vol[c] / s.vol0[c]
            } else {
                1.0
            };
            s.level[c] = mass / (4.0 * full_mass) * j - 0.5;
        }
    }
    // The flags live on the owner nodes (a periodic edge's two sides are one node).
    for c in &s.corners {
        for &n in c {
            s.fluid_node[owner(grid, n as usize)] = false;
        }
    }
    s.corners.clear();
    for c in 0..s.unknown.len() {
        let corners = corners_of(c);
        // A cell whose corners the particles' stencils do not all reach (a
        // particle clamped into it from outside the box) has no operator row.
        let reached = corners.iter().all(|&n| grid.is_active(n as usize));
        if s.vol0[c] > 0.0 && reached && (!ghost || s.level[c] >= 0.0) {
            s.unknown[c] = s.fluid.len() as u32;
            s.fluid.push(c as u32);
            for n in corners {
                s.fluid_node[owner(grid, n as usize)] = true;
            }
            s.corners.push(corners);
        } else {
            // No row: its particles (above a ghost surface, or clamped in
            // from outside the box) read p = 0, not a gradient left over.
            s.pressure[c] = 0.0;
            s.gradient[c] = Vec2::zeros();
        }
    }
    s.ghost.clear();
    for k in 0..s.fluid.len() {
        let c = s.fluid[k] as usize;
        let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
        let weights = CORNERS.map(|(a, b, _, _)| {
            if !ghost {
                return 1.0;
            }
            // The cell across this corner; off a walled box the fold stands for it.
            let across = s.cell_at(ci + 2 * a as i64 - 1, cj + 2 * b as i64 - 1);
            match across {
                Some(o) if s.unknown[o] == AIR => 1.0 / s.surface_share(c, o),
                _ => 1.0,
            }
        });
        s.ghost.push(weights);
    }
    s.neighbours.clear();
    for k in 0..s.fluid.len() {
        let c = s.fluid[k] as usize;
        let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
        let row = std::array::from_fn(|slot| {
            let (dx, dy) = (slot as i64 % 3 - 1, slot as i64 / 3 - 1);
            s.cell_at(ci + dx, cj + dy).map_or(AIR, |c| s.unknown[c])
        });
        s.neighbours.push(row);
    }
    // The nodes whose four cells are all fluid (walls: no image cells).
    s.quads.clear();
    let [cx, cy] = s.cells.map(|n| n as i64);
    let node_range = |axis: usize, n: i64| if s.periodic[axis] { 0..n } else { 1..n };
    for nj in node_range(1, cy) {
        for ni in node_range(0, cx) {
            let around = [(-1, -1), (0, -1), (-1, 0), (0, 0)]
                .map(|(a, b)| s.cell_at(ni + a, nj + b).map(|c| s.unknown[c]));
            if let [Some(sw), Some(se), Some(nw), Some(ne)] = around {
                if [sw, se, nw, ne].iter().all(|&u| u != AIR) {
                    s.quads.push([sw, se, nw, ne]);
                }
            }
        }
    }
}

/// The 2 x 2 alternating sum of a node's cells (SW - SE - NW + NE).
#[inline]
fn alternating(quad: &[u32; 4], x: &[f64]) -> f64 {
    quad.iter()
        .zip(HOURGLASS)
        .map(|(&u, sign)| sign * x[u as usize])
        .sum()
}

/// D u at a cell: (1 / 2h) sum over the corners of w (sx, sy) . u, with
/// the corners' weights w (1 but under `ghost_orthogonal`).
#[inline]
fn divergence(corners: &[u32; 4], weights: &[f64; 4], u: &[Vec2], h: f64) -> f64 {
    let mut sum = 0.0;
    for ((&n, (_, _, sx, sy)), w) in corners.iter().zip(CORNERS).zip(weights) {
        let v = u[n as usize];
        sum += w * (sx * v.x + sy * v.y);
    }
    sum / (2.0 * h)
}

/// The corners' weights of the divergence: 1, or the ghost weights under
/// `ghost_orthogonal` (then D = G^T / h^2 with the same G as the force,
/// and the projection is orthogonal in the nodal masses).
const UNWEIGHTED: [f64; 4] = [1.0; 4];

/// `s.nodal` = M'^-1 F G p for the cell values `value(s, k)` of the
/// unknowns: G p scattered on the corners, folded (walls, periodic
/// edges), divided by the mass, filled back to the ghosts.
fn apply_g(grid: &Grid, s: &mut Scratch, value: impl Fn(&Scratch, usize) -> f64) {
    let half_h = 0.5 * grid.h;
    for &n in &grid.active {
        s.nodal[n as usize] = Vec2::zeros();
    }
    for k in 0..s.fluid.len() {
        let g = half_h * value(s, k);
        let corners = s.corners[k];
        let ghost = s.ghost[k];
        for ((&n, (_, _, sx, sy)), w) in corners.iter().zip(CORNERS).zip(ghost) {
            let g = g * w;
            s.nodal[n as usize] += Vec2::new(sx * g, sy * g);
        }
    }
    grid.fold(&mut s.nodal);
    for &n in &grid.inside {
        let n = n as usize;
        s.nodal[n] *= s.inv_mass[n];
    }
    grid.fill(&mut s.nodal);
}

/// The right-hand side, the diagonal terms and the Jacobi preconditioner.
fn assemble(
    grid: &Grid,
    s: &mut Scratch,
    mat: &Material,
    set: &ProjectionSettings,
    dt: f64,
    full_mass: f64,
) {
    let h = grid.h;
    let h2 = h * h;
    let incompressible = mat.k == f64::INFINITY;
    let beta = set.checkerboard / mat.rho0;
    let full = FULL_NODE_SHARE * full_mass;
    s.q.clear();
    s.q.resize(s.fluid.len(), 0.0);
    s.alpha.clear();
    s.target.clear();
    s.b.clear();
    s.diag.clear();
    s.x.clear();
    let (mut error_sum, mut error_cells) = (0.0, 0usize);
    for (k, &c) in s.fluid.iter().enumerate() {
        let c = c as usize;
        let corners = s.corners[k];
        let j_cell = s.vol[c] / s.vol0[c];
        // The grid's packing: the corners' mass over a full node's.
        let masses = corners.map(|n| grid.mass[n as usize]);
        // The packing error where all four corners are full, reported
        // there; the correction reads it only `drift_depth` cells inside
        // the fluid (NaN elsewhere).
        let error = if masses.iter().all(|&m| m >= full) {
            let packing = masses.iter().sum::<f64>() / (4.0 * full_mass);
            let error = if incompressible {
                packing - 1.0
            } else {
                packing * j_cell - 1.0
            };
            error_sum += error;
            error_cells += 1;
            if set.drift_depth == 0 || s.deep(c, set.drift_depth as i64) {
                error
            } else {
                f64::NAN
            }
        } else {
            f64::NAN
        };
        let (alpha, p_eos) = if incompressible {
            (0.0, 0.0)
        } else {
            let state = mat.eos(j_cell);
            let kt = state.tangent_modulus.max(1e-300);
            (h2 / (kt * dt * dt), state.pressure)
        };
        let div_star = divergence(&corners, s.divergence_weights(k), &grid.vel_new, h);
        s.alpha.push(alpha);
        s.target.push(error);
        // The EOS and u* parts; the drift's is added below.
        s.b.push(alpha * p_eos - h2 / dt * div_star);
        // Diagonal of G^T M^-1 G without the walls' doubling (|g|^2 = h^2 / 2
        // per corner): a preconditioner only.
        let gmg: f64 = corners
            .iter()
            .zip(s.ghost[k])
            .zip(s.divergence_weights(k))
            .map(|((&n, w), v)| 0.5 * h2 * w * v * s.inv_mass[n as usize])
            .sum();
        s.diag.push(alpha + gmg);
        s.x.push(s.pressure[c]);
    }
    // The drift target r = drift e~ / dt, e~ the packing error smoothed
    // with weights (1, 2, 1) x (1, 2, 1) over the full cells of the 3 x 3
    // block: the raw per-cell error alternates from cell to cell, and a
    // target that alternates drives the checkerboard the operator cannot
    // resist (measured, 3 s of the incompressible dam break at h = 1 cm:
    // the cell checkerboard 0.18 with the raw error, 0.05 without the drift
    // control, whose grid packing then ends 53 % above 1).
    const WEIGHT: [f64; 3] = [1.0, 2.0, 1.0];
    for k in 0..s.fluid.len() {
        let (mut sum, mut weight) = (0.0, 0.0);
        for (slot, &m) in s.neighbours[k].iter().enumerate() {
            if m == AIR {
                continue;
            }
            let e = s.target[m as usize];
            if e.is_finite() {
                let w = WEIGHT[slot % 3] * WEIGHT[slot / 3];
                sum += w * e;
                weight += w;
            }
        }
        // The rate lands in `q` first: `target` is still being read.
        s.q[k] = if s.target[k].is_finite() && weight > 0.0 {
            set.drift * sum / weight / dt
        } else {
            0.0
        };
    }
    for k in 0..s.fluid.len() {
        s.target[k] = s.q[k];
    }
    // Incompressible and no air cell: the solve drops the mean of the
    // right-hand side, so the target must have none (else every cell's J
    // rate e would be minus its mean).
    if incompressible && s.fluid.len() == s.unknown.len() {
        remove_mean(&mut s.target);
    }
    s.shift.clear();
    if set.drift_correction == DriftCorrection::Position {
        s.shift.extend_from_slice(&s.target);
        s.target.fill(0.0);
    }
    for k in 0..s.fluid.len() {
        s.b[k] += h2 / dt * s.target[k];
    }
    for quad in &s.quads {
        for &u in quad {
            s.diag[u as usize] += beta;
        }
    }
    s.stats.packing_error = if error_cells > 0 {
        error_sum / error_cells as f64
    } else {
        0.0
    };
}

/// y = A x for the unknowns (`s.nodal` is scratch).
fn apply_a(grid: &Grid, s: &mut Scratch, beta: f64, from_d: bool) {
    let h = grid.h;
    if from_d {
        apply_g(grid, s, |s, k| s.d[k]);
    } else {
        apply_g(grid, s, |s, k| s.x[k]);
    }
    let h2 = h * h;
    for k in 0..s.fluid.len() {
        let v = if from_d { s.d[k] } else { s.x[k] };
        s.q[k] =
            s.alpha[k] * v + h2 * divergence(&s.corners[k], s.divergence_weights(k), &s.nodal, h);
    }
    let src = if from_d { &s.d } else { &s.x };
    add_checkerboard(&s.quads, src, beta, &mut s.q);
}

/// out += S p, S = beta C^T C over the nodes whose four cells are fluid
/// (the checkerboard control).
fn add_checkerboard(quads: &[[u32; 4]], p: &[f64], beta: f64, out: &mut [f64]) {
    if beta == 0.0 {
        return;
    }
    for quad in quads {
        let c = beta * alternating(quad, p);
        for (u, sign) in quad.iter().zip(HOURGLASS) {
            out[*u as usize] += sign * c;
        }
    }
}

/// Preconditioned conjugate gradient (IC(0) on the probed matrix, or
/// Jacobi) from the last step's pressure.
/// `fresh`: read the matrix and factorise it (else this step's pressure
/// matrix and its factor are used: the drift solve by position, whose
/// matrix differs only by the EOS diagonal taken out beforehand).
/// `tolerance`: the relative residual to stop at.
fn solve(
    grid: &Grid,
    s: &mut Scratch,
    set: &ProjectionSettings,
    beta: f64,
    fresh: bool,
    tolerance: f64,
) {
    let n = s.fluid.len();
    for v in [&mut s.r, &mut s.z, &mut s.d, &mut s.q] {
        v.clear();
        v.resize(n, 0.0);
    }
    if n == 0 {
        s.stats.converged = true;
        return;
    }
    // No air cell and no compressibility: p is known up to a constant;
    // solve for the mean-free part of a mean-free right-hand side.
    let singular = s.alpha.iter().all(|&a| a == 0.0) && n == s.unknown.len();
    if singular {
        remove_mean(&mut s.b);
        remove_mean(&mut s.x);
    }
    let incomplete_cholesky = set.preconditioner != Preconditioner::Jacobi && s.probe_exact;
    if incomplete_cholesky && fresh {
        probe_matrix(grid, s, beta);
        let tau = if set.preconditioner == Preconditioner::Mic0 {
            MIC_SHARE
        } else {
            0.0
        };
        factorise(s, tau);
    }
    apply_a(grid, s, beta, false);
    for k in 0..n {
        s.r[k] = s.b[k] - s.q[k];
    }
    let b_norm = dot(&s.b, &s.b).sqrt();
    let goal = tolerance * b_norm.max(f64::MIN_POSITIVE);
    let mut r_norm = dot(&s.r, &s.r).sqrt();
    let mut rz = 0.0;
    let mut iterations = 0;
    while r_norm > goal && iterations < set.max_iterations {
        if incomplete_cholesky {
            precondition(s);
        } else {
            for k in 0..n {
                s.z[k] = s.r[k] / s.diag[k];
            }
        }
        if singular {
            remove_mean(&mut s.z);
        }
        let rz_new = dot(&s.r, &s.z);
        if iterations == 0 {
            s.d.copy_from_slice(&s.z);
        } else {
            let ratio = rz_new / rz;
            for k in 0..n {
                s.d[k] = s.z[k] + ratio * s.d[k];
            }
        }
        rz = rz_new;
        if incomplete_cholesky {
            apply_matrix(s);
        } else {
            apply_a(grid, s, beta, true);
        }
        let dq = dot(&s.d, &s.q);
        if dq.is_nan() || dq <= 0.0 {
            break;
        }
        let step = rz / dq;
        for k in 0..n {
            s.x[k] += step * s.d[k];
            s.r[k] -= step * s.q[k];
        }
        r_norm = dot(&s.r, &s.r).sqrt();
        iterations += 1;
    }
    s.stats.iterations = iterations;
    s.stats.residual = if b_norm > 0.0 {
        r_norm / b_norm
    } else {
        r_norm
    };
    s.stats.converged = r_norm <= goal;
}

/// Reads the matrix row by row with nine probes: the cells of one colour
/// (i mod 3, j mod 3) are three apart, so each cell's 3 x 3 block holds
/// one of them and A times the colour's indicator is that column's entry.
fn probe_matrix(grid: &Grid, s: &mut Scratch, beta: f64) {
    let n = s.fluid.len();
    s.matrix.clear();
    s.matrix.resize(n, [0.0; 9]);
    let colour = |s: &Scratch, k: usize| {
        let c = s.fluid[k] as usize;
        (c % s.cells[0]) % 3 + 3 * ((c / s.cells[0]) % 3)
    };
    for probe in 0..9 {
        for k in 0..n {
            s.d[k] = if colour(s, k) == probe { 1.0 } else { 0.0 };
        }
        apply_a(grid, s, beta, true);
        for k in 0..n {
            if colour(s, k) != probe {
                continue;
            }
            for slot in 0..9 {
                let m = s.neighbours[k][slot];
                if m != AIR {
                    s.matrix[m as usize][8 - slot] = s.q[m as usize];
                }
            }
        }
    }
    s.d.fill(0.0);
}

/// The share of the dropped fill MIC(0) moves onto the diagonals (below 1,
/// which would make L L^T exactly row-sum preserving and singular on a
/// closed incompressible box: the usual 0.97).
const MIC_SHARE: f64 = 0.97;

/// Incomplete Cholesky on the 3 x 3 pattern, column by column
/// (right-looking): each pivot's column updates the Schur complement of
/// the rows below it, and an update that falls outside the pattern (fill)
/// is dropped (IC(0), `tau` = 0) or moved, times `tau`, onto the diagonals
/// of the two rows it would have coupled (MIC(0)), so that L L^T keeps A's
/// row sums to within 1 - tau: the smooth error that IC(0) resolves slowly
/// is what the pressure's conjugate gradient spends its iterations on. A
/// pivot below a quarter of A's diagonal is replaced by that diagonal (the
/// factor always exists). A row keeps at most four entries left of its
/// diagonal (its 3 x 3 block's cells before it; more only across a
/// periodic edge, where the rest is dropped).
fn factorise(s: &mut Scratch, tau: f64) {
    let n = s.fluid.len();
    s.schur.clear();
    s.schur.extend_from_slice(&s.matrix);
    s.lower.clear();
    s.lower.resize(n, Lower::default());
    for k in 0..n {
        let pivot = s.schur[k][4];
        let d = if pivot > 0.25 * s.matrix[k][4] {
            pivot.sqrt()
        } else {
            s.matrix[k][4].sqrt()
        };
        s.lower[k].diagonal = d;
        s.lower[k].inverse = 1.0 / d;
        // The pivot's column below the diagonal: L's entries (m, k).
        let mut below = [(0u32, 0.0f64); 8];
        let mut count = 0;
        for (slot, &m) in s.neighbours[k].iter().enumerate() {
            if m != AIR && m as usize > k && count < below.len() {
                below[count] = (m, s.schur[k][slot] / d);
                count += 1;
            }
        }
        for &(m, l) in &below[..count] {
            let row = &mut s.lower[m as usize];
            if row.len < 4 {
                row.index[row.len] = k as u32;
                row.value[row.len] = l;
                row.len += 1;
            }
        }
        for a in 0..count {
            let (i, li) = below[a];
            s.schur[i as usize][4] -= li * li;
            for &(j, lj) in &below[..a] {
                let update = li * lj;
                match s.neighbours[i as usize].iter().position(|&m| m == j) {
                    Some(slot) => {
                        s.schur[i as usize][slot] -= update;
                        s.schur[j as usize][8 - slot] -= update;
                    }
                    None => {
                        s.schur[i as usize][4] -= tau * update;
                        s.schur[j as usize][4] -= tau * update;
                    }
                }
            }
        }
    }
}

/// z = (L L^T)^-1 r: forward by rows of L, backward by its columns.
fn precondition(s: &mut Scratch) {
    let n = s.fluid.len();
    for i in 0..n {
        let row = &s.lower[i];
        let mut sum = s.r[i];
        for a in 0..row.len {
            sum -= row.value[a] * s.z[row.index[a] as usize];
        }
        s.z[i] = sum * row.inverse;
    }
    for i in (0..n).rev() {
        let row = &s.lower[i];
        let zi = s.z[i] * row.inverse;
        s.z[i] = zi;
        for a in 0..row.len {
            s.z[row.index[a] as usize] -= row.value[a] * zi;
        }
    }
}

/// q = A d with the probed matrix (the same operator as `apply_a`, nine
/// products a row).
fn apply_matrix(s: &mut Scratch) {
    for i in 0..s.fluid.len() {
        let mut sum = 0.0;
        for (slot, &k) in s.neighbours[i].iter().enumerate() {
            if k != AIR {
                sum += s.matrix[i][slot] * s.d[k as usize];
            }
        }
        s.q[i] = sum;
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn remove_mean(v: &mut [f64]) {
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    v.iter_mut().for_each(|x| *x -= mean);
}

/// Removes `share` of each fluid cell's hourglass velocity, cell by cell
/// in order, on the owner nodes, then fills the ghosts. The change
/// du_k = -share G_k a / M'_k with a = sum G u / sum 1/M' keeps the
/// momentum (sum G = 0) and is the one of least kinetic energy in M':
/// it removes share (2 - share) / 2 of |sum G u|^2 / sum 1/M', never adds.
fn damp_hourglass(grid: &mut Grid, s: &Scratch, share: f64) {
    for corners in &s.corners {
        let owners = corners.map(|n| owner(grid, n as usize));
        let mut mode = Vec2::zeros();
        let mut compliance = 0.0;
        for k in 0..4 {
            mode += HOURGLASS[k] * grid.vel_new[owners[k]];
            compliance += s.inv_mass[owners[k]];
        }
        let a = mode / compliance;
        for k in 0..4 {
            let n = owners[k];
            let dv = -share * HOURGLASS[k] * s.inv_mass[n] * a;
            grid.vel_new[n] = grid.project_walls(n, grid.vel_new[n] + dv);
        }
    }
    grid.fill_vel_new(false);
}

/// The node a cell corner's value lives on: itself, or across a periodic edge.
/// The node a padded node's value lives on: itself, or across a periodic
/// edge (the ghosts on either side wrap to their partners in the box).
fn owner(grid: &Grid, n: usize) -> usize {
    let (i, j) = grid.coords(n);
    let wrap = |k: usize, axis: usize| {
        if grid.periodic[axis] {
            let cells = grid.cells[axis] as i64;
            ((k as i64 - PAD as i64).rem_euclid(cells) + PAD as i64) as usize
        } else {
            k
        }
    };
    grid.index(wrap(i, 0), wrap(j, 1))
}

/// The drift correction by position (`drift_correction = "position"`),
/// after the particle update: the same operator without its EOS term
/// solves A q = h^2 dt s for the step's drift rate s, and each particle
/// moves by its stencil's share of the nodal displacement M'^-1 G q, whose
/// divergence D is dt s. Velocities, J and the stored energy are left
/// alone (a velocity target would be carried on as flow: it swamped the
/// slosh's wave); the gravitational energy the move changes is booked with
/// the projection. Returns that energy removed (J/m).
#[allow(clippy::too_many_arguments)]
pub fn shift_particles(
    particles: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    set: &ProjectionSettings,
    beta: f64,
    gravity: Vec2,
    s: &mut Scratch,
    dt: f64,
) -> f64 {
    let n = s.fluid.len();
    if s.shift.len() != n || s.shift.iter().all(|&r| r == 0.0) {
        return 0.0;
    }
    let h2 = grid.h * grid.h;
    // The operator without its EOS diagonal: the probed matrix loses it
    // too, and the pressure matrix's factor preconditions (at K = infinity
    // it is the same matrix).
    for k in 0..n {
        s.diag[k] -= s.alpha[k];
        if let Some(row) = s.matrix.get_mut(k) {
            row[4] -= s.alpha[k];
        }
        s.alpha[k] = 0.0;
        s.b[k] = h2 * dt * s.shift[k];
        s.x[k] = 0.0;
    }
    let pressure_solve = s.stats;
    solve(grid, s, set, beta, false, set.drift_tolerance);
    let shift_iterations = s.stats.iterations;
    s.stats = SolveStats {
        shift_iterations,
        ..pressure_solve
    };
    apply_g(grid, s, |s, k| s.x[k]);
    let bilinear = set.advection == Advection::Bilinear;
    let removed = crate::shapes::with_width!(shape, W => move_particles::<W>(particles, stencils, shape, grid, gravity, bilinear, s));
    s.stats.dissipated_projection += removed;
    removed
}

/// x_p += sum N_ip d_i for the nodal displacement d in `s.nodal` (N the
/// bilinear element's under `bilinear`, whose cell-integrated divergence is
/// D d); returns sum m_p g . dx_p, the gravitational energy taken out.
fn move_particles<const W: usize>(
    particles: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    gravity: Vec2,
    bilinear: bool,
    s: &mut Scratch,
) -> f64 {
    let nx = grid.dims[0];
    let n = particles.len();
    let n_chunks = crate::par::chunk_count(n);
    let piece = crate::par::piece_chunks(n);
    let displacement = &s.nodal[..];
    let lo = grid.origin;
    let size = Vec2::new(grid.cells[0] as f64 * grid.h, grid.cells[1] as f64 * grid.h);
    (
        particles.x.par_chunks_mut(CHUNK),
        particles.mass.par_chunks(CHUNK),
        stencils.par_chunks(CHUNK),
        s.partials[..n_chunks].par_iter_mut(),
    )
        .into_par_iter()
        .pieces(piece)
        .for_each(|(x, mass, st, energy)| {
            let mut acc = 0.0;
            for k in 0..x.len() {
                let dx = if bilinear {
                    crate::transfers::serial::bilinear(displacement, grid, x[k])
                } else {
                    crate::transfers::serial::interpolate::<W>(displacement, &st[k], shape, nx)
                };
                acc += mass[k] * gravity.dot(&dx);
                x[k] += dx;
                for axis in 0..2 {
                    if grid.periodic[axis] {
                        x[k][axis] = lo[axis] + (x[k][axis] - lo[axis]).rem_euclid(size[axis]);
                    }
                }
            }
            *energy = acc;
        });
    s.partials[..n_chunks].iter().sum()
}

/// The particles after G2P: F from the velocity gradient, J^{n+1} = J^n
/// (1 + dt e) of the particle's cell, the viscous stress, the cell
/// pressure, the stored energy; no wave speed (no sound limits the step).
/// Returns the viscous work.
pub fn update_particles(
    particles: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    material: &Material,
    s: &mut Scratch,
    dt: f64,
) -> f64 {
    crate::shapes::with_width!(shape, W => update_with::<W>(particles, stencils, shape, grid, material, s, dt))
}

fn update_with<const W: usize>(
    particles: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    m: &Material,
    s: &mut Scratch,
    dt: f64,
) -> f64 {
    let nx = grid.dims[0];
    let inv_h = 1.0 / grid.h;
    let n = particles.len();
    let n_chunks = crate::par::chunk_count(n);
    let piece = crate::par::piece_chunks(n);
    let (rate, pressure_cell, gradient) = (&s.rate[..], &s.pressure[..], &s.gradient[..]);
    let (origin, h, cells_x) = (grid.origin, grid.h, s.cells[0]);
    let velocity = &grid.vel_new[..];
    (
        particles.f.par_chunks_mut(CHUNK),
        particles.j.par_chunks_mut(CHUNK),
        particles.vol.par_chunks_mut(CHUNK),
        particles.stress.par_chunks_mut(CHUNK),
        particles.pressure.par_chunks_mut(CHUNK),
        particles.dev_rate.par_chunks_mut(CHUNK),
        particles.wave_speed.par_chunks_mut(CHUNK),
        particles.stored_energy.par_chunks_mut(CHUNK),
        particles
            .vol0
            .par_chunks(CHUNK)
            .zip(particles.x.par_chunks(CHUNK)),
        stencils.par_chunks(CHUNK),
        s.particle_cell[..n].par_chunks(CHUNK),
        s.partials[..n_chunks].par_iter_mut(),
    )
        .into_par_iter()
        .pieces(piece)
        .for_each(
            |(f, j, vol, stress, pressure, dev_rate, wave, stored, (vol0, x), st, cell, work)| {
                let mut acc = 0.0;
                for k in 0..f.len() {
                    let l = crate::stages::stress::velocity_gradient::<W>(
                        shape, &st[k], velocity, nx, inv_h,
                    );
                    let c = cell[k] as usize;
                    let j_next = j[k] * (1.0 + dt * rate[c]);
                    let f_new = (Mat2::identity() + dt * l) * f[k];
                    let det = f_new.determinant();
                    f[k] = if det > 0.0 && j_next > 0.0 {
                        f_new * (j_next / det).sqrt()
                    } else {
                        f_new
                    };
                    j[k] = j_next;
                    vol[k] = vol0[k] * j_next;
                    let d = 0.5 * (l + l.transpose());
                    let visc = viscosity::newtonian(m.viscosity, &d);
                    acc += visc.power * vol[k] * dt;
                    let centre = origin
                        + h * Vec2::new((c % cells_x) as f64 + 0.5, (c / cells_x) as f64 + 0.5);
                    pressure[k] = pressure_cell[c] + gradient[c].dot(&(x[k] - centre));
                    stress[k] = visc.stress - pressure[k] * Mat2::identity();
                    dev_rate[k] = visc.dev_rate;
                    wave[k] = 0.0;
                    stored[k] = vol0[k] * m.eos(j_next).energy;
                }
                *work = acc;
            },
        );
    s.partials[..n_chunks].iter().sum()
}

/// The flow's time step: CFL h / max |v|, the gravity-wave limit CFL
/// sqrt(h / g) and the explicit viscous limit h^2 / (4 nu).
pub fn flow_dt(cfl: f64, h: f64, max_speed: f64, gravity: f64, nu: f64) -> f64 {
    let mut dt = f64::INFINITY;
    if max_speed > 0.0 {
        dt = dt.min(cfl * h / max_speed);
    }
    if gravity > 0.0 {
        dt = dt.min(cfl * (h / gravity).sqrt());
    }
    if nu > 0.0 {
        dt = dt.min(0.25 * h * h / nu);
    }
    if dt.is_finite() {
        dt
    } else {
        // Neither flow nor gravity nor viscosity: a cell per unit speed.
        cfl * h
    }
}
