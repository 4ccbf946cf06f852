//! The monitor crate's integration tests, one binary: a module per subject.

mod booked_controls;
mod checkerboard;
mod checkerboard_fields;
mod common;
mod energy_budget;
mod events_anomaly;
mod events_clean_physics;
mod events_column;
mod events_dam_break;
mod events_merge;
mod events_moving_window;
mod events_real_kick;
mod events_sustained;
mod front;
mod hydrostatic;
mod hydrostatic_floor;
mod inversion;
mod mechanisms;
mod mixture;
mod non_finite;
mod particle_history;
mod remedy_booking;
mod ringing;
mod state;
