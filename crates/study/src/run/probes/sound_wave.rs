//! The acoustic yardstick (docs/physics.md section 7): a closed box the
//! water fills, without gravity, starts with a standing sound wave
//! u = U sin(k x). After every step the velocity projected on that mode,
//! A = sum m u . s / sum m s . s; at the end its period from the zero
//! crossings and its amplitude decay rate from the extremes, against linear
//! acoustics: frequency c k (c = sqrt(K / rho0)) and decay (2/3) nu k^2.
//! The excess decay is stated as a viscosity, (rate - (2/3) nu k^2) /
//! ((2/3) k^2), so that an inviscid run has one too: what a damper that
//! acts on compression (bulk damping, artificial viscosity) shows, where
//! the nearly incompressible Taylor-Green vortex does not.

use crate::output::summary::Check;
use crate::output::tables;
use crate::run::probes::mode_decay::projected;
use crate::run::probes::slosh::Swing;
use crate::run::{Probe, Run, Simulated};
use serde::{Deserialize, Serialize};
use solver::flows::Flow;
use solver::{Scene, Solver};
use std::f64::consts::PI;
use std::path::PathBuf;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SoundWaveFigures {
    /// The wave's wavenumber k (1/m), k h, and the sound speed c (m/s).
    pub k: f64,
    pub kh: f64,
    pub sound_speed: f64,
    /// Linear acoustics' period 2 pi / (c k) (s).
    pub period_theory_s: f64,
    /// The measured period (s): twice the slope of the zero-crossing times
    /// against their count. None with fewer than 3 crossings.
    pub period_s: Option<f64>,
    /// The frequency's error, period_theory_s / period_s - 1.
    pub frequency_error: Option<f64>,
    /// (2/3) nu k^2 (1/s; 0 inviscid).
    pub decay_theory: f64,
    /// The fitted decay rate of |A| at its extremes (1/s). None with fewer
    /// than 3 extremes above 2 % of the first.
    pub decay_rate: Option<f64>,
    /// (decay_rate - decay_theory) / ((2/3) k^2) (m^2/s): the viscosity the
    /// method adds to the sound.
    pub excess_viscosity: Option<f64>,
    /// The largest |A| / A0 over the second theoretical period [T, 2 T):
    /// what a strongly damped run (backward Euler at a step near the
    /// period) keeps of the sound after one period. None with no sample there.
    pub kept_after_period: Option<f64>,
    pub extremes: usize,
    pub crossings: usize,
    pub followed_to_s: f64,
}

impl Check for SoundWaveFigures {
    const NAME: &'static str = "sound_wave";
}

pub struct SoundWave {
    flow: Flow,
    rect: [f64; 4],
    cell: f64,
    sound_speed: f64,
    nu: f64,
    /// (t, A) after every step.
    samples: Vec<(f64, f64)>,
    dir: PathBuf,
    csv: bool,
}

impl SoundWave {
    /// For a scene with one body whose flow is a sound wave in a material
    /// with a finite sound speed (none at K = inf: the projection removes
    /// the whole wave).
    pub fn new(scene: &Scene, dir: PathBuf, csv: bool) -> Option<Self> {
        let [body] = scene.bodies.as_slice() else {
            return None;
        };
        let flow = body.flow?;
        let Flow::SoundWave { .. } = flow else {
            return None;
        };
        let material = &scene.materials[scene.material_index(body)?];
        let sound_speed = material.wave_speed(1.0);
        sound_speed.is_finite().then(|| SoundWave {
            flow,
            rect: body.rect,
            cell: scene.cell,
            sound_speed,
            nu: material.viscosity / material.rho0,
            samples: vec![],
            dir,
            csv,
        })
    }

    /// The velocity projected on the wave's shape.
    fn amplitude(&self, s: &Solver) -> f64 {
        projected(s, &self.flow, self.rect, 0.0)
    }

    fn figures(&self) -> SoundWaveFigures {
        let k = self.flow.wavenumber(self.rect);
        let period_theory_s = 2.0 * PI / (self.sound_speed * k);
        let t: Vec<f64> = self.samples.iter().map(|s| s.0).collect();
        let a: Vec<f64> = self.samples.iter().map(|s| s.1).collect();
        let swing = Swing::of_signal(&t, &a, 0);
        let period_s = swing.period();
        let decay_theory = 2.0 / 3.0 * self.nu * k * k;
        let decay_rate = swing.decay_rate();
        SoundWaveFigures {
            k,
            kh: k * self.cell,
            sound_speed: self.sound_speed,
            period_theory_s,
            period_s,
            frequency_error: period_s.map(|p| period_theory_s / p - 1.0),
            decay_theory,
            decay_rate,
            excess_viscosity: decay_rate.map(|r| (r - decay_theory) / (2.0 / 3.0 * k * k)),
            kept_after_period: kept_after(&self.samples, period_theory_s),
            extremes: swing.extremes.len(),
            crossings: swing.crossings.len(),
            followed_to_s: swing.followed_to,
        }
    }
}

/// The largest |A| / A0 over [T, 2 T); None without a sample there.
fn kept_after(samples: &[(f64, f64)], period: f64) -> Option<f64> {
    let a0 = samples.first()?.1;
    samples
        .iter()
        .filter(|s| s.0 >= period && s.0 < 2.0 * period)
        .map(|s| (s.1 / a0).abs())
        .reduce(f64::max)
}

impl Probe<Solver> for SoundWave {
    fn begin(&mut self, run: &Run<Solver>) -> std::io::Result<()> {
        let a = self.amplitude(run.stepper);
        self.samples.push((run.stepper.time(), a));
        Ok(())
    }

    fn after_step(&mut self, run: &Run<Solver>, _: &[u32]) -> std::io::Result<()> {
        let a = self.amplitude(run.stepper);
        self.samples.push((run.stepper.time(), a));
        Ok(())
    }

    fn finish(&mut self, _: &Run<Solver>, outcome: &mut Simulated) -> std::io::Result<()> {
        let t: Vec<f64> = self.samples.iter().map(|s| s.0).collect();
        let a: Vec<f64> = self.samples.iter().map(|s| s.1).collect();
        tables::write_columns(
            &[("t", &t), ("amplitude", &a)],
            &self.dir,
            "sound_wave",
            self.csv,
        )?;
        outcome.metrics.set_check(&self.figures());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A damped cosine sampled at 40 points a period gives its period and
    /// rate back; a wave that dies within a period keeps what it kept.
    #[test]
    fn a_damped_cosine_gives_its_period_rate_and_what_it_keeps() {
        let (period, rate) = (0.0103, 12.0);
        let omega = 2.0 * PI / period;
        let samples: Vec<(f64, f64)> = (0..=800)
            .map(|i| i as f64 * period / 40.0)
            .map(|t| (t, 1e-3 * (omega * t).cos() * (-rate * t).exp()))
            .collect();
        let t: Vec<f64> = samples.iter().map(|s| s.0).collect();
        let a: Vec<f64> = samples.iter().map(|s| s.1).collect();
        let s = Swing::of_signal(&t, &a, 0);
        let p = s.period().unwrap();
        assert!((p / period - 1.0).abs() < 1e-4, "{p}");
        let r = s.decay_rate().unwrap();
        assert!((r / rate - 1.0).abs() < 1e-3, "{r}");
        assert_eq!(s.extremes.first().map(|e| e.0), Some(0.0));
        let kept = kept_after(&samples, period).unwrap();
        assert!((kept - (-rate * period).exp()).abs() < 1e-12, "{kept}");
        assert_eq!(kept_after(&samples[..30], period), None);
    }
}
