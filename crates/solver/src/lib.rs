//! kick's solver: a 2D plane-strain explicit MPM in which every choice suspected
//! of mattering for the kinematic anomaly is a switch (see `config`).
//!
//! A step is a short chain of named stages (`stages/scheme.rs` orders
//! them): sort, P2G, grid update, G2P, stress. The remedies (`remedies/`)
//! plug into the stages through hooks. The monitor sees the state only
//! through [`StateView`].
//!
//! Layout: `stages/` (one file per stage, and the schemes that order them),
//! `shapes/`, `eos/`, `transfers/` (XPIC and the serial particle-grid sums),
//! `remedies/` (one file per remedy), `multiphase/` (the mixture, drag, pore
//! pressure and inflow); `config` and `choices` describe a run.

pub mod checkpoint;
pub mod choices;
pub mod config;
mod config_error;
pub mod deletion;
pub mod energy;
pub mod eos;
pub mod flows;
pub mod forensics;
pub mod grid;
mod init_hydrostatic;
pub mod material;
mod measure;
pub mod multiphase;
pub mod par;
pub mod particles;
pub mod perturb;
pub mod remedies;
pub mod scene;
pub mod shapes;
pub mod solid_neo_hookean;
pub mod stages;
pub mod timestep;
pub mod timing;
pub mod transfers;
mod view;
pub mod viscosity;

pub use checkpoint::CheckpointError;
pub use config::*;
pub use deletion::{CullReason, Culled, Losses};
pub use energy::Energy;
pub use multiphase::mixture::Mixture;
pub use particles::{Mat2, Vec2};
pub use perturb::{Direction, Perturb, Placement, Planted, Sustained};
pub use remedies::EnergyChange;
pub use timing::StageTimes;
pub use view::{GridView, ProjectionView, StateView};

use deletion::CullRules;
use grid::Grid;
use particles::Particles;
use shapes::{Shape, Stencil};
use stages::sort::Bins;

/// Why a step could not be taken.
#[derive(Clone, Debug, PartialEq)]
pub enum StepError {
    /// A particle left the grid (box plus ghost layers): the run has blown up.
    OutsideGrid { id: u32, x: [f64; 2] },
    /// The configuration cannot run (e.g. a NaN time step).
    BadTimeStep(f64),
}

impl std::fmt::Display for StepError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StepError::OutsideGrid { id, x } => {
                write!(f, "particle {id} left the grid at ({}, {})", x[0], x[1])
            }
            StepError::BadTimeStep(dt) => write!(f, "time step {dt} is not positive and finite"),
        }
    }
}

impl std::error::Error for StepError {}

/// The stages of a step, each runnable alone for the per-stage benchmarks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Stencils, counting sort, tiles and the active-node set.
    Sort,
    /// Mass, momentum and force to the grid (all three sums).
    P2g,
    /// Nodal velocities and the momentum update.
    Grid,
    G2p,
    Stress,
}

impl Stage {
    pub const ALL: [Stage; 5] = [
        Stage::Sort,
        Stage::P2g,
        Stage::Grid,
        Stage::G2p,
        Stage::Stress,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Stage::Sort => "sort",
            Stage::P2g => "p2g",
            Stage::Grid => "grid",
            Stage::G2p => "g2p",
            Stage::Stress => "stress",
        }
    }
}

#[derive(Clone)]
pub struct Solver {
    cfg: SolverConfig,
    shape: Shape,
    particles: Particles,
    grid: Grid,
    stencils: Vec<Stencil>,
    bins: Bins,
    measure_partials: Vec<measure::Partial>,
    partials_stress: Vec<stages::stress::Partial>,
    gravity: Vec2,
    step: u64,
    time: f64,
    dt: f64,
    /// The step fixed at t = 0 (used when `method.dt` is fixed).
    dt_fixed: f64,
    dissipated: f64,
    energy: Energy,
    courant: f64,
    /// max_p(c_p + |v_p|) as of the last `measure`.
    signal_speed: f64,
    /// Uintah's per-axis signal speed for the next step (`DtMode::PerAxis`).
    axis_signal_speed: f64,
    /// max_p c_p for the next step: a slab's z axis (`scene.slab`).
    z_signal_speed: f64,
    ke_particles_p2g: f64,
    ke_grid_p2g: f64,
    ke_grid_updated: f64,
    /// Kinetic energy the `[[perturb]]` impulses of the last step added.
    impulse_kinetic: f64,
    /// Every `[[perturb]]` impulse applied, as resolved.
    planted: Vec<Planted>,
    /// The plants with a duration still pushing (or that pushed last step).
    sustained: Vec<Sustained>,
    times: StageTimes,
    grid_mass_p2g: f64,
    n_outside: usize,
    n_nonfinite: usize,
    /// Particle count at t = 0 (deleted particles included).
    n_initial: usize,
    /// One past the largest id at t = 0: injected particles take the ids on from it.
    id_base: u32,
    /// None unless `on_escape` or `on_inversion` is "delete".
    cull_rules: Option<CullRules>,
    losses: Losses,
    /// The particles deleted at the last step (capacity: every particle).
    culled: Vec<Culled>,
    /// Scratch of XPIC(m) (empty for the other transfers).
    xpic: transfers::xpic::Scratch,
    /// The remedies switched on, with their scratch (`remedies/`).
    remedies: remedies::Remedies,
    /// Scratch of `quadrature = "mixed"` (empty otherwise).
    quadrature: stages::quadrature_mixed::Scratch,
    /// The cell pressure and scratch of the pressure-implicit step (empty otherwise).
    projection: stages::projection::Scratch,
}

