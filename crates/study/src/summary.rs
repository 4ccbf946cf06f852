//! `summary.json`: one case's outcome, written by `run_case` and read by the
//! matrix, the report and `reproduce` through this one type.

use crate::output_files::write_atomic;
use monitor::Event;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Bumped whenever a field of `Summary` or `Metrics` changes meaning or name.
pub const SCHEMA_VERSION: u32 = 7;

/// How a case ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Reached `scene.t_end`.
    Completed,
    /// Stopped by the monitor (blow-out, non-finite state) or the solver.
    BlewUp,
    /// Could not run (setup error or a panic inside the case).
    Failed,
}

impl Status {
    pub fn as_str(&self) -> &'static str {
        match self {
            Status::Completed => "completed",
            Status::BlewUp => "blew_up",
            Status::Failed => "failed",
        }
    }
}

/// The case's figures (docs/physics.md section 4); `None` where undefined
/// (no rows in the window, no kick, not a dam-break scene).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Mean relative RMS hydrostatic departure over the last simulated
    /// second, for a run that reached t_end (event rows and the t = 0 row left out).
    pub hydro_rel_rms_late: Option<f64>,
    /// Mean largest hydrostatic departure over the same window.
    pub hydro_max_late: Option<f64>,
    /// Mean departure over the same window from the pressure that the weight
    /// and the vertical accelerations above demand (relative to the
    /// hydrostatic pressure): what the motion does not explain.
    pub hydro_unexplained_rel_rms_late: Option<f64>,
    /// Mean checkerboard index over the same window.
    pub checkerboard_late: Option<f64>,
    /// The three figures above over the second before a run stopped (blew up).
    pub hydro_rel_rms_pre_failure: Option<f64>,
    pub hydro_max_pre_failure: Option<f64>,
    pub checkerboard_pre_failure: Option<f64>,
    pub checkerboard_peak: Option<f64>,
    /// Largest energy injected above the running minimum (J/m).
    pub energy_injected_max: Option<f64>,
    /// Time of the first kick (an event whose cause is `injection` or `inversion`), s.
    pub t_first_kick: Option<f64>,
    /// Events whose cause is `injection` or `inversion`.
    pub n_kicks: usize,
    /// Kicks with the hallmark (quiescent before, highly deformed earlier):
    /// the kinematic anomaly proper.
    pub n_anomalies: usize,
    /// Time of the first anomaly (s).
    pub t_first_anomaly: Option<f64>,
    /// Every event counted by cause, with the time of the first.
    pub causes: BTreeMap<String, CauseCount>,
    /// Events opened by the energy-budget rule (kind `energy_injection`).
    pub n_energy_injections: usize,
    pub courant_max: Option<f64>,
    /// Largest nodal advective number |v_i| dt / h.
    pub node_advection_max: Option<f64>,
    pub max_accel_g: Option<f64>,
    /// RMS of Z against Martin & Moyce while the front is short of the far wall.
    pub front_rms_error: Option<f64>,
    /// The same in two regimes (`metrics::front_errors`): early (T <= 3.5)
    /// raw and after the best time shift (in T, |shift| <= 0.3), late (T >
    /// 3.5) the RMS and the simulated dZ/dT.
    #[serde(default)]
    pub front_rms_error_early: Option<f64>,
    #[serde(default)]
    pub front_rms_error_early_shifted: Option<f64>,
    #[serde(default)]
    pub front_time_shift: Option<f64>,
    #[serde(default)]
    pub front_speed_late: Option<f64>,
    #[serde(default)]
    pub front_rms_error_late: Option<f64>,
    /// Event openings past `monitor.max_events`, counted per step.
    pub events_dropped: u64,
    /// Particles deleted (`scene.on_escape` / `on_inversion = "delete"`):
    /// escaped, inverted, their share of the initial mass, and the time of
    /// the first deletion.
    pub particles_escaped: u64,
    pub particles_inverted: u64,
    pub mass_lost_fraction: f64,
    pub t_first_loss: Option<f64>,
    /// Outflow through drained walls (not a loss): particles and their
    /// share of the initial mass.
    #[serde(default)]
    pub particles_drained: u64,
    #[serde(default)]
    pub mass_drained_fraction: f64,
    /// Inflow through inflow walls: particles that entered and their mass
    /// as a share of the initial mass.
    #[serde(default)]
    pub particles_injected: u64,
    #[serde(default)]
    pub mass_injected_fraction: f64,
    /// Mixtures (docs/physics.md section 6). In a uniform periodic mixture
    /// without gravity (the drag-decay scene): the largest |dv(t) - dv0
    /// exp(-t/tau)| over the run relative to |dv0|, dv the difference of the
    /// phases' mean velocities; the same against the update's own discrete
    /// law (explicit prod(1 - dt/tau), implicit prod 1/(1 + dt/tau),
    /// exponential exp(-t/tau)); and the first step's dt/tau.
    #[serde(default)]
    pub drag_decay_rel_error: Option<f64>,
    #[serde(default)]
    pub drag_decay_discrete_rel_error: Option<f64>,
    #[serde(default)]
    pub drag_dt_over_tau: Option<f64>,
    /// The Darcy column (a fixed layer in a periodic box under gravity), at
    /// t_end: |drop - mu q L / k| / (mu q L / k) with the drop from the
    /// pressure gradients fitted inside and outside the layer, the largest
    /// departure of the layer's row-averaged pressure from its line over
    /// that drop, and the measured Darcy flux q (m/s).
    #[serde(default)]
    pub darcy_dp_rel_error: Option<f64>,
    #[serde(default)]
    pub darcy_linearity: Option<f64>,
    #[serde(default)]
    pub darcy_flux: Option<f64>,
    /// |q - q_ideal| / q_ideal with q_ideal = rho g H n^2 / (B L), the flux
    /// at which the layer's drop carries the whole column's weight: the
    /// node-based drag acts over a layer about a cell longer than L.
    #[serde(default)]
    pub darcy_flux_rel_error: Option<f64>,
    /// The drag-convergence scene (a fixed layer without gravity in a fluid
    /// moving along it): the largest error of the fluid's mean velocity
    /// against the update's own law inside the layer and free flow outside,
    /// relative to the part the layer takes (|u0| L / H).
    #[serde(default)]
    pub drag_layer_error: Option<f64>,
    /// Terzaghi's column (pore pressure on, a top traction, no gravity): the
    /// largest |p - p_exact| / p0 over rows of half a cell and the samples
    /// with T >= 0.05 (the issue's window), and the largest |U -
    /// U_exact| there; both series are in terzaghi.parquet.
    #[serde(default)]
    pub terzaghi_max_error_over_p0: Option<f64>,
    #[serde(default)]
    pub terzaghi_u_error: Option<f64>,
    /// Under gravity in a box closed along it, for a run that reached t_end:
    /// the mean over the last second of the fluid's free-surface spread
    /// (highest fluid particle per column of one cell, max - min over the
    /// columns) and of its lowest particle's spread (evenness of
    /// penetration), in metres.
    #[serde(default)]
    pub surface_spread_late: Option<f64>,
    #[serde(default)]
    pub penetration_spread_late: Option<f64>,
    /// At the end: the largest saturation of a cell (grains' and fluid's
    /// reference volumes over its area): above 1 where the water crowds
    /// into the grains' room.
    #[serde(default)]
    pub saturation_max: Option<f64>,
    /// Kinetic energy the drag dissipated over the run (J/m).
    #[serde(default)]
    pub drag_dissipated: Option<f64>,
    /// Largest rise of the mixture's total energy (both phases, drag
    /// dissipation included) above its value at t = 0 (J/m): must stay at
    /// round-off. Undefined in a box periodic along gravity (a particle that
    /// wraps jumps by m g H).
    #[serde(default)]
    pub mixture_energy_growth: Option<f64>,
    /// Largest |P(t) - P(0)| of both phases' momentum over the run, relative
    /// to sum m |v| at t = 0 (periodic scenes without gravity only).
    #[serde(default)]
    pub momentum_drift_rel: Option<f64>,
}

