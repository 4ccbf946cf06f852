//! The monitor: its state and the step it observes. The detector, the
//! event clustering and the energy arithmetic are its parts (their files).

use crate::checkerboard::{self, CellField};
use crate::checkerboard_fields::FieldCheckerboard;
use crate::clustering::{Cluster, UNLABELLED};
use crate::config::MonitorConfig;
use crate::detector::{Candidate, Scan};
use crate::energy_budget::{Entry, Ledger, TERMS};
use crate::energy_terms::EnergyStep;
use crate::events::Event;
use crate::front::{self, Front};
use crate::geometry::Geometry;
use crate::hydrostatic::Hydrostatic;
use crate::jump::{JumpRule, Jumps, Margin};
use crate::particle_history::ParticleHistory;
use crate::remedy_booking::RemedyBooking;
use crate::step_history::StepHistory;
use crate::step_report::{FieldMetrics, StepReport};
use solver::StateView;

#[derive(Clone, Debug)]
pub struct Monitor {
    pub cfg: MonitorConfig,
    pub geom: Geometry,
    /// Force-driven |a_p| per particle, filled only on steps that need it (`fill_accel`).
    pub(crate) accel: Vec<f64>,
    pub(crate) accel_step: Option<u64>,
    pub(crate) flagged: Vec<Candidate>,
    pub(crate) jumps: Jumps,
    pub(crate) history: ParticleHistory,
    /// The energy ledger (the injection window and the run's credited gain),
    /// each booked term's cumulative net removal, gravity's stepping term
    /// booked so far, and the potential energy at the last observation.
    pub(crate) ledger: Ledger,
    pub(crate) ledger_terms: [f64; TERMS],
    pub(crate) gravity_stepping: f64,
    /// Of it, the advection's part (a ledger term).
    pub(crate) advection_stepping: f64,
    pub(crate) prev_potential: Option<f64>,
    /// The particle set changed at this observation (deletions, inflow, a restore).
    pub(crate) ids_changed: bool,
    pub(crate) cell_label: Vec<u32>,
    pub(crate) touched: Vec<u32>,
    pub(crate) stack: Vec<u32>,
    pub(crate) clusters: Vec<Cluster>,
    pub(crate) event_mark: Vec<u32>,
    pub(crate) events: Vec<Event>,
    pub(crate) field: CellField,
    pub(crate) field_checkerboard: FieldCheckerboard,
    pub(crate) hydro: Hydrostatic,
    pub(crate) front: Front,
    pub(crate) report: StepReport,
    pub(crate) events_dropped: u64,
    /// Courant and nodal advective numbers of the last steps (cause evidence).
    pub(crate) steps: StepHistory,
    /// The shape's critical Courant number.
    pub(crate) critical_courant: f64,
    /// Time of the previous observation (particle activity is judged against it).
    pub(crate) prev_time: f64,
    /// Particle ids per slot as of the last observation (deletions compact the history).
    pub(crate) ids: Vec<u32>,
    /// Set by a restore: the next observation takes the solver's ids as the
    /// restored histories' (not saved: the solver's checkpoint holds them).
    pub(crate) adopt_ids: bool,
    /// Mass at t = 0, deleted particles included.
    pub(crate) initial_mass: f64,
    /// Transfer loss accumulated since t = 0 (see `StepReport::transfer_loss`).
    pub(crate) transfer_loss: f64,
    /// Each remedy's energy booked since t = 0.
    pub(crate) booking: RemedyBooking,
    /// E at t = 0 (the budgets' drifts are measured from it).
    pub(crate) initial_total: f64,
    /// The hallmark log (`hallmark_log`).
    pub(crate) hallmark_rows: Vec<crate::hallmark_log::HallmarkRow>,
}

/// Nodes lighter than this fraction of a full cell's mass rho0 h^2 are left
/// out of the nodal advective number.
pub const ADVECTION_MIN_MASS: f64 = 1e-3;

/// The critical effective Courant number of a shape family (docs/physics.md section 4b).
pub fn critical_courant(shape: solver::ShapeKind) -> f64 {
    match shape {
        solver::ShapeKind::Linear
        | solver::ShapeKind::Gimp
        | solver::ShapeKind::Cpgimp
        | solver::ShapeKind::Cpdi => 1.0,
        solver::ShapeKind::Bspline2 => 1.7,
        solver::ShapeKind::Bspline3 => 1.9,
    }
}

