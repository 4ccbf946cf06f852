//! The ablation table: one row per method (the `method.*` keys that vary),
//! labelled by what it changes from the most common value of each key (the
//! baseline), with the fraction of runs that kicked (by cause, and with the
//! hallmark), that blew up, and the survival time as median [min, max].

use crate::report::data::{median, spread_text, Matrix, ParamKey, Row};
use crate::report::html::{Cell, Page};
use crate::report::matrix::cure;
use crate::report::plot::Res;
use crate::report::yardsticks::{self as yardsticks, Yardsticks};
use monitor::Cause;
use std::collections::BTreeMap;
use std::path::Path;
use study::output::summary::Status;
use study::replay::explain::counterfactual::{RARE_SHARE, REPRODUCED_SHARE};

/// For each varying `method.*` axis: its index and the baseline's value,
/// the named case's (`Matrix::baseline_case`) or else the most common.
fn baseline(m: &Matrix) -> Vec<(usize, String)> {
    let named = m
        .baseline_case
        .as_ref()
        .and_then(|name| m.rows.iter().find(|r| r.case() == name));
    m.axes
        .iter()
        .enumerate()
        .filter(|(_, k)| matches!(k, ParamKey::Method(_)))
        .map(|(i, _)| {
            if let Some(r) = named {
                return (i, r.params[i].clone());
            }
            let mut counts: BTreeMap<&String, usize> = BTreeMap::new();
            for r in &m.rows {
                *counts.entry(&r.params[i]).or_default() += 1;
            }
            let mode = counts
                .into_iter()
                .max_by_key(|(_, n)| *n)
                .map(|(v, _)| v.clone())
                .unwrap_or_default();
            (i, mode)
        })
        .collect()
}

/// What a run's method changes from the baseline ("baseline" when nothing).
fn label(m: &Matrix, base: &[(usize, String)], r: &Row) -> String {
    let changes: Vec<String> = base
        .iter()
        .filter(|(i, mode)| r.params[*i] != *mode)
        .map(|(i, _)| {
            let key = m.axes[*i].field();
            format!("{key} = {}", r.params[*i])
        })
        .collect();
    if changes.is_empty() {
        "baseline".into()
    } else {
        changes.join(", ")
    }
}

fn percent(k: usize, n: usize) -> Cell {
    Cell::Num(format!("{:.0} %", 100.0 * k as f64 / n.max(1) as f64))
}

/// The runs of each method, the baseline first, then by name.
fn method_groups<'a>(m: &'a Matrix, base: &[(usize, String)]) -> Vec<(String, Vec<&'a Row>)> {
    let mut groups: Vec<(String, Vec<&Row>)> = vec![];
    for r in &m.rows {
        let l = label(m, base, r);
        match groups.iter_mut().find(|(g, _)| *g == l) {
            Some((_, rows)) => rows.push(r),
            None => groups.push((l, vec![r])),
        }
    }
    groups.sort_by(|a, b| (a.0 != "baseline", &a.0).cmp(&(b.0 != "baseline", &b.0)));
    groups
}

const HEADERS: [&str; 18] = [
    "method",
    "runs",
    "kicked",
    "injection",
    "inversion",
    "anomaly",
    "cfl",
    "blew up",
    "survived (s)",
    "completed",
    "late departure",
    "late floor",
    "late excess",
    "late checkerboard, cell means",
    "late checkerboard, nodal",
    "late checkerboard, cell",
    "M particle-steps/s",
    "wall (s)",
];

