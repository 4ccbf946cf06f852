//! The kick detector: one pass over the particles flags candidates (a
//! kinetic-energy spike, or a gaining particle above `kick_accel_g` whose
//! robust z among its neighbours' accelerations is an outlier), and the
//! whole-state checks open energy-injection and blow-out events
//! (docs/physics.md section 4b).

use crate::clustering::Cluster;
use crate::config::MonitorConfig;
use crate::events::{CellRange, EventKind, Outcome, Rule, Rules};
use crate::particle_history::Calm;
use crate::Monitor;
use solver::StateView;

/// A particle accelerating above `accel_candidate_g`, with its history from before this step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate {
    pub(crate) p: u32,
    /// Force-driven |a_p|.
    pub(crate) a: f64,
    /// NaN until scored (a gaining candidate above `kick_accel_g`), 0 when not scored.
    pub(crate) z: f64,
    pub(crate) rules: Rules,
    /// Its quiet spell and earlier peak |dev D| (hallmark evidence).
    pub(crate) calm: Calm,
}

/// The thresholds of the per-particle pass, from the config, g and dt.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScanThresholds {
    /// Per-step decay of the kinetic-energy history, exp(-dt / ke_history_seconds).
    pub(crate) decay: f64,
    /// Quiescent speed squared (floors the kinetic-energy history as 1/2 m v_q^2).
    pub(crate) quiescent2: f64,
    /// Hallmark activity thresholds: quiet_speed squared, and quiet_rate.
    pub(crate) quiet_speed2: f64,
    pub(crate) quiet_rate: f64,
    /// Squared acceleration of a candidate: (accel_candidate_g g)^2.
    pub(crate) candidate_a2: f64,
    /// det F differs from J (the exp J update): check it apart for inversion.
    pub(crate) det_apart: bool,
    pub(crate) ke_spike_ratio: f64,
    /// kick_accel_g g.
    pub(crate) kick_a: f64,
}

impl ScanThresholds {
    pub(crate) fn new(cfg: &MonitorConfig, g: f64, dt: f64, det_apart: bool) -> Self {
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
pub(crate) struct Scan {
    pub(crate) max_ratio: f64,
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
    /// Largest vertical speed |v_y|.
    pub(crate) max_vertical_speed: f64,
    /// Some candidate awaits its z score.
    pub(crate) need_z: bool,
}

impl Scan {
    pub(crate) fn new() -> Self {
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

impl Monitor {
    /// One pass over the particles: the cheap figures, the history update,
    /// then this step's candidates (with their calm before this burst) into `flagged`.
    pub(crate) fn scan_particles(&mut self, v: &StateView, g: f64, dt: f64) -> Scan {
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
    pub(crate) fn score_candidates(&mut self, v: &StateView) -> f64 {
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
    pub(crate) fn check_energy_injection(
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
