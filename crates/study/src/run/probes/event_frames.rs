//! Particle frames around the first `EVENT_WINDOWS` events of a lone
//! solver: every `EVENT_FRAME_EVERY` steps, `EVENT_FRAMES` before (from a
//! ring of recent frames) to `EVENT_FRAMES` after, into `particles/event_K/`.

use crate::output::vtu::{self, Snapshot};
use crate::run::{Probe, Run, Stepper};
use solver::StateView;
use std::path::{Path, PathBuf};

const EVENT_FRAME_EVERY: u64 = 5;
const EVENT_FRAMES: usize = 4;
const EVENT_WINDOWS: usize = 8;

pub struct EventFrames {
    dir: PathBuf,
    recent: Vec<Snapshot>,
    next: usize,
    now: Snapshot,
    /// (event id, last step of its window)
    open: Vec<(u32, u64)>,
    opened: usize,
}

impl EventFrames {
    pub fn new(dir: PathBuf, particles: usize) -> Self {
        EventFrames {
            dir,
            recent: (0..EVENT_FRAMES)
                .map(|_| Snapshot::with_capacity(particles))
                .collect(),
            next: 0,
            now: Snapshot::with_capacity(particles),
            open: vec![],
            opened: 0,
        }
    }

    fn write(dir: &Path, id: u32, snap: &Snapshot) -> std::io::Result<()> {
        vtu::write_file(&dir.join(format!("event_{id}")), "particles", snap)
    }

    /// Events `ids` opened at `step`: the recent frames and this one.
    fn opened(&mut self, ids: &[u32], v: &StateView, step: u64) -> std::io::Result<()> {
        self.now.capture(v);
        for &id in ids {
            if self.opened >= EVENT_WINDOWS {
                break;
            }
            self.opened += 1;
            for f in self
                .recent
                .iter()
                .filter(|f| !f.x.is_empty() && f.step < step)
            {
                Self::write(&self.dir, id, f)?;
            }
            Self::write(&self.dir, id, &self.now)?;
            self.open
                .push((id, step + EVENT_FRAME_EVERY * EVENT_FRAMES as u64));
        }
        Ok(())
    }

    fn every_few_steps(&mut self, v: &StateView, step: u64) -> std::io::Result<()> {
        if !step.is_multiple_of(EVENT_FRAME_EVERY) {
            return Ok(());
        }
        let f = &mut self.recent[self.next];
        f.capture(v);
        self.next = (self.next + 1) % EVENT_FRAMES;
        self.open.retain(|&(_, until)| until >= step);
        for &(id, _) in &self.open {
            Self::write(&self.dir, id, f)?;
        }
        Ok(())
    }
}

impl<S: Stepper> Probe<S> for EventFrames {
    fn after_step(&mut self, run: &Run<S>, opened: &[u32]) -> std::io::Result<()> {
        let (v, step) = (run.stepper.phase(0).view(), run.step());
        if !opened.is_empty() {
            self.opened(opened, &v, step)?;
        }
        self.every_few_steps(&v, step)
    }
}