/// One method's row: shares over all its runs; the late figures (mean over
/// the last simulated second) over its completed runs only, since a window
/// that holds a blow-up says nothing.
fn method_cells(label: &str, runs: &[&Row]) -> Vec<Cell> {
    let n = runs.len();
    let with = |keep: &dyn Fn(&monitor::Event) -> bool| {
        runs.iter()
            .filter(|r| r.summary.events.iter().any(keep))
            .count()
    };
    let blew = runs
        .iter()
        .filter(|r| r.summary.status == Status::BlewUp)
        .count();
    let completed: Vec<&&Row> = runs
        .iter()
        .filter(|r| r.summary.status == Status::Completed)
        .collect();
    let late = |f: &dyn Fn(&Row) -> Option<f64>| {
        let values: Vec<f64> = completed.iter().filter_map(|r| f(r)).collect();
        Cell::Num(spread_text(values.iter().copied(), values.len(), 3))
    };
    vec![
        Cell::Text(label.to_string()),
        Cell::Num(n.to_string()),
        percent(with(&|e| e.is_kick()), n),
        percent(with(&|e| e.cause == Cause::Injection), n),
        percent(with(&|e| e.cause == Cause::Inversion), n),
        percent(with(&|e| e.is_anomaly()), n),
        percent(with(&|e| e.cause == Cause::Cfl), n),
        percent(blew, n),
        Cell::Num(spread_text(runs.iter().map(|r| r.summary.t_end), n, 2)),
        Cell::Num(completed.len().to_string()),
        late(&|r| r.summary.metrics.figure("hydro_rel_rms_late")),
        late(&|r| r.summary.metrics.figure("hydro_floor_late")),
        late(&|r| r.summary.metrics.figure("hydro_excess_late")),
        late(&|r| r.summary.metrics.figure("checkerboard_means_late")),
        late(&|r| r.summary.metrics.figure("checkerboard_nodal_late")),
        late(&|r| r.summary.metrics.figure("checkerboard_cell_late")),
        Cell::Num(spread_text(
            runs.iter().map(|r| r.summary.particle_steps_per_s / 1e6),
            1,
            2,
        )),
        Cell::Num(format!(
            "{:.0}",
            runs.iter().map(|r| r.summary.wall_s).sum::<f64>()
        )),
    ]
}

/// One method's standing for the verdict.
pub struct MethodStanding {
    pub label: String,
    pub runs: usize,
    /// Runs that completed without a kick.
    pub clean: usize,
    /// Median late hydrostatic departure over its completed runs.
    pub late: Option<f64>,
}

/// The `k` methods that best avoid the kick: by the share of their runs
/// that completed without one, then by the median late hydrostatic
/// departure of their completed runs. Empty when no method key varies.
pub fn best_methods(m: &Matrix, k: usize) -> Vec<MethodStanding> {
    let base = baseline(m);
    if base.is_empty() {
        return vec![];
    }
    let groups = method_groups(m, &base);
    if groups.len() < 2 {
        return vec![];
    }
    let mut v: Vec<MethodStanding> = groups
        .iter()
        .map(|(label, runs)| {
            let completed = || {
                runs.iter()
                    .filter(|r| r.summary.status == Status::Completed)
            };
            let late: Vec<f64> = completed()
                .filter_map(|r| r.summary.metrics.figure("hydro_rel_rms_late"))
                .collect();
            MethodStanding {
                label: label.clone(),
                runs: runs.len(),
                clean: completed()
                    .filter(|r| !r.summary.events.iter().any(|e| e.is_kick()))
                    .count(),
                late: median(&late),
            }
        })
        .collect();
    let share = |s: &MethodStanding| s.clean as f64 / s.runs.max(1) as f64;
    v.sort_by(|a, b| {
        share(b).total_cmp(&share(a)).then(
            a.late
                .unwrap_or(f64::INFINITY)
                .total_cmp(&b.late.unwrap_or(f64::INFINITY)),
        )
    });
    v.truncate(k);
    v
}

