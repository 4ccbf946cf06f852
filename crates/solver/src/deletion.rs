//! Cull stage (end of step): deletes the particles that left the box,
//! inverted or hold a non-finite state when the scene says so (`on_escape`
//! / `on_inversion` / `on_nonfinite = "delete"`, Uintah's behaviour),
//! keeping id order, and counts them. Under
//! "stop" nothing is deleted: the monitor sees the particle and stops the run.
//! A particle past an open side of the box (a drained wall) has flowed out:
//! it is always deleted and counted apart, as outflow, not as a loss.

use crate::config::{JUpdate, OnLoss, Scene};
use crate::particles::{Particles, Vec2};
use serde::{Deserialize, Serialize};

/// Why a particle was deleted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CullReason {
    /// Outside the box on a non-periodic axis.
    Escaped,
    /// J <= 0 or not a number, det F <= 0, or J above `scene.max_j`.
    Inverted,
    /// Flowed out through an open side (a drained wall).
    Drained,
    /// Its position, velocity, J, pressure, stress or stored energy is not
    /// a finite number (`on_nonfinite = "delete"`); counted with the
    /// escaped, as Uintah's relocation drops it like a particle that left
    /// the domain.
    NonFinite,
}

/// A particle deleted at the last step, as it was when deleted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Culled {
    pub id: u32,
    pub x: Vec2,
    pub v: Vec2,
    pub mass: f64,
    pub reason: CullReason,
}

/// Particles deleted since t = 0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Losses {
    pub escaped: u64,
    pub inverted: u64,
    pub mass_escaped: f64,
    pub mass_inverted: f64,
    /// Time of the first loss (None while none; outflow is not a loss).
    pub t_first: Option<f64>,
    /// Outflow through open sides: not counted by `count` or `mass`.
    #[serde(default)]
    pub drained: u64,
    #[serde(default)]
    pub mass_drained: f64,
    /// Inflow: particles appended through inflow walls (not losses either).
    #[serde(default)]
    pub injected: u64,
    #[serde(default)]
    pub mass_injected: f64,
}

impl Losses {
    /// Particles lost (escaped or inverted; outflow excluded).
    pub fn count(&self) -> u64 {
        self.escaped + self.inverted
    }

    pub fn mass(&self) -> f64 {
        self.mass_escaped + self.mass_inverted
    }
}

/// Which deletions are on for a scene (None when both are "stop" and no
/// side is open).
#[derive(Clone, Copy, Debug)]
pub struct CullRules {
    escape: bool,
    inversion: bool,
    nonfinite: bool,
    /// Open sides [axis][low, high]: outflow.
    open: [[bool; 2]; 2],
    /// det F is checked apart from J (the exp J update keeps J > 0).
    det_apart: bool,
    /// J beyond which a particle counts as degenerate (`scene.max_j`).
    max_j: f64,
    lo: Vec2,
    hi: Vec2,
    periodic: [bool; 2],
}

impl CullRules {
    pub fn of(scene: &Scene, j_update: JUpdate, open: [[bool; 2]; 2]) -> Option<Self> {
        let escape = scene.on_escape == OnLoss::Delete;
        let inversion = scene.on_inversion == OnLoss::Delete;
        let nonfinite = scene.on_nonfinite == OnLoss::Delete;
        let lo = Vec2::from(scene.origin);
        let any_open = open.iter().flatten().any(|&o| o);
        (escape || inversion || nonfinite || any_open).then_some(CullRules {
            escape,
            inversion,
            nonfinite,
            open,
            det_apart: j_update == JUpdate::Exp,
            max_j: scene.max_j.unwrap_or(f64::INFINITY),
            lo,
            hi: lo + Vec2::from(scene.size),
            periodic: scene.periodic,
        })
    }

    fn reason(&self, ps: &Particles, p: usize) -> Option<CullReason> {
        // Inversion first, as the monitor judges it: an inverted particle
        // often leaves the box in the same step.
        // A J that is not a number too, as Uintah's Water model's !(J > 0).
        let j = ps.j[p];
        let degenerate = j <= 0.0
            || j.is_nan()
            || j > self.max_j
            || (self.det_apart && ps.f[p].determinant() <= 0.0);
        if self.inversion && degenerate {
            return Some(CullReason::Inverted);
        }
        if self.nonfinite && !finite_state(ps, p) {
            return Some(CullReason::NonFinite);
        }
        let x = ps.x[p];
        let past_open = |k: usize| {
            (self.open[k][0] && x[k] < self.lo[k]) || (self.open[k][1] && x[k] > self.hi[k])
        };
        if past_open(0) || past_open(1) {
            return Some(CullReason::Drained);
        }
        // A non-finite position is not an escape: the monitor stops the run
        // on it unless `on_nonfinite = "delete"` took it above.
        if self.escape
            && (0..2).any(|k| !self.periodic[k] && (x[k] < self.lo[k] || x[k] > self.hi[k]))
        {
            return Some(CullReason::Escaped);
        }
        None
    }
}

/// Position, velocity, J, pressure, stress and stored energy all finite
/// (what the measures sum and the monitor checks).
fn finite_state(ps: &Particles, p: usize) -> bool {
    let (x, v) = (ps.x[p], ps.v[p]);
    x.iter().chain(v.iter()).all(|c| c.is_finite())
        && ps.j[p].is_finite()
        && ps.pressure[p].is_finite()
        && ps.stored_energy[p].is_finite()
        && ps.stress[p].iter().all(|s| s.is_finite())
}

/// Deletes the particles `rules` select; `culled` receives them (cleared
/// first, its capacity reserved for every particle so that it never grows).
pub fn cull(
    ps: &mut Particles,
    rules: &CullRules,
    time: f64,
    losses: &mut Losses,
    culled: &mut Vec<Culled>,
) -> usize {
    culled.clear();
    if !(0..ps.len()).any(|p| rules.reason(ps, p).is_some()) {
        return 0;
    }
    let deleted = ps.retain(|ps, p| match rules.reason(ps, p) {
        None => true,
        Some(reason) => {
            culled.push(Culled {
                id: ps.id[p],
                x: ps.x[p],
                v: ps.v[p],
                mass: ps.mass[p],
                reason,
            });
            false
        }
    });
    for c in culled.iter() {
        match c.reason {
            CullReason::Escaped | CullReason::NonFinite => {
                losses.escaped += 1;
                losses.mass_escaped += c.mass;
            }
            CullReason::Inverted => {
                losses.inverted += 1;
                losses.mass_inverted += c.mass;
            }
            CullReason::Drained => {
                losses.drained += 1;
                losses.mass_drained += c.mass;
            }
        }
    }
    if culled.iter().any(|c| c.reason != CullReason::Drained) {
        losses.t_first.get_or_insert(time);
    }
    deleted
}
