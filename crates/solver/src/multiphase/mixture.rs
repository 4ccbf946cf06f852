//! Two phases as interacting bodies ("multiple velocity fields",
//! docs/physics.md section 6): each phase is a `Solver` with its own
//! particles, material and grid over the same box, stepped by the same
//! stages with one shared time step; between each phase's grid update and
//! its G2P the drag couples the two grids (`coupling::couple`). Phase 0 is the
//! solid, phase 1 the fluid (its volume fraction is the porosity). A single-phase
//! run is a plain `Solver` and is untouched by this.

use crate::checkpoint::{unseal, CheckpointError, Reader, Writer};
use crate::config::Wall;
use crate::multiphase::boundary_inflow::Inflow;
use crate::multiphase::drag::{self, Coupling, Drag, DragUpdate};
use crate::multiphase::pore_pressure::{PoreMode, PorePressure, TopLoad};
use crate::{ConfigError, Energy, Material, Scene, Solver, StepError, Vec2};

const MAGIC: &[u8; 8] = b"KICKMIX2";

pub struct Mixture {
    phases: [Solver; 2],
    drag: Drag,
    scratch: drag::Scratch,
    /// Kinetic energy the drag dissipated since t = 0.
    drag_dissipated: f64,
    last: Coupling,
    /// The solid is a fixed skeleton (its grid velocity held at zero).
    fixed_solid: bool,
    /// The fluid's pressure on the grid (`with_pore_pressure`).
    pore: Option<PorePressure>,
    /// Longitudinal wave speed of the pore pressure (bounds the step).
    pore_wave_speed: f64,
    load: Option<TopLoad>,
    inflow: Option<Inflow>,
    /// Each phase's grid velocity after its own update, before the
    /// exchange, on its active nodes (see `exchange_cross_term`).
    before_exchange: [Vec<Vec2>; 2],
}

/// What a mixture needs of its phases and its drag: one box and grid,
/// the explicit formulation, particle quadrature, no remedy that assumes a
/// phase fills its cells, and a drag in range.
fn check_phases(phases: &[Solver; 2], drag: &Drag) -> Result<(), ConfigError> {
    let (a, b) = (&phases[0].cfg.scene, &phases[1].cfg.scene);
    let same = a.origin == b.origin
        && a.cell == b.cell
        && a.size == b.size
        && a.periodic == b.periodic
        && a.no_slip == b.no_slip;
    if !same {
        return Err(ConfigError {
            key: "scene".into(),
            message: "the phases of a mixture need the same box, cell, periodic axes and walls"
                .into(),
        });
    }
    for p in phases.iter() {
        // A phase fills only its share of each node and of the space.
        p.config().method.remedies.refuse_in_mixture()?;
    }
    if phases
        .iter()
        .any(|p| !crate::shapes::TENSOR_PRODUCT.contains(&p.config().method.shape))
    {
        // Drag and pore pressure spread with per-axis weights.
        return Err(ConfigError {
            key: "method.shape".into(),
            message: "\"cpdi\" is not a tensor product; a mixture's drag and pore pressure need \"linear\" | \"gimp\" | \"cpgimp\" | \"bspline2\" | \"bspline3\"".into(),
        });
    }
    if phases
        .iter()
        .any(|p| p.config().method.formulation != crate::config::Formulation::Explicit)
    {
        // Its pressure solve is for one fluid filling its cells.
        return Err(ConfigError {
            key: "method.formulation".into(),
            message: "\"pressure_implicit\" solves one fluid phase; a mixture needs \"explicit\""
                .into(),
        });
    }
    if phases
        .iter()
        .any(|p| p.config().method.quadrature == crate::config::QuadratureKind::Mixed)
    {
        // Its full cells are judged by one phase's density.
        return Err(ConfigError {
            key: "method.quadrature".into(),
            message:
                "\"mixed\" is for a single phase: in a mixture each phase fills only part of a cell"
                    .into(),
        });
    }
    if !(drag.coefficient >= 0.0 && drag.coefficient.is_finite()) {
        return Err(ConfigError {
            key: "drag.coefficient".into(),
            message: format!("{} is not a finite number >= 0", drag.coefficient),
        });
    }
    if drag.model.is_particle_based() && drag.update != DragUpdate::Explicit {
        return Err(ConfigError {
            key: "drag.update".into(),
            message: format!(
                "{:?} with the particle-based model {:?} (allowed: explicit)",
                drag.update, drag.model
            ),
        });
    }
    if let Some(n0) = drag.kozeny_carman {
        if !(n0 > 0.0 && n0 < 1.0) {
            return Err(ConfigError {
                key: "drag.kozeny_carman".into(),
                message: format!("reference porosity {n0} is outside (0, 1)"),
            });
        }
    }
    Ok(())
}

