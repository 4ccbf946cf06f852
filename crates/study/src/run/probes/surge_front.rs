//! The surge front of a dam break against Martin & Moyce (docs/physics.md
//! section 4), from the timeseries' front columns.

use crate::output::metrics;
use crate::output::summary::Check;
use crate::run::{Probe, Run, Simulated, Stepper};
use serde::{Deserialize, Serialize};
use solver::Scene;

/// RMS of Z against Martin & Moyce while the front is short of the far
/// wall; the same in two regimes (`metrics::front_errors`): early (T <=
/// 3.5) raw and after the best time shift (in T, |shift| <= 0.3), late (T >
/// 3.5) the RMS and the simulated dZ/dT.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SurgeFrontFigures {
    pub rms_error: Option<f64>,
    pub rms_error_early: Option<f64>,
    pub rms_error_early_shifted: Option<f64>,
    pub time_shift: Option<f64>,
    pub speed_late: Option<f64>,
    pub rms_error_late: Option<f64>,
}

impl Check for SurgeFrontFigures {
    const NAME: &'static str = "surge_front";
}

pub struct SurgeFront {
    /// Where the front meets the far wall (Z units).
    z_wall: f64,
}

impl SurgeFront {
    /// Only for a dam-break scene (`front_wall_z`).
    pub fn new(scene: &Scene) -> Option<Self> {
        front_wall_z(scene).map(|z_wall| SurgeFront { z_wall })
    }
}

/// Where the surge front meets the far wall (Z units), for dam-break scenes:
/// one body standing on the floor against the left wall, narrower than the box.
pub fn front_wall_z(scene: &Scene) -> Option<f64> {
    let [b] = scene.bodies.as_slice() else {
        return None;
    };
    let a = b.rect[2] - b.rect[0];
    let against_wall = (b.rect[0] - scene.origin[0]).abs() < 1e-9 * scene.size[0]
        && (b.rect[1] - scene.origin[1]).abs() < 1e-9 * scene.size[1];
    (against_wall && a < scene.size[0] && scene.gravity > 0.0).then(|| scene.size[0] / a)
}

impl<S: Stepper> Probe<S> for SurgeFront {
    fn finish(&mut self, run: &Run<S>, outcome: &mut Simulated) -> std::io::Result<()> {
        let series = &run.watches[run.stepper.primary_phase()].series;
        let front = metrics::front_errors(
            &metrics::front_track(series),
            &metrics::martin_moyce(),
            self.z_wall,
        );
        outcome.metrics.set_check(&SurgeFrontFigures {
            rms_error: metrics::front_rms_error(series, self.z_wall),
            rms_error_early: front.early_rms,
            rms_error_early_shifted: front.early_shifted_rms,
            time_shift: front.time_shift,
            speed_late: front.late_speed,
            rms_error_late: front.late_rms,
        });
        Ok(())
    }
}
