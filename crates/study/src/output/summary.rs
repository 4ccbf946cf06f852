//! `summary.json`: one case's outcome, written by `run::case` and read by the
//! matrix, the report and `reproduce` through this one type.

use crate::output::files::write_atomic;
use monitor::{Cause, Event};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Bumped whenever a field of `Summary` or `Metrics` changes meaning or name.
pub const SCHEMA_VERSION: u32 = 9;

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

/// The case's figures (docs/physics.md section 4): those drawn from the
/// timeseries (by its column declarations), from the events, the losses,
/// and each verification check's own.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Peaks and late or pre-failure means of timeseries columns, by the
    /// names their declarations give (`timeseries::COLUMNS`); null where
    /// undefined (no rows in the window).
    pub figures: BTreeMap<String, Option<f64>>,
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
    pub causes: BTreeMap<Cause, CauseCount>,
    /// Events opened by the energy-budget rule (kind `energy_injection`).
    pub n_energy_injections: usize,
    /// Event openings past `monitor.max_events`, counted per step.
    pub events_dropped: u64,
    pub losses: LossFigures,
    /// Each verification check's figures under its name (`Check::NAME`),
    /// for the checks the scene allows.
    pub checks: BTreeMap<String, serde_json::Value>,
}

impl Metrics {
    /// A figure drawn from a timeseries column, by its declared name.
    pub fn figure(&self, name: &str) -> Option<f64> {
        let value = self.figures.get(name).copied();
        debug_assert!(
            value.is_some() || crate::output::timeseries::figure_declared(name),
            "no timeseries figure {name}"
        );
        value.flatten()
    }

    /// A verification check's figures, if the case ran it.
    pub fn check<C: Check>(&self) -> Option<C> {
        let value = self.checks.get(C::NAME)?;
        serde_json::from_value(value.clone()).ok()
    }

    /// The metrics as one flat object: nested objects (figures, causes,
    /// losses, checks) by dotted keys, e.g. `checks.darcy.flux`.
    pub fn flattened(&self) -> serde_json::Map<String, serde_json::Value> {
        fn flatten(
            prefix: &str,
            v: serde_json::Value,
            out: &mut serde_json::Map<String, serde_json::Value>,
        ) {
            match v {
                serde_json::Value::Object(map) => {
                    for (k, v) in map {
                        let key = if prefix.is_empty() {
                            k
                        } else {
                            format!("{prefix}.{k}")
                        };
                        flatten(&key, v, out);
                    }
                }
                leaf => {
                    out.insert(prefix.to_string(), leaf);
                }
            }
        }
        let mut out = serde_json::Map::new();
        if let Ok(v) = serde_json::to_value(self) {
            flatten("", v, &mut out);
        }
        out
    }

    pub fn set_check<C: Check>(&mut self, figures: &C) {
        if let Ok(value) = serde_json::to_value(figures) {
            self.checks.insert(C::NAME.to_string(), value);
        }
    }
}

/// A verification check's figures, stored in `Metrics::checks` under its name.
pub trait Check: Serialize + serde::de::DeserializeOwned {
    const NAME: &'static str;
}

/// Particles deleted (`scene.on_escape` / `on_inversion = "delete"`):
/// escaped, inverted, their share of the initial mass, and the time of the
/// first deletion; outflow through drained walls and inflow through inflow
/// walls (neither a loss), as counts and shares of the initial mass.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LossFigures {
    pub particles_escaped: u64,
    pub particles_inverted: u64,
    pub mass_lost_fraction: f64,
    pub t_first_loss: Option<f64>,
    pub particles_drained: u64,
    pub mass_drained_fraction: f64,
    pub particles_injected: u64,
    pub mass_injected_fraction: f64,
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

/// A small kick event as a summary stores it (the tests of what reads
/// summaries, here and in the report).
pub fn sample_event() -> Event {
    serde_json::from_value(serde_json::json!({
        "id": 1, "kind": "kick", "first_step": 3, "last_step": 4, "t": 0.1, "last_t": 0.2,
        "cells": {"i_min": 0, "j_min": 0, "i_max": 1, "j_max": 1},
        "region": {"x_min": 0.0, "y_min": 0.0, "x_max": 0.01, "y_max": 0.01},
        "extent": {"i_min": 0, "j_min": 0, "i_max": 1, "j_max": 1},
        "n_particles": 4, "particles": [1, 2], "peak_accel_g": 1.0, "jump_speed": 0.05,
        "energy_injected": 0.0, "courant": 0.2, "quiescent_before": false,
        "deformed_by": [], "rules": ["velocity_jump"], "state_hash": null, "checkpoint": null
    }))
    .unwrap()
}

/// A method's identity across studies: its resolved `method.*` settings and
/// `scene.ppc` as `key=value` lines (a remedy switched on by `true` and by
/// its settings table are the same).
pub fn method_id(params: &BTreeMap<String, serde_json::Value>) -> String {
    let keys: Vec<&String> = params
        .keys()
        .filter(|k| k.starts_with("method.") || *k == "scene.ppc")
        .collect();
    keys.iter()
        .filter(|k| {
            let prefix = format!("{k}.");
            !(params[**k] == serde_json::Value::Bool(true)
                && keys.iter().any(|o| o.starts_with(&prefix)))
        })
        .map(|k| format!("{k}={}", params[*k]))
        .collect::<Vec<_>>()
        .join("\n")
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
