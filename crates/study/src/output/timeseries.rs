//! The per-case timeseries: one row per k steps plus a row at each event's
//! first step. Every column is declared once in `COLUMNS`: its name, unit
//! and meaning, where its value comes from, how a row samples the steps
//! since the previous row (the value now, or the extreme or sum since the
//! previous row, so that no spike between rows is lost), and the figures
//! the summary draws from it. That one declaration feeds the rows, the
//! Parquet and CSV tables, the summary's figures and the plots' labels.
//! Missing values are NaN in memory, empty in CSV and null in Parquet.

use monitor::{FieldMetrics, StepReport};

/// Where a column's value comes from.
#[derive(Clone, Copy)]
pub enum Source {
    /// The monitor's step report, sampled by the rule.
    Step(fn(&StepReport) -> f64, Sample),
    /// The field metrics, computed when the row is written.
    Field(fn(&FieldMetrics) -> f64),
}

/// How a row samples a step-report value over the steps since the previous row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sample {
    /// The value at the row's step.
    Now,
    /// The largest since the previous row, at least this.
    Max(f64),
    /// The smallest since the previous row, at most this.
    Min(f64),
    /// The sum since the previous row.
    Sum,
}

/// How a figure of the summary is drawn from a column (docs/physics.md section 4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rule {
    /// The largest finite value of any row.
    Peak,
    /// The mean over the last simulated second of a run that reached t_end
    /// (event rows and the t = 0 row left out).
    Late,
    /// The same over the second before a stopped run's state stopped being
    /// whole (`metrics::summarise`).
    PreFailure,
}

/// A figure of the summary: its name there, its rule and its label in the
/// report (the unit is the column's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Figure {
    pub name: &'static str,
    pub rule: Rule,
    pub label: &'static str,
}

const fn peak(name: &'static str, label: &'static str) -> Figure {
    Figure {
        name,
        rule: Rule::Peak,
        label,
    }
}

const fn late(name: &'static str, label: &'static str) -> Figure {
    Figure {
        name,
        rule: Rule::Late,
        label,
    }
}

const fn pre_failure(name: &'static str, label: &'static str) -> Figure {
    Figure {
        name,
        rule: Rule::PreFailure,
        label,
    }
}

/// One declared column.
#[derive(Clone)]
pub struct Column {
    pub name: &'static str,
    /// SI unit ("1" for a plain number).
    pub unit: &'static str,
    pub meaning: &'static str,
    pub source: Source,
    pub figures: &'static [Figure],
}

impl Column {
    /// An axis label: the name and the unit.
    pub fn label(&self) -> String {
        match self.unit {
            "1" => self.name.to_string(),
            unit => format!("{} ({unit})", self.name),
        }
    }
}

const fn step(
    name: &'static str,
    unit: &'static str,
    meaning: &'static str,
    get: fn(&StepReport) -> f64,
    sample: Sample,
    figures: &'static [Figure],
) -> Column {
    Column {
        name,
        unit,
        meaning,
        source: Source::Step(get, sample),
        figures,
    }
}

const fn field(
    name: &'static str,
    unit: &'static str,
    meaning: &'static str,
    get: fn(&FieldMetrics) -> f64,
    figures: &'static [Figure],
) -> Column {
    Column {
        name,
        unit,
        meaning,
        source: Source::Field(get),
        figures,
    }
}

fn or_nan(v: Option<f64>) -> f64 {
    v.unwrap_or(f64::NAN)
}

use Sample::{Max, Min, Now, Sum};

/// One remedy's booking column (registry slot, key, `dissipated` or
/// `injected`), with its total as a figure.
macro_rules! booked {
    ($slot:literal, $key:ident, $part:ident) => {
        step(
            concat!("booked_", stringify!($key), "_", stringify!($part)),
            "J/m",
            concat!(
                "energy ",
                stringify!($key),
                " ",
                stringify!($part),
                " so far (empty: not in the method)"
            ),
            |r| r.booked[$slot].map_or(f64::NAN, |b| b.$part),
            Now,
            &[peak(
                concat!(
                    "booked_",
                    stringify!($key),
                    "_",
                    stringify!($part),
                    "_total"
                ),
                concat!("energy ", stringify!($key), " ", stringify!($part)),
            )],
        )
    };
}

