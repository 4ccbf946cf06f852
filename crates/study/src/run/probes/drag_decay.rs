//! The drag-decay scene (docs/physics.md section 6): the phases' relative
//! velocity against the exact decay and the update's own discrete law.

use super::mixture_scene::mean_velocity;
use crate::output::summary::Check;
use crate::run::{Probe, Run, Simulated};
use crate::study_file::MixtureSpec;
use serde::{Deserialize, Serialize};
use solver::multiphase::drag::DragUpdate;
use solver::{Mixture, Phase, Scene, Vec2};

/// The difference of the phases' mean velocities, fluid minus solid.
pub fn relative_velocity(mix: &Mixture) -> Vec2 {
    mean_velocity(mix.phase(1)) - mean_velocity(mix.phase(0))
}

/// The drag-decay scene: periodic in x and y, no gravity, every body
/// covering the whole box (a uniform mixture). Then dv = v_f - v_s decays as
/// dv0 exp(-t/tau), tau = rs rf / [B (rs + rf)] with the partial densities
/// rs = n_s rho_s, rf = n_f rho_f (tau = rf / B over a fixed skeleton).
pub fn decay_time(scene: &Scene, spec: &MixtureSpec) -> Option<f64> {
    let covers = |r: &[f64; 4]| {
        let tol = 1e-12 * scene.size[0].max(scene.size[1]);
        (r[0] - scene.origin[0]).abs() <= tol
            && (r[1] - scene.origin[1]).abs() <= tol
            && (r[2] - scene.origin[0] - scene.size[0]).abs() <= tol
            && (r[3] - scene.origin[1] - scene.size[1]).abs() <= tol
    };
    let uniform = scene.periodic == [true, true]
        && scene.gravity == 0.0
        && scene.bodies.iter().all(|b| covers(&b.rect));
    if !uniform {
        return None;
    }
    let [rs, rf] = Phase::ALL.map(|phase| {
        let b = scene.bodies.iter().find(|b| b.phase == Some(phase));
        b.map_or(0.0, |b| {
            let m = scene.material_index(b).expect("validated");
            b.fraction * scene.materials[m].rho0
        })
    });
    let fraction = |phase| {
        scene
            .bodies
            .iter()
            .find(|b| b.phase == Some(phase))
            .map_or(0.0, |b| b.fraction)
    };
    let (ns, nf) = (fraction(Phase::Solid), fraction(Phase::Fluid));
    let b = spec.drag.coefficient_at(nf / (ns + nf));
    if b <= 0.0 {
        return None;
    }
    Some(if spec.fixed_solid {
        rf / b
    } else {
        rs * rf / (b * (rs + rf))
    })
}

/// The factor by which an update multiplies the relative velocity over a
/// step of dt = r tau, with no other force: 1 - r explicit, 1 / (1 + r)
/// implicit, exp(-r) exponential.
pub fn discrete_decay(update: DragUpdate, r: f64) -> f64 {
    match update {
        DragUpdate::Explicit => 1.0 - r,
        DragUpdate::Implicit => 1.0 / (1.0 + r),
        DragUpdate::Exponential => (-r).exp(),
    }
}

/// The exact decay dv0 exp(-t/tau).
#[derive(Clone, Copy, Debug)]
pub struct DecayLaw {
    pub tau: f64,
    pub dv0: Vec2,
}

impl DecayLaw {
    /// Of a drag-decay scene with a relative velocity.
    pub fn of(scene: &Scene, spec: &MixtureSpec, mix: &Mixture) -> Option<Self> {
        let tau = decay_time(scene, spec)?;
        let dv0 = relative_velocity(mix);
        (dv0.norm() > 0.0).then_some(DecayLaw { tau, dv0 })
    }

    pub fn exact(&self, t: f64) -> Vec2 {
        self.dv0 * (-t / self.tau).exp()
    }
}

/// In a uniform periodic mixture without gravity: the largest |dv(t) - dv0
/// exp(-t/tau)| over the run relative to |dv0|, dv the difference of the
/// phases' mean velocities; the same against the update's own discrete law
/// (explicit prod(1 - dt/tau), implicit prod 1/(1 + dt/tau), exponential
/// exp(-t/tau)); and the first step's dt/tau.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DragDecayFigures {
    pub rel_error: f64,
    pub discrete_rel_error: f64,
    pub dt_over_tau: Option<f64>,
}

impl Check for DragDecayFigures {
    const NAME: &'static str = "drag_decay";
}

/// The relative velocity against the exact decay and the update's own law.
pub struct DecayCheck {
    law: DecayLaw,
    update: DragUpdate,
    /// The update's discrete decay factor so far.
    discrete: f64,
    max_error: f64,
    max_discrete_error: f64,
    first_ratio: Option<f64>,
}

impl DecayCheck {
    /// Against the scene's exact decay `law`, for the drag's `update`.
    pub fn new(law: DecayLaw, update: DragUpdate) -> Self {
        DecayCheck {
            law,
            update,
            discrete: 1.0,
            max_error: 0.0,
            max_discrete_error: 0.0,
            first_ratio: None,
        }
    }
}

impl Probe<Mixture> for DecayCheck {
    fn after_step(&mut self, run: &Run<Mixture>, _: &[u32]) -> std::io::Result<()> {
        let mix = run.stepper;
        let (dt, t, dv) = (mix.phase(0).view().dt, mix.time(), relative_velocity(mix));
        let DecayLaw { tau, dv0 } = self.law;
        let r = dt / tau;
        self.first_ratio.get_or_insert(r);
        self.discrete *= discrete_decay(self.update, r);
        let scale = dv0.norm();
        self.max_error = self.max_error.max((dv - self.law.exact(t)).norm() / scale);
        self.max_discrete_error = self
            .max_discrete_error
            .max((dv - dv0 * self.discrete).norm() / scale);
        Ok(())
    }

    fn finish(&mut self, _: &Run<Mixture>, outcome: &mut Simulated) -> std::io::Result<()> {
        outcome.metrics.set_check(&DragDecayFigures {
            rel_error: self.max_error,
            discrete_rel_error: self.max_discrete_error,
            dt_over_tau: self.first_ratio,
        });
        Ok(())
    }
}
