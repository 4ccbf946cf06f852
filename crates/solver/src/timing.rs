//! Wall time spent in each stage since the last reset, so benchmarks can
//! print a per-stage profile (a few clock reads per step, no allocation).

use std::time::Instant;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    pub sort: f64,
    pub p2g: f64,
    pub grid: f64,
    pub g2p: f64,
    pub stress: f64,
    /// Time step, energies and blow-out counters.
    pub other: f64,
    pub steps: u64,
}

impl StageTimes {
    pub fn total(&self) -> f64 {
        self.sort + self.p2g + self.grid + self.g2p + self.stress + self.other
    }
}

/// Adds the time since `since` to `slot` and restarts the clock.
#[inline]
pub fn lap(slot: &mut f64, since: &mut Instant) {
    let now = Instant::now();
    *slot += (now - *since).as_secs_f64();
    *since = now;
}
