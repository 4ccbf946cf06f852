//! `kick report`: turns a case folder or a matrix folder into
//! `report/index.html` (self-contained, relative links) with every figure as
//! PNG and SVG, and an animated GIF around each kick. The pages are built in
//! `report_case` and `report_matrix`; this file dispatches and reads tables.

use crate::plot_common::{short, Res};
use crate::report_case::case_report;
use crate::report_matrix::matrix_report;
use polars::prelude::*;
use std::path::{Path, PathBuf};

/// Writes the report of `dir` (a case or a matrix) and returns the page's path.
pub fn report(dir: &Path) -> Res<PathBuf> {
    if dir.join("summary.parquet").exists() {
        matrix_report(dir)
    } else if dir.join("summary.json").exists() {
        case_report(dir)
    } else {
        Err(format!(
            "{}: neither a matrix folder (summary.parquet) nor a case folder (summary.json)",
            dir.display()
        ))
    }
}

pub(crate) fn read_parquet(path: &Path) -> Res<DataFrame> {
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    ParquetReader::new(file)
        .finish()
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// A numeric column (nulls as NaN).
pub(crate) fn f64_column(df: &DataFrame, name: &str) -> Option<Vec<f64>> {
    let c = df.column(name).ok()?.cast(&DataType::Float64).ok()?;
    Some(
        c.f64()
            .ok()?
            .into_iter()
            .map(|v| v.unwrap_or(f64::NAN))
            .collect(),
    )
}

/// Any column as text (nulls as "").
pub(crate) fn text_column(df: &DataFrame, name: &str) -> Option<Vec<String>> {
    let c = df.column(name).ok()?;
    Some(
        (0..c.len())
            .map(|i| match c.get(i) {
                Ok(AnyValue::String(s)) => s.to_string(),
                Ok(AnyValue::Null) => String::new(),
                Ok(AnyValue::Float64(f)) => short(f),
                Ok(other) => other.to_string(),
                Err(_) => String::new(),
            })
            .collect(),
    )
}
