//! A mixture case end to end (docs/physics.md section 6): the two phases
//! stepped together by `solver::Mixture`, each watched by its own monitor
//! (events carry their phase), one timeseries per phase (`timeseries.parquet`
//! the fluid's, `timeseries_solid.parquet` the solid's), the mixture's own
//! rows in `mixture.parquet` (relative velocity, drag dissipation, total
//! energy and momentum), VTK files per phase and the summary with each
//! phase's figures, and ring checkpoints of the mixture and both monitors
//! (the one before each event kept) for `kick reproduce`.

use crate::case_checkpoint;
use crate::metrics::{self, line_fit};
use crate::run_case::{CheckpointRing, RunOptions, Simulated};
use crate::snapshot::{self, Snapshot};
use crate::study_file::{Case, MixtureSpec};
use crate::summary::{Metrics, PhaseSummary, Status};
use crate::tables;
use crate::timeseries::{Peaks, Timeseries};
use indicatif::ProgressBar;
use monitor::{Event, Monitor, StepReport};
use solver::multiphase::drag::DragUpdate;
use solver::multiphase::pore_pressure::ramp_share;
use solver::{Mixture, Phase, Scene, Solver, StateView, Vec2};
use std::path::Path;

/// One phase's monitor and the timeseries it feeds.
struct PhaseWatch {
    phase: Phase,
    monitor: Monitor,
    series: Timeseries,
    peaks: Peaks,
}

impl PhaseWatch {
    /// Observes the phase's last step; the monitor's blow-out reason, if any.
    /// Observes the phase's last step and stamps the events it opened with
    /// the phase and the mixture's state hash (computed once a step, and
    /// only when an event opens: it reads every particle).
    fn observe(&mut self, mix: &Mixture, hash: &mut Option<String>) -> Option<String> {
        self.monitor.observe(&mix.phase(self.phase.index()).view());
        let report = self.monitor.report();
        self.peaks.add(report);
        let opened = report.events_opened;
        let blow_out = report.blow_out.clone();
        if opened > 0 {
            let hash = hash
                .get_or_insert_with(|| format!("{:016x}", mix.state_hash()))
                .clone();
            let n = self.monitor.events().len();
            for e in &mut self.monitor.events_mut()[n - opened..] {
                e.phase = Some(self.phase.name().into());
                e.state_hash = Some(hash.clone());
            }
        }
        blow_out
    }

    fn push_row(&mut self, v: &StateView, event_row: bool) {
        if self.series.last_step() == Some(v.step) {
            return;
        }
        let fields = self.monitor.field_metrics(v);
        let report = if v.step == 0 || self.monitor.report().step != v.step {
            StepReport::of_state(v)
        } else {
            self.monitor.report().clone()
        };
        self.series.push(&report, &self.peaks, &fields, event_row);
        self.peaks = Peaks::default();
    }
}

/// Mass-weighted mean particle velocity of a phase.
fn mean_velocity(s: &Solver) -> Vec2 {
    let p = s.view();
    let (mut mv, mut m) = (Vec2::zeros(), 0.0);
    for (v, mass) in p.v.iter().zip(p.mass) {
        mv += *mass * v;
        m += mass;
    }
    if m > 0.0 {
        mv / m
    } else {
        Vec2::zeros()
    }
}

fn momentum_and_scale(s: &Solver) -> (Vec2, f64) {
    let p = s.view();
    p.v.iter()
        .zip(p.mass)
        .fold((Vec2::zeros(), 0.0), |(sum, scale), (v, m)| {
            (sum + *m * v, scale + m * v.norm())
        })
}

