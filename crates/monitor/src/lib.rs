//! kick's monitor: watches every step through the solver's read-only
//! [`StateView`] for kinetic-energy spikes, local acceleration outliers,
//! energy injection and blow-out, and logs each kick as an [`Event`] with its
//! step, region and hallmark flags. Field metrics (checkerboard, hydrostatic
//! departure, surge front) are computed on demand: at output rows and when an
//! event opens. Definitions: PHYSICS.md section 4.

pub mod accel_outliers;
pub mod cells;
pub mod checkerboard;
pub mod config;
pub mod energy_budget;
pub mod events;
pub mod front;
pub mod geometry;
pub mod hydrostatic;
pub mod particle_history;
mod state;

pub use config::MonitorConfig;
pub use events::{CellRange, Event, EventKind, Region};
pub use geometry::Geometry;

use accel_outliers::WindowStats;
use cells::CellBins;
use checkerboard::CellField;
use energy_budget::EnergyBudget;
use events::rule;
use front::Front;
use hydrostatic::Hydrostatic;
use particle_history::{ParticleHistory, NEVER};
use serde::Serialize;
use solver::{Mat2, StateView};

/// The cheap per-step figures.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StepReport {
    pub step: u64,
    pub t: f64,
    pub dt: f64,
    pub e_kin: f64,
    pub e_grav: f64,
    pub e_int: f64,
    pub d_visc: f64,
    pub e_total: f64,
    /// Total minus its running minimum.
    pub energy_injected: f64,
    /// Injection over the last `injection_window` steps, and its noise floor.
    pub injection_window: f64,
    pub injection_floor: f64,
    pub max_accel_g: f64,
    /// Largest z computed this step (0 when no particle was a candidate).
    pub max_z: f64,
    pub max_ke_ratio: f64,
    pub max_speed: f64,
    pub courant: f64,
    pub j_min: f64,
    pub j_max: f64,
    /// Smallest nodal mass over rho0 h^2 among active nodes.
    pub min_node_mass_ratio: f64,
    pub max_node_accel_g: f64,
    /// Particle minus grid kinetic energy after P2G (FLIP ringing).
    pub ringing_energy: f64,
    pub n_outside: usize,
    pub n_nonfinite: usize,
    pub n_flagged: usize,
    /// Events opened at this step.
    pub events_opened: usize,
    /// Set when the run must stop (blow-out or non-finite state).
    pub blow_out: Option<String>,
}

impl StepReport {
    /// The figures the state itself carries (time, energies, Courant); the rest zero.
    pub fn of_state(v: &StateView) -> Self {
        StepReport {
            step: v.step,
            t: v.time,
            dt: v.dt,
            e_kin: v.energy.kinetic,
            e_grav: v.energy.gravitational,
            e_int: v.energy.stored,
            d_visc: v.energy.dissipated,
            e_total: v.energy.total(),
            courant: v.courant,
            ..Default::default()
        }
    }
}

/// Field metrics, computed at output rows and when an event opens.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FieldMetrics {
    pub checkerboard: Option<f64>,
    /// RMS of (p_particle - p_cell) / (rho0 g h).
    pub pressure_spread: f64,
    pub hydro_rel_rms: f64,
    pub hydro_max: f64,
    pub front_x: Option<f64>,
    pub front_z: Option<f64>,
    pub front_t: f64,
}

/// A particle accelerating above `accel_candidate_g`, with its history from before this step.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    p: u32,
    /// |dv| / dt.
    a: f64,
    z: f64,
    rules: u32,
    last_fast: i64,
    last_deformed: i64,
}

#[derive(Clone, Debug)]
struct Cluster {
    cells: CellRange,
    rules: u32,
    peak_accel: f64,
    peak_z: f64,
    quiescent: usize,
    deformed_rate: usize,
    distorted: usize,
    count: usize,
    event: usize,
}

impl Cluster {
    /// A cluster over `cells` with no particles tallied yet.
    fn new(cells: CellRange, rules: u32, peak_accel: f64) -> Self {
        Cluster {
            cells,
            rules,
            peak_accel,
            peak_z: 0.0,
            quiescent: 0,
            deformed_rate: 0,
            distorted: 0,
            count: 0,
            event: 0,
        }
    }
}

