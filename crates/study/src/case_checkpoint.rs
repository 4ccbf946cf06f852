//! A case checkpoint: the solver's state and the monitor's memory in one
//! sealed file, so a restart continues and detects events bit for bit.

use monitor::Monitor;
use solver::checkpoint::{unseal, CheckpointError, Reader, Writer};
use solver::Solver;

const MAGIC: &[u8; 8] = b"KICKCASE";

pub fn save(solver: &Solver, monitor: &Monitor) -> Vec<u8> {
    let s = solver.checkpoint();
    let m = monitor.save_state();
    let mut w = Writer(Vec::with_capacity(s.len() + m.len() + 40));
    w.0.extend_from_slice(MAGIC);
    w.bytes(&s);
    w.bytes(&m);
    w.seal()
}

/// Restores both; on error neither is trusted.
pub fn load(
    bytes: &[u8],
    solver: &mut Solver,
    monitor: &mut Monitor,
) -> Result<(), CheckpointError> {
    let mut r = Reader(unseal(bytes, MAGIC)?);
    let s = r.bytes()?;
    let m = r.bytes()?;
    r.finish()?;
    solver.restore(s)?;
    monitor.restore_state(m)
}
