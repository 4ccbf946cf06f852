//! Brackbill's ringing test (docs/physics.md section 7b): a uniform flow
//! through a periodic grid with a seed near the grid scale. Measured here:
//! the kinetic energy of the particles' velocity about their mean,
//! E' = sum 1/2 m |v - V|^2 with V = sum m v / sum m (the momentum is
//! conserved on a periodic box, so V is the drift), after every step; and
//! its growth rate, the least-squares slope of ln E' over the second half
//! of the linear window. The window ends at the first step where E' is
//! past `SATURATED` of the drift's energy (the perturbation is no longer
//! small), before `FLOOR_STEPS` steps in a row below `FLOOR` of its
//! starting value (round-off would come next; a run of steps, so that the
//! dips of a decay that rings with the particles' passage through the
//! cells do not end it by a hair), or at the first that is not finite;
//! else at the last step. Its second half drops the
//! transient of the seed's projection on the method's own modes, so the
//! rate is the dominant mode's and does not depend on the seed's amplitude
//! (in the linear window E' scales with its square).

use serde::{Deserialize, Serialize};
use solver::StateView;

/// E' over 1/2 M |V|^2 past which the perturbation is not small (its
/// speed about 3 % of the drift's).
pub const SATURATED: f64 = 1e-3;
/// E' / E'(0) below which the window ends: 12 decades below the start
/// and, with a seed of 1e-4 U, still 10 decades above round-off.
pub const FLOOR: f64 = 1e-12;
/// Steps in a row below `FLOOR` that end the window.
pub const FLOOR_STEPS: usize = 100;

/// Why the fit's window ended.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WindowEnd {
    /// The run ended first (its last step).
    #[default]
    LastStep,
    /// E' reached `SATURATED` of the drift's energy.
    Saturated,
    /// E' stayed below `FLOOR` of its start for `FLOOR_STEPS` steps.
    Floor,
    /// E' was not finite (the run blew up).
    NotFinite,
}

/// The growth figures of one run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GrowthFigures {
    /// E' at t = 0 and the drift's energy 1/2 M |V|^2 (J/m).
    pub e0: f64,
    pub drift_energy: f64,
    /// Growth rate of E' per step and per second (negative: decay); None
    /// with fewer than 3 steps in the window.
    pub rate_per_step: Option<f64>,
    pub rate_per_second: Option<f64>,
    /// The fit's steps [from, to] and why the window ended.
    pub fit_from_step: u64,
    pub fit_to_step: u64,
    pub window_end: WindowEnd,
    /// E' / E'(0) at the window's end.
    pub ratio_end: f64,
}

/// E' of a view, and the drift's energy 1/2 M |V|^2.
pub fn perturbation_energy(v: &StateView) -> (f64, f64) {
    let (mut m, mut p) = (0.0, solver::Vec2::zeros());
    for (mass, u) in v.mass.iter().zip(v.v) {
        m += mass;
        p += *mass * u;
    }
    if m <= 0.0 {
        return (0.0, 0.0);
    }
    let drift = p / m;
    let e: f64 = v
        .mass
        .iter()
        .zip(v.v)
        .map(|(mass, u)| 0.5 * mass * (u - drift).norm_squared())
        .sum();
    (e, 0.5 * m * drift.norm_squared())
}

/// The record of E' step by step, and the fit over its window.
#[derive(Clone, Debug, Default)]
pub struct PerturbationGrowth {
    /// (step, t, ln E') of every step inside the window.
    samples: Vec<(u64, f64, f64)>,
    /// Where the current run of samples below the floor began.
    below_since: Option<usize>,
    e0: Option<f64>,
    drift_energy: f64,
    end: Option<(WindowEnd, f64)>,
}

impl PerturbationGrowth {
    /// Room for `steps` samples, so that observing does not allocate.
    pub fn with_capacity(steps: usize) -> Self {
        PerturbationGrowth {
            samples: Vec::with_capacity(steps + 1),
            ..Self::default()
        }
    }

    /// Records the state after a step (and at t = 0).
    pub fn observe(&mut self, v: &StateView) {
        let (e, drift) = perturbation_energy(v);
        self.observe_energy(v.step, v.time, e, drift);
    }

