//! The mechanisms of a kick (docs/physics.md section 4c), measured on the
//! solver's force forensics (`solver::forensics`) over an event's onset
//! window.
//!
//! Shares: share_X = sum (c_X . dv) / sum |dv|^2, the sums over the
//! window's steps and the event's particles, c_X the part of a particle's
//! velocity change that meets criterion X. The parts of the full split
//! (internal force, gravity, walls, transfer jump, and under the
//! pressure-implicit formulation its hourglass control, pressure
//! correction and velocity extrapolation, impulse, rest) add up to dv, so
//! their shares add up to 1; the mechanisms M1-M3 are subsets of them and
//! may overlap.
//!
//! - M1, small-mass node: every nodal part but gravity (internal force,
//!   walls, jump and the projection's parts) of the nodes lighter than
//!   `SMALL_NODE_SHARE` of a full node rho0 h^2 (gravity is the same at
//!   every node and is left out).
//! - M2, cell crossing: the stress parts of the particles whose cell at
//!   this step's P2G is not their cell at the previous step's (their
//!   gradients jumped; linear shapes jump, uGIMP's do not).
//! - M3, stress outlier: the stress parts of the particles whose pressure
//!   is more than `OUTLIER_SIGMAS` robust sigmas (1.4826 MAD, at least
//!   `OUTLIER_FLOOR` rho0 g h) from the median of the other particles in
//!   the 3 x 3 cells around theirs.
//! - M4, ringing (a flag with its value): the event particles' drift from
//!   the grid-interpolated velocity, sum |v_p - sum N v_i| / sum |v_p|,
//!   and its mean in m/s (the explanation divides it by sqrt(g H)).
//! - M5, time step (a flag with its value): the event's Courant number and
//!   nodal advective number, as the event logged them.

use crate::stats::median_and_mad;
use solver::forensics::{Explained, ExplainedStep};
use solver::Vec2;
use std::collections::HashMap;

/// M1: a node lighter than this share of rho0 h^2.
pub const SMALL_NODE_SHARE: f64 = 0.1;
/// M3: robust sigmas from the neighbours' median.
pub const OUTLIER_SIGMAS: f64 = 5.0;
/// M3: the robust sigma's floor, in rho0 g h (a uniform field has MAD 0).
pub const OUTLIER_FLOOR: f64 = 0.1;

/// Shares of the velocity change (see the module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Shares {
    pub internal: f64,
    pub external: f64,
    pub walls: f64,
    pub jump: f64,
    /// The pressure-implicit projection's parts (0 under explicit
    /// formulations; absent from older files).
    #[serde(default)]
    pub hourglass: f64,
    #[serde(default)]
    pub pressure_correction: f64,
    #[serde(default)]
    pub extrapolation: f64,
    /// `[[perturb]]` impulses.
    pub impulse: f64,
    pub rest: f64,
    pub small_mass_node: f64,
    pub cell_crossing: f64,
    pub stress_outlier: f64,
}

impl Shares {
    /// The full split's shares: 1 to round-off.
    pub fn split_sum(&self) -> f64 {
        self.internal
            + self.external
            + self.walls
            + self.jump
            + self.hourglass
            + self.pressure_correction
            + self.extrapolation
            + self.impulse
            + self.rest
    }

    /// Adds another sum of projections part by part.
    pub fn add(&mut self, b: &Shares) {
        self.internal += b.internal;
        self.external += b.external;
        self.walls += b.walls;
        self.jump += b.jump;
        self.hourglass += b.hourglass;
        self.pressure_correction += b.pressure_correction;
        self.extrapolation += b.extrapolation;
        self.impulse += b.impulse;
        self.rest += b.rest;
        self.small_mass_node += b.small_mass_node;
        self.cell_crossing += b.cell_crossing;
        self.stress_outlier += b.stress_outlier;
    }