impl Mixture {
    /// Two phases over the same box and grid (`scene.origin`, `cell`, `size`,
    /// `periodic` alike), both at t = 0.
    pub fn new(phases: [Solver; 2], drag: Drag) -> Result<Self, ConfigError> {
        check_phases(&phases, &drag)?;
        let scratch = drag::Scratch::new(&phases[0].grid);
        let before_exchange = [0, 1].map(|k| vec![Vec2::zeros(); phases[k].grid.vel_new.len()]);
        let mut mixture = Mixture {
            before_exchange,
            phases,
            drag,
            scratch,
            drag_dissipated: 0.0,
            fixed_solid: false,
            pore: None,
            pore_wave_speed: 0.0,
            load: None,
            inflow: None,
            last: Coupling {
                stable_dt: f64::INFINITY,
                ..Coupling::default()
            },
        };
        if drag.update == DragUpdate::Explicit {
            mixture.last.stable_dt = mixture.probe_stable_dt();
        }
        Ok(mixture)
    }

    /// The explicit limit of the initial state, so that the first step obeys
    /// it too: a coupling of copies of the phases (once, at set-up).
    fn probe_stable_dt(&mut self) -> f64 {
        let dt = self.phases[0].next_dt().min(self.phases[1].next_dt());
        let [mut a, mut b] = self.phases.clone();
        if a.begin_step(dt).is_err() || b.begin_step(dt).is_err() {
            return f64::INFINITY;
        }
        super::coupling::couple(&mut a, &mut b, &self.drag, &mut self.scratch, dt, false).stable_dt
    }

    /// Holds the solid (phase 0) as a fixed porous skeleton: its grid
    /// velocity is zero every step, so its particles stay where they are,
    /// and the fluid's drag acts against it as against an infinite mass.
    pub fn fix_solid(mut self) -> Self {
        self.fixed_solid = true;
        self
    }

    /// Moves the fluid's pressure to the grid (`pore_pressure.rs`): the
    /// fluid's material becomes the pore fluid's EOS, its particles' own EOS
    /// pressure is switched off (K = 0 there; viscosity stays), and the step
    /// stays below cfl h / c with c^2 = K_f / rho_f + K_f (1 - n) / (n rho_s).
    pub fn with_pore_pressure(mut self) -> Self {
        let [solid, fluid] = &mut self.phases;
        let scene = fluid.scene();
        let body = &scene.bodies[0];
        let index = scene.material_index(body).expect("validated");
        let pore_fluid = scene.materials[index].clone();
        let n = body.fraction;
        let solid_scene = solid.scene();
        let rho_s = solid_scene
            .material_index(&solid_scene.bodies[0])
            .map_or(pore_fluid.rho0, |m| solid_scene.materials[m].rho0);
        let k_f = pore_fluid.k;
        self.pore_wave_speed = (k_f / pore_fluid.rho0 + k_f * (1.0 - n) / (n * rho_s)).sqrt();
        for m in fluid.materials_mut().iter_mut() {
            m.k = 0.0;
        }
        fluid.refresh_eos_cache();
        let gravity = fluid.scene().gravity;
        self.pore = Some(PorePressure::new(
            fluid.grid(),
            pore_fluid,
            PoreMode::Balance,
            gravity,
        ));
        self
    }

    /// Node-averaged pore pressure (`pore_pressure.rs`, `average_nodes`):
    /// each node's pressure the [1 2 1] / 4 average of its neighbours along
    /// each axis, which removes the node-to-node mode of the volume balance.
    /// Needs the pore pressure (`with_pore_pressure`).
    pub fn with_pore_node_average(mut self) -> Result<Self, ConfigError> {
        match self.pore.as_mut() {
            Some(pore) if pore.mode == PoreMode::Balance => {
                pore.node_average = true;
                Ok(self)
            }
            _ => Err(ConfigError {
                key: "drag.pore_node_average".into(),
                message: "it needs drag.pore_pressure = true".into(),
            }),
        }
    }