pub const COLUMNS: &[Column] = &[
    step("t", "s", "simulated time", |r| r.t, Now, &[]),
    step("dt", "s", "time step", |r| r.dt, Now, &[]),
    step(
        "e_kin",
        "J/m",
        "particle kinetic energy",
        |r| r.e_kin,
        Now,
        &[],
    ),
    step(
        "e_affine",
        "J/m",
        "kinetic energy of the APIC affine velocity (B-splines; else 0)",
        |r| r.e_affine,
        Now,
        &[],
    ),
    step(
        "e_grav",
        "J/m",
        "gravitational energy",
        |r| r.e_grav,
        Now,
        &[],
    ),
    step(
        "e_int",
        "J/m",
        "stored (internal) energy",
        |r| r.e_int,
        Now,
        &[],
    ),
    step(
        "d_visc",
        "J/m",
        "viscous dissipation so far",
        |r| r.d_visc,
        Now,
        &[],
    ),
    step("e_total", "J/m", "total energy", |r| r.e_total, Now, &[]),
    step(
        "energy_injected",
        "J/m",
        "the whole run's energy gain, booked terms by their net (the pump figure)",
        |r| r.energy_injected,
        Now,
        &[
            peak("energy_injected_max", "largest energy injected"),
            peak("pump_gain", "energy the whole body gained (pump)"),
        ],
    ),
    step(
        "injection_window",
        "J/m",
        "injection over the detector's window",
        |r| r.injection_window,
        Now,
        &[],
    ),
    step(
        "injection_floor",
        "J/m",
        "the injection detector's floor",
        |r| r.injection_floor,
        Now,
        &[],
    ),
    step(
        "gravity_stepping",
        "J/m",
        "gravity's stepping term booked so far",
        |r| r.gravity_stepping,
        Now,
        &[],
    ),
    step(
        "transfer_loss",
        "J/m",
        "kinetic energy lost in transfers so far",
        |r| r.transfer_loss,
        Now,
        &[],
    ),
    step(
        "remedy_dissipated",
        "J/m",
        "energy the remedies removed so far (booked as their dissipation)",
        |r| r.remedy_dissipated,
        Now,
        &[peak(
            "remedy_dissipated_total",
            "energy the remedies removed",
        )],
    ),
    step(
        "remedy_injected",
        "J/m",
        "energy the remedies added so far (booked as their injection, seen by the injection test)",
        |r| r.remedy_injected,
        Now,
        &[peak("remedy_injected_total", "energy the remedies added")],
    ),
    booked!(0, pic_damping, dissipated),
    booked!(0, pic_damping, injected),
    booked!(1, min_node_mass, dissipated),
    booked!(1, min_node_mass, injected),
    booked!(2, f_reset, dissipated),
    booked!(2, f_reset, injected),
    booked!(3, bulk_damping, dissipated),
    booked!(3, bulk_damping, injected),
    booked!(4, cell_dilatation, dissipated),
    booked!(4, cell_dilatation, injected),
    booked!(5, j_bar, dissipated),
    booked!(5, j_bar, injected),
    booked!(6, volume_relaxation, dissipated),
    booked!(6, volume_relaxation, injected),
    booked!(7, pressure_smoothing, dissipated),
    booked!(7, pressure_smoothing, injected),
    booked!(8, null_space_filter, dissipated),
    booked!(8, null_space_filter, injected),
    booked!(9, shifting, dissipated),
    booked!(9, shifting, injected),
    booked!(10, artificial_viscosity, dissipated),
    booked!(10, artificial_viscosity, injected),
    booked!(11, grid_damping, dissipated),
    booked!(11, grid_damping, injected),
    booked!(12, speed_cap, dissipated),
    booked!(12, speed_cap, injected),
    step(
        "packing_error",
        "of the packing",
        "pressure-implicit step: mean of packing J - 1 over the cells whose nodes are full, the packing from the grid mass",
        |r| r.packing_error.unwrap_or(f64::NAN),
        Now,
        &[
            late("packing_error_late", "packing error of the grid mass"),
            peak("packing_error_peak", "largest packing error of the grid mass"),
        ],
    ),
    step(
        "solver_iterations",
        "iterations",
        "pressure-implicit step: most conjugate-gradient iterations of a step since the previous row",
        |r| r.solver_iterations.unwrap_or(f64::NAN),
        Max(f64::NAN),
        &[peak("solver_iterations_max", "most solver iterations in a step")],
    ),
    step(
        "solver_residual",
        "of |b|",
        "pressure-implicit step: largest final relative residual since the previous row",
        |r| r.solver_residual.unwrap_or(f64::NAN),
        Max(f64::NAN),
        &[peak("solver_residual_max", "largest final relative residual")],
    ),
    step(
        "projection_dissipated",
        "J/m",
        "pressure-implicit step: energy the projection removed since the previous row (kinetic lost less the pressure's work into stored energy; its drift and checkerboard controls and the extrapolation included)",
        |r| r.projection_dissipated.unwrap_or(f64::NAN),
        Sum,
        &[],
    ),
    step(
        "hourglass_dissipated",
        "J/m",
        "pressure-implicit step: energy the hourglass control removed since the previous row",
        |r| r.hourglass_dissipated.unwrap_or(f64::NAN),
        Sum,
        &[],
    ),
    step(
        "budget_drift",
        "J/m",
        "the budget with every booking (E + transfer loss + remedy dissipation - remedy injection) minus its value at t = 0",
        |r| r.budget_drift,
        Now,
        &[],
    ),
    step(
        "budget_closure",
        "J/m",
        "largest |budget_drift| since the previous row",
        |r| r.budget_drift.abs(),
        Max(0.0),
        &[peak(
            "budget_closure_max",
            "largest |drift| of the booked budget",
        )],
    ),
    step(
        "budget_closure_unbooked",
        "J/m",
        "largest |E + transfer loss - its value at t = 0| since the previous row (the remedies not booked)",
        |r| r.budget_drift_unbooked.abs(),
        Max(0.0),
        &[peak(
            "budget_closure_unbooked_max",
            "largest |drift| of the budget without the remedies' bookings",
        )],
    ),
    step(
        "max_accel_g",
        "g",
        "largest particle acceleration over g",
        |r| r.max_accel_g,
        Max(0.0),
        &[peak("max_accel_g", "largest acceleration")],
    ),
    step(
        "max_transfer_jump",
        "1",
        "largest velocity jump of a transfer, over the flow speed",
        |r| r.max_transfer_jump,
        Max(0.0),
        &[],
    ),
    step(
        "max_jump",
        "m/s",
        "largest velocity jump against the local flow",
        |r| r.max_jump,
        Max(0.0),
        &[peak("max_jump", "largest velocity jump")],
    ),
    step(
        "max_speed",
        "m/s",
        "largest particle speed",
        |r| r.max_speed,
        Max(0.0),
        &[],
    ),
    step(
        "courant",
        "(v + c) dt / h",
        "largest particle Courant number (c + |v|) dt / h",
        |r| r.courant,
        Max(0.0),
        &[peak("courant_max", "largest Courant number")],
    ),
    step(
        "j_min",
        "1",
        "smallest J",
        |r| r.j_min,
        Min(f64::INFINITY),
        &[],
    ),
    step(
        "j_max",
        "1",
        "largest J",
        |r| r.j_max,
        Max(f64::NEG_INFINITY),
        &[],
    ),
    step(
        "min_node_mass_ratio",
        "1",
        "smallest nodal mass over a full node's",
        |r| r.min_node_mass_ratio,
        Min(f64::INFINITY),
        &[],
    ),
    step(
        "max_node_accel_g",
        "1",
        "largest nodal acceleration over g",
        |r| r.max_node_accel_g,
        Max(0.0),
        &[],
    ),
    step(
        "node_advection",
        "|v| dt / h",
        "largest nodal advective number |v_i| dt / h",
        |r| r.node_advection,
        Max(0.0),
        &[peak("node_advection_max", "largest nodal advection")],
    ),
    step(
        "ringing_energy",
        "J/m",
        "particle kinetic energy minus the grid's after P2G",
        |r| r.ringing_energy,
        Now,
        &[],
    ),
    step(
        "n_outside",
        "1",
        "particles outside the grid",
        |r| r.n_outside as f64,
        Now,
        &[],
    ),
    step(
        "particles_lost",
        "1",
        "particles deleted so far",
        |r| r.particles_lost as f64,
        Now,
        &[],
    ),
    step(
        "mass_lost_fraction",
        "1",
        "share of the initial mass deleted so far",
        |r| r.mass_lost_fraction,
        Now,
        &[],
    ),
    step(
        "n_flagged",
        "1",
        "particles flagged since the previous row",
        |r| r.n_flagged as f64,
        Sum,
        &[],
    ),
    step(
        "events_opened",
        "1",
        "events opened since the previous row",
        |r| r.events_opened as f64,
        Sum,
        &[],
    ),
    field(
        "checkerboard_means",
        "index",
        "checkerboard share of the cell means of particle pressure (blind to a mode J-bar reads back from its nodes)",
        |f| or_nan(f.checkerboard_means),
        &[
            late("checkerboard_means_late", "late checkerboard of the cell means"),
            pre_failure(
                "checkerboard_means_pre_failure",
                "checkerboard of the cell means in the second before the blow-up",
            ),
            peak(
                "checkerboard_means_peak",
                "largest checkerboard of the cell means",
            ),
        ],
    ),
    field(
        "checkerboard_nodal",
        "of rho g h",
        "alternating amplitude of the nodal pressure that drives the forces",
        |f| or_nan(f.checkerboard_nodal),
        &[
            late("checkerboard_nodal_late", "late nodal checkerboard"),
            pre_failure(
                "checkerboard_nodal_pre_failure",
                "nodal checkerboard in the second before the blow-up",
            ),
            peak("checkerboard_nodal_peak", "largest nodal checkerboard"),
        ],
    ),
    field(
        "checkerboard_cell",
        "of rho g h",
        "alternating amplitude of the cell pressure (methods that carry one)",
        |f| or_nan(f.checkerboard_cell),
        &[
            late("checkerboard_cell_late", "late cell checkerboard"),
            peak("checkerboard_cell_peak", "largest cell checkerboard"),
        ],
    ),
    field(
        "pressure_spread",
        "1",
        "RMS of particle pressure about its cell's mean, over rho0 g h",
        |f| f.pressure_spread,
        &[],
    ),
    field(
        "hydro_rel_rms",
        "of rho g depth",
        "relative RMS departure from hydrostatic pressure",
        |f| f.hydro_rel_rms,
        &[
            late("hydro_rel_rms_late", "late hydrostatic departure, RMS"),
            pre_failure(
                "hydro_rel_rms_pre_failure",
                "hydrostatic departure in the second before the blow-up, RMS",
            ),
        ],
    ),
    field(
        "hydro_floor_rel_rms",
        "of rho g depth",
        "the same departure of the exact rest field of a flat layer of the same mass: the reference's sampling floor",
        |f| f.hydro_floor_rel_rms,
        &[late("hydro_floor_late", "late floor of the hydrostatic departure")],
    ),
    field(
        "hydro_excess_rel_rms",
        "of rho g depth",
        "hydrostatic departure above its floor, sqrt(max(departure^2 - floor^2, 0))",
        |f| f.hydro_excess_rel_rms,
        &[late(
            "hydro_excess_late",
            "late hydrostatic departure above its floor",
        )],
    ),
    field(
        "hydro_max",
        "of rho g depth",
        "largest departure from hydrostatic pressure",
        |f| f.hydro_max,
        &[
            late("hydro_max_late", "late hydrostatic departure, largest"),
            pre_failure(
                "hydro_max_pre_failure",
                "hydrostatic departure in the second before the blow-up, largest",
            ),
        ],
    ),
    field(
        "hydro_unexplained_rel_rms",
        "of rho g depth",
        "departure from the pressure that weight and vertical accelerations demand",
        |f| f.hydro_unexplained_rel_rms,
        &[late(
            "hydro_unexplained_rel_rms_late",
            "of it not explained by the accelerations",
        )],
    ),
    field(
        "front_x",
        "m",
        "surge front position",
        |f| or_nan(f.front_x),
        &[],
    ),
    field(
        "front_z",
        "1",
        "surge front Z = x / a",
        |f| or_nan(f.front_z),
        &[],
    ),
    field(
        "front_t",
        "1",
        "time T = t sqrt(2 g / a)",
        |f| f.front_t,
        &[],
    ),
];