/// The grid's figures of a step (`Monitor::grid_figures`).
struct GridFigures {
    min_node_mass_ratio: f64,
    max_node_accel: f64,
    node_advection: f64,
}

impl Monitor {
    /// A monitor for the state `v` (the solver at t = 0 or a restart, which
    /// then restores the monitor's state).
    pub fn new(cfg: MonitorConfig, v: &StateView) -> Self {
        let geom = Geometry::from_scene(v.scene);
        let n = v.x.len();
        let cells = geom.cell_count();
        let mut history = ParticleHistory::new(n);
        // A body with an initial velocity is moving, not spiking, at step 1.
        let (quiet2, quiet_rate) = (cfg.quiet_speed * cfg.quiet_speed, cfg.quiet_rate);
        for p in 0..n {
            let (speed2, rate) = (v.v[p].norm_squared(), v.dev_rate[p]);
            let active = speed2 > quiet2 || rate > quiet_rate;
            history.start(p, v.time, active, rate);
        }
        if cfg.hallmark_log {
            let at = |f: f64, p: usize| {
                v.v[p].norm_squared() > quiet2 * f * f || v.dev_rate[p] > quiet_rate
            };
            history = history.with_levels(v.time, at);
        }
        Monitor {
            accel: vec![0.0; n],
            accel_step: None,
            flagged: Vec::with_capacity(n),
            jumps: Jumps::default(),
            history,
            ledger: Ledger::new(
                cfg.injection_seconds,
                Entry {
                    t: v.time,
                    base: v.energy.total(),
                    terms: [0.0; TERMS],
                },
            ),
            ledger_terms: [0.0; TERMS],
            gravity_stepping: 0.0,
            advection_stepping: 0.0,
            prev_potential: Some(v.energy.gravitational),
            ids_changed: false,
            cell_label: vec![UNLABELLED; cells],
            touched: Vec::with_capacity(cells),
            stack: Vec::with_capacity(cells),
            clusters: Vec::with_capacity(64),
            event_mark: vec![0; v.n_initial],
            events: Vec::new(),
            field: CellField::new(&geom),
            field_checkerboard: FieldCheckerboard::default(),
            hydro: Hydrostatic::new(&geom, n),
            front: Front::new(&geom),
            report: StepReport::default(),
            events_dropped: 0,
            steps: StepHistory::default(),
            critical_courant: critical_courant(v.shape),
            prev_time: v.time,
            ids: v.id.to_vec(),
            adopt_ids: false,
            initial_mass: v.mass.iter().sum::<f64>() + v.losses.mass(),
            transfer_loss: 0.0,
            booking: RemedyBooking::default(),
            initial_total: v.energy.total_with_affine(),
            hallmark_rows: vec![],
            geom,
            cfg,
        }
    }

    pub fn events(&self) -> &[Event] {
        &self.events
    }

    pub fn events_mut(&mut self) -> &mut [Event] {
        &mut self.events
    }

    /// Event openings refused because `max_events` was reached (an episode
    /// flagged on several steps counts once per step).
    pub fn events_dropped(&self) -> u64 {
        self.events_dropped
    }

    /// Mass at t = 0, deleted particles included.
    pub fn initial_mass(&self) -> f64 {
        self.initial_mass
    }

    /// The booked terms the method has, and each one's cumulative net
    /// removal so far (J/m; negative: it added energy, net).
    pub fn booked_terms(
        &self,
    ) -> (
        crate::energy_budget::Terms,
        &[f64; crate::energy_budget::TERMS],
    ) {
        (self.ledger.present, &self.ledger_terms)
    }

    pub fn report(&self) -> &StepReport {
        &self.report
    }

    /// Gravity used to scale accelerations (9.81 when the scene has none).
    pub(crate) fn g_ref(&self) -> f64 {
        if self.geom.gravity > 0.0 {
            self.geom.gravity
        } else {
            9.81
        }
    }

    /// Force-driven |a_p| of every particle for this step (once).
    pub(crate) fn fill_accel(&mut self, v: &StateView) {
        if self.accel_step == Some(v.step) {
            return;
        }
        self.accel.resize(v.accel.len(), 0.0);
        for (a, acc) in self.accel.iter_mut().zip(v.accel) {
            *a = acc.norm();
        }
        self.accel_step = Some(v.step);
    }