/// The ablation table (a matrix section: `matrix::MATRIX_SECTIONS`);
/// nothing unless a method key varies.
pub fn methods_table(m: &Matrix, _out: &Path, page: &mut Page) -> Res {
    let base = baseline(m);
    if base.is_empty() {
        return Ok(());
    }
    let groups = method_groups(m, &base);
    if groups.len() < 2 {
        return Ok(());
    }
    page.h2("Methods: which change removes the kick");
    let from = match &m.baseline_case {
        Some(name) => format!("from the method of case {name} (`kick report --baseline`)"),
        None => "from the most common value of each varying method key".into(),
    };
    page.p(&format!("One row per method, named by what it changes {from}. Over all its runs (every case and ensemble member): the share with at least one kick, with a kick of each cause, with a kick that has the hallmark (the anomaly proper), with a time-step (cfl) event, and that blew up; the time survived (a completed run counts its t_end) as median [min, max]. Over its completed runs only, each the mean over the last simulated second as median [min, max]: the late hydrostatic departure, its floor (the same score of the exact rest field of a flat layer of the same mass on the same particles: what the reference's sampling of a disordered arrangement costs even the exact pressure) and its excess over that floor, sqrt(departure^2 - floor^2), and the checkerboard index. The median particle-steps per second, and the wall seconds summed over the runs."));
    let sticks = Yardsticks::of_matrix(m);
    let mut headers: Vec<String> = HEADERS.map(String::from).to_vec();
    if !sticks.is_empty() {
        page.p(&format!("The yardsticks a damper cannot pass (docs/physics.md section 7), measured for the same method (the same resolved method settings and particles per cell) at h = {} cm and K = {} MPa: from the walled Taylor-Green vortex, the fluid's viscosity as the method sees it (nu_phys, mode 1) and the method's own dissipation nu_num and beta (least squares of rate / (2 k²) = nu_num + beta k² over the inviscid rates of every mode run), both over the fluid's nu; from the sloshing tank at the viscous run, the period error against linear theory and the decay rate over 2 nu k²; from the surge front (viscous, free-slip floor) the early RMS error in Z after the best time shift and the late front speed dZ/dT (the data about 1.7). A method whose nu_num exceeds {} nu by more than its uncertainty (the larger of its movement when the rates move by 1 % and, from three modes, when the highest mode is left out) is a damper: whatever its kicks and late departure, it gets there by taking the flow's energy. Where nu_num, give or take its uncertainty, straddles that share, the verdict is undecided at this h.", 100.0 * yardsticks::CELL, yardsticks::BULK_MODULUS / 1e6, yardsticks::DAMPER_SHARE));
        page.p(&format!("Beside them: from the standing sound wave in a closed box (inviscid), the frequency error against c k and the excess decay as a viscosity, (rate - (2/3) nu k²) / ((2/3) k²), over nu, at mode 1 and at k h = π/4; from the inviscid Taylor-Green modes near k h = π/4 and π/2, the measured decay rates at {} MPa and at {} MPa (read as measured: the line nu_num + beta k² bends there); from every inviscid yardstick, the largest growth of the motion's energy (kinetic, potential and stored above the water at rest, averaged over an energy period, over 5 s or over any 1 s) as a share of the wave's, and the largest energy the booked terms cycled (the smaller of what they added and what they removed, each by its net over an energy period) over the wave's. The verdict, its rules fixed before the runs: a damper by nu_num (above), by the sound (mode 1's excess decay above {} /s: it loses 63 % of its amplitude within the dam break's second) or by the grid scale (the π/4 mode's rate above {} /s, twice the modern baseline's); a pump when the motion's energy grows by more than {} % of the wave's; accurate when every rule was measured and none fired; undecided otherwise. A method whose booked terms put in and take out more than the wave's energy also cycles.", yardsticks::BULK_MODULUS / 1e6, yardsticks::STIFF_BULK_MODULUS / 1e6, yardsticks::SOUND_DAMPER_RATE, yardsticks::GRID_DAMPER_RATE, 100.0 * yardsticks::PUMP_SHARE));
        headers.extend(YARDSTICK_HEADERS.map(String::from));
    }
    page.p(&format!("The cure column, its rule fixed before the runs (docs/physics.md section 7, the cure column): each method against the baseline on the same physics case (the same values of every axis that is not a method key, nor a key the formulation ignores), over the case's ensemble members. The baseline kicks in a case when at least {:.0} % of its members kicked; the method prevents it there when at most {:.0} % of its members kicked and none blew up; it brings a kick when the baseline's case is clean and the method's kicks. A method is a cure when it prevents the baseline's kick in more than half of its kicking cases (the count with its 95 % Wilson interval), brings none, and the yardsticks call it accurate (not judged when they were not measured or are undecided); the yardsticks' damper or pump comes first, whatever it prevents; one that prevents some and brings others moves the event.", 100.0 * REPRODUCED_SHARE, 100.0 * RARE_SHARE));
    headers.push("cure".into());
    let case_axes = cure::case_axes(&m.axes);
    let baseline_runs: Vec<&Row> = groups
        .iter()
        .find(|(l, _)| l == "baseline")
        .map_or(vec![], |(_, runs)| runs.clone());
    let rows: Vec<(String, Vec<Cell>)> = groups
        .iter()
        .map(|(l, runs)| {
            let mut cells = method_cells(l, runs);
            if !sticks.is_empty() {
                cells.extend(yardstick_cells(&sticks, runs));
            }
            cells.push(Cell::Text(if l == "baseline" {
                "-".into()
            } else {
                let p = cure::paired(&case_axes, &baseline_runs, runs);
                let y = runs.first().and_then(|r| sticks.of_method(&r.summary));
                cure::verdict(p, y)
            }));
            (String::new(), cells)
        })
        .collect();
    page.table("ablation", &headers, &rows);
    Ok(())
}

