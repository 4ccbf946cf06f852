//! The sloshing tank (docs/physics.md section 7): a body that fills its
//! tank's width starts with a standing wave of odd mode m. At every
//! timeseries row the water's horizontal centre of mass X; at the end the
//! period from the zero crossings of X - X(0) and the amplitude decay rate
//! from a log-linear fit of the swing's extremes, against linear theory:
//! T = 2 pi / sqrt(g k tanh(k d)) and 2 nu k^2. The centre of mass is
//! robust at an amplitude below the particle spacing, where a surface
//! tracker is not. Even modes do not move the centre of mass; they get no
//! check.

use crate::output::metrics::line_fit;
use crate::output::summary::Check;
use crate::output::tables;
use crate::run::{Probe, Run, Simulated};
use serde::{Deserialize, Serialize};
use solver::flows::Flow;
use solver::{Scene, Solver};
use std::f64::consts::PI;
use std::path::PathBuf;

/// The swing is followed while its extremes are at least this share of the
/// first one; below it a damped wave's X is round-off and particle noise.
pub const PEAK_FLOOR: f64 = 0.02;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SloshFigures {
    /// The wave's wavenumber k (1/m) and linear theory's period (s).
    pub k: f64,
    pub period_theory_s: f64,
    /// The measured period (s): twice the slope of the zero-crossing times
    /// against their count. None with fewer than 3 crossings.
    pub period_s: Option<f64>,
    /// period_s / period_theory_s - 1.
    pub period_error: Option<f64>,
    /// Linear theory's amplitude decay rate 2 nu k^2 (1/s; 0 inviscid).
    pub decay_theory: f64,
    /// The fitted decay rate of |X - X(0)| at its extremes (1/s). None with
    /// fewer than 3 extremes.
    pub decay_rate: Option<f64>,
    /// decay_rate / decay_theory (None inviscid).
    pub decay_ratio: Option<f64>,
    /// Linear theory's swing of X (m), 2 a W / (m pi)^2 / d, and the first
    /// measured extreme's (the largest |X - X(0)| if the swing never
    /// crossed back).
    pub swing_theory_m: f64,
    pub swing_m: f64,
    /// Extremes and crossings used, and the time of the last one used (s).
    pub extremes: usize,
    pub crossings: usize,
    pub followed_to_s: f64,
}

impl Check for SloshFigures {
    const NAME: &'static str = "slosh";
}

pub struct Slosh {
    flow: Flow,
    rect: [f64; 4],
    gravity: f64,
    nu: f64,
    /// (t, X) at each row.
    samples: Vec<(f64, f64)>,
    dir: PathBuf,
    csv: bool,
}

impl Slosh {
    /// For a scene with one body whose flow is a standing wave of odd mode.
    pub fn new(scene: &Scene, dir: PathBuf, csv: bool) -> Option<Self> {
        let [body] = scene.bodies.as_slice() else {
            return None;
        };
        let flow = body.flow?;
        let Flow::StandingWave { mode, .. } = flow else {
            return None;
        };
        let material = &scene.materials[scene.material_index(body)?];
        (mode % 2 == 1).then(|| Slosh {
            flow,
            rect: body.rect,
            gravity: scene.gravity,
            nu: material.viscosity / material.rho0,
            samples: vec![],
            dir,
            csv,
        })
    }

    fn centre_x(s: &Solver) -> f64 {
        let v = s.view();
        let (mut mx, mut m) = (0.0, 0.0);
        for (x, mass) in v.x.iter().zip(v.mass) {
            mx += mass * x.x;
            m += mass;
        }
        if m > 0.0 {
            mx / m
        } else {
            0.0
        }
    }

    /// The largest |X - X(0)|: the swing of a wave damped before it
    /// crossed back once (no half swing closed).
    fn largest_swing(&self) -> f64 {
        let x0 = self.samples.first().map_or(0.0, |s| s.1);
        self.samples
            .iter()
            .fold(0.0, |m: f64, s| m.max((s.1 - x0).abs()))
    }

