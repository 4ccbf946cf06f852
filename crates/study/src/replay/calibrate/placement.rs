//! Placements that resolve to one patch. Each `[[calibration.patch]]`
//! takes the qualifying block nearest its point at the plant, so two
//! points can land on the same block, or on blocks within `merge_cells`
//! of each other. Planted together they would add their speeds, and each
//! would be credited with the other's event. The later of two such
//! placements is therefore not planted. Where each lands is read by one
//! step from the twin's checkpoint with every patch at a negligible speed:
//! the same resolution the planted runs make.

use super::{cells_of, perturb_of, stepped_once, Twin};
use crate::study_file::calibration::CalibrationSpec;
use crate::study_file::Case;
use monitor::{CellRange, Geometry};

/// A speed no detector sees (m/s): the placement, not the plant, is wanted.
const NEGLIGIBLE: f64 = 1e-12;

/// Per placement, the earlier placement whose patch it shares (None: its own).
pub(super) fn shared(
    case: &Case,
    twin: &Twin,
    spec: &CalibrationSpec,
    size: usize,
) -> Result<Vec<Option<usize>>, String> {
    let n = spec.patch.len();
    let perturb = (0..n)
        .map(|k| perturb_of((case, spec), k, twin.t_plant, size, Some(NEGLIGIBLE)))
        .collect();
    let Some((solver, _)) = stepped_once(case, twin, perturb)? else {
        return Ok(vec![None; n]);
    };
    let geom = Geometry::from_scene(&case.solver.scene);
    let mut cells: Vec<Option<CellRange>> = vec![None; n];
    for p in solver.planted() {
        cells[p.entry] = Some(cells_of(&geom, p.region));
    }
    Ok(first_sharers(&cells, case.monitor.merge_cells))
}

/// For each patch, the first earlier one of its own (not itself sharing)
/// within `reach` cells of it.
fn first_sharers(cells: &[Option<CellRange>], reach: usize) -> Vec<Option<usize>> {
    let mut shared: Vec<Option<usize>> = vec![None; cells.len()];
    for b in 0..cells.len() {
        let Some(cb) = cells[b] else { continue };
        shared[b] =
            (0..b).find(|&a| shared[a].is_none() && cells[a].is_some_and(|ca| ca.near(&cb, reach)));
    }
    shared
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(i: usize) -> Option<CellRange> {
        Some(CellRange {
            i_min: i,
            j_min: 0,
            i_max: i + 1,
            j_max: 1,
        })
    }

    #[test]
    fn a_patch_on_or_beside_an_earlier_one_shares_it() {
        // 0 and 2 on one block; 3 within 3 cells of 0's; 1 and 4 apart;
        // 5 not placed.
        let cells = [at(10), at(30), at(10), at(14), at(19), None];
        assert_eq!(
            first_sharers(&cells, 3),
            vec![None, None, Some(0), Some(0), None, None]
        );
        // With no reach, only the same block is shared.
        assert_eq!(
            first_sharers(&cells, 0),
            vec![None, None, Some(0), None, None, None]
        );
    }
}
