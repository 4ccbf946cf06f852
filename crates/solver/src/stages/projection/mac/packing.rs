//! The staggered scheme's packing correction by position: where the
//! faces' mass says the particles pack denser (or looser) than J says,
//! the same operator without its EOS term solves for a displacement whose
//! flux balance is the drift share of that error, and the particles move
//! by its quadratic B-spline interpolation. Velocities, J and the stored
//! energy are left alone; the gravitational energy the move changes is
//! booked with the projection.

use super::super::advect::solve_displacement;
use super::super::operator::set_drift_target;
use super::super::{pcg, Scratch};
use super::solve::apply_gradient;
use super::transfer::stencil;
use super::Faces;
use crate::config::{Material, ProjectionSettings};
use crate::grid::{Grid, FULL_NODE_SHARE};
use crate::particles::{Particles, Vec2};

/// The packing error is read at least this many cells inside the fluid:
/// a face within a B-spline's reach (1.5 cells) of the surface misses the
/// mass the air would hold, and reads as loose packing (at rest, corrected
/// there, it set a column moving at 2e-3 m/s).
const SURFACE_REACH: u32 = 2;

/// Moves the particles to correct the packing error the step started with;
/// returns the gravitational energy the move took out (J/m).
pub fn correct_packing(
    particles: &mut Particles,
    s: &mut Scratch,
    set: &ProjectionSettings,
    mat: &Material,
    grid: &Grid,
    gravity: Vec2,
    dt: f64,
) -> f64 {
    if s.fluid.is_empty() {
        return 0.0;
    }
    let mut faces = std::mem::take(&mut s.faces);
    let h = grid.h;
    let full_mass = mat.rho0 * h * h;
    let incompressible = mat.k == f64::INFINITY;
    // Measured without the correction too: the monitor's packing figures.
    packing_errors(&faces, s, set, full_mass, incompressible);
    if set.drift == 0.0 {
        s.faces = faces;
        return 0.0;
    }
    set_drift_target(s, set, dt, incompressible);
    let mut removed = 0.0;
    if s.shift.iter().any(|&r| r != 0.0) {
        solve_shift(&mut faces, s, set, h, dt, set.light_node_share * full_mass);
        removed = move_particles(particles, &faces, grid, gravity);
        s.stats.dissipated_projection += removed;
        s.stats.dissipated_packing += removed;
    }
    s.faces = faces;
    removed
}

/// Per fluid cell, the raw packing error in `s.target`: its four faces'
/// mass over four full faces', less 1 (times J at a finite K), where all
/// four are full and the cell lies `drift_depth` cells inside (at least
/// `SURFACE_REACH`); else NaN.
fn packing_errors(
    faces: &Faces,
    s: &mut Scratch,
    set: &ProjectionSettings,
    full_mass: f64,
    incompressible: bool,
) {
    let full = FULL_NODE_SHARE * full_mass;
    let (mut sum, mut count) = (0.0, 0usize);
    for k in 0..s.fluid.len() {
        let c = s.fluid[k] as usize;
        let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
        let [fx, fy] = &faces.fields;
        let masses = [
            fx.mass[fx.index(ci, cj)],
            fx.mass[fx.index(ci + 1, cj)],
            fy.mass[fy.index(ci, cj)],
            fy.mass[fy.index(ci, cj + 1)],
        ];
        s.target[k] = if masses.iter().all(|&m| m >= full) {
            let packing = masses.iter().sum::<f64>() / (4.0 * full_mass);
            let error = if incompressible {
                packing - 1.0
            } else {
                packing * s.cell_j(c) - 1.0
            };
            sum += error;
            count += 1;
            if s.deep(c, set.drift_depth.max(SURFACE_REACH) as i64) {
                error
            } else {
                f64::NAN
            }
        } else {
            f64::NAN
        };
    }
    s.stats.packing_error = if count > 0 { sum / count as f64 } else { 0.0 };
}

/// Solves (A - alpha) q = h^2 dt r for the drift rate r in `s.shift`, then
/// the faces' displacement -h (q_hi - q_lo) / m' (its flux balance dt r).
fn solve_shift(
    faces: &mut Faces,
    s: &mut Scratch,
    set: &ProjectionSettings,
    h: f64,
    dt: f64,
    light: f64,
) {
    // The pressure is kept per cell (`s.pressure`); `s.x` is free.
    solve_displacement(s, h * h, dt, |s| {
        pcg::solve_assembled(s, set, set.drift_tolerance)
    });
    for field in faces.fields.iter_mut() {
        let mut shift = std::mem::take(&mut field.shift);
        shift.fill(0.0);
        apply_gradient(field, s, h, 1.0, light, &mut shift);
        field.shift = shift;
    }
}

/// x_p += the displacement interpolated at x_p; returns sum m_p g . dx_p.
fn move_particles(particles: &mut Particles, faces: &Faces, grid: &Grid, gravity: Vec2) -> f64 {
    let (origin, h) = (grid.origin, grid.h);
    let mut energy = 0.0;
    for p in 0..particles.len() {
        let x = particles.x[p];
        let moved = faces.fields.each_ref().map(|field| {
            stencil(field, origin, h, x).map(|st| {
                let mut d = 0.0;
                for jy in 0..3 {
                    for ix in 0..3 {
                        let f = field.index(st.first.0 + ix as i64, st.first.1 + jy as i64);
                        d += st.w[0][ix] * st.w[1][jy] * field.shift[f];
                    }
                }
                d
            })
        });
        if let [Some(dx), Some(dy)] = moved {
            let dx = Vec2::new(dx, dy);
            energy += particles.mass[p] * gravity.dot(&dx);
            particles.x[p] = x + dx;
        }
    }
    energy
}
