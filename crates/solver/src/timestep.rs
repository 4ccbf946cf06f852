//! CFL time step: dt = CFL h / max_p(c_p(J_p) + |v_p|).

use crate::config::Material;
use crate::par;
use crate::particles::Particles;

/// max_p(c_p + |v_p|) over all particles (c_p as cached by the stress stage).
pub fn max_signal_speed(particles: &Particles) -> f64 {
    par::max(particles.len(), |p| {
        particles.wave_speed[p] + particles.v[p].norm()
    })
}

/// Recomputes the cached c(J) and V0 U(J) of every particle (after seeding or a restore).
pub fn refresh_eos_cache(particles: &mut Particles, materials: &[Material]) {
    for p in 0..particles.len() {
        refresh_eos_of(particles, materials, p);
    }
}

/// The cached c(J) and V0 U(J) of particle `p` (also for one just injected).
pub fn refresh_eos_of(particles: &mut Particles, materials: &[Material], p: usize) {
    let m = &materials[particles.material[p] as usize];
    let j = particles.j[p];
    let state = m.eos(j);
    particles.wave_speed[p] = m.wave_speed_of(&state, j);
    particles.stored_energy[p] = particles.vol0[p] * m.energy_of(j, &state);
    // The stress itself is the stress stage's (restored, or zero at seeding).
    let mut unused = crate::particles::Mat2::zeros();
    crate::solid_neo_hookean::add_to(
        m,
        &particles.f[p],
        particles.vol0[p],
        particles.history[p],
        particles.history[p],
        &mut unused,
        &mut particles.wave_speed[p],
        &mut particles.stored_energy[p],
    );
}

/// max_p(c_p + max(|v_prev,x|, |v_prev,y|)): Uintah's per-axis signal
/// speed from the step-start velocity.
pub fn max_axis_signal_speed(particles: &Particles) -> f64 {
    par::max(particles.len(), |p| axis_signal_speed_of(particles, p))
}

/// Particle `p`'s c_p + max(|v_prev,x|, |v_prev,y|).
#[inline]
pub fn axis_signal_speed_of(particles: &Particles, p: usize) -> f64 {
    let old = particles.v_prev[p];
    particles.wave_speed[p] + old.x.abs().max(old.y.abs())
}

pub fn cfl_step(cfl: f64, h: f64, signal_speed: f64) -> f64 {
    cfl * h / signal_speed.max(1e-300)
}