#[derive(Clone, Debug)]
pub struct Monitor {
    pub cfg: MonitorConfig,
    pub geom: Geometry,
    /// |dv| / dt per particle, filled only on steps that need it (`fill_accel`).
    accel: Vec<f64>,
    accel_step: Option<u64>,
    flagged: Vec<Candidate>,
    bins: CellBins,
    stats: WindowStats,
    history: ParticleHistory,
    energy: EnergyBudget,
    cell_label: Vec<u32>,
    touched: Vec<u32>,
    stack: Vec<u32>,
    clusters: Vec<Cluster>,
    event_mark: Vec<u32>,
    events: Vec<Event>,
    field: CellField,
    hydro: Hydrostatic,
    front: Front,
    report: StepReport,
    prev_injected: f64,
    total_mass: f64,
    events_dropped: u64,
}

const UNLABELLED: u32 = u32::MAX;

impl Monitor {
    /// A monitor for the state `v` (the solver at t = 0 or a restart).
    pub fn new(cfg: MonitorConfig, v: &StateView) -> Self {
        let geom = Geometry::from_scene(v.scene);
        let n = v.x.len();
        let cells = geom.cell_count();
        Monitor {
            accel: vec![0.0; n],
            accel_step: None,
            flagged: Vec::with_capacity(n),
            bins: CellBins::new(&geom, n),
            stats: WindowStats::new(&geom, n),
            history: ParticleHistory::new(n),
            energy: EnergyBudget::new(v.energy.total(), cfg.injection_window as usize),
            cell_label: vec![UNLABELLED; cells],
            touched: Vec::with_capacity(cells),
            stack: Vec::with_capacity(cells),
            clusters: Vec::with_capacity(64),
            event_mark: vec![0; n],
            events: Vec::new(),
            field: CellField::new(&geom),
            hydro: Hydrostatic::new(&geom, n),
            front: Front::new(&geom),
            report: StepReport::default(),
            prev_injected: 0.0,
            events_dropped: 0,
            total_mass: v.mass.iter().sum(),
            geom,
            cfg,
        }
    }

    pub fn events(&self) -> &[Event] {
        &self.events
    }

    pub fn events_mut(&mut self) -> &mut [Event] {
        &mut self.events
    }

    /// Event openings refused because `max_events` was reached (an episode
    /// flagged on several steps counts once per step).
    pub fn events_dropped(&self) -> u64 {
        self.events_dropped
    }

    pub fn report(&self) -> &StepReport {
        &self.report
    }

    /// Gravity used to scale accelerations (9.81 when the scene has none).
    fn g_ref(&self) -> f64 {
        if self.geom.gravity > 0.0 {
            self.geom.gravity
        } else {
            9.81
        }
    }

    /// Acceleration |v - v_prev| / dt of every particle for this step (once).
    fn fill_accel(&mut self, v: &StateView) {
        if self.accel_step == Some(v.step) {
            return;
        }
        let inv_dt = 1.0 / v.dt.max(1e-300);
        for (a, (vn, vp)) in self.accel.iter_mut().zip(v.v.iter().zip(v.v_prev)) {
            *a = (vn - vp).norm() * inv_dt;
        }
        self.accel_step = Some(v.step);
    }

