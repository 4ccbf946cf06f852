//! The drag-convergence scene (docs/physics.md section 6).

use super::drag_decay::discrete_decay;
use super::mixture_scene::{fixed_layer, mean_velocity};
use crate::output::summary::Check;
use crate::run::{Probe, Run, Simulated};
use crate::study_file::MixtureSpec;
use serde::{Deserialize, Serialize};
use solver::multiphase::drag::DragUpdate;
use solver::{Mixture, Phase, Scene, Vec2};

/// The drag-convergence scene: a fixed layer without gravity in a fluid
/// filling the box, moving along the layer. The fluid inside the layer
/// decays by the update's own law (exp(-t/tau) exponential, prod(1 -
/// dt/tau) explicit, prod 1/(1 + dt/tau) implicit; tau = n rho_f / B), the
/// rest keeps its speed: u(t) = u0 [s law(t) + 1 - s], s = L / H. The error
/// is |u - u(t)| / (|u0| s), its largest over the run: what the
/// interaction model's treatment of the layer's faces costs.
/// The drag-convergence scene (a fixed layer without gravity in a fluid
/// moving along it): the largest error of the fluid's mean velocity
/// against the update's own law inside the layer and free flow outside,
/// relative to the part the layer takes (|u0| L / H).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DragLayerFigures {
    pub error: f64,
}

impl Check for DragLayerFigures {
    const NAME: &'static str = "drag_layer";
}

pub struct LayerCheck {
    u0: Vec2,
    share: f64,
    tau: f64,
    update: DragUpdate,
    law: f64,
    max_error: f64,
}

impl LayerCheck {
    pub fn new(scene: &Scene, spec: &MixtureSpec, mix: &Mixture) -> Option<Self> {
        let u0 = mean_velocity(mix.phase(1));
        let layer = fixed_layer(scene, spec).filter(|_| scene.gravity == 0.0)?;
        let fluid = scene
            .bodies
            .iter()
            .find(|b| b.phase == Some(Phase::Fluid))?;
        let rho = scene.materials[scene.material_index(fluid)?].rho0;
        let n = fluid.fraction;
        let b = spec.drag.coefficient_at(n);
        (u0.norm() > 0.0 && b > 0.0).then(|| LayerCheck {
            u0,
            share: (layer[1] - layer[0]) / scene.size[1],
            tau: n * rho / b,
            update: spec.drag.update,
            law: 1.0,
            max_error: 0.0,
        })
    }
}

impl Probe<Mixture> for LayerCheck {
    fn after_step(&mut self, run: &Run<Mixture>, _: &[u32]) -> std::io::Result<()> {
        let (dt, u) = (
            run.stepper.phase(0).view().dt,
            mean_velocity(run.stepper.phase(1)),
        );
        let r = dt / self.tau;
        self.law *= discrete_decay(self.update, r);
        let expected = self.u0 * (self.share * self.law + 1.0 - self.share);
        let error = (u - expected).norm() / (self.u0.norm() * self.share);
        self.max_error = self.max_error.max(error);
        Ok(())
    }

    fn finish(&mut self, _: &Run<Mixture>, outcome: &mut Simulated) -> std::io::Result<()> {
        outcome.metrics.set_check(&DragLayerFigures {
            error: self.max_error,
        });
        Ok(())
    }
}
