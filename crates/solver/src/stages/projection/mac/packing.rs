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
use crate::grid::Grid;
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
/// mass over four full faces' (a wall's face is half a face), less 1
/// (times J at a finite K), where the cell lies `drift_depth` cells
/// inside (at least `SURFACE_REACH`), whatever its faces hold; else NaN.
/// The reported error is their mean. A floor on the faces' mass (read
/// only where all four held three quarters of a full face, as before)
/// kept the dense cells and dropped the sparse ones and those at a wall,
/// so uneven packing read as compaction (docs/findings/projection_mac.md,
/// "The packing's reading").
fn packing_errors(
    faces: &Faces,
    s: &mut Scratch,
    set: &ProjectionSettings,
    full_mass: f64,
    incompressible: bool,
) {
    let depth = set.drift_depth.max(SURFACE_REACH) as i64;
    // A wall's face holds half a full face: half its volume is in the box.
    let fill = |field: &super::FaceField, i: i64, j: i64| {
        let full = if field.on_wall(i, j) { 0.5 } else { 1.0 } * full_mass;
        field.mass[field.index(i, j)] / full
    };
    let (mut sum, mut count) = (0.0, 0usize);
    for k in 0..s.fluid.len() {
        let c = s.fluid[k] as usize;
        if !s.deep(c, depth) {
            s.target[k] = f64::NAN;
            continue;
        }
        let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
        let [fx, fy] = &faces.fields;
        let packing = 0.25
            * (fill(fx, ci, cj) + fill(fx, ci + 1, cj) + fill(fy, ci, cj) + fill(fy, ci, cj + 1));
        let error = if incompressible {
            packing - 1.0
        } else {
            packing * s.cell_j(c) - 1.0
        };
        s.target[k] = error;
        sum += error;
        count += 1;
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

#[cfg(test)]
mod tests {
    use crate::config::Holes;
    use crate::stages::projection::surface::tests::column;

    /// The column at rest, then four cells emptied inside it, each one's
    /// particles moved a cell right into its neighbour: the whole exactly
    /// packed. Read over the cells two inside, wall faces counted as the
    /// half faces they are, the error is +0.10 %; read only where all four
    /// faces held three quarters of a full face's mass (as before), the
    /// same state read +4.1 % (this build: the emptied cells dropped, the
    /// doubled ones kept).
    #[test]
    fn uneven_packing_does_not_read_as_compaction() {
        let mut s = column(Holes::Air, None);
        s.step().unwrap();
        for x in s.particles.x.iter_mut() {
            let (ci, cj) = ((x.x / 0.01).floor() as i64, (x.y / 0.01).floor() as i64);
            if [2, 6].contains(&ci) && [2, 5].contains(&cj) {
                x.x += 0.01;
            }
        }
        s.step().unwrap();
        let error = s.projection.stats.packing_error;
        assert!(error.abs() < 2e-3, "packing error {error}");
    }
}
