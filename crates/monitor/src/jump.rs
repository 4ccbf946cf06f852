//! The velocity-jump rule (docs/physics.md section 4b). A kick is a
//! velocity change the local flow does not share: each step, each
//! particle's change v - v_prev is set against the local flow's, the
//! component-wise median of the mean changes of the cells 2 to
//! `jump_ring_cells` cells away (a patch up to a few cells wide cannot drag
//! that median along; beyond a wall, the wall's mirror image of the cells
//! inside, as the boundary condition has it), with 1.4826 times their
//! median absolute deviation as the flow's own spread. A particle whose
//! change departs by at least `jump_speed` and `jump_z` spreads, and whose
//! kinetic energy grew, jumped (a kick adds kinetic energy; a particle an
//! impact stops does not count). The threshold is a velocity, not an
//! acceleration: an impulse dv is the same jump at every time step and
//! formulation, where an acceleration dv / dt is not.
//!
//! A jump is *calm* when the ring's median velocity change over the last
//! `calm_seconds` stays below `calm_change`: no impact, rebound or splash
//! (the local flow stopping or turning) explains it. A calm jump is a kick
//! by this rule; any other is physics unless the energy test says it added
//! energy. The rule keeps a few snapshots of the velocities for that window.
//!
//! A push that builds up over many steps departs from the local flow by
//! little in any one step, and by the less the smaller the step. So, with
//! `windowed`, each time a snapshot is taken (every half calm window) the
//! rule also judges each particle's change since the snapshot a whole calm
//! window old against the local flow's change over the same span (a plane
//! fitted to the ring), by the same thresholds: the same instrument in
//! physical time at every step size. It judges the particles that were
//! quiet at the span's start and stayed within 2 cells: in moving flow a
//! particle's change along its path holds gradients no ring describes.
//!
//! With `moving`, the windowed rule judges every particle present at the
//! span's start, moving or not, in the Lagrangian frame: its change over
//! the span against the ring of the cell it started the span in, whose
//! changes are those of the particles that started there (binned by their
//! positions at the span's start). Those are its material neighbours, and
//! a smooth flow's change over a span is a smooth function of where the
//! particles started, however fast they move.

use crate::geometry::Geometry;
use crate::stats::lower_median;
use solver::{StateView, Vec2};

/// A particle's jump: its slot now and how far its change departs from the
/// local flow's (m/s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jump {
    pub p: u32,
    pub residual: f64,
    /// The local flow was calm: the ring's median velocity change over the
    /// last `calm_seconds` stayed below `calm_change` (no impact, no
    /// rebound, no splash around it).
    pub calm: bool,
}

/// The particles' velocities and positions at a time (ids ascending, as
/// the solver keeps them).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Snapshot {
    pub t: f64,
    pub ids: Vec<u32>,
    pub v: Vec<Vec2>,
    /// The positions, read by the moving rule only (checkpointed with it).
    pub x: Vec<Vec2>,
}

/// The rule's thresholds (`MonitorConfig`'s `jump_*`).
#[derive(Clone, Copy, Debug)]
pub struct JumpRule {
    /// Smallest departure that counts (m/s) ...
    pub speed: f64,
    /// ... and in spreads of the local flow.
    pub z: f64,
    /// Outer radius (cells) of the ring the local flow is read from.
    pub ring: usize,
    /// The calm window (s) and the ring's velocity change over it below
    /// which the local flow is calm (m/s).
    pub calm_seconds: f64,
    pub calm_change: f64,
    /// Also judge the change over the calm window, every half window, of
    /// the particles slower than `quiet_speed` at its start (m/s).
    pub windowed: bool,
    pub quiet_speed: f64,
    /// The windowed rule judges every particle in its span's start
    /// configuration (`MonitorConfig::moving_window`).
    pub moving: bool,
    /// Judge each step's change too (`MonitorConfig::step_jumps`).
    pub per_step: bool,
}

