//! Terzaghi's consolidation (docs/physics.md section 6).

use crate::output::summary::Check;
use crate::output::tables;
use crate::run::{Probe, Run, Simulated};
use crate::study_file::MixtureSpec;
use serde::{Deserialize, Serialize};
use solver::multiphase::pore_pressure::ramp_share;
use solver::{Mixture, Phase, Scene};
use std::path::{Path, PathBuf};

/// Terzaghi's consolidation (docs/physics.md section 6): a saturated
/// column (one solid and one fluid body over the same rectangle standing on
/// the floor, periodic in x, no gravity, pore pressure on) loaded on top by
/// q ramped over t_r (`ramp_share`). Its pore pressure against the series
/// solution for that ramp (Duhamel's sum of the step solution over the
/// load's increments), and its degree of consolidation from the top's
/// settlement against the exact one. The series is posed on the skeleton
/// (small strain): each water row is compared at its depth in the
/// skeleton's reference column, the depth of the grains beside it at t = 0.
/// The top rows settle by up to s_inf (1.2 % of the height), and the
/// steep early gradient at the drained top makes the fixed-wall depth
/// differ by a third of the error budget there.
pub struct TerzaghiCheck {
    height: f64,
    p0: f64,
    cv: f64,
    ramp: f64,
    /// Settlement per unit load right after loading (undrained) and at the end.
    s0: f64,
    s_inf: f64,
    row: f64,
    /// The solid's lattice row of each particle (by id) and each row's
    /// height at t = 0.
    solid_row: Vec<usize>,
    row_y0: Vec<f64>,
    /// Samples: t, T, max |p - p_exact| / p0, U simulated, U exact.
    samples: Vec<[f64; 5]>,
}

/// Terms of the series solutions.
const MODES: usize = 400;

impl TerzaghiCheck {
    /// Compared only for T >= this: the issue's window ("after the initial
    /// wave has passed"); the ramp's ringing is still in it.
    const T_FROM: f64 = 0.05;

    pub fn new(scene: &Scene, spec: &MixtureSpec, mix: &Mixture) -> Option<Self> {
        let [solid, fluid] = Phase::ALL.map(|ph| scene.bodies.iter().find(|b| b.phase == Some(ph)));
        let (solid, fluid) = (solid?, fluid?);
        let single = scene.bodies.len() == 2;
        let on_floor = (solid.rect[1] - scene.origin[1]).abs() < 1e-12;
        if !(spec.pore_pressure
            && spec.top_traction > 0.0
            && scene.gravity == 0.0
            && single
            && on_floor
            && solid.rect == fluid.rect
            && scene.periodic == [true, false])
        {
            return None;
        }
        let sm = &scene.materials[scene.material_index(solid)?];
        let k_f = mix.pore_fluid()?.k;
        let n = fluid.fraction;
        let m = solid.fraction * (sm.k + 4.0 * sm.shear_modulus / 3.0);
        let permeability_over_mu = n * n / spec.drag.coefficient_at(n);
        let height = solid.rect[3] - solid.rect[1];
        let q = spec.top_traction;
        let v = mix.phase(0).view();
        let l = scene.cell / scene.ppc as f64;
        let y_max = v.x.iter().map(|x| x.y).fold(f64::NEG_INFINITY, f64::max);
        let y_min = v.x.iter().map(|x| x.y).fold(f64::INFINITY, f64::min);
        let row_of = |y: f64| ((y - y_min) / l).round().max(0.0) as usize;
        let rows = row_of(y_max) + 1;
        let mut solid_row = vec![usize::MAX; v.n_initial];
        let mut row_sums = vec![(0.0, 0.0); rows];
        for (x, &id) in v.x.iter().zip(v.id) {
            let r = row_of(x.y);
            solid_row[id as usize] = r;
            row_sums[r].0 += x.y;
            row_sums[r].1 += 1.0;
        }
        let row_y0 = row_sums
            .iter()
            .map(|&(y, c)| y / f64::max(c, 1.0))
            .collect();
        Some(TerzaghiCheck {
            height,
            solid_row,
            row_y0,
            p0: q / (1.0 + n * m / k_f),
            cv: permeability_over_mu / (1.0 / m + n / k_f),
            ramp: spec.traction_ramp,
            s0: q * height / (m + k_f / n),
            s_inf: q * height / m,
            row: 0.5 * scene.cell,
            samples: vec![],
        })
    }

