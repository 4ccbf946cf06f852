//! `kick reproduce`'s checks on a replay from a checkpoint: particle files
//! of every step in a window around the event, the state hash at the
//! event's first step, and the event as its phase's monitor detects it again.

use crate::run::{Probe, Run, Stepper};
use monitor::Event;
use std::path::PathBuf;

/// What a replay found.
#[derive(Default)]
pub struct Found {
    pub hash_at_first: Option<String>,
    pub replayed: Option<Event>,
}

pub struct Replay<'a> {
    /// Particle files every step from this step on, into this folder.
    pub files_from: u64,
    pub files: PathBuf,
    /// The logged event and its phase.
    pub event: &'a Event,
    pub phase: usize,
    pub found: &'a mut Found,
}

impl<S: Stepper> Probe<S> for Replay<'_> {
    fn after_step(&mut self, run: &Run<S>, _: &[u32]) -> std::io::Result<()> {
        let step = run.step();
        if step >= self.files_from {
            super::particle_files::write_phases(&self.files, run.stepper)?;
        }
        if step == self.event.first_step {
            self.found.hash_at_first = Some(format!("{:016x}", run.stepper.state_hash()));
        }
        if step == self.event.last_step {
            self.found.replayed = run.watches[self.phase]
                .monitor
                .events()
                .iter()
                .find(|e| e.id == self.event.id)
                .cloned();
        }
        Ok(())
    }
}
