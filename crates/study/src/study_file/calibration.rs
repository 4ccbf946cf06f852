//! The `[calibration]` table: how `kick calibrate` plants kicks of known
//! size in the study's cases (docs/usage.md, "Calibrating the detector").
//! Each case runs clean first (its twin) and is checkpointed at `plant_t`;
//! planted runs restart from that checkpoint with one patch per `[[patch]]`
//! entry, `cells` x `cells` cells, and are judged over `window` seconds.

use serde::{Deserialize, Serialize};
use solver::{Direction, Placement};

/// One placement of the calibration: where its patch goes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PatchSpec {
    pub place: Placement,
    /// The qualifying patch nearest this point (m).
    pub near: [f64; 2],
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationSpec {
    /// When the patches are planted (s): the first step that ends at or
    /// after it is the twin's checkpoint, and the patches go in the step after.
    pub plant_t: f64,
    /// How long after the plant an event still counts as finding it (s).
    #[serde(default = "CalibrationSpec::default_window")]
    pub window: f64,
    /// Patch sizes (cells a side).
    pub sizes: Vec<usize>,
    #[serde(default = "CalibrationSpec::default_direction")]
    pub direction: Direction,
    pub patch: Vec<PatchSpec>,
    /// Bisect the smallest dv found between these speeds (m/s) ...
    #[serde(default)]
    pub bisect: Option<[f64; 2]>,
    /// ... until the bracket's ratio is at most this.
    #[serde(default = "CalibrationSpec::default_ratio")]
    pub ratio: f64,
    /// ... or plant exactly these speeds (m/s).
    #[serde(default)]
    pub dv: Vec<f64>,
    /// Every case's twin starts from this case's state `switch_lead`
    /// seconds before the plant, switched to its own method there: the
    /// methods are then compared on one flow, not on their own (None:
    /// each case runs from t = 0).
    #[serde(default)]
    pub common_state: Option<String>,
    #[serde(default = "CalibrationSpec::default_switch_lead")]
    pub switch_lead: f64,
    /// Every patch holds at least this many particles (None: the case's
    /// `monitor.min_cluster_particles`, the detector's resolution; 1: any
    /// block of fluid cells). A patch of fewer is no velocity-jump event
    /// under any method, and which cells hold fewer depends on each
    /// method's packing, so planting there measures the packing.
    #[serde(default)]
    pub min_particles: Option<usize>,
    /// Each patch's speed spread evenly over this long (s), a constant
    /// acceleration from the plant (None: one impulse in the plant's step).
    #[serde(default)]
    pub duration: Option<f64>,
}

type KeyError = (String, String);

impl CalibrationSpec {
    fn default_window() -> f64 {
        0.1
    }

    fn default_direction() -> Direction {
        Direction::Up
    }

    fn default_ratio() -> f64 {
        1.2
    }

    /// Past the detector's 30 ms energy window: the switch's own step is
    /// out of every window the plant is judged over.
    fn default_switch_lead() -> f64 {
        0.1
    }

    /// Reads the table; Err: (dotted key, message).
    pub fn from_toml(v: toml::Value) -> Result<Self, KeyError> {
        let spec: CalibrationSpec = v
            .try_into()
            .map_err(|e: toml::de::Error| ("calibration".to_string(), e.message().to_string()))?;
        spec.validate()?;
        Ok(spec)
    }

    /// The window ends by `t_end` (checked by `kick calibrate` only: a
    /// shorter `kick run` of the same study is fine).
    pub fn fits(&self, t_end: f64) -> Result<(), KeyError> {
        if self.plant_t + self.window <= t_end {
            return Ok(());
        }
        Err((
            "calibration.window".into(),
            format!(
                "plant_t + window = {} is out of range (allowed <= scene.t_end = {t_end})",
                self.plant_t + self.window
            ),
        ))
    }

    fn validate(&self) -> Result<(), KeyError> {
        self.validate_times()?;
        self.validate_patches()?;
        self.validate_speeds()
    }

    /// The plant time, the window, the switch's lead and the push's duration.
    fn validate_times(&self) -> Result<(), KeyError> {
        let bad = |k: &str, m: String| Err((format!("calibration.{k}"), m));
        if !(self.plant_t.is_finite() && self.plant_t > 0.0) {
            return bad(
                "plant_t",
                format!("{} is out of range (allowed > 0 s)", self.plant_t),
            );
        }
        if !(self.window.is_finite() && self.window > 0.0) {
            return bad(
                "window",
                format!("{} is out of range (allowed > 0 s)", self.window),
            );
        }
        if self.common_state.is_some()
            && !(self.switch_lead.is_finite()
                && self.switch_lead > 0.0
                && self.switch_lead < self.plant_t)
        {
            return bad(
                "switch_lead",
                format!(
                    "{} is out of range (allowed 0 < switch_lead < plant_t = {} s)",
                    self.switch_lead, self.plant_t
                ),
            );
        }
        if let Some(d) = self
            .duration
            .filter(|&d| !(d.is_finite() && d > 0.0 && d < self.window))
        {
            return bad(
                "duration",
                format!(
                    "{d} is out of range (allowed 0 < duration < window = {} s)",
                    self.window
                ),
            );
        }
        Ok(())
    }

