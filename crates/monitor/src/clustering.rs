//! Event clustering: this step's flagged particles grouped by 8-adjacent
//! cells, each group merged into an open event of its kind nearby or
//! opening one, with the hallmark tallies (quiet before, deformed).

use crate::events::{
    Cause, CellRange, DeformedBy, Event, EventKind, Evidence, Outcome, Rule, Rules,
};
use crate::{particle_history, Monitor};
use solver::{Mat2, StateView};

/// A cell not yet labelled by `label_clusters`.
pub(crate) const UNLABELLED: u32 = u32::MAX;

#[derive(Clone, Debug)]
pub(crate) struct Cluster {
    pub(crate) cells: CellRange,
    pub(crate) rules: Rules,
    pub(crate) peak_accel: f64,
    pub(crate) peak_jump: f64,
    /// Its particles whose local flow was calm.
    pub(crate) calm_flow: usize,
    pub(crate) quiescent: usize,
    pub(crate) deformed_rate: usize,
    pub(crate) distorted: usize,
    pub(crate) count: usize,
    pub(crate) event: usize,
    /// Largest earlier peak |dev D| of its particles, and when.
    pub(crate) peak_rate: f64,
    pub(crate) peak_rate_t: f64,
    pub(crate) j_min: f64,
    /// Largest speed of its particles at the start of the step.
    pub(crate) speed_before: f64,
    /// Largest transfer jump of its particles this step (m/s).
    pub(crate) transfer_jump: f64,
    /// It opened its event this step (else it joined one, or none).
    pub(crate) opened: bool,
}

impl Cluster {
    /// A cluster over `cells` with no particles tallied yet.
    pub(crate) fn new(cells: CellRange, rules: Rules, peak_accel: f64) -> Self {
        Cluster {
            cells,
            rules,
            peak_accel,
            peak_jump: 0.0,
            calm_flow: 0,
            quiescent: 0,
            deformed_rate: 0,
            distorted: 0,
            count: 0,
            event: 0,
            peak_rate: 0.0,
            peak_rate_t: particle_history::NEVER,
            j_min: f64::INFINITY,
            speed_before: 0.0,
            transfer_jump: 0.0,
            opened: false,
        }
    }
}

impl Monitor {
    /// Clusters this step's flagged particles by 8-adjacent cells and files them as kicks.
    pub(crate) fn cluster_flagged(&mut self, v: &StateView, g: f64) {
        self.label_clusters(v);
        self.tally_clusters(v);
        for k in 0..self.clusters.len() {
            let cluster = self.clusters[k].clone();
            let before = self.events.len();
            self.clusters[k].event = if cluster.count >= self.cfg.min_cluster_particles {
                self.attach(EventKind::Kick, cluster, v, g, false)
            } else {
                usize::MAX
            };
            self.clusters[k].opened = self.events.len() > before;
        }
        self.count_members(v);
        self.log_hallmark(v);
    }

    /// Labels the cells holding flagged particles by 8-connected component,
    /// one empty cluster per component (`cell_label` holds its index).
    fn label_clusters(&mut self, v: &StateView) {
        let nx = self.geom.cells[0];
        let ny = self.geom.cells[1];
        for &c in &self.touched {
            self.cell_label[c as usize] = UNLABELLED;
        }
        self.touched.clear();
        // Mark flagged cells with a placeholder label.
        const FLAGGED: u32 = u32::MAX - 1;
        for f in &self.flagged {
            let c = self.geom.cell_index(v.x[f.p as usize]);
            if self.cell_label[c] == UNLABELLED {
                self.cell_label[c] = FLAGGED;
                self.touched.push(c as u32);
            }
        }
        self.clusters.clear();
        for k in 0..self.touched.len() {
            let seed = self.touched[k] as usize;
            if self.cell_label[seed] != FLAGGED {
                continue;
            }
            let label = self.clusters.len() as u32;
            let (si, sj) = (seed % nx, seed / nx);
            let mut cells = CellRange::of(si, sj);
            self.cell_label[seed] = label;
            self.stack.clear();
            self.stack.push(seed as u32);
            while let Some(c) = self.stack.pop() {
                let (i, j) = (c as usize % nx, c as usize / nx);
                cells = cells.union(&CellRange::of(i, j));
                for j2 in j.saturating_sub(1)..=(j + 1).min(ny - 1) {
                    for i2 in i.saturating_sub(1)..=(i + 1).min(nx - 1) {
                        let c2 = i2 + j2 * nx;
                        if self.cell_label[c2] == FLAGGED {
                            self.cell_label[c2] = label;
                            self.stack.push(c2 as u32);
                        }
                    }
                }
            }
            self.clusters.push(Cluster::new(cells, Rules::NONE, 0.0));
        }
    }

