//! The energy the motion gains (docs/physics.md section 7), on every
//! yardstick flow (Taylor-Green, the shear wave, the standing wave, the
//! sound wave). Each starts from the water at rest plus a velocity field,
//! so the physical energy of the motion is E = kinetic (with APIC's affine
//! part) + potential + stored, less the same water's at rest, and the
//! wave's energy is E(0). Under gravity the water at rest is a *rest twin*:
//! the same case without its flow and its perturbations, stepped beside it
//! with the same steps, so a method that moves its own rest state (lifts or
//! drains the water) does not read as growth; without gravity it is the
//! state at t = 0. No booked term is added back: a method that puts
//! energy in shows it as growth. E is averaged over blocks of one energy
//! period (pi / omega: kinetic and potential or stored energy trade twice a
//! period), so the exchange does not read as growth. The figures: the
//! growth from the first block to the last within `GROWTH_WINDOW_S`, the
//! largest growth between blocks at most `LARGEST_WINDOW_S` apart, both as
//! fractions of the wave's energy, and the energy each booked term moved
//! over the same blocks, added and removed, each by its net over a block.

use crate::output::summary::Check;
use crate::run::{Probe, Run, Simulated};
use monitor::energy_budget::{term_name, Terms, TERMS, TRANSFER};
use serde::{Deserialize, Serialize};
use solver::flows::Flow;
use solver::{Solver, SolverConfig};

/// The growth's window from the first block (s).
pub const GROWTH_WINDOW_S: f64 = 5.0;
/// The largest growth's window (s).
pub const LARGEST_WINDOW_S: f64 = 1.0;
/// A *pump*: in an inviscid run, the motion's energy grows by more than
/// this share of the wave's, over the growth's window or over any
/// `LARGEST_WINDOW_S` (fixed before the runs it judges).
pub const PUMP_SHARE: f64 = 0.01;
/// *Cycling*: the booked terms put in, and take out, more energy than the
/// wave holds (the smaller of the two, over the wave's energy).
pub const CYCLING_SHARE: f64 = 1.0;

/// One booked term's energy moved over the growth window (J/m).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TermMoved {
    pub term: String,
    pub added: f64,
    pub removed: f64,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyGainFigures {
    /// The motion's energy at t = 0 (J/m).
    pub wave_energy: f64,
    /// The averaging block, one energy period pi / omega (s; the step where
    /// that is shorter).
    pub energy_period_s: f64,
    /// The centres of the first and last blocks the growth spans (s).
    pub growth_from_s: Option<f64>,
    pub growth_to_s: Option<f64>,
    /// (mean E of the last block - of the first) / wave_energy.
    pub growth: Option<f64>,
    /// The largest (mean E_j - mean E_i) / wave_energy over blocks i before
    /// j, at most `LARGEST_WINDOW_S` apart, within the growth's window.
    pub largest_growth_1s: Option<f64>,
    /// Each booked term the method has, over the growth's window.
    pub booked: Vec<TermMoved>,
    /// Every booked term's energy moved (added + removed) over the growth's
    /// window, over wave_energy.
    pub booked_moved: f64,
    /// E was measured above a rest twin (else above the state at t = 0).
    #[serde(default)]
    pub rest_twin: bool,
}

impl Check for EnergyGainFigures {
    const NAME: &'static str = "energy_gain";
}

impl EnergyGainFigures {
    /// The larger of the growth and the largest 1 s growth.
    pub fn largest_growth(&self) -> Option<f64> {
        self.growth
            .into_iter()
            .chain(self.largest_growth_1s)
            .reduce(f64::max)
    }

    /// The run pumps (None: too short to tell); judged on inviscid runs.
    pub fn is_pump(&self) -> Option<bool> {
        self.largest_growth().map(|g| g > PUMP_SHARE)
    }

    /// The smaller of the energy the booked terms added and removed, over
    /// wave_energy: above `CYCLING_SHARE`, the method cycles more energy
    /// than the wave holds (a damper only removes).
    pub fn booked_cycled(&self) -> f64 {
        let added: f64 = self.booked.iter().map(|m| m.added).sum();
        let removed: f64 = self.booked.iter().map(|m| m.removed).sum();
        added.min(removed) / self.wave_energy.abs().max(f64::MIN_POSITIVE)
    }

    pub fn is_cycling(&self) -> bool {
        self.booked_cycled() > CYCLING_SHARE
    }
}

/// One closed block: its centre, mean E and each term's cumulative net
/// removal at its end.
#[derive(Clone, Copy, Debug)]
struct Block {
    centre: f64,
    mean: f64,
    terms: [f64; TERMS],
}

