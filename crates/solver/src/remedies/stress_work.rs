//! The work of a pressure change made by a remedy (pressure smoothing, an
//! averaged J that is not carried): the change dp_p is kept until the grid
//! update that uses it (the same step under USF, the next under USL and
//! MUSL), which books dt sum_i df_i . v_i^{n+1/2} = dt sum_p V_p dp_p
//! div v^{n+1/2}(x_p), with the force's gradient form (df_i = sum_p V_p dp_p
//! grad N_ip). A particle deleted in between drops the step's booking (the
//! kept changes no longer line up with the particles).

use super::GridStep;
use crate::particles::Particles;
use crate::shapes::with_width;

#[derive(Clone, Debug, Default)]
pub struct StressWork {
    /// Per particle: the pressure change not yet booked.
    dp: Vec<f64>,
    /// Particles when it was recorded (None: nothing pending).
    recorded: Option<usize>,
}

impl StressWork {
    pub fn new(particles: usize) -> Self {
        StressWork {
            dp: vec![0.0; particles],
            recorded: None,
        }
    }

    pub fn fit_particles(&mut self, n: usize) {
        if self.dp.len() < n {
            self.dp.resize(n, 0.0);
        }
    }

    /// Keeps p - `before` per particle (0 where either is not finite).
    pub fn record(&mut self, ps: &Particles, before: &[f64]) {
        let n = ps.len();
        for p in 0..n {
            let d = ps.pressure[p] - before[p];
            self.dp[p] = if d.is_finite() { d } else { 0.0 };
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
        let (ps, grid) = (g.particles, &*g.grid);
        let nx = grid.dims[0];
        let inv_h = 1.0 / grid.h;
        let mut sum = 0.0;
        for (p, st) in g.stencils.iter().enumerate() {
            if self.dp[p] == 0.0 {
                continue;
            }
            let (wx, dwx) = g.shape.stencil_weights::<W>(st.frac[0], st.half[0]);
            let (wy, dwy) = g.shape.stencil_weights::<W>(st.frac[1], st.half[1]);
            let mut div = 0.0;
            for c in 0..W {
                let row = st.node as usize + c * nx;
                for a in 0..W {
                    let v = 0.5 * (grid.vel[row + a] + grid.vel_new[row + a]);
                    div += dwx[a] * wy[c] * v.x + wx[a] * dwy[c] * v.y;
                }
            }
            sum += ps.vol[p] * self.dp[p] * div * inv_h;
        }
        g.dt * sum
    }
}