    /// Observes the state after a step.
    pub fn observe(&mut self, v: &StateView) -> &StepReport {
        let cfg = self.cfg.clone();
        let g = self.g_ref();
        let step = v.step;
        let dt = v.dt.max(1e-300);
        let n = v.x.len();
        let decay = (-1.0 / cfg.ke_history_steps.max(1.0)).exp();
        let ke_floor_speed2 = cfg.quiescent_speed * cfg.quiescent_speed;

        // One pass over the particles: cheap figures, candidates (with their
        // history as it was before this step), then the history update.
        let (mut max_ratio, mut max_speed) = (0.0f64, 0.0f64);
        let (mut j_min, mut j_max) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut gain_max = (f64::NEG_INFINITY, 0usize);
        let mut need_z = false;
        let candidate_a = cfg.accel_candidate_g * g;
        let quiescent2 = cfg.quiescent_speed * cfg.quiescent_speed;
        self.flagged.clear();
        let h = &mut self.history;
        // Squared velocity jumps compared against (a dt)^2: no root per particle.
        let inv_dt = 1.0 / dt;
        let candidate_dv2 = (candidate_a * dt).powi(2);
        let mut max_dv2 = 0.0f64;
        // Every slice cut to n up front: no bounds checks in the loop.
        let (vel, vel_prev, mass, jac, dev_rate) = (
            &v.v[..n],
            &v.v_prev[..n],
            &v.mass[..n],
            &v.j[..n],
            &v.dev_rate[..n],
        );
        let (ke_recent, last_fast, last_deformed) = (
            &mut h.ke_recent[..n],
            &mut h.last_fast_step[..n],
            &mut h.last_deformed_step[..n],
        );
        let (max_rate, max_rate_step) = (&mut h.max_dev_rate[..n], &mut h.max_dev_rate_step[..n]);
        for p in 0..n {
            let dv2 = (vel[p] - vel_prev[p]).norm_squared();
            max_dv2 = max_dv2.max(dv2);
            let candidate = dv2 >= candidate_dv2;
            let speed2 = vel[p].norm_squared();
            let prev2 = vel_prev[p].norm_squared();
            let e = 0.5 * mass[p] * speed2;
            let ke_ref = ke_recent[p].max(0.5 * mass[p] * ke_floor_speed2);
            // Divide only for a candidate or a possible new maximum.
            let ratio = if candidate || e > max_ratio * ke_ref {
                e / ke_ref
            } else {
                0.0
            };
            max_ratio = max_ratio.max(ratio);
            max_speed = max_speed.max(speed2);
            j_min = j_min.min(jac[p]);
            j_max = j_max.max(jac[p]);
            let gain = 0.5 * mass[p] * (speed2 - prev2);
            if gain > gain_max.0 {
                gain_max = (gain, p);
            }
            if candidate {
                let a = dv2.sqrt() * inv_dt;
                let mut rules = 0;
                if ratio >= cfg.ke_spike_ratio {
                    rules |= rule::KE_SPIKE;
                }
                // A kick adds kinetic energy; an impact that stops particles does not count.
                let wants_z = speed2 > prev2 && a >= cfg.kick_accel_g * g;
                need_z |= wants_z;
                // A candidate with no rule and no z to come would be dropped below.
                if rules != 0 || wants_z {
                    self.flagged.push(Candidate {
                        p: p as u32,
                        a,
                        z: if wants_z { f64::NAN } else { 0.0 },
                        rules,
                        last_fast: last_fast[p],
                        last_deformed: last_deformed[p],
                    });
                }
            }
            ke_recent[p] = e.max(ke_recent[p] * decay);
            if speed2 > quiescent2 {
                last_fast[p] = step as i64;
            }
            let rate = dev_rate[p];
            if rate >= cfg.deformed_rate {
                last_deformed[p] = step as i64;
            }
            if rate > max_rate[p] {
                max_rate[p] = rate;
                max_rate_step[p] = step as i64;
            }
        }
        let max_speed = max_speed.sqrt();
        let max_a = max_dv2.sqrt() * inv_dt;
        if need_z {
            // The z windows read every particle's acceleration.
            self.fill_accel(v);
        }

        // Robust z only for gaining candidates above kick_accel_g.
        let mut max_z = 0.0f64;
        if need_z {
            self.bins.rebuild(&self.geom, v.x);
            for c in self.flagged.iter_mut().filter(|c| c.z.is_nan()) {
                c.z = self.stats.z(
                    &self.geom,
                    &self.bins,
                    &self.accel,
                    (cfg.window_tile_cells, cfg.window_half_cells),
                    c.p as usize,
                    step.max(1),
                );
                max_z = max_z.max(c.z);
                if c.z >= cfg.kick_z {
                    c.rules |= rule::ACCEL_OUTLIER;
                }
            }
        }
        self.flagged.retain(|c| c.rules != 0);

        // Energy budget.
        let injection = self.energy.observe(v.energy.total());
        let floor = solver::energy::injection_noise_floor(self.total_mass, g, self.geom.size.y, dt);

        let opened_before = self.events.len();
        if !self.flagged.is_empty() {
            self.cluster_flagged(v, g);
        }
        if injection.window > cfg.injection_floor_factor * floor {
            self.fill_accel(v);
            let (i, j) = self.geom.cell_of(v.x[gain_max.1]);
            let cluster = Cluster::new(
                CellRange::of(i, j),
                rule::INJECTION_WINDOW,
                self.accel[gain_max.1],
            );
            self.attach(EventKind::EnergyInjection, cluster, v, g);
        }
        let mut blow_out = None;
        if v.n_nonfinite > 0 {
            blow_out = Some(format!("non-finite state in {} particles", v.n_nonfinite));
            self.blow_out_event(EventKind::NonFinite, rule::NON_FINITE, v, g, |x, vel| {
                !(x.x.is_finite() && x.y.is_finite() && vel.x.is_finite() && vel.y.is_finite())
            });
        } else if v.n_outside > 0 {
            blow_out = Some(format!("{} particles left the box", v.n_outside));
            let (lo, hi) = (self.geom.origin, self.geom.origin + self.geom.size);
            self.blow_out_event(EventKind::BlowOut, rule::OUTSIDE_BOX, v, g, |x, _| {
                x.x < lo.x || x.y < lo.y || x.x > hi.x || x.y > hi.y
            });
        } else {
            let escape = cfg.escape_speed_factor * (2.0 * g * self.geom.size.y).sqrt();
            if max_speed > escape {
                blow_out = Some(format!(
                    "a particle reached {max_speed:.3} m/s, beyond the escape speed {escape:.3} m/s"
                ));
                self.blow_out_event(EventKind::BlowOut, rule::ESCAPE_SPEED, v, g, |_, vel| {
                    vel.norm() > escape
                });
            }
        }
        // Energy injected while each event is open.
        for e in self.events.iter_mut().filter(|e| e.last_step == step) {
            if e.first_step == step {
                e.injected_at_open = self.prev_injected;
            }
            e.energy_injected = e.energy_injected.max(injection.total - e.injected_at_open);
        }
        self.prev_injected = injection.total;

        // Grid figures.
        let h2 = self.geom.rho0 * self.geom.cell * self.geom.cell;
        let (mut min_mass, mut max_node_a) = (f64::INFINITY, 0.0f64);
        for &node in v.grid.active {
            let m = v.grid.mass[node as usize];
            if m > 0.0 {
                min_mass = min_mass.min(m / h2);
                max_node_a = max_node_a.max(v.grid.acceleration[node as usize].norm());
            }
        }

        self.report = StepReport {
            step,
            energy_injected: injection.total,
            injection_window: injection.window,
            injection_floor: floor,
            max_accel_g: max_a / g,
            max_z,
            max_ke_ratio: max_ratio,
            max_speed,
            j_min,
            j_max,
            min_node_mass_ratio: if min_mass.is_finite() { min_mass } else { 0.0 },
            max_node_accel_g: max_node_a / g,
            ringing_energy: v.ke_particles_p2g - v.ke_grid_p2g,
            n_outside: v.n_outside,
            n_nonfinite: v.n_nonfinite,
            n_flagged: self.flagged.len(),
            events_opened: self.events.len() - opened_before,
            blow_out,
            ..StepReport::of_state(v)
        };
        &self.report
    }