pub struct EnergyGain {
    period: f64,
    /// E's rest part at t = 0 (potential + stored) and E(0).
    rest: Option<f64>,
    /// The rest twin, stepped to the run's time (None: no gravity, or it
    /// failed or could not follow a restored run).
    twin: Option<Solver>,
    twin_start: Option<f64>,
    twin_used: bool,
    wave_energy: f64,
    present: Terms,
    /// The open block: its start, the time it spans and the integral of E;
    /// the last observation's time.
    start: f64,
    span: f64,
    integral: f64,
    last_t: Option<f64>,
    start_terms: [f64; TERMS],
    blocks: Vec<Block>,
}

impl EnergyGain {
    /// For a case with one body whose flow is a yardstick's.
    pub fn new(cfg: &SolverConfig) -> Option<Self> {
        let scene = &cfg.scene;
        let [body] = scene.bodies.as_slice() else {
            return None;
        };
        let flow = body.flow?;
        let material = &scene.materials[scene.material_index(body)?];
        let k = flow.wavenumber(body.rect);
        let omega = match flow {
            Flow::StandingWave { .. } => flow.omega(body.rect, scene.gravity),
            Flow::GridSeed { .. } => return None,
            _ => material.wave_speed(1.0) * k,
        };
        let twin = (scene.gravity > 0.0)
            .then(|| {
                let mut rest = cfg.clone();
                rest.scene.bodies[0].flow = None;
                rest.perturb.clear();
                Solver::new(rest).ok()
            })
            .flatten();
        Some(EnergyGain::with(std::f64::consts::PI / omega, twin))
    }

    /// A probe with blocks of `period` seconds, above `twin` if any.
    fn with(period: f64, twin: Option<Solver>) -> Self {
        EnergyGain {
            period,
            rest: None,
            twin,
            twin_start: None,
            twin_used: false,
            wave_energy: 0.0,
            present: Default::default(),
            start: 0.0,
            span: 0.0,
            integral: 0.0,
            last_t: None,
            start_terms: [0.0; TERMS],
            blocks: Vec::with_capacity(1024),
        }
    }

    /// Observes E at `t` (the first call: t = 0 or the restored step), with
    /// the booked terms' cumulative net removals.
    fn observe(&mut self, t: f64, e: Energies, terms: &[f64; TERMS]) {
        let rest = *self.rest.get_or_insert(e.potential + e.stored);
        let motion = e.kinetic + e.potential + e.stored - rest;
        let Some(before) = self.last_t.replace(t) else {
            self.wave_energy = motion;
            self.start = t;
            self.start_terms = *terms;
            return;
        };
        let dt = t - before;
        self.integral += motion * dt;
        self.span += dt;
        if self.span >= self.period {
            self.blocks.push(Block {
                centre: self.start + 0.5 * self.span,
                mean: self.integral / self.span,
                terms: *terms,
            });
            self.start = t;
            self.span = 0.0;
            self.integral = 0.0;
        }
    }

    fn figures(&self) -> EnergyGainFigures {
        let mut f = EnergyGainFigures {
            wave_energy: self.wave_energy,
            energy_period_s: self.period,
            rest_twin: self.twin_used,
            ..Default::default()
        };
        let Some(first) = self.blocks.first() else {
            return f;
        };
        let within: Vec<&Block> = self
            .blocks
            .iter()
            .take_while(|b| b.centre <= first.centre + GROWTH_WINDOW_S)
            .collect();
        let last = within[within.len() - 1];
        let scale = self.wave_energy.abs().max(f64::MIN_POSITIVE);
        if within.len() >= 2 {
            f.growth_from_s = Some(first.centre);
            f.growth_to_s = Some(last.centre);
            f.growth = Some((last.mean - first.mean) / scale);
            f.largest_growth_1s = Some(largest_growth(&within) / scale);
        }
        let mut previous = self.start_terms;
        let mut moved = [(0.0, 0.0); TERMS];
        for b in &within {
            for k in 0..TERMS {
                let net = b.terms[k] - previous[k];
                if net > 0.0 {
                    moved[k].1 += net;
                } else {
                    moved[k].0 -= net;
                }
            }
            previous = b.terms;
        }
        for k in (0..TERMS).filter(|&k| self.present.contains(k)) {
            f.booked.push(TermMoved {
                term: term_name(k).to_string(),
                added: moved[k].0,
                removed: moved[k].1,
            });
            f.booked_moved += (moved[k].0 + moved[k].1) / scale;
        }
        f
    }
}

/// The largest mean_j - mean_i over blocks i before j at most
/// `LARGEST_WINDOW_S` apart (0 when E never rises).
fn largest_growth(blocks: &[&Block]) -> f64 {
    let mut best: f64 = 0.0;
    for (j, b) in blocks.iter().enumerate() {
        for a in blocks[..j].iter().rev() {
            if b.centre - a.centre > LARGEST_WINDOW_S {
                break;
            }
            best = best.max(b.mean - a.mean);
        }
    }
    best
}

/// The energies E is made of (J/m).
#[derive(Clone, Copy, Debug)]
struct Energies {
    kinetic: f64,
    potential: f64,
    stored: f64,
}

