//! A mixture's conservation checks: total energy growth (where the budget
//! is defined), momentum drift (periodic, no gravity, free skeleton), the
//! drag's dissipated energy, and the largest cell saturation at the end.

use super::mixture_scene::momentum_and_scale;
use crate::output::summary::Check;
use crate::run::{Probe, Run, Simulated};
use crate::study_file::MixtureSpec;
use serde::{Deserialize, Serialize};
use solver::{Mixture, Scene, Vec2};

/// Largest saturation of a cell: the reference volumes (grains and the
/// fluid's V_p^0) of the particles in it over its area. 1 in a saturated
/// mixture; above 1 where water crowds into the grains' room.
fn saturation_max(mix: &Mixture) -> f64 {
    let v = mix.phase(0).view();
    let (h, o) = (v.scene.cell, v.scene.origin);
    let [nx, ny] = [0, 1].map(|k| (v.scene.size[k] / h).round() as usize);
    let mut cells = vec![0.0; nx * ny];
    for k in 0..2 {
        let v = mix.phase(k).view();
        for (x, v0) in v.x.iter().zip(v.volume0) {
            let i = (((x.x - o[0]) / h).floor().max(0.0) as usize).min(nx - 1);
            let j = (((x.y - o[1]) / h).floor().max(0.0) as usize).min(ny - 1);
            cells[i + j * nx] += v0;
        }
    }
    cells.iter().fold(0.0, |m: f64, c| m.max(c / (h * h)))
}

/// At the end: the largest saturation of a cell (grains' and fluid's
/// reference volumes over its area; above 1 where the water crowds into
/// the grains' room); the kinetic energy the drag dissipated (J/m); the
/// largest rise of the total energy (both phases, drag dissipation
/// included) above its value at t = 0 (J/m), which must stay at round-off
/// (undefined in a box periodic along gravity: a particle that wraps jumps
/// by m g H); the largest |P(t) - P(0)| of both phases' momentum relative
/// to sum m |v| at t = 0 (periodic scenes without gravity only).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MixtureFigures {
    pub saturation_max: f64,
    pub drag_dissipated: f64,
    pub energy_growth: Option<f64>,
    pub momentum_drift_rel: Option<f64>,
}

impl Check for MixtureFigures {
    const NAME: &'static str = "mixture";
}

pub struct MixtureConservation {
    /// Periodic on both axes, no gravity, a free skeleton.
    conserves_momentum: bool,
    /// Not periodic along gravity (where wrapping particles jump in potential energy).
    budget_defined: bool,
    p0: Vec2,
    p_scale: f64,
    momentum_drift: f64,
    e0: f64,
    energy_growth: f64,
}

impl MixtureConservation {
    pub fn new(scene: &Scene, spec: &MixtureSpec, mix: &Mixture) -> Self {
        let (a, b) = (
            momentum_and_scale(mix.phase(0)),
            momentum_and_scale(mix.phase(1)),
        );
        MixtureConservation {
            conserves_momentum: scene.periodic == [true, true]
                && scene.gravity == 0.0
                && !spec.fixed_solid,
            budget_defined: !(scene.periodic[1] && scene.gravity > 0.0),
            p0: a.0 + b.0,
            p_scale: a.1 + b.1,
            momentum_drift: 0.0,
            e0: mix.energy().total(),
            energy_growth: 0.0,
        }
    }
}

impl Probe<Mixture> for MixtureConservation {
    fn after_step(&mut self, run: &Run<Mixture>, _: &[u32]) -> std::io::Result<()> {
        let mix = run.stepper;
        if self.conserves_momentum && self.p_scale > 0.0 {
            let (a, b) = (
                momentum_and_scale(mix.phase(0)),
                momentum_and_scale(mix.phase(1)),
            );
            let drift = (a.0 + b.0 - self.p0).norm() / self.p_scale;
            self.momentum_drift = self.momentum_drift.max(drift);
        }
        self.energy_growth = self.energy_growth.max(mix.energy().total() - self.e0);
        Ok(())
    }

    fn finish(&mut self, run: &Run<Mixture>, outcome: &mut Simulated) -> std::io::Result<()> {
        let mix = run.stepper;
        outcome.metrics.set_check(&MixtureFigures {
            saturation_max: saturation_max(mix),
            drag_dissipated: mix.drag_dissipated(),
            energy_growth: self.budget_defined.then_some(self.energy_growth),
            momentum_drift_rel: (self.conserves_momentum && self.p_scale > 0.0)
                .then_some(self.momentum_drift),
        });
        Ok(())
    }
}