    /// The volume constraint n_s + n_f <= 1 (`PoreMode::Constraint`): where
    /// grains and water overfill a node, a pressure K_f times the excess
    /// pushes them apart; the fluid keeps its own EOS. The step stays below
    /// cfl h / c with c^2 = (K_f / rho_f) (1 + 1 / n), n = 1 - n_s the
    /// skeleton's porosity (both pressures on water that fills only its pores).
    pub fn with_volume_constraint(mut self) -> Self {
        let [solid, fluid] = &self.phases;
        let scene = fluid.scene();
        let index = scene.material_index(&scene.bodies[0]).expect("validated");
        let water = scene.materials[index].clone();
        let porosity = (1.0 - solid.scene().bodies[0].fraction).max(1e-3);
        self.pore_wave_speed = (water.k / water.rho0 * (1.0 + 1.0 / porosity)).sqrt();
        let gravity = scene.gravity;
        self.pore = Some(PorePressure::new(
            fluid.grid(),
            water,
            PoreMode::Constraint,
            gravity,
        ));
        self
    }

    /// Drained walls (docs/physics.md section 6): the pore pressure is
    /// `pressure` (Pa) on each given wall, and the wall is open to both
    /// phases (no mirror; what crosses flows out and is counted as outflow).
    /// Needs the pore pressure (`with_pore_pressure`); see `check_drained`.
    pub fn with_drained(mut self, walls: &[Wall], pressure: f64) -> Result<Self, ConfigError> {
        let balance = self.pore_fluid().is_some();
        check_drained(&self.phases[0].cfg.scene, walls, pressure, balance)?;
        let pore = self
            .pore
            .as_mut()
            .expect("checked: the pore pressure is on");
        let open = Wall::mask(walls);
        for (axis, sides) in open.iter().enumerate() {
            for (side, &is_open) in sides.iter().enumerate() {
                if is_open {
                    pore.drained[axis][side] = Some(pressure);
                }
            }
        }
        for s in &mut self.phases {
            s.open_sides(open);
        }
        Ok(self)
    }

    /// Inflow walls (docs/physics.md section 6, `boundary_inflow.rs`): the
    /// fluid enters through each at `velocity` (m/s, into the box), a row of
    /// particles at a time; the wall is open to the fluid and a wall to the
    /// solid. Needs the pore pressure; see `check_inflow`.
    pub fn with_inflow(mut self, walls: &[Wall], velocity: f64) -> Result<Self, ConfigError> {
        let balance = self.pore_fluid().is_some();
        let drained = self.pore.as_ref().map_or([[false; 2]; 2], |p| {
            p.drained.map(|sides| sides.map(|d| d.is_some()))
        });
        check_inflow(&self.phases[1].cfg.scene, walls, velocity, balance, drained)?;
        if walls.is_empty() {
            return Ok(self);
        }
        let fluid = &mut self.phases[1];
        let inflow = Inflow::new(fluid, walls, velocity).ok_or_else(|| ConfigError {
            key: "drag.inflow".into(),
            message: "the fluid holds no particles to copy the inflow's from".into(),
        })?;
        let mut open = fluid.grid().open;
        for (axis, sides) in inflow.mask().iter().enumerate() {
            for (side, &on) in sides.iter().enumerate() {
                open[axis][side] |= on;
            }
        }
        fluid.open_sides(open);
        fluid.reserve_particles(inflow.expected_entries(fluid));
        self.inflow = Some(inflow);
        Ok(self)
    }

    /// A downward traction q (Pa) on the solid's top surface, ramped over `ramp` s.
    pub fn with_top_load(mut self, traction: f64, ramp: f64) -> Self {
        self.load = Some(TopLoad::new(&self.phases[0], traction, ramp));
        self
    }

    /// The pore pressure's EOS (the fluid's material as given), when on.
    pub fn pore_fluid(&self) -> Option<&Material> {
        self.pore
            .as_ref()
            .filter(|p| p.mode == PoreMode::Balance)
            .map(|p| &p.fluid)
    }

    pub fn phase(&self, k: usize) -> &Solver {
        &self.phases[k]
    }

    pub fn time(&self) -> f64 {
        self.phases[0].time()
    }

    /// The phases' smallest step; under the explicit drag also below the
    /// stability limit 2 / k of the last coupling (of the initial state at
    /// the first step; nodal masses and volumes change little in a step),
    /// with the phases' CFL number as safety.
    pub fn next_dt(&self) -> f64 {
        let mut dt = self.phases[0].next_dt().min(self.phases[1].next_dt());
        if self.pore.is_some() {
            let s = &self.phases[0];
            dt = dt.min(s.config().method.cfl * s.scene().cell / self.pore_wave_speed);
        }
        match self.drag.update {
            DragUpdate::Explicit => dt.min(self.phases[0].cfg.method.cfl * self.last.stable_dt),
            DragUpdate::Implicit | DragUpdate::Exponential => dt,
        }
    }

