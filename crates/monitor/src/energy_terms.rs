//! The energy arithmetic of each step: the transfer loss, the remedies'
//! bookings, the total the injection test watches and the budget's drift,
//! then the energy injected while each event is open and its floor
//! (docs/physics.md section 4b).

use crate::detector::Scan;
use crate::energy_budget::Injection;
use crate::events::EventKind;
use crate::Monitor;
use solver::StateView;

/// Relative round-off of the energy sums (O(1e-16) per term over up to 1e6
/// particles, with margin): a rise below this times the energies' magnitude
/// is not an injection.
pub const ROUND_OFF: f64 = 1e-12;

/// A step's energy figures (`Monitor::book_energy`).
pub(crate) struct EnergyStep {
    /// The injection so far and over the window (0 where the budget is undefined).
    pub(crate) injection: Injection,
    /// The injection window's noise floor.
    pub(crate) floor: f64,
    /// What the injection test watches (`StepReport::detector_total`).
    pub(crate) watched: f64,
    /// The budget with every booking, and without the remedies'.
    pub(crate) budget: f64,
    pub(crate) budget_unbooked: f64,
    /// False when periodic along gravity (a wrap jumps by m g H).
    pub(crate) budget_defined: bool,
}

impl Monitor {
    /// Books this step's transfer loss and remedy energies, and observes
    /// the watched total in the injection window.
    pub(crate) fn book_energy(
        &mut self,
        v: &StateView,
        scan: &Scan,
        g: f64,
        dt: f64,
    ) -> EnergyStep {
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
        EnergyStep {
            injection,
            floor,
            watched,
            budget,
            budget_unbooked,
            budget_defined,
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
    pub(crate) fn track_injected_energy(
        &mut self,
        v: &StateView,
        g: f64,
        total: f64,
        vertical_speed: f64,
    ) {
        let e = &v.energy;
        let energy_scale = e.kinetic_with_affine().abs()
            + e.gravitational.abs()
            + e.stored.abs()
            + e.dissipated.abs();
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
}
