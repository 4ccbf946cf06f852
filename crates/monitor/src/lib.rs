//! kick's monitor: watches every step through the solver's read-only
//! [`StateView`] for kinetic-energy spikes, local acceleration outliers,
//! energy injection and blow-out, and logs each kick as an [`Event`] with its
//! step, region and hallmark flags. Field metrics (checkerboard, hydrostatic
//! departure, surge front) are computed on demand: at output rows and when an
//! event opens. Definitions: docs/physics.md section 4.

pub mod accel_outliers;
pub mod cells;
pub mod checkerboard;
pub mod checkerboard_fields;
pub mod config;
pub mod energy_budget;
pub mod events;
pub mod front;
pub mod geometry;
pub mod hydrostatic;
pub mod mechanisms;
pub mod particle_history;
pub mod remedy_booking;
pub mod rest_field;
pub mod ringing_growth;
mod state;
pub mod step_history;

pub use config::MonitorConfig;
pub use events::{
    Cause, CellRange, DeformedBy, Event, EventKind, Evidence, Outcome, Region, Rule, Rules,
};
pub use geometry::Geometry;

use accel_outliers::WindowStats;
use cells::CellBins;
use checkerboard::CellField;
use checkerboard_fields::FieldCheckerboard;
use energy_budget::EnergyBudget;
use front::Front;
use hydrostatic::Hydrostatic;
use particle_history::{Calm, ParticleHistory};
use remedy_booking::{Booked, RemedyBooking, REMEDIES};
use serde::Serialize;
use solver::{Mat2, StateView};
use step_history::StepHistory;

/// The cheap per-step figures.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StepReport {
    pub step: u64,
    pub t: f64,
    pub dt: f64,
    pub e_kin: f64,
    /// Kinetic energy of the APIC affine velocity (B-splines; else 0).
    pub e_affine: f64,
    pub e_grav: f64,
    pub e_int: f64,
    pub d_visc: f64,
    pub e_total: f64,
    /// Total minus its running minimum.
    pub energy_injected: f64,
    /// Injection over the last `injection_seconds`, and its noise floor.
    pub injection_window: f64,
    pub injection_floor: f64,
    /// Transfer loss accumulated since t = 0: sum over steps and particles of
    /// 1/2 m (|v_prev + dt a_p|^2 - |v|^2), the kinetic energy the transfer
    /// took from FLIP's exact update (PIC dissipates there); under B-spline
    /// APIC the grid's measure, (E_kin + E_affine before P2G - the grid's
    /// after it) + (the updated grid's - E_kin + E_affine after G2P). Less
    /// what the remedies' after-G2P hooks (the FLIP/PIC blend) took, which
    /// is booked to them. It is added to the total in every injection test
    /// but APIC's, and to every budget but the gradient-form APIC's.
    pub transfer_loss: f64,
    /// What the injection test watches (J/m): E + L + the remedies'
    /// dissipation (under APIC without L).
    pub detector_total: f64,
    /// Every remedy's removals since t = 0 (its dissipation), and its
    /// additions (its injection, left visible to the injection test).
    pub remedy_dissipated: f64,
    pub remedy_injected: f64,
    /// The same per remedy, in registry order (None: not in the method).
    pub booked: [Option<Booked>; REMEDIES],
    /// The budget with every booking, E + L + remedy dissipation - remedy
    /// injection, minus its value at t = 0: what no term accounts for (the
    /// time integration's error; under APIC also the transfer's loss).
    pub budget_drift: f64,
    /// The same without the remedies' bookings, E + L minus its value at t = 0.
    pub budget_drift_unbooked: f64,
    /// Largest force-driven acceleration |a_p| (in g).
    pub max_accel_g: f64,
    /// Largest transfer jump |v - v_prev - dt a_p| (m/s): the velocity change
    /// not driven by forces (for PIC and APIC, sum_i N_i v_i - v_prev).
    pub max_transfer_jump: f64,
    /// Largest z computed this step (0 when no particle was a candidate).
    pub max_z: f64,
    pub max_ke_ratio: f64,
    pub max_speed: f64,
    pub courant: f64,
    pub j_min: f64,
    pub j_max: f64,
    /// Smallest nodal mass over rho0 h^2 among active nodes.
    pub min_node_mass_ratio: f64,
    pub max_node_accel_g: f64,
    /// Largest nodal advective number |v_i| dt / h over the active nodes (with
    /// linear shapes a particle can cross a free-slip wall only above 1).
    pub node_advection: f64,
    /// Particle minus grid kinetic energy after P2G (FLIP ringing; under
    /// B-spline APIC, with the affine part, P2G's loss, never negative).
    pub ringing_energy: f64,
    pub n_outside: usize,
    pub n_nonfinite: usize,
    /// Particles deleted so far (`on_escape` / `on_inversion = "delete"`), and
    /// their share of the initial mass.
    pub particles_lost: u64,
    pub mass_lost_fraction: f64,
    pub n_flagged: usize,
    /// Events opened at this step.
    pub events_opened: usize,
    /// Set when the run must stop (blow-out or non-finite state).
    pub blow_out: Option<String>,
    /// The pressure-implicit step (None otherwise): the mean packing error
    /// of the grid mass (packing J - 1 over the cells whose nodes are
    /// full), the conjugate gradient's iterations and final relative
    /// residual, and the energy the projection (with its drift and
    /// checkerboard controls and the extrapolation) and the hourglass
    /// control removed this step (J/m), which the solver books as dissipated.
    pub packing_error: Option<f64>,
    pub solver_iterations: Option<f64>,
    pub solver_residual: Option<f64>,
    pub projection_dissipated: Option<f64>,
    pub hourglass_dissipated: Option<f64>,
}

