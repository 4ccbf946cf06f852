//! The particles after the solve: their update from the cell's J rate and
//! pressure, and the drift correction by position.

use super::operator::apply_g;
use super::pcg::solve;
use super::{Scratch, SolveStats};
use crate::config::{Advection, Material, ProjectionSettings};
use crate::grid::Grid;

use crate::par::{Pieces, CHUNK};
use crate::particles::{Mat2, Particles, Vec2};
use crate::shapes::{Shape, Stencil};
use crate::viscosity;
use rayon::prelude::*;

/// The drift correction by position (`drift_correction = "position"`),
/// after the particle update: the same operator without its EOS term
/// solves A q = h^2 dt s for the step's drift rate s, and each particle
/// moves by its stencil's share of the nodal displacement M'^-1 G q, whose
/// divergence D is dt s. Velocities, J and the stored energy are left
/// alone (a velocity target would be carried on as flow: it swamped the
/// slosh's wave); the gravitational energy the move changes is booked with
/// the projection. Returns that energy removed (J/m).
#[allow(clippy::too_many_arguments)]
pub fn shift_particles(
    particles: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    set: &ProjectionSettings,
    beta: f64,
    gravity: Vec2,
    s: &mut Scratch,
    dt: f64,
) -> f64 {
    let n = s.fluid.len();
    if s.shift.len() != n || s.shift.iter().all(|&r| r == 0.0) {
        return 0.0;
    }
    solve_displacement(s, grid.h * grid.h, dt, |s| {
        solve(grid, s, set, beta, false, set.drift_tolerance)
    });
    apply_g(grid, s, |s, k| s.x[k]);
    let bilinear = set.advection == Advection::Bilinear;
    let removed = crate::shapes::with_width!(shape, W => move_particles::<W>(particles, stencils, shape, grid, gravity, bilinear, s));
    s.stats.dissipated_projection += removed;
    s.stats.dissipated_packing += removed;
    removed
}

/// The drift correction's solve, shared by both schemes: the pressure's
/// operator without its EOS diagonal (the matrix read or assembled loses
/// it too, and the pressure matrix's factor preconditions: at K = infinity
/// it is the same matrix), right-hand side h^2 dt s for the drift rate s,
/// from 0, by `solve_with`. The stats stay the pressure solve's, with the
/// displacement's iterations.
pub(super) fn solve_displacement(
    s: &mut Scratch,
    h2: f64,
    dt: f64,
    solve_with: impl FnOnce(&mut Scratch),
) {
    for k in 0..s.fluid.len() {
        s.diag[k] -= s.alpha[k];
        if let Some(row) = s.matrix.get_mut(k) {
            row[4] -= s.alpha[k];
        }
        s.alpha[k] = 0.0;
        s.b[k] = h2 * dt * s.shift[k];
        s.x[k] = 0.0;
    }
    let pressure_solve = s.stats;
    solve_with(s);
    s.stats = SolveStats {
        shift_iterations: s.stats.iterations,
        ..pressure_solve
    };
}

/// x_p += sum N_ip d_i for the nodal displacement d in `s.nodal` (N the
/// bilinear element's under `bilinear`, whose cell-integrated divergence is
/// D d); returns sum m_p g . dx_p, the gravitational energy taken out.
fn move_particles<const W: usize>(
    particles: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    gravity: Vec2,
    bilinear: bool,
    s: &mut Scratch,
) -> f64 {
    let nx = grid.dims[0];
    let n = particles.len();
    let n_chunks = crate::par::chunk_count(n);
    let piece = crate::par::piece_chunks(n);
    let displacement = &s.nodal[..];
    let lo = grid.origin;
    let size = Vec2::new(grid.cells[0] as f64 * grid.h, grid.cells[1] as f64 * grid.h);
    (
        particles.x.par_chunks_mut(CHUNK),
        particles.mass.par_chunks(CHUNK),
        stencils.par_chunks(CHUNK),
        s.partials[..n_chunks].par_iter_mut(),
    )
        .into_par_iter()
        .pieces(piece)
        .for_each(|(x, mass, st, energy)| {
            let mut acc = 0.0;
            for k in 0..x.len() {
                let dx = if bilinear {
                    crate::transfers::serial::bilinear(displacement, grid, x[k])
                } else {
                    crate::transfers::serial::interpolate::<W>(displacement, &st[k], shape, nx)
                };
                acc += mass[k] * gravity.dot(&dx);
                x[k] += dx;
                for axis in 0..2 {
                    if grid.periodic[axis] {
                        x[k][axis] = lo[axis] + (x[k][axis] - lo[axis]).rem_euclid(size[axis]);
                    }
                }
            }
            *energy = acc;
        });
    s.partials[..n_chunks].iter().sum()
}