impl Solver {
    /// Seeds the scene (relaxing it to hydrostatic equilibrium if asked).
    pub fn new(cfg: SolverConfig) -> Result<Self, ConfigError> {
        cfg.validate()?;
        let particles = scene::seed(&cfg.scene);
        if particles.is_empty() {
            return Err(ConfigError {
                key: "scene.body".into(),
                message: "the bodies hold no particles".into(),
            });
        }
        let failed = |e: StepError| ConfigError {
            key: "scene.initial".into(),
            message: format!("hydrostatic relaxation failed: {e}"),
        };
        let mut solver = match cfg.scene.initial {
            InitialState::ZeroStress => Self::with_particles(cfg, particles),
            InitialState::Hydrostatic => {
                let mut solver = Self::with_particles(cfg, particles);
                init_hydrostatic::relax(&mut solver).map_err(failed)?;
                solver
            }
            InitialState::HydrostaticGate => {
                init_hydrostatic::relax_behind_gates(cfg, particles).map_err(failed)?
            }
        };
        solver.start_flows();
        solver.start_clock();
        Ok(solver)
    }

    /// A solver over given particles (tests and benchmarks seed their own).
    pub fn with_particles(cfg: SolverConfig, particles: Particles) -> Self {
        // Each `[[perturb]]` entry applies once: its record allocates nothing in the step loop.
        let perturbations = cfg.perturb.len();
        let s = &cfg.scene;
        let grid = Grid::new(Vec2::from(s.origin), s.cell, s.cells(), s.periodic)
            .with_no_slip(s.no_slip_mask())
            .with_wall_ghosts(s.wall_ghosts);
        let n = particles.len();
        let chunks = par::chunk_count(n);
        let cull_rules = CullRules::of(s, cfg.method.j_update, [[false; 2]; 2]);
        let mut solver = Solver {
            shape: Shape::new(cfg.method.shape, s.ppc),
            gravity: Vec2::new(0.0, -s.gravity),
            stencils: vec![Stencil::default(); n],
            bins: Bins::new(grid.dims, n),
            measure_partials: vec![measure::Partial::default(); chunks],
            partials_stress: vec![Default::default(); chunks],
            grid,
            particles,
            cfg,
            step: 0,
            time: 0.0,
            dt: 0.0,
            dt_fixed: 0.0,
            dissipated: 0.0,
            energy: Energy::default(),
            courant: 0.0,
            signal_speed: 0.0,
            axis_signal_speed: 0.0,
            z_signal_speed: 0.0,
            ke_particles_p2g: 0.0,
            times: StageTimes::default(),
            ke_grid_p2g: 0.0,
            ke_grid_updated: 0.0,
            impulse_kinetic: 0.0,
            planted: Vec::with_capacity(perturbations),
            sustained: Vec::with_capacity(perturbations),
            grid_mass_p2g: 0.0,
            n_outside: 0,
            n_nonfinite: 0,
            n_initial: n,
            id_base: 0,
            cull_rules,
            losses: Losses::default(),
            culled: Vec::with_capacity(n),
            xpic: transfers::xpic::Scratch::default(),
            remedies: remedies::Remedies::default(),
            quadrature: stages::quadrature_mixed::Scratch::default(),
            projection: stages::projection::Scratch::default(),
        };
        if solver.cfg.method.quadrature == QuadratureKind::Mixed {
            solver.quadrature = stages::quadrature_mixed::Scratch::new(&solver.grid);
        }
        if solver.cfg.method.transfer == TransferKind::Xpic {
            solver.xpic = transfers::xpic::Scratch::new(&solver.grid, n);
        }
        solver.remedies = solver.cfg.build_remedies(&solver.grid, n);
        solver.build_projection(n);
        solver.start_clock();
        solver
    }

