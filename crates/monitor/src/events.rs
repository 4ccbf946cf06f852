//! Kick events: flagged particles of one step clustered by cell adjacency
//! (8-neighbours), merged with open events nearby in space and time.

use crate::geometry::Geometry;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    Kick,
    BlowOut,
    EnergyInjection,
    NonFinite,
}

/// Inclusive cell range.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct CellRange {
    pub i_min: usize,
    pub j_min: usize,
    pub i_max: usize,
    pub j_max: usize,
}

impl CellRange {
    pub fn of(i: usize, j: usize) -> Self {
        CellRange {
            i_min: i,
            j_min: j,
            i_max: i,
            j_max: j,
        }
    }

    pub fn union(&self, o: &CellRange) -> CellRange {
        CellRange {
            i_min: self.i_min.min(o.i_min),
            j_min: self.j_min.min(o.j_min),
            i_max: self.i_max.max(o.i_max),
            j_max: self.j_max.max(o.j_max),
        }
    }

    /// True when the ranges overlap after growing this one by `margin` cells.
    pub fn near(&self, o: &CellRange, margin: usize) -> bool {
        self.i_min <= o.i_max + margin
            && o.i_min <= self.i_max + margin
            && self.j_min <= o.j_max + margin
            && o.j_min <= self.j_max + margin
    }

    pub fn metres(&self, geom: &Geometry) -> Region {
        Region {
            x_min: geom.origin.x + self.i_min as f64 * geom.cell,
            y_min: geom.origin.y + self.j_min as f64 * geom.cell,
            x_max: geom.origin.x + (self.i_max + 1) as f64 * geom.cell,
            y_max: geom.origin.y + (self.j_max + 1) as f64 * geom.cell,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Region {
    pub x_min: f64,
    pub y_min: f64,
    pub x_max: f64,
    pub y_max: f64,
}

/// Which detection rule fired (bit flags, listed by name in the event).
pub mod rule {
    pub const ACCEL_OUTLIER: u32 = 1;
    pub const KE_SPIKE: u32 = 2;
    pub const INJECTION_WINDOW: u32 = 4;
    pub const OUTSIDE_BOX: u32 = 8;
    pub const ESCAPE_SPEED: u32 = 16;
    pub const NON_FINITE: u32 = 32;

    pub fn names(bits: u32) -> Vec<String> {
        [
            (ACCEL_OUTLIER, "accel_outlier"),
            (KE_SPIKE, "ke_spike"),
            (INJECTION_WINDOW, "injection_window"),
            (OUTSIDE_BOX, "outside_box"),
            (ESCAPE_SPEED, "escape_speed"),
            (NON_FINITE, "non_finite"),
        ]
        .iter()
        .filter(|(b, _)| bits & b != 0)
        .map(|(_, n)| n.to_string())
        .collect()
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Event {
    pub id: u32,
    pub kind: EventKind,
    pub first_step: u64,
    pub last_step: u64,
    /// Time of the first step, and of the last.
    pub t: f64,
    pub last_t: f64,
    /// Cells flagged at the first step, and in metres.
    pub cells: CellRange,
    pub region: Region,
    /// Union of the cells flagged over the event.
    pub extent: CellRange,
    pub n_particles: usize,
    /// Ids of the first `max_event_ids` particles flagged.
    pub particles: Vec<u32>,
    pub peak_accel_g: f64,
    pub peak_z: f64,
    /// Energy injected (above the running minimum) while the event was open.
    pub energy_injected: f64,
    /// Effective Courant number at the first step.
    pub courant: f64,
    pub quiescent_before: bool,
    pub previously_deformed: bool,
    /// "strain_rate" and/or "distortion" when previously_deformed.
    pub deformed_by: Vec<String>,
    pub rules: Vec<String>,
    /// Filled in by the study runner.
    pub state_hash: Option<String>,
    pub checkpoint: Option<String>,
    #[serde(skip)]
    pub(crate) rule_bits: u32,
    #[serde(skip)]
    pub(crate) injected_at_open: f64,
}