    /// Sums of projections c . dv over sum |dv|^2: the shares (0 when
    /// nothing moved).
    pub fn over(&self, dv2: f64) -> Shares {
        let d = if dv2 > 0.0 { 1.0 / dv2 } else { 0.0 };
        Shares {
            internal: self.internal * d,
            external: self.external * d,
            walls: self.walls * d,
            jump: self.jump * d,
            hourglass: self.hourglass * d,
            pressure_correction: self.pressure_correction * d,
            extrapolation: self.extrapolation * d,
            impulse: self.impulse * d,
            rest: self.rest * d,
            small_mass_node: self.small_mass_node * d,
            cell_crossing: self.cell_crossing * d,
            stress_outlier: self.stress_outlier * d,
        }
    }

    /// The part of the full split with the largest share.
    pub fn largest_part(&self) -> (&'static str, f64) {
        [
            ("internal force", self.internal),
            ("gravity", self.external),
            ("walls", self.walls),
            ("transfer jump", self.jump),
            ("hourglass control", self.hourglass),
            ("pressure correction", self.pressure_correction),
            ("velocity extrapolation", self.extrapolation),
            ("impulse", self.impulse),
            ("rest (after-G2P hooks)", self.rest),
        ]
        .into_iter()
        .fold(
            ("none", f64::NEG_INFINITY),
            |a, b| if b.1 > a.1 { b } else { a },
        )
    }

    /// The mechanism among M1-M3 with the largest share.
    pub fn leading(&self) -> (&'static str, f64) {
        [
            ("M1 small-mass node", self.small_mass_node),
            ("M2 cell crossing", self.cell_crossing),
            ("M3 stress outlier", self.stress_outlier),
        ]
        .into_iter()
        .fold(
            ("none", f64::NEG_INFINITY),
            |a, b| if b.1 > a.1 { b } else { a },
        )
    }
}

/// How many of a set of explained particles meet each mechanism's
/// criterion at one step, before its velocity change: the precursors
/// (docs/physics.md section 4c), counted over the quiet window before
/// an event and in matched quiet regions of the same run.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Flags {
    pub particles: usize,
    /// M1: a stencil node lighter than `SMALL_NODE_SHARE` of a full node.
    pub light_node: usize,
    /// M2: a cell other than at the previous step's P2G.
    pub crossed: usize,
    /// M3: a stress outlier among its neighbours.
    pub outlier: usize,
    /// M4 in the quiet window: the sum over the particle-steps of the drift
    /// |v_p - sum N v_i| at P2G (m/s), the velocity the grid does not carry
    /// (absent from older files).
    #[serde(default)]
    pub drift_sum: f64,
}

impl Flags {
    pub fn add(&mut self, b: &Flags) {
        self.particles += b.particles;
        self.light_node += b.light_node;
        self.crossed += b.crossed;
        self.outlier += b.outlier;
        self.drift_sum += b.drift_sum;
    }

    /// The mean drift per particle-step (m/s); NaN when empty.
    pub fn mean_drift(&self) -> f64 {
        if self.particles == 0 {
            return f64::NAN;
        }
        self.drift_sum / self.particles as f64
    }

    /// The shares of particle-steps flagged (M1, M2, M3); NaN when empty.
    pub fn fractions(&self) -> [f64; 3] {
        let n = self.particles as f64;
        if self.particles == 0 {
            return [f64::NAN; 3];
        }
        [self.light_node, self.crossed, self.outlier].map(|k| k as f64 / n)
    }
}

/// The cancellation index of a split, sum |s_i| / |sum s_i|: 1 when every
/// part pushes the same way; above `CANCELLING` the parts mostly cancel
/// and no mechanism is named.
pub fn cancellation(s: &Shares) -> f64 {
    let parts = [
        s.internal,
        s.external,
        s.walls,
        s.jump,
        s.hourglass,
        s.pressure_correction,
        s.extrapolation,
        s.impulse,
        s.rest,
    ];
    let sum: f64 = parts.iter().sum();
    parts.iter().map(|x| x.abs()).sum::<f64>() / sum.abs()
}

/// The cancellation index above which the mechanism is undecided.
pub const CANCELLING: f64 = 2.0;

/// The share below which the largest mechanism is not named: it explains
/// too little of the velocity change (the matrix report's rule too).
pub const NAMED_SHARE: f64 = 0.1;

