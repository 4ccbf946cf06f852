//! The energy arithmetic of each step (docs/physics.md section 4b): the
//! transfer loss, gravity's stepping term, the booked terms (the transfer's
//! where it is counted, each remedy's, the projection's and the hourglass
//! control's) into the ledger, the budget's drift, and the energy each open
//! event gained over the injection window against its floor.

use crate::detector::Scan;
use crate::energy_budget::{Entry, Gain, ADVECTION, FIRST_REMEDY, HOURGLASS, PROJECTION, TRANSFER};
use crate::events::EventKind;
use crate::Monitor;
use solver::StateView;

/// Relative round-off of the energy sums (O(1e-16) per term over up to 1e6
/// particles, with margin): a rise below this times the energies' magnitude
/// is not an injection.
pub const ROUND_OFF: f64 = 1e-12;

/// A step's energy figures (`Monitor::book_energy`).
pub(crate) struct EnergyStep {
    /// The largest gain over the injection window ending now, and the run's
    /// credited gain (the pump figure); 0 where the budget is undefined.
    pub(crate) window: Gain,
    pub(crate) run_gain: f64,
    /// The floor of a whole-body injection: 1/2 M `jump_speed`^2, the
    /// `injection_share` of the kinetic energy and round-off.
    pub(crate) floor: f64,
    /// The ledger's base (`StepReport::detector_total`).
    pub(crate) base: f64,
    /// The budget with every booking, and without the remedies'.
    pub(crate) budget: f64,
    pub(crate) budget_unbooked: f64,
    /// False when periodic along gravity (a wrap jumps by m g H).
    pub(crate) budget_defined: bool,
}

impl Monitor {
    /// Books this step's transfer loss, gravity's stepping term and the
    /// booked terms, and observes the ledger's window.
    pub(crate) fn book_energy(&mut self, v: &StateView, scan: &Scan, g: f64) -> EnergyStep {
        let step_loss = self.step_transfer_loss(v, scan);
        self.book_gravity_stepping(v, g);
        // Each remedy's removals are its dissipation, its additions its
        // injection; the ledger judges both by their net over the window.
        self.booking.book(v.remedies.energy_parts());
        let loss_counted = v.transfer != solver::TransferKind::Apic;
        let entry = self.ledger_entry(v, step_loss, loss_counted);
        let (mut window, mut run_gain) = self.ledger.observe(entry);
        // Periodic along gravity, a particle that wraps jumps by m g H in
        // potential energy: the budget is undefined there, so its rule is off.
        let budget_defined = !(v.scene.periodic[1] && g > 0.0);
        if !budget_defined {
            window = Gain::default();
            run_gain = 0.0;
        }
        // The budget: E (with the affine part) + L + the remedies' bookings,
        // gravity's stepping term booked.
        let loss = if loss_counted {
            self.transfer_loss
        } else {
            0.0
        };
        let (budget, budget_unbooked) = if v.affine_inertia.is_some() {
            let e = v.energy.total_with_affine() + self.transfer_loss - self.gravity_stepping;
            (e + self.booking.detector_offset(true), e)
        } else {
            let e = v.energy.total() + loss - self.gravity_stepping;
            (e + self.booking.detector_offset(loss_counted), e)
        };
        let u = self.cfg.jump_speed;
        EnergyStep {
            window,
            run_gain,
            floor: 0.5 * self.initial_mass * u * u
                + self.cfg.injection_share * v.energy.kinetic_with_affine()
                + ROUND_OFF * energy_scale(v),
            base: entry.base,
            budget,
            budget_unbooked,
            budget_defined,
        }
    }

    /// This step's transfer loss, added to the run's.
    fn step_transfer_loss(&mut self, v: &StateView, scan: &Scan) -> f64 {
        // B-spline APIC: both transfers are projections once the affine
        // velocity's energy is counted, so the loss is measured on the grid
        // (particles before P2G minus the grid after it, the updated grid
        // minus the particles after G2P), each part >= 0 away from walls.
        // The staggered step's transfers are read on its faces under any
        // transfer: the particle-side FLIP reading cannot see its P2G.
        let step_loss = if v.staggered || v.affine_inertia.is_some() {
            // An impulse is no transfer: it stays an injection.
            (v.ke_particles_p2g - v.ke_grid_p2g)
                + (v.ke_grid_updated - (v.energy.kinetic_with_affine() - v.impulse_kinetic))
        } else {
            scan.transfer_loss
        };
        if step_loss.is_finite() {
            self.transfer_loss += step_loss;
            step_loss
        } else {
            0.0
        }
    }