    /// Observes the state after a step.
    pub fn observe(&mut self, v: &StateView) -> &StepReport {
        let g = self.g_ref();
        let dt = v.dt.max(1e-300);
        self.follow_ids(v);
        let scan = self.scan_particles(v, dt);
        self.prev_time = v.time;
        let max_jump = self.flag_jumps(v);
        let energy = self.book_energy(v, &scan, self.geom.gravity);
        let grid = self.grid_figures(v);
        // Before any event opens: its window before onset includes this step.
        self.steps.push(v.time, v.courant, grid.node_advection);
        let opened_before = self.events.len();
        if !self.flagged.is_empty() {
            self.cluster_flagged(v, g);
        }
        let gainer = scan.gain_max.1;
        self.check_energy_injection(v, g, energy.window.gain, energy.floor, gainer);
        if !v.culled.is_empty() {
            self.culled_events(v, g);
        }
        let blow_out = self.check_blow_out(v, g, scan.max_speed2.sqrt(), &scan);
        if blow_out.is_some() {
            self.stopped(v);
        }
        self.track_injected_energy(v, energy.window);
        let opened = self.events.len() - opened_before;
        self.report = self.step_report(v, g, &scan, &energy, &grid, max_jump, opened, blow_out);
        &self.report
    }

    /// The velocity-jump rule's margins of these particles in the step last
    /// observed (the calibration reads how far a twin's particles stood
    /// from the threshold where a patch is planted).
    pub fn jump_margins(&mut self, v: &StateView, particles: &[usize]) -> Vec<Option<Margin>> {
        let rule = self.jump_rule();
        particles
            .iter()
            .map(|&p| self.jumps.margin(&self.geom, v, &rule, p))
            .collect()
    }

    /// The velocity-jump rule's thresholds.
    pub(crate) fn jump_rule(&self) -> JumpRule {
        JumpRule {
            speed: self.cfg.jump_speed,
            z: self.cfg.jump_z,
            ring: self.cfg.jump_ring_cells,
            calm_seconds: self.cfg.calm_seconds,
            calm_change: self.cfg.calm_change,
            windowed: self.cfg.windowed_jumps,
            quiet_speed: self.cfg.quiet_speed,
            moving: self.cfg.moving_rule(),
            per_step: self.cfg.step_jumps,
        }
    }

    /// Follows the solver's particle ids: after a restore, and after
    /// deletions or inflow, the histories keep their particles.
    fn follow_ids(&mut self, v: &StateView) {
        self.ids_changed = false;
        if std::mem::take(&mut self.adopt_ids) && v.id.len() == self.history.len() {
            // Restored from a checkpoint taken after deletions.
            self.ids.clear();
            self.ids.extend_from_slice(v.id);
        }
        if v.id.len() != self.ids.len() || v.id.last() != self.ids.last() {
            // The solver deleted particles, or some entered through an
            // inflow wall: keep the history of the others.
            self.history.compact(&self.ids, v.id, self.prev_time);
            self.ids_changed = true;
            self.ids.clear();
            self.ids.extend_from_slice(v.id);
            let ids = v.id.last().map_or(0, |&id| id as usize + 1);
            if ids > self.event_mark.len() {
                self.event_mark.resize(ids, 0);
            }
        }
    }

