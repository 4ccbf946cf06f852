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

mod advect;
pub mod inf_sup;
pub mod mac;
mod operator;
mod pcg;
mod surface;
pub mod surface_depth;

pub use advect::{shift_particles, update_particles};

use crate::choices::ShapeKind;
use crate::config::{AirNodes, FreeSurface, Holes, Material, ProjectionSettings, SurfaceLevel};
use crate::grid::{Grid, PAD};
use crate::particles::{Particles, Vec2};
use operator::{add_checkerboard, apply_g, assemble, divergence, UNWEIGHTED};
use pcg::{solve, Lower};
use surface::{extrapolate, mark_collocated_rows, mark_fluid, reconstruct, slave_air_nodes};

/// No unknown: an air cell.
const AIR: u32 = u32::MAX;

/// The corners of a cell as (x offset, y offset, sign of x, sign of y) of
/// the bilinear gradient at its centre: grad N = (sx, sy) / (2 h).
const CORNERS: [(usize, usize, f64, f64); 4] = [
    (0, 0, -1.0, -1.0),
    (1, 0, 1.0, -1.0),
    (0, 1, -1.0, 1.0),
    (1, 1, 1.0, 1.0),
];

/// The reach up to which `Scratch::deep` reads a per-step erosion (the
/// packing's reading asks for 2, the material's density for 1).
const CACHED_REACH: u8 = 2;

/// The hourglass pattern over the corners (in `CORNERS` order): the nodal
/// velocity mode the centre divergence and gradient cannot see.
const HOURGLASS: [f64; 4] = [1.0, -1.0, -1.0, 1.0];

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
    /// into the stored energy (the compression's loss counted: backward
    /// Euler's, or (2 theta - 1) times it under the staggered scheme's
    /// theta), plus the gravitational energy the drift correction by
    /// position took out (J/m).
    pub dissipated_projection: f64,
    /// Of `dissipated_projection`, the gravitational energy the drift
    /// correction by position took out this step (J/m): the monitor's
    /// gravity stepping term leaves it out, since it is booked here.
    pub dissipated_packing: f64,
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
    /// level; the ghost surfaces and `holes = "kept"` only).
    level: Vec<f64>,
    /// Per cell: how deep below the surface its fraction says its centre
    /// lies, in cells (`surface_level = "distance"` only; `surface_depth`).
    depth: Vec<f64>,
    /// Per cell: whether this step's `depth` is read (a cell borders up
    /// to eight fluid cells; its bisection runs once).
    depth_read: Vec<bool>,
    /// The kernel whose response to a flat surface maps the fractions to
    /// depths (`surface_level = "distance"`), or None (linear in them).
    depth_basis: Option<ShapeKind>,
    /// The least theta (`min_surface_share`): 1 / theta scales the
    /// surface's pressure force, unbounded at the fluid cell's centre.
    surface_floor: f64,
    /// Per unknown and corner: 1 / theta where the cell diagonally across
    /// that corner is air (theta the share of the way to its centre at
    /// which the surface lies), else 1. The corner's pressure force is
    /// scaled by it: the air cell's ghost pressure p (theta - 1) / theta.
    ghost: Vec<[f64; 4]>,
    /// Whether the divergence takes the ghost weights too (`ghost_orthogonal`).
    orthogonal: bool,
    /// Whether p = 0 sits where the fluid fraction crosses a half (either
    /// ghost surface) rather than at the air cells' centres.
    ghost_surface: bool,
    /// Per unknown: h^2 / (K_t dt^2) (over theta^2 under the staggered
    /// scheme's theta; 0 at K = infinity), and the drift target r.
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
    /// Per cell: fluid at the last step (what `holes = "kept"` reads).
    was_fluid: Vec<bool>,
    /// Per cell: 1 + the largest reach r <= `CACHED_REACH` for which
    /// `deep(c, r)` holds (0 for air), and the erosion's two buffers.
    reach: Vec<u8>,
    eroded: [Vec<u8>; 2],
    /// The staggered scheme's faces (empty under the collocated one).
    pub faces: mac::Faces,
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
            depth: vec![0.0; n_cells],
            depth_read: vec![false; n_cells],
            depth_basis: None,
            surface_floor: ProjectionSettings::default().min_surface_share,
            ghost: Vec::with_capacity(n_cells),
            orthogonal: false,
            ghost_surface: false,
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
            was_fluid: vec![false; n_cells],
            reach: vec![0; n_cells],
            eroded: [vec![0; n_cells], vec![0; n_cells]],
            faces: mac::Faces::default(),
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

    /// The last step's fluid cells (what `holes = "kept"` reads).
    pub fn fluid_cells(&self) -> &[u32] {
        &self.fluid
    }

    /// Restores the last step's fluid cells from a checkpoint (none when
    /// it holds none), the cells fluid before it cleared: `unknown` is
    /// not `AIR` exactly for the cells `fluid` lists. Returns the first
    /// cell outside the grid, if any.
    pub fn restore_fluid_cells(&mut self, cells: &[u32]) -> Result<(), u32> {
        if let Some(&c) = cells.iter().find(|&&c| c as usize >= self.unknown.len()) {
            return Err(c);
        }
        for c in self.fluid.drain(..) {
            self.unknown[c as usize] = AIR;
            self.rate[c as usize] = 0.0;
        }
        self.fluid.extend_from_slice(cells);
        Ok(())
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
    /// half (or, with `depth_basis`, the depths read from the fractions
    /// cross 0): where the free surface's p = 0 sits (ghost fluid).
    /// Floored at `surface_floor`; 1 (the air centre) where `o` reads
    /// fuller than a half (an air cell without particles).
    fn surface_share(&self, c: usize, o: usize) -> f64 {
        if self.level[o] >= 0.0 {
            return 1.0;
        }
        let [inside, outside] = match self.depth_basis {
            Some(_) => [self.depth[c], self.depth[o]],
            None => [self.level[c], self.level[o]],
        };
        let inside = inside.max(0.0);
        (inside / (inside - outside)).clamp(self.surface_floor, 1.0)
    }

    /// Cell `c`'s particle volumes over their rest volumes; 1 in a cell
    /// that holds none (a hole the staggered scheme solves as fluid, an
    /// empty cell under the ghost surface).
    pub(super) fn cell_j(&self, c: usize) -> f64 {
        if self.vol0[c] > 0.0 {
            self.vol[c] / self.vol0[c]
        } else {
            1.0
        }
    }

    /// Whether every cell within `reach` cells of `c` (off a walled box:
    /// the wall's image) is fluid; read from this step's erosion up to
    /// `CACHED_REACH`.
    pub(super) fn deep(&self, c: usize, reach: i64) -> bool {
        if reach <= CACHED_REACH as i64 {
            return self.reach[c] as i64 > reach;
        }
        self.deep_by_search(c, reach)
    }

    /// `deep` read cell by cell.
    fn deep_by_search(&self, c: usize, reach: i64) -> bool {
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
    /// The run's kernels (for `surface_level = "distance"`).
    pub shape: ShapeKind,
    pub dt: f64,
}

impl Inputs<'_> {
    /// Hands `s` how this step's ghost surface is read: the kernel it reads
    /// depths by, if it does, and theta's floor.
    fn set_surface_reading(&self, s: &mut Scratch) {
        let set = self.settings;
        s.depth_basis = (set.surface_level == SurfaceLevel::Distance).then_some(self.shape);
        s.surface_floor = set.min_surface_share;
    }
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
    let full_mass = mat.rho0 * grid.h * grid.h;
    inputs.set_surface_reading(s);
    mark_fluid(ps, grid, s, set.free_surface, full_mass, Holes::Air, false);
    mark_collocated_rows(s, set.free_surface);
    let light = set.light_node_share * full_mass;
    prepare_velocities(grid, s, set, light, dt);
    assemble(grid, s, mat, set, dt, full_mass);
    let beta = set.checkerboard / mat.rho0;
    solve(grid, s, set, beta, true, set.tolerance);
    correct_velocities(grid, s, dt);
    extrapolate(grid, s, dt, light, set.air_nodes == AirNodes::Slaved);
    book_rate_and_work(grid, s, beta, dt);
    reconstruct(s, grid.h, set.free_surface != FreeSurface::Cell);
}