impl StepReport {
    /// The figures the state itself carries (time, energies, Courant); the rest zero.
    pub fn of_state(v: &StateView) -> Self {
        StepReport {
            step: v.step,
            t: v.time,
            dt: v.dt,
            e_kin: v.energy.kinetic,
            e_affine: v.energy.affine,
            e_grav: v.energy.gravitational,
            e_int: v.energy.stored,
            d_visc: v.energy.dissipated,
            e_total: v.energy.total(),
            courant: v.courant,
            ..Default::default()
        }
    }
}

/// Field metrics, computed at output rows and when an event opens.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FieldMetrics {
    /// The checkerboard share of the cell means of particle pressure
    /// (blind to a mode J-bar reads back from its nodes).
    pub checkerboard_means: Option<f64>,
    /// The alternating amplitude of the nodal pressure that drives the
    /// forces, over rho0 g h (`checkerboard_fields`).
    pub checkerboard_nodal: Option<f64>,
    /// The same of the cell pressure, for a method that carries one.
    pub checkerboard_cell: Option<f64>,
    /// RMS of (p_particle - p_cell) / (rho0 g h).
    pub pressure_spread: f64,
    pub hydro_rel_rms: f64,
    /// The same score of the exact rest field of a flat layer holding the
    /// particles' mass: the reference's own sampling floor.
    pub hydro_floor_rel_rms: f64,
    /// sqrt(max(rel_rms^2 - floor^2, 0)): the departure above that floor.
    pub hydro_excess_rel_rms: f64,
    pub hydro_max: f64,
    /// Departure from the pressure that the weight and the vertical
    /// accelerations above demand, relative to the hydrostatic pressure.
    pub hydro_unexplained_rel_rms: f64,
    pub front_x: Option<f64>,
    pub front_z: Option<f64>,
    pub front_t: f64,
}

/// A particle accelerating above `accel_candidate_g`, with its history from before this step.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    p: u32,
    /// Force-driven |a_p|.
    a: f64,
    /// NaN until scored (a gaining candidate above `kick_accel_g`), 0 when not scored.
    z: f64,
    rules: Rules,
    /// Its quiet spell and earlier peak |dev D| (hallmark evidence).
    calm: Calm,
}

/// The thresholds of the per-particle pass, from the config, g and dt.
#[derive(Clone, Copy, Debug)]
struct ScanThresholds {
    /// Per-step decay of the kinetic-energy history, exp(-dt / ke_history_seconds).
    decay: f64,
    /// Quiescent speed squared (floors the kinetic-energy history as 1/2 m v_q^2).
    quiescent2: f64,
    /// Hallmark activity thresholds: quiet_speed squared, and quiet_rate.
    quiet_speed2: f64,
    quiet_rate: f64,
    /// Squared acceleration of a candidate: (accel_candidate_g g)^2.
    candidate_a2: f64,
    /// det F differs from J (the exp J update): check it apart for inversion.
    det_apart: bool,
    ke_spike_ratio: f64,
    /// kick_accel_g g.
    kick_a: f64,
}

impl ScanThresholds {
    fn new(cfg: &MonitorConfig, g: f64, dt: f64, det_apart: bool) -> Self {
        let candidate_a = cfg.accel_candidate_g * g;
        ScanThresholds {
            decay: (-dt / cfg.ke_history_seconds.max(1e-300)).exp(),
            quiescent2: cfg.quiescent_speed * cfg.quiescent_speed,
            quiet_speed2: cfg.quiet_speed * cfg.quiet_speed,
            quiet_rate: cfg.quiet_rate,
            candidate_a2: candidate_a * candidate_a,
            det_apart,
            ke_spike_ratio: cfg.ke_spike_ratio,
            kick_a: cfg.kick_accel_g * g,
        }
    }

    /// The candidate particle `p` (squared acceleration a2 >= candidate_a2), or None
    /// when no rule fired and no z is to come. `gaining`: its kinetic energy grew.
    fn candidate(
        &self,
        p: usize,
        a2: f64,
        ke_ratio: f64,
        gaining: bool,
        calm: Calm,
    ) -> Option<Candidate> {
        let a = a2.sqrt();
        let mut rules = Rules::NONE;
        if ke_ratio >= self.ke_spike_ratio {
            rules.insert(Rule::KeSpike);
        }
        // A kick adds kinetic energy; an impact that stops particles does not count.
        let wants_z = gaining && a >= self.kick_a;
        (!rules.is_empty() || wants_z).then_some(Candidate {
            p: p as u32,
            a,
            z: if wants_z { f64::NAN } else { 0.0 },
            rules,
            calm,
        })
    }
}

/// The cheap figures of the per-particle pass.
#[derive(Clone, Copy, Debug)]
struct Scan {
    max_ratio: f64,
    max_speed2: f64,
    max_a2: f64,
    /// Largest squared transfer jump, and this step's transfer loss.
    max_jump2: f64,
    transfer_loss: f64,
    j_min: f64,
    j_max: f64,
    /// Smallest det F (J <= 0 or det F <= 0 is an inversion; the exp J update keeps J > 0).
    det_min: f64,
    /// Largest kinetic-energy gain 1/2 m (|v|^2 - |v_prev|^2), and its particle.
    gain_max: (f64, usize),
    /// Largest vertical speed |v_y|.
    max_vertical_speed: f64,
    /// Some candidate awaits its z score.
    need_z: bool,
}

impl Scan {
    fn new() -> Self {
        Scan {
            max_ratio: 0.0,
            max_speed2: 0.0,
            max_a2: 0.0,
            max_jump2: 0.0,
            transfer_loss: 0.0,
            j_min: f64::INFINITY,
            j_max: f64::NEG_INFINITY,
            det_min: f64::INFINITY,
            gain_max: (f64::NEG_INFINITY, 0),
            max_vertical_speed: 0.0,
            need_z: false,
        }
    }