/// Where a particle stands against the rule in the step last observed:
/// its change's departure from the local flow's, the threshold that
/// departure must reach, and whether the local flow was calm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Margin {
    pub departure: Vec2,
    pub threshold: f64,
    pub calm: bool,
}

/// Cells of the ring a verdict needs (else the cell is left unjudged: spray).
pub const MIN_RING_CELLS: usize = 6;

/// What the rule knows of a cell this step: the ring's median change and
/// its spread (NaN when unjudged), and its median change over the calm window.
#[derive(Clone, Copy, Debug, Default)]
struct Local {
    change: Vec2,
    spread: f64,
    window_change: f64,
}

/// Which per-cell change a ring's median is taken of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Field {
    /// This step's.
    Step,
    /// Since the newest snapshot at least half a calm window old.
    Window,
    /// Since the snapshot a whole calm window old (the windowed rule).
    Span,
}

/// The rule's snapshots (its only memory) and per-step scratch.
#[derive(Clone, Debug, Default)]
pub struct Jumps {
    /// The velocities every half calm window, newest first (at most three).
    pub snaps: Vec<Snapshot>,
    /// This step's jumps.
    found: Vec<Jump>,
    /// Per cell: mass, mass-weighted mean change this step and over the calm window.
    mass: Vec<f64>,
    change: Vec<Vec2>,
    window_change: Vec<Vec2>,
    /// The windowed rule's scratch: per particle, its change since the
    /// snapshot a calm window old (NaN: it is newer); per cell, the mass
    /// that snapshot holds and its mean change; and the ring's median
    /// change and spread of each cell it judged (NaN spread: unjudged).
    /// Each particle's cell its span is binned by: where it is now, or
    /// under the moving rule where it started the span.
    span_dv: Vec<Vec2>,
    span_cell: Vec<usize>,
    span_mass: Vec<f64>,
    span_change: Vec<Vec2>,
    span_local: Vec<Option<(Vec2, f64)>>,
    /// Per cell: whether `local` holds this step's figures.
    judged: Vec<bool>,
    local: Vec<Local>,
    /// Per cell: the mean change of its 9 x 9-cell block (the cheap first test).
    block: Vec<Vec2>,
    sat_m: Vec<f64>,
    sat_p: Vec<Vec2>,
    /// The ring's cells, each with whether it is a wall's image in x and y,
    /// and its offset from the centre cell (cells).
    ring: Vec<(usize, [bool; 2])>,
    ring_at: Vec<[f64; 2]>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    dev: Vec<f64>,
}

impl Jumps {
    /// This step's jumps: the particles whose velocity change departs from
    /// the local flow's.
    pub fn observe(&mut self, geom: &Geometry, v: &StateView, rule: &JumpRule) -> &[Jump] {
        let snapped = self.snapshot(v, rule);
        self.cell_sums(geom, v, rule.calm_seconds);
        self.block_means(geom);
        let cells = geom.cell_count();
        self.judged.clear();
        self.judged.resize(cells, false);
        self.local.resize(cells, Local::default());
        self.found.clear();
        let judged_per_step = if rule.per_step { v.x.len() } else { 0 };
        for p in 0..judged_per_step {
            let dv = v.v[p] - v.v_prev[p];
            let c = geom.cell_index(v.x[p]);
            // The local flow is read only where a particle departs from its
            // block's mean by half the threshold.
            let departure = (dv - self.block[c]).norm();
            if departure.is_nan() || departure < 0.5 * rule.speed {
                continue;
            }
            if !self.judged[c] {
                self.judged[c] = true;
                self.local[c] = self.local_flow(geom, c, rule.ring);
            }
            let l = self.local[c];
            let residual = (dv - l.change).norm();
            let gaining = v.v[p].norm_squared() > v.v_prev[p].norm_squared();
            if gaining && residual.is_finite() && residual >= rule.speed.max(rule.z * l.spread) {
                self.found.push(Jump {
                    p: p as u32,
                    residual,
                    calm: l.window_change < rule.calm_change,
                });
            }
        }
        if snapped && rule.windowed && self.snaps.len() >= 3 {
            self.judge_span(geom, v, rule);
        }
        &self.found
    }