/// The particles after G2P: F from the velocity gradient, J^{n+1} = J^n
/// (1 + dt e) of the particle's cell, the viscous stress, the cell
/// pressure, the stored energy; no wave speed (no sound limits the step).
/// Returns the viscous work.
pub fn update_particles(
    particles: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    material: &Material,
    s: &mut Scratch,
    dt: f64,
) -> f64 {
    crate::shapes::with_width!(shape, W => update_with::<W>(particles, stencils, shape, grid, material, s, dt))
}

fn update_with<const W: usize>(
    particles: &mut Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    m: &Material,
    s: &mut Scratch,
    dt: f64,
) -> f64 {
    let nx = grid.dims[0];
    let inv_h = 1.0 / grid.h;
    let n = particles.len();
    let n_chunks = crate::par::chunk_count(n);
    let piece = crate::par::piece_chunks(n);
    let (rate, pressure_cell, gradient) = (&s.rate[..], &s.pressure[..], &s.gradient[..]);
    let (origin, h, cells_x) = (grid.origin, grid.h, s.cells[0]);
    let velocity = &grid.vel_new[..];
    (
        particles.f.par_chunks_mut(CHUNK),
        particles.j.par_chunks_mut(CHUNK),
        particles.vol.par_chunks_mut(CHUNK),
        particles.stress.par_chunks_mut(CHUNK),
        particles.pressure.par_chunks_mut(CHUNK),
        particles.dev_rate.par_chunks_mut(CHUNK),
        particles.wave_speed.par_chunks_mut(CHUNK),
        particles.stored_energy.par_chunks_mut(CHUNK),
        particles
            .vol0
            .par_chunks(CHUNK)
            .zip(particles.x.par_chunks(CHUNK)),
        stencils.par_chunks(CHUNK),
        s.particle_cell[..n].par_chunks(CHUNK),
        s.partials[..n_chunks].par_iter_mut(),
    )
        .into_par_iter()
        .pieces(piece)
        .for_each(
            |(f, j, vol, stress, pressure, dev_rate, wave, stored, (vol0, x), st, cell, work)| {
                let mut acc = 0.0;
                for k in 0..f.len() {
                    let l = crate::stages::stress::velocity_gradient::<W>(
                        shape, &st[k], velocity, nx, inv_h,
                    );
                    let c = cell[k] as usize;
                    let j_next = j[k] * (1.0 + dt * rate[c]);
                    let f_new = (Mat2::identity() + dt * l) * f[k];
                    let det = f_new.determinant();
                    f[k] = if det > 0.0 && j_next > 0.0 {
                        f_new * (j_next / det).sqrt()
                    } else {
                        f_new
                    };
                    j[k] = j_next;
                    vol[k] = vol0[k] * j_next;
                    let d = 0.5 * (l + l.transpose());
                    let visc = viscosity::newtonian(m.viscosity, &d);
                    acc += visc.power * vol[k] * dt;
                    let centre = origin
                        + h * Vec2::new((c % cells_x) as f64 + 0.5, (c / cells_x) as f64 + 0.5);
                    pressure[k] = pressure_cell[c] + gradient[c].dot(&(x[k] - centre));
                    stress[k] = visc.stress - pressure[k] * Mat2::identity();
                    dev_rate[k] = visc.dev_rate;
                    wave[k] = 0.0;
                    stored[k] = vol0[k] * m.stored(j_next);
                }
                *work = acc;
            },
        );
    s.partials[..n_chunks].iter().sum()
}