/// The drag-decay scene: periodic in x and y, no gravity, every body
/// covering the whole box (a uniform mixture). Then dv = v_f - v_s decays as
/// dv0 exp(-t/tau), tau = rs rf / [B (rs + rf)] with the partial densities
/// rs = n_s rho_s, rf = n_f rho_f (tau = rf / B over a fixed skeleton).
fn decay_time(scene: &Scene, spec: &MixtureSpec) -> Option<f64> {
    let covers = |r: &[f64; 4]| {
        let tol = 1e-12 * scene.size[0].max(scene.size[1]);
        (r[0] - scene.origin[0]).abs() <= tol
            && (r[1] - scene.origin[1]).abs() <= tol
            && (r[2] - scene.origin[0] - scene.size[0]).abs() <= tol
            && (r[3] - scene.origin[1] - scene.size[1]).abs() <= tol
    };
    let uniform = scene.periodic == [true, true]
        && scene.gravity == 0.0
        && scene.bodies.iter().all(|b| covers(&b.rect));
    if !uniform {
        return None;
    }
    let [rs, rf] = Phase::ALL.map(|phase| {
        let b = scene.bodies.iter().find(|b| b.phase == Some(phase));
        b.map_or(0.0, |b| {
            let m = scene.material_index(b).expect("validated");
            b.fraction * scene.materials[m].rho0
        })
    });
    let fraction = |phase| {
        scene
            .bodies
            .iter()
            .find(|b| b.phase == Some(phase))
            .map_or(0.0, |b| b.fraction)
    };
    let (ns, nf) = (fraction(Phase::Solid), fraction(Phase::Fluid));
    let b = spec.drag.coefficient_at(nf / (ns + nf));
    if b <= 0.0 {
        return None;
    }
    Some(if spec.fixed_solid {
        rf / b
    } else {
        rs * rf / (b * (rs + rf))
    })
}

/// The Darcy column: a fixed layer (below) under gravity.
fn darcy_layer(scene: &Scene, spec: &MixtureSpec) -> Option<[f64; 2]> {
    fixed_layer(scene, spec).filter(|_| scene.gravity > 0.0)
}

/// A fixed skeleton layer spanning the box's width in a box periodic in x
/// and y. Returns the layer's [y0, y1].
fn fixed_layer(scene: &Scene, spec: &MixtureSpec) -> Option<[f64; 2]> {
    let solids: Vec<_> = scene
        .bodies
        .iter()
        .filter(|b| b.phase == Some(Phase::Solid))
        .collect();
    let tol = 1e-12 * scene.size[0];
    let spans = |r: &[f64; 4]| {
        (r[0] - scene.origin[0]).abs() <= tol
            && (r[2] - scene.origin[0] - scene.size[0]).abs() <= tol
    };
    let [layer] = solids.as_slice() else {
        return None;
    };
    (spec.fixed_solid && scene.periodic == [true, true] && spans(&layer.rect))
        .then_some([layer.rect[1], layer.rect[3]])
}

/// The drag-convergence scene: a fixed layer without gravity in a fluid
/// filling the box, moving along the layer. The fluid inside the layer
/// decays by the update's own law (exp(-t/tau) exponential, prod(1 -
/// dt/tau) explicit, prod 1/(1 + dt/tau) implicit; tau = n rho_f / B), the
/// rest keeps its speed: u(t) = u0 [s law(t) + 1 - s], s = L / H. The error
/// is |u - u(t)| / (|u0| s), its largest over the run: what the
/// interaction model's treatment of the layer's faces costs.
struct LayerCheck {
    u0: Vec2,
    share: f64,
    tau: f64,
    update: DragUpdate,
    law: f64,
    max_error: f64,
}

impl LayerCheck {
    fn new(scene: &Scene, spec: &MixtureSpec, u0: Vec2) -> Option<Self> {
        let layer = fixed_layer(scene, spec).filter(|_| scene.gravity == 0.0)?;
        let fluid = scene
            .bodies
            .iter()
            .find(|b| b.phase == Some(Phase::Fluid))?;
        let rho = scene.materials[scene.material_index(fluid)?].rho0;
        let n = fluid.fraction;
        let b = spec.drag.coefficient_at(n);
        (u0.norm() > 0.0 && b > 0.0).then(|| LayerCheck {
            u0,
            share: (layer[1] - layer[0]) / scene.size[1],
            tau: n * rho / b,
            update: spec.drag.update,
            law: 1.0,
            max_error: 0.0,
        })
    }

    fn after_step(&mut self, dt: f64, u: Vec2) {
        let r = dt / self.tau;
        self.law *= match self.update {
            DragUpdate::Explicit => 1.0 - r,
            DragUpdate::Implicit => 1.0 / (1.0 + r),
            DragUpdate::Exponential => (-r).exp(),
        };
        let expected = self.u0 * (self.share * self.law + 1.0 - self.share);
        let error = (u - expected).norm() / (self.u0.norm() * self.share);
        self.max_error = self.max_error.max(error);
    }
}