    /// The windowed rule: each particle's change since the snapshot a calm
    /// window old, against the ring's over the same span (thresholds and
    /// the gain test as per step). A particle this step already flagged
    /// keeps its step's verdict.
    fn judge_span(&mut self, geom: &Geometry, v: &StateView, rule: &JumpRule) {
        self.span_sums(geom, v, rule.moving);
        // Judged: a particle quiet at the span's start (in moving flow the
        // change along its path holds the flow's own gradients, which no
        // ring describes), which stayed inside the ring's inner edge.
        let span = self.snaps[0].t - self.snaps[self.snaps.len() - 1].t;
        let reach2 = (2.0 * geom.cell / span).powi(2);
        let quiet2 = rule.quiet_speed.powi(2);
        let stepped = self.found.len();
        let mut k = 0;
        for p in 0..v.x.len() {
            while k < stepped && (self.found[k].p as usize) < p {
                k += 1;
            }
            let dv = self.span_dv[p];
            let (now, before) = (v.v[p].norm_squared(), (v.v[p] - dv).norm_squared());
            let judged =
                !dv.x.is_nan() && (rule.moving || (before <= quiet2 && now.max(before) <= reach2));
            if !judged || (k < stepped && self.found[k].p as usize == p) {
                continue;
            }
            let c = self.span_cell[p];
            let Some((change, spread)) = self.span_local(geom, c, rule.ring) else {
                continue;
            };
            let residual = (dv - change).norm();
            if now > before && residual.is_finite() && residual >= rule.speed.max(rule.z * spread) {
                self.found.push(Jump {
                    p: p as u32,
                    residual,
                    calm: change.norm() < rule.calm_change,
                });
            }
        }
        self.found.sort_unstable_by_key(|j| j.p);
    }

    /// Per particle, its change since the oldest snapshot (matched by id),
    /// and per cell (where the particle is, or with `moving` where it
    /// started the span) the mass-weighted mean of those changes.
    fn span_sums(&mut self, geom: &Geometry, v: &StateView, moving: bool) {
        let n = geom.cell_count();
        self.span_mass.clear();
        self.span_mass.resize(n, 0.0);
        self.span_change.clear();
        self.span_change.resize(n, Vec2::zeros());
        self.span_local.clear();
        self.span_local.resize(n, None);
        self.span_dv.clear();
        self.span_cell.clear();
        let s = &self.snaps[self.snaps.len() - 1];
        let mut k = 0;
        for p in 0..v.x.len() {
            while k < s.ids.len() && s.ids[k] < v.id[p] {
                k += 1;
            }
            if k < s.ids.len() && s.ids[k] == v.id[p] {
                let dv = v.v[p] - s.v[k];
                let at = if moving { s.x[k] } else { v.x[p] };
                let (c, m) = (geom.cell_index(at), v.mass[p]);
                self.span_mass[c] += m;
                self.span_change[c] += m * dv;
                self.span_dv.push(dv);
                self.span_cell.push(c);
            } else {
                self.span_dv.push(Vec2::repeat(f64::NAN));
                self.span_cell.push(usize::MAX);
            }
        }
        for c in 0..n {
            if self.span_mass[c] > 0.0 {
                self.span_change[c] /= self.span_mass[c];
            }
        }
    }

    /// Cell `c`'s local change over the span and its spread, computed once
    /// per judging (None: spray, fewer than `MIN_RING_CELLS` cells).
    fn span_local(&mut self, geom: &Geometry, c: usize, ring: usize) -> Option<(Vec2, f64)> {
        if self.span_local[c].is_none() {
            let judged = if self.ring_of(geom, c, ring, Field::Span) {
                self.plane_and_spread()
            } else {
                (Vec2::repeat(f64::NAN), f64::NAN)
            };
            self.span_local[c] = Some(judged);
        }
        self.span_local[c].filter(|(_, spread)| spread.is_finite())
    }