    /// Load history weights: (tau, dq/q over the step) at RAMP_POINTS
    /// midpoints of the ramp's part before t (empty for a step load).
    fn history(&self, t: f64) -> Vec<(f64, f64)> {
        const RAMP_POINTS: usize = 200;
        if self.ramp <= 0.0 {
            return vec![];
        }
        let held = t.min(self.ramp);
        let d = held / RAMP_POINTS as f64;
        (0..RAMP_POINTS)
            .map(|i| {
                let (a, b) = (i as f64 * d, (i + 1) as f64 * d);
                (
                    0.5 * (a + b),
                    ramp_share(b, self.ramp) - ramp_share(a, self.ramp),
                )
            })
            .collect()
    }

    /// Each mode's decay at t for the ramped load (Duhamel: the step
    /// solution's exp(-a_k (t - tau)) summed over the load's increments).
    fn mode_decays(&self, t: f64, history: &[(f64, f64)]) -> Vec<f64> {
        let hh = self.height * self.height;
        (0..MODES)
            .map(|k| {
                let m = (2 * k + 1) as f64 * std::f64::consts::FRAC_PI_2;
                let a = m * m * self.cv / hh;
                if history.is_empty() {
                    (-a * t).exp()
                } else {
                    history
                        .iter()
                        .map(|&(tau, dq)| dq * (-a * (t - tau)).exp())
                        .sum()
                }
            })
            .collect()
    }

    /// The exact pressure at depth z from the modes' decays.
    fn pressure(&self, z: f64, decays: &[f64]) -> f64 {
        self.p0
            * decays
                .iter()
                .enumerate()
                .map(|(k, d)| {
                    let m = (2 * k + 1) as f64 * std::f64::consts::FRAC_PI_2;
                    2.0 / m * (m * z / self.height).sin() * d
                })
                .sum::<f64>()
    }

    /// Settlement fraction of the step load: s0 + (s_inf - s0) U(T).
    fn step_settlement(&self, t: f64) -> f64 {
        let big_t = self.cv * t / (self.height * self.height);
        let u = 1.0
            - (0..MODES)
                .map(|k| {
                    let m = (2 * k + 1) as f64;
                    8.0 / (m * m * std::f64::consts::PI.powi(2))
                        * (-m * m * std::f64::consts::PI.powi(2) * big_t / 4.0).exp()
                })
                .sum::<f64>();
        self.s0 + (self.s_inf - self.s0) * u
    }

    /// U of the ramped load, as the simulation's: the settlement beyond the
    /// undrained part of the load applied so far, over s_inf - s0.
    fn exact_u(&self, t: f64, history: &[(f64, f64)]) -> f64 {
        let settlement = if history.is_empty() {
            self.step_settlement(t)
        } else {
            history
                .iter()
                .map(|&(tau, dq)| dq * self.step_settlement(t - tau))
                .sum()
        };
        (settlement - self.s0 * ramp_share(t, self.ramp)) / (self.s_inf - self.s0)
    }

    pub fn sample(&mut self, mix: &Mixture) {
        let t = mix.time();
        let big_t = self.cv * t / (self.height * self.height);
        let history = self.history(t);
        let decays = self.mode_decays(t, &history);
        let skeleton = self.skeleton_rows(mix);
        let fluid = mix.phase(1).view();
        let rows = (self.height / self.row).ceil() as usize + 1;
        let mut sums = vec![(0.0, 0.0, 0usize); rows];
        for (x, p) in fluid.x.iter().zip(fluid.pressure) {
            if x.y < self.height {
                let r = ((x.y / self.row) as usize).min(rows - 1);
                sums[r].0 += x.y;
                sums[r].1 += p;
                sums[r].2 += 1;
            }
        }
        let error = sums
            .iter()
            .filter(|r| r.2 > 0)
            .map(|&(y, p, c)| {
                let (y, p) = (y / c as f64, p / c as f64);
                let z = self.height - reference_height(y, &skeleton);
                (p - self.pressure(z.clamp(0.0, self.height), &decays)).abs()
            })
            .fold(0.0, f64::max)
            / self.p0;
        // The top row's settlement.
        let settlement = skeleton.last().map_or(0.0, |&(y, y0)| y0 - y);
        let u = (settlement - self.s0 * ramp_share(t, self.ramp)) / (self.s_inf - self.s0);
        self.samples
            .push([t, big_t, error, u, self.exact_u(t, &history)]);
    }