/// Darcy's figures from the fluid's state: (relative error of the layer's
/// pressure drop against mu q L / k = B q L / n^2, linearity of p inside the
/// layer relative to that drop, from three rows up; the flux q). Rows of one cell; the layer's
/// gradient from rows at least one cell inside its faces, the free fluid's
/// from rows at least two cells away from them.
fn darcy_figures(
    v: &StateView,
    layer: [f64; 2],
    b: f64,
    n: f64,
) -> Option<(f64, Option<f64>, f64)> {
    let h = v.scene.cell;
    let (y_lo, height) = (v.scene.origin[1], v.scene.size[1]);
    let rows = (height / h).round() as usize;
    let mut sum = vec![(0.0, 0.0, 0usize); rows];
    for ((x, p), vel) in v.x.iter().zip(v.pressure).zip(v.v) {
        let r = (((x.y - y_lo) / h).floor().max(0.0) as usize).min(rows - 1);
        sum[r].0 += p;
        sum[r].1 += vel.y;
        sum[r].2 += 1;
    }
    let [y0, y1] = layer;
    let row = |r: usize| {
        let (lo, hi) = (y_lo + r as f64 * h, y_lo + (r + 1) as f64 * h);
        let (p, vy, c) = sum[r];
        (lo, hi, p / c.max(1) as f64, vy / c.max(1) as f64, c)
    };
    let eps = 1e-9 * h;
    let inside: Vec<_> = (0..rows)
        .map(row)
        .filter(|&(lo, hi, _, _, c)| c > 0 && lo >= y0 + h - eps && hi <= y1 - h + eps)
        .collect();
    let far = |lo: f64, hi: f64| hi <= y0 - 2.0 * h + eps || lo >= y1 + 2.0 * h - eps;
    let above: Vec<(f64, f64)> = (0..rows)
        .map(row)
        .filter(|&(lo, hi, _, _, c)| c > 0 && far(lo, hi) && lo >= y1)
        .map(|(lo, hi, p, _, _)| (0.5 * (lo + hi), p))
        .collect();
    let below: Vec<(f64, f64)> = (0..rows)
        .map(row)
        .filter(|&(lo, hi, _, _, c)| c > 0 && far(lo, hi) && hi <= y0)
        .map(|(lo, hi, p, _, _)| (0.5 * (lo + hi), p))
        .collect();
    let pts: Vec<(f64, f64)> = inside
        .iter()
        .map(|&(lo, hi, p, _, _)| (0.5 * (lo + hi), p))
        .collect();
    let (s_in, a_in) = line_fit(&pts)?;
    let outside: Vec<(f64, usize)> = [&above, &below]
        .iter()
        .filter_map(|pts| line_fit(pts).map(|(s, _)| (s, pts.len())))
        .collect();
    let weight: usize = outside.iter().map(|o| o.1).sum();
    if weight == 0 {
        return None;
    }
    let s_out = outside.iter().map(|o| o.0 * o.1 as f64).sum::<f64>() / weight as f64;
    // Darcy flux (downward positive): n times the fluid's speed in the layer.
    let q = -n * inside.iter().map(|r| r.3).sum::<f64>() / inside.len() as f64;
    let expected = b * q / (n * n);
    let error = ((s_in - s_out) - expected).abs() / expected.abs();
    let drop = expected.abs() * (y1 - y0);
    // A line through two rows says nothing about linearity.
    let linearity = (pts.len() >= 3).then(|| {
        pts.iter()
            .map(|&(y, p)| (p - (a_in + s_in * y)).abs())
            .fold(0.0, f64::max)
            / drop
    });
    Some((error, linearity, q))
}

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
struct TerzaghiCheck {
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

