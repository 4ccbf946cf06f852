//! The fluid's free surface and wetting front (docs/physics.md section 6).

use crate::output::summary::{Check, Status};
use crate::run::{Probe, Run, Simulated};
use serde::{Deserialize, Serialize};
use solver::{Mixture, Scene};

/// The fluid's free surface and wetting front under gravity (a box closed
/// along gravity): per column of one cell, the highest and the lowest
/// fluid particle; their spreads (max - min over the columns holding
/// fluid) per sample, averaged over the last simulated second of a run that
/// reached t_end (the filter stone's levelling and evenness of penetration).
/// Under gravity in a box closed along it, for a run that reached t_end:
/// the mean over the last second of the fluid's free-surface spread and of
/// its lowest particle's spread (evenness of penetration), in metres.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SurfaceFigures {
    pub surface_spread_late: Option<f64>,
    pub penetration_spread_late: Option<f64>,
}

impl Check for SurfaceFigures {
    const NAME: &'static str = "surface";
}

pub struct SurfaceCheck {
    /// (t, surface spread, penetration spread)
    samples: Vec<[f64; 3]>,
}

impl SurfaceCheck {
    pub fn new(scene: &Scene) -> Option<Self> {
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

impl Probe<Mixture> for SurfaceCheck {
    fn row(&mut self, run: &Run<Mixture>) {
        self.sample(run.stepper);
    }

    fn finish(&mut self, run: &Run<Mixture>, outcome: &mut Simulated) -> std::io::Result<()> {
        let completed = outcome.status == Status::Completed;
        let t = run.stepper.time();
        outcome.metrics.set_check(&SurfaceFigures {
            surface_spread_late: completed.then(|| self.late(1, t)).flatten(),
            penetration_spread_late: completed.then(|| self.late(2, t)).flatten(),
        });
        Ok(())
    }
}
