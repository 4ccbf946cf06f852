//! Particle files (VTK) at the study's times (`output.vtk_times`), and at
//! the end of the run however it ended; one file per phase.

use crate::output::vtu::{self, Snapshot};
use crate::run::{Probe, Run, Simulated, Stepper};
use std::path::{Path, PathBuf};

pub struct ParticleFiles {
    dir: PathBuf,
    times: Vec<f64>,
    next: usize,
}

impl ParticleFiles {
    pub fn new(dir: PathBuf, mut times: Vec<f64>) -> Self {
        times.sort_by(f64::total_cmp);
        ParticleFiles {
            dir,
            times,
            next: 0,
        }
    }

    /// Writes one file per time reached since the last call.
    fn catch_up<S: Stepper>(&mut self, s: &S) -> std::io::Result<()> {
        while self.next < self.times.len() && self.times[self.next] <= s.time() {
            write_phases(&self.dir, s)?;
            self.next += 1;
        }
        Ok(())
    }
}

/// Each phase's particles now, into `dir` (named by the phase, or
/// `particles` for a lone solver).
pub fn write_phases<S: Stepper>(dir: &Path, s: &S) -> std::io::Result<()> {
    for k in 0..s.phase_count() {
        let name = s.phase_name(k).unwrap_or("particles");
        vtu::write_file(dir, name, &Snapshot::of(&s.phase(k).view()))?;
    }
    Ok(())
}

impl<S: Stepper> Probe<S> for ParticleFiles {
    fn begin(&mut self, run: &Run<S>) -> std::io::Result<()> {
        self.catch_up(run.stepper)
    }

    fn between_steps(&mut self, run: &Run<S>) -> std::io::Result<()> {
        self.catch_up(run.stepper)
    }

    fn finish(&mut self, run: &Run<S>, _: &mut Simulated) -> std::io::Result<()> {
        write_phases(&self.dir, run.stepper)
    }
}