const YARDSTICK_HEADERS: [&str; 15] = [
    "nu_phys / nu",
    "nu_num / nu",
    "beta (m⁴/s)",
    "slosh period error",
    "slosh decay / theory",
    "surge early error, shifted",
    "surge late speed",
    "sound frequency error",
    "sound excess nu / nu (mode 1; k h = π/4)",
    "grid rate k h = π/4 (1/s)",
    "grid rate k h = π/2 (1/s)",
    "grid rates at 15 MPa (1/s)",
    "energy growth, inviscid",
    "booked cycled / wave",
    "verdict",
];

/// A method's yardsticks (its runs share one method; the first one's).
fn yardstick_cells(sticks: &Yardsticks, runs: &[&Row]) -> Vec<Cell> {
    let y = runs
        .first()
        .and_then(|r| sticks.of_method(&r.summary))
        .cloned()
        .unwrap_or_default();
    let num = |v: Option<f64>, f: &dyn Fn(f64) -> String| {
        Cell::Num(v.filter(|x| x.is_finite()).map_or("-".into(), f))
    };
    let over_nu = |v: Option<f64>| v.zip(y.nu).map(|(v, nu)| v / nu);
    let pair = |a: Option<f64>, b: Option<f64>, f: &dyn Fn(f64) -> String| {
        let one = |v: Option<f64>| v.filter(|x| x.is_finite()).map_or("-".into(), f);
        Cell::Num(format!("{}; {}", one(a), one(b)))
    };
    vec![
        num(over_nu(y.nu_phys), &|x| format!("{x:.3}")),
        num(over_nu(y.nu_num), &|x| format!("{x:.3}")),
        num(y.beta, &|x| format!("{x:.2e}")),
        num(y.slosh_period_error, &|x| format!("{:+.2} %", 100.0 * x)),
        num(y.slosh_decay_ratio, &|x| format!("{x:.2}")),
        num(y.surge_early_shifted, &|x| format!("{x:.3}")),
        num(y.surge_speed_late, &|x| format!("{x:.2}")),
        num(y.sound_frequency_error, &|x| format!("{:+.2} %", 100.0 * x)),
        pair(
            over_nu(y.sound_excess_nu),
            over_nu(y.sound_excess_nu_pi4),
            &|x| format!("{x:.3}"),
        ),
        num(y.grid_rate[0], &|x| format!("{x:.0}")),
        num(y.grid_rate[1], &|x| format!("{x:.0}")),
        pair(y.grid_rate_stiff[0], y.grid_rate_stiff[1], &|x| {
            format!("{x:.0}")
        }),
        num(y.energy_growth, &|x| format!("{:+.1} %", 100.0 * x)),
        num(y.booked_cycled, &|x| format!("{x:.2}")),
        Cell::Text(verdict_text(&y)),
    ]
}