    /// Kinetic energy `e` over its reference `ke_ref`, tracking the largest;
    /// divided only for a candidate or a possible new maximum (0 otherwise).
    #[inline(always)]
    fn ke_ratio(&mut self, e: f64, ke_ref: f64, candidate: bool) -> f64 {
        let ratio = if candidate || e > self.max_ratio * ke_ref {
            e / ke_ref
        } else {
            0.0
        };
        self.max_ratio = self.max_ratio.max(ratio);
        ratio
    }

    /// Speed, Jacobian and kinetic-energy gain of particle `p`.
    #[inline(always)]
    fn add(&mut self, p: usize, speed2: f64, prev2: f64, mass: f64, j: f64) {
        self.max_speed2 = self.max_speed2.max(speed2);
        self.j_min = self.j_min.min(j);
        self.j_max = self.j_max.max(j);
        let gain = 0.5 * mass * (speed2 - prev2);
        if gain > self.gain_max.0 {
            self.gain_max = (gain, p);
        }
    }
}

#[derive(Clone, Debug)]
struct Cluster {
    cells: CellRange,
    rules: Rules,
    peak_accel: f64,
    peak_z: f64,
    quiescent: usize,
    deformed_rate: usize,
    distorted: usize,
    count: usize,
    event: usize,
    /// Largest earlier peak |dev D| of its particles, and when.
    peak_rate: f64,
    peak_rate_t: f64,
    j_min: f64,
    /// Largest speed of its particles at the start of the step.
    speed_before: f64,
    /// Largest transfer jump of its particles this step (m/s).
    transfer_jump: f64,
}

impl Cluster {
    /// A cluster over `cells` with no particles tallied yet.
    fn new(cells: CellRange, rules: Rules, peak_accel: f64) -> Self {
        Cluster {
            cells,
            rules,
            peak_accel,
            peak_z: 0.0,
            quiescent: 0,
            deformed_rate: 0,
            distorted: 0,
            count: 0,
            event: 0,
            peak_rate: 0.0,
            peak_rate_t: particle_history::NEVER,
            j_min: f64::INFINITY,
            speed_before: 0.0,
            transfer_jump: 0.0,
        }
    }
}

#[derive(Clone, Debug)]
pub struct Monitor {
    pub cfg: MonitorConfig,
    pub geom: Geometry,
    /// Force-driven |a_p| per particle, filled only on steps that need it (`fill_accel`).
    accel: Vec<f64>,
    accel_step: Option<u64>,
    flagged: Vec<Candidate>,
    bins: CellBins,
    stats: WindowStats,
    history: ParticleHistory,
    energy: EnergyBudget,
    cell_label: Vec<u32>,
    touched: Vec<u32>,
    stack: Vec<u32>,
    clusters: Vec<Cluster>,
    event_mark: Vec<u32>,
    events: Vec<Event>,
    field: CellField,
    field_checkerboard: FieldCheckerboard,
    hydro: Hydrostatic,
    front: Front,
    report: StepReport,
    prev_injected: f64,
    /// Largest particle |v_y| at the previous observation (bounds the
    /// explicit-stepping energy error of an event that opens now).
    prev_vertical_speed: f64,
    events_dropped: u64,
    /// Courant and nodal advective numbers of the last steps (cause evidence).
    steps: StepHistory,
    /// The shape's critical Courant number.
    critical_courant: f64,
    /// Time of the previous observation (particle activity is judged against it).
    prev_time: f64,
    /// Particle ids per slot as of the last observation (deletions compact the history).
    ids: Vec<u32>,
    /// Set by a restore: the next observation takes the solver's ids as the
    /// restored histories' (not saved: the solver's checkpoint holds them).
    adopt_ids: bool,
    /// Mass at t = 0, deleted particles included.
    initial_mass: f64,
    /// Transfer loss accumulated since t = 0 (see `StepReport::transfer_loss`).
    transfer_loss: f64,
    /// Each remedy's energy booked since t = 0.
    booking: RemedyBooking,
    /// E at t = 0 (the budgets' drifts are measured from it).
    initial_total: f64,
}

/// Nodes lighter than this fraction of a full cell's mass rho0 h^2 are left
/// out of the nodal advective number.
pub const ADVECTION_MIN_MASS: f64 = 1e-3;

/// The critical effective Courant number of a shape family (docs/physics.md section 4b).
pub fn critical_courant(shape: solver::ShapeKind) -> f64 {
    match shape {
        solver::ShapeKind::Linear | solver::ShapeKind::Gimp | solver::ShapeKind::Cpgimp => 1.0,
        solver::ShapeKind::Bspline2 => 1.7,
        solver::ShapeKind::Bspline3 => 1.9,
    }
}

const UNLABELLED: u32 = u32::MAX;