/// One phase of a mixture: its particles, events and figures alone.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhaseSummary {
    /// `solid` or `fluid`.
    pub phase: String,
    pub particles: usize,
    pub n_events: usize,
    pub metrics: Metrics,
}

/// Events of one cause.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CauseCount {
    pub count: usize,
    /// Time of the first (s).
    pub t_first: Option<f64>,
}

/// One case's `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub schema_version: u32,
    pub case: String,
    /// Every study parameter by dotted key, method defaults included.
    pub params: BTreeMap<String, serde_json::Value>,
    pub status: Status,
    /// Why the run stopped ("" when it completed).
    pub reason: String,
    pub steps: u64,
    /// Simulated time reached (s).
    pub t_end: f64,
    pub wall_s: f64,
    /// Particles at t = 0 (deleted ones included).
    pub particles: usize,
    pub particle_steps_per_s: f64,
    /// 64-bit state hash (hex) of the particle arrays at the last step.
    pub final_state_hash: String,
    pub events: Vec<Event>,
    pub metrics: Metrics,
    /// A mixture's phases (solid, fluid); empty for one phase. Then
    /// `metrics` holds the fluid's field figures, the counts of both
    /// phases' events and the mixture's own figures.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub phases: Vec<PhaseSummary>,
}

impl Summary {
    pub const FILE: &'static str = "summary.json";