/// One step's c . dv per part, summed over the event's particles, with sum |dv|^2.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepParts {
    pub time: f64,
    pub dv2: f64,
    pub projected: Shares,
    /// sum |v_p - sum N v_i| / sum |v_p| over the particles (M4), v_p
    /// and v_i at the step's start (P2G).
    pub drift: f64,
    /// The mean drift |v_p - sum N v_i| itself (m/s): M4 in a velocity
    /// unit of the scene, not of the particles' own speed, which makes the
    /// ratio swell for quiet particles (absent from older files).
    #[serde(default)]
    pub drift_speed: f64,
    /// The largest |rest| / (dv's and the parts' sizes): round-off unless
    /// after-G2P hooks or impulses act (the decomposition's closure).
    pub rest_max: f64,
    /// Contributing particles that crossed a cell line, and outliers.
    pub crossers: usize,
    pub outliers: usize,
    /// The lightest stencil node's share of a full node.
    pub min_node_share: f64,
}

/// |v_p - sum N v_i| of an explained particle at P2G: its velocity that the
/// grid does not carry (M4).
fn drift(e: &Explained) -> f64 {
    let interpolated: Vec2 = e.nodes.iter().map(|n| n.interpolated).sum();
    (e.v_before - interpolated).norm()
}

/// How many distinct values `v` holds (sorted and deduplicated in place).
fn distinct(v: &mut Vec<usize>) -> usize {
    v.sort_unstable();
    v.dedup();
    v.len()
}

/// Accumulates shares over the steps of a window.
#[derive(Clone, Debug, Default)]
pub struct Mechanisms {
    origin: Vec2,
    h: f64,
    /// rho0 g h: the outlier floor's unit.
    pressure_unit: f64,
    /// Cell at the previous step's P2G, by particle id.
    previous_cell: HashMap<u32, (i64, i64)>,
    sum: Shares,
    dv2: f64,
}

impl Mechanisms {
    pub fn new(origin: Vec2, h: f64, rho0: f64, gravity: f64) -> Self {
        let g = if gravity > 0.0 { gravity } else { 9.81 };
        Mechanisms {
            origin,
            h,
            pressure_unit: rho0 * g * h,
            ..Mechanisms::default()
        }
    }

    fn cell(&self, x: Vec2) -> (i64, i64) {
        let r = (x - self.origin) / self.h;
        (r.x.floor() as i64, r.y.floor() as i64)
    }

    /// Remembers this step's cells without counting it (the step before
    /// the window: its cells are what M2 compares the first step with).
    pub fn prime(&mut self, step: &ExplainedStep) {
        self.remember_cells(step);
    }

    fn remember_cells(&mut self, step: &ExplainedStep) {
        self.previous_cell.clear();
        for (k, &id) in step.id.iter().enumerate() {
            let c = self.cell(step.x[k]);
            self.previous_cell.insert(id, c);
        }
    }

    /// The precursor flags of the explained particles `member` selects, at
    /// this step (call before `add`, which moves the cell memory on).
    pub fn flags(&self, step: &ExplainedStep, member: impl Fn(usize) -> bool) -> Flags {
        let cells: Vec<(i64, i64)> = step.x.iter().map(|&x| self.cell(x)).collect();
        let mut bins: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        for (q, &c) in cells.iter().enumerate() {
            bins.entry(c).or_default().push(q);
        }
        let mut f = Flags::default();
        for e in step.explained.iter().filter(|e| member(e.particle)) {
            f.particles += 1;
            let q = e.particle;
            if e.nodes.iter().any(|n| n.mass_share < SMALL_NODE_SHARE) {
                f.light_node += 1;
            }
            if self
                .previous_cell
                .get(&step.id[q])
                .is_some_and(|&c| c != cells[q])
            {
                f.crossed += 1;
            }
            if self.outlier(q, &cells, &bins, &step.pressure) {
                f.outlier += 1;
            }
            f.drift_sum += drift(e);
        }
        f
    }

    /// Counts one step of the window; its parts.
    pub fn add(&mut self, step: &ExplainedStep) -> StepParts {
        self.add_where(step, |_| true)
    }

