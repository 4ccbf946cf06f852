//! The decay of a body's initial flow mode (docs/physics.md section 7):
//! after every step, the particles' velocity projected on the flow's
//! shape, A = sum m v . s / sum m s . s (s at the particles' current
//! positions); the decay rate is a log-linear fit of A over the first
//! stretch where A / A0 falls from 0.9 to 0.05, or to t = 5 s, whichever
//! comes first, accumulated as the run goes (a damper's window can be
//! shorter than a timeseries row). A is sampled every step at first; the
//! stride doubles after every `SAMPLES_PER_STRIDE` samples, each weighted
//! by its stride, so the fit stays uniform in time and costs a few per
//! cent of a step. The table mode_decay.parquet has A at the rows. For Taylor-Green the fluid's own rate is
//! 2 nu k^2 and for the shear wave nu k^2; `nu_equivalent` is the fitted
//! rate over that factor, the viscosity the method acts as if it had.

use crate::output::summary::Check;
use crate::output::tables;
use crate::run::{Probe, Run, Simulated};
use serde::{Deserialize, Serialize};
use solver::flows::Flow;
use solver::{Scene, Solver};
use std::path::PathBuf;

/// The fit starts once A / A0 is at most this ...
pub const FIT_FROM: f64 = 0.9;
/// ... and ends before A / A0 falls below this, or at `FIT_UNTIL_S`.
pub const FIT_TO: f64 = 0.05;
pub const FIT_UNTIL_S: f64 = 5.0;
/// With `output.end_when_checked`, the run goes on after the fit's window
/// closes for as long again as it took to close (this factor), and at least
/// `FOLLOW_MIN_S`, to see whether the mode comes back (`later_max_ratio`).
pub const FOLLOW_FACTOR: f64 = 1.0;
pub const FOLLOW_MIN_S: f64 = 0.25;
/// Samples taken at one stride before it doubles.
pub const SAMPLES_PER_STRIDE: usize = 1000;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ModeDecayFigures {
    /// The flow's wavenumber k (1/m).
    pub k: f64,
    /// The projection at t = 0 (m/s).
    pub a0: f64,
    /// The fitted amplitude decay rate (1/s); None with fewer than 3 steps
    /// in the window.
    pub rate: Option<f64>,
    /// rate / (2 k^2) for Taylor-Green, rate / k^2 for the shear wave (m^2/s).
    pub nu_equivalent: Option<f64>,
    /// The fit's window (s) and the steps in it.
    pub fit_from_s: Option<f64>,
    pub fit_to_s: Option<f64>,
    pub fit_steps: usize,
    /// A / A0 after the last step.
    pub ratio_end: f64,
    /// The largest |A| / A0 after the fit's window: near 1 when the mode
    /// does not decay but trades its energy back and forth (with the
    /// stored energy, on the linear FLIP baseline), and the rate is then
    /// not a decay rate.
    pub later_max_ratio: f64,
}

impl Check for ModeDecayFigures {
    const NAME: &'static str = "mode_decay";
}

pub struct ModeDecay {
    flow: Flow,
    rect: [f64; 4],
    gravity: f64,
    decay: DecayFit,
    /// Steps per sample, and the steps and samples counted at this stride.
    stride: usize,
    steps_since: usize,
    taken: usize,
    /// (t, A) at each timeseries row.
    rows: Vec<(f64, f64)>,
    dir: PathBuf,
    csv: bool,
}

/// Where a sample stands against the fit's window.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
enum Window {
    #[default]
    Before,
    Inside,
    After,
}

/// The weighted log-linear fit of A / A0 over its window, one sample at a
/// time (running means and co-moments: no storage, no cancellation).
#[derive(Clone, Debug, Default)]
struct DecayFit {
    a0: Option<f64>,
    window: Window,
    /// Samples and the sum of their weights in the window.
    n: usize,
    weight: f64,
    mean_t: f64,
    mean_y: f64,
    c_tt: f64,
    c_ty: f64,
    from: Option<f64>,
    to: Option<f64>,
    /// When the window closed, and the last sample's time.
    closed_at: Option<f64>,
    last_t: f64,
    last_ratio: f64,
    later_max_ratio: f64,
}

