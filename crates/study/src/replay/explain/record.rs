//! explain.json: what `kick explain` found for one event, written from
//! `ExplainRecord`; the report reads it back through `ExplainedHead`, the
//! part it shows (a NaN figure is written as null, so it reads as None).

use super::precursors::Precursors;
use super::{CounterfactualRow, Window};
use monitor::mechanisms::Shares;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The file's name in an event's explain folder.
pub const FILE: &str = "explain.json";

/// The whole record (written with its keys sorted, as it always was).
#[derive(Clone, Debug, Serialize)]
pub struct ExplainRecord {
    pub case_dir: String,
    pub event: u32,
    pub checkpoint: String,
    pub checkpoint_t: f64,
    pub replayed_state_hash: Option<String>,
    pub logged_state_hash: Option<String>,
    /// The replay met the logged event at its first step with its hash.
    pub matched: bool,
    pub window: Window,
    /// The event's particles (ids, ascending).
    pub particles: Vec<u32>,
    pub steps_explained: usize,
    /// Largest part of the velocity change no term explains.
    pub closure_rest_max: f64,
    pub shares: Shares,
    /// sum |s_i| / |sum s_i| over the split's parts: above
    /// `monitor::mechanisms::CANCELLING` the leading mechanism is "undecided".
    pub cancellation: f64,
    pub leading: Leading,
    pub largest_part: LargestPart,
    pub precursors: Precursors,
    pub m4_ringing: Ringing,
    pub m5_time_step: TimeStep,
    pub criteria: Criteria,
    pub counterfactual: Vec<CounterfactualRow>,
}

/// The mechanism with the largest share (M1-M3), and the share; "undecided"
/// when the split's parts cancel.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Leading {
    pub mechanism: String,
    pub share: Option<f64>,
}

/// The part of the split with the largest share, and the share.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LargestPart {
    pub part: String,
    pub share: Option<f64>,
}

/// M4: the transfer's drift over the particles' speed before onset.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Ringing {
    pub drift_over_speed: f64,
    /// The mean drift over sqrt(g H), H the scene's column height: the
    /// ratio to compare across events (quiet particles do not swell it).
    pub drift_over_gravity_wave: f64,
    pub steps: usize,
    pub window_s: f64,
}

/// M5: the Courant and nodal advective numbers before onset.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TimeStep {
    pub courant_before: f64,
    pub advection_before: f64,
    pub critical_courant: f64,
}

/// The mechanisms' criteria (docs/physics.md section 4c).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Criteria {
    pub small_node_share: f64,
    pub outlier_sigmas: f64,
    pub outlier_floor_rho0_g_h: f64,
}

/// The shares the report tables.
#[derive(Clone, Copy, Debug, Default, Deserialize)]
pub struct ShareFigures {
    pub internal: Option<f64>,
    pub small_mass_node: Option<f64>,
    pub cell_crossing: Option<f64>,
    pub stress_outlier: Option<f64>,
}

/// The precursor the report tables (absent from older records).
#[derive(Clone, Debug, Default, Deserialize)]
pub struct PrecursorHead {
    pub named: String,
}

/// What the report reads of a record.
#[derive(Clone, Debug, Deserialize)]
pub struct ExplainedHead {
    pub matched: bool,
    pub shares: ShareFigures,
    pub leading: Leading,
    pub largest_part: LargestPart,
    /// The split's cancellation index and the precursors (absent from
    /// records written before they were measured).
    #[serde(default)]
    pub cancellation: Option<f64>,
    #[serde(default)]
    pub precursors: Option<PrecursorHead>,
}

impl ExplainRecord {
    /// Writes the record into `dir` (keys sorted at every level).
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        let sorted = serde_json::to_value(self)?;
        crate::output::files::write_atomic(
            &dir.join(FILE),
            serde_json::to_string_pretty(&sorted)?.as_bytes(),
        )
    }
}

impl ExplainedHead {
    /// The record of event `id` of the case in `case_dir`, if `kick
    /// explain` wrote one that reads.
    pub fn read(case_dir: &Path, id: u32) -> Option<ExplainedHead> {
        let file = case_dir
            .join("explain")
            .join(format!("event_{id}"))
            .join(FILE);
        serde_json::from_str(&std::fs::read_to_string(file).ok()?).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_head_reads_back_what_the_record_wrote_null_for_nan() {
        let dir = std::env::temp_dir().join(format!("kick-explain-record-{}", std::process::id()));
        let event = dir.join("explain").join("event_7");
        std::fs::create_dir_all(&event).unwrap();
        let record = ExplainRecord {
            case_dir: dir.display().to_string(),
            event: 7,
            checkpoint: "ckpt_000010.bin".into(),
            checkpoint_t: 0.5,
            replayed_state_hash: Some("00ff".into()),
            logged_state_hash: None,
            matched: true,
            window: Window {
                explain_from: 0.4,
                onset_from: 0.49,
                switch_from: 0.49,
                first_step: 11,
                last_step: 12,
                last_t: 0.51,
            },
            particles: vec![3, 4],
            steps_explained: 2,
            closure_rest_max: 1e-12,
            cancellation: 1.0,
            precursors: Precursors::new(&Default::default(), 0, 0, 1.0),
            shares: Shares {
                internal: 0.75,
                small_mass_node: f64::NAN,
                stress_outlier: 0.25,
                ..Shares::default()
            },
            leading: Leading {
                mechanism: "M3".into(),
                share: Some(0.25),
            },
            largest_part: LargestPart {
                part: "internal".into(),
                share: Some(0.75),
            },
            m4_ringing: Ringing {
                drift_over_speed: f64::NAN,
                drift_over_gravity_wave: f64::NAN,
                steps: 0,
                window_s: 0.09,
            },
            m5_time_step: TimeStep {
                courant_before: 0.2,
                advection_before: 0.1,
                critical_courant: 1.0,
            },
            criteria: Criteria {
                small_node_share: 0.01,
                outlier_sigmas: 5.0,
                outlier_floor_rho0_g_h: 1.0,
            },
            counterfactual: vec![],
        };
        record.write(&event).unwrap();
        let text = std::fs::read_to_string(event.join(FILE)).unwrap();
        // Sorted keys, as the untyped record wrote them.
        let keys: Vec<usize> = ["case_dir", "checkpoint", "counterfactual", "window"]
            .iter()
            .map(|k| text.find(&format!("\"{k}\"")).unwrap())
            .collect();
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "{text}");
        let head = ExplainedHead::read(&dir, 7).unwrap();
        assert!(head.matched);
        assert_eq!(head.shares.internal, Some(0.75));
        assert_eq!(head.shares.small_mass_node, None);
        assert_eq!(head.leading.mechanism, "M3");
        assert_eq!(head.largest_part.share, Some(0.75));
        assert_eq!(head.cancellation, Some(1.0));
        assert_eq!(
            head.precursors.map(|p| p.named).as_deref(),
            Some("no control")
        );
        assert!(ExplainedHead::read(&dir, 8).is_none());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
