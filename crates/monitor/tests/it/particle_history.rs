//! What the monitor remembers per particle follows deletions and appends
//! (particles that enter through an inflow wall).

use monitor::particle_history::{ParticleHistory, NEVER};

#[test]
fn compaction_keeps_survivors_and_opens_entries_for_new_particles() {
    let mut h = ParticleHistory::new(4);
    for p in 0..4 {
        h.start(p, 0.0, false, 0.0);
        h.record(p, 1.0, 0.5, true, 10.0 * p as f64);
    }
    // Particle 1 left; particles 7 and 8 entered at t = 1.5 (after the
    // observation at t = 1.0).
    h.compact(&[0, 1, 2, 3], &[0, 2, 3, 7, 8], 1.0);
    assert_eq!(h.len(), 5);
    assert_eq!(h.peak_rate, vec![0.0, 20.0, 30.0, 0.0, 0.0]);
    assert_eq!(h.activity.last_active[3], 1.0);
    assert_eq!(h.activity.active_since[4], 1.0);
    assert_eq!(h.activity.quiet_before[3], 0.0);
    assert_eq!(h.peak_rate_t[4], NEVER);
    // Moving on at entry is not a burst out of calm: no quiet spell.
    h.record(3, 1.5, 1.0, true, 0.0);
    let calm = h.calm(3, 1.5, 0.1);
    assert_eq!(calm.quiet_for, 0.0);
    // Deletions alone still compact as before.
    h.compact(&[0, 2, 3, 7, 8], &[2, 8], 1.5);
    assert_eq!(h.len(), 2);
    assert_eq!(h.peak_rate, vec![20.0, 0.0]);
}