/// A figure of that name is declared by some column.
pub fn figure_declared(name: &str) -> bool {
    COLUMNS
        .iter()
        .flat_map(|c| c.figures)
        .any(|f| f.name == name)
}

/// The declared column named `name`.
pub fn column(name: &str) -> Option<&'static Column> {
    COLUMNS.iter().find(|c| c.name == name)
}

/// The samples of step-report columns since the last row, one slot per
/// column (unused by field columns).
#[derive(Clone)]
pub struct Peaks {
    defs: &'static [Column],
    values: Vec<f64>,
}

impl Default for Peaks {
    fn default() -> Self {
        Peaks::of(COLUMNS)
    }
}

impl Peaks {
    /// For a timeseries of these columns.
    pub fn of(defs: &'static [Column]) -> Self {
        let mut p = Peaks {
            defs,
            values: vec![0.0; defs.len()],
        };
        p.reset();
        p
    }

    /// Folds in one step's report.
    pub fn add(&mut self, r: &StepReport) {
        for (c, acc) in self.defs.iter().zip(self.values.iter_mut()) {
            let Source::Step(get, sample) = c.source else {
                continue;
            };
            *acc = match sample {
                Now => continue,
                Max(_) => acc.max(get(r)),
                Min(_) => acc.min(get(r)),
                Sum => *acc + get(r),
            };
        }
    }

