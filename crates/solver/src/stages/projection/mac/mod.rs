//! The staggered (MAC) pressure projection (`method.projection.scheme =
//! "mac"`, docs/physics.md section 8): each velocity component lives on
//! the cell faces normal to it and the pressure at the cell centres, so
//! the divergence D is a cell's flux balance and the pressure gradient its
//! transpose. The pair is inf-sup stable (docs/findings/inf_sup.md): no
//! checkerboard penalty, hourglass control or drift correction holds it.
//!
//! The particles transfer to each component's faces with quadratic
//! B-splines centred there (APIC's affine part per component, as in
//! FLIP/APIC liquid solvers). The nodal grid still takes its P2G and
//! grid update, which the monitor reads; after the solve its velocities
//! are the faces' averaged onto the nodes. The faces' transfers are
//! serial, in particle order: bit-identical for any thread count.

mod field;
mod packing;
mod solve;
mod transfer;

pub use field::FaceField;
pub use packing::correct_packing;

use super::surface::mark_fluid;
use super::{Inputs, Scratch};
use crate::config::{Advection, AdvectionStep, FaceDensity, ProjectionSettings, ShareFloor};
use crate::grid::Grid;
use crate::particles::{Mat2, Particles, Vec2};
use crate::viscosity;
use transfer::{flux_velocity, gather, linear_velocity, scatter, stencil, Sources};

/// Both components' faces.
#[derive(Clone, Debug, Default)]
pub struct Faces {
    pub fields: [FaceField; 2],
}

impl Faces {
    pub fn new(grid: &Grid) -> Self {
        let no_slip = grid.no_slip_walls();
        Faces {
            fields: [0, 1].map(|a| FaceField::new(grid, a, no_slip)),
        }
    }

    /// sum over the faces (ghosts included: they carry the real particles'
    /// mass beyond a wall) of m_raw u^2 / 2: the P2G velocity u^n, or
    /// (`updated`) u^{n+1}.
    pub fn kinetic(&self, updated: bool) -> f64 {
        self.fields
            .iter()
            .map(|field| {
                let u = if updated { &field.vel_new } else { &field.vel };
                field
                    .mass_raw
                    .iter()
                    .zip(u)
                    .map(|(m, u)| 0.5 * m * u * u)
                    .sum::<f64>()
            })
            .sum()
    }

    pub fn is_empty(&self) -> bool {
        self.fields[0].vel.is_empty()
    }
}

/// The MAC step's grid side: P2G onto the faces, u* from the viscous force
/// and gravity, the pressure solve, u^{n+1}; the nodal grid's velocities
/// and accelerations then follow the faces (for the monitor).
pub fn project(inputs: &Inputs, gravity: Vec2, affine: bool, grid: &mut Grid, s: &mut Scratch) {
    let (ps, mat, set, dt) = (
        inputs.particles,
        inputs.material,
        inputs.settings,
        inputs.dt,
    );
    let h = grid.h;
    let full_mass = mat.rho0 * h * h;
    let light = set.light_node_share * full_mass;
    inputs.set_surface_reading(s);
    mark_fluid(ps, grid, s, set.free_surface, full_mass, set.holes, true);
    let mut faces = std::mem::take(&mut s.faces);
    let src = Sources {
        particles: ps,
        origin: grid.origin,
        h,
        affine,
    };
    for field in faces.fields.iter_mut() {
        scatter(&src, field);
        predict(field, gravity[field.axis], dt);
    }
    let material = (set.face_density == FaceDensity::Material).then_some(full_mass);
    for field in faces.fields.iter_mut() {
        solve::mark_solved(field, s);
        solve::slave_air_faces(field, s, material);
        solve::fill_shares(field, s, full_mass, set.share_floor == ShareFloor::FaceMass);
    }
    s.stats = solve::fresh_stats(s.fluid.len());
    // Incompressible, p is the constraint's multiplier: D u^{n+1} = 0
    // (theta < 1 would ask D u_theta = 0: D u^{n+1} = -(1 - theta) /
    // theta D u^n).
    let theta = if mat.k == f64::INFINITY {
        1.0
    } else {
        set.theta
    };
    solve::assemble(&faces.fields, s, mat, h, dt, light, theta);
    super::pcg::solve_assembled(s, set, set.tolerance);
    solve::correct(&mut faces.fields, s, h, dt, light);
    solve::book(&faces.fields, s, h, dt, theta);
    super::surface::reconstruct(s, h, s.ghost_surface);
    onto_nodes(&faces, grid, s, dt);
    s.faces = faces;
}