    fn implicit(&self) -> bool {
        self.cfg.method.formulation == Formulation::PressureImplicit
    }

    /// The pressure-implicit step on the staggered (MAC) grid.
    fn staggered(&self) -> bool {
        self.implicit() && self.cfg.method.projection.scheme == config::ProjectionScheme::Mac
    }

    /// The pressure-implicit step's scratch (kept when it exists: its
    /// pressure is the next solve's starting guess).
    fn build_projection(&mut self, n: usize) {
        if !self.implicit() {
            self.projection = stages::projection::Scratch::default();
        } else if self.projection.pressure.is_empty() {
            self.projection = stages::projection::Scratch::new(&self.grid, n);
        }
        if self.staggered() && self.projection.faces.is_empty() {
            self.projection.faces = stages::projection::mac::Faces::new(&self.grid);
        }
    }

    /// What the last pressure solve did (pressure-implicit step only).
    pub fn projection_stats(&self) -> Option<stages::projection::SolveStats> {
        self.implicit().then_some(self.projection.stats)
    }

    /// Adds the bodies' initial flows (docs/physics.md section 7) to the
    /// particles of their material inside their rectangle, once the initial
    /// state stands (a hydrostatic relaxation would damp them): velocity,
    /// APIC affine velocity, and the pressure that goes with the flow.
    fn start_flows(&mut self) {
        let s = &self.cfg.scene;
        let l = s.cell / s.ppc as f64;
        let ps = &mut self.particles;
        for body in s.bodies.iter().filter(|b| b.flow.is_some()) {
            let (Some(flow), Some(material)) = (body.flow, s.material_index(body)) else {
                continue;
            };
            let mat = &s.materials[material];
            let r = body.rect;
            let inside = |x: Vec2| {
                x.x >= r[0] - 0.5 * l
                    && x.x <= r[2] + 0.5 * l
                    && x.y >= r[1] - 0.5 * l
                    && x.y <= r[3] + 0.5 * l
            };
            for q in 0..ps.len() {
                if ps.material[q] as usize != material || !inside(ps.x[q]) {
                    continue;
                }
                let x = ps.x[q];
                let scale = flow.drift_scale(body.velocity);
                ps.v[q] += scale * flow.velocity(x, r, s.gravity);
                ps.affine[q] = scale * flow.gradient(x, r, s.gravity);
                let dp = flow.pressure(x, r, mat.rho0);
                if dp != 0.0 {
                    let p = ps.pressure[q] + dp;
                    let j = mat.j_at_pressure(p);
                    ps.vol[q] *= j / ps.j[q];
                    ps.f[q] *= (j / ps.j[q]).sqrt();
                    ps.j[q] = j;
                    ps.pressure[q] = p;
                    ps.stress[q] = -p * Mat2::identity();
                }
            }
        }
    }

    /// Sets t = 0: fixes the time step from the current state and measures energy.
    fn start_clock(&mut self) {
        self.refresh_eos_cache();
        self.step = 0;
        self.time = 0.0;
        self.dissipated = 0.0;
        // Particles deleted while relaxing to equilibrium are not losses of the run.
        self.n_initial = self.particles.len();
        self.id_base = self.particles.id.iter().max().map_or(0, |&i| i + 1);
        self.losses = Losses::default();
        self.culled.clear();
        self.measure();
        self.dt_fixed = self.cfl_dt();
        self.dt = self.dt_fixed;
    }

    /// The step the method takes: the CFL step, raised to `method.dt_min`.
    fn cfl_dt(&self) -> f64 {
        let step = self.cfl_step();
        match self.cfg.method.dt_min {
            Some(floor) if !self.implicit() && self.cfg.method.dt_value.is_none() => {
                step.max(floor)
            }
            _ => step,
        }
    }

    /// The CFL step (or `dt_value`), with no floor: the hydrostatic
    /// relaxation's, which must stay stable whatever the method's floor.
    pub(crate) fn cfl_step(&self) -> f64 {
        if let Some(dt) = self.cfg.method.dt_value {
            return dt;
        }
        if self.implicit() {
            // The wave speeds are zero: the signal speed is max |v|.
            let s = &self.cfg.scene;
            let m = &s.materials[0];
            let cfl = self.cfg.method.cfl;
            let gravity_cfl = self.cfg.method.projection.gravity_cfl.unwrap_or(cfl);
            return stages::projection::flow_dt(
                [cfl, gravity_cfl],
                s.cell,
                self.signal_speed,
                s.gravity,
                m.viscosity / m.rho0,
            );
        }
        let (cfl, h) = (self.cfg.method.cfl, self.cfg.scene.cell);
        match (self.cfg.method.dt, self.cfg.scene.slab) {
            // Uintah's step takes the least over the axes, z included.
            (DtMode::PerAxis, Some(dz)) => timestep::cfl_step(cfl, h, self.axis_signal_speed)
                .min(timestep::cfl_step(cfl, dz, self.z_signal_speed)),
            (DtMode::PerAxis, None) => timestep::cfl_step(cfl, h, self.axis_signal_speed),
            (DtMode::Fixed | DtMode::Dynamic, _) => timestep::cfl_step(cfl, h, self.signal_speed),
        }
    }

