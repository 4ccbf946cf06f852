//! Ring checkpoints every `every` steps (plus step 0), the last
//! `CHECKPOINT_RING` kept, and any that precedes an event kept for good.

use crate::output_files::write_atomic;
use crate::runner::{Probe, Run, Stepper};
use std::collections::BTreeSet;
use std::path::PathBuf;

/// Ring checkpoints kept per case (besides the step-0 one and event ones).
const CHECKPOINT_RING: usize = 3;

/// A ring checkpoint's path relative to the case folder.
pub fn ring_name(step: u64) -> String {
    format!("checkpoints/ring_{step:09}.ckpt")
}

pub struct CheckpointRing {
    dir: PathBuf,
    every: u64,
    ring: Vec<(u64, PathBuf)>,
    pinned: BTreeSet<u64>,
}

impl CheckpointRing {
    /// `every` = 0: no checkpoints.
    pub fn new(dir: PathBuf, every: u64) -> Self {
        CheckpointRing {
            dir,
            every,
            ring: vec![],
            pinned: BTreeSet::new(),
        }
    }

    fn save<S: Stepper>(&mut self, run: &Run<S>) -> std::io::Result<()> {
        let step = run.step();
        let path = self.dir.join(ring_name(step));
        write_atomic(&path, &run.stepper.save(run.watches))?;
        self.ring.push((step, path));
        Ok(())
    }
}

impl<S: Stepper> Probe<S> for CheckpointRing {
    /// The first checkpoint precedes any event, even one at the first step.
    /// It is kept for good: a replay of any event can start from it when no
    /// later checkpoint precedes the event's window.
    fn begin(&mut self, run: &Run<S>) -> std::io::Result<()> {
        if self.every > 0 {
            self.save(run)?;
            self.pinned.insert(run.step());
        }
        Ok(())
    }

    fn pin_checkpoint(&mut self) -> Option<String> {
        let (step, _) = self.ring.last()?;
        self.pinned.insert(*step);
        Some(ring_name(*step))
    }

    fn between_steps(&mut self, run: &Run<S>) -> std::io::Result<()> {
        if self.every == 0 || !run.step().is_multiple_of(self.every) {
            return Ok(());
        }
        self.save(run)?;
        if self.ring.len() > CHECKPOINT_RING {
            let (old, path) = self.ring.remove(0);
            if !self.pinned.contains(&old) {
                let _ = std::fs::remove_file(path);
            }
        }
        Ok(())
    }
}
