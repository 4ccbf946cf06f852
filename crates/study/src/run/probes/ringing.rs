//! Brackbill's ringing test (docs/physics.md section 7b): on a scene whose
//! one body carries a `grid_seed` flow, the growth of the perturbation's
//! kinetic energy E' about the drift after every step
//! (`monitor::ringing_growth`), the check `ringing` with the map's
//! coordinates U dt / h and c dt / h, and the table ringing.parquet (E' and
//! the drift's energy at the rows). With `output.end_when_checked` the run
//! ends once the fit's window has closed.

use crate::output::summary::Check;
use crate::output::tables;
use crate::run::{Probe, Run, Simulated};
use monitor::ringing_growth::{perturbation_energy, GrowthFigures, PerturbationGrowth};
use serde::{Deserialize, Serialize};
use solver::flows::Flow;
use solver::{Scene, Solver};
use std::path::PathBuf;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RingingFigures {
    /// The map's coordinates at the first step: U dt / h and c dt / h,
    /// c = sqrt(K / rho0) the sound speed at rest.
    pub flow_courant: f64,
    pub sound_courant: f64,
    /// The seed's share of |U| and its wavelength in cells.
    pub share: f64,
    pub wavelength_cells: f64,
    /// The growth fit (its keys sit beside these in the check).
    #[serde(flatten)]
    pub growth: GrowthFigures,
}

impl Check for RingingFigures {
    const NAME: &'static str = "ringing";
}

pub struct Ringing {
    growth: PerturbationGrowth,
    /// U (m/s), c (m/s), h (m), the seed's share and wavelength (cells).
    drift: f64,
    sound: f64,
    cell: f64,
    share: f64,
    wavelength_cells: f64,
    first_dt: Option<f64>,
    /// (t, E', drift energy) at each timeseries row.
    rows: Vec<(f64, f64, f64)>,
    dir: PathBuf,
    csv: bool,
}

impl Ringing {
    /// For a scene with one body whose flow is a grid seed.
    pub fn new(scene: &Scene, dir: PathBuf, csv: bool) -> Option<Self> {
        let [body] = scene.bodies.as_slice() else {
            return None;
        };
        let Some(Flow::GridSeed { share, mode }) = body.flow else {
            return None;
        };
        let material = &scene.materials[scene.material_index(body)?];
        let width = body.rect[2] - body.rect[0];
        Some(Ringing {
            growth: PerturbationGrowth::with_capacity(4096),
            drift: body.velocity[0].hypot(body.velocity[1]),
            sound: (material.k / material.rho0).sqrt(),
            cell: scene.cell,
            share,
            wavelength_cells: width / mode as f64 / scene.cell,
            first_dt: None,
            rows: vec![],
            dir,
            csv,
        })
    }

    fn figures(&self) -> RingingFigures {
        let dt_over_h = self.first_dt.unwrap_or(0.0) / self.cell;
        RingingFigures {
            flow_courant: self.drift * dt_over_h,
            sound_courant: self.sound * dt_over_h,
            share: self.share,
            wavelength_cells: self.wavelength_cells,
            growth: self.growth.figures(),
        }
    }
}

impl Probe<Solver> for Ringing {
    fn begin(&mut self, run: &Run<Solver>) -> std::io::Result<()> {
        self.first_dt = Some(run.stepper.next_dt());
        self.growth.observe(&run.stepper.view());
        Ok(())
    }

    fn after_step(&mut self, run: &Run<Solver>, _: &[u32]) -> std::io::Result<()> {
        self.growth.observe(&run.stepper.view());
        Ok(())
    }

    fn ends_run(&self) -> Option<String> {
        self.growth.closed().then(|| {
            let f = self.growth.figures();
            format!(
                "ringing growth fitted: its window closed ({:?}) after step {}",
                f.window_end, f.fit_to_step
            )
        })
    }

    fn row(&mut self, run: &Run<Solver>) {
        let (e, drift) = perturbation_energy(&run.stepper.view());
        self.rows.push((run.stepper.time(), e, drift));
    }

    fn finish(&mut self, _: &Run<Solver>, outcome: &mut Simulated) -> std::io::Result<()> {
        let t: Vec<f64> = self.rows.iter().map(|r| r.0).collect();
        let e: Vec<f64> = self.rows.iter().map(|r| r.1).collect();
        let d: Vec<f64> = self.rows.iter().map(|r| r.2).collect();
        tables::write_columns(
            &[("t", &t), ("e_perturbation", &e), ("e_drift", &d)],
            &self.dir,
            "ringing",
            self.csv,
        )?;
        outcome.metrics.set_check(&self.figures());
        Ok(())
    }
}