    pub fn config(&self) -> &SolverConfig {
        &self.cfg
    }

    pub fn step_count(&self) -> u64 {
        self.step
    }

    pub fn time(&self) -> f64 {
        self.time
    }

    /// The step the next `step()` will take (before clamping to t_end).
    pub fn next_dt(&self) -> f64 {
        if self.implicit() {
            return self.cfl_dt();
        }
        match self.cfg.method.dt {
            DtMode::Fixed => self.dt_fixed,
            DtMode::Dynamic | DtMode::PerAxis => self.cfl_dt(),
        }
    }

    pub fn energy(&self) -> Energy {
        self.energy
    }

    pub fn particle_count(&self) -> usize {
        self.particles.len()
    }

    /// True once t has reached the scene's end time.
    pub fn finished(&self) -> bool {
        self.time >= self.cfg.scene.t_end * (1.0 - 1e-12)
    }

    /// Takes one explicit step (clamped so as to land on t_end exactly).
    pub fn step(&mut self) -> Result<(), StepError> {
        self.step_with_dt(self.step_dt())
    }

    /// The next step's size, clamped so as to land on t_end exactly.
    pub(crate) fn step_dt(&self) -> f64 {
        let dt = self.next_dt();
        let remaining = self.cfg.scene.t_end - self.time;
        if self.implicit() && remaining > dt && remaining < 2.0 * dt {
            // Two halves rather than a full step and a sliver: the
            // projection's pressure goes as 1 / dt (a last step 44 times
            // shorter read a cell checkerboard of 2.7 on the slosh tank).
            0.5 * remaining
        } else if remaining > 0.0 && dt > remaining {
            remaining
        } else {
            dt
        }
    }

    /// Takes one step of a given size (relaxation and tests).
    pub fn step_with_dt(&mut self, dt: f64) -> Result<(), StepError> {
        self.begin_step(dt)?;
        self.finish_step();
        Ok(())
    }