/// Relative round-off of the energy sums (O(1e-16) per term over up to 1e6
/// particles, with margin): a rise below this times the energies' magnitude
/// is not an injection.
pub const ROUND_OFF: f64 = 1e-12;

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
            history.start(p, v.time, 0.5 * v.mass[p] * speed2, active, rate);
        }
        Monitor {
            accel: vec![0.0; n],
            accel_step: None,
            flagged: Vec::with_capacity(n),
            bins: CellBins::new(&geom, n),
            stats: WindowStats::new(&geom, n),
            history,
            energy: EnergyBudget::new(v.energy.total(), v.time, cfg.injection_seconds),
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
            prev_injected: 0.0,
            prev_vertical_speed: 0.0,
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

    pub fn report(&self) -> &StepReport {
        &self.report
    }

    /// Gravity used to scale accelerations (9.81 when the scene has none).
    fn g_ref(&self) -> f64 {
        if self.geom.gravity > 0.0 {
            self.geom.gravity
        } else {
            9.81
        }
    }

    /// Force-driven |a_p| of every particle for this step (once).
    fn fill_accel(&mut self, v: &StateView) {
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
        if std::mem::take(&mut self.adopt_ids) && v.id.len() == self.history.ke_recent.len() {
            // Restored from a checkpoint taken after deletions.
            self.ids.clear();
            self.ids.extend_from_slice(v.id);
        }
        if v.id.len() != self.ids.len() || v.id.last() != self.ids.last() {
            // The solver deleted particles, or some entered through an
            // inflow wall: keep the history of the others.
            self.history.compact(&self.ids, v.id, self.prev_time);
            self.ids.clear();
            self.ids.extend_from_slice(v.id);
            let ids = v.id.last().map_or(0, |&id| id as usize + 1);
            if ids > self.event_mark.len() {
                self.event_mark.resize(ids, 0);
            }
        }
        let scan = self.scan_particles(v, g, dt);
        self.prev_time = v.time;
        let max_z = if scan.need_z {
            self.score_candidates(v)
        } else {
            0.0
        };
        self.flagged.retain(|c| !c.rules.is_empty());
        // B-spline APIC: both transfers are projections once the affine
        // velocity's energy is counted, so the loss is measured on the grid
        // (particles before P2G minus the grid after it, the updated grid
        // minus the particles after G2P), each part >= 0 away from walls.
        let step_loss = match v.affine_inertia {
            Some(_) => {
                // An impulse is no transfer: it stays an injection.
                (v.ke_particles_p2g - v.ke_grid_p2g)
                    + (v.ke_grid_updated - (v.energy.kinetic_with_affine() - v.impulse_kinetic))
            }
            None => scan.transfer_loss,
        };
        if step_loss.is_finite() {
            self.transfer_loss += step_loss;
        }
        // The transfer's dissipation must not hide a gain elsewhere. Under
        // APIC the injection test watches the particles' total without the
        // loss (measured: with either measure a floor impact reads as an
        // injection); the budget below adds the affine energy and the
        // grid's loss where they are known (B-splines). Under APIC with
        // linear or uGIMP shapes C is not a least-squares fit and D varies
        // with the position: the loss is logged only.
        let loss_counted = v.transfer != solver::TransferKind::Apic;
        let loss = if loss_counted {
            self.transfer_loss
        } else {
            0.0
        };
        // Each remedy's removals are its dissipation; its additions stay
        // in the total, where the injection test sees them.
        self.booking.book(v.remedies.energy_parts());
        let watched = v.energy.total() + loss + self.booking.detector_offset(loss_counted);
        // The budget: E (with the affine part) + L + the remedies' bookings.
        let (budget, budget_unbooked) = if v.affine_inertia.is_some() {
            let e = v.energy.total_with_affine() + self.transfer_loss;
            (e + self.booking.detector_offset(true), e)
        } else {
            (watched, v.energy.total() + loss)
        };
        let mut injection = self.energy.observe(v.time, watched);
        // Periodic along gravity, a particle that wraps jumps by m g H in
        // potential energy: the budget is undefined there, so its rule is off.
        let budget_defined = !(v.scene.periodic[1] && g > 0.0);
        if !budget_defined {
            injection.total = 0.0;
            injection.window = 0.0;
        }
        let floor =
            solver::energy::injection_noise_floor(self.initial_mass, g, self.geom.size.y, dt);
        let (min_node_mass_ratio, max_node_a, max_node_speed) = self.grid_figures(v);
        let node_advection = max_node_speed * v.dt / v.grid.h;
        // Before any event opens: its window before onset includes this step.
        self.steps.push(v.time, v.courant, node_advection);
        let opened_before = self.events.len();
        if !self.flagged.is_empty() {
            self.cluster_flagged(v, g);
        }
        self.check_energy_injection(v, g, injection.window, floor, scan.gain_max.1);
        if !v.culled.is_empty() {
            self.culled_events(v, g);
        }
        let max_speed = scan.max_speed2.sqrt();
        let blow_out = self.check_blow_out(v, g, max_speed, &scan);
        if blow_out.is_some() {
            self.stopped(v);
        }
        let e = &v.energy;
        let energy_scale = e.kinetic_with_affine().abs()
            + e.gravitational.abs()
            + e.stored.abs()
            + e.dissipated.abs();
        self.track_injected_energy(v, g, injection.total, scan.max_vertical_speed, energy_scale);
        let undefined = |x: f64| if budget_defined { x } else { f64::NAN };
        self.report = StepReport {
            step: v.step,
            energy_injected: undefined(injection.total),
            injection_window: undefined(injection.window),
            injection_floor: floor,
            transfer_loss: self.transfer_loss + self.booking.in_transfer_loss(),
            remedy_dissipated: self.booking.dissipated(),
            remedy_injected: self.booking.injected(),
            booked: self.booking.booked,
            budget_drift: budget - self.booking.injected() - self.initial_total,
            budget_drift_unbooked: budget_unbooked - self.initial_total,
            packing_error: v.projection.map(|p| p.stats.packing_error),
            solver_iterations: v.projection.map(|p| p.stats.iterations as f64),
            solver_residual: v.projection.map(|p| p.stats.residual),
            projection_dissipated: v.projection.map(|p| p.stats.dissipated_projection),
            hourglass_dissipated: v.projection.map(|p| p.stats.dissipated_hourglass),
            detector_total: watched,
            max_accel_g: scan.max_a2.sqrt() / g,
            max_transfer_jump: scan.max_jump2.sqrt(),
            max_z,
            max_ke_ratio: scan.max_ratio,
            max_speed,
            j_min: scan.j_min,
            j_max: scan.j_max,
            min_node_mass_ratio,
            max_node_accel_g: max_node_a / g,
            node_advection,
            ringing_energy: v.ke_particles_p2g - v.ke_grid_p2g,
            n_outside: v.n_outside,
            n_nonfinite: v.n_nonfinite,
            particles_lost: v.losses.count(),
            mass_lost_fraction: v.losses.mass() / self.initial_mass,
            n_flagged: self.flagged.len(),
            events_opened: self.events.len() - opened_before,
            blow_out,
            ..StepReport::of_state(v)
        };
        &self.report
    }

    /// One pass over the particles: the cheap figures, the history update,
    /// then this step's candidates (with their calm before this burst) into `flagged`.
    fn scan_particles(&mut self, v: &StateView, g: f64, dt: f64) -> Scan {
        let t = ScanThresholds::new(&self.cfg, g, dt, v.j_update == solver::JUpdate::Exp);
        let (time, prev_time, grace) = (v.time, self.prev_time, self.cfg.merge_seconds);
        let n = v.x.len();
        let mut s = Scan::new();
        self.flagged.clear();
        // Every slice cut to n up front: no bounds checks in the loop.
        let (vel, vel_prev, accel, mass, jac, dev_rate, def) = (
            &v.v[..n],
            &v.v_prev[..n],
            &v.accel[..n],
            &v.mass[..n],
            &v.j[..n],
            &v.dev_rate[..n],
            &v.deformation[..n],
        );
        let h = &mut self.history;
        for p in 0..n {
            // Squared accelerations compared against a^2: no root per particle.
            let a2 = accel[p].norm_squared();
            s.max_a2 = s.max_a2.max(a2);
            let candidate = a2 >= t.candidate_a2;
            let speed2 = vel[p].norm_squared();
            // FLIP's exact update against what the transfer gave.
            let flip = vel_prev[p] + dt * accel[p];
            s.max_jump2 = s.max_jump2.max((vel[p] - flip).norm_squared());
            s.transfer_loss += 0.5 * mass[p] * (flip.norm_squared() - speed2);
            let prev2 = vel_prev[p].norm_squared();
            let e = 0.5 * mass[p] * speed2;
            let ke_ref = h.ke_recent[p].max(0.5 * mass[p] * t.quiescent2);
            let ratio = s.ke_ratio(e, ke_ref, candidate);
            s.add(p, speed2, prev2, mass[p], jac[p]);
            s.max_vertical_speed = s.max_vertical_speed.max(vel[p].y.abs());
            if t.det_apart {
                s.det_min = s.det_min.min(def[p].determinant());
            }
            h.ke_recent[p] = e.max(h.ke_recent[p] * t.decay);
            let rate = dev_rate[p];
            let active = speed2 > t.quiet_speed2 || rate > t.quiet_rate;
            h.record(p, time, prev_time, active, rate);
            if candidate {
                let calm = h.calm(p, time, grace);
                if let Some(c) = t.candidate(p, a2, ratio, speed2 > prev2, calm) {
                    s.need_z |= c.z.is_nan();
                    self.flagged.push(c);
                }
            }
        }
        s
    }

    /// Robust z of the candidates awaiting one (gaining, above `kick_accel_g`),
    /// flagging outliers; the largest z.
    fn score_candidates(&mut self, v: &StateView) -> f64 {
        // The z windows read every particle's acceleration.
        self.fill_accel(v);
        self.bins.rebuild(&self.geom, v.x);
        let window = (self.cfg.window_tile_cells, self.cfg.window_half_cells);
        let mut max_z = 0.0f64;
        for c in self.flagged.iter_mut().filter(|c| c.z.is_nan()) {
            c.z = self.stats.z(
                &self.geom,
                &self.bins,
                &self.accel,
                window,
                c.p as usize,
                v.step.max(1),
            );
            max_z = max_z.max(c.z);
            if c.z >= self.cfg.kick_z {
                c.rules.insert(Rule::AccelOutlier);
            }
        }
        max_z
    }

    /// An energy-injection event at the particle that gained most (`gainer`)
    /// when the injection over the window exceeds its noise floor.
    fn check_energy_injection(
        &mut self,
        v: &StateView,
        g: f64,
        window: f64,
        floor: f64,
        gainer: usize,
    ) {
        if window > self.cfg.injection_floor_factor * floor {
            self.fill_accel(v);
            let (i, j) = self.geom.cell_of(v.x[gainer]);
            let cluster = Cluster::new(
                CellRange::of(i, j),
                Rule::InjectionWindow.into(),
                self.accel[gainer],
            );
            self.attach(EventKind::EnergyInjection, cluster, v, g, false);
        }
    }

    /// Non-finite state, particles outside the box or one faster than the
    /// escape speed: the blow-out event and why the run must stop.
    fn check_blow_out(
        &mut self,
        v: &StateView,
        g: f64,
        max_speed: f64,
        scan: &Scan,
    ) -> Option<String> {
        // Inversion first: J <= 0 also makes pressures and energies non-finite.
        if scan.j_min <= 0.0 || scan.det_min <= 0.0 {
            let reason = format!(
                "inversion: smallest J {:.3e}, smallest det F {:.3e}",
                scan.j_min, scan.det_min
            );
            self.blow_out_event(EventKind::Inversion, Rule::Inversion, v, g, |p| {
                v.j[p] <= 0.0 || v.deformation[p].determinant() <= 0.0
            });
            return Some(reason);
        }
        if v.n_nonfinite > 0 {
            let reason = format!("non-finite state in {} particles", v.n_nonfinite);
            self.blow_out_event(EventKind::NonFinite, Rule::NonFinite, v, g, |p| {
                let (x, vel) = (v.x[p], v.v[p]);
                !(x.x.is_finite() && x.y.is_finite() && vel.x.is_finite() && vel.y.is_finite())
            });
            return Some(reason);
        }
        // A non-finite total with finite particles (e.g. U(J) at J -> 0) is not dropped by a min.
        if !v.energy.total().is_finite() {
            let reason = format!("non-finite total energy {}", v.energy.total());
            self.blow_out_event(EventKind::NonFinite, Rule::NonFinite, v, g, |p| {
                !v.j[p].is_finite() || v.j[p] <= 0.0
            });
            return Some(reason);
        }
        if v.n_outside > 0 {
            let reason = format!("{} particles left the box", v.n_outside);
            let (lo, hi) = (self.geom.origin, self.geom.origin + self.geom.size);
            self.blow_out_event(EventKind::BlowOut, Rule::OutsideBox, v, g, |p| {
                let x = v.x[p];
                x.x < lo.x || x.y < lo.y || x.x > hi.x || x.y > hi.y
            });
            return Some(reason);
        }
        let lost = v.losses.mass() / self.initial_mass;
        if lost > v.scene.lost_mass_limit {
            return Some(format!(
                "{:.1} % of the mass deleted ({} escaped, {} inverted), beyond lost_mass_limit {}",
                100.0 * lost,
                v.losses.escaped,
                v.losses.inverted,
                v.scene.lost_mass_limit
            ));
        }
        // Under on_escape = "delete" a fast particle is left to leave the box.
        let fall = (2.0 * g * self.geom.size.y).sqrt();
        let escape = self.cfg.escape_speed_factor * fall.max(self.geom.body_speed);
        if v.scene.on_escape == solver::OnLoss::Stop && max_speed > escape {
            let reason = format!(
                "a particle reached {max_speed:.3} m/s, beyond the escape speed {escape:.3} m/s"
            );
            self.blow_out_event(EventKind::BlowOut, Rule::EscapeSpeed, v, g, |p| {
                v.v[p].norm() > escape
            });
            return Some(reason);
        }
        None
    }

    /// The run stops at this step: every event still open (within the merge
    /// window of its last step) gets the stop's outcome.
    fn stopped(&mut self, v: &StateView) {
        let outcome = self
            .events
            .iter()
            .rev()
            .find(|e| e.last_step == v.step)
            .map_or(Outcome::BlowOut, |e| match e.kind {
                EventKind::Inversion => Outcome::Inverted,
                EventKind::NonFinite => Outcome::NonFinite,
                _ => Outcome::BlowOut,
            });
        let merge_seconds = self.cfg.merge_seconds;
        for e in self
            .events
            .iter_mut()
            .filter(|e| e.last_step == v.step || e.last_t + merge_seconds >= v.time)
        {
            e.outcome = outcome;
        }
    }

    /// Energy injected while each event touched at this step is open (`total`
    /// is the injection so far), and the cause judged against the floor of
    /// the event's mass (docs/physics.md section 4b). Symplectic Euler under
    /// gravity adds m g dt dv_y / 2 when a particle's vertical velocity
    /// changes by dv_y, and |dv_y| <= 2 V with V the largest |v_y| of any
    /// particle from the step before the event opened to now: the floor is
    /// `injection_floor_factor` m g dt min(2 V, sqrt(2 g H)) / 2, the
    /// free-fall speed over the box height H capping it as before; plus the
    /// sums' round-off, `ROUND_OFF` times the energies' magnitude (without
    /// vertical motion the first term vanishes).
    fn track_injected_energy(
        &mut self,
        v: &StateView,
        g: f64,
        total: f64,
        vertical_speed: f64,
        energy_scale: f64,
    ) {
        let (step, time, merge) = (v.step, v.time, self.cfg.merge_seconds);
        let mean_mass = self.initial_mass / self.event_mark.len().max(1) as f64;
        let free_fall = (2.0 * g * self.geom.size.y).sqrt();
        let per_kg_per_speed = self.cfg.injection_floor_factor * g * v.dt / 2.0;
        let prev_speed = self.prev_vertical_speed;
        for e in self.events.iter_mut() {
            let live = e.last_step + 1 >= step || time - e.last_t <= merge;
            if !live {
                continue;
            }
            let bound = &mut e.evidence.vertical_speed_bound;
            if e.first_step == step {
                *bound = prev_speed;
            }
            *bound = bound.max(vertical_speed);
            if e.last_step != step {
                continue;
            }
            if e.first_step == step {
                e.injected_at_open = self.prev_injected;
            }
            e.energy_injected = e.energy_injected.max(total - e.injected_at_open);
            // An energy-injection event is the whole budget's: the whole mass's floor.
            let mass = if e.kind == EventKind::EnergyInjection {
                self.initial_mass
            } else {
                e.n_particles as f64 * mean_mass
            };
            let speed = (2.0 * e.evidence.vertical_speed_bound).min(free_fall);
            e.evidence.energy_floor = per_kg_per_speed * speed * mass + ROUND_OFF * energy_scale;
            e.classify();
        }
        self.prev_injected = total;
        self.prev_vertical_speed = vertical_speed;
    }

    /// Over the active grid nodes: the smallest nodal mass over rho0 h^2 (0
    /// without any), the largest nodal acceleration, and the largest speed of
    /// the nodes with at least `ADVECTION_MIN_MASS` rho0 h^2.
    fn grid_figures(&self, v: &StateView) -> (f64, f64, f64) {
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
        let min_mass = if min_mass.is_finite() { min_mass } else { 0.0 };
        (min_mass, max_node_a, max_speed2.sqrt())
    }

    /// Clusters this step's flagged particles by 8-adjacent cells and files them as kicks.
    fn cluster_flagged(&mut self, v: &StateView, g: f64) {
        self.label_clusters(v);
        self.tally_clusters(v);
        for k in 0..self.clusters.len() {
            let cluster = self.clusters[k].clone();
            self.clusters[k].event = if cluster.count >= self.cfg.min_cluster_particles {
                self.attach(EventKind::Kick, cluster, v, g, false)
            } else {
                usize::MAX
            };
        }
        self.count_members(v);
    }

    /// Labels the cells holding flagged particles by 8-connected component,
    /// one empty cluster per component (`cell_label` holds its index).
    fn label_clusters(&mut self, v: &StateView) {
        let nx = self.geom.cells[0];
        let ny = self.geom.cells[1];
        for &c in &self.touched {
            self.cell_label[c as usize] = UNLABELLED;
        }
        self.touched.clear();
        // Mark flagged cells with a placeholder label.
        const FLAGGED: u32 = u32::MAX - 1;
        for f in &self.flagged {
            let c = self.geom.cell_index(v.x[f.p as usize]);
            if self.cell_label[c] == UNLABELLED {
                self.cell_label[c] = FLAGGED;
                self.touched.push(c as u32);
            }
        }
        self.clusters.clear();
        for k in 0..self.touched.len() {
            let seed = self.touched[k] as usize;
            if self.cell_label[seed] != FLAGGED {
                continue;
            }
            let label = self.clusters.len() as u32;
            let (si, sj) = (seed % nx, seed / nx);
            let mut cells = CellRange::of(si, sj);
            self.cell_label[seed] = label;
            self.stack.clear();
            self.stack.push(seed as u32);
            while let Some(c) = self.stack.pop() {
                let (i, j) = (c as usize % nx, c as usize / nx);
                cells = cells.union(&CellRange::of(i, j));
                for j2 in j.saturating_sub(1)..=(j + 1).min(ny - 1) {
                    for i2 in i.saturating_sub(1)..=(i + 1).min(nx - 1) {
                        let c2 = i2 + j2 * nx;
                        if self.cell_label[c2] == FLAGGED {
                            self.cell_label[c2] = label;
                            self.stack.push(c2 as u32);
                        }
                    }
                }
            }
            self.clusters.push(Cluster::new(cells, Rules::NONE, 0.0));
        }
    }

    /// Tallies each flagged particle into its cluster: rules, peaks, count and
    /// the hallmark counts (quiet, deformed, distorted before this step).
    fn tally_clusters(&mut self, v: &StateView) {
        let (quiet, quiet_start) = (self.cfg.quiet_seconds, v.time - self.cfg.quiet_seconds);
        for f in &self.flagged {
            let p = f.p as usize;
            let label = self.cell_label[self.geom.cell_index(v.x[p])] as usize;
            let c = &mut self.clusters[label];
            c.rules = c.rules.union(f.rules);
            c.peak_accel = c.peak_accel.max(f.a);
            c.peak_z = c.peak_z.max(f.z);
            c.count += 1;
            c.j_min = c.j_min.min(v.j[p]);
            c.speed_before = c.speed_before.max(v.v_prev[p].norm());
            let flip = v.v_prev[p] + v.dt * v.accel[p];
            c.transfer_jump = c.transfer_jump.max((v.v[p] - flip).norm());
            if f.calm.quiet_for >= quiet {
                c.quiescent += 1;
            }
            if f.calm.peak_rate >= self.cfg.deformed_rate && f.calm.peak_rate_t < quiet_start {
                c.deformed_rate += 1;
            }
            if f.calm.peak_rate > c.peak_rate {
                c.peak_rate = f.calm.peak_rate;
                c.peak_rate_t = f.calm.peak_rate_t;
            }
            if isochoric_stretch_ratio(&v.deformation[p]) >= self.cfg.distortion_ratio {
                c.distorted += 1;
            }
        }
    }

    /// Counts each flagged particle once into its cluster's event, keeping the
    /// first `max_event_ids` ids.
    fn count_members(&mut self, v: &StateView) {
        let cap = self.cfg.max_event_ids;
        for f in &self.flagged {
            let p = f.p as usize;
            let label = self.cell_label[self.geom.cell_index(v.x[p])] as usize;
            let event = self.clusters[label].event;
            if event == usize::MAX {
                continue;
            }
            let e = &mut self.events[event];
            let id = v.id[p] as usize;
            if self.event_mark[id] != e.id {
                self.event_mark[id] = e.id;
                e.n_particles += 1;
                if e.particles.len() < cap {
                    e.particles.push(v.id[p]);
                }
            }
        }
    }

    /// Merges a cluster into an open event of the same kind nearby, or opens
    /// one; usize::MAX when the event store is full.
    fn attach(&mut self, kind: EventKind, c: Cluster, v: &StateView, g: f64, stops: bool) -> usize {
        let step = v.step;
        let open = self.events.iter().rposition(|e| {
            e.kind == kind
                && (e.last_step + 1 >= step || v.time - e.last_t <= self.cfg.merge_seconds)
                && e.extent.near(&c.cells, self.cfg.merge_cells)
        });
        // The event that stops a run is always stored.
        if open.is_none() && !stops && self.events.len() >= self.cfg.max_events {
            self.events_dropped += 1;
            return usize::MAX;
        }
        match open {
            Some(k) => {
                self.merge(k, &c, v, g);
                k
            }
            None => {
                self.open(kind, &c, v, g);
                self.events.len() - 1
            }
        }
    }

    /// Extends open event `k` by this step's cluster.
    fn merge(&mut self, k: usize, c: &Cluster, v: &StateView, g: f64) {
        let e = &mut self.events[k];
        e.last_step = v.step;
        e.last_t = v.time;
        e.extent = e.extent.union(&c.cells);
        if e.first_step == v.step {
            e.cells = e.cells.union(&c.cells);
            e.region = e.cells.metres(&self.geom);
        }
        e.peak_accel_g = e.peak_accel_g.max(c.peak_accel / g);
        e.peak_z = e.peak_z.max(c.peak_z);
        e.rules = e.rules.union(c.rules);
    }

    /// Opens an event for the cluster; a hallmark holds for at least half its particles.
    fn open(&mut self, kind: EventKind, c: &Cluster, v: &StateView, g: f64) {
        let half = |k: usize| c.count > 0 && 2 * k >= c.count;
        let fraction = |k: usize| {
            if c.count > 0 {
                k as f64 / c.count as f64
            } else {
                0.0
            }
        };
        let mut deformed_by = vec![];
        if half(c.deformed_rate) {
            deformed_by.push(DeformedBy::StrainRate);
        }
        if half(c.distorted) {
            deformed_by.push(DeformedBy::Distortion);
        }
        let (courant_before, advection_before) =
            self.steps.max_since(v.time - self.cfg.merge_seconds);
        let mut event = Event {
            id: self.events.len() as u32 + 1,
            kind,
            first_step: v.step,
            last_step: v.step,
            t: v.time,
            last_t: v.time,
            cells: c.cells,
            region: c.cells.metres(&self.geom),
            extent: c.cells,
            n_particles: 0,
            particles: Vec::new(),
            peak_accel_g: c.peak_accel / g,
            peak_z: c.peak_z,
            energy_injected: 0.0,
            courant: v.courant,
            quiescent_before: half(c.quiescent),
            deformed_by,
            rules: c.rules,
            cause: Cause::Impact,
            evidence: Evidence {
                courant_before,
                advection_before,
                critical_courant: self.critical_courant,
                energy_floor: 0.0,
                vertical_speed_bound: 0.0,
                quiescent_fraction: fraction(c.quiescent),
                deformed_fraction: fraction(c.deformed_rate),
                peak_dev_rate: c.peak_rate,
                t_peak_dev_rate: c.peak_rate_t.is_finite().then_some(c.peak_rate_t),
                j_min: c.j_min.is_finite().then_some(c.j_min),
                speed_before: c.speed_before,
                transfer_jump: c.transfer_jump,
            },
            outcome: Outcome::Recovered,
            state_hash: None,
            checkpoint: None,
            phase: None,
            injected_at_open: self.prev_injected,
        };
        event.classify();
        self.events.push(event);
    }

    fn blow_out_event(
        &mut self,
        kind: EventKind,
        rule: Rule,
        v: &StateView,
        g: f64,
        bad: impl Fn(usize) -> bool,
    ) {
        self.fill_accel(v);
        let mut cells: Option<CellRange> = None;
        let mut count = 0;
        let mut peak = 0.0f64;
        for p in 0..v.x.len() {
            if bad(p) {
                let (i, j) = self.geom.cell_of(v.x[p]);
                cells = Some(cells.map_or(CellRange::of(i, j), |c| c.union(&CellRange::of(i, j))));
                count += 1;
                if self.accel[p].is_finite() {
                    peak = peak.max(self.accel[p]);
                }
            }
        }
        let Some(cells) = cells else { return };
        let k = self.attach(kind, Cluster::new(cells, rule.into(), peak), v, g, true);
        let cap = self.cfg.max_event_ids;
        let e = &mut self.events[k];
        e.n_particles = e.n_particles.max(count);
        for p in 0..v.x.len() {
            if e.particles.len() >= cap {
                break;
            }
            if bad(p) && !e.particles.contains(&v.id[p]) {
                e.particles.push(v.id[p]);
            }
        }
    }

    /// Events for the particles the solver deleted at this step (escaped:
    /// `blow_out`, inverted: `inversion`), by where they were; the run goes on.
    fn culled_events(&mut self, v: &StateView, g: f64) {
        use solver::CullReason;
        let kinds = [
            (CullReason::Escaped, EventKind::BlowOut, Rule::OutsideBox),
            (CullReason::Inverted, EventKind::Inversion, Rule::Inversion),
        ];
        for (reason, kind, rule) in kinds {
            let mut cells: Option<CellRange> = None;
            let mut count = 0;
            for c in v.culled.iter().filter(|c| c.reason == reason) {
                let (i, j) = self.geom.cell_of(c.x);
                let cell = CellRange::of(i, j);
                cells = Some(cells.map_or(cell, |r| r.union(&cell)));
                count += 1;
            }
            let Some(cells) = cells else { continue };
            let k = self.attach(kind, Cluster::new(cells, rule.into(), 0.0), v, g, false);
            if k == usize::MAX {
                continue;
            }
            let cap = self.cfg.max_event_ids;
            let e = &mut self.events[k];
            e.n_particles += count;
            for c in v.culled.iter().filter(|c| c.reason == reason) {
                if e.particles.len() < cap {
                    e.particles.push(c.id);
                }
            }
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

/// Largest over smallest principal stretch of F (in plane); 1 for a pure dilatation.
pub fn isochoric_stretch_ratio(f: &Mat2) -> f64 {
    let c = f.transpose() * f;
    let tr = c.trace();
    let det = c.determinant();
    let disc = (0.25 * tr * tr - det).max(0.0).sqrt();
    let (l1, l2) = (0.5 * tr + disc, 0.5 * tr - disc);
    if l2 <= 0.0 {
        return f64::INFINITY;
    }
    (l1 / l2).sqrt()
}