/// Folds the P2G sums, then u^n = p / m and u* = u^n + dt (f / m + g) on
/// the in-box faces (a wall's normal faces hold 0); ghosts filled.
fn predict(field: &mut FaceField, g: f64, dt: f64) {
    let mut mass = std::mem::take(&mut field.mass);
    mass.copy_from_slice(&field.mass_raw);
    field.fold(&mut mass, false);
    field.mass = mass;
    let (mut momentum, mut force) = (
        std::mem::take(&mut field.momentum),
        std::mem::take(&mut field.force),
    );
    field.fold(&mut momentum, true);
    field.fold(&mut force, true);
    for f in 0..field.vel.len() {
        let (i, j) = field.coords(f);
        let m = field.mass[f];
        let (u, star) = if !field.in_box(i, j) || field.on_wall(i, j) || m <= 0.0 {
            (0.0, 0.0)
        } else {
            let u = momentum[f] / m;
            (u, u + dt * (force[f] / m + g))
        };
        field.vel[f] = u;
        field.vel_star[f] = star;
    }
    (field.momentum, field.force) = (momentum, force);
    let (mut vel, mut star) = (
        std::mem::take(&mut field.vel),
        std::mem::take(&mut field.vel_star),
    );
    field.fill(&mut vel);
    field.fill(&mut star);
    (field.vel, field.vel_star) = (vel, star);
    field.vel_new.copy_from_slice(&field.vel_star);
}

/// Each in-box active node's velocity: the mean of the two faces of each
/// component beside it; its acceleration from the P2G velocity. The
/// force forensics (`Scratch::node_changes`) read the whole change from
/// the nodes' own u* as the pressure's.
fn onto_nodes(faces: &Faces, grid: &mut Grid, s: &mut Scratch, dt: f64) {
    let [fx, fy] = &faces.fields;
    for &n in &grid.inside {
        let n = n as usize;
        let (i, j) = grid.coords(n);
        let (i, j) = (
            i as i64 - crate::grid::PAD as i64,
            j as i64 - crate::grid::PAD as i64,
        );
        let u = 0.5 * (fx.vel_new[fx.index(i, j - 1)] + fx.vel_new[fx.index(i, j)]);
        let v = 0.5 * (fy.vel_new[fy.index(i - 1, j)] + fy.vel_new[fy.index(i, j)]);
        let vel = grid.project_walls(n, Vec2::new(u, v));
        let star = grid.vel_new[n];
        s.before_merge[n] = star;
        s.before_hourglass[n] = star;
        s.before_projection[n] = star;
        s.nodal[n] = (vel - star) / dt;
        grid.accel[n] = (vel - grid.vel[n]) / dt;
        grid.vel_new[n] = vel;
    }
    grid.fill_vel_new(true);
    for values in [
        &mut s.nodal,
        &mut s.before_merge,
        &mut s.before_hourglass,
        &mut s.before_projection,
    ] {
        grid.fill(values);
    }
}

/// The faces' velocity at `x`: the shapes' (B-spline), the bilinear
/// element's or the flux element's; None beyond the padded faces.
fn velocity_at(faces: &Faces, advection: Advection, origin: Vec2, h: f64, x: Vec2) -> Option<Vec2> {
    let [fx, fy] = &faces.fields;
    Some(match advection {
        Advection::Shape => Vec2::new(
            gather(fx, &stencil(fx, origin, h, x)?, h).v,
            gather(fy, &stencil(fy, origin, h, x)?, h).v,
        ),
        Advection::Bilinear => Vec2::new(
            linear_velocity(fx, origin, h, x)?,
            linear_velocity(fy, origin, h, x)?,
        ),
        Advection::Flux => Vec2::new(
            flux_velocity(fx, origin, h, x)?,
            flux_velocity(fy, origin, h, x)?,
        ),
    })
}

/// A particle's new position: one Euler step or the midpoint rule through
/// the faces' velocity field (`v_pic`, the shapes' velocity at `x`, where
/// the field does not reach).
fn advect(
    faces: &Faces,
    set: &ProjectionSettings,
    origin: Vec2,
    h: f64,
    x: Vec2,
    v_pic: Vec2,
    dt: f64,
) -> Vec2 {
    let here = match set.advection {
        Advection::Shape => v_pic,
        Advection::Bilinear | Advection::Flux => {
            velocity_at(faces, set.advection, origin, h, x).unwrap_or(v_pic)
        }
    };
    match set.advection_step {
        AdvectionStep::Euler => x + dt * here,
        AdvectionStep::Midpoint => {
            let mid = x + 0.5 * dt * here;
            x + dt * velocity_at(faces, set.advection, origin, h, mid).unwrap_or(here)
        }
    }
}