    /// Particle `p`'s margin in the step `observe` last judged (None: its
    /// cell's ring is spray, or `observe` has never run). Call it on the
    /// state `observe` last saw: the cell sums are that step's.
    pub fn margin(
        &mut self,
        geom: &Geometry,
        v: &StateView,
        rule: &JumpRule,
        p: usize,
    ) -> Option<Margin> {
        let c = geom.cell_index(v.x[p]);
        if c >= self.judged.len() || self.mass.len() != self.judged.len() {
            return None;
        }
        if !self.judged[c] {
            self.judged[c] = true;
            self.local[c] = self.local_flow(geom, c, rule.ring);
        }
        let l = self.local[c];
        l.spread.is_finite().then(|| Margin {
            departure: v.v[p] - v.v_prev[p] - l.change,
            threshold: rule.speed.max(rule.z * l.spread),
            calm: l.window_change < rule.calm_change,
        })
    }

    /// Keeps the velocities every half calm window (the three newest),
    /// and the positions only for the moving rule, which bins by them;
    /// true when it took one this step.
    fn snapshot(&mut self, v: &StateView, rule: &JumpRule) -> bool {
        let half = 0.5 * rule.calm_seconds * (1.0 - 1e-9);
        let due = self.snaps.first().is_none_or(|s| v.time - s.t >= half);
        if due {
            // The oldest's buffers are reused once there are three.
            let mut s = if self.snaps.len() >= 3 {
                self.snaps.pop().unwrap_or_default()
            } else {
                Snapshot::default()
            };
            s.t = v.time;
            s.ids.clear();
            s.ids.extend_from_slice(v.id);
            s.v.clear();
            s.v.extend_from_slice(v.v);
            s.x.clear();
            if rule.moving {
                s.x.extend_from_slice(v.x);
            }
            self.snaps.insert(0, s);
        }
        due
    }

    /// Per cell, the mass-weighted mean change of its particles this step,
    /// and since the newest snapshot at least half a calm window old, or
    /// else the oldest (matched by id; a particle it lacks counts as unchanged).
    fn cell_sums(&mut self, geom: &Geometry, v: &StateView, window: f64) {
        let n = geom.cell_count();
        self.mass.clear();
        self.mass.resize(n, 0.0);
        self.change.clear();
        self.change.resize(n, Vec2::zeros());
        self.window_change.clear();
        self.window_change.resize(n, Vec2::zeros());
        // Early in a run, the oldest there is (the window is still shorter).
        let reference = self
            .snaps
            .iter()
            .find(|s| v.time - s.t >= 0.5 * window * (1.0 - 1e-9))
            .or(self.snaps.last().filter(|s| s.t < v.time));
        let mut k = 0;
        for p in 0..v.x.len() {
            let c = geom.cell_index(v.x[p]);
            let m = v.mass[p];
            self.mass[c] += m;
            self.change[c] += m * (v.v[p] - v.v_prev[p]);
            if let Some(s) = reference {
                while k < s.ids.len() && s.ids[k] < v.id[p] {
                    k += 1;
                }
                if k < s.ids.len() && s.ids[k] == v.id[p] {
                    self.window_change[c] += m * (v.v[p] - s.v[k]);
                }
            }
        }
        for c in 0..n {
            if self.mass[c] > 0.0 {
                self.change[c] /= self.mass[c];
                self.window_change[c] /= self.mass[c];
            }
        }
    }

