//! `kick report`: turns a case folder or a matrix folder into
//! `report/index.html` (self-contained, relative links) with every figure as
//! PNG and SVG, and an animated GIF around each kick. The entry of the
//! report modules, which import one another without a cycle:
//! report -> case / matrix -> the matrix page's sections
//! (matrix::MATRIX_SECTIONS) -> data / html (leaves). It lives in the
//! binary: the library it reads cannot reach it.

pub mod case;
pub mod data;
pub mod explain_picture;
pub mod html;
pub mod matrix;
pub mod plot;
pub mod yardsticks;

use crate::report::case::case_report;
use crate::report::data::RecordedRun;
use crate::report::matrix::matrix_report;
use crate::report::plot::Res;
use std::path::{Path, PathBuf};

/// Writes the report of `dir` (a case or a matrix) and returns the page's
/// path. A matrix's Methods table also reads the viscous-decay, slosh and surge-front
/// matrix folders `yardsticks` (`yardsticks`), and takes the method of
/// the case `baseline` as its baseline (None: the most common one); its
/// four-behaviour table adds the `recorded_runs` of earlier matrices.
pub fn report(
    dir: &Path,
    yardsticks: &[PathBuf],
    baseline: Option<&str>,
    recorded_runs: Vec<RecordedRun>,
) -> Res<PathBuf> {
    if dir.join("summary.parquet").exists() {
        matrix_report(dir, yardsticks, baseline, recorded_runs)
    } else if dir.join("summary.json").exists() {
        case_report(dir)
    } else {
        Err(format!(
            "{}: neither a matrix folder (summary.parquet) nor a case folder (summary.json)",
            dir.display()
        ))
    }
}
