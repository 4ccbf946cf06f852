//! Ring checkpoints every `every` steps (plus step 0), the last
//! `CHECKPOINT_RING` kept, and any that precedes an event kept for good.
//! The ring also keeps the latest checkpoint that is at least `keep_seconds`
//! old (the monitor's quiet window), and an event pins that one too, so that
//! `kick explain` can replay the event's quiet window from just before it.

use crate::output::files::write_atomic;
use crate::run::{Probe, Run, Stepper};
use std::collections::BTreeSet;
use std::path::PathBuf;

/// Ring checkpoints kept per case (besides the step-0 one and event ones).
const CHECKPOINT_RING: usize = 3;

/// At most this many ring checkpoints wait for the quiet window (a dense
/// ring with a long window would otherwise keep thousands).
const MAX_RING: usize = 64;

/// A ring checkpoint's path relative to the case folder.
pub fn ring_name(step: u64) -> String {
    format!("checkpoints/ring_{step:09}.ckpt")
}

/// The step of a ring checkpoint named by `ring_name` (folder optional).
pub fn ring_step(name: &str) -> Option<u64> {
    let file = std::path::Path::new(name).file_name()?.to_str()?;
    file.strip_prefix("ring_")?
        .strip_suffix(".ckpt")?
        .parse()
        .ok()
}

pub struct CheckpointRing {
    dir: PathBuf,
    every: u64,
    keep_seconds: f64,
    /// Step, time and path of each ring checkpoint, oldest first.
    ring: Vec<(u64, f64, PathBuf)>,
    pinned: BTreeSet<u64>,
}

impl CheckpointRing {
    /// `every` = 0: no checkpoints.
    pub fn new(dir: PathBuf, every: u64, keep_seconds: f64) -> Self {
        CheckpointRing {
            dir,
            every,
            keep_seconds,
            ring: vec![],
            pinned: BTreeSet::new(),
        }
    }

    fn save<S: Stepper>(&mut self, run: &Run<S>) -> std::io::Result<()> {
        let step = run.step();
        let path = self.dir.join(ring_name(step));
        write_atomic(&path, &run.stepper.save(run.watches))?;
        self.ring.push((step, run.stepper.time(), path));
        Ok(())
    }

    /// The latest ring checkpoint at least `keep_seconds` older than the
    /// newest one.
    fn before_quiet_window(&self) -> Option<u64> {
        let &(_, newest, _) = self.ring.last()?;
        let at = newest - self.keep_seconds;
        self.ring
            .iter()
            .rev()
            .find(|(_, t, _)| *t <= at)
            .map(|r| r.0)
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
        let step = self.ring.last()?.0;
        self.pinned.insert(step);
        if let Some(early) = self.before_quiet_window() {
            self.pinned.insert(early);
        }
        Some(ring_name(step))
    }

    fn between_steps(&mut self, run: &Run<S>) -> std::io::Result<()> {
        if self.every == 0 || !run.step().is_multiple_of(self.every) {
            return Ok(());
        }
        self.save(run)?;
        // The oldest goes once the next one is old enough to start a quiet
        // window from.
        let newest = run.stepper.time();
        while self.ring.len() > CHECKPOINT_RING
            && (self.ring[1].1 <= newest - self.keep_seconds || self.ring.len() > MAX_RING)
        {
            let (old, _, path) = self.ring.remove(0);
            if !self.pinned.contains(&old) {
                let _ = std::fs::remove_file(path);
            }
        }
        Ok(())
    }
}
