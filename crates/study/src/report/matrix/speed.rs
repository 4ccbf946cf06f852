//! Speed against accuracy on the matrix page: cost (wall seconds per
//! simulated second) against the late hydrostatic departure, its excess
//! over the exact floor, and, when the study tracks a surge front, its early
//! error; when the methods' yardsticks are known (`report::yardsticks`),
//! against the method's own dissipation nu_num / nu too. Each with its
//! Pareto front as a figure and as a table of the cheapest case for a
//! stated error.

use crate::report::data::{Matrix, Row};
use crate::report::html::{link, Cell, Page};
use crate::report::plot::matrix::{pareto_front, ParetoFigure};
use crate::report::plot::{render, Res};
use crate::report::yardsticks::Yardsticks;
use std::path::Path;
use study::output::summary::Status;
use study::run::probes::surge_front::SurgeFrontFigures;

/// The accuracy figures the speed-accuracy front is drawn against: the late
/// hydrostatic departure always, the surge front's early error (shifted)
/// when the study tracks a front.
/// (A matrix section: `matrix::MATRIX_SECTIONS`.)
pub fn speed_accuracy(m: &Matrix, out: &Path, page: &mut Page) -> Res {
    page.h2("Speed against accuracy");
    let rows = &m.rows;
    pareto(
        m,
        out,
        page,
        (
            "speed_accuracy",
            "late hydrostatic rel. RMS",
            "late hydrostatic departure",
        ),
        Row::hydro_late_or_pre_failure,
    )?;
    let front = |r: &Row| {
        Row::nan(
            r.summary
                .metrics
                .check::<SurgeFrontFigures>()
                .and_then(|c| c.rms_error_early_shifted),
        )
    };
    let excess = |r: &Row| Row::nan(r.summary.metrics.figure("hydro_excess_late"));
    if rows.iter().any(|r| excess(r).is_finite()) {
        pareto(
            m,
            out,
            page,
            (
                "speed_accuracy_excess",
                "late hydrostatic excess over its floor",
                "the late hydrostatic departure's excess over the exact floor, sqrt(d² - f²)",
            ),
            excess,
        )?;
    }
    let sticks = Yardsticks::of_matrix(m);
    let own = |r: &Row| {
        let y = sticks.of_method(&r.summary);
        Row::nan(
            y.and_then(|y| y.nu_num.zip(y.nu))
                .map(|(n, nu)| n.abs() / nu),
        )
    };
    if rows.iter().any(|r| own(r).is_finite()) {
        pareto(
            m,
            out,
            page,
            (
                "speed_accuracy_dissipation",
                "method's own dissipation |nu_num| / nu",
                "the method's own dissipation (Taylor-Green, h = 1 cm, 1.5 MPa) over the fluid's viscosity",
            ),
            own,
        )?;
    }
    if rows.iter().any(|r| front(r).is_finite()) {
        pareto(
            m,
            out,
            page,
            (
                "speed_accuracy_front",
                "surge front, early shifted RMS error (Z)",
                "the surge front's early error after the best time shift",
            ),
            front,
        )?;
    }
    Ok(())
}

/// Cost (wall seconds per simulated second) against `error`, one point per
/// case, with the Pareto front: completed cases when at least two completed;
/// otherwise every case that ran (a blown-up one's accuracy then over the
/// second before it blew up). `names`: file stem, axis label, caption.
fn pareto(
    m: &Matrix,
    out: &Path,
    page: &mut Page,
    names: (&str, &str, &str),
    error: impl Fn(&Row) -> f64,
) -> Res {
    let (stem, label, caption) = names;
    let rows = &m.rows;
    let point = |r: &Row| (r.case().to_string(), r.summary.wall_s / r.t_end(), error(r));
    let ran = |r: &&Row| r.summary.status != Status::Failed && r.t_end() > 0.0;
    let completed: Vec<_> = rows
        .iter()
        .filter(ran)
        .filter(|r| r.summary.status == Status::Completed)
        .map(point)
        .collect();
    let (points, which) = if completed.len() >= 2 {
        (completed, "completed cases")
    } else {
        (
            rows.iter().filter(ran).map(point).collect(),
            "all cases, blown-up ones over the second before failure; fewer than two completed",
        )
    };
    if points.len() < 2 {
        return Ok(());
    }
    let fig = ParetoFigure {
        title: format!("Speed against accuracy ({which})"),
        x_label: "wall seconds per simulated second".into(),
        y_label: label.into(),
        points,
    };
    page.figure(
        &render(&fig, out, stem)?,
        &format!("Cost against {caption}, Pareto front in red"),
    );
    cheapest_table(m, &fig.points, stem, label, page);
    Ok(())
}

/// The Pareto front as a table: for an error of at most each front point's,
/// that point is the cheapest case that ran.
fn cheapest_table(
    m: &Matrix,
    points: &[(String, f64, f64)],
    stem: &str,
    label: &str,
    page: &mut Page,
) {
    let front = cheapest_for_error(points);
    if front.is_empty() {
        return;
    }
    page.p(&format!(
        "The cheapest case for a stated {label}: for an error of at most the first column, no case that ran costs less than the one named (its name gives its parameters; the cost is as measured on the machine and under the load the matrix ran with)."
    ));
    let headers = [
        "error at most",
        "cheapest case",
        "wall s per simulated s",
        "M particle-steps/s",
    ]
    .map(String::from);
    let rows: Vec<(String, Vec<Cell>)> = front
        .iter()
        .filter_map(|&i| {
            let (case, cost, error) = &points[i];
            let row = m.rows.iter().find(|r| r.case() == case)?;
            let cells = vec![
                Cell::Num(format!("{error:.4}")),
                Cell::Text(link(row.link.as_deref(), row.case())),
                Cell::Num(format!("{cost:.3}")),
                Cell::Num(format!("{:.2}", row.summary.particle_steps_per_s / 1e6)),
            ];
            Some((String::new(), cells))
        })
        .collect();
    page.table(&format!("{stem}_cheapest"), &headers, &rows);
}

/// Indices of the Pareto front of (name, cost, error) points with positive
/// finite cost and error, cheapest first: each is the cheapest point whose
/// error is at most its own.
pub fn cheapest_for_error(points: &[(String, f64, f64)]) -> Vec<usize> {
    let usable: Vec<usize> = (0..points.len())
        .filter(|&i| {
            let (_, x, y) = points[i];
            x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite()
        })
        .collect();
    let xy: Vec<(f64, f64)> = usable.iter().map(|&i| (points[i].1, points[i].2)).collect();
    pareto_front(&xy).into_iter().map(|k| usable[k]).collect()
}