    fn figures(&self) -> SloshFigures {
        let k = self.flow.wavenumber(self.rect);
        let (w, d) = (self.rect[2] - self.rect[0], self.rect[3] - self.rect[1]);
        let (amplitude, mode) = match self.flow {
            Flow::StandingWave { amplitude, mode } => (amplitude, mode as f64),
            _ => (0.0, 1.0),
        };
        let period_theory_s = 2.0 * PI / self.flow.omega(self.rect, self.gravity);
        let decay_theory = 2.0 * self.nu * k * k;
        let swing = Swing::of(&self.samples);
        let period_s = swing.period();
        let decay_rate = swing.decay_rate();
        SloshFigures {
            k,
            period_theory_s,
            period_s,
            period_error: period_s.map(|t| t / period_theory_s - 1.0),
            decay_theory,
            decay_rate,
            decay_ratio: decay_rate
                .filter(|_| decay_theory > 0.0)
                .map(|r| r / decay_theory),
            swing_theory_m: 2.0 * amplitude * w / (mode * PI).powi(2) / d,
            swing_m: swing
                .extremes
                .first()
                .map_or_else(|| self.largest_swing(), |e| e.1),
            extremes: swing.extremes.len(),
            crossings: swing.crossings.len(),
            followed_to_s: swing.followed_to,
        }
    }
}

/// The zero crossings and the extremes of an oscillating signal (X - X(0)
/// of the slosh, the sound wave's mode), followed while the extremes stay
/// above `PEAK_FLOOR` of the first.
#[derive(Debug, Default)]
pub(crate) struct Swing {
    pub(crate) crossings: Vec<f64>,
    /// (t, |d|) at each extreme, refined by a parabola through the
    /// largest sample and its neighbours.
    pub(crate) extremes: Vec<(f64, f64)>,
    pub(crate) followed_to: f64,
}

impl Swing {
    /// The swing of X - X(0), which starts at 0.
    fn of(samples: &[(f64, f64)]) -> Self {
        let Some(&(_, x0)) = samples.first() else {
            return Swing::default();
        };
        let d: Vec<f64> = samples.iter().map(|s| s.1 - x0).collect();
        let t: Vec<f64> = samples.iter().map(|s| s.0).collect();
        Swing::of_signal(&t, &d, 1)
    }

    /// The swing of `d` at times `t`, its first half swing from row `first`
    /// (1 for a signal that starts at 0, 0 for one that starts at an extreme).
    pub(crate) fn of_signal(t: &[f64], d: &[f64], first: usize) -> Self {
        let mut swing = Swing::default();
        // Half swings: the stretches between sign changes.
        let mut start = first;
        for i in first..d.len() {
            // A row exactly at zero counts as positive, so no crossing is missed.
            let closes = i + 1 == d.len() || (d[i] >= 0.0) != (d[i + 1] >= 0.0);
            if !closes || i < start {
                continue;
            }
            let Some(extreme) = refined_extreme(t, d, start, i) else {
                break;
            };
            let first = swing.extremes.first().map_or(extreme.1, |e| e.1);
            if extreme.1 < PEAK_FLOOR * first || i + 1 == d.len() {
                break;
            }
            swing.extremes.push(extreme);
            // Linear interpolation of the crossing between rows i and i + 1.
            let crossing = t[i] + (t[i + 1] - t[i]) * d[i] / (d[i] - d[i + 1]);
            swing.crossings.push(crossing);
            swing.followed_to = crossing;
            start = i + 1;
        }
        swing
    }

    /// Twice the slope of the crossing times against their count.
    pub(crate) fn period(&self) -> Option<f64> {
        if self.crossings.len() < 3 {
            return None;
        }
        let pts: Vec<(f64, f64)> = self
            .crossings
            .iter()
            .enumerate()
            .map(|(n, &t)| (n as f64, t))
            .collect();
        line_fit(&pts).map(|(slope, _)| 2.0 * slope)
    }

    pub(crate) fn decay_rate(&self) -> Option<f64> {
        if self.extremes.len() < 3 {
            return None;
        }
        let pts: Vec<(f64, f64)> = self.extremes.iter().map(|&(t, a)| (t, a.ln())).collect();
        line_fit(&pts).map(|(slope, _)| -slope)
    }
}

/// The largest |d| in rows a..=b, refined by the parabola through it and
/// its neighbours: (t, |d|). None for an empty or all-zero stretch.
fn refined_extreme(t: &[f64], d: &[f64], a: usize, b: usize) -> Option<(f64, f64)> {
    let i = (a..=b).max_by(|&i, &j| d[i].abs().total_cmp(&d[j].abs()))?;
    if d[i] == 0.0 {
        return None;
    }
    if i == 0 || i + 1 >= d.len() {
        return Some((t[i], d[i].abs()));
    }
    let (y0, y1, y2) = (d[i - 1].abs(), d[i].abs(), d[i + 1].abs());
    let curvature = y0 - 2.0 * y1 + y2;
    let h = 0.5 * (t[i + 1] - t[i - 1]);
    if curvature >= 0.0 {
        return Some((t[i], y1));
    }
    let s = 0.5 * (y0 - y2) / curvature;
    Some((t[i] + s * h, y1 - 0.25 * (y0 - y2) * s))
}

