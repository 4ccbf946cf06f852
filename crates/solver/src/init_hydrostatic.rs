//! Discrete hydrostatic equilibrium: the lattice seeded by `scene::seed` already
//! carries the hydrostatic J and stress; a damped PIC relaxation under gravity
//! then removes what the discretisation (walls, free surface) leaves out of
//! balance, before the clock starts at t = 0 with the particles at rest.

use crate::config::{DtMode, SolverConfig, TransferKind};
use crate::particles::{Mat2, Particles, Vec2};
use crate::{Solver, StepError};

/// Lowest-mode periods of damped relaxation.
const PERIODS: f64 = 3.0;

pub fn relax(s: &mut Solver) -> Result<(), StepError> {
    let method = s.config().method.clone();
    let perturb = std::mem::take(s.perturbations_mut());
    s.method_mut().transfer = TransferKind::Pic;
    s.method_mut().dt = DtMode::Dynamic;
    let scene = s.scene();
    let height = scene
        .bodies
        .iter()
        .map(|b| b.rect[3] - b.rect[1])
        .fold(0.0, f64::max);
    let c0 = scene
        .materials
        .iter()
        .map(|m| m.wave_speed(1.0))
        .fold(f64::INFINITY, f64::min);
    // Quarter-wave mode of a column with a free top: period 4 H / c.
    let omega = 2.0 * std::f64::consts::PI * c0 / (4.0 * height);
    let duration = PERIODS * 4.0 * height / c0;
    let mut t = 0.0;
    let result = loop {
        if t >= duration {
            break Ok(());
        }
        let dt = s.cfl_step();
        if let Err(e) = s.step_with_dt(dt) {
            break Err(e);
        }
        let damp = (1.0 - 2.0 * omega * dt).max(0.0);
        s.particles_mut().v.iter_mut().for_each(|v| *v *= damp);
        s.refresh_signal_speed();
        t += dt;
    };
    *s.method_mut() = method;
    *s.perturbations_mut() = perturb;
    let ps = s.particles_mut();
    ps.v.iter_mut().for_each(|v| *v = Vec2::zeros());
    ps.v_prev.iter_mut().for_each(|v| *v = Vec2::zeros());
    ps.accel.iter_mut().for_each(|a| *a = Vec2::zeros());
    ps.affine.iter_mut().for_each(|c| *c = Mat2::zeros());
    result
}

/// Relaxes the particles in the box cut to the bodies' left and right edges
/// (free-slip gates), then hands them, at rest, to a solver over the whole box.
pub fn relax_behind_gates(cfg: SolverConfig, particles: Particles) -> Result<Solver, StepError> {
    let mut held_cfg = cfg.clone();
    held_cfg.scene = cfg.scene.gated();
    let mut held = Solver::with_particles(held_cfg, particles);
    relax(&mut held)?;
    Ok(Solver::with_particles(cfg, held.into_particles()))
}