    /// Each solid lattice row's (current, initial) mean height, bottom up.
    fn skeleton_rows(&self, mix: &Mixture) -> Vec<(f64, f64)> {
        let solid = mix.phase(0).view();
        let mut sums = vec![(0.0, 0.0); self.row_y0.len()];
        for (x, &id) in solid.x.iter().zip(solid.id) {
            if let Some(&r) = self
                .solid_row
                .get(id as usize)
                .filter(|&&r| r != usize::MAX)
            {
                sums[r].0 += x.y;
                sums[r].1 += 1.0;
            }
        }
        sums.iter()
            .zip(&self.row_y0)
            .filter(|(s, _)| s.1 > 0.0)
            .map(|(&(y, c), &y0)| (y / c, y0))
            .collect()
    }

    fn max_error(&self) -> Option<f64> {
        self.samples
            .iter()
            .filter(|s| s[1] >= Self::T_FROM)
            .map(|s| s[2])
            .reduce(f64::max)
    }

    fn write(&self, dir: &Path, csv: bool) -> std::io::Result<()> {
        let col = |k: usize| self.samples.iter().map(|s| s[k]).collect::<Vec<f64>>();
        let (t, big_t, e, u, ue) = (col(0), col(1), col(2), col(3), col(4));
        tables::write_columns(
            &[
                ("t", &t),
                ("T", &big_t),
                ("max_error_over_p0", &e),
                ("U", &u),
                ("U_exact", &ue),
            ],
            dir,
            "terzaghi",
            csv,
        )
    }
}

/// The height at t = 0 of the skeleton's material now at height y, from
/// its rows' (current, initial) heights, bottom up: linear between rows,
/// and beyond the outer rows displaced as they are.
fn reference_height(y: f64, rows: &[(f64, f64)]) -> f64 {
    let (Some(first), Some(last)) = (rows.first(), rows.last()) else {
        return y;
    };
    if y <= first.0 {
        return y + first.1 - first.0;
    }
    if y >= last.0 {
        return y + last.1 - last.0;
    }
    let k = rows.partition_point(|r| r.0 <= y);
    let ((ya, a0), (yb, b0)) = (rows[k - 1], rows[k]);
    a0 + (y - ya) / (yb - ya) * (b0 - a0)
}

/// Terzaghi's column (pore pressure on, a top traction, no gravity): the
/// largest |p - p_exact| / p0 over rows of half a cell and the samples with
/// T >= 0.05 (the window), and the largest |U - U_exact| there;
/// both series are in terzaghi.parquet.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TerzaghiFigures {
    pub max_error_over_p0: Option<f64>,
    pub u_error: Option<f64>,
}

impl Check for TerzaghiFigures {
    const NAME: &'static str = "terzaghi";
}

/// The check sampled at every timeseries row; `terzaghi.parquet` and its
/// figures at the end.
pub struct Terzaghi {
    pub check: TerzaghiCheck,
    pub dir: PathBuf,
    pub csv: bool,
}

impl Probe<Mixture> for Terzaghi {
    fn row(&mut self, run: &Run<Mixture>) {
        self.check.sample(run.stepper);
    }

    fn finish(&mut self, _: &Run<Mixture>, outcome: &mut Simulated) -> std::io::Result<()> {
        let c = &self.check;
        c.write(&self.dir, self.csv)?;
        outcome.metrics.set_check(&TerzaghiFigures {
            max_error_over_p0: c.max_error(),
            u_error: c
                .samples
                .iter()
                .filter(|s| s[1] >= TerzaghiCheck::T_FROM)
                .map(|s| (s[3] - s[4]).abs())
                .reduce(f64::max),
        });
        Ok(())
    }
}