    /// Counts one step of the window over the explained particles `member`
    /// selects (the others are a control's); its parts.
    pub fn add_where(&mut self, step: &ExplainedStep, member: impl Fn(usize) -> bool) -> StepParts {
        let cells: Vec<(i64, i64)> = step.x.iter().map(|&x| self.cell(x)).collect();
        let crossed = |q: usize| {
            self.previous_cell
                .get(&step.id[q])
                .is_some_and(|&c| c != cells[q])
        };
        let mut bins: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        for (q, &c) in cells.iter().enumerate() {
            bins.entry(c).or_default().push(q);
        }
        let mut outlier_cache: HashMap<usize, bool> = HashMap::new();
        let mut is_outlier = |q: usize| {
            *outlier_cache
                .entry(q)
                .or_insert_with(|| self.outlier(q, &cells, &bins, &step.pressure))
        };
        let mut out = StepParts {
            time: step.time,
            min_node_share: f64::INFINITY,
            ..StepParts::default()
        };
        let (mut crossers, mut outliers) = (vec![], vec![]);
        let (mut drift_sum, mut speed_sum, mut counted) = (0.0, 0.0, 0usize);
        for e in step.explained.iter().filter(|e| member(e.particle)) {
            if !e.dv.iter().all(|c| c.is_finite()) {
                continue; // deleted in the step
            }
            let dv = e.dv;
            out.dv2 += dv.norm_squared();
            let p = &mut out.projected;
            p.internal += e.internal().dot(&dv);
            p.external += e.external().dot(&dv);
            p.walls += e.walls().dot(&dv);
            p.jump += e.jump().dot(&dv);
            p.hourglass += e.hourglass().dot(&dv);
            p.pressure_correction += e.pressure_correction().dot(&dv);
            p.extrapolation += e.extrapolation().dot(&dv);
            p.impulse += e.impulse.dot(&dv);
            p.rest += e.rest.dot(&dv);
            for n in &e.nodes {
                out.min_node_share = out.min_node_share.min(n.mass_share);
                if n.mass_share < SMALL_NODE_SHARE {
                    p.small_mass_node += (n.own_parts() - n.external).dot(&dv);
                }
            }
            for s in &e.stresses {
                let c = (s.pressure + s.deviatoric).dot(&dv);
                if crossed(s.particle) {
                    p.cell_crossing += c;
                    crossers.push(s.particle);
                }
                if is_outlier(s.particle) {
                    p.stress_outlier += c;
                    outliers.push(s.particle);
                }
            }
            drift_sum += drift(e);
            speed_sum += e.v_before.norm();
            counted += 1;
            let size = e.dv.norm() + e.nodes.iter().map(|n| n.parts_size()).sum::<f64>();
            if size > 0.0 {
                out.rest_max = out.rest_max.max(e.rest.norm() / size);
            }
        }
        out.crossers = distinct(&mut crossers);
        out.outliers = distinct(&mut outliers);
        if speed_sum > 0.0 {
            out.drift = drift_sum / speed_sum;
        }
        if counted > 0 {
            out.drift_speed = drift_sum / counted as f64;
        }
        self.add_parts(&out);
        self.remember_cells(step);
        out
    }

    fn add_parts(&mut self, s: &StepParts) {
        self.sum.add(&s.projected);
        self.dv2 += s.dv2;
    }

    /// The window's shares so far.
    pub fn shares(&self) -> Shares {
        self.sum.over(self.dv2)
    }

    fn outlier(
        &self,
        q: usize,
        cells: &[(i64, i64)],
        bins: &HashMap<(i64, i64), Vec<usize>>,
        pressure: &[f64],
    ) -> bool {
        let (ci, cj) = cells[q];
        let mut near: Vec<f64> = vec![];
        for dj in -1..=1 {
            for di in -1..=1 {
                if let Some(list) = bins.get(&(ci + di, cj + dj)) {
                    near.extend(list.iter().filter(|&&k| k != q).map(|&k| pressure[k]));
                }
            }
        }
        if near.len() < 3 || !pressure[q].is_finite() {
            return false;
        }
        let (median, mad) = median_and_mad(&mut near);
        let sigma = (1.4826 * mad).max(OUTLIER_FLOOR * self.pressure_unit);
        (pressure[q] - median).abs() > OUTLIER_SIGMAS * sigma
    }
}