    /// Clusters this step's flagged particles by 8-adjacent cells and files them as kicks.
    fn cluster_flagged(&mut self, v: &StateView, g: f64) {
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
            self.clusters.push(Cluster::new(cells, 0, 0.0));
        }
        let step = v.step as i64;
        let recent = self.cfg.recent_steps as i64;
        for f in &self.flagged {
            let p = f.p as usize;
            let label = self.cell_label[self.geom.cell_index(v.x[p])] as usize;
            let c = &mut self.clusters[label];
            c.rules |= f.rules;
            c.peak_accel = c.peak_accel.max(f.a);
            c.peak_z = c.peak_z.max(f.z);
            c.count += 1;
            if f.last_fast < step - recent {
                c.quiescent += 1;
            }
            let last = f.last_deformed;
            if last != NEVER && last < step - recent {
                c.deformed_rate += 1;
            }
            if isochoric_stretch_ratio(&v.deformation[p]) >= self.cfg.distortion_ratio {
                c.distorted += 1;
            }
        }
        for k in 0..self.clusters.len() {
            let cluster = self.clusters[k].clone();
            self.clusters[k].event = if cluster.count >= self.cfg.min_cluster_particles {
                self.attach(EventKind::Kick, cluster, v, g)
            } else {
                usize::MAX
            };
        }
        let cap = self.cfg.max_event_ids;
        for f in &self.flagged {
            let p = f.p as usize;
            let label = self.cell_label[self.geom.cell_index(v.x[p])] as usize;
            let event = self.clusters[label].event;
            if event == usize::MAX {
                continue;
            }
            let e = &mut self.events[event];
            if self.event_mark[p] != e.id {
                self.event_mark[p] = e.id;
                e.n_particles += 1;
                if e.particles.len() < cap {
                    e.particles.push(v.id[p]);
                }
            }
        }
    }

    /// Merges a cluster into an open event of the same kind nearby, or opens
    /// one; usize::MAX when the event store is full.
    fn attach(&mut self, kind: EventKind, c: Cluster, v: &StateView, g: f64) -> usize {
        let step = v.step;
        let open = self.events.iter().rposition(|e| {
            e.kind == kind
                && (e.last_step + self.cfg.merge_steps >= step
                    || v.time - e.last_t <= self.cfg.merge_seconds)
                && e.extent.near(&c.cells, self.cfg.merge_cells)
        });
        let blow_out = matches!(kind, EventKind::BlowOut | EventKind::NonFinite);
        if open.is_none() && !blow_out && self.events.len() >= self.cfg.max_events {
            self.events_dropped += 1;
            return usize::MAX;
        }
        let half = |k: usize| c.count > 0 && 2 * k >= c.count;
        match open {
            Some(k) => {
                let e = &mut self.events[k];
                e.last_step = step;
                e.last_t = v.time;
                e.extent = e.extent.union(&c.cells);
                if e.first_step == step {
                    e.cells = e.cells.union(&c.cells);
                    e.region = e.cells.metres(&self.geom);
                }
                e.peak_accel_g = e.peak_accel_g.max(c.peak_accel / g);
                e.peak_z = e.peak_z.max(c.peak_z);
                e.rule_bits |= c.rules;
                e.rules = rule::names(e.rule_bits);
                k
            }
            None => {
                let mut deformed_by = vec![];
                if half(c.deformed_rate) {
                    deformed_by.push("strain_rate".to_string());
                }
                if half(c.distorted) {
                    deformed_by.push("distortion".to_string());
                }
                self.events.push(Event {
                    id: self.events.len() as u32 + 1,
                    kind,
                    first_step: step,
                    last_step: step,
                    t: v.time,
                    last_t: v.time,
                    cells: c.cells,
                    region: c.cells.metres(&self.geom),
                    extent: c.cells,
                    n_particles: 0,
                    particles: Vec::new(),
                    peak_accel_g: c.peak_accel / g,
                    peak_z: c.peak_z,
                    energy_injected: 0.0,
                    courant: v.courant,
                    quiescent_before: half(c.quiescent),
                    previously_deformed: !deformed_by.is_empty(),
                    deformed_by,
                    rules: rule::names(c.rules),
                    state_hash: None,
                    checkpoint: None,
                    rule_bits: c.rules,
                    injected_at_open: self.prev_injected,
                });
                self.events.len() - 1
            }
        }
    }

    fn blow_out_event(
        &mut self,
        kind: EventKind,
        rules: u32,
        v: &StateView,
        g: f64,
        bad: impl Fn(solver::Vec2, solver::Vec2) -> bool,
    ) {
        self.fill_accel(v);
        let mut cells: Option<CellRange> = None;
        let mut count = 0;
        let mut peak = 0.0f64;
        for p in 0..v.x.len() {
            if bad(v.x[p], v.v[p]) {
                let (i, j) = self.geom.cell_of(v.x[p]);
                cells = Some(cells.map_or(CellRange::of(i, j), |c| c.union(&CellRange::of(i, j))));
                count += 1;
                if self.accel[p].is_finite() {
                    peak = peak.max(self.accel[p]);
                }
            }
        }
        let Some(cells) = cells else { return };
        let k = self.attach(kind, Cluster::new(cells, rules, peak), v, g);
        let cap = self.cfg.max_event_ids;
        let e = &mut self.events[k];
        e.n_particles = e.n_particles.max(count);
        for p in 0..v.x.len() {
            if e.particles.len() >= cap {
                break;
            }
            if bad(v.x[p], v.v[p]) && !e.particles.contains(&v.id[p]) {
                e.particles.push(v.id[p]);
            }
        }
    }

    /// Checkerboard, hydrostatic departure and surge front of the current state.
    pub fn field_metrics(&mut self, v: &StateView) -> FieldMetrics {
        let geom = &self.geom;
        self.field.accumulate(geom, v.x, v.pressure);
        let checkerboard = checkerboard::index(geom, &self.field);
        let pressure_spread = checkerboard::intra_cell_spread(geom, &self.field, v.x, v.pressure);
        self.hydro.compute(geom, v.x, v.mass);
        let dep = self.hydro.departure(geom, v.volume, v.pressure);
        let front_x = self.front.position(geom, &self.field);
        let (front_z, front_t) = match front_x {
            Some(x) => {
                let (z, t) = front::dimensionless(geom, x, v.time);
                (Some(z), t)
            }
            None => (None, front::dimensionless(geom, 0.0, v.time).1),
        };
        FieldMetrics {
            checkerboard,
            pressure_spread,
            hydro_rel_rms: dep.rel_rms,
            hydro_max: dep.max,
            front_x,
            front_z,
            front_t,
        }
    }

    /// The hydrostatic reference pressure of every particle (after `field_metrics`).
    pub fn hydrostatic_reference(&self) -> &[f64] {
        &self.hydro.reference
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
