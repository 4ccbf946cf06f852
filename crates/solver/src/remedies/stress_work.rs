//! The work of a stress change made by a remedy (pressure smoothing, an
//! averaged J that is not carried, which also leaves this step's volume):
//! the change of V sigma per particle is kept until the grid update that
//! uses it (the same step under USF, the next under USL and MUSL), which
//! books dt sum_i df_i . v_i^{n+1/2} = -dt sum_p d(V sigma)_p : L_p^{n+1/2},
//! with the force's gradient form (df_i = -sum_p d(V sigma)_p grad N_ip)
//! and L^{n+1/2} = sum_i v_i^{n+1/2} grad N_ip^T. A particle deleted in
//! between, or a method changed mid-run (`Solver::set_method`), drops the
//! pending booking (the kept changes no longer line up with the particles).

// The loops walk the particles and their kept changes in step.
#![allow(clippy::needless_range_loop)]

use super::GridStep;
use crate::particles::{Mat2, Particles};
use crate::shapes::with_width;

#[derive(Clone, Debug, Default)]
pub struct StressWork {
    /// Per particle: the change of V sigma not yet booked.
    d: Vec<Mat2>,
    /// Particles when it was recorded (None: nothing pending).
    recorded: Option<usize>,
}

impl StressWork {
    pub fn new(particles: usize) -> Self {
        StressWork {
            d: vec![Mat2::zeros(); particles],
            recorded: None,
        }
    }

    pub fn fit_particles(&mut self, n: usize) {
        if self.d.len() < n {
            self.d.resize(n, Mat2::zeros());
        }
    }

    /// Keeps V sigma - `volume` `stress` per particle, the state without
    /// the remedy being given (0 where it is not finite).
    pub fn record(&mut self, ps: &Particles, volume: &[f64], stress: &[Mat2]) {
        let n = ps.len();
        for p in 0..n {
            let d = ps.vol[p] * ps.stress[p] - volume[p] * stress[p];
            self.d[p] = if d.iter().all(|v| v.is_finite()) {
                d
            } else {
                Mat2::zeros()
            };
        }
        self.recorded = Some(n);
    }

    /// The work of the kept change in this step's grid update, then cleared.
    pub fn book(&mut self, g: &GridStep) -> f64 {
        let Some(n) = self.recorded.take() else {
            return 0.0;
        };
        if n != g.particles.len() {
            return 0.0;
        }
        with_width!(g.shape, W => self.work::<W>(g))
    }

    fn work<const W: usize>(&self, g: &GridStep) -> f64 {
        let grid = &*g.grid;
        let nx = grid.dims[0];
        let inv_h = 1.0 / grid.h;
        let mut sum = 0.0;
        for (p, st) in g.stencils.iter().enumerate() {
            if self.d[p] == Mat2::zeros() {
                continue;
            }
            let mut l = Mat2::zeros();
            g.shape.each_piece::<W>(st, nx, |pc| {
                pc.each_node(nx, |n, _, _, [gx, gy]| {
                    let v = 0.5 * (grid.vel[n] + grid.vel_new[n]);
                    l += v * crate::Vec2::new(gx, gy).transpose();
                })
            });
            sum += self.d[p].component_mul(&l).sum() * inv_h;
        }
        -g.dt * sum
    }
}
