//! The narrow read-only view of the state that the monitor observes.

use crate::config::{JUpdate, Material, Scene, ShapeKind, TransferKind};
use crate::deletion::{Culled, Losses};
use crate::energy::Energy;
use crate::particles::{Mat2, Vec2};
use crate::Solver;

/// Grid geometry and nodal fields after the last step (ghost layers included).
#[derive(Clone, Copy)]
pub struct GridView<'a> {
    pub h: f64,
    /// Position of padded node (0, 0).
    pub padded_origin: Vec2,
    /// Padded node count per axis; node (i, j) is `i + j * dims[0]`.
    pub dims: [usize; 2],
    /// Folded nodal mass (mirror images included).
    pub mass: &'a [f64],
    /// Nodal mass of the real particles only.
    pub mass_raw: &'a [f64],
    /// Velocity after the grid update.
    pub velocity: &'a [Vec2],
    pub acceleration: &'a [Vec2],
    /// Indices of the nodes worked on this step.
    pub active: &'a [u32],
}

#[derive(Clone, Copy)]
pub struct StateView<'a> {
    pub step: u64,
    pub time: f64,
    /// Size of the last step.
    pub dt: f64,
    pub scene: &'a Scene,
    pub materials: &'a [Material],
    /// The shape family (its critical Courant number judges time-step instability).
    pub shape: ShapeKind,
    /// The transfer (the monitor measures APIC's transfer loss on the grid
    /// where `affine_inertia` is known, and does not add it elsewhere).
    pub transfer: TransferKind,
    /// How J follows F: under `Det`, J is det F bit for bit; under `Exp` they differ.
    pub j_update: JUpdate,
    pub x: &'a [Vec2],
    pub v: &'a [Vec2],
    /// Velocities at the start of the last step.
    pub v_prev: &'a [Vec2],
    /// Force-driven acceleration of the last step (FLIP's exact increment over
    /// dt, walls applied, plus `[[perturb]]` impulses over dt).
    pub accel: &'a [Vec2],
    /// APIC's affine velocity C, or a gradient-enhanced FLIP's last L (an
    /// initial flow's gradient before the first step; else zero).
    pub affine: &'a [Mat2],
    pub mass: &'a [f64],
    pub volume: &'a [f64],
    pub volume0: &'a [f64],
    pub deformation: &'a [Mat2],
    pub j: &'a [f64],
    pub pressure: &'a [f64],
    /// In-plane Cauchy stress -p I + 2 mu dev(D) of the last stress stage
    /// (before the first step: the initial stress).
    pub stress: &'a [Mat2],
    /// |dev D| of the last step (1/s).
    pub dev_rate: &'a [f64],
    /// The history variable xi, accumulated equivalent shear strain (0 but
    /// in a softening solid).
    pub history: &'a [f64],
    pub material: &'a [u16],
    pub id: &'a [u32],
    pub grid: GridView<'a>,
    pub energy: Energy,
    /// Particle kinetic energy at P2G of the last step (with the affine part
    /// where `affine_inertia` is known).
    pub ke_particles_p2g: f64,
    /// Grid kinetic energy right after P2G of the last step (real mass only).
    pub ke_grid_p2g: f64,
    /// Grid kinetic energy of v^{n+1} as G2P read it (real mass only).
    pub ke_grid_updated: f64,
    /// APIC's D = d I where constant (B-splines; see `Solver::affine_inertia`):
    /// the affine kinetic energy is in `energy.affine`, and the transfer
    /// loss is measured on the grid (docs/physics.md section 4).
    pub affine_inertia: Option<f64>,
    /// The pressure-implicit step's velocities live on the cell faces
    /// (`ke_grid_*` are the faces'; the nodes only follow them).
    pub staggered: bool,
    /// Kinetic energy the `[[perturb]]` impulses of the last step added.
    pub impulse_kinetic: f64,
    /// Total P2G nodal mass of the last step (ghost nodes included, before folding).
    pub grid_mass_p2g: f64,
    /// Effective Courant number max(c_p + |v_p|) dt / h at the start of the last step.
    pub courant: f64,
    /// Particles outside the box (non-periodic axes).
    pub n_outside: usize,
    /// Particles with a non-finite position, velocity, J or pressure.
    pub n_nonfinite: usize,
    /// Particles deleted since t = 0, and those deleted at the last step.
    pub losses: Losses,
    pub culled: &'a [Culled],
    /// Particle count at t = 0 (ids run from 0 below it).
    pub n_initial: usize,
    /// The remedies: each one's energy change in the last step
    /// (`energy_parts`) and the fields it builds the pressure from
    /// (`pressure_fields`).
    pub remedies: &'a crate::remedies::Remedies,
    /// The pressure-implicit step's cell pressure (None otherwise).
    pub projection: Option<ProjectionView<'a>>,
}

/// The pressure-implicit step as the monitor reads it.
#[derive(Clone, Copy)]
pub struct ProjectionView<'a> {
    /// Per cell of the box (`i + j * cells[0]`): the solved pressure (air: 0).
    pub pressure: &'a [f64],
    /// Per cell: the particles' V0 (a cell is fluid when it holds some).
    pub volume0: &'a [f64],
    pub stats: crate::stages::projection::SolveStats,
}

pub fn make(s: &Solver) -> StateView<'_> {
    let ps = &s.particles;
    let g = &s.grid;
    StateView {
        step: s.step,
        time: s.time,
        dt: s.dt,
        scene: &s.cfg.scene,
        materials: &s.cfg.scene.materials,
        shape: s.cfg.method.shape,
        transfer: s.cfg.method.transfer,
        j_update: s.cfg.method.j_update,
        x: &ps.x,
        v: &ps.v,
        v_prev: &ps.v_prev,
        accel: &ps.accel,
        affine: &ps.affine,
        mass: &ps.mass,
        volume: &ps.vol,
        volume0: &ps.vol0,
        deformation: &ps.f,
        j: &ps.j,
        pressure: &ps.pressure,
        stress: &ps.stress,
        dev_rate: &ps.dev_rate,
        history: &ps.history,
        material: &ps.material,
        id: &ps.id,
        grid: GridView {
            h: g.h,
            padded_origin: g.position(0),
            dims: g.dims,
            mass: &g.mass,
            mass_raw: &g.mass_raw,
            velocity: &g.vel_new,
            acceleration: &g.accel,
            active: &g.active,
        },
        energy: s.energy,
        ke_particles_p2g: s.ke_particles_p2g,
        ke_grid_p2g: s.ke_grid_p2g,
        ke_grid_updated: s.ke_grid_updated,
        affine_inertia: s.affine_inertia(),
        staggered: s.staggered(),
        impulse_kinetic: s.impulse_kinetic,
        grid_mass_p2g: s.grid_mass_p2g,
        courant: s.courant,
        n_outside: s.n_outside,
        n_nonfinite: s.n_nonfinite,
        losses: s.losses,
        culled: &s.culled,
        n_initial: s.n_initial,
        remedies: &s.remedies,
        projection: s.projection_stats().map(|stats| ProjectionView {
            pressure: &s.projection.pressure,
            volume0: s.projection.cell_volume0(),
            stats,
        }),
    }
}
