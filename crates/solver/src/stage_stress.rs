//! Stress stage: velocity gradient from the grid, deformation-gradient and J
//! update, EOS pressure plus Newtonian viscosity (plane strain, 3D deviator),
//! and the EOS figures the time step and the energy need (one EOS call).

use crate::config::{JUpdate, Material};
use crate::grid::Grid;
use crate::par::CHUNK;
use crate::particles::{Mat2, Particles, Vec2};
use crate::shape::Weights1d;
use crate::viscosity;
use rayon::prelude::*;

pub struct Inputs<'a> {
    pub weights: &'a [[Weights1d; 2]],
    pub grid: &'a Grid,
    /// The grid velocity this scheme takes the gradient of.
    pub velocity: &'a [Vec2],
    pub width: usize,
    pub materials: &'a [Material],
    pub j_update: JUpdate,
    pub dt: f64,
}

/// Updates F, J, V, stress, pressure and |dev D|; returns the viscous work of this step.
pub fn update(inputs: &Inputs, particles: &mut Particles, partials: &mut [[f64; 1]]) -> f64 {
    let Inputs {
        weights,
        grid,
        velocity,
        width,
        materials,
        j_update,
        dt,
    } = *inputs;
    let pad = crate::grid::PAD as i64;
    let inv_h = 1.0 / grid.h;
    let n_chunks = crate::par::chunk_count(particles.len());
    (
        particles.f.par_chunks_mut(CHUNK),
        particles.j.par_chunks_mut(CHUNK),
        particles.vol.par_chunks_mut(CHUNK),
        particles.stress.par_chunks_mut(CHUNK),
        particles.pressure.par_chunks_mut(CHUNK),
        particles.dev_rate.par_chunks_mut(CHUNK),
        particles.wave_speed.par_chunks_mut(CHUNK),
        particles.stored_energy.par_chunks_mut(CHUNK),
        particles.vol0.par_chunks(CHUNK),
        particles.material.par_chunks(CHUNK),
        weights.par_chunks(CHUNK),
        partials[..n_chunks].par_iter_mut(),
    )
        .into_par_iter()
        .for_each(
            |(f, j, vol, stress, pressure, dev_rate, wave, stored, vol0, mat, w, work)| {
                let mut acc = 0.0;
                for k in 0..f.len() {
                    let [wx, wy] = &w[k];
                    let (bi, bj) = ((wx.base + pad) as usize, (wy.base + pad) as usize);
                    let mut l = Mat2::zeros();
                    for c in 0..width {
                        for a in 0..width {
                            let grad = Vec2::new(wx.dw[a] * wy.w[c], wx.w[a] * wy.dw[c]) * inv_h;
                            l += velocity[grid.index(bi + a, bj + c)] * grad.transpose();
                        }
                    }
                    let f_new = (Mat2::identity() + dt * l) * f[k];
                    let det = f_new.determinant();
                    let (f_next, j_next) = match j_update {
                        JUpdate::Det => (f_new, det),
                        JUpdate::Exp => {
                            let jn = j[k] * (dt * l.trace()).exp();
                            // Rescale F's volumetric part so that det F = J still holds.
                            (f_new * (jn / det).abs().sqrt(), jn)
                        }
                    };
                    f[k] = f_next;
                    j[k] = j_next;
                    vol[k] = vol0[k] * j_next;
                    let m = &materials[mat[k] as usize];
                    let state = m.eos(j_next);
                    let p = m.cut(state.pressure);
                    wave[k] = m.wave_speed_of(&state, j_next);
                    stored[k] = vol0[k] * state.energy;
                    let d = 0.5 * (l + l.transpose());
                    let visc = viscosity::newtonian(m.viscosity, &d);
                    stress[k] = visc.stress - p * Mat2::identity();
                    pressure[k] = p;
                    dev_rate[k] = visc.dev_rate;
                    acc += visc.power * vol[k] * dt;
                }
                work[0] = acc;
            },
        );
    partials[..n_chunks].iter().map(|w| w[0]).sum()
}
