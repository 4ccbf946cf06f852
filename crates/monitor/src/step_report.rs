//! What the monitor reports each step (`StepReport`) and on demand (`FieldMetrics`).

use crate::remedy_booking::{Booked, REMEDIES};
use serde::Serialize;
use solver::StateView;

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
    /// The whole run's energy gain: the ledger's credited total (each
    /// booked term credited by its net removal since t = 0) over its running
    /// minimum. Its peak is the method's pump figure.
    pub energy_injected: f64,
    /// The largest gain over the last `injection_seconds` (booked terms by
    /// their net over it), and the whole body's floor for it.
    pub injection_window: f64,
    pub injection_floor: f64,
    /// Gravity's stepping term booked since t = 0 (J/m): the potential
    /// energy change beyond gravity's work at the time-centred velocity.
    pub gravity_stepping: f64,
    /// Transfer loss accumulated since t = 0: sum over steps and particles of
    /// 1/2 m (|v_prev + dt a_p|^2 - |v|^2), the kinetic energy the transfer
    /// took from FLIP's exact update (PIC dissipates there); under B-spline
    /// APIC the grid's measure, (E_kin + E_affine before P2G - the grid's
    /// after it) + (the updated grid's - E_kin + E_affine after G2P). Less
    /// what the remedies' after-G2P hooks (the FLIP/PIC blend) took, which
    /// is booked to them. It is added to the total in every injection test
    /// but APIC's, and to every budget but the gradient-form APIC's.
    pub transfer_loss: f64,
    /// The ledger's base (J/m): E less the projection's and the hourglass
    /// control's bookings and gravity's stepping term (the booked terms are
    /// credited over the window by their net).
    pub detector_total: f64,
    /// Every remedy's removals since t = 0 (its dissipation), and its
    /// additions (its injection, left visible to the injection test).
    pub remedy_dissipated: f64,
    pub remedy_injected: f64,
    /// The same per remedy, in registry order (None: not in the method).
    pub booked: [Option<Booked>; REMEDIES],
    /// The budget with every booking, E + L + remedy dissipation - remedy
    /// injection - gravity's stepping term, minus its value at t = 0: what
    /// no term accounts for (the time integration's error; under APIC also
    /// the transfer's loss).
    pub budget_drift: f64,
    /// The same without the remedies' bookings, E + L minus its value at t = 0.
    pub budget_drift_unbooked: f64,
    /// Largest force-driven acceleration |a_p| (in g).
    pub max_accel_g: f64,
    /// Largest transfer jump |v - v_prev - dt a_p| (m/s): the velocity change
    /// not driven by forces (for PIC and APIC, sum_i N_i v_i - v_prev).
    pub max_transfer_jump: f64,
    /// Largest velocity jump against the local flow this step (m/s; 0 when
    /// none reached `jump_speed`).
    pub max_jump: f64,
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
