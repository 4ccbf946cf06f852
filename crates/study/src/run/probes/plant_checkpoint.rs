//! The calibration's restart point: the case's state and monitors at the
//! first step that ends at or after the plant time, written once as
//! `plant.ckpt` (`kick calibrate` restarts its planted runs from it).

use crate::output::files::write_atomic;
use crate::run::{Probe, Run, Stepper};
use std::path::PathBuf;

pub const PLANT_CHECKPOINT: &str = "plant.ckpt";

pub struct PlantCheckpoint {
    path: PathBuf,
    at: f64,
    written: bool,
}

impl PlantCheckpoint {
    pub fn new(dir: PathBuf, at: f64) -> Self {
        PlantCheckpoint {
            path: dir.join(PLANT_CHECKPOINT),
            at,
            written: false,
        }
    }
}

impl<S: Stepper> Probe<S> for PlantCheckpoint {
    fn between_steps(&mut self, run: &Run<S>) -> std::io::Result<()> {
        if !self.written && run.stepper.time() >= self.at {
            write_atomic(&self.path, &run.stepper.save(run.watches))?;
            self.written = true;
        }
        Ok(())
    }
}
