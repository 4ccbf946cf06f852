//! The decay of a body's initial flow mode (docs/physics.md section 7):
//! at every timeseries row, the particles' velocity projected on the
//! flow's shape, A = sum m v . s / sum m s . s (s at the particles' current
//! positions); at the end, the decay rate from a log-linear fit of A over
//! the first stretch where A / A0 falls from 0.9 to 0.05, or to t = 5 s,
//! whichever comes first. For Taylor-Green the fluid's own rate is
//! 2 nu k^2 and for the shear wave nu k^2; `nu_equivalent` is the fitted
//! rate over that factor, the viscosity the method acts as if it had.

use crate::metrics::line_fit;
use crate::runner::{Probe, Run, Simulated};
use crate::summary::Check;
use crate::tables;
use serde::{Deserialize, Serialize};
use solver::flows::Flow;
use solver::{Scene, Solver};
use std::path::PathBuf;

/// The fit starts once A / A0 is at most this ...
pub const FIT_FROM: f64 = 0.9;
/// ... and ends before A / A0 falls below this, or at `FIT_UNTIL_S`.
pub const FIT_TO: f64 = 0.05;
pub const FIT_UNTIL_S: f64 = 5.0;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ModeDecayFigures {
    /// The flow's wavenumber k (1/m).
    pub k: f64,
    /// The projection at t = 0 (m/s).
    pub a0: f64,
    /// The fitted amplitude decay rate (1/s); None with fewer than 3 rows
    /// in the window.
    pub rate: Option<f64>,
    /// rate / (2 k^2) for Taylor-Green, rate / k^2 for the shear wave (m^2/s).
    pub nu_equivalent: Option<f64>,
    /// The fit's window (s) and rows.
    pub fit_from_s: Option<f64>,
    pub fit_to_s: Option<f64>,
    pub fit_rows: usize,
    /// A / A0 at the last row.
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
    /// (t, A) at each row.
    samples: Vec<(f64, f64)>,
    dir: PathBuf,
    csv: bool,
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
            samples: vec![],
            dir,
            csv,
        })
    }

    /// The velocity projected on the flow's shape.
    fn amplitude(&self, s: &Solver) -> f64 {
        let v = s.view();
        let (mut num, mut den) = (0.0, 0.0);
        for ((x, u), m) in v.x.iter().zip(v.v).zip(v.mass) {
            let shape = self.flow.shape(*x, self.rect, self.gravity);
            num += m * u.dot(&shape);
            den += m * shape.norm_squared();
        }
        if den > 0.0 {
            num / den
        } else {
            0.0
        }
    }

    /// The largest |A| / A0 after time `after`.
    fn later_max_ratio(&self, after: f64) -> f64 {
        let a0 = self.samples.first().map_or(0.0, |s| s.1);
        self.samples
            .iter()
            .filter(|(t, _)| *t > after)
            .fold(0.0, |m: f64, (_, a)| m.max((a / a0).abs()))
    }

    /// The log-linear fit over the window; (rate, from, to, rows).
    fn fit(&self) -> (Option<f64>, Option<f64>, Option<f64>, usize) {
        let Some(&(_, a0)) = self.samples.first() else {
            return (None, None, None, 0);
        };
        let window: Vec<(f64, f64)> = self
            .samples
            .iter()
            .skip_while(|(_, a)| a / a0 > FIT_FROM)
            .take_while(|(t, a)| a / a0 >= FIT_TO && *t <= FIT_UNTIL_S)
            .map(|&(t, a)| (t, (a / a0).ln()))
            .collect();
        let rate = (window.len() >= 3)
            .then(|| line_fit(&window).map(|(slope, _)| -slope))
            .flatten();
        (
            rate,
            window.first().map(|w| w.0),
            window.last().map(|w| w.0),
            window.len(),
        )
    }
}

impl Probe<Solver> for ModeDecay {
    fn row(&mut self, run: &Run<Solver>) {
        let a = self.amplitude(run.stepper);
        self.samples.push((run.stepper.time(), a));
    }

    fn finish(&mut self, _: &Run<Solver>, outcome: &mut Simulated) -> std::io::Result<()> {
        let t: Vec<f64> = self.samples.iter().map(|s| s.0).collect();
        let a: Vec<f64> = self.samples.iter().map(|s| s.1).collect();
        tables::write_columns(
            &[("t", &t), ("amplitude", &a)],
            &self.dir,
            "mode_decay",
            self.csv,
        )?;
        let k = self.flow.wavenumber(self.rect);
        let (rate, from, to, rows) = self.fit();
        let factor = match self.flow {
            Flow::TaylorGreen { .. } => 2.0 * k * k,
            _ => k * k,
        };
        let a0 = a.first().copied().unwrap_or(0.0);
        outcome.metrics.set_check(&ModeDecayFigures {
            k,
            a0,
            rate,
            nu_equivalent: rate.map(|r| r / factor),
            fit_from_s: from,
            fit_to_s: to,
            fit_rows: rows,
            ratio_end: a.last().map_or(f64::NAN, |last| last / a0),
            later_max_ratio: self.later_max_ratio(to.unwrap_or(f64::INFINITY)),
        });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sampled exp(-r t) gives r back; the window starts at A / A0 <= 0.9
    /// and stops below 0.05.
    #[test]
    fn the_fit_recovers_an_exponential_rate_in_its_window() {
        let mut p = ModeDecay {
            flow: Flow::ShearWave { amplitude: 1.0 },
            rect: [0.0, 0.0, 1.0, 1.0],
            gravity: 0.0,
            samples: vec![],
            dir: PathBuf::new(),
            csv: false,
        };
        p.samples = (0..=400)
            .map(|i| 0.01 * i as f64)
            .map(|t| (t, 2.0 * (-1.5 * t).exp()))
            .collect();
        let (rate, from, to, rows) = p.fit();
        assert!((rate.unwrap() - 1.5).abs() < 1e-12, "{rate:?}");
        // exp(-1.5 t) = 0.9 at t = 0.0702, = 0.05 at t = 1.997.
        assert_eq!(from, Some(0.08));
        assert_eq!(to, Some(1.99));
        assert_eq!(rows, 192);
        assert!(p.later_max_ratio(1.99) < 0.05);
        // A mode that swings back: the same fit, but it comes back to 1.
        p.samples = (0..=400)
            .map(|i| 0.01 * i as f64)
            .map(|t| (t, 2.0 * (10.0 * t).cos()))
            .collect();
        let (_, _, to, _) = p.fit();
        assert!(p.later_max_ratio(to.unwrap()) > 0.99);
    }
}