    /// Each cell's 9 x 9-cell block mean change, from a summed-area table.
    fn block_means(&mut self, geom: &Geometry) {
        let [nx, ny] = geom.cells;
        let w = nx + 1;
        self.sat_m.clear();
        self.sat_m.resize(w * (ny + 1), 0.0);
        self.sat_p.clear();
        self.sat_p.resize(w * (ny + 1), Vec2::zeros());
        for j in 0..ny {
            for i in 0..nx {
                let (c, k) = (i + nx * j, (i + 1) + w * (j + 1));
                let m = self.mass[c];
                self.sat_m[k] = m + self.sat_m[k - 1] + self.sat_m[k - w] - self.sat_m[k - w - 1];
                self.sat_p[k] = m * self.change[c] + self.sat_p[k - 1] + self.sat_p[k - w]
                    - self.sat_p[k - w - 1];
            }
        }
        self.block.clear();
        for j in 0..ny {
            for i in 0..nx {
                let (i0, j0) = (i.saturating_sub(4), j.saturating_sub(4));
                let (i1, j1) = ((i + 5).min(nx), (j + 5).min(ny));
                let (a, b, c, d) = (i0 + w * j0, i1 + w * j0, i0 + w * j1, i1 + w * j1);
                let m = self.sat_m[d] - self.sat_m[c] - self.sat_m[b] + self.sat_m[a];
                let p = self.sat_p[d] - self.sat_p[c] - self.sat_p[b] + self.sat_p[a];
                self.block.push(if m > 0.0 { p / m } else { Vec2::zeros() });
            }
        }
    }

    /// Cell `c`'s local flow: the ring's median change and spread (NaN:
    /// fewer than `MIN_RING_CELLS` cells with material).
    fn local_flow(&mut self, geom: &Geometry, c: usize, ring: usize) -> Local {
        if !self.ring_of(geom, c, ring, Field::Step) {
            return Local {
                change: Vec2::repeat(f64::NAN),
                spread: f64::NAN,
                window_change: f64::NAN,
            };
        }
        let (change, spread) = self.median_and_spread(Field::Step);
        let (window, _) = self.median_and_spread(Field::Window);
        Local {
            change,
            spread,
            window_change: window.norm(),
        }
    }

    /// Fills `ring` with cell `c`'s ring cells holding material (by the
    /// field's own masses); false when they are fewer than `MIN_RING_CELLS`.
    fn ring_of(&mut self, geom: &Geometry, c: usize, ring: usize, field: Field) -> bool {
        let [nx, ny] = geom.cells;
        let r = ring as i64;
        let (ci, cj) = ((c % nx) as i64, (c / nx) as i64);
        let mass = if field == Field::Span {
            &self.span_mass
        } else {
            &self.mass
        };
        self.ring.clear();
        self.ring_at.clear();
        for j in cj - r..=cj + r {
            for i in ci - r..=ci + r {
                if (i - ci).abs().max((j - cj).abs()) < 2 {
                    continue;
                }
                // Beyond a wall, the wall's mirror image of the cell inside
                // (the boundary condition is a mirror): normal component flipped.
                let (o, flip) = image(i, nx, geom.periodic[0])
                    .zip(image(j, ny, geom.periodic[1]))
                    .map_or((usize::MAX, [false; 2]), |((ii, fx), (jj, fy))| {
                        (ii + nx * jj, [fx, fy])
                    });
                if o != usize::MAX && mass[o] > 0.0 {
                    self.ring.push((o, flip));
                    self.ring_at.push([(i - ci) as f64, (j - cj) as f64]);
                }
            }
        }
        self.ring.len() >= MIN_RING_CELLS
    }