/// The MAC step's particle side: G2P from the faces (PIC, FLIP blend or
/// APIC; positions by `advect`), then F, J^{n+1} = J^n (1 + dt e)
/// of the particle's cell, the viscous stress, the cell's pressure and the
/// stored energy. Returns the viscous work. Serial (a reduction of work in
/// particle order).
pub fn update_particles(
    particles: &mut Particles,
    s: &Scratch,
    set: &ProjectionSettings,
    m: &crate::config::Material,
    grid: &Grid,
    flip_alpha: Option<f64>,
    dt: f64,
) -> f64 {
    let (origin, h, cells_x) = (grid.origin, grid.h, s.cells[0]);
    let faces = &s.faces;
    let mut work = 0.0;
    for p in 0..particles.len() {
        let x = particles.x[p];
        let gathered = faces
            .fields
            .each_ref()
            .map(|field| stencil(field, origin, h, x).map(|st| gather(field, &st, h)));
        let [Some(gx), Some(gy)] = gathered else {
            // Beyond the padded faces (outside a closed box): left as it
            // was, for the escape rules.
            continue;
        };
        let v_pic = Vec2::new(gx.v, gy.v);
        let dv = Vec2::new(gx.dv, gy.dv);
        particles.accel[p] = dv / dt;
        particles.v[p] = match flip_alpha {
            Some(alpha) => alpha * (particles.v[p] + dv) + (1.0 - alpha) * v_pic,
            None => v_pic,
        };
        if flip_alpha.is_none() {
            particles.affine[p] = Mat2::new(gx.c_row.x, gx.c_row.y, gy.c_row.x, gy.c_row.y);
        }
        particles.x[p] = advect(faces, set, origin, h, x, v_pic, dt);
        let l = Mat2::new(gx.l_row.x, gx.l_row.y, gy.l_row.x, gy.l_row.y);
        let c = s.particle_cell[p] as usize;
        let j_next = particles.j[p] * (1.0 + dt * s.rate[c]);
        let f_new = (Mat2::identity() + dt * l) * particles.f[p];
        let det = f_new.determinant();
        particles.f[p] = if det > 0.0 && j_next > 0.0 {
            f_new * (j_next / det).sqrt()
        } else {
            f_new
        };
        particles.j[p] = j_next;
        particles.vol[p] = particles.vol0[p] * j_next;
        let d = 0.5 * (l + l.transpose());
        let visc = viscosity::newtonian(m.viscosity, &d);
        work += visc.power * particles.vol[p] * dt;
        let centre = origin + h * Vec2::new((c % cells_x) as f64 + 0.5, (c / cells_x) as f64 + 0.5);
        let pressure = s.pressure[c] + s.gradient[c].dot(&(x - centre));
        particles.pressure[p] = pressure;
        particles.stress[p] = visc.stress - pressure * Mat2::identity();
        particles.dev_rate[p] = visc.dev_rate;
        particles.wave_speed[p] = 0.0;
        particles.stored_energy[p] = particles.vol0[p] * m.stored(j_next);
    }
    work
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rigid rotation at rate OMEGA about the middle of an 8 x 8 box of
    /// 1 cm cells, on both components' faces.
    const OMEGA: f64 = 10.0;

    fn rotating_faces() -> Faces {
        let grid = Grid::new(Vec2::zeros(), 0.01, [8, 8], [false, false]);
        let fields = [0, 1].map(|axis| {
            let mut f = FaceField::new(&grid, axis, [[false; 2]; 2]);
            for g in 0..f.vel_new.len() {
                let (i, j) = f.coords(g);
                let at = Vec2::new(i as f64 + f.offset[0], j as f64 + f.offset[1]) * 0.01;
                let r = at - Vec2::new(0.04, 0.04);
                f.vel_new[g] = if axis == 0 { -OMEGA * r.y } else { OMEGA * r.x };
            }
            f
        });
        Faces { fields }
    }

    /// The radius after 20 steps of OMEGA dt = 0.1 from 2 cm, by `step`
    /// through `advection`'s field (both exact for a rotation, which is
    /// affine), the shapes' velocity passed as v_PIC.
    fn radius_after(advection: Advection, step: AdvectionStep) -> f64 {
        let faces = rotating_faces();
        let set = ProjectionSettings {
            advection,
            advection_step: step,
            ..Default::default()
        };
        let (dt, centre) = (0.1 / OMEGA, Vec2::new(0.04, 0.04));
        let mut x = centre + Vec2::new(0.02, 0.0);
        for _ in 0..20 {
            let v_pic = velocity_at(&faces, Advection::Shape, Vec2::zeros(), 0.01, x).unwrap();
            x = advect(&faces, &set, Vec2::zeros(), 0.01, x, v_pic, dt);
        }
        (x - centre).norm() / 0.02
    }

    /// An Euler step through a rotation widens each circle by
    /// sqrt(1 + (OMEGA dt)^2); the midpoint rule by sqrt(1 + (OMEGA dt)^4 / 4).
    #[test]
    fn the_midpoint_rule_keeps_a_rotations_circles() {
        for advection in [Advection::Shape, Advection::Bilinear] {
            let euler = radius_after(advection, AdvectionStep::Euler);
            let midpoint = radius_after(advection, AdvectionStep::Midpoint);
            let (want_euler, want_midpoint) = (1.01f64.powi(10), (1.0 + 2.5e-5f64).powi(10));
            assert!(
                (euler - want_euler).abs() < 1e-12,
                "{advection:?} Euler: {euler}"
            );
            assert!(
                (midpoint - want_midpoint).abs() < 1e-12,
                "{advection:?} midpoint: {midpoint}"
            );
        }
    }
}
