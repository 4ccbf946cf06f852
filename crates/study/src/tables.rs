//! Tables written with polars: the per-case timeseries and the matrix
//! summary, as Parquet (always) and CSV (with --csv). NaN and missing values
//! become nulls.

use crate::output_files::write_atomic;
use crate::timeseries::{Timeseries, COLUMNS};
use polars::prelude::*;
use serde_json::Value;
use std::path::Path;

fn io(e: PolarsError) -> std::io::Error {
    std::io::Error::other(e.to_string())
}

fn nullable(v: &[f64]) -> Vec<Option<f64>> {
    v.iter().map(|x| x.is_finite().then_some(*x)).collect()
}

pub fn timeseries_frame(ts: &Timeseries) -> PolarsResult<DataFrame> {
    let mut cols = vec![Column::new("step".into(), &ts.step)];
    for (name, values) in COLUMNS.iter().zip(&ts.columns) {
        cols.push(Column::new((*name).into(), nullable(values)));
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
    let mut df = timeseries_frame(ts).map_err(io)?;
    write_frame(&mut df, dir, "timeseries", csv)
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

/// One row per case: `case`, one column per parameter (dotted key), the run's
/// figures and one column per metric, plus `case_dir`.
pub fn summary_frame(rows: &[(String, Value)]) -> PolarsResult<DataFrame> {
    let mut param_keys: Vec<String> = vec![];
    let mut metric_keys: Vec<String> = vec![];
    for (_, s) in rows {
        for (set, field) in [(&mut param_keys, "params"), (&mut metric_keys, "metrics")] {
            if let Some(m) = s[field].as_object() {
                for k in m.keys() {
                    if !set.contains(k) {
                        set.push(k.clone());
                    }
                }
            }
        }
    }
    param_keys.sort();
    let mut cols = vec![json_column(
        "case",
        &rows.iter().map(|(_, s)| s.get("case")).collect::<Vec<_>>(),
    )];
    for k in &param_keys {
        let v: Vec<Option<&Value>> = rows.iter().map(|(_, s)| s["params"].get(k)).collect();
        cols.push(json_column(k, &v));
    }
    for k in [
        "status",
        "reason",
        "steps",
        "t_end",
        "wall_s",
        "particles",
        "particle_steps_per_s",
    ] {
        let v: Vec<Option<&Value>> = rows.iter().map(|(_, s)| s.get(k)).collect();
        cols.push(json_column(k, &v));
    }
    let n_events: Vec<Option<f64>> = rows
        .iter()
        .map(|(_, s)| s["events"].as_array().map(|a| a.len() as f64))
        .collect();
    cols.push(Column::new("n_events".into(), n_events));
    for k in &metric_keys {
        let v: Vec<Option<&Value>> = rows
            .iter()
            .map(|(_, s)| s["metrics"].get(k).filter(|v| !v.is_null()))
            .collect();
        let name = if param_keys.contains(k) {
            format!("metric.{k}")
        } else {
            k.clone()
        };
        cols.push(json_column(&name, &v));
    }
    let dirs: Vec<String> = rows.iter().map(|(d, _)| d.clone()).collect();
    cols.push(Column::new("case_dir".into(), dirs));
    DataFrame::new(cols)
}

/// OUT/summary.parquet and OUT/summary.csv (both always: the matrix table is small).
pub fn write_summary(rows: &[(String, Value)], out: &Path) -> std::io::Result<()> {
    let mut df = summary_frame(rows).map_err(io)?;
    write_frame(&mut df, out, "summary", true)
}
