//! Grid stage: fold wall/periodic images, nodal velocities, momentum update,
//! ghost refill. Zero-mass active nodes (a particle exactly on a node line)
//! keep zero velocity.

use crate::grid::Grid;
use crate::particles::Vec2;

/// v^n = p / m from the folded P2G sums; also returns the grid kinetic energy
/// of the real particles' mass (sum over nodes of m_raw |v|^2 / 2).
pub fn velocities(grid: &mut Grid) -> f64 {
    for &n in &grid.active {
        let n = n as usize;
        grid.mass[n] = grid.mass_raw[n];
    }
    let mut mass = std::mem::take(&mut grid.mass);
    grid.fold(&mut mass);
    grid.mass = mass;
    project_momentum(grid);
    let mut ke = 0.0;
    for &n in &grid.active {
        let n = n as usize;
        ke += 0.5 * grid.mass_raw[n] * grid.vel[n].norm_squared();
    }
    ke
}

/// v = p / m for the current momentum (already P2G'd), with folded mass:
/// v^n after P2G, or under MUSL the re-projection of the updated particle
/// velocities.
pub fn project_momentum(grid: &mut Grid) {
    let mut momentum = std::mem::take(&mut grid.momentum);
    grid.fold(&mut momentum);
    for &n in &grid.inside {
        let n = n as usize;
        let m = grid.mass[n];
        grid.vel[n] = if m > 0.0 {
            momentum[n] / m
        } else {
            momentum[n] * 0.0
        };
    }
    grid.momentum = momentum;
    let mut vel = std::mem::take(&mut grid.vel);
    grid.fill(&mut vel);
    grid.vel = vel;
    let mut mass = std::mem::take(&mut grid.mass);
    grid.fill(&mut mass);
    grid.mass = mass;
}

/// v^{n+1} = v^n + dt f / m from the folded nodal force (gravity included,
/// its images at no-slip walls corrected).
pub fn update(grid: &mut Grid, dt: f64, gravity: Vec2) {
    let mut force = std::mem::take(&mut grid.force);
    grid.fold(&mut force);
    grid.correct_weight_images(&mut force, gravity);
    for &n in &grid.inside {
        let n = n as usize;
        let m = grid.mass[n];
        let a = if m > 0.0 {
            force[n] / m
        } else {
            force[n] * 0.0
        };
        grid.accel[n] = a;
        grid.vel_new[n] = grid.vel[n] + a * dt;
    }
    grid.force = force;
    grid.fill_vel_new(true);
}

/// sum over the active nodes (ghosts included: they carry the real
/// particles' mass that lands beyond a wall or a periodic edge) of
/// m_raw |v^{n+1}|^2 / 2.
pub(crate) fn updated_kinetic(g: &Grid) -> f64 {
    g.active
        .iter()
        .map(|&n| 0.5 * g.mass_raw[n as usize] * g.vel_new[n as usize].norm_squared())
        .sum()
}