    /// Back to the state before any step, without allocating.
    pub fn reset(&mut self) {
        for (c, acc) in self.defs.iter().zip(self.values.iter_mut()) {
            *acc = match c.source {
                Source::Step(_, Max(from) | Min(from)) => from,
                _ => 0.0,
            };
        }
    }
}

#[derive(Clone)]
pub struct Timeseries {
    /// The declared columns (`COLUMNS`, or more in a test).
    pub defs: &'static [Column],
    pub step: Vec<u64>,
    /// Rows written only because an event opened (or the run stopped) at
    /// their step: never part of a "late" window.
    pub event_row: Vec<bool>,
    /// One vector per declared column.
    pub columns: Vec<Vec<f64>>,
}

impl Default for Timeseries {
    fn default() -> Self {
        Timeseries::of(COLUMNS)
    }
}

impl Timeseries {
    pub fn new() -> Self {
        Timeseries::default()
    }

    /// A timeseries of these columns.
    pub fn of(defs: &'static [Column]) -> Self {
        Timeseries {
            defs,
            step: vec![],
            event_row: vec![],
            columns: vec![vec![]; defs.len()],
        }
    }

    pub fn last_step(&self) -> Option<u64> {
        self.step.last().copied()
    }

    /// The values of a declared column (a name not in COLUMNS is a bug).
    pub fn column(&self, name: &str) -> &[f64] {
        let k = self
            .defs
            .iter()
            .position(|c| c.name == name)
            .unwrap_or_else(|| panic!("no timeseries column {name}"));
        &self.columns[k]
    }