impl DecayFit {
    fn observe(&mut self, t: f64, a: f64, weight: f64) {
        let a0 = *self.a0.get_or_insert(a);
        let ratio = a / a0;
        self.last_ratio = ratio;
        self.last_t = t;
        if self.window == Window::Before && ratio <= FIT_FROM {
            self.window = Window::Inside;
        }
        if self.window == Window::Inside && !(ratio >= FIT_TO && t <= FIT_UNTIL_S) {
            self.window = Window::After;
            self.closed_at = Some(t);
        }
        match self.window {
            Window::Before => {}
            Window::Inside => self.add(t, ratio.ln(), weight),
            Window::After => self.later_max_ratio = self.later_max_ratio.max(ratio.abs()),
        }
    }

    fn add(&mut self, t: f64, y: f64, weight: f64) {
        self.n += 1;
        self.weight += weight;
        let share = weight / self.weight;
        let (dt, dy) = (t - self.mean_t, y - self.mean_y);
        self.mean_t += share * dt;
        self.mean_y += share * dy;
        self.c_tt += weight * dt * (t - self.mean_t);
        self.c_ty += weight * dt * (y - self.mean_y);
        self.from.get_or_insert(t);
        self.to = Some(t);
    }

    /// The window has closed and been followed long enough: when it closed.
    fn followed(&self) -> Option<f64> {
        let closed = self.closed_at?;
        let follow = (FOLLOW_FACTOR * closed).max(FOLLOW_MIN_S);
        (self.last_t >= closed + follow).then_some(closed)
    }

    /// The fitted decay rate; None with fewer than 3 samples in the window.
    fn rate(&self) -> Option<f64> {
        (self.n >= 3 && self.c_tt > 0.0).then(|| -self.c_ty / self.c_tt)
    }
}

impl ModeDecay {
    /// For a scene with one body whose flow is a Taylor-Green vortex or a
    /// shear wave (the standing wave is the slosh check's).
    pub fn new(scene: &Scene, dir: PathBuf, csv: bool) -> Option<Self> {
        let [body] = scene.bodies.as_slice() else {
            return None;
        };
        let flow = body.flow?;
        matches!(flow, Flow::TaylorGreen { .. } | Flow::ShearWave { .. }).then(|| ModeDecay {
            flow,
            rect: body.rect,
            gravity: scene.gravity,
            decay: DecayFit::default(),
            stride: 1,
            steps_since: 0,
            taken: 0,
            rows: vec![],
            dir,
            csv,
        })
    }

    fn amplitude(&self, s: &Solver) -> f64 {
        projected(s, &self.flow, self.rect, self.gravity)
    }

    fn observe(&mut self, s: &Solver) {
        let a = self.amplitude(s);
        self.decay.observe(s.time(), a, self.stride as f64);
        self.taken += 1;
        if self.taken == SAMPLES_PER_STRIDE {
            self.stride *= 2;
            self.taken = 0;
        }
    }
}

