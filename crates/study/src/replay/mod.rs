//! Runs replayed or timed from what a run left: an event reproduced from
//! its checkpoint, an event explained (its velocity change split and single
//! changes replayed), and the solver's speed measured.

pub mod bench;
pub mod calibrate;
pub mod explain;
pub mod inf_sup;
pub mod reproduce;
