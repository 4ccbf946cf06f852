//! Every threshold of the monitor, by name, with its documented default.
//! All are study-file keys under `[monitor]`.

use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MonitorConfig {
    /// The velocity-jump rule (`jump`): a particle's velocity change over a
    /// step departing from the local flow's by at least this (m/s) ...
    pub jump_speed: f64,
    /// ... and this many spreads of the local flow's change ...
    pub jump_z: f64,
    /// ... read from the cells 2 to this many cells away. A jump is a kick
    /// when the local flow was calm: the ring's median velocity change over
    /// the last `calm_seconds` below `calm_change` (m/s).
    pub jump_ring_cells: usize,
    pub calm_seconds: f64,
    pub calm_change: f64,
    /// Also judge each particle's change over the last `calm_seconds`,
    /// every half of it, by the same thresholds: a push that builds up over
    /// many steps is found in physical time at every step size. Judged
    /// where the particle was slower than `quiet_speed` at the window's
    /// start and moved at most 2 cells over it.
    pub windowed_jumps: bool,
    /// Judge every particle over the window, moving or not, against the
    /// ring of the cell it started the window in, in the window's start
    /// configuration (its material neighbours, followed by id): the same
    /// instrument in physical time in moving flow. Off by default: in a
    /// splashing flow the water shares a push over the window, so it finds
    /// none the per-step rule misses (docs/findings/detector_calibration.md).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub moving_window: bool,
    /// Judge each step's velocity change too (the per-step rule). Off, the
    /// jumps are judged over the window alone (`windowed_jumps`,
    /// `moving_window`): one instrument in physical time at every step,
    /// whose events are timed to the half window.
    #[serde(skip_serializing_if = "is_true")]
    pub step_jumps: bool,
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
    /// The energy gained within the last `injection_seconds` (at most the
    /// last `step_history::CAPACITY` steps; booked terms by their net over
    /// it) counts as an injection above the kinetic energy of the mass
    /// concerned at `jump_speed`, plus this share of the kinetic energy it
    /// carries (what explicit time integration misplaces in a violent flow
    /// at the step it takes; gravity's stepping term is booked exactly).
    pub injection_seconds: f64,
    pub injection_share: f64,
    /// Blow-out: a particle faster than this multiple of sqrt(2 g H_box), or
    /// of the bodies' largest initial speed when that is larger.
    pub escape_speed_factor: f64,
    /// Log the hallmark's raw figures of every opening kick's particles at
    /// quiet speeds a factor of 3 each way (`monitor::hallmark_log`), to
    /// re-apply the hallmark offline. Off by default: it adds to the
    /// monitor's memory and checkpoints.
    pub hallmark_log: bool,
}

impl Default for MonitorConfig {
    fn default() -> Self {
        MonitorConfig {
            jump_speed: 0.02,
            jump_z: 5.0,
            jump_ring_cells: 4,
            calm_seconds: 0.03,
            calm_change: 0.5,
            windowed_jumps: true,
            moving_window: false,
            step_jumps: true,
            quiet_seconds: 0.05,
            quiet_speed: 0.1,
            quiet_rate: 2.0,
            deformed_rate: 50.0,
            distortion_ratio: 4.0,
            min_cluster_particles: 4,
            merge_cells: 3,
            merge_seconds: 0.03,
            max_events: 500,
            max_event_ids: 64,
            injection_seconds: 0.03,
            injection_share: 0.1,
            escape_speed_factor: 10.0,
            hallmark_log: false,
        }
    }
}

fn is_true(b: &bool) -> bool {
    *b
}

impl MonitorConfig {
    /// Whether the windowed rule bins each span by where it started (and so
    /// keeps the snapshots' positions).
    pub(crate) fn moving_rule(&self) -> bool {
        self.windowed_jumps && self.moving_window
    }

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
            jump_speed,
            jump_z,
            calm_seconds,
            calm_change,
            quiet_seconds,
            quiet_speed,
            quiet_rate,
            deformed_rate,
            distortion_ratio,
            merge_seconds,
            injection_seconds,
            injection_share,
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
        if !self.step_jumps && !self.windowed_jumps {
            return Err((
                "step_jumps".to_string(),
                "false needs windowed_jumps = true (else no velocity jump is judged)".to_string(),
            ));
        }
        if self.moving_window && !self.windowed_jumps {
            return Err((
                "moving_window".to_string(),
                "true needs windowed_jumps = true (it is a rule of the window)".to_string(),
            ));
        }
        count_within!(
            jump_ring_cells: 2, 100;
            min_cluster_particles: 0, 1_000_000_000;
            merge_cells: 0, 1_000_000;
            max_events: 0, 10_000_000;
            max_event_ids: 0, 1_000_000;
        );
        Ok(())
    }
}