/// The verdict with what decided it.
fn verdict_text(y: &yardsticks::Yardstick) -> String {
    let v = y.verdict();
    let mut why: Vec<String> = y.damps().iter().map(|w| w.to_string()).collect();
    if y.is_pump() == Some(true) {
        why.push("energy grows".into());
    }
    if y.is_cycling() == Some(true) {
        why.push("cycles".into());
    }
    let over = |v: Option<f64>| v.zip(y.nu).map(|(v, nu)| v / nu);
    let undecided = match (over(y.nu_num), over(y.nu_num_uncertainty)) {
        (Some(n), Some(u)) if y.is_damper().is_none() => format!(
            "undecided: nu_num = {n:.2} ± {u:.2} nu straddles {}",
            yardsticks::DAMPER_SHARE
        ),
        _ => "undecided: not every yardstick measured".into(),
    };
    let name = match v {
        yardsticks::Verdict::Undecided => undecided,
        _ => v.name().into(),
    };
    if why.is_empty() {
        name
    } else {
        format!("{name} ({})", why.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With Taylor-Green cases among the reference rows, the Methods table
    /// gains the yardstick columns and names the damper; without, it has
    /// none.
    #[test]
    fn the_methods_table_shows_the_yardsticks_of_its_methods() {
        use crate::report::yardsticks::test_rows::{decay, summary};
        let rate = |k: f64, nu: f64| 2.0 * k * k * nu;
        let reference = vec![
            summary("apic", 1, 0.0, decay(rate(15.0, 1e-4), 15.0, 0.0)),
            summary("apic", 2, 0.0, decay(rate(30.0, 1e-4), 30.0, 0.0)),
            summary("pic", 1, 0.0, decay(rate(15.0, 0.3), 15.0, 0.0)),
            summary("pic", 2, 0.0, decay(rate(30.0, 0.3), 30.0, 0.0)),
            summary("pic", 1, 0.5, decay(rate(15.0, 0.3005), 15.0, 0.0)),
            summary("apic", 1, 0.5, decay(rate(15.0, 6e-4), 15.0, 0.0)),
        ];
        // The dam-break rows: the same methods (same resolved settings).
        let dam_break = |t: &str| {
            let mut r = run(t, Some((0.1, 0.1)), vec![]);
            r.summary.params = reference[if t == "pic" { 2 } else { 0 }]
                .summary
                .params
                .clone();
            r
        };
        let rows = vec![dam_break("apic"), dam_break("apic"), dam_break("pic")];
        let mut m = Matrix {
            reference_rows: reference,
            baseline_case: None,
            recorded_runs: vec![],
            axes: vec![ParamKey::Method("transfer".into())],
            rows,
        };
        let html = |m: &Matrix| {
            let mut page = Page::default();
            methods_table(m, Path::new("."), &mut page).unwrap();
            page.finish("t")
        };
        let with = html(&m);
        for header in YARDSTICK_HEADERS {
            assert!(
                with.contains(&format!("<th>{header}</th>")),
                "{header}: {with}"
            );
        }
        // nu_num / nu: 0.2 for APIC, 600 for PIC, which is the damper.
        assert!(with.contains("<td>0.200</td>"), "{with}");
        assert!(with.contains("<td>600.000</td>"), "{with}");
        assert_eq!(with.matches(">damper (nu_num)</td>").count(), 1, "{with}");
        m.reference_rows.clear();
        assert!(!html(&m).contains("nu_num"), "no yardsticks, no columns");
    }
    use study::output::summary::{sample_event, Metrics, Summary, SCHEMA_VERSION};

    fn event(cause: Cause) -> monitor::Event {
        let mut e = sample_event();
        e.cause = cause;
        e
    }

    fn run(transfer: &str, late: Option<(f64, f64)>, events: Vec<monitor::Event>) -> Row {
        let status = if late.is_some() {
            Status::Completed
        } else {
            Status::BlewUp
        };
        let mut metrics = Metrics::default();
        metrics
            .figures
            .insert("hydro_rel_rms_late".into(), late.map(|l| l.0));
        metrics
            .figures
            .insert("checkerboard_means_late".into(), late.map(|l| l.1));
        // A floor of half the departure: the excess is sqrt(3) / 2 of it.
        let floor = late.map(|l| 0.5 * l.0);
        let excess = late.map(|l| 0.75f64.sqrt() * l.0);
        metrics.figures.insert("hydro_floor_late".into(), floor);
        metrics.figures.insert("hydro_excess_late".into(), excess);
        let summary = Summary {
            schema_version: SCHEMA_VERSION,
            case: transfer.into(),
            params: Default::default(),
            status,
            reason: String::new(),
            steps: 10,
            t_end: if late.is_some() { 5.0 } else { 1.5 },
            wall_s: 10.0,
            particles: 100,
            particle_steps_per_s: 2.0e6,
            final_state_hash: "0".into(),
            events,
            metrics,
            phases: vec![],
        };
        Row::for_test(summary, vec![transfer.into()])
    }

    fn text(c: &Cell) -> &str {
        match c {
            Cell::Num(s) | Cell::Text(s) => s,
        }
    }

    /// The cure column pairs each method with the baseline on the same
    /// physics case (the non-method axes), over its members.
    #[test]
    fn the_cure_column_pairs_each_method_with_the_baseline_case_by_case() {
        let kick = || vec![event(Cause::Jump)];
        // Axes: transfer (a method key) and K (the physics case).
        let at = |t: &str, k: &str, events: Vec<monitor::Event>| {
            let mut r = run(t, Some((0.1, 0.1)), events);
            r.params = vec![t.into(), k.into()];
            r
        };
        let mut rows = vec![];
        for _ in 0..5 {
            // The baseline (apic) kicks at K = 1 and 2, is clean at K = 3.
            rows.push(at("apic", "1", kick()));
            rows.push(at("apic", "2", kick()));
            rows.push(at("apic", "3", vec![]));
            // PIC prevents both kicks; FLIP prevents one and brings one.
            rows.push(at("pic", "1", vec![]));
            rows.push(at("pic", "2", vec![]));
            rows.push(at("pic", "3", vec![]));
            rows.push(at("flip", "1", vec![]));
            rows.push(at("flip", "2", kick()));
            rows.push(at("flip", "3", kick()));
        }
        // One of PIC's five members at K = 2 kicks: still at most 1 of 5.
        rows[4].summary.events = kick();
        // A sixth clean baseline member makes apic the most common transfer.
        rows.push(at("apic", "3", vec![]));
        let m = Matrix {
            reference_rows: vec![],
            baseline_case: None,
            recorded_runs: vec![],
            axes: vec![
                ParamKey::Method("transfer".into()),
                ParamKey::Material {
                    name: "water".into(),
                    field: "K".into(),
                },
            ],
            rows,
        };
        let mut page = Page::default();
        methods_table(&m, Path::new("."), &mut page).unwrap();
        let html = page.finish("t");
        assert!(html.contains("<th>cure</th>"), "{html}");
        assert!(
            html.contains("not judged: no yardstick (prevents 2 of 2 [0.34, 1.00], brings 0)"),
            "{html}"
        );
        assert!(
            html.contains("moves the event (prevents 1 of 2 [0.09, 0.91], brings 1)"),
            "{html}"
        );
    }

    /// `--baseline` names the case whose method the others are labelled
    /// and paired against, whatever is most common.
    #[test]
    fn a_named_baseline_replaces_the_most_common_method() {
        let mut m = Matrix {
            reference_rows: vec![],
            baseline_case: None,
            recorded_runs: vec![],
            axes: vec![ParamKey::Method("transfer".into())],
            rows: vec![
                run("apic", Some((0.2, 0.3)), vec![]),
                run("apic", Some((0.2, 0.3)), vec![]),
                run("pic", Some((0.2, 0.3)), vec![]),
            ],
        };
        let names = |m: &Matrix| -> Vec<String> {
            method_groups(m, &baseline(m))
                .into_iter()
                .map(|(l, _)| l)
                .collect()
        };
        assert_eq!(names(&m), ["baseline", "transfer = pic"]);
        m.baseline_case = Some("pic".into());
        assert_eq!(names(&m), ["baseline", "transfer = apic"]);
        let mut page = Page::default();
        methods_table(&m, Path::new("."), &mut page).unwrap();
        assert!(page.finish("t").contains("from the method of case pic"));
    }

    #[test]
    fn a_method_row_counts_kicks_over_all_runs_and_late_figures_over_completed_runs() {
        let m = Matrix {
            reference_rows: vec![],
            baseline_case: None,
            recorded_runs: vec![],
            axes: vec![ParamKey::Method("transfer".into())],
            rows: vec![
                run("pic", Some((0.05, 0.01)), vec![event(Cause::Impact)]),
                run("apic", Some((0.2, 0.3)), vec![]),
                run("apic", Some((0.4, 0.1)), vec![event(Cause::Injection)]),
                run(
                    "apic",
                    None,
                    vec![event(Cause::Inversion), event(Cause::Cfl)],
                ),
            ],
        };
        let base = baseline(&m);
        let groups = method_groups(&m, &base);
        let names: Vec<&str> = groups.iter().map(|(l, _)| l.as_str()).collect();
        assert_eq!(names, ["baseline", "transfer = pic"]);
        let cells = |i: usize| -> Vec<String> {
            let (l, runs) = &groups[i];
            method_cells(l, runs)
                .iter()
                .map(|c| text(c).to_string())
                .collect()
        };
        let column = |name: &str| HEADERS.iter().position(|h| *h == name).unwrap();
        let apic = cells(0);
        assert_eq!(apic.len(), HEADERS.len());
        assert_eq!(apic[column("runs")], "3");
        assert_eq!(apic[column("kicked")], "67 %");
        assert_eq!(apic[column("injection")], "33 %");
        assert_eq!(apic[column("inversion")], "33 %");
        assert_eq!(apic[column("cfl")], "33 %");
        assert_eq!(apic[column("blew up")], "33 %");
        assert_eq!(apic[column("survived (s)")], "5.00 [1.50, 5.00]");
        assert_eq!(apic[column("completed")], "2");
        // The blown-up run has no late window: it is not counted as zero.
        assert_eq!(apic[column("late departure")], "0.300 [0.200, 0.400]");
        assert_eq!(apic[column("late floor")], "0.150 [0.100, 0.200]");
        assert_eq!(apic[column("late excess")], "0.260 [0.173, 0.346]");
        assert_eq!(
            apic[column("late checkerboard, cell means")],
            "0.200 [0.100, 0.300]"
        );
        assert_eq!(apic[column("wall (s)")], "30");
        // PIC's one run completed without a kick; the baseline's one of three.
        let best = best_methods(&m, 3);
        let order: Vec<(&str, usize, usize)> = best
            .iter()
            .map(|b| (b.label.as_str(), b.clean, b.runs))
            .collect();
        assert_eq!(order, [("transfer = pic", 1, 1), ("baseline", 1, 3)]);
        assert!(
            (best[1].late.unwrap() - 0.3).abs() < 1e-12,
            "the median of 0.2 and 0.4"
        );
        let pic = cells(1);
        assert_eq!(pic[column("kicked")], "0 %", "an impact is not a kick");
        assert_eq!(pic[column("late departure")], "0.050");
        assert_eq!(pic[column("M particle-steps/s")], "2.00");
    }
}
