//! Tables written with polars: the per-case timeseries and the matrix
//! summary, as Parquet (always) and CSV (with --csv). NaN and missing values
//! become nulls.

use crate::output::files::write_atomic;
use crate::output::summary::Summary;
use crate::output::timeseries::Timeseries;
use polars::prelude::*;
use serde_json::Value;
use std::collections::BTreeSet;
use std::path::Path;

fn io(e: PolarsError) -> std::io::Error {
    std::io::Error::other(e.to_string())
}

fn nullable(v: &[f64]) -> Vec<Option<f64>> {
    v.iter().map(|x| x.is_finite().then_some(*x)).collect()
}

pub fn timeseries_frame(ts: &Timeseries) -> PolarsResult<DataFrame> {
    let mut cols = vec![
        Column::new("step".into(), &ts.step),
        Column::new("event_row".into(), &ts.event_row),
    ];
    for (c, values) in ts.defs.iter().zip(&ts.columns) {
        cols.push(Column::new(c.name.into(), nullable(values)));
    }
    DataFrame::new(cols)
}

/// Writes `stem`.parquet (and `stem`.csv) in `dir`, each atomically.
pub fn write_frame(df: &mut DataFrame, dir: &Path, stem: &str, csv: bool) -> std::io::Result<()> {
    let mut bytes = Vec::new();
    ParquetWriter::new(&mut bytes).finish(df).map_err(io)?;
    write_atomic(&dir.join(format!("{stem}.parquet")), &bytes)?;
    if csv {
        let mut bytes = Vec::new();
        CsvWriter::new(&mut bytes)
            .include_header(true)
            .finish(df)
            .map_err(io)?;
        write_atomic(&dir.join(format!("{stem}.csv")), &bytes)?;
    }
    Ok(())
}

pub fn write_timeseries(ts: &Timeseries, dir: &Path, csv: bool) -> std::io::Result<()> {
    write_timeseries_as(ts, dir, "timeseries", csv)
}

/// The timeseries as `stem`.parquet (a mixture writes one per phase).
pub fn write_timeseries_as(
    ts: &Timeseries,
    dir: &Path,
    stem: &str,
    csv: bool,
) -> std::io::Result<()> {
    let mut df = timeseries_frame(ts).map_err(io)?;
    write_frame(&mut df, dir, stem, csv)
}

/// Named f64 columns (same length) as `stem`.parquet.
pub fn write_columns(
    columns: &[(&str, &[f64])],
    dir: &Path,
    stem: &str,
    csv: bool,
) -> std::io::Result<()> {
    let cols = columns
        .iter()
        .map(|(name, v)| Column::new((*name).into(), nullable(v)))
        .collect();
    let mut df = DataFrame::new(cols).map_err(io)?;
    write_frame(&mut df, dir, stem, csv)
}

/// A column of JSON values typed by what it holds: numbers as f64, strings,
/// booleans, anything else as its JSON text.
fn json_column(name: &str, values: &[Option<&Value>]) -> Column {
    let present = || values.iter().flatten();
    if present().all(|v| v.is_number()) {
        let v: Vec<Option<f64>> = values.iter().map(|v| v.and_then(|v| v.as_f64())).collect();
        Column::new(name.into(), v)
    } else if present().all(|v| v.is_boolean()) {
        let v: Vec<Option<bool>> = values.iter().map(|v| v.and_then(|v| v.as_bool())).collect();
        Column::new(name.into(), v)
    } else {
        let v: Vec<Option<String>> = values
            .iter()
            .map(|v| {
                v.map(|v| match v {
                    Value::String(s) => s.clone(),
                    other => other.to_string(),
                })
            })
            .collect();
        Column::new(name.into(), v)
    }
}

/// One matrix row: a case's summary and its folder relative to the matrix folder.
#[derive(Clone, Debug)]
pub struct SummaryRow {
    pub case_dir: String,
    pub summary: Summary,
}

/// Each row's metrics as one flat object (`Metrics::flattened`).
fn metrics_objects(rows: &[SummaryRow]) -> Vec<serde_json::Map<String, Value>> {
    rows.iter().map(|r| r.summary.metrics.flattened()).collect()
}

/// One row per case: `case`, one column per parameter (dotted key), the run's
/// figures, `n_events`, one column per metric (dotted keys), and `case_dir`.
pub fn summary_frame(rows: &[SummaryRow]) -> PolarsResult<DataFrame> {
    let param_keys: BTreeSet<&String> = rows.iter().flat_map(|r| r.summary.params.keys()).collect();
    let metrics = metrics_objects(rows);
    let s = |f: fn(&Summary) -> f64| -> Vec<f64> { rows.iter().map(|r| f(&r.summary)).collect() };
    let text = |f: fn(&SummaryRow) -> String| -> Vec<String> { rows.iter().map(f).collect() };
    let mut cols = vec![Column::new("case".into(), text(|r| r.summary.case.clone()))];
    for k in &param_keys {
        let v: Vec<Option<&Value>> = rows.iter().map(|r| r.summary.params.get(*k)).collect();
        cols.push(json_column(k, &v));
    }
    cols.push(Column::new(
        "status".into(),
        text(|r| r.summary.status.as_str().to_string()),
    ));
    cols.push(Column::new(
        "reason".into(),
        text(|r| r.summary.reason.clone()),
    ));
    cols.push(Column::new("steps".into(), s(|x| x.steps as f64)));
    cols.push(Column::new("t_end".into(), s(|x| x.t_end)));
    cols.push(Column::new("wall_s".into(), s(|x| x.wall_s)));
    cols.push(Column::new("particles".into(), s(|x| x.particles as f64)));
    cols.push(Column::new(
        "particle_steps_per_s".into(),
        s(|x| x.particle_steps_per_s),
    ));
    cols.push(Column::new("n_events".into(), s(|x| x.events.len() as f64)));
    // Every row's keys: the checks differ between scenes.
    let metric_keys: BTreeSet<&String> = metrics.iter().flat_map(|m| m.keys()).collect();
    for k in metric_keys {
        let v: Vec<Option<&Value>> = metrics
            .iter()
            .map(|m| m.get(k).filter(|v| !v.is_null()))
            .collect();
        let name = if param_keys.contains(k) {
            format!("metric.{k}")
        } else {
            k.clone()
        };
        cols.push(json_column(&name, &v));
    }
    cols.push(Column::new("case_dir".into(), text(|r| r.case_dir.clone())));
    DataFrame::new(cols)
}

/// OUT/summary.parquet and OUT/summary.csv (both always: the matrix table is small).
pub fn write_summary(rows: &[SummaryRow], out: &Path) -> std::io::Result<()> {
    let mut df = summary_frame(rows).map_err(io)?;
    write_frame(&mut df, out, "summary", true)
}
