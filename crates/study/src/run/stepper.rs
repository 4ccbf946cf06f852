//! What the run loop steps: one solver, or a mixture of a solid and a
//! fluid phase stepped together.

use super::Watch;
use crate::run::checkpoint;
use solver::checkpoint::CheckpointError;
use solver::{Mixture, Phase, Solver};

pub trait Stepper {
    /// One step; Err: why the run cannot go on ("step N: ...").
    fn advance(&mut self) -> Result<(), String>;
    fn finished(&self) -> bool;
    fn step_count(&self) -> u64;
    fn time(&self) -> f64;
    fn state_hash(&self) -> u64;
    fn phase_count(&self) -> usize;
    fn phase(&self, k: usize) -> &Solver;
    /// A phase's name in events and file names; None for a lone solver.
    fn phase_name(&self, k: usize) -> Option<&'static str>;
    /// The phase whose timeseries stands for the run in its summary.
    fn primary_phase(&self) -> usize;
    /// A phase's timeseries file stem.
    fn timeseries_stem(&self, k: usize) -> String;
    /// A checkpoint of the state and the monitors' memory.
    fn save(&self, watches: &[Watch]) -> Vec<u8>;
    /// Restores both; on error neither is trusted.
    fn load(&mut self, bytes: &[u8], watches: &mut [Watch]) -> Result<(), CheckpointError>;
}

impl Stepper for Solver {
    fn advance(&mut self) -> Result<(), String> {
        self.step()
            .map_err(|e| format!("step {}: {e}", self.step_count() + 1))
    }
    fn finished(&self) -> bool {
        Solver::finished(self)
    }
    fn step_count(&self) -> u64 {
        Solver::step_count(self)
    }
    fn time(&self) -> f64 {
        Solver::time(self)
    }
    fn state_hash(&self) -> u64 {
        Solver::state_hash(self)
    }
    fn phase_count(&self) -> usize {
        1
    }
    fn phase(&self, _k: usize) -> &Solver {
        self
    }
    fn phase_name(&self, _k: usize) -> Option<&'static str> {
        None
    }
    fn primary_phase(&self) -> usize {
        0
    }
    fn timeseries_stem(&self, _k: usize) -> String {
        "timeseries".into()
    }
    fn save(&self, watches: &[Watch]) -> Vec<u8> {
        checkpoint::save(self, &watches[0].monitor)
    }
    fn load(&mut self, bytes: &[u8], watches: &mut [Watch]) -> Result<(), CheckpointError> {
        checkpoint::load(bytes, self, &mut watches[0].monitor)
    }
}

fn phase_of(k: usize) -> Phase {
    Phase::ALL[k]
}

impl Stepper for Mixture {
    fn advance(&mut self) -> Result<(), String> {
        self.step()
            .map_err(|e| format!("step {}: {e}", self.phase(0).step_count() + 1))
    }
    fn finished(&self) -> bool {
        self.phase(0).finished()
    }
    fn step_count(&self) -> u64 {
        self.phase(0).step_count()
    }
    fn time(&self) -> f64 {
        Mixture::time(self)
    }
    fn state_hash(&self) -> u64 {
        Mixture::state_hash(self)
    }
    fn phase_count(&self) -> usize {
        Phase::ALL.len()
    }
    fn phase(&self, k: usize) -> &Solver {
        Mixture::phase(self, k)
    }
    fn phase_name(&self, k: usize) -> Option<&'static str> {
        Some(phase_of(k).name())
    }
    fn primary_phase(&self) -> usize {
        Phase::Fluid.index()
    }
    fn timeseries_stem(&self, k: usize) -> String {
        match phase_of(k) {
            Phase::Fluid => "timeseries".into(),
            Phase::Solid => "timeseries_solid".into(),
        }
    }
    fn save(&self, watches: &[Watch]) -> Vec<u8> {
        checkpoint::save_mixture(self, [&watches[0].monitor, &watches[1].monitor])
    }
    fn load(&mut self, bytes: &[u8], watches: &mut [Watch]) -> Result<(), CheckpointError> {
        // A mixture's runner has a watch per phase.
        let (solid, fluid) = watches.split_at_mut(1);
        checkpoint::load_mixture(bytes, self, [&mut solid[0].monitor, &mut fluid[0].monitor])
    }
}