    fn new(scene: &Scene, spec: &MixtureSpec, mix: &Mixture) -> Option<Self> {
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

    fn sample(&mut self, mix: &Mixture) {
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

/// The fluid's free surface and wetting front under gravity (a box closed
/// along gravity): per column of one cell, the highest and the lowest
/// fluid particle; their spreads (max - min over the columns holding
/// fluid) per sample, averaged over the last simulated second of a run that
/// reached t_end (the filter stone's levelling and evenness of penetration).
struct SurfaceCheck {
    /// (t, surface spread, penetration spread)
    samples: Vec<[f64; 3]>,
}

impl SurfaceCheck {
    fn new(scene: &Scene) -> Option<Self> {
        (scene.gravity > 0.0 && !scene.periodic[1]).then_some(SurfaceCheck { samples: vec![] })
    }

    fn sample(&mut self, mix: &Mixture) {
        let v = mix.phase(1).view();
        let (h, x0) = (v.scene.cell, v.scene.origin[0]);
        let columns = (v.scene.size[0] / h).round() as usize;
        let mut top = vec![f64::NEG_INFINITY; columns];
        let mut bottom = vec![f64::INFINITY; columns];
        for x in v.x {
            let c = (((x.x - x0) / h).floor().max(0.0) as usize).min(columns - 1);
            top[c] = top[c].max(x.y);
            bottom[c] = bottom[c].min(x.y);
        }
        let spread = |v: &[f64]| {
            let (lo, hi) = v
                .iter()
                .filter(|y| y.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
                    (a.min(y), b.max(y))
                });
            if hi >= lo {
                hi - lo
            } else {
                f64::NAN
            }
        };
        self.samples
            .push([mix.time(), spread(&top), spread(&bottom)]);
    }

    /// Mean of column k over the last simulated second.
    fn late(&self, k: usize, t_end: f64) -> Option<f64> {
        let v: Vec<f64> = self
            .samples
            .iter()
            .filter(|s| s[0] >= t_end - 1.0 && s[0] > 0.0 && s[k].is_finite())
            .map(|s| s[k])
            .collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    }
}

/// Largest saturation of a cell: the reference volumes (grains and the
/// fluid's V_p^0) of the particles in it over its area. 1 in a saturated
/// mixture; above 1 where water crowds into the grains' room.
fn saturation_max(mix: &Mixture) -> f64 {
    let v = mix.phase(0).view();
    let (h, o) = (v.scene.cell, v.scene.origin);
    let [nx, ny] = [0, 1].map(|k| (v.scene.size[k] / h).round() as usize);
    let mut cells = vec![0.0; nx * ny];
    for k in 0..2 {
        let v = mix.phase(k).view();
        for (x, v0) in v.x.iter().zip(v.volume0) {
            let i = (((x.x - o[0]) / h).floor().max(0.0) as usize).min(nx - 1);
            let j = (((x.y - o[1]) / h).floor().max(0.0) as usize).min(ny - 1);
            cells[i + j * nx] += v0;
        }
    }
    cells.iter().fold(0.0, |m: f64, c| m.max(c / (h * h)))
}

/// The relative velocity against the exact decay and the update's own law.
struct DecayCheck {
    tau: f64,
    dv0: Vec2,
    update: DragUpdate,
    /// The update's discrete decay factor so far.
    discrete: f64,
    max_error: f64,
    max_discrete_error: f64,
    first_ratio: Option<f64>,
}

impl DecayCheck {
    fn new(tau: f64, dv0: Vec2, update: DragUpdate) -> Option<Self> {
        (dv0.norm() > 0.0).then_some(DecayCheck {
            tau,
            dv0,
            update,
            discrete: 1.0,
            max_error: 0.0,
            max_discrete_error: 0.0,
            first_ratio: None,
        })
    }

    fn exact(&self, t: f64) -> Vec2 {
        self.dv0 * (-t / self.tau).exp()
    }

    fn after_step(&mut self, dt: f64, t: f64, dv: Vec2) {
        let r = dt / self.tau;
        self.first_ratio.get_or_insert(r);
        self.discrete *= match self.update {
            DragUpdate::Explicit => 1.0 - r,
            DragUpdate::Implicit => 1.0 / (1.0 + r),
            DragUpdate::Exponential => (-r).exp(),
        };
        let scale = self.dv0.norm();
        self.max_error = self.max_error.max((dv - self.exact(t)).norm() / scale);
        self.max_discrete_error = self
            .max_discrete_error
            .max((dv - self.dv0 * self.discrete).norm() / scale);
    }
}

/// The mixture's own rows (`mixture.parquet`).
#[derive(Default)]
struct MixtureRows {
    step: Vec<f64>,
    t: Vec<f64>,
    dt: Vec<f64>,
    dv_x: Vec<f64>,
    dv_y: Vec<f64>,
    dv_exact_x: Vec<f64>,
    dv_exact_y: Vec<f64>,
    drag_dissipated: Vec<f64>,
    drag_nodes: Vec<f64>,
    drag_stable_dt: Vec<f64>,
    e_total: Vec<f64>,
    momentum_x: Vec<f64>,
    momentum_y: Vec<f64>,
}

impl MixtureRows {
    fn push(&mut self, mix: &Mixture, dv: Vec2, exact: Option<Vec2>, e_total: f64) {
        let c = mix.last_coupling();
        let p = mix.momentum();
        let exact = exact.unwrap_or(Vec2::new(f64::NAN, f64::NAN));
        let s = mix.phase(0);
        self.step.push(s.step_count() as f64);
        self.t.push(mix.time());
        self.dt.push(s.view().dt);
        self.dv_x.push(dv.x);
        self.dv_y.push(dv.y);
        self.dv_exact_x.push(exact.x);
        self.dv_exact_y.push(exact.y);
        self.drag_dissipated.push(mix.drag_dissipated());
        self.drag_nodes.push(c.nodes as f64);
        self.drag_stable_dt.push(c.stable_dt);
        self.e_total.push(e_total);
        self.momentum_x.push(p.x);
        self.momentum_y.push(p.y);
    }

    fn write(&self, dir: &Path, csv: bool) -> std::io::Result<()> {
        tables::write_columns(
            &[
                ("step", &self.step),
                ("t", &self.t),
                ("dt", &self.dt),
                ("dv_x", &self.dv_x),
                ("dv_y", &self.dv_y),
                ("dv_exact_x", &self.dv_exact_x),
                ("dv_exact_y", &self.dv_exact_y),
                ("drag_dissipated", &self.drag_dissipated),
                ("drag_nodes", &self.drag_nodes),
                ("drag_stable_dt", &self.drag_stable_dt),
                ("e_total", &self.e_total),
                ("momentum_x", &self.momentum_x),
                ("momentum_y", &self.momentum_y),
            ],
            dir,
            "mixture",
            csv,
        )
    }
}

fn write_vtk(dir: &Path, mix: &Mixture) -> std::io::Result<()> {
    for phase in Phase::ALL {
        let v = mix.phase(phase.index()).view();
        snapshot::write_file(dir, phase.name(), &Snapshot::of(&v))?;
    }
    Ok(())
}

fn checkpoint(mix: &Mixture, watches: &[PhaseWatch; 2]) -> Vec<u8> {
    case_checkpoint::save_mixture(mix, [&watches[0].monitor, &watches[1].monitor])
}

/// The mixture a case describes, at t = 0.
pub(crate) fn build(case: &Case, spec: &MixtureSpec) -> Result<Mixture, String> {
    let [solid, fluid] = case.phase_configs();
    let phases = [solid, fluid].map(Solver::new);
    let [solid, fluid] = phases;
    let solid = solid.map_err(|e| format!("setup (solid): {e}"))?;
    let fluid = fluid.map_err(|e| format!("setup (fluid): {e}"))?;
    let mut mix = Mixture::new([solid, fluid], spec.drag).map_err(|e| format!("setup: {e}"))?;
    if spec.fixed_solid {
        mix = mix.fix_solid();
    }
    if spec.pore_pressure {
        mix = mix.with_pore_pressure();
    }
    if spec.pore_node_average {
        mix = mix
            .with_pore_node_average()
            .map_err(|e| format!("setup: {e}"))?;
    }
    if spec.volume_constraint {
        mix = mix.with_volume_constraint();
    }
    if spec.top_traction > 0.0 {
        mix = mix.with_top_load(spec.top_traction, spec.traction_ramp);
    }
    if !spec.drained.is_empty() {
        mix = mix
            .with_drained(&spec.drained, spec.drained_pressure)
            .map_err(|e| format!("setup: {e}"))?;
    }
    if !spec.inflow.is_empty() {
        mix = mix
            .with_inflow(&spec.inflow, spec.inflow_velocity)
            .map_err(|e| format!("setup: {e}"))?;
    }
    Ok(mix)
}

pub(crate) fn simulate(case: &Case, dir: &Path, opts: &RunOptions) -> std::io::Result<Simulated> {
    let spec = case.mixture.clone().expect("a mixture case");
    let mut mix = match build(case, &spec) {
        Ok(m) => m,
        Err(reason) => return Ok(Simulated::failed(reason)),
    };
    let mut watches = Phase::ALL.map(|phase| PhaseWatch {
        phase,
        monitor: Monitor::new(case.monitor.clone(), &mix.phase(phase.index()).view()),
        series: Timeseries::new(),
        peaks: Peaks::default(),
    });
    let scene = &case.solver.scene;
    let t_end = scene.t_end;
    let expected_steps = (t_end / mix.next_dt()).ceil().max(1.0) as u64;
    let row_every = (expected_steps / case.output.timeseries_rows).max(1);
    let bar = opts.bar.clone().unwrap_or_else(ProgressBar::hidden);
    bar.set_length(1000);
    bar.set_prefix(case.name.clone());
    let particles_dir = dir.join("particles");
    let mut vtk_times = case.output.vtk_times.clone();
    vtk_times.sort_by(f64::total_cmp);
    let mut next_vtk = 0;

    let relative = |m: &Mixture| mean_velocity(m.phase(1)) - mean_velocity(m.phase(0));
    let mut decay = decay_time(scene, &spec)
        .and_then(|tau| DecayCheck::new(tau, relative(&mix), spec.drag.update));
    let mut layer = LayerCheck::new(scene, &spec, mean_velocity(mix.phase(1)));
    let mut terzaghi = TerzaghiCheck::new(scene, &spec, &mix);
    let mut surface = SurfaceCheck::new(scene);
    let conserves_momentum =
        scene.periodic == [true, true] && scene.gravity == 0.0 && !spec.fixed_solid;
    let (p0, p_scale) = {
        let (a, b) = (
            momentum_and_scale(mix.phase(0)),
            momentum_and_scale(mix.phase(1)),
        );
        (a.0 + b.0, a.1 + b.1)
    };
    let mut momentum_drift: f64 = 0.0;
    let total_energy = |m: &Mixture| m.energy().total();
    let e0 = total_energy(&mix);
    let mut energy_growth: f64 = 0.0;
    let mut rows = MixtureRows::default();

    let push_rows = |mix: &Mixture,
                     watches: &mut [PhaseWatch; 2],
                     rows: &mut MixtureRows,
                     decay: &Option<DecayCheck>,
                     terzaghi: &mut Option<TerzaghiCheck>,
                     surface: &mut Option<SurfaceCheck>,
                     event_row: bool| {
        for w in watches.iter_mut() {
            w.push_row(&mix.phase(w.phase.index()).view(), event_row);
        }
        if rows.step.last() != Some(&(mix.phase(0).step_count() as f64)) {
            let exact = decay.as_ref().map(|d| d.exact(mix.time()));
            rows.push(mix, relative(mix), exact, total_energy(mix));
            if let Some(c) = terzaghi.as_mut() {
                c.sample(mix);
            }
            if let Some(c) = surface.as_mut() {
                c.sample(mix);
            }
        }
    };

    while next_vtk < vtk_times.len() && vtk_times[next_vtk] <= mix.time() {
        write_vtk(&particles_dir, &mix)?;
        next_vtk += 1;
    }
    push_rows(
        &mix,
        &mut watches,
        &mut rows,
        &decay,
        &mut terzaghi,
        &mut surface,
        false,
    );
    let mut ring = CheckpointRing::start(dir, case.output.checkpoint_every, || {
        checkpoint(&mix, &watches)
    })?;
    let (status, reason) = loop {
        if mix.phase(0).finished() {
            break (Status::Completed, String::new());
        }
        let stop = mix
            .step()
            .err()
            .map(|e| format!("step {}: {e}", mix.phase(0).step_count() + 1));
        let step = mix.phase(0).step_count();
        let mut opened = 0;
        let mut stop = stop;
        if stop.is_none() {
            let mut hash = None;
            let mut new = [0; 2];
            for (k, w) in watches.iter_mut().enumerate() {
                let before = w.monitor.events().len();
                if let Some(r) = w.observe(&mix, &mut hash) {
                    stop.get_or_insert(format!("{} phase, step {step}: {r}", w.phase.name()));
                }
                new[k] = w.monitor.events().len() - before;
                opened += new[k];
            }
            if opened > 0 {
                // The checkpoint before them, kept for `kick reproduce`.
                let checkpoint = ring.pin_latest();
                for (w, n_new) in watches.iter_mut().zip(new) {
                    let n = w.monitor.events().len();
                    for e in &mut w.monitor.events_mut()[n - n_new..] {
                        e.checkpoint = checkpoint.clone();
                    }
                }
            }
            let dt = mix.phase(0).view().dt;
            if let Some(d) = decay.as_mut() {
                d.after_step(dt, mix.time(), relative(&mix));
            }
            if let Some(l) = layer.as_mut() {
                l.after_step(dt, mean_velocity(mix.phase(1)));
            }
            if conserves_momentum && p_scale > 0.0 {
                let (a, b) = (
                    momentum_and_scale(mix.phase(0)),
                    momentum_and_scale(mix.phase(1)),
                );
                momentum_drift = momentum_drift.max((a.0 + b.0 - p0).norm() / p_scale);
            }
            energy_growth = energy_growth.max(total_energy(&mix) - e0);
        }
        let regular = step % row_every == 0;
        if regular || opened > 0 || stop.is_some() {
            push_rows(
                &mix,
                &mut watches,
                &mut rows,
                &decay,
                &mut terzaghi,
                &mut surface,
                !regular || stop.is_some(),
            );
            let t = mix.time();
            bar.set_position((1000.0 * t / t_end) as u64);
            let events: usize = watches.iter().map(|w| w.monitor.events().len()).sum();
            bar.set_message(format!("t = {t:.3} s, {events} events"));
        }
        if let Some(reason) = stop {
            break (Status::BlewUp, reason);
        }
        while next_vtk < vtk_times.len() && vtk_times[next_vtk] <= mix.time() {
            write_vtk(&particles_dir, &mix)?;
            next_vtk += 1;
        }
        ring.after_step(step, || checkpoint(&mix, &watches))?;
    };
    push_rows(
        &mix,
        &mut watches,
        &mut rows,
        &decay,
        &mut terzaghi,
        &mut surface,
        status != Status::Completed,
    );
    write_vtk(&particles_dir, &mix)?;
    let completed = status == Status::Completed;
    let mut events: Vec<Event> = vec![];
    let mut phases = vec![];
    let mut initial_mass = 0.0;
    for w in &watches {
        let s = mix.phase(w.phase.index());
        let stem = match w.phase {
            Phase::Fluid => "timeseries".to_string(),
            Phase::Solid => "timeseries_solid".to_string(),
        };
        tables::write_timeseries_as(&w.series, dir, &stem, opts.csv)?;
        let own = w.monitor.events().to_vec();
        let mut m = metrics::summarise(&w.series, &own, None, completed);
        m.events_dropped = w.monitor.events_dropped();
        fill_losses(&mut m, s, w.monitor.initial_mass());
        initial_mass += w.monitor.initial_mass();
        phases.push(PhaseSummary {
            phase: w.phase.name().into(),
            particles: s.initial_particle_count(),
            n_events: own.len(),
            metrics: m,
        });
        events.extend(own);
    }
    rows.write(dir, opts.csv)?;
    events.sort_by(|a, b| a.t.total_cmp(&b.t));
    let fluid = &watches[Phase::Fluid.index()];
    let mut metrics = metrics::summarise(&fluid.series, &events, None, completed);
    metrics.events_dropped = phases.iter().map(|p| p.metrics.events_dropped).sum();
    let lost = |f: fn(&Metrics) -> u64| phases.iter().map(|p| f(&p.metrics)).sum::<u64>();
    metrics.particles_escaped = lost(|m| m.particles_escaped);
    metrics.particles_inverted = lost(|m| m.particles_inverted);
    metrics.particles_drained = lost(|m| m.particles_drained);
    let drained_mass: f64 = (0..2).map(|k| mix.phase(k).losses().mass_drained).sum();
    metrics.mass_drained_fraction = drained_mass / initial_mass;
    metrics.particles_injected = lost(|m| m.particles_injected);
    let injected_mass: f64 = (0..2).map(|k| mix.phase(k).losses().mass_injected).sum();
    metrics.mass_injected_fraction = injected_mass / initial_mass;
    let lost_mass: f64 = (0..2).map(|k| mix.phase(k).losses().mass()).sum();
    metrics.mass_lost_fraction = lost_mass / initial_mass;
    metrics.t_first_loss = phases
        .iter()
        .filter_map(|p| p.metrics.t_first_loss)
        .reduce(f64::min);
    if let Some(d) = &decay {
        metrics.drag_decay_rel_error = Some(d.max_error);
        metrics.drag_decay_discrete_rel_error = Some(d.max_discrete_error);
        metrics.drag_dt_over_tau = d.first_ratio;
    }
    metrics.drag_layer_error = layer.map(|l| l.max_error);
    metrics.saturation_max = Some(saturation_max(&mix));
    if let (Some(c), true) = (&surface, completed) {
        metrics.surface_spread_late = c.late(1, mix.time());
        metrics.penetration_spread_late = c.late(2, mix.time());
    }
    if let Some(c) = &terzaghi {
        c.write(dir, opts.csv)?;
        metrics.terzaghi_max_error_over_p0 = c.max_error();
        metrics.terzaghi_u_error = c
            .samples
            .iter()
            .filter(|s| s[1] >= TerzaghiCheck::T_FROM)
            .map(|s| (s[3] - s[4]).abs())
            .reduce(f64::max);
    }
    if let Some(layer) = darcy_layer(scene, &spec) {
        let n = scene
            .bodies
            .iter()
            .find(|b| b.phase == Some(Phase::Fluid))
            .map_or(1.0, |b| b.fraction);
        let b = spec.drag.coefficient_at(n);
        if let Some((error, linearity, q)) = darcy_figures(&mix.phase(1).view(), layer, b, n) {
            metrics.darcy_dp_rel_error = Some(error);
            metrics.darcy_linearity = linearity;
            metrics.darcy_flux = Some(q);
            // The column's weight balances the layer's drop: q = rho g H n^2 / (B L).
            let fluid = mix.phase(1).view();
            let rho = fluid.materials[fluid.material[0] as usize].rho0;
            let ideal = rho * scene.gravity * scene.size[1] * n * n / (b * (layer[1] - layer[0]));
            metrics.darcy_flux_rel_error = Some((q - ideal).abs() / ideal);
        }
    }
    metrics.drag_dissipated = Some(mix.drag_dissipated());
    // Periodic along gravity, the potential energy jumps as particles wrap.
    let budget_defined = !(scene.periodic[1] && scene.gravity > 0.0);
    metrics.mixture_energy_growth = budget_defined.then_some(energy_growth);
    metrics.momentum_drift_rel = (conserves_momentum && p_scale > 0.0).then_some(momentum_drift);
    Ok(Simulated {
        status,
        reason,
        steps: mix.phase(0).step_count(),
        t_end: mix.time(),
        particles: phases.iter().map(|p| p.particles).sum(),
        final_hash: mix.state_hash(),
        events,
        metrics,
        phases,
    })
}

fn fill_losses(m: &mut Metrics, s: &Solver, initial_mass: f64) {
    let losses = s.losses();
    m.particles_escaped = losses.escaped;
    m.particles_inverted = losses.inverted;
    m.mass_lost_fraction = losses.mass() / initial_mass;
    m.t_first_loss = losses.t_first;
    m.particles_drained = losses.drained;
    m.mass_drained_fraction = losses.mass_drained / initial_mass;
    m.particles_injected = losses.injected;
    m.mass_injected_fraction = losses.mass_injected / initial_mass;
}

/// `kick reproduce` of a mixture's event: the mixture and both monitors
/// restored from `checkpoint`, stepped through the event's last step (VTK
/// per phase every step from `opts.before` steps before its first step),
/// the state hash at its first step and the event its phase's monitor
/// detects again. Err: the checkpoint does not restore, or is not before the event.
pub(crate) fn replay(
    case: &Case,
    checkpoint: &[u8],
    logged: &Event,
    opts: &crate::reproduce::ReproduceOptions,
    out: &Path,
) -> std::io::Result<Result<crate::reproduce::Replay, String>> {
    let spec = case.mixture.clone().expect("a mixture case");
    let mut mix = match build(case, &spec) {
        Ok(m) => m,
        Err(e) => return Ok(Err(e)),
    };
    let mut watches = Phase::ALL.map(|phase| PhaseWatch {
        phase,
        monitor: Monitor::new(case.monitor.clone(), &mix.phase(phase.index()).view()),
        series: Timeseries::new(),
        peaks: Peaks::default(),
    });
    {
        let [a, b] = &mut watches;
        if let Err(e) =
            case_checkpoint::load_mixture(checkpoint, &mut mix, [&mut a.monitor, &mut b.monitor])
        {
            return Ok(Err(e.to_string()));
        }
    }
    let start = mix.phase(0).step_count();
    if start >= logged.first_step {
        return Ok(Err(format!(
            "taken at step {start}, not before the event (step {})",
            logged.first_step
        )));
    }
    let phase = match logged.phase.as_deref() {
        Some("solid") => Phase::Solid,
        _ => Phase::Fluid,
    };
    let vtk_from = logged.first_step.saturating_sub(opts.before).max(start);
    let end = logged.last_step + opts.after;
    let (mut hash_at_first, mut replayed) = (None, None);
    while !mix.phase(0).finished() && mix.phase(0).step_count() < end {
        if mix.step().is_err() {
            break;
        }
        let step = mix.phase(0).step_count();
        let mut hash = None;
        let mut stop = false;
        for w in watches.iter_mut() {
            stop |= w.observe(&mix, &mut hash).is_some();
        }
        if step >= vtk_from {
            write_vtk(&out.join("particles"), &mix)?;
        }
        if step == logged.first_step {
            hash_at_first = Some(format!("{:016x}", mix.state_hash()));
        }
        if step == logged.last_step {
            replayed = watches[phase.index()]
                .monitor
                .events()
                .iter()
                .find(|e| e.id == logged.id)
                .cloned();
        }
        if stop {
            break;
        }
    }
    Ok(Ok(crate::reproduce::Replay {
        start,
        hash_at_first,
        replayed,
    }))
}
