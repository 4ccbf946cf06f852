//! What the monitor remembers of each particle: its recent kinetic-energy
//! maximum (decaying), the last step it moved faster than the quiescent
//! speed, and its deviatoric strain-rate history (running maximum with its
//! step, and the last step it was above the deformation threshold).

/// Step marker for "never".
pub const NEVER: i64 = i64::MIN / 2;

#[derive(Clone, Debug, PartialEq)]
pub struct ParticleHistory {
    pub ke_recent: Vec<f64>,
    pub last_fast_step: Vec<i64>,
    pub last_deformed_step: Vec<i64>,
    /// Running maximum of |dev D| (written each step and checkpointed; not read yet, kept for a later issue).
    pub max_dev_rate: Vec<f64>,
    /// Step of `max_dev_rate` (written each step and checkpointed; not read yet, kept for a later issue).
    pub max_dev_rate_step: Vec<i64>,
}

impl ParticleHistory {
    pub fn new(n: usize) -> Self {
        ParticleHistory {
            ke_recent: vec![0.0; n],
            last_fast_step: vec![NEVER; n],
            last_deformed_step: vec![NEVER; n],
            max_dev_rate: vec![0.0; n],
            max_dev_rate_step: vec![NEVER; n],
        }
    }
}
