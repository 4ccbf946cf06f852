//! `kick inf-sup`: the discrete inf-sup test of a velocity-pressure pair
//! (`solver::stages::projection::inf_sup`: the projection's collocated
//! pair, and a staggered one for comparison) on a study's box at several cell
//! sizes, for the whole box (free slip and no slip) and for the scene's
//! bodies at t = 0 (a dam break's column: a free surface). A stable pair
//! keeps beta bounded away from 0 with no trend in h; the table says
//! whether the gradient sees the constant and the checkerboard.

use crate::output::files::write_atomic;
use crate::output::tables;
use polars::prelude::*;
use serde::{Deserialize, Serialize};
use solver::stages::projection::inf_sup::{self, Mask, PairKind};
use solver::Scene;
use std::path::Path;

/// One mask at one cell size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InfSupRow {
    pub pair: String,
    pub mask: String,
    pub h: f64,
    pub pressures: usize,
    pub velocities: usize,
    /// Rayleigh quotients of S (0: in the gradient's kernel).
    pub constant_quotient: f64,
    pub checkerboard_quotient: f64,
    /// Probes deflated as kernel.
    pub kernel: usize,
    pub lambda_min: f64,
    pub beta: f64,
    pub residual: f64,
    pub lambda_max: f64,
    pub lanczos_steps: usize,
    pub wall_s: f64,
}

/// The most cells a mask may have (a Lanczos basis of 400 vectors of them
/// must fit in memory).
const MAX_CELLS: usize = 1_000_000;

/// The masks of a scene at cell size h: the whole box with free-slip and
/// with no-slip walls, and the bodies' cells (all walls of the box, none
/// periodic, whatever the scene says: the pair is what is measured).
fn masks(scene: &Scene, h: f64) -> Result<Vec<(&'static str, Mask)>, String> {
    let cells = scene.size.map(|l| (l / h).round() as usize);
    for (axis, &n) in cells.iter().enumerate() {
        let fits = (n as f64 * h - scene.size[axis]).abs() <= 1e-9 * scene.size[axis];
        if n < 2 || !fits {
            return Err(format!(
                "--cell {h}: the box's {} m is not a whole number (at least 2) of cells",
                scene.size[axis]
            ));
        }
    }
    if cells[0] * cells[1] > MAX_CELLS {
        return Err(format!(
            "--cell {h}: {} x {} cells is out of range (allowed at most {MAX_CELLS} cells)",
            cells[0], cells[1]
        ));
    }
    let full = Mask::full(cells, h);
    let mut held = full.clone();
    held.no_slip = true;
    let rects: Vec<[f64; 4]> = scene
        .bodies
        .iter()
        .map(|b| {
            let o = scene.origin;
            [
                b.rect[0] - o[0],
                b.rect[1] - o[1],
                b.rect[2] - o[0],
                b.rect[3] - o[1],
            ]
        })
        .collect();
    let mut masks = vec![("box, free slip", full), ("box, no slip", held)];
    let bodies = Mask::of_rects(cells, h, &rects);
    if bodies.fluid.iter().any(|&f| f) {
        masks.push(("bodies at t = 0", bodies));
    } else {
        eprintln!("kick inf-sup: --cell {h}: no cell centre lies in a body; that mask is left out");
    }
    Ok(masks)
}

/// Runs the test for every pair, mask and cell size; writes
/// OUT/inf_sup.{parquet,csv,json}.
pub fn run(
    scene: &Scene,
    pairs: &[PairKind],
    cells: &[f64],
    max_steps: usize,
    out: &Path,
) -> Result<Vec<InfSupRow>, String> {
    let mut rows = vec![];
    for &h in cells {
        for (name, mask) in masks(scene, h)? {
            for &kind in pairs {
                rows.push(row(kind, name, &mask, max_steps)?);
            }
        }
    }
    write(&rows, out).map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(rows)
}

/// One pair on one mask.
fn row(kind: PairKind, name: &str, mask: &Mask, max_steps: usize) -> Result<InfSupRow, String> {
    let h = mask.h;
    let started = std::time::Instant::now();
    let r = inf_sup::test(mask, kind, max_steps).map_err(|e| format!("{name}, h = {h}: {e}"))?;
    let quotient = |k: &str| {
        r.probes
            .iter()
            .find(|p| p.name == k)
            .map_or(f64::NAN, |p| p.quotient)
    };
    Ok(InfSupRow {
        pair: kind.name().into(),
        mask: name.into(),
        h,
        pressures: r.pressures,
        velocities: r.velocities,
        constant_quotient: quotient("constant"),
        checkerboard_quotient: quotient("checkerboard"),
        kernel: r.deflated,
        lambda_min: r.lambda_min,
        beta: r.beta,
        residual: r.residual,
        lambda_max: r.lambda_max,
        lanczos_steps: r.lanczos_steps,
        wall_s: started.elapsed().as_secs_f64(),
    })
}

fn write(rows: &[InfSupRow], out: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(out)?;
    write_atomic(
        &out.join("inf_sup.json"),
        serde_json::to_string_pretty(rows)?.as_bytes(),
    )?;
    let f = |name: &str, get: fn(&InfSupRow) -> f64| {
        Column::new(name.into(), rows.iter().map(get).collect::<Vec<_>>())
    };
    let u = |name: &str, get: fn(&InfSupRow) -> usize| {
        Column::new(
            name.into(),
            rows.iter().map(|r| get(r) as u64).collect::<Vec<_>>(),
        )
    };
    let text = |name: &str, get: fn(&InfSupRow) -> &str| {
        Column::new(name.into(), rows.iter().map(get).collect::<Vec<_>>())
    };
    let cols = vec![
        text("pair", |r| &r.pair),
        text("mask", |r| &r.mask),
        f("h", |r| r.h),
        u("pressures", |r| r.pressures),
        u("velocities", |r| r.velocities),
        f("constant_quotient", |r| r.constant_quotient),
        f("checkerboard_quotient", |r| r.checkerboard_quotient),
        u("kernel", |r| r.kernel),
        f("lambda_min", |r| r.lambda_min),
        f("beta", |r| r.beta),
        f("residual", |r| r.residual),
        f("lambda_max", |r| r.lambda_max),
        u("lanczos_steps", |r| r.lanczos_steps),
        f("wall_s", |r| r.wall_s),
    ];
    let mut df = DataFrame::new(cols).map_err(|e| std::io::Error::other(e.to_string()))?;
    tables::write_frame(&mut df, out, "inf_sup", true)
}
