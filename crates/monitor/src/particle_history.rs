//! What the monitor remembers of each particle, in seconds (dt differs 80x
//! across the bug-report matrix): when it was last active (faster than `quiet_speed` or
//! deforming faster than `quiet_rate`), how long it had been quiet before
//! its current active stretch, and its running maximum of the in-plane
//! |dev D| with the time reached, also as it stood when that stretch began.

/// Time marker for "never".
pub const NEVER: f64 = f64::NEG_INFINITY;

#[derive(Clone, Debug, PartialEq)]
pub struct ParticleHistory {
    /// When it was last active, since when, the quiet spell before, and the
    /// peak as it stood then, at `quiet_speed` itself.
    pub activity: LevelHistory,
    /// Running maximum of the in-plane |dev D| (1/s) and when it was reached.
    pub peak_rate: Vec<f64>,
    pub peak_rate_t: Vec<f64>,
    /// The same activity memory at other quiet speeds (`[monitor]
    /// hallmark_log`): the hallmark re-thresholded offline. Empty unless logged.
    pub levels: Vec<LevelHistory>,
}

/// The quiet speeds the hallmark log follows, as multiples of `quiet_speed`:
/// a factor of 3 each way.
pub const SPEED_FACTORS: [f64; 5] = [
    1.0 / 3.0,
    0.577_350_269_189_625_8,
    1.0,
    1.732_050_807_568_877_2,
    3.0,
];

/// One quiet speed's activity memory; the running peak |dev D| is
/// `ParticleHistory`'s, shared by every quiet speed.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelHistory {
    /// The quiet speed's multiple of `quiet_speed`.
    pub factor: f64,
    /// Last time the particle was active.
    pub last_active: Vec<f64>,
    /// Start of its current (or last) active stretch.
    pub active_since: Vec<f64>,
    /// Length of the quiet spell that ended at `active_since` (infinite when
    /// it had never been active before).
    pub quiet_before: Vec<f64>,
    /// The running peak and its time as they stood at `active_since`.
    pub settled_peak: Vec<f64>,
    pub settled_peak_t: Vec<f64>,
}

impl LevelHistory {
    pub fn new(n: usize, factor: f64) -> Self {
        LevelHistory {
            factor,
            last_active: vec![NEVER; n],
            active_since: vec![NEVER; n],
            quiet_before: vec![f64::INFINITY; n],
            settled_peak: vec![0.0; n],
            settled_peak_t: vec![NEVER; n],
        }
    }

    /// Active at `t` with no quiet spell before it: nothing is known of
    /// the time before the first observation.
    fn start(&mut self, p: usize, t0: f64) {
        self.last_active[p] = t0;
        self.active_since[p] = t0;
        self.quiet_before[p] = 0.0;
    }

    /// Records particle `p` at time `t`; `prev_t` is the time of the
    /// previous observation (an active particle then has `last_active ==
    /// prev_t`); `peak` is the running peak before this observation's rate.
    #[inline(always)]
    pub fn record(&mut self, p: usize, t: f64, prev_t: f64, active: bool, peak: (f64, f64)) {
        if active {
            if self.last_active[p] != prev_t {
                self.quiet_before[p] = t - self.last_active[p];
                self.active_since[p] = t;
                self.settled_peak[p] = peak.0;
                self.settled_peak_t[p] = peak.1;
            }
            self.last_active[p] = t;
        }
    }

    /// The calm of particle `p` before a burst seen at time `t` (after
    /// `record`), `peak` the running peak now. A burst that began within
    /// `grace` seconds counts from its start, so a kick caught a few steps
    /// late still finds the quiet before it.
    pub fn calm(&self, p: usize, t: f64, grace: f64, peak: (f64, f64)) -> Calm {
        if self.last_active[p] == t {
            let recent = t - self.active_since[p] <= grace;
            Calm {
                quiet_for: if recent { self.quiet_before[p] } else { 0.0 },
                peak_rate: self.settled_peak[p],
                peak_rate_t: self.settled_peak_t[p],
            }
        } else {
            Calm {
                quiet_for: t - self.last_active[p],
                peak_rate: peak.0,
                peak_rate_t: peak.1,
            }
        }
    }

    /// Its arrays, each sized to the kept particles (see `compact_array`),
    /// new entries active since `t`.
    fn compact(&mut self, old_ids: &[u32], new_ids: &[u32], kept: usize, t: f64) {
        for (a, fill) in self.arrays_mut().into_iter().zip([t, t, 0.0, 0.0, NEVER]) {
            compact_array(a, old_ids, new_ids, kept, fill);
        }
    }

    fn arrays_mut(&mut self) -> [&mut Vec<f64>; 5] {
        [
            &mut self.last_active,
            &mut self.active_since,
            &mut self.quiet_before,
            &mut self.settled_peak,
            &mut self.settled_peak_t,
        ]
    }

    fn arrays(&self) -> [&Vec<f64>; 5] {
        [
            &self.last_active,
            &self.active_since,
            &self.quiet_before,
            &self.settled_peak,
            &self.settled_peak_t,
        ]
    }
}

/// Moves `v`'s entries of the particles kept (the first `kept` of
/// `new_ids`, found in `old_ids`; both in id order) down to their new slots
/// and sizes it to `new_ids`, new entries set to `fill`. Allocates nothing.
fn compact_array(v: &mut Vec<f64>, old_ids: &[u32], new_ids: &[u32], kept: usize, fill: f64) {
    let mut from = 0;
    for (to, &id) in new_ids[..kept].iter().enumerate() {
        while old_ids[from] != id {
            from += 1;
        }
        v[to] = v[from];
        from += 1;
    }
    v.truncate(kept);
    v.resize(new_ids.len(), fill);
}

