//! The kick detector (docs/physics.md section 4b): one pass over the
//! particles takes the cheap figures and keeps their histories; the
//! velocity-jump rule (`jump`) flags the particles whose velocity change
//! the local flow does not share; the whole-state checks open
//! energy-injection and blow-out events.

use crate::clustering::Cluster;
use crate::events::{CellRange, EventKind, Outcome, Rule};
use crate::particle_history::Calm;
use crate::Monitor;
use solver::StateView;

/// A particle that jumped this step, with its history from before it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate {
    pub(crate) p: u32,
    /// Its force-driven |a_p|.
    pub(crate) a: f64,
    /// Its change's departure from the local flow's (m/s), and whether that
    /// flow was calm.
    pub(crate) jump: f64,
    pub(crate) calm_flow: bool,
    /// Its quiet spell and earlier peak |dev D| (hallmark evidence).
    pub(crate) calm: Calm,
}

/// The cheap figures of the per-particle pass.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scan {
    pub(crate) max_speed2: f64,
    pub(crate) max_a2: f64,
    /// Largest squared transfer jump, and this step's transfer loss.
    pub(crate) max_jump2: f64,
    pub(crate) transfer_loss: f64,
    pub(crate) j_min: f64,
    pub(crate) j_max: f64,
    /// Smallest det F (J <= 0 or det F <= 0 is an inversion; the exp J update keeps J > 0).
    pub(crate) det_min: f64,
    /// Largest kinetic-energy gain 1/2 m (|v|^2 - |v_prev|^2), and its particle.
    pub(crate) gain_max: (f64, usize),
}

impl Scan {
    fn new() -> Self {
        Scan {
            max_speed2: 0.0,
            max_a2: 0.0,
            max_jump2: 0.0,
            transfer_loss: 0.0,
            j_min: f64::INFINITY,
            j_max: f64::NEG_INFINITY,
            det_min: f64::INFINITY,
            gain_max: (f64::NEG_INFINITY, 0),
        }
    }
}