/// The energies, each booked term's cumulative net removal, and the terms
/// present. The transfer's loss is reported for every method, also where
/// the detector's ledger does not count it (APIC's B-spline budget).
fn energies(run: &Run<Solver>) -> (Energies, [f64; TERMS], Terms) {
    let e = run.stepper.view().energy;
    let monitor = &run.watches[0].monitor;
    let (mut present, terms) = monitor.booked_terms();
    let mut terms = *terms;
    terms[TRANSFER] = monitor.report().transfer_loss;
    present.insert(TRANSFER);
    let e = Energies {
        kinetic: e.kinetic_with_affine(),
        potential: e.gravitational,
        stored: e.stored,
    };
    (e, terms, present)
}

impl EnergyGain {
    /// The rest twin stepped to `t` (its steps the run's), and its energy
    /// now (None without a twin).
    fn rest_drift(&mut self, t: f64) -> Option<f64> {
        let twin = self.twin.as_mut()?;
        let dt = t - twin.time();
        if dt > 0.0 && twin.step_with_dt(dt).is_err() {
            self.twin = None;
            return None;
        }
        let e = twin.view().energy;
        Some(e.kinetic_with_affine() + e.gravitational + e.stored)
    }

    /// E's parts at `t`, the rest twin's drift since t = 0 taken off (booked
    /// with the potential energy: only the sum counts).
    fn observe_run(&mut self, run: &Run<Solver>) {
        let (mut e, terms, present) = energies(run);
        self.present = present;
        let t = run.stepper.time();
        if let Some(now) = self.rest_drift(t) {
            let start = *self.twin_start.get_or_insert(now);
            e.potential -= now - start;
            self.twin_used = true;
        }
        self.observe(t, e, &terms);
    }
}

impl Probe<Solver> for EnergyGain {
    fn begin(&mut self, run: &Run<Solver>) -> std::io::Result<()> {
        // A restored run starts past t = 0, where the twin cannot follow.
        if run.stepper.time() > 0.0 {
            self.twin = None;
        }
        self.observe_run(run);
        Ok(())
    }

    fn after_step(&mut self, run: &Run<Solver>, _: &[u32]) -> std::io::Result<()> {
        self.observe_run(run);
        Ok(())
    }

    fn finish(&mut self, _: &Run<Solver>, outcome: &mut Simulated) -> std::io::Result<()> {
        outcome.metrics.set_check(&self.figures());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wave that trades kinetic for potential energy twice a period, and
    /// loses 30 % of it in the trade and gets it back (the mean of E is
    /// 0.85 E(0)), reads no growth; the same with a source that adds 2 % a
    /// second reads 0.85 x 2 % a second, over 5 s and over 1 s. A term that
    /// adds and removes alike within each block moves nothing; one that
    /// removes steadily moves what it removed.
    #[test]
    fn growth_is_read_through_the_exchange_and_booked_terms_by_block() {
        let (omega, e0, dt) = (8.4, 0.0245, 1e-3);
        let period = std::f64::consts::PI / omega;
        for source in [0.0, 0.02] {
            let mut p = EnergyGain::with(period, None);
            p.present.insert(1);
            p.present.insert(4);
            for n in 0..=6000 {
                let t = n as f64 * dt;
                let c2 = (omega * t).cos().powi(2);
                let e = Energies {
                    kinetic: e0 * c2 * (1.0 + source * t),
                    potential: 39.0 + 0.7 * e0 * (1.0 - c2) * (1.0 + source * t),
                    stored: 0.5,
                };
                let mut terms = [0.0; TERMS];
                terms[1] = 1e-4 * (2.0 * omega * t).sin();
                terms[4] = 1e-3 * t;
                p.observe(t, e, &terms);
            }
            let f = p.figures();
            assert!((f.wave_energy / e0 - 1.0).abs() < 1e-12, "{f:?}");
            let span = f.growth_to_s.unwrap() - f.growth_from_s.unwrap();
            assert!(span <= GROWTH_WINDOW_S && span > GROWTH_WINDOW_S - 2.0 * period);
            let g = f.growth.unwrap();
            assert!((g - 0.85 * source * span).abs() < 1e-3, "{g} at {source}");
            let largest = f.largest_growth_1s.unwrap();
            let most = 0.85 * source * LARGEST_WINDOW_S;
            assert!(
                largest <= most + 1e-3 && largest >= most * (1.0 - period) - 1e-3,
                "{largest}"
            );
            let moved = |name: &str| f.booked.iter().find(|m| m.term == name).unwrap().clone();
            let projection = moved("projection");
            assert!(
                projection.added + projection.removed < 1e-5,
                "{projection:?}"
            );
            let steady = moved(term_name(4));
            let end = f.growth_to_s.unwrap() + period;
            assert!(
                (steady.removed - 1e-3 * end).abs() < 1e-3 * period,
                "{steady:?}"
            );
            assert_eq!(steady.added, 0.0);
        }
    }
}