    /// The first half of a step of size `dt`: sort, then the scheme's stages
    /// up to the grid update (the grid then holds v^{n+1}). A multiphase step
    /// couples the phases' grids between this and `finish_step`.
    pub(crate) fn begin_step(&mut self, dt: f64) -> Result<(), StepError> {
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(StepError::BadTimeStep(dt));
        }
        let mut clock = std::time::Instant::now();
        self.dt = dt;
        self.courant = self.signal_speed * dt / self.cfg.scene.cell;
        let ps = &mut self.particles;
        par::keep_warm(|| ps.v_prev.copy_from_slice(&ps.v));
        self.ke_particles_p2g = self.energy.kinetic_with_affine();
        self.impulse_kinetic = 0.0;
        self.remedies.begin_step();
        timing::lap(&mut self.times.other, &mut clock);
        stages::sort::sort(
            &self.particles,
            &mut self.grid,
            &self.shape,
            &mut self.stencils,
            &mut self.bins,
        )?;
        timing::lap(&mut self.times.sort, &mut clock);
        stages::scheme::to_grid(self, &mut clock);
        Ok(())
    }

    /// The second half of the step `begin_step` started: G2P (and the
    /// stress under USL and MUSL), the clock, deletions and the measures.
    pub(crate) fn finish_step(&mut self) {
        let mut clock = std::time::Instant::now();
        // What G2P reads: after the hooks and a mixture's coupling.
        self.ke_grid_updated = if self.staggered() {
            self.projection.faces.kinetic(true)
        } else {
            stages::grid_update::updated_kinetic(&self.grid)
        };
        stages::scheme::from_grid(self, &mut clock);
        self.step += 1;
        self.time += self.dt;
        self.cull();
        self.forget_non_finite_work();
        self.measure();
        timing::lap(&mut self.times.other, &mut clock);
        self.times.steps += 1;
    }

    /// Deletes escaped or inverted particles when the scene asks for it.
    fn cull(&mut self) {
        let Some(rules) = &self.cull_rules else {
            return;
        };
        let ps = &mut self.particles;
        if deletion::cull(ps, rules, self.time, &mut self.losses, &mut self.culled) > 0 {
            self.stencils.truncate(ps.len());
        }
    }

    /// Under `on_nonfinite = "delete"`, a step whose dissipated work came
    /// out not a number (from particles now deleted as non-finite) books
    /// none of it, so that the budget goes on: Uintah keeps no such ledger.
    /// `energy.dissipated` still holds the value the last measure took.
    fn forget_non_finite_work(&mut self) {
        if self.cfg.scene.on_nonfinite == config::OnLoss::Delete && !self.dissipated.is_finite() {
            self.dissipated = self.energy.dissipated;
        }
    }

    /// Opens the sides marked [axis][low, high]: no wall there (the grid
    /// mirrors nothing) and particles that cross are deleted as outflow.
    pub(crate) fn open_sides(&mut self, open: [[bool; 2]; 2]) {
        self.grid.set_open(open);
        self.cull_rules = CullRules::of(&self.cfg.scene, self.cfg.method.j_update, open);
    }

    /// Room for `extra` more particles, reserved at set-up so that an inflow
    /// appends them without reallocating.
    pub(crate) fn reserve_particles(&mut self, extra: usize) {
        self.particles.reserve(extra);
        self.stencils.reserve(extra);
        self.culled.reserve(extra);
        self.fit_scratch(self.particles.len() + extra);
    }

    /// Every per-particle scratch sized for at least `n` particles.
    fn fit_scratch(&mut self, n: usize) {
        if self.bins.order.len() < n {
            self.bins.order.resize(n, 0);
        }
        let chunks = par::chunk_count(n);
        if self.measure_partials.len() < chunks {
            self.measure_partials
                .resize(chunks, measure::Partial::default());
            self.partials_stress.resize(chunks, Default::default());
        }
        self.xpic.fit_particles(n);
        self.remedies.fit_particles(n);
        if self.implicit() {
            self.projection.fit_particles(n);
        }
    }

    /// Appends a particle that enters through an inflow wall: the next free
    /// id, J = 1, no stress. It is counted as injected, and the energy it
    /// brings from outside is booked as exchanged (like a load's work), so
    /// that the budget does not read it as an injection.
    pub(crate) fn inject(&mut self, x: Vec2, v: Vec2, mass: f64, vol0: f64, material: u16) {
        let id = self.id_base + self.losses.injected as u32;
        let implicit = self.implicit();
        let ps = &mut self.particles;
        ps.push(x, v, mass, vol0, material);
        let p = ps.len() - 1;
        ps.id[p] = id;
        timestep::refresh_eos_of(ps, &self.cfg.scene.materials, p);
        if implicit {
            // No wave speed limits the step (`refresh_eos_cache`).
            ps.wave_speed[p] = 0.0;
        }
        self.stencils.push(Stencil::default());
        self.fit_scratch(self.particles.len());
        self.losses.injected += 1;
        self.losses.mass_injected += mass;
        let floor = self.cfg.scene.origin[1];
        let brought = 0.5 * mass * v.norm_squared()
            + mass * self.cfg.scene.gravity * (x.y - floor)
            + self.particles.stored_energy[p];
        self.dissipated -= brought;
    }

    /// Each remedy's key and the energy it changed in the last step.
    pub fn remedy_energy(
        &self,
    ) -> impl Iterator<Item = (&'static str, remedies::EnergyChange)> + '_ {
        self.remedies.energy()
    }

    /// Switches to another method mid-run (a restart from a checkpoint with
    /// changed remedies, for counterfactual replay): validated like a new
    /// configuration, the remedies and transfer scratch rebuilt for it.
    pub fn set_method(&mut self, method: Method) -> Result<(), ConfigError> {
        let cfg = SolverConfig {
            method,
            ..self.cfg.clone()
        };
        cfg.validate()?;
        if cfg.method.shape != self.cfg.method.shape {
            return Err(ConfigError {
                key: "method.shape".into(),
                message: "cannot change mid-run (the stencils are the shape's)".into(),
            });
        }
        self.cfg = cfg;
        let n = self.particles.len();
        self.xpic = if self.cfg.method.transfer == TransferKind::Xpic {
            transfers::xpic::Scratch::new(&self.grid, n)
        } else {
            transfers::xpic::Scratch::default()
        };
        self.quadrature = if self.cfg.method.quadrature == QuadratureKind::Mixed {
            stages::quadrature_mixed::Scratch::new(&self.grid)
        } else {
            stages::quadrature_mixed::Scratch::default()
        };
        self.remedies = self.cfg.build_remedies(&self.grid, n);
        self.build_projection(n);
        self.fit_scratch(n);
        if let Some(dt) = self.cfg.method.dt_value {
            self.dt_fixed = dt;
        }
        // The energy as the new method counts it (APIC's affine part).
        self.measure();
        Ok(())
    }

    /// Switches the materials' constants mid-run (the detector's calibration
    /// from one state shared by several methods, one of them at K = inf):
    /// validated with the current method; the same materials, by count and
    /// name, since the particles hold their material by index.
    pub fn set_materials(&mut self, materials: Vec<Material>) -> Result<(), ConfigError> {
        let now = &self.cfg.scene.materials;
        // The particles' masses were set from rho0: it cannot change either.
        let other = |a: &Material, b: &Material| a.name != b.name || a.rho0 != b.rho0;
        if materials.len() != now.len() || materials.iter().zip(now).any(|(a, b)| other(a, b)) {
            return Err(ConfigError {
                key: "materials".into(),
                message: "cannot change mid-run but for their constants other than rho0 (the \
                          particles hold them by index, with masses from rho0)"
                    .into(),
            });
        }
        let mut cfg = self.cfg.clone();
        cfg.scene.materials = materials;
        cfg.validate()?;
        self.cfg = cfg;
        self.refresh_eos_cache();
        self.measure();
        Ok(())
    }

    // The state as the multiphase coupling and the set-up read and change it:
    // through these methods, never through the fields.

    pub(crate) fn grid(&self) -> &Grid {
        &self.grid
    }

    pub(crate) fn grid_mut(&mut self) -> &mut Grid {
        &mut self.grid
    }

    pub(crate) fn particles(&self) -> &Particles {
        &self.particles
    }

    pub(crate) fn particles_mut(&mut self) -> &mut Particles {
        &mut self.particles
    }

    /// This step's stencils (one per particle, after the sort stage).
    pub(crate) fn stencils(&self) -> &[Stencil] {
        &self.stencils
    }

    pub(crate) fn shape(&self) -> &Shape {
        &self.shape
    }

    pub(crate) fn scene(&self) -> &Scene {
        &self.cfg.scene
    }

    /// The size of the step being taken (or last taken).
    pub(crate) fn dt(&self) -> f64 {
        self.dt
    }

    /// The grid with the particles and their stencils, borrowed apart.
    pub(crate) fn grid_and_particles(&mut self) -> (&mut Grid, &mut Particles, &[Stencil], &Shape) {
        (
            &mut self.grid,
            &mut self.particles,
            &self.stencils,
            &self.shape,
        )
    }

    /// Energy that came in from outside this phase (a load's work, drag
    /// from the other phase; negative: it left), booked so that the
    /// budget does not read it as an injection.
    pub(crate) fn book_exchange(&mut self, energy: f64) {
        self.dissipated -= energy;
    }

    /// Energy this phase dissipated (drag taken from it).
    pub(crate) fn book_dissipated(&mut self, energy: f64) {
        self.dissipated += energy;
    }

    /// Particle `p` gives part of its mass and volume away through a drained
    /// wall (keeping its J): what leaves is counted as drained, with its
    /// kinetic and stored energy.
    pub(crate) fn drain_particle(&mut self, p: usize, mass: f64, vol0: f64) {
        let affine_inertia = self.affine_inertia();
        let ps = &mut self.particles;
        let j = if ps.vol0[p] > 0.0 {
            ps.vol[p] / ps.vol0[p]
        } else {
            ps.j[p]
        };
        let ratio = if ps.vol0[p] > 0.0 {
            vol0 / ps.vol0[p]
        } else {
            0.0
        };
        let given = ps.mass[p] - mass;
        self.energy.kinetic -= 0.5 * given * ps.v[p].norm_squared();
        if let Some(d) = affine_inertia {
            self.energy.affine -= 0.5 * given * d * ps.affine[p].norm_squared();
        }
        self.energy.stored -= (1.0 - ratio) * ps.stored_energy[p];
        ps.stored_energy[p] *= ratio;
        self.losses.mass_drained += given;
        ps.mass[p] = mass;
        ps.vol0[p] = vol0;
        ps.vol[p] = j * vol0;
    }

    /// The method, changed by the set-up (the relaxation to equilibrium
    /// runs PIC with a dynamic step, then restores it).
    pub(crate) fn method_mut(&mut self) -> &mut Method {
        &mut self.cfg.method
    }

    pub(crate) fn perturbations_mut(&mut self) -> &mut Vec<Perturb> {
        &mut self.cfg.perturb
    }

    /// The EOS figures (wave speed, stored energy) of every particle again.
    /// Under the pressure-implicit step no wave speed limits the step: zero.
    pub(crate) fn refresh_eos_cache(&mut self) {
        timestep::refresh_eos_cache(&mut self.particles, &self.cfg.scene.materials);
        if self.implicit() {
            self.particles.wave_speed.fill(0.0);
        }
    }

    /// The particles, handed on to another solver (the set-up behind gates).
    pub(crate) fn into_particles(self) -> Particles {
        self.particles
    }

    /// The materials, changed before t = 0 (a mixture's pore fluid).
    pub(crate) fn materials_mut(&mut self) -> &mut [Material] {
        &mut self.cfg.scene.materials
    }

    /// Particles deleted since t = 0 (`on_escape` / `on_inversion = "delete"`).
    pub fn losses(&self) -> Losses {
        self.losses
    }

    /// Particle count at t = 0, deleted particles included.
    pub fn initial_particle_count(&self) -> usize {
        self.n_initial
    }

    /// Energies, blow-out counters and signal speed after a step.
    fn measure(&mut self) {
        let s = &self.cfg.scene;
        let lo = Vec2::from(s.origin);
        let bounds = measure::Bounds {
            lo,
            hi: lo + Vec2::from(s.size),
            periodic: s.periodic,
        };
        let affine_inertia = self.affine_inertia();
        let m = measure::measure(
            &self.particles,
            s.gravity,
            &bounds,
            self.dissipated,
            affine_inertia,
            &mut self.measure_partials,
        );
        self.energy = m.energy;
        self.n_outside = m.n_outside;
        self.n_nonfinite = m.n_nonfinite;
        self.signal_speed = m.signal_speed;
        self.set_axis_signal_speed(m.axis_signal_speed, m.wave_speed);
    }

    /// The per-axis signal speed for the next step: `measured` after a
    /// step, Uintah's initial one before the first.
    fn set_axis_signal_speed(&mut self, measured: f64, wave_speed: f64) {
        (self.axis_signal_speed, self.z_signal_speed) = if self.step == 0 {
            (self.initial_axis_signal_speed(), self.initial_wave_speed())
        } else {
            (measured, wave_speed)
        };
    }

    /// Uintah's first-step wave speed of particle `p`: c = sqrt(K / rho0)
    /// of its material (without the tangent's gamma).
    fn initial_wave_speed_of(&self, p: usize) -> f64 {
        let m = &self.cfg.scene.materials[self.particles.material[p] as usize];
        (m.k / m.rho0).sqrt()
    }

    /// Uintah's first step along z: the largest initial wave speed.
    fn initial_wave_speed(&self) -> f64 {
        (0..self.particles.len())
            .map(|p| self.initial_wave_speed_of(p))
            .fold(0.0, f64::max)
    }

    /// Uintah's first step: the initial wave speed plus the particle's
    /// largest velocity component.
    fn initial_axis_signal_speed(&self) -> f64 {
        let v = &self.particles.v;
        (0..v.len())
            .map(|p| self.initial_wave_speed_of(p) + v[p].x.abs().max(v[p].y.abs()))
            .fold(0.0, f64::max)
    }

    /// APIC's D = d I (m^2) where it is constant (B-splines: h^2/4 quadratic,
    /// h^2/3 cubic): the affine velocity's kinetic energy is then
    /// 1/2 m d |C|^2, and both transfers are projections that cannot add
    /// energy (docs/physics.md section 4). None for every other transfer.
    pub fn affine_inertia(&self) -> Option<f64> {
        if self.cfg.method.transfer != TransferKind::Apic {
            return None;
        }
        let h = self.cfg.scene.cell;
        self.shape.apic_inverse_inertia().map(|inv| h * h / inv)
    }

    /// Recomputes the signal speed after velocities were changed outside a step.
    fn refresh_signal_speed(&mut self) {
        self.signal_speed = timestep::max_signal_speed(&self.particles);
        let wave = par::max(self.particles.len(), |p| self.particles.wave_speed[p]);
        self.set_axis_signal_speed(timestep::max_axis_signal_speed(&self.particles), wave);
    }

    /// Adds the perturbations due in the step being taken (after G2P),
    /// each resolved against the particles now and recorded in `planted`,
    /// then the share of this step of every plant with a duration.
    fn apply_perturbations(&mut self) {
        let step = self.step + 1;
        let now = self.time;
        self.sustained.retain(|s| s.until > now);
        for (entry, pert) in self.cfg.perturb.iter().enumerate() {
            if !pert.due(step, self.time, self.dt) {
                continue;
            }
            let sc = &self.cfg.scene;
            let frame = perturb::Frame {
                origin: sc.origin,
                size: sc.size,
                cell: sc.cell,
                cells: sc.cells(),
            };
            let Some((region, dv)) = pert.resolve(&frame, &self.particles) else {
                continue;
            };
            let (count, j_scale, dx, duration) = match pert.duration {
                Some(duration) => {
                    let from = pert.t.unwrap_or(self.time);
                    let span = (from, from + duration);
                    let s = Sustained::start(entry, (region, dv), span, &self.particles);
                    let count = s.ids.len();
                    self.sustained.push(s);
                    (count, 1.0, Vec2::zeros(), duration)
                }
                None => {
                    let j_scale = pert.j_scale.unwrap_or(1.0);
                    let dx = Vec2::from(pert.dx.unwrap_or([0.0; 2]));
                    let ps = &mut self.particles;
                    let mut count = 0;
                    for p in 0..ps.len() {
                        if perturb::covers(region, ps.x[p]) {
                            self.impulse_kinetic += push(ps, p, dv, self.dt);
                            // The stress follows from J at the next stress update.
                            ps.scale_j(p, j_scale);
                            ps.x[p] += dx;
                            count += 1;
                        }
                    }
                    (count, j_scale, dx, 0.0)
                }
            };
            self.planted.push(Planted {
                entry,
                step,
                t: self.time,
                region,
                dv: [dv.x, dv.y],
                particles: count,
                j_scale,
                dx: [dx.x, dx.y],
                duration,
            });
        }
        self.push_sustained(step);
    }

    /// Each plant with a duration pushes its particles by its share of this
    /// step: a force, part of their force-driven acceleration.
    fn push_sustained(&mut self, step: u64) {
        let (time, dt) = (self.time, self.dt);
        let ps = &mut self.particles;
        for s in self.sustained.iter_mut() {
            let dv = s.share(time, dt) * s.dv;
            if dv == Vec2::zeros() {
                continue;
            }
            for p in 0..ps.len() {
                if s.holds(ps.id[p]) {
                    self.impulse_kinetic += push(ps, p, dv, dt);
                }
            }
            s.last_step = step;
            s.last_dv = dv;
        }
    }

    /// Moves every particle by a seeded offset of at most `relative` h per
    /// axis, as `scene.jitter` does at t = 0: ensemble members of a replay
    /// from one checkpoint.
    pub fn jitter(&mut self, relative: f64, seed: u64) {
        let amplitude = relative * self.cfg.scene.cell;
        scene::jitter_positions(&mut self.particles.x, amplitude, seed);
        self.measure();
    }

    /// Every impulse applied so far, as resolved.
    pub fn planted(&self) -> &[Planted] {
        &self.planted
    }

    /// Runs one stage alone on the current state, with the current time step
    /// (benchmarks; a normal step runs them through `step`).
    pub fn run_stage(&mut self, stage: Stage) -> Result<(), StepError> {
        let mut clock = std::time::Instant::now();
        match stage {
            Stage::Sort => stages::sort::sort(
                &self.particles,
                &mut self.grid,
                &self.shape,
                &mut self.stencils,
                &mut self.bins,
            )?,
            Stage::P2g => stages::scheme::run_p2g_all(self, &mut clock),
            Stage::Grid => stages::scheme::run_grid(self, &mut clock),
            Stage::G2p => stages::scheme::run_g2p(self, &mut clock),
            Stage::Stress => stages::scheme::run_stress(self, &mut clock),
        }
        Ok(())
    }

    /// Time per stage since the last `reset_stage_times`.
    pub fn stage_times(&self) -> StageTimes {
        self.times
    }

    pub fn reset_stage_times(&mut self) {
        self.times = StageTimes::default();
    }

    /// The read-only view the monitor observes.
    pub fn view(&self) -> StateView<'_> {
        view::make(self)
    }

    /// 64-bit hash of the particle state (positions, velocities, affine, F, J, stress).
    pub fn state_hash(&self) -> u64 {
        checkpoint::state_hash(&self.particles)
    }

    /// Serialises the full dynamic state (versioned, checksummed).
    pub fn checkpoint(&self) -> Vec<u8> {
        checkpoint::save(self)
    }

    /// Restores a state saved from a solver built from the same configuration.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), CheckpointError> {
        checkpoint::load(self, bytes)?;
        // Impulses after the restored step have not happened (yet).
        let step = self.step;
        self.planted.retain(|p| p.step <= step);
        // An inflow may have left more particles than there were at t = 0.
        self.fit_scratch(self.particles.len());
        self.refresh_eos_cache();
        self.measure();
        Ok(())
    }
}

/// Adds `dv` to particle `p` as a push over the step `dt` (part of its
/// force-driven acceleration); the kinetic energy it adds.
fn push(ps: &mut Particles, p: usize, dv: Vec2, dt: f64) -> f64 {
    let v = ps.v[p];
    ps.v[p] = v + dv;
    ps.accel[p] += dv / dt;
    0.5 * ps.mass[p] * ((v + dv).norm_squared() - v.norm_squared())
}