    /// Records E' at a step; the window closes on the first step outside
    /// the linear range.
    pub fn observe_energy(&mut self, step: u64, t: f64, e: f64, drift_energy: f64) {
        if self.end.is_some() {
            return;
        }
        let e0 = *self.e0.get_or_insert(e);
        if self.samples.is_empty() {
            self.drift_energy = drift_energy;
        }
        let ratio = e / e0;
        let end = if !e.is_finite() {
            Some(WindowEnd::NotFinite)
        } else if e > SATURATED * self.drift_energy {
            Some(WindowEnd::Saturated)
        } else {
            None
        };
        if let Some(end) = end {
            self.end = Some((end, t));
            return;
        }
        if ratio >= FLOOR {
            self.below_since = None;
        } else if self.below_since.is_none() {
            self.below_since = Some(self.samples.len());
        }
        self.samples.push((step, t, e.ln()));
        if let Some(first) = self.below_since {
            if self.samples.len() - first >= FLOOR_STEPS {
                self.samples.truncate(first);
                self.end = Some((WindowEnd::Floor, t));
            }
        }
    }

    /// The window has closed (the run can end).
    pub fn closed(&self) -> bool {
        self.end.is_some()
    }

    /// The figures over the window so far.
    pub fn figures(&self) -> GrowthFigures {
        let window = &self.samples[self.samples.len() / 2..];
        let slope = |x: &dyn Fn(&(u64, f64, f64)) -> f64| {
            if window.len() < 3 {
                return None;
            }
            let n = window.len() as f64;
            let mx = window.iter().map(x).sum::<f64>() / n;
            let my = window.iter().map(|s| s.2).sum::<f64>() / n;
            let (mut sxx, mut sxy) = (0.0, 0.0);
            for s in window {
                let dx = x(s) - mx;
                sxx += dx * dx;
                sxy += dx * (s.2 - my);
            }
            (sxx > 0.0).then(|| sxy / sxx)
        };
        GrowthFigures {
            e0: self.e0.unwrap_or(0.0),
            drift_energy: self.drift_energy,
            rate_per_step: slope(&|s| s.0 as f64),
            rate_per_second: slope(&|s| s.1),
            fit_from_step: window.first().map_or(0, |s| s.0),
            fit_to_step: window.last().map_or(0, |s| s.0),
            window_end: self.end.map_or(WindowEnd::LastStep, |e| e.0),
            ratio_end: self
                .samples
                .last()
                .map_or(0.0, |s| s.2.exp() / self.e0.unwrap_or(1.0)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fed(e: impl Fn(u64) -> f64, steps: u64) -> PerturbationGrowth {
        let mut g = PerturbationGrowth::with_capacity(steps as usize);
        for n in 0..=steps {
            g.observe_energy(n, 1e-3 * n as f64, e(n), 1.0);
        }
        g
    }

    /// An exponential after a transient gives its rate back, per step and
    /// per second, over the second half of the window.
    #[test]
    fn the_fit_takes_the_dominant_rate_after_the_transient() {
        let e = |n: u64| 1e-9 * ((0.01 * n as f64).exp() + 50.0 * (-0.2 * n as f64).exp());
        let f = fed(e, 400).figures();
        assert!((f.rate_per_step.unwrap() - 0.01).abs() < 1e-9, "{f:?}");
        assert!((f.rate_per_second.unwrap() - 10.0).abs() < 1e-6, "{f:?}");
        assert_eq!((f.fit_from_step, f.fit_to_step), (200, 400));
        assert_eq!(f.window_end, WindowEnd::LastStep);
    }

    /// Growth closes the window at saturation, decay at the floor, and a
    /// blow-up at the first non-finite energy.
    #[test]
    fn the_window_closes_outside_the_linear_range() {
        let grow = fed(|n| 1e-9 * (0.05 * n as f64).exp(), 1000);
        assert!(grow.closed());
        let f = grow.figures();
        assert_eq!(f.window_end, WindowEnd::Saturated);
        // 1e-9 e^(0.05 n) > 1e-3 from n = 277.
        assert_eq!(f.fit_to_step, 276);
        assert!((f.rate_per_step.unwrap() - 0.05).abs() < 1e-9);
        let decay = fed(|n| 1e-9 * (-0.1 * n as f64).exp(), 1000).figures();
        assert_eq!(decay.window_end, WindowEnd::Floor);
        // e^(-0.1 n) < 1e-12 from n = 277.
        assert_eq!(decay.fit_to_step, 276);
        // Dips below the floor shorter than FLOOR_STEPS do not end it.
        let dips = |n: u64| 1e-9 * if n % 150 < 99 { 1e-13 } else { 1.0 };
        assert_eq!(fed(dips, 1000).figures().window_end, WindowEnd::LastStep);
        assert!((decay.rate_per_step.unwrap() + 0.1).abs() < 1e-9);
        let blown = fed(|n| if n < 40 { 1e-9 } else { f64::NAN }, 100).figures();
        assert_eq!(blown.window_end, WindowEnd::NotFinite);
        assert_eq!(blown.fit_to_step, 39);
    }
}