    /// One step of `next_dt`, clamped to land on t_end.
    pub fn step(&mut self) -> Result<(), StepError> {
        let mut dt = self.next_dt();
        let remaining = self.phases[0].cfg.scene.t_end - self.time();
        if remaining > 0.0 && dt > remaining {
            dt = remaining;
        }
        self.step_with_dt(dt)
    }

    /// One step of a given size: both phases to their grid update, the drag,
    /// then both phases on from the grid.
    pub fn step_with_dt(&mut self, dt: f64) -> Result<(), StepError> {
        let t = self.time();
        let [a, b] = &mut self.phases;
        if let Some(pore) = self.pore.as_mut() {
            pore.drain_outflow(a);
            pore.drain_outflow(b);
        }
        a.begin_step(dt)?;
        b.begin_step(dt)?;
        for (s, v) in [&*a, &*b].into_iter().zip(&mut self.before_exchange) {
            for &n in &s.grid().active {
                v[n as usize] = s.grid().vel_new[n as usize];
            }
        }
        // External and pore forces first (each phase's budget books the
        // energy they give as exchange, like the drag's), then the drag.
        if let Some(load) = self.load.as_mut() {
            if !self.fixed_solid {
                let energy = load.apply(a, t, dt);
                a.book_exchange(energy);
            }
        }
        if let Some(pore) = self.pore.as_mut() {
            let gained = pore.apply(a, b, dt, self.fixed_solid, self.inflow.as_ref());
            let energy = gained[0];
            a.book_exchange(energy);
            let energy = gained[1];
            b.book_exchange(energy);
        }
        self.last =
            super::coupling::couple(a, b, &self.drag, &mut self.scratch, dt, self.fixed_solid);
        self.drag_dissipated += self.last.dissipated;
        if let Some(inflow) = self.inflow.as_mut() {
            // The wall's work on the fluid is exchange, like the pore force's.
            let energy = inflow.impose(b);
            b.book_exchange(energy);
        }
        for (s, v) in [&mut *a, &mut *b].into_iter().zip(&self.before_exchange) {
            let energy = exchange_cross_term(s.grid(), v);
            s.book_dissipated(energy);
        }
        a.finish_step();
        b.finish_step();
        if let Some(inflow) = self.inflow.as_mut() {
            if inflow.enter(b, dt) > 0 {
                // The step's energies then count the rows that entered.
                b.measure();
            }
        }
        if let Some(pore) = &self.pore {
            pore.show_on(b);
        }
        Ok(())
    }

    /// What the last step's coupling did.
    pub fn last_coupling(&self) -> Coupling {
        self.last
    }

    /// Both phases' energies summed. Each phase's `dissipated` holds the
    /// kinetic energy the drag took from it (so each phase's budget closes
    /// alone, and a monitor can watch each); the sum holds the drag's
    /// dissipation.
    pub fn energy(&self) -> Energy {
        let (a, b) = (self.phases[0].energy(), self.phases[1].energy());
        Energy {
            kinetic: a.kinetic + b.kinetic,
            affine: a.affine + b.affine,
            gravitational: a.gravitational + b.gravitational,
            stored: a.stored + b.stored,
            dissipated: a.dissipated + b.dissipated,
        }
    }

    pub fn drag_dissipated(&self) -> f64 {
        self.drag_dissipated
    }

    /// 64-bit hash of both phases' particle states.
    pub fn state_hash(&self) -> u64 {
        let mut h = crate::checkpoint::Hasher::default();
        for s in &self.phases {
            h.word(s.state_hash());
        }
        h.finish()
    }

    /// Both phases' checkpoints and the mixture's own state (the drag's
    /// dissipation and the last coupling's explicit limit, which sets the
    /// next step), sealed with a checksum.
    pub fn checkpoint(&self) -> Vec<u8> {
        let mut w = Writer(MAGIC.to_vec());
        for s in &self.phases {
            w.bytes(&s.checkpoint());
        }
        w.f64(self.drag_dissipated);
        w.f64(self.last.stable_dt);
        if let Some(inflow) = &self.inflow {
            inflow.save(&mut w);
        }
        w.seal()
    }

    /// Restores a checkpoint of a mixture built from the same configurations.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), CheckpointError> {
        let mut r = Reader(unseal(bytes, MAGIC)?);
        let (a, b) = (r.bytes()?, r.bytes()?);
        let (dissipated, stable_dt) = (r.f64()?, r.f64()?);
        if let Some(inflow) = self.inflow.as_mut() {
            inflow.load(&mut r)?;
        }
        r.finish()?;
        self.phases[0].restore(a)?;
        self.phases[1].restore(b)?;
        self.drag_dissipated = dissipated;
        self.last = Coupling {
            stable_dt,
            ..Coupling::default()
        };
        Ok(())
    }

    /// Total particle momentum of both phases.
    pub fn momentum(&self) -> Vec2 {
        self.phases
            .iter()
            .map(|s| {
                let p = s.particles();
                p.v.iter()
                    .zip(&p.mass)
                    .fold(Vec2::zeros(), |sum, (v, m)| sum + *m * v)
            })
            .fold(Vec2::zeros(), |a, b| a + b)
    }
}