/// The particles' velocity projected on `flow`'s shape over its body
/// `rect`: sum m v . s / sum m s . s (0 when the shape vanishes).
pub(crate) fn projected(s: &Solver, flow: &Flow, rect: [f64; 4], gravity: f64) -> f64 {
    let v = s.view();
    let (mut num, mut den) = (0.0, 0.0);
    for ((x, u), m) in v.x.iter().zip(v.v).zip(v.mass) {
        let shape = flow.shape(*x, rect, gravity);
        num += m * u.dot(&shape);
        den += m * shape.norm_squared();
    }
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

impl Probe<Solver> for ModeDecay {
    fn begin(&mut self, run: &Run<Solver>) -> std::io::Result<()> {
        self.observe(run.stepper);
        Ok(())
    }

    fn after_step(&mut self, run: &Run<Solver>, _: &[u32]) -> std::io::Result<()> {
        self.steps_since += 1;
        if self.steps_since == self.stride {
            self.steps_since = 0;
            self.observe(run.stepper);
        }
        Ok(())
    }

    fn ends_run(&self) -> Option<String> {
        let closed = self.decay.followed()?;
        Some(format!(
            "mode decay fitted: its window closed at t = {closed:.4} s and was followed to {:.4} s",
            self.decay.last_t
        ))
    }

    fn row(&mut self, run: &Run<Solver>) {
        let a = self.amplitude(run.stepper);
        self.rows.push((run.stepper.time(), a));
    }

    fn finish(&mut self, _: &Run<Solver>, outcome: &mut Simulated) -> std::io::Result<()> {
        let t: Vec<f64> = self.rows.iter().map(|s| s.0).collect();
        let a: Vec<f64> = self.rows.iter().map(|s| s.1).collect();
        tables::write_columns(
            &[("t", &t), ("amplitude", &a)],
            &self.dir,
            "mode_decay",
            self.csv,
        )?;
        let k = self.flow.wavenumber(self.rect);
        let factor = match self.flow {
            Flow::TaylorGreen { .. } => 2.0 * k * k,
            _ => k * k,
        };
        let fit = &self.decay;
        let rate = fit.rate();
        outcome.metrics.set_check(&ModeDecayFigures {
            k,
            a0: fit.a0.unwrap_or(0.0),
            rate,
            nu_equivalent: rate.map(|r| r / factor),
            fit_from_s: fit.from,
            fit_to_s: fit.to,
            fit_steps: fit.n,
            ratio_end: fit.last_ratio,
            later_max_ratio: fit.later_max_ratio,
        });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fit_of(samples: impl Iterator<Item = (f64, f64)>) -> DecayFit {
        let mut fit = DecayFit::default();
        for (t, a) in samples {
            fit.observe(t, a, 1.0);
        }
        fit
    }

    /// A sampled exp(-r t) gives r back; the window starts at A / A0 <= 0.9
    /// and stops below 0.05.
    #[test]
    fn the_fit_recovers_an_exponential_rate_in_its_window() {
        let times = || (0..=400).map(|i| 0.01 * i as f64);
        let fit = fit_of(times().map(|t| (t, 2.0 * (-1.5 * t).exp())));
        assert!((fit.rate().unwrap() - 1.5).abs() < 1e-12, "{fit:?}");
        // exp(-1.5 t) = 0.9 at t = 0.0702, = 0.05 at t = 1.997.
        assert_eq!(fit.from, Some(0.08));
        assert_eq!(fit.to, Some(1.99));
        assert_eq!(fit.n, 192);
        assert!(fit.later_max_ratio < 0.05);
        // Closed at 2.0 s and followed for as long again, to 4.0 s.
        assert_eq!(fit.closed_at, Some(2.0));
        assert_eq!(fit.followed(), Some(2.0));
        let fit = fit_of(
            (0..=390)
                .map(|i| 0.01 * i as f64)
                .map(|t| (t, (-1.5 * t).exp())),
        );
        assert_eq!(fit.followed(), None);
        // A mode that swings back: the same fit, but it comes back to 1.
        let fit = fit_of(times().map(|t| (t, 2.0 * (10.0 * t).cos())));
        assert!(fit.later_max_ratio > 0.99, "{fit:?}");
        // A damper whose window is shorter than a row: every step counts.
        let fit = fit_of(
            (0..=1000)
                .map(|i| 1e-5 * i as f64)
                .map(|t| (t, (-250.0 * t).exp())),
        );
        assert!((fit.rate().unwrap() / 250.0 - 1.0).abs() < 1e-9, "{fit:?}");
        assert!(fit.n > 1000 / 2 && fit.to.unwrap() < 0.012, "{fit:?}");
    }

    /// Samples at a doubling stride, each weighted by its stride, fit as
    /// the same samples taken uniformly would (a line is recovered exactly,
    /// and a curve's weighted fit matches the uniform one closely).
    #[test]
    fn strided_weighted_samples_fit_like_uniform_ones() {
        let curve = |t: f64| (-0.8 * t - 0.3 * t * t).exp();
        let uniform = fit_of((0..=8000).map(|i| 5e-4 * i as f64).map(|t| (t, curve(t))));
        let mut strided = DecayFit::default();
        let (mut step, mut stride) = (0, 1);
        while step <= 8000 {
            for _ in 0..10 {
                let t = 5e-4 * step as f64;
                strided.observe(t, curve(t), stride as f64);
                step += stride;
            }
            stride *= 2;
        }
        let (u, s) = (uniform.rate().unwrap(), strided.rate().unwrap());
        assert!((s / u - 1.0).abs() < 0.02, "uniform {u}, strided {s}");
        let line = |t: f64| (-0.8 * t).exp();
        let mut strided = DecayFit::default();
        for (i, t) in [0.0, 0.1, 0.2, 0.4, 0.8, 1.6].into_iter().enumerate() {
            strided.observe(t, line(t), (1 << i) as f64);
        }
        assert!((strided.rate().unwrap() - 0.8).abs() < 1e-12, "{strided:?}");
    }
}
