//! The drag coupling of one step: each phase's nodal volume (and presence),
//! then the node-based or the particle-based model (`drag`,
//! `drag_particle`), and the energy the drag took from each phase.

use super::drag::{
    couple_nodes, grid_kinetic, nodal_presence, nodal_volume, refill, Coupling, Drag, Scratch,
};
use crate::particles::Vec2;
use crate::Solver;

/// Corrects both phases' v^{n+1} (and the nodal accelerations) for the drag
/// over a step of `dt`; both must have run `begin_step` with the same dt.
/// With `fixed_a` phase a is a fixed skeleton: its grid velocities are held
/// at zero (infinite mass in the drag) and only b's velocity changes.
pub fn couple(
    a: &mut Solver,
    b: &mut Solver,
    drag: &Drag,
    scratch: &mut Scratch,
    dt: f64,
    fixed_a: bool,
) -> Coupling {
    {
        let [va, vb] = &mut scratch.volume;
        nodal_volume(a, va);
        nodal_volume(b, vb);
    }
    if drag.model.uses_presence() {
        let [pa, pb] = &mut scratch.presence;
        nodal_presence(a, &mut scratch.per_particle, pa);
        nodal_presence(b, &mut scratch.per_particle, pb);
    }
    let mut out = Coupling {
        stable_dt: f64::INFINITY,
        ..Coupling::default()
    };
    if fixed_a {
        let ga = a.grid_mut();
        for &n in &ga.active {
            let n = n as usize;
            ga.vel[n] = Vec2::zeros();
            ga.vel_new[n] = Vec2::zeros();
            ga.accel[n] = Vec2::zeros();
        }
    }
    let before = [grid_kinetic(a.grid()), grid_kinetic(b.grid())];
    if drag.model.is_particle_based() {
        super::drag_particle::couple(a, b, drag, scratch, dt, fixed_a, &mut out);
    } else {
        couple_nodes(a, b, drag, scratch, dt, fixed_a, &mut out);
    }
    let (ga, gb) = (a.grid_mut(), b.grid_mut());
    for g in [&mut *ga, &mut *gb] {
        refill(g);
    }
    // Each phase's budget counts what the drag took from it (negative when
    // it gained), so each closes alone and their sum is the dissipation.
    let lost = [before[0] - grid_kinetic(ga), before[1] - grid_kinetic(gb)];
    let energy = lost[0];
    a.book_dissipated(energy);
    let energy = lost[1];
    b.book_dissipated(energy);
    out.dissipated = lost[0] + lost[1];
    out
}
