//! kick's monitor: watches every step through the solver's read-only
//! [`StateView`] for kinetic-energy spikes, local acceleration outliers,
//! energy injection and blow-out, and logs each kick as an [`Event`] with its
//! step, region and hallmark flags. Field metrics (checkerboard, hydrostatic
//! departure, surge front) are computed on demand: at output rows and when an
//! event opens. Definitions: docs/physics.md section 4.

pub mod checkerboard;
pub mod checkerboard_fields;
mod clustering;
pub mod config;
mod detector;
pub mod energy_budget;
mod energy_terms;
pub mod events;
pub mod front;
pub mod geometry;
pub mod hallmark_log;
pub mod hydrostatic;
pub mod jump;
pub mod mechanisms;
mod monitor;
pub mod particle_history;
pub mod remedy_booking;
pub mod rest_field;
pub mod ringing_growth;
mod state;
pub mod stats;
pub mod step_history;
mod step_report;

pub use clustering::isochoric_stretch_ratio;
pub use config::MonitorConfig;
pub use energy_terms::ROUND_OFF;
pub use events::{
    Cause, CellRange, DeformedBy, Event, EventKind, Evidence, Outcome, Region, Rule, Rules,
};
pub use geometry::Geometry;
pub use monitor::{critical_courant, Monitor, ADVECTION_MIN_MASS};
pub use step_report::{FieldMetrics, StepReport};