    /// The patches: their sizes, placements and least particle count.
    fn validate_patches(&self) -> Result<(), KeyError> {
        let bad = |k: &str, m: String| Err((format!("calibration.{k}"), m));
        if let Some(m) = self
            .min_particles
            .filter(|m| !(1..=1_000_000_000).contains(m))
        {
            return bad(
                "min_particles",
                format!("{m} is out of range (allowed 1 ..= 1000000000)"),
            );
        }
        if self.sizes.is_empty() || self.sizes.iter().any(|&s| !(1..=64).contains(&s)) {
            return bad(
                "sizes",
                format!(
                    "{:?}: allowed a non-empty list of 1 ..= 64 cells",
                    self.sizes
                ),
            );
        }
        if self.patch.is_empty() {
            return bad(
                "patch",
                "at least one [[calibration.patch]] is required".into(),
            );
        }
        Ok(())
    }

    /// A bracket to bisect, or the speeds to plant.
    fn validate_speeds(&self) -> Result<(), KeyError> {
        let bad = |k: &str, m: String| Err((format!("calibration.{k}"), m));
        match (self.bisect, self.dv.is_empty()) {
            (Some(_), false) | (None, true) => bad(
                "bisect | dv",
                "exactly one of them is required (a bracket to bisect, or the speeds to plant)"
                    .into(),
            ),
            (Some([lo, hi]), true) => {
                if !(lo.is_finite() && lo > 0.0 && hi > lo && hi.is_finite()) {
                    return bad("bisect", format!("[{lo}, {hi}]: allowed 0 < lo < hi m/s"));
                }
                if !(self.ratio.is_finite() && self.ratio > 1.0) {
                    return bad(
                        "ratio",
                        format!("{} is out of range (allowed > 1)", self.ratio),
                    );
                }
                Ok(())
            }
            (None, false) => {
                if let Some(v) = self.dv.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
                    return bad("dv", format!("{v} is out of range (allowed > 0 m/s)"));
                }
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(extra: &str) -> Result<CalibrationSpec, KeyError> {
        let text = format!(
            "plant_t = 0.5\nsizes = [2]\n{extra}\n[[patch]]\nplace = \"bulk\"\nnear = [0.4, 0.15]\n"
        );
        let spec = CalibrationSpec::from_toml(text.parse::<toml::Table>().unwrap().into())?;
        spec.fits(1.0)?;
        Ok(spec)
    }

    #[test]
    fn a_bracket_or_speeds_but_not_both() {
        assert!(spec("bisect = [0.005, 0.32]").is_ok());
        assert!(spec("dv = [0.05, 0.1]").is_ok());
        assert_eq!(spec("").unwrap_err().0, "calibration.bisect | dv");
        assert_eq!(
            spec("bisect = [0.005, 0.32]\ndv = [0.1]").unwrap_err().0,
            "calibration.bisect | dv"
        );
        assert_eq!(
            spec("bisect = [0.3, 0.1]").unwrap_err().0,
            "calibration.bisect"
        );
        assert_eq!(
            spec("dv = [0.1]\nwindow = 0.6").unwrap_err().0,
            "calibration.window"
        );
        assert_eq!(spec("dv = [-1.0]").unwrap_err().0, "calibration.dv");
        assert_eq!(
            spec("dv = [0.1]\nmin_particles = 0").unwrap_err().0,
            "calibration.min_particles"
        );
        assert!(spec("dv = [0.1]\nduration = 0.03").is_ok());
        assert_eq!(
            spec("dv = [0.1]\nduration = 0.1").unwrap_err().0,
            "calibration.duration"
        );
        assert_eq!(spec("dv = [0.1]\nhunch = 1").unwrap_err().0, "calibration");
    }

    #[test]
    fn a_common_state_switches_before_the_plant() {
        let s = spec("dv = [0.1]\ncommon_state = \"a\"").unwrap();
        assert_eq!((s.common_state.as_deref(), s.switch_lead), (Some("a"), 0.1));
        for lead in ["0.0", "0.5", "-0.1"] {
            let extra = format!("dv = [0.1]\ncommon_state = \"a\"\nswitch_lead = {lead}");
            assert_eq!(spec(&extra).unwrap_err().0, "calibration.switch_lead");
        }
        // Without a common state the lead is not read.
        assert!(spec("dv = [0.1]\nswitch_lead = 0.5").is_ok());
    }
}
