//! The hallmark's raw figures (`[monitor] hallmark_log = true`): for every
//! particle of the cluster that opens a kick-kind event, at each of the
//! `SPEED_FACTORS` quiet speeds, how long it had been quiet, its earlier
//! peak |dev D| and when, and its distortion of F. The hallmark can then be
//! re-applied offline at other `quiet_speed`, `quiet_seconds` and
//! `deformed_rate` settings, and under either reading of "highly
//! deformed", without rerunning (docs/physics.md section 4b).

use crate::clustering::isochoric_stretch_ratio;
use crate::Monitor;
use serde::{Deserialize, Serialize};
use solver::StateView;

/// One particle of an opening cluster at one quiet speed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HallmarkRow {
    pub event: u32,
    pub particle: u32,
    /// The event's opening time (s).
    pub t: f64,
    /// The quiet speed's multiple of `quiet_speed`.
    pub speed_factor: f64,
    /// Seconds quiet before this burst at that quiet speed.
    pub quiet_for: f64,
    /// Its peak in-plane |dev D| (1/s) before the burst, and when.
    pub peak_rate: f64,
    pub peak_rate_t: f64,
    /// Largest over smallest principal stretch of F at the opening.
    pub distortion: f64,
}

impl Monitor {
    /// Logs the rows of this step's clusters that opened an event.
    pub(crate) fn log_hallmark(&mut self, v: &StateView) {
        if self.history.levels.is_empty() {
            return;
        }
        let grace = self.cfg.merge_seconds;
        for f in &self.flagged {
            let p = f.p as usize;
            let c = &self.clusters[self.cell_label[self.geom.cell_index(v.x[p])] as usize];
            if !c.opened {
                continue;
            }
            let event = self.events[c.event].id;
            let h = &self.history;
            let peak = h.peak(p);
            let distortion = isochoric_stretch_ratio(&v.deformation[p]);
            for level in &h.levels {
                let calm = level.calm(p, v.time, grace, peak);
                self.hallmark_rows.push(HallmarkRow {
                    event,
                    particle: v.id[p],
                    t: v.time,
                    speed_factor: level.factor,
                    quiet_for: calm.quiet_for,
                    peak_rate: calm.peak_rate,
                    peak_rate_t: calm.peak_rate_t,
                    distortion,
                });
            }
        }
    }

    /// The hallmark log so far (empty unless `hallmark_log`).
    pub fn hallmark_rows(&self) -> &[HallmarkRow] {
        &self.hallmark_rows
    }
}

/// The hallmark's thresholds, as the monitor's config names them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setting {
    /// Which logged quiet speed (a `SPEED_FACTORS` entry).
    pub speed_factor: f64,
    pub quiet_seconds: f64,
    pub deformed_rate: f64,
    pub distortion_ratio: f64,
}

/// The hallmark of one event re-applied to its logged rows: the shares of
/// its opening particles quiet before, deformed by strain rate, and
/// distorted (each holds for the event when at least half its particles
/// meet it, as the monitor's rule reads).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reapplied {
    pub particles: usize,
    pub quiescent: f64,
    pub deformed_rate: f64,
    pub distorted: f64,
}

impl Reapplied {
    /// Quiet before and deformed earlier (the strain-rate reading).
    pub fn hallmark(&self) -> bool {
        self.quiescent >= 0.5 && self.deformed_rate >= 0.5
    }

    /// Quiet before and distorted (the distortion reading).
    pub fn hallmark_by_distortion(&self) -> bool {
        self.quiescent >= 0.5 && self.distorted >= 0.5
    }
}

/// Re-applies the hallmark at `s` to event `event`'s rows.
pub fn reapply(rows: &[HallmarkRow], event: u32, s: &Setting) -> Reapplied {
    let mut r = Reapplied::default();
    let (mut quiet, mut deformed, mut distorted) = (0usize, 0usize, 0usize);
    for row in rows
        .iter()
        .filter(|w| w.event == event && w.speed_factor == s.speed_factor)
    {
        r.particles += 1;
        quiet += usize::from(row.quiet_for >= s.quiet_seconds);
        let before = row.peak_rate_t < row.t - s.quiet_seconds;
        deformed += usize::from(row.peak_rate >= s.deformed_rate && before);
        distorted += usize::from(row.distortion >= s.distortion_ratio);
    }
    if r.particles > 0 {
        let n = r.particles as f64;
        r.quiescent = quiet as f64 / n;
        r.deformed_rate = deformed as f64 / n;
        r.distorted = distorted as f64 / n;
    }
    r
}