    /// Reads `dir/summary.json`; errors name the file.
    pub fn read(dir: &Path) -> Result<Summary, String> {
        let path = dir.join(Self::FILE);
        let bytes =
            std::fs::read(&path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        #[derive(Deserialize)]
        struct Version {
            schema_version: Option<u32>,
        }
        let version = serde_json::from_slice::<Version>(&bytes)
            .map_err(|e| format!("{}: not valid JSON: {e}", path.display()))?
            .schema_version;
        if version != Some(SCHEMA_VERSION) {
            return Err(format!(
                "{}: schema_version {} is not {SCHEMA_VERSION} (written by another kick version: run the case again)",
                path.display(),
                version.map_or("missing".into(), |v| v.to_string())
            ));
        }
        serde_json::from_slice(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Writes `dir/summary.json` atomically (the last file a case writes).
    /// A blow-up's non-finite event figures are written as +-f64::MAX, so
    /// that the file reads back (JSON has no NaN or infinity).
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        let safe = Summary {
            events: self.events.iter().map(Event::json_safe).collect(),
            ..self.clone()
        };
        write_atomic(
            &dir.join(Self::FILE),
            serde_json::to_string_pretty(&safe)?.as_bytes(),
        )
    }

    /// The case logged at least one kick.
    pub fn kicked(&self) -> bool {
        self.metrics.t_first_kick.is_some()
    }
}

/// A small kick event as a summary stores it, for tests.
#[cfg(test)]
pub fn sample_event() -> Event {
    serde_json::from_value(serde_json::json!({
        "id": 1, "kind": "kick", "first_step": 3, "last_step": 4, "t": 0.1, "last_t": 0.2,
        "cells": {"i_min": 0, "j_min": 0, "i_max": 1, "j_max": 1},
        "region": {"x_min": 0.0, "y_min": 0.0, "x_max": 0.01, "y_max": 0.01},
        "extent": {"i_min": 0, "j_min": 0, "i_max": 1, "j_max": 1},
        "n_particles": 4, "particles": [1, 2], "peak_accel_g": 1.0, "peak_z": 2.0,
        "energy_injected": 0.0, "courant": 0.2, "quiescent_before": false,
        "deformed_by": [], "rules": ["ke_spike"], "state_hash": null, "checkpoint": null
    }))
    .unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A blown-up run's events hold infinities and NaN: the summary still reads back.
    #[test]
    fn non_finite_event_figures_read_back() {
        let dir = std::env::temp_dir().join(format!("kick-summary-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut event = sample_event();
        event.evidence.advection_before = f64::INFINITY;
        event.energy_injected = f64::NAN;
        event.evidence.j_min = Some(f64::NEG_INFINITY);
        let summary = Summary {
            schema_version: SCHEMA_VERSION,
            case: "c".into(),
            params: BTreeMap::new(),
            status: Status::BlewUp,
            reason: "r".into(),
            steps: 4,
            t_end: 0.2,
            wall_s: 1.0,
            particles: 10,
            particle_steps_per_s: 40.0,
            final_state_hash: "0".into(),
            events: vec![event],
            metrics: Metrics::default(),
            phases: vec![],
        };
        summary.write(&dir).unwrap();
        let back = Summary::read(&dir).unwrap();
        let e = &back.events[0];
        assert_eq!(e.evidence.advection_before, f64::MAX);
        assert_eq!(e.energy_injected, f64::MAX);
        assert_eq!(e.evidence.j_min, Some(f64::MIN));
        assert_eq!(e.t, 0.1);
        std::fs::remove_dir_all(&dir).ok();
    }
}