/// The operator's masses (the air nodes' slaved shares in) and u* after
/// the hourglass control, with u* kept before and after it for the
/// energy booked with each.
fn prepare_velocities(
    grid: &mut Grid,
    s: &mut Scratch,
    set: &ProjectionSettings,
    light: f64,
    dt: f64,
) {
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
}

/// u^{n+1} = u* + dt M^-1 G p, and the change of the nodes' kinetic
/// energy it made (`SolveStats::kinetic_change`, `cross_work`).
fn correct_velocities(grid: &mut Grid, s: &mut Scratch, dt: f64) {
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
}

/// The cells' J rate e = D u^{n+1} + (dt / h^2) S p - r, and the energy
/// the projection and the hourglass control removed.
fn book_rate_and_work(grid: &Grid, s: &mut Scratch, beta: f64, dt: f64) {
    let h = grid.h;
    let n = s.fluid.len();
    s.q[..n].fill(0.0);
    add_checkerboard(&s.quads, &s.x, beta, &mut s.q);
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

/// The flow's time step: CFL h / max |v|, the gravity-wave limit
/// gravity_cfl sqrt(h / g) and the explicit viscous limit h^2 / (4 nu).
pub fn flow_dt([cfl, gravity_cfl]: [f64; 2], h: f64, max_speed: f64, gravity: f64, nu: f64) -> f64 {
    let mut dt = f64::INFINITY;
    if max_speed > 0.0 {
        dt = dt.min(cfl * h / max_speed);
    }
    if gravity > 0.0 {
        dt = dt.min(gravity_cfl * (h / gravity).sqrt());
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

/// Subtracts the mean (an incompressible closed box: p and its right-hand
/// side are known up to a constant).
fn remove_mean(v: &mut [f64]) {
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    v.iter_mut().for_each(|x| *x -= mean);
}