    /// Tallies each flagged particle into its cluster: rules, peaks, count and
    /// the hallmark counts (quiet, deformed, distorted before this step).
    fn tally_clusters(&mut self, v: &StateView) {
        let (quiet, quiet_start) = (self.cfg.quiet_seconds, v.time - self.cfg.quiet_seconds);
        for f in &self.flagged {
            let p = f.p as usize;
            let label = self.cell_label[self.geom.cell_index(v.x[p])] as usize;
            let c = &mut self.clusters[label];
            c.rules.insert(Rule::VelocityJump);
            c.peak_accel = c.peak_accel.max(f.a);
            c.peak_jump = c.peak_jump.max(f.jump);
            c.calm_flow += usize::from(f.calm_flow);
            c.count += 1;
            c.j_min = c.j_min.min(v.j[p]);
            c.speed_before = c.speed_before.max(v.v_prev[p].norm());
            let flip = v.v_prev[p] + v.dt * v.accel[p];
            c.transfer_jump = c.transfer_jump.max((v.v[p] - flip).norm());
            if f.calm.quiet_for >= quiet {
                c.quiescent += 1;
            }
            if f.calm.peak_rate >= self.cfg.deformed_rate && f.calm.peak_rate_t < quiet_start {
                c.deformed_rate += 1;
            }
            if f.calm.peak_rate > c.peak_rate {
                c.peak_rate = f.calm.peak_rate;
                c.peak_rate_t = f.calm.peak_rate_t;
            }
            if isochoric_stretch_ratio(&v.deformation[p]) >= self.cfg.distortion_ratio {
                c.distorted += 1;
            }
        }
    }

    /// Counts each flagged particle once into its cluster's event, keeping the
    /// first `max_event_ids` ids.
    fn count_members(&mut self, v: &StateView) {
        let cap = self.cfg.max_event_ids;
        for f in &self.flagged {
            let p = f.p as usize;
            let label = self.cell_label[self.geom.cell_index(v.x[p])] as usize;
            let event = self.clusters[label].event;
            if event == usize::MAX {
                continue;
            }
            let e = &mut self.events[event];
            let id = v.id[p] as usize;
            if self.event_mark[id] != e.id {
                self.event_mark[id] = e.id;
                e.n_particles += 1;
                if e.particles.len() < cap {
                    e.particles.push(v.id[p]);
                }
            }
        }
    }

    /// Merges a cluster into an open event of the same kind nearby, or opens
    /// one; usize::MAX when the event store is full.
    pub(crate) fn attach(
        &mut self,
        kind: EventKind,
        c: Cluster,
        v: &StateView,
        g: f64,
        stops: bool,
    ) -> usize {
        let step = v.step;
        let open = self.events.iter().rposition(|e| {
            e.kind == kind
                && (e.last_step + 1 >= step || v.time - e.last_t <= self.cfg.merge_seconds)
                && e.extent.near(&c.cells, self.cfg.merge_cells)
        });
        // The event that stops a run is always stored.
        if open.is_none() && !stops && self.events.len() >= self.cfg.max_events {
            self.events_dropped += 1;
            return usize::MAX;
        }
        match open {
            Some(k) => {
                self.merge(k, &c, v, g);
                k
            }
            None => {
                self.open(kind, &c, v, g);
                self.events.len() - 1
            }
        }
    }

    /// Extends open event `k` by this step's cluster.
    fn merge(&mut self, k: usize, c: &Cluster, v: &StateView, g: f64) {
        let e = &mut self.events[k];
        e.last_step = v.step;
        e.last_t = v.time;
        e.extent = e.extent.union(&c.cells);
        if e.first_step == v.step {
            e.cells = e.cells.union(&c.cells);
            e.region = e.cells.metres(&self.geom);
        }
        e.peak_accel_g = e.peak_accel_g.max(c.peak_accel / g);
        e.jump_speed = e.jump_speed.max(c.peak_jump);
        e.rules = e.rules.union(c.rules);
    }