impl Monitor {
    /// One pass over the particles: the cheap figures and the history update.
    pub(crate) fn scan_particles(&mut self, v: &StateView, dt: f64) -> Scan {
        let det_apart = v.j_update == solver::JUpdate::Exp;
        let (quiet2, quiet_rate) = (self.cfg.quiet_speed.powi(2), self.cfg.quiet_rate);
        let (time, prev_time) = (v.time, self.prev_time);
        let n = v.x.len();
        let mut s = Scan::new();
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
            s.max_a2 = s.max_a2.max(accel[p].norm_squared());
            let speed2 = vel[p].norm_squared();
            s.max_speed2 = s.max_speed2.max(speed2);
            // FLIP's exact update against what the transfer gave.
            let flip = vel_prev[p] + dt * accel[p];
            s.max_jump2 = s.max_jump2.max((vel[p] - flip).norm_squared());
            s.transfer_loss += 0.5 * mass[p] * (flip.norm_squared() - speed2);
            s.j_min = s.j_min.min(jac[p]);
            s.j_max = s.j_max.max(jac[p]);
            let gain = 0.5 * mass[p] * (speed2 - vel_prev[p].norm_squared());
            if gain > s.gain_max.0 {
                s.gain_max = (gain, p);
            }
            if det_apart {
                s.det_min = s.det_min.min(def[p].determinant());
            }
            let rate = dev_rate[p];
            h.record_levels(p, time, prev_time, |factor| {
                speed2 > quiet2 * factor * factor || rate > quiet_rate
            });
            h.record(
                p,
                time,
                prev_time,
                speed2 > quiet2 || rate > quiet_rate,
                rate,
            );
        }
        s
    }

    /// This step's jumps into `flagged`, each with its calm before the
    /// burst; the largest departure (m/s).
    pub(crate) fn flag_jumps(&mut self, v: &StateView) -> f64 {
        let rule = self.jump_rule();
        let jumps = self.jumps.observe(&self.geom, v, &rule);
        let grace = self.cfg.merge_seconds;
        self.flagged.clear();
        let mut largest: f64 = 0.0;
        for j in jumps.iter() {
            let p = j.p as usize;
            largest = largest.max(j.residual);
            self.flagged.push(Candidate {
                p: j.p,
                a: v.accel[p].norm(),
                jump: j.residual,
                calm_flow: j.calm,
                calm: self.history.calm(p, v.time, grace),
            });
        }
        largest
    }

    /// An energy-injection event at the particle that gained most
    /// (`gainer`) when the window's gain exceeds its floor and is local: at
    /// least half of this step's kinetic-energy gains lie within
    /// `merge_cells` of it. A gain spread over the body is the pump figure.
    pub(crate) fn check_energy_injection(
        &mut self,
        v: &StateView,
        g: f64,
        gain: f64,
        floor: f64,
        gainer: usize,
    ) {
        // A NaN gain is no injection; with no particle left (the last
        // deleted) no one gained, and there is no site to place it at.
        if gain.partial_cmp(&floor) != Some(std::cmp::Ordering::Greater)
            || gainer >= v.x.len()
            || !self.gain_is_local(v, gainer)
        {
            return;
        }
        self.fill_accel(v);
        let (i, j) = self.geom.cell_of(v.x[gainer]);
        let cluster = Cluster::new(
            CellRange::of(i, j),
            Rule::InjectionWindow.into(),
            self.accel[gainer],
        );
        self.attach(EventKind::EnergyInjection, cluster, v, g, false);
    }

    /// At least half of this step's kinetic-energy gains lie within
    /// `merge_cells` cells of particle `at`.
    fn gain_is_local(&self, v: &StateView, at: usize) -> bool {
        let (i, j) = self.geom.cell_of(v.x[at]);
        self.gain_is_near(v, CellRange::of(i, j))
    }

    /// At least half of this step's kinetic-energy gains lie within
    /// `merge_cells` cells of `cells`: a gain spread over the body is not
    /// theirs.
    pub(crate) fn gain_is_near(&self, v: &StateView, cells: CellRange) -> bool {
        let reach = self.cfg.merge_cells;
        let (mut near, mut all) = (0.0, 0.0);
        for p in 0..v.x.len() {
            let gain = 0.5 * v.mass[p] * (v.v[p].norm_squared() - v.v_prev[p].norm_squared());
            if gain > 0.0 {
                all += gain;
                let (i, j) = self.geom.cell_of(v.x[p]);
                if cells.near(&CellRange::of(i, j), reach) {
                    near += gain;
                }
            }
        }
        2.0 * near >= all
    }

    /// Non-finite state, particles outside the box or one faster than the
    /// escape speed: the blow-out event and why the run must stop.
    pub(crate) fn check_blow_out(
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
            // Kept inverted particles extend their event while they last.
            let stops = v.scene.on_inversion != solver::OnLoss::Keep;
            self.blow_out_event(EventKind::Inversion, Rule::Inversion, v, (g, stops), |p| {
                v.j[p] <= 0.0 || v.deformation[p].determinant() <= 0.0
            });
            if stops {
                return Some(reason);
            }
        }
        if v.n_nonfinite > 0 {
            let reason = format!("non-finite state in {} particles", v.n_nonfinite);
            self.blow_out_event(EventKind::NonFinite, Rule::NonFinite, v, (g, true), |p| {
                let (x, vel) = (v.x[p], v.v[p]);
                !(x.x.is_finite() && x.y.is_finite() && vel.x.is_finite() && vel.y.is_finite())
            });
            return Some(reason);
        }
        // A non-finite total with finite particles (e.g. U(J) at J -> 0) is not dropped by a min.
        if !v.energy.total().is_finite() {
            let reason = format!("non-finite total energy {}", v.energy.total());
            self.blow_out_event(EventKind::NonFinite, Rule::NonFinite, v, (g, true), |p| {
                !v.j[p].is_finite() || v.j[p] <= 0.0
            });
            return Some(reason);
        }
        if v.n_outside > 0 {
            let reason = format!("{} particles left the box", v.n_outside);
            let (lo, hi) = (self.geom.origin, self.geom.origin + self.geom.size);
            self.blow_out_event(EventKind::BlowOut, Rule::OutsideBox, v, (g, true), |p| {
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
            self.blow_out_event(EventKind::BlowOut, Rule::EscapeSpeed, v, (g, true), |p| {
                v.v[p].norm() > escape
            });
            return Some(reason);
        }
        None
    }

    /// The run stops at this step: every event still open (within the merge
    /// window of its last step) gets the stop's outcome.
    pub(crate) fn stopped(&mut self, v: &StateView) {
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
}
