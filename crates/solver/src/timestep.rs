//! CFL time step: dt = CFL h / max_p(c_p(J_p) + |v_p|).

use crate::config::Material;
use crate::par;
use crate::particles::Particles;

/// max_p(c_p + |v_p|) over all particles.
pub fn max_signal_speed(particles: &Particles, materials: &[Material]) -> f64 {
    par::max(particles.len(), |p| {
        let m = &materials[particles.material[p] as usize];
        m.wave_speed(particles.j[p]) + particles.v[p].norm()
    })
}

pub fn cfl_step(cfl: f64, h: f64, signal_speed: f64) -> f64 {
    cfl * h / signal_speed.max(1e-300)
}