    /// Opens an event for the cluster; a hallmark holds for at least half its particles.
    fn open(&mut self, kind: EventKind, c: &Cluster, v: &StateView, g: f64) {
        let half = |k: usize| c.count > 0 && 2 * k >= c.count;
        let fraction = |k: usize| {
            if c.count > 0 {
                k as f64 / c.count as f64
            } else {
                0.0
            }
        };
        let mut deformed_by = vec![];
        if half(c.deformed_rate) {
            deformed_by.push(DeformedBy::StrainRate);
        }
        if half(c.distorted) {
            deformed_by.push(DeformedBy::Distortion);
        }
        let (courant_before, advection_before) =
            self.steps.max_since(v.time - self.cfg.merge_seconds);
        let mut event = Event {
            id: self.events.len() as u32 + 1,
            kind,
            first_step: v.step,
            last_step: v.step,
            t: v.time,
            last_t: v.time,
            cells: c.cells,
            region: c.cells.metres(&self.geom),
            extent: c.cells,
            n_particles: 0,
            particles: Vec::new(),
            peak_accel_g: c.peak_accel / g,
            jump_speed: c.peak_jump,
            energy_injected: 0.0,
            courant: v.courant,
            quiescent_before: half(c.quiescent),
            deformed_by,
            rules: c.rules,
            cause: Cause::Impact,
            evidence: Evidence {
                courant_before,
                advection_before,
                critical_courant: self.critical_courant,
                energy_floor: 0.0,
                booked_added: Default::default(),
                calm_flow_fraction: fraction(c.calm_flow),
                quiescent_fraction: fraction(c.quiescent),
                deformed_fraction: fraction(c.deformed_rate),
                peak_dev_rate: c.peak_rate,
                t_peak_dev_rate: c.peak_rate_t.is_finite().then_some(c.peak_rate_t),
                j_min: c.j_min.is_finite().then_some(c.j_min),
                speed_before: c.speed_before,
                transfer_jump: c.transfer_jump,
            },
            outcome: Outcome::Recovered,
            state_hash: None,
            checkpoint: None,
            phase: None,
        };
        event.classify();
        self.events.push(event);
    }

    pub(crate) fn blow_out_event(
        &mut self,
        kind: EventKind,
        rule: Rule,
        v: &StateView,
        (g, stops): (f64, bool),
        bad: impl Fn(usize) -> bool,
    ) {
        self.fill_accel(v);
        let mut cells: Option<CellRange> = None;
        let mut count = 0;
        let mut peak = 0.0f64;
        for p in 0..v.x.len() {
            if bad(p) {
                let (i, j) = self.geom.cell_of(v.x[p]);
                cells = Some(cells.map_or(CellRange::of(i, j), |c| c.union(&CellRange::of(i, j))));
                count += 1;
                if self.accel[p].is_finite() {
                    peak = peak.max(self.accel[p]);
                }
            }
        }
        let Some(cells) = cells else { return };
        let k = self.attach(kind, Cluster::new(cells, rule.into(), peak), v, g, stops);
        // An event that does not stop the run obeys `max_events`.
        if k == usize::MAX {
            return;
        }
        let cap = self.cfg.max_event_ids;
        let e = &mut self.events[k];
        e.n_particles = e.n_particles.max(count);
        for p in 0..v.x.len() {
            if e.particles.len() >= cap {
                break;
            }
            if bad(p) && !e.particles.contains(&v.id[p]) {
                e.particles.push(v.id[p]);
            }
        }
    }

    /// Events for the particles the solver deleted at this step (escaped:
    /// `blow_out`, inverted: `inversion`, non-finite: `non_finite`), by
    /// where they were; the run goes on. A non-finite position places
    /// nothing: an event of such particles alone spans the box.
    pub(crate) fn culled_events(&mut self, v: &StateView, g: f64) {
        use solver::CullReason;
        let kinds = [
            (CullReason::Escaped, EventKind::BlowOut, Rule::OutsideBox),
            (CullReason::Inverted, EventKind::Inversion, Rule::Inversion),
            (CullReason::NonFinite, EventKind::NonFinite, Rule::NonFinite),
        ];
        for (reason, kind, rule) in kinds {
            let mut cells: Option<CellRange> = None;
            let mut count = 0;
            for c in v.culled.iter().filter(|c| c.reason == reason) {
                count += 1;
                if !(c.x.x.is_finite() && c.x.y.is_finite()) {
                    continue;
                }
                let (i, j) = self.geom.cell_of(c.x);
                let cell = CellRange::of(i, j);
                cells = Some(cells.map_or(cell, |r| r.union(&cell)));
            }
            if count == 0 {
                continue;
            }
            let [ni, nj] = self.geom.cells;
            let whole = CellRange::of(0, 0).union(&CellRange::of(ni - 1, nj - 1));
            let cluster = Cluster::new(cells.unwrap_or(whole), rule.into(), 0.0);
            let k = self.attach(kind, cluster, v, g, false);
            if k == usize::MAX {
                continue;
            }
            let cap = self.cfg.max_event_ids;
            let e = &mut self.events[k];
            e.n_particles += count;
            for c in v.culled.iter().filter(|c| c.reason == reason) {
                if e.particles.len() < cap {
                    e.particles.push(c.id);
                }
            }
        }
    }
}

/// Largest over smallest principal stretch of F (in plane); 1 for a pure dilatation.
pub fn isochoric_stretch_ratio(f: &Mat2) -> f64 {
    let c = f.transpose() * f;
    let tr = c.trace();
    let det = c.determinant();
    let disc = (0.25 * tr * tr - det).max(0.0).sqrt();
    let (l1, l2) = (0.5 * tr + disc, 0.5 * tr - disc);
    if l2 <= 0.0 {
        return f64::INFINITY;
    }
    (l1 / l2).sqrt()
}
