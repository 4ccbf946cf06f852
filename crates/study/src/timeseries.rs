//! The per-case timeseries: one row per k steps plus a row at each event's
//! first step. Peak columns (max_*, node_advection, courant, j range, smallest nodal mass)
//! hold the extreme since the previous row so that no spike between rows is
//! lost; the others are the value at the row's step. Missing values are NaN
//! in memory, empty in CSV and null in Parquet.

use monitor::{FieldMetrics, StepReport};

pub const COLUMNS: &[&str] = &[
    "t",
    "dt",
    "e_kin",
    "e_grav",
    "e_int",
    "d_visc",
    "e_total",
    "energy_injected",
    "injection_window",
    "injection_floor",
    "transfer_loss",
    "max_accel_g",
    "max_transfer_jump",
    "max_z",
    "max_ke_ratio",
    "max_speed",
    "courant",
    "j_min",
    "j_max",
    "min_node_mass_ratio",
    "max_node_accel_g",
    "node_advection",
    "ringing_energy",
    "n_outside",
    "particles_lost",
    "mass_lost_fraction",
    "n_flagged",
    "events_opened",
    "checkerboard",
    "pressure_spread",
    "hydro_rel_rms",
    "hydro_max",
    "hydro_unexplained_rel_rms",
    "front_x",
    "front_z",
    "front_t",
];

/// Extremes since the last row.
#[derive(Clone, Copy, Debug)]
pub struct Peaks {
    accel_g: f64,
    transfer_jump: f64,
    z: f64,
    ke_ratio: f64,
    speed: f64,
    courant: f64,
    j_min: f64,
    j_max: f64,
    node_mass: f64,
    node_accel_g: f64,
    node_advection: f64,
    flagged: usize,
    opened: usize,
}

impl Default for Peaks {
    fn default() -> Self {
        Peaks {
            accel_g: 0.0,
            transfer_jump: 0.0,
            z: 0.0,
            ke_ratio: 0.0,
            speed: 0.0,
            courant: 0.0,
            j_min: f64::INFINITY,
            j_max: f64::NEG_INFINITY,
            node_mass: f64::INFINITY,
            node_accel_g: 0.0,
            node_advection: 0.0,
            flagged: 0,
            opened: 0,
        }
    }
}

impl Peaks {
    pub fn add(&mut self, r: &StepReport) {
        self.accel_g = self.accel_g.max(r.max_accel_g);
        self.z = self.z.max(r.max_z);
        self.ke_ratio = self.ke_ratio.max(r.max_ke_ratio);
        self.speed = self.speed.max(r.max_speed);
        self.courant = self.courant.max(r.courant);
        self.j_min = self.j_min.min(r.j_min);
        self.j_max = self.j_max.max(r.j_max);
        self.node_mass = self.node_mass.min(r.min_node_mass_ratio);
        self.node_accel_g = self.node_accel_g.max(r.max_node_accel_g);
        self.node_advection = self.node_advection.max(r.node_advection);
        self.transfer_jump = self.transfer_jump.max(r.max_transfer_jump);
        self.flagged += r.n_flagged;
        self.opened += r.events_opened;
    }
}

#[derive(Clone, Debug, Default)]
pub struct Timeseries {
    pub step: Vec<u64>,
    /// Rows written only because an event opened (or the run stopped) at
    /// their step: never part of a "late" window.
    pub event_row: Vec<bool>,
    /// One vector per entry of COLUMNS.
    pub columns: Vec<Vec<f64>>,
}

fn or_nan(v: Option<f64>) -> f64 {
    v.unwrap_or(f64::NAN)
}

impl Timeseries {
    pub fn new() -> Self {
        Timeseries {
            step: vec![],
            event_row: vec![],
            columns: vec![vec![]; COLUMNS.len()],
        }
    }

    pub fn last_step(&self) -> Option<u64> {
        self.step.last().copied()
    }

    pub fn column(&self, name: &str) -> &[f64] {
        let k = COLUMNS
            .iter()
            .position(|c| *c == name)
            .expect("known column");
        &self.columns[k]
    }

    /// Appends a row from the step report, the peaks since the last row and
    /// the field metrics; `event_row` when it is written only for an event.
    pub fn push(&mut self, r: &StepReport, p: &Peaks, f: &FieldMetrics, event_row: bool) {
        let finite_or_nan = |v: f64| if v.is_finite() { v } else { f64::NAN };
        let row = [
            r.t,
            r.dt,
            r.e_kin,
            r.e_grav,
            r.e_int,
            r.d_visc,
            r.e_total,
            r.energy_injected,
            r.injection_window,
            r.injection_floor,
            r.transfer_loss,
            p.accel_g,
            p.transfer_jump,
            p.z,
            p.ke_ratio,
            p.speed,
            p.courant,
            finite_or_nan(p.j_min),
            finite_or_nan(p.j_max),
            finite_or_nan(p.node_mass),
            p.node_accel_g,
            p.node_advection,
            r.ringing_energy,
            r.n_outside as f64,
            r.particles_lost as f64,
            r.mass_lost_fraction,
            p.flagged as f64,
            p.opened as f64,
            or_nan(f.checkerboard),
            f.pressure_spread,
            f.hydro_rel_rms,
            f.hydro_max,
            f.hydro_unexplained_rel_rms,
            or_nan(f.front_x),
            or_nan(f.front_z),
            f.front_t,
        ];
        debug_assert_eq!(row.len(), COLUMNS.len());
        self.step.push(r.step);
        self.event_row.push(event_row);
        for (col, v) in self.columns.iter_mut().zip(row) {
            col.push(v);
        }
    }
}
