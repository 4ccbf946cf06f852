//! Every threshold of the monitor, by name, with its documented default.
//! All are study-file keys under `[monitor]`.

use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MonitorConfig {
    /// z scores are computed only for particles accelerating above this (in g).
    pub accel_candidate_g: f64,
    /// A particle is an acceleration outlier when a/g >= this ...
    pub kick_accel_g: f64,
    /// ... and its robust z score against its neighbourhood >= this.
    pub kick_z: f64,
    /// Half-width (cells) of the neighbourhood window for median/MAD; it must be
    /// wider than any patch to be caught (a 5 x 5 window is blind inside a 5 x 5 kick).
    pub window_half_cells: usize,
    /// Window statistics are shared by tiles of this many cells per side (cost).
    pub window_tile_cells: usize,
    /// Kinetic-energy spike: e_p over its recent maximum (floored) >= this ...
    pub ke_spike_ratio: f64,
    /// ... with the recent maximum floored by 1/2 m v_q^2 at this speed (m/s).
    pub quiescent_speed: f64,
    /// Seconds over which a particle's kinetic-energy history decays (1/e): a
    /// spike is a jump within this time (a window in seconds: dt differs 80x
    /// across the bug-report matrix).
    pub ke_history_seconds: f64,
    /// Hallmark, quiescent before: over `quiet_seconds` before onset the
    /// particle was never faster than `quiet_speed` (m/s; 0.05 sqrt(g H) at
    /// H = 0.4 m) nor deformed faster than `quiet_rate` (in-plane |dev D|, 1/s).
    pub quiet_seconds: f64,
    pub quiet_speed: f64,
    pub quiet_rate: f64,
    /// Hallmark, highly deformed earlier: the particle's running maximum of
    /// the in-plane |dev D| (1/s) reached this before the quiet window.
    pub deformed_rate: f64,
    /// Isochoric stretch ratio of F (largest / smallest principal stretch) above
    /// which a particle counts as highly distorted.
    pub distortion_ratio: f64,
    /// Clusters with fewer flagged particles are noise, not kicks (default: one
    /// cell's worth at 2 x 2 particles per cell).
    pub min_cluster_particles: usize,
    /// Events closer than this many cells, and than this many seconds (a
    /// window in seconds: stiff cases take tiny steps), are merged.
    pub merge_cells: usize,
    pub merge_seconds: f64,
    /// Events stored per run; later openings are only counted, per step
    /// (blow-outs are always stored).
    pub max_events: usize,
    /// Particle ids kept per event (the count is always exact).
    pub max_event_ids: usize,
    /// Energy injected within the last `injection_seconds` (at most the last
    /// `step_history::CAPACITY` steps) counts as an event when it exceeds this
    /// multiple of the explicit-stepping noise floor.
    pub injection_floor_factor: f64,
    pub injection_seconds: f64,
    /// Blow-out: a particle faster than this multiple of sqrt(2 g H_box), or
    /// of the bodies' largest initial speed when that is larger.
    pub escape_speed_factor: f64,
}

impl Default for MonitorConfig {
    fn default() -> Self {
        MonitorConfig {
            accel_candidate_g: 5.0,
            kick_accel_g: 50.0,
            kick_z: 10.0,
            window_half_cells: 5,
            window_tile_cells: 4,
            ke_spike_ratio: 25.0,
            quiescent_speed: 0.05,
            ke_history_seconds: 0.005,
            quiet_seconds: 0.05,
            quiet_speed: 0.1,
            quiet_rate: 2.0,
            deformed_rate: 50.0,
            distortion_ratio: 4.0,
            min_cluster_particles: 4,
            merge_cells: 3,
            merge_seconds: 0.01,
            max_events: 500,
            max_event_ids: 64,
            injection_floor_factor: 3.0,
            injection_seconds: 0.005,
            escape_speed_factor: 10.0,
        }
    }
}

impl MonitorConfig {
    /// Range check of every threshold: (key, message) for the first bad one.
    pub fn validate(&self) -> Result<(), (String, String)> {
        macro_rules! non_negative {
            ($($field:ident),*) => {$(
                let v = self.$field;
                if !(v.is_finite() && (0.0..=1e12).contains(&v)) {
                    return Err((
                        stringify!($field).to_string(),
                        format!("{v} is out of range (allowed 0 ..= 1e12)"),
                    ));
                }
            )*};
        }
        non_negative!(
            accel_candidate_g,
            kick_accel_g,
            kick_z,
            ke_spike_ratio,
            quiescent_speed,
            ke_history_seconds,
            quiet_seconds,
            quiet_speed,
            quiet_rate,
            deformed_rate,
            distortion_ratio,
            merge_seconds,
            injection_floor_factor,
            injection_seconds,
            escape_speed_factor
        );
        if self.injection_seconds <= 0.0 {
            return Err((
                "injection_seconds".to_string(),
                format!("{} is out of range (allowed > 0)", self.injection_seconds),
            ));
        }
        // Counts size buffers (a window of steps, cells, events): bounded so a
        // typo is an error, not an allocation that aborts the run.
        macro_rules! count_within {
            ($($field:ident: $lo:expr, $hi:expr);* $(;)?) => {$(
                let v = self.$field as u64;
                if !($lo..=$hi).contains(&v) {
                    return Err((
                        stringify!($field).to_string(),
                        format!("{v} is out of range (allowed {} ..= {})", $lo, $hi),
                    ));
                }
            )*};
        }
        count_within!(
            window_half_cells: 0, 1_000;
            window_tile_cells: 1, 1_000;
            min_cluster_particles: 0, 1_000_000_000;
            merge_cells: 0, 1_000_000;
            max_events: 0, 10_000_000;
            max_event_ids: 0, 1_000_000;
        );
        Ok(())
    }
}