/// The exchange's work is booked above stage by stage as the kinetic
/// energy each stage adds to v^{n+1}; those sum to the whole exchange's
/// dv_ext . (v_a + v_f) / 2 per unit mass, v_a the velocity after the
/// phase's own update and v_f the final one. Its work over the step is
/// dv_ext . (v^n + v_f) / 2, the rule under which the step's kinetic energy
/// splits exactly between the phase's own forces and the exchange. The two
/// differ by dv_ext . dv_own / 2 (dv_own = v_a - v^n): second order in dt,
/// yet under a load that the stresses nearly balance every step it sums to
/// the order of the load's own work, which the monitor then reads as an
/// injection. This returns that difference, to add to `dissipated`.
fn exchange_cross_term(g: &crate::grid::Grid, before: &[Vec2]) -> f64 {
    g.active
        .iter()
        .map(|&n| {
            let n = n as usize;
            let (own, ext) = (before[n] - g.vel[n], g.vel_new[n] - before[n]);
            0.5 * g.mass_raw[n] * own.dot(&ext)
        })
        .sum()
}

/// Whether drained walls at `pressure` fit the scene: the pore pressure on
/// (`pore_pressure`), each wall on a non-periodic axis and not also no-slip,
/// a finite pressure. The study file asks the same before a run.
pub fn check_drained(
    scene: &Scene,
    walls: &[Wall],
    pressure: f64,
    pore_pressure: bool,
) -> Result<(), ConfigError> {
    check_walls(
        "drag.drained",
        "a drained wall prescribes the pore pressure",
        scene,
        walls,
        pore_pressure,
    )?;
    if !walls.is_empty() && !pressure.is_finite() {
        return Err(ConfigError {
            key: "drag.drained_pressure".into(),
            message: format!("{pressure} is out of range (allowed: finite, Pa)"),
        });
    }
    Ok(())
}

/// Whether inflow walls at `velocity` fit the scene: the pore pressure on
/// (`pore_pressure`), each wall on a non-periodic axis, neither no-slip nor
/// drained (`drained` [axis][low, high]), a finite velocity > 0. The study
/// file asks the same before a run.
pub fn check_inflow(
    scene: &Scene,
    walls: &[Wall],
    velocity: f64,
    pore_pressure: bool,
    drained: [[bool; 2]; 2],
) -> Result<(), ConfigError> {
    check_walls(
        "drag.inflow",
        "an inflow wall's entering water takes the grid's pore pressure",
        scene,
        walls,
        pore_pressure,
    )?;
    if walls.is_empty() {
        return Ok(());
    }
    let inflow = Wall::mask(walls);
    if (0..2).any(|axis| (0..2).any(|side| inflow[axis][side] && drained[axis][side])) {
        return Err(ConfigError {
            key: "drag.inflow".into(),
            message: "a wall is both drained and an inflow (allowed: one of them)".into(),
        });
    }
    if !(velocity > 0.0 && velocity.is_finite()) {
        return Err(ConfigError {
            key: "drag.inflow_velocity".into(),
            message: format!("{velocity} is out of range (allowed: finite, > 0 m/s into the box)"),
        });
    }
    Ok(())
}

/// What drained and inflow walls both need: the pore pressure on (`why`
/// says what for), each wall on a non-periodic axis and not also no-slip;
/// refused under `key`.
fn check_walls(
    key: &str,
    why: &str,
    scene: &Scene,
    walls: &[Wall],
    pore_pressure: bool,
) -> Result<(), ConfigError> {
    let err = |message: String| {
        Err(ConfigError {
            key: key.into(),
            message,
        })
    };
    if walls.is_empty() {
        return Ok(());
    }
    if !pore_pressure {
        return err(format!("{why}: it needs drag.pore_pressure = true"));
    }
    for w in walls {
        if scene.periodic[w.axis()] {
            return err(format!(
                "{w:?} is on a periodic axis (scene.periodic): there is no wall there"
            ));
        }
        if scene.no_slip.contains(w) {
            return err(format!(
                "{w:?} is also in scene.no_slip (allowed: one of them)"
            ));
        }
    }
    Ok(())
}