    /// The span's local change at the centre cell: over a window the flow's
    /// own gradients build up (a wall's run-up, a one-sided ring at the
    /// surface or in a corner), so the ring's changes are fitted with a
    /// plane (gradient by least squares, level by the median of what the
    /// gradient leaves); the spread is 1.4826 times the median distance
    /// from the plane.
    fn plane_and_spread(&mut self) -> (Vec2, f64) {
        let n = self.ring.len() as f64;
        let (mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let (mut sf, mut sxf, mut syf) = (Vec2::zeros(), Vec2::zeros(), Vec2::zeros());
        for (r, &[x, y]) in self.ring.iter().zip(&self.ring_at) {
            let f = imaged(&self.span_change, r);
            (sx, sy, sxx, sxy, syy) = (sx + x, sy + y, sxx + x * x, sxy + x * y, syy + y * y);
            (sf, sxf, syf) = (sf + f, sxf + x * f, syf + y * f);
        }
        // Centred sums: the gradient's 2 x 2 normal equations.
        let (cxx, cxy, cyy) = (sxx - sx * sx / n, sxy - sx * sy / n, syy - sy * sy / n);
        let (cxf, cyf) = (sxf - sx * sf / n, syf - sy * sf / n);
        let det = cxx * cyy - cxy * cxy;
        let (gx, gy) = if det > 1e-9 * (cxx * cyy).max(1.0) {
            ((cyy * cxf - cxy * cyf) / det, (cxx * cyf - cxy * cxf) / det)
        } else {
            (Vec2::zeros(), Vec2::zeros())
        };
        let ring = std::mem::take(&mut self.ring);
        let at = std::mem::take(&mut self.ring_at);
        let level = |r: &(usize, [bool; 2]), &[x, y]: &[f64; 2]| {
            imaged(&self.span_change, r) - x * gx - y * gy
        };
        self.xs.clear();
        self.xs
            .extend(ring.iter().zip(&at).map(|(r, a)| level(r, a).x));
        self.ys.clear();
        self.ys
            .extend(ring.iter().zip(&at).map(|(r, a)| level(r, a).y));
        let centre = Vec2::new(lower_median(&mut self.xs), lower_median(&mut self.ys));
        self.dev.clear();
        self.dev.extend(
            ring.iter()
                .zip(&at)
                .map(|(r, a)| (level(r, a) - centre).norm()),
        );
        (self.ring, self.ring_at) = (ring, at);
        (centre, 1.4826 * lower_median(&mut self.dev))
    }

    /// The ring's component-wise median of the cells' changes (this step's,
    /// over the calm window or over the span) and 1.4826 times the median
    /// distance from it.
    fn median_and_spread(&mut self, field: Field) -> (Vec2, f64) {
        let field = match field {
            Field::Step => &self.change,
            Field::Window => &self.window_change,
            Field::Span => &self.span_change,
        };
        let at = |r: &(usize, [bool; 2])| imaged(field, r);
        self.xs.clear();
        self.xs.extend(self.ring.iter().map(|r| at(r).x));
        self.ys.clear();
        self.ys.extend(self.ring.iter().map(|r| at(r).y));
        let centre = Vec2::new(lower_median(&mut self.xs), lower_median(&mut self.ys));
        self.dev.clear();
        self.dev
            .extend(self.ring.iter().map(|r| (at(r) - centre).norm()));
        (centre, 1.4826 * lower_median(&mut self.dev))
    }
}

/// A ring cell's value of `field`: the cell's own, with the normal
/// component flipped where the ring cell is a wall's image.
fn imaged(field: &[Vec2], &(o, [fx, fy]): &(usize, [bool; 2])) -> Vec2 {
    let f = field[o];
    Vec2::new(if fx { -f.x } else { f.x }, if fy { -f.y } else { f.y })
}

/// Cell index `k` along an axis of `n` cells: itself inside, wrapped on a
/// periodic axis, else its mirror image across the wall (and true: the
/// normal component flips); None beyond the image.
fn image(k: i64, n: usize, periodic: bool) -> Option<(usize, bool)> {
    let n = n as i64;
    if (0..n).contains(&k) {
        Some((k as usize, false))
    } else if periodic {
        Some((k.rem_euclid(n) as usize, false))
    } else if k < 0 && -1 - k < n {
        Some(((-1 - k) as usize, true))
    } else if k >= n && 2 * n - 1 - k >= 0 {
        Some(((2 * n - 1 - k) as usize, true))
    } else {
        None
    }
}