    /// This step's report from its parts.
    #[allow(clippy::too_many_arguments)]
    fn step_report(
        &self,
        v: &StateView,
        g: f64,
        scan: &Scan,
        energy: &EnergyStep,
        grid: &GridFigures,
        max_jump: f64,
        events_opened: usize,
        blow_out: Option<String>,
    ) -> StepReport {
        let undefined = |x: f64| if energy.budget_defined { x } else { f64::NAN };
        let booking = &self.booking;
        StepReport {
            step: v.step,
            energy_injected: undefined(energy.run_gain),
            injection_window: undefined(energy.window.gain),
            injection_floor: energy.floor,
            gravity_stepping: self.gravity_stepping,
            transfer_loss: self.transfer_loss + booking.in_transfer_loss(),
            remedy_dissipated: booking.dissipated(),
            remedy_injected: booking.injected(),
            booked: booking.booked,
            budget_drift: energy.budget - booking.injected() - self.initial_total,
            budget_drift_unbooked: energy.budget_unbooked - self.initial_total,
            packing_error: v.projection.map(|p| p.stats.packing_error),
            solver_iterations: v.projection.map(|p| p.stats.iterations as f64),
            solver_residual: v.projection.map(|p| p.stats.residual),
            projection_dissipated: v.projection.map(|p| p.stats.dissipated_projection),
            hourglass_dissipated: v.projection.map(|p| p.stats.dissipated_hourglass),
            detector_total: energy.base,
            max_accel_g: scan.max_a2.sqrt() / g,
            max_transfer_jump: scan.max_jump2.sqrt(),
            max_jump,
            max_speed: scan.max_speed2.sqrt(),
            j_min: scan.j_min,
            j_max: scan.j_max,
            min_node_mass_ratio: grid.min_node_mass_ratio,
            max_node_accel_g: grid.max_node_accel / g,
            node_advection: grid.node_advection,
            ringing_energy: v.ke_particles_p2g - v.ke_grid_p2g,
            n_outside: v.n_outside,
            n_nonfinite: v.n_nonfinite,
            particles_lost: v.losses.count(),
            mass_lost_fraction: v.losses.mass() / self.initial_mass,
            n_flagged: self.flagged.len(),
            events_opened,
            blow_out,
            ..StepReport::of_state(v)
        }
    }

    /// Over the active grid nodes: the smallest nodal mass over rho0 h^2 (0
    /// without any), the largest nodal acceleration, and the advective
    /// number of the nodes with at least `ADVECTION_MIN_MASS` rho0 h^2.
    fn grid_figures(&self, v: &StateView) -> GridFigures {
        let h2 = self.geom.rho0 * self.geom.cell * self.geom.cell;
        let (mut min_mass, mut max_node_a, mut max_speed2) = (f64::INFINITY, 0.0f64, 0.0f64);
        for &node in v.grid.active {
            let m = v.grid.mass[node as usize];
            if m > 0.0 {
                min_mass = min_mass.min(m / h2);
                max_node_a = max_node_a.max(v.grid.acceleration[node as usize].norm());
                // A node in a shape's far tail (1e-13 of a cell under B-splines)
                // can take any speed and moves no particle: not advection.
                if m >= ADVECTION_MIN_MASS * h2 {
                    max_speed2 = max_speed2.max(v.grid.velocity[node as usize].norm_squared());
                }
            }
        }
        GridFigures {
            min_node_mass_ratio: if min_mass.is_finite() { min_mass } else { 0.0 },
            max_node_accel: max_node_a,
            node_advection: max_speed2.sqrt() * v.dt / v.grid.h,
        }
    }

    /// Checkerboard, hydrostatic departure and surge front of the current state.
    pub fn field_metrics(&mut self, v: &StateView) -> FieldMetrics {
        let scale = v.materials[0].rho0 * self.g_ref() * v.grid.h;
        let geom = &self.geom;
        self.field.accumulate(geom, v.x, v.pressure);
        let checkerboard_means = checkerboard::index(geom, &self.field);
        let checkerboard_nodal = self.field_checkerboard.nodal(v, geom.cells, scale);
        let checkerboard_cell = self.field_checkerboard.cell(v, geom.cells, scale);
        let pressure_spread = checkerboard::intra_cell_spread(geom, &self.field, v.x, v.pressure);
        self.hydro.compute(geom, v.x, v.mass, v.accel);
        let dep = self.hydro.departure(geom, v.volume, v.pressure);
        let front_x = self.front.position(geom, &self.field);
        let (front_z, front_t) = match front_x {
            Some(x) => {
                let (z, t) = front::dimensionless(geom, x, v.time);
                (Some(z), t)
            }
            None => (None, front::dimensionless(geom, 0.0, v.time).1),
        };
        FieldMetrics {
            checkerboard_means,
            checkerboard_nodal,
            checkerboard_cell,
            pressure_spread,
            hydro_rel_rms: dep.rel_rms,
            hydro_floor_rel_rms: dep.floor_rel_rms,
            hydro_excess_rel_rms: dep.excess_rel_rms,
            hydro_max: dep.max,
            hydro_unexplained_rel_rms: dep.unexplained_rel_rms,
            front_x,
            front_z,
            front_t,
        }
    }
}