    /// Appends a row: each column from its source, step-report columns
    /// sampled as declared (a non-finite extreme is missing); `event_row`
    /// when it is written only for an event.
    pub fn push(&mut self, r: &StepReport, p: &Peaks, f: &FieldMetrics, event_row: bool) {
        self.step.push(r.step);
        self.event_row.push(event_row);
        debug_assert!(std::ptr::eq(self.defs, p.defs), "peaks of other columns");
        for ((c, acc), col) in self.defs.iter().zip(&p.values).zip(&mut self.columns) {
            let v = match c.source {
                Source::Step(get, Now) => get(r),
                Source::Step(..) if acc.is_finite() => *acc,
                Source::Step(..) => f64::NAN,
                Source::Field(get) => get(f),
            };
            col.push(v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One pair of booking columns per remedy, reading its own registry
    /// slot.
    #[test]
    fn each_remedy_has_its_booking_columns_in_registry_order() {
        let keys = solver::remedies::REMEDY_KEYS;
        assert_eq!(keys.len(), monitor::remedy_booking::REMEDIES);
        for (i, key) in keys.iter().enumerate() {
            let mut r = StepReport::default();
            r.booked[i] = Some(monitor::remedy_booking::Booked {
                dissipated: 1.0 + i as f64,
                injected: 100.0 + i as f64,
            });
            for (part, want) in [("dissipated", 1.0), ("injected", 100.0)] {
                let c = column(&format!("booked_{key}_{part}")).expect("declared");
                let Source::Step(get, Now) = c.source else {
                    panic!("{} is not a step column", c.name)
                };
                assert_eq!(get(&r), want + i as f64, "{}", c.name);
            }
        }
        let booked = COLUMNS.iter().filter(|c| c.name.starts_with("booked_"));
        assert_eq!(booked.count(), 2 * keys.len());
    }

    #[test]
    fn names_are_unique_and_every_figure_name_is_unique() {
        let mut names: Vec<&str> = COLUMNS.iter().map(|c| c.name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), COLUMNS.len());
        let mut figures: Vec<&str> = COLUMNS
            .iter()
            .flat_map(|c| c.figures)
            .map(|f| f.name)
            .collect();
        let n = figures.len();
        figures.sort();
        figures.dedup();
        assert_eq!(figures.len(), n);
    }

    /// Rows sample as declared: the value now, the extreme and the sum
    /// since the previous row; an extreme never reached is missing.
    #[test]
    fn rows_sample_each_column_by_its_rule() {
        let mut p = Peaks::default();
        let report = |t: f64, accel: f64, j: f64, flagged: usize| StepReport {
            t,
            max_accel_g: accel,
            j_min: j,
            n_flagged: flagged,
            ..Default::default()
        };
        p.add(&report(0.1, 5.0, 0.9, 2));
        p.add(&report(0.2, 3.0, 0.95, 1));
        let mut ts = Timeseries::new();
        ts.push(
            &report(0.2, 3.0, 0.95, 1),
            &p,
            &FieldMetrics::default(),
            false,
        );
        assert_eq!(ts.column("t"), &[0.2]);
        assert_eq!(ts.column("max_accel_g"), &[5.0]);
        assert_eq!(ts.column("j_min"), &[0.9]);
        assert_eq!(ts.column("n_flagged"), &[3.0]);
        p.reset();
        ts.push(
            &report(0.3, 1.0, 1.0, 0),
            &p,
            &FieldMetrics::default(),
            false,
        );
        assert_eq!(ts.column("max_accel_g")[1], 0.0);
        assert!(ts.column("j_min")[1].is_nan(), "no step since the last row");
        assert!(
            ts.column("checkerboard_means")[1].is_nan(),
            "no checkerboard figure"
        );
    }

    /// A column declared once (here an extra one, in a test) reaches the
    /// rows, the summary's figures, the Parquet and CSV frame and the axis
    /// labels, with nothing else written for it.
    #[test]
    fn a_new_column_is_one_declaration() {
        const MOST: &[Figure] = &[peak("n_nonfinite_max", "most non-finite particles")];
        static EXTENDED: std::sync::LazyLock<Vec<Column>> = std::sync::LazyLock::new(|| {
            let mut defs = COLUMNS.to_vec();
            defs.push(step(
                "n_nonfinite",
                "count",
                "particles with a non-finite state",
                |r| r.n_nonfinite as f64,
                Max(0.0),
                MOST,
            ));
            defs
        });
        let defs: &'static [Column] = EXTENDED.as_slice();
        let (mut ts, mut p) = (Timeseries::of(defs), Peaks::of(defs));
        for (k, bad) in [0, 3, 1].into_iter().enumerate() {
            let r = StepReport {
                step: k as u64,
                t: 0.1 * k as f64,
                n_nonfinite: bad,
                ..Default::default()
            };
            p.add(&r);
            ts.push(&r, &p, &FieldMetrics::default(), false);
            p.reset();
        }
        assert_eq!(ts.column("n_nonfinite"), &[0.0, 3.0, 1.0]);
        let m = crate::output::metrics::summarise(&ts, &[], true);
        assert_eq!(m.figure("n_nonfinite_max"), Some(3.0));
        let frame = crate::output::tables::timeseries_frame(&ts).unwrap();
        let col = frame.column("n_nonfinite").unwrap().f64().unwrap().clone();
        assert_eq!(
            col.into_iter().collect::<Vec<_>>(),
            [Some(0.0), Some(3.0), Some(1.0)]
        );
        assert_eq!(defs.last().unwrap().label(), "n_nonfinite (count)");
    }

    #[test]
    fn labels_carry_units() {
        assert_eq!(column("e_kin").unwrap().label(), "e_kin (J/m)");
        assert_eq!(column("j_min").unwrap().label(), "j_min");
    }
}
