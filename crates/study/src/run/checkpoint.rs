//! A case checkpoint: the solver's state and the monitor's memory in one
//! sealed file, so a restart continues and detects events bit for bit.

use monitor::Monitor;
use solver::checkpoint::{unseal, CheckpointError, Reader, Writer};
use solver::{Mixture, Solver};

const MAGIC: &[u8; 8] = b"KICKCASE";
const MIXTURE_MAGIC: &[u8; 8] = b"KICKCMIX";

pub fn save(solver: &Solver, monitor: &Monitor) -> Vec<u8> {
    let s = solver.checkpoint();
    let m = monitor.save_state();
    let mut w = Writer(Vec::with_capacity(s.len() + m.len() + 40));
    w.0.extend_from_slice(MAGIC);
    w.bytes(&s);
    w.bytes(&m);
    w.seal()
}

/// The step and time of a single-phase case checkpoint, without restoring it.
pub fn clock(bytes: &[u8]) -> Result<(u64, f64), CheckpointError> {
    let mut r = Reader(unseal(bytes, MAGIC)?);
    solver::checkpoint::clock(r.bytes()?)
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

/// A mixture case's checkpoint: the mixture (both phases) and each phase's
/// monitor, sealed.
pub fn save_mixture(mix: &Mixture, monitors: [&Monitor; 2]) -> Vec<u8> {
    let mut w = Writer(MIXTURE_MAGIC.to_vec());
    w.bytes(&mix.checkpoint());
    for m in monitors {
        w.bytes(&m.save_state());
    }
    w.seal()
}

/// Restores a mixture and its monitors; on error none is trusted.
pub fn load_mixture(
    bytes: &[u8],
    mix: &mut Mixture,
    monitors: [&mut Monitor; 2],
) -> Result<(), CheckpointError> {
    let mut r = Reader(unseal(bytes, MIXTURE_MAGIC)?);
    let m = r.bytes()?;
    let states = [r.bytes()?, r.bytes()?];
    r.finish()?;
    mix.restore(m)?;
    for (monitor, state) in monitors.into_iter().zip(states) {
        monitor.restore_state(state)?;
    }
    Ok(())
}
