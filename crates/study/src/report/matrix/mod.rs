//! The matrix report page: every case's page first (so the matrix page can
//! link them), then the sections of `MATRIX_SECTIONS` in order: the verdict,
//! the bug report's behaviours, the methods, refinement, the mixtures,
//! outcome and late-hydrostatic heatmaps, the stability map, the explained
//! events by mechanism, the ringing map, the detection of planted kicks
//! (a calibration folder), speed against
//! accuracy, the ensembles and the case table. The rows are read once
//! (`data::Matrix`, from each case's summary.json found through
//! summary.parquet's `case_dir`) and every section renders from them.

pub mod behaviours;
pub mod cure;
pub mod detection;
pub mod heatmaps;
pub mod mechanisms;
pub mod methods;
pub mod mixture;
pub mod refinement;
pub mod ringing;
pub mod runs;
pub mod speed;
pub mod stability;
pub mod verdict;

use crate::report::case::case_report;
use crate::report::data::{Matrix, RecordedRun};
use crate::report::html::Page;
use crate::report::plot::{err, Res};
use std::path::{Path, PathBuf};
use study::output::files::{relative_path, write_atomic};

/// One section of the matrix page.
pub struct Section {
    /// What the section shows (its errors, the tests and readers of this list).
    pub name: &'static str,
    /// Written only when some parameter varies (the matrix has axes).
    pub needs_axes: bool,
    /// Appends the section to the page; its figures go into the folder.
    pub write: fn(&Matrix, &Path, &mut Page) -> Res,
}

/// The matrix page's sections, in the order the page shows them.
pub const MATRIX_SECTIONS: &[Section] = &[
    Section {
        name: "verdict",
        needs_axes: false,
        write: verdict::verdict,
    },
    // Its axes may come from the recorded runs alone (a matrix that ran
    // nothing the record held).
    Section {
        name: "behaviours",
        needs_axes: false,
        write: behaviours::behaviours,
    },
    Section {
        name: "ablation",
        needs_axes: true,
        write: methods::methods_table,
    },
    Section {
        name: "refinement",
        needs_axes: true,
        write: refinement::refinement_table,
    },
    Section {
        name: "mixture",
        needs_axes: true,
        write: mixture::mixture_section,
    },
    Section {
        name: "heatmaps",
        needs_axes: true,
        write: heatmaps::heatmaps,
    },
    Section {
        name: "stability",
        needs_axes: true,
        write: stability::stability_map,
    },
    Section {
        name: "mechanisms",
        needs_axes: false,
        write: mechanisms::mechanism_table,
    },
    Section {
        name: "ringing",
        needs_axes: true,
        write: ringing::ringing_map,
    },
    Section {
        name: "detection",
        needs_axes: false,
        write: detection::detection_table,
    },
    Section {
        name: "speed_accuracy",
        needs_axes: false,
        write: speed::speed_accuracy,
    },
    Section {
        name: "ensembles",
        needs_axes: false,
        write: runs::ensemble_table,
    },
    Section {
        name: "cases",
        needs_axes: false,
        write: runs::case_table,
    },
];

/// The matrix page (and every case's page); returns its path.
pub fn matrix_report(
    dir: &Path,
    yardsticks: &[PathBuf],
    baseline: Option<&str>,
    recorded_runs: Vec<RecordedRun>,
) -> Res<PathBuf> {
    let out = dir.join("report");
    let mut m = Matrix::read(dir)?;
    m.recorded_runs = recorded_runs;
    if let Some(name) = baseline {
        if !m.rows.iter().any(|r| r.case() == name) {
            return Err(format!("--baseline {name}: no such case in the matrix"));
        }
        m.baseline_case = Some(name.to_string());
    }
    for other in yardsticks {
        m.reference_rows.extend(Matrix::read(other)?.rows);
    }
    std::fs::create_dir_all(&out).map_err(err)?;
    // Case pages first, so the matrix page can link them.
    for r in &mut m.rows {
        match case_report(&r.dir) {
            Ok(index) => r.link = Some(relative_path(&out, &index)),
            Err(e) => eprintln!("kick report: {}: {e}", r.case()),
        }
    }
    std::fs::create_dir_all(&out).map_err(err)?;
    let mut page = Page::default();
    for section in MATRIX_SECTIONS {
        if section.needs_axes && m.axes.is_empty() {
            continue;
        }
        (section.write)(&m, &out, &mut page)
            .map_err(|e| format!("the {} section: {e}", section.name))?;
    }
    let title = format!(
        "kick matrix report: {}",
        dir.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let index = out.join("index.html");
    write_atomic(&index, page.finish(&title).as_bytes()).map_err(err)?;
    Ok(index)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The page's order: the verdict first, the sections about the varying
    /// parameters, then speed, the ensembles and every case.
    #[test]
    fn the_matrix_page_lists_its_sections_once_in_order() {
        let names: Vec<&str> = MATRIX_SECTIONS.iter().map(|s| s.name).collect();
        assert_eq!(
            names,
            [
                "verdict",
                "behaviours",
                "ablation",
                "refinement",
                "mixture",
                "heatmaps",
                "stability",
                "mechanisms",
                "ringing",
                "detection",
                "speed_accuracy",
                "ensembles",
                "cases"
            ]
        );
        let needs_axes: Vec<&str> = MATRIX_SECTIONS
            .iter()
            .filter(|s| s.needs_axes)
            .map(|s| s.name)
            .collect();
        assert_eq!(
            needs_axes,
            [
                "ablation",
                "refinement",
                "mixture",
                "heatmaps",
                "stability",
                "ringing"
            ]
        );
    }
}