    /// Gravity's stepping term, booked exactly: the particles' potential
    /// energy change less gravity's work at their time-centred velocity, m g
    /// dt (v_y^n + v_y^{n+1}) / 2 each. Of it, the part beyond the position
    /// update at the new velocity, m g (dy - dt v_y^{n+1}), is the
    /// *advection* term: positions moved other than by the particles' own
    /// velocity (FLIP's grid velocity, wall clamps), judged in the ledger
    /// by its net like any booked term. The rest, m g
    /// dt (v_y^{n+1} - v_y^n) / 2, is what symplectic Euler adds beside the
    /// physics; it telescopes over a window. Over a step that deleted or
    /// added particles neither is defined, and both are left out. The
    /// pressure-implicit drift correction's move is such an advection, but
    /// the solver books it (in its dissipation): it is left out of the
    /// stepping term (booked twice, it read as a budget drift of the whole
    /// move) and the ledger reads it as the advection's, not the
    /// projection's (`ledger_entry`).
    fn book_gravity_stepping(&mut self, v: &StateView, g: f64) {
        let pe = v.energy.gravitational;
        let booked_move = v.projection.map_or(0.0, |p| p.stats.dissipated_packing);
        if let Some(prev) = self.prev_potential.filter(|_| !self.ids_changed) {
            let (mut centred, mut new) = (0.0, 0.0);
            for p in 0..v.x.len() {
                centred += v.mass[p] * 0.5 * (v.v[p].y + v.v_prev[p].y);
                new += v.mass[p] * v.v[p].y;
            }
            let term = (pe - prev + booked_move) - g * v.dt * centred;
            let advection = (pe - prev) - g * v.dt * new;
            if term.is_finite() && advection.is_finite() {
                self.gravity_stepping += term;
                self.advection_stepping += advection;
            }
        }
        self.prev_potential = Some(pe);
    }

    /// The ledger's entry for this step: the base, and each booked term's
    /// cumulative net removal (its presence noted).
    fn ledger_entry(&mut self, v: &StateView, step_loss: f64, loss_counted: bool) -> Entry {
        let mut terms = self.ledger_terms;
        if loss_counted {
            terms[TRANSFER] += step_loss;
            self.ledger.present.insert(TRANSFER);
        }
        if let Some(p) = v.projection {
            // The drift correction's move is the advection term's.
            terms[PROJECTION] += p.stats.dissipated_projection - p.stats.dissipated_packing;
            terms[HOURGLASS] += p.stats.dissipated_hourglass;
            self.ledger.present.insert(PROJECTION);
            self.ledger.present.insert(HOURGLASS);
        }
        // Energy the advection added is a removal of minus that.
        terms[ADVECTION] = -self.advection_stepping;
        self.ledger.present.insert(ADVECTION);
        for (slot, b) in self.booking.booked.iter().enumerate() {
            if let Some(b) = b {
                terms[FIRST_REMEDY + slot] = b.dissipated - b.injected;
                self.ledger.present.insert(FIRST_REMEDY + slot);
            }
        }
        self.ledger_terms = terms;
        // The base: what no term books. The solver adds the projection's and
        // the hourglass control's removals to the dissipation: taken out here,
        // they count as terms (the solve's; the drift correction's move stays
        // in the dissipation, so its potential energy change nets to 0 in
        // the total); the remedies' parts the loss and the dissipation
        // already hold are taken back (`detector_offset` less the remedies'
        // own removals).
        let held = self.booking.detector_offset(loss_counted) - self.booking.dissipated();
        // Gravity's stepping term is booked exactly, less the advection's
        // part, which is a term. The drift correction's move is out of the
        // first and in the second, so `symplectic` carries +R for a move
        // that removed R: the base falls by R, which the advection term
        // books.
        let symplectic = self.gravity_stepping - self.advection_stepping;
        let base = v.energy.total() - terms[PROJECTION] - terms[HOURGLASS] - symplectic + held;
        Entry {
            t: v.time,
            base,
            terms,
        }
    }

    /// The energy each event touched at this step gained over the window
    /// (the largest so far), the terms that added over it, and its floor:
    /// 1/2 m `jump_speed`^2 of the event's mass m (the whole mass for an
    /// energy-injection event), the `injection_share` of the kinetic energy
    /// m carries at the body's mean (specific kinetic energy), and the sums'
    /// round-off.
    pub(crate) fn track_injected_energy(&mut self, v: &StateView, window: Gain) {
        let (step, time, merge) = (v.step, v.time, self.cfg.merge_seconds);
        let mean_mass = self.initial_mass / self.event_mark.len().max(1) as f64;
        let (u, scale) = (self.cfg.jump_speed, energy_scale(v));
        let kinetic = self.cfg.injection_share * v.energy.kinetic_with_affine() / self.initial_mass;
        for k in 0..self.events.len() {
            let e = &self.events[k];
            let live = e.last_step + 1 >= step || time - e.last_t <= merge;
            if !live || e.last_step != step {
                continue;
            }
            // The window's gain is the event's only where this step's gains
            // are: a gain spread over the body is the pump figure.
            let whole_body = e.kind == EventKind::EnergyInjection;
            let theirs = window.gain > 0.0 && (whole_body || self.gain_is_near(v, e.extent));
            let e = &mut self.events[k];
            if theirs {
                e.energy_injected = e.energy_injected.max(window.gain);
                e.evidence.booked_added = e.evidence.booked_added.union(window.added);
            }
            let mass = if e.kind == EventKind::EnergyInjection {
                self.initial_mass
            } else {
                e.n_particles as f64 * mean_mass
            };
            e.evidence.energy_floor = 0.5 * mass * u * u + kinetic * mass + ROUND_OFF * scale;
            e.classify();
        }
    }
}

/// The magnitude of the energies (the round-off floor's scale).
fn energy_scale(v: &StateView) -> f64 {
    let e = &v.energy;
    e.kinetic_with_affine().abs() + e.gravitational.abs() + e.stored.abs() + e.dissipated.abs()
}