/// A particle's quiet spell and earlier peak |dev D| as seen at an onset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calm {
    /// Seconds it had been quiet before this burst began.
    pub quiet_for: f64,
    pub peak_rate: f64,
    pub peak_rate_t: f64,
}

impl ParticleHistory {
    pub fn new(n: usize) -> Self {
        ParticleHistory {
            activity: LevelHistory::new(n, 1.0),
            peak_rate: vec![0.0; n],
            peak_rate_t: vec![NEVER; n],
            levels: vec![],
        }
    }

    /// Follows the `SPEED_FACTORS` quiet speeds too (the hallmark log);
    /// `active(factor, p)` is particle p's activity at the first observation.
    pub fn with_levels(mut self, t0: f64, active: impl Fn(f64, usize) -> bool) -> Self {
        let n = self.len();
        self.levels = SPEED_FACTORS
            .iter()
            .map(|&f| {
                let mut level = LevelHistory::new(n, f);
                for p in (0..n).filter(|&p| active(f, p)) {
                    level.start(p, t0);
                }
                level
            })
            .collect();
        self
    }

    /// The particles it follows.
    pub fn len(&self) -> usize {
        self.peak_rate.len()
    }

    pub fn is_empty(&self) -> bool {
        self.peak_rate.is_empty()
    }

    /// The state at the first observation (t = `t0`): a particle already
    /// active (a body given an initial velocity) is active since t0 with no
    /// quiet spell before it: nothing is known of the time before t0.
    pub fn start(&mut self, p: usize, t0: f64, active: bool, rate: f64) {
        if active {
            self.activity.start(p, t0);
        }
        if rate > 0.0 {
            self.peak_rate[p] = rate;
            self.peak_rate_t[p] = t0;
        }
    }

    /// The running peak of particle `p` and its time.
    #[inline(always)]
    pub fn peak(&self, p: usize) -> (f64, f64) {
        (self.peak_rate[p], self.peak_rate_t[p])
    }

    /// Records particle `p` at time `t` (see `LevelHistory::record`), then
    /// its rate into the running peak.
    #[inline(always)]
    pub fn record(&mut self, p: usize, t: f64, prev_t: f64, active: bool, rate: f64) {
        let peak = self.peak(p);
        self.activity.record(p, t, prev_t, active, peak);
        if rate > self.peak_rate[p] {
            self.peak_rate[p] = rate;
            self.peak_rate_t[p] = t;
        }
    }

    /// Records particle `p` at the hallmark log's quiet speeds (before
    /// `record`, which moves the peak on); `active(factor)` is its activity
    /// at `factor` times `quiet_speed`. Nothing unless logged.
    #[inline(always)]
    pub fn record_levels(&mut self, p: usize, t: f64, prev_t: f64, active: impl Fn(f64) -> bool) {
        let peak = self.peak(p);
        for level in &mut self.levels {
            level.record(p, t, prev_t, active(level.factor), peak);
        }
    }

    /// The calm of particle `p` before a burst seen at time `t` (after
    /// `record`; see `LevelHistory::calm`).
    pub fn calm(&self, p: usize, t: f64, grace: f64) -> Calm {
        self.activity.calm(p, t, grace, self.peak(p))
    }

    /// Keeps the entries of the particles still present and opens entries
    /// for new ones: `old_ids` were the ids per slot before, `new_ids` after
    /// deletions and appends (both in id order; an appended particle has a
    /// larger id than any before it). A new particle (one that entered
    /// through an inflow wall at `t`) starts active at `t` with no quiet
    /// spell before it, as an already moving body does at t = 0: its entry
    /// is not a burst out of calm.
    pub fn compact(&mut self, old_ids: &[u32], new_ids: &[u32], t: f64) {
        let kept = new_ids
            .iter()
            .take_while(|&&id| old_ids.last().is_some_and(|&last| id <= last))
            .count();
        compact_array(&mut self.peak_rate, old_ids, new_ids, kept, 0.0);
        compact_array(&mut self.peak_rate_t, old_ids, new_ids, kept, NEVER);
        self.activity.compact(old_ids, new_ids, kept, t);
        for level in &mut self.levels {
            level.compact(old_ids, new_ids, kept, t);
        }
    }

    /// The levels' arrays, in checkpoint order (after `arrays`).
    pub fn level_arrays(&self) -> Vec<&Vec<f64>> {
        self.levels.iter().flat_map(|l| l.arrays()).collect()
    }

    pub fn level_arrays_mut(&mut self) -> Vec<&mut Vec<f64>> {
        self.levels
            .iter_mut()
            .flat_map(|l| l.arrays_mut())
            .collect()
    }

    /// Every array, in checkpoint order.
    pub fn arrays_mut(&mut self) -> [&mut Vec<f64>; 7] {
        let a = &mut self.activity;
        [
            &mut a.last_active,
            &mut a.active_since,
            &mut a.quiet_before,
            &mut self.peak_rate,
            &mut self.peak_rate_t,
            &mut a.settled_peak,
            &mut a.settled_peak_t,
        ]
    }

    pub fn arrays(&self) -> [&Vec<f64>; 7] {
        let a = &self.activity;
        [
            &a.last_active,
            &a.active_since,
            &a.quiet_before,
            &self.peak_rate,
            &self.peak_rate_t,
            &a.settled_peak,
            &a.settled_peak_t,
        ]
    }
}