impl Probe<Solver> for Slosh {
    fn row(&mut self, run: &Run<Solver>) {
        let x = Self::centre_x(run.stepper);
        self.samples.push((run.stepper.time(), x));
    }

    fn finish(&mut self, _: &Run<Solver>, outcome: &mut Simulated) -> std::io::Result<()> {
        let t: Vec<f64> = self.samples.iter().map(|s| s.0).collect();
        let x: Vec<f64> = self.samples.iter().map(|s| s.1).collect();
        tables::write_columns(&[("t", &t), ("x_centre", &x)], &self.dir, "slosh", self.csv)?;
        outcome.metrics.set_check(&self.figures());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn samples(f: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
        (0..=1000)
            .map(|i| 0.005 * i as f64)
            .map(|t| (t, 0.2 + f(t)))
            .collect()
    }

    /// A damped sine sampled at the rows' spacing gives its period and
    /// decay rate back.
    #[test]
    fn the_swing_recovers_period_and_decay_of_a_damped_sine() {
        let (period, rate) = (0.7475, 0.0617);
        let omega = 2.0 * PI / period;
        let s = Swing::of(&samples(|t| -2e-3 * (omega * t).sin() * (-rate * t).exp()));
        assert_eq!(s.crossings.len(), 13, "{s:?}");
        let measured = s.period().unwrap();
        assert!((measured / period - 1.0).abs() < 1e-4, "{measured}");
        let r = s.decay_rate().unwrap();
        assert!((r / rate - 1.0).abs() < 0.01, "{r}");
        // Its first extreme at a quarter period, of amplitude 2e-3 e^{-r T/4}.
        let (t1, a1) = s.extremes[0];
        assert!((t1 - period / 4.0).abs() < 1e-3, "{t1}");
        assert!(
            (a1 / (2e-3 * (-rate * period / 4.0).exp()) - 1.0).abs() < 1e-4,
            "{a1}"
        );
    }

    /// A swing that dies within two periods is followed only while its
    /// extremes exceed PEAK_FLOOR of the first, and a still tank has none.
    #[test]
    fn a_dying_swing_is_followed_only_above_the_floor() {
        let omega = 2.0 * PI / 0.75;
        let s = Swing::of(&samples(|t| 1e-3 * (omega * t).sin() * (-4.0 * t).exp()));
        let last = s.extremes.last().unwrap().1;
        assert!(last >= PEAK_FLOOR * s.extremes[0].1, "{s:?}");
        assert!(s.followed_to < 1.5, "{s:?}");
        let r = s.decay_rate().unwrap();
        assert!((r / 4.0 - 1.0).abs() < 0.02, "{r}");
        let still = Swing::of(&samples(|_| 0.0));
        assert!(still.extremes.is_empty() && still.period().is_none());
        // Over-damped: X goes out and creeps back without crossing; the
        // swing it reached is still reported.
        let mut p = tank();
        p.samples = samples(|t| 1e-3 * 20.0 * t * (-20.0 * t).exp() * std::f64::consts::E);
        let f = p.figures();
        assert_eq!((f.crossings, f.period_s), (0, None));
        assert!((f.swing_m - 1e-3).abs() < 1e-6, "{f:?}");
    }

    fn tank() -> Slosh {
        Slosh {
            flow: Flow::StandingWave {
                amplitude: 0.005,
                mode: 1,
            },
            rect: [0.0, 0.0, 0.4, 0.2],
            gravity: 9.81,
            nu: 5e-4,
            samples: vec![],
            dir: PathBuf::new(),
            csv: false,
        }
    }

    /// Linear theory's figures for the issue's tank: T = 0.747 s and
    /// 2 nu k^2 = 0.0617 /s at 0.5 Pa s.
    #[test]
    fn the_tank_of_the_slosh_study_has_the_issues_theory() {
        let f = tank().figures();
        assert!((f.period_theory_s - 0.7475).abs() < 5e-4, "{f:?}");
        assert!((f.decay_theory - 0.0617).abs() < 5e-4, "{f:?}");
        assert!((f.swing_theory_m - 2.026e-3).abs() < 1e-6, "{f:?}");
        assert_eq!(f.period_s, None);
    }
}
