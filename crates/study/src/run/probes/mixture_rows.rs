//! The mixture's own rows (`mixture.parquet`): relative velocity (and the
//! exact decay where the scene has one), drag dissipation, total energy
//! and momentum.

use super::drag_decay::{relative_velocity, DecayLaw};
use crate::output::tables;
use crate::run::{Probe, Run, Simulated};
use solver::{Mixture, Vec2};
use std::path::{Path, PathBuf};

#[derive(Default)]
struct Columns {
    step: Vec<f64>,
    t: Vec<f64>,
    dt: Vec<f64>,
    dv_x: Vec<f64>,
    dv_y: Vec<f64>,
    dv_exact_x: Vec<f64>,
    dv_exact_y: Vec<f64>,
    drag_dissipated: Vec<f64>,
    drag_nodes: Vec<f64>,
    drag_stable_dt: Vec<f64>,
    e_total: Vec<f64>,
    momentum_x: Vec<f64>,
    momentum_y: Vec<f64>,
}

impl Columns {
    fn push(&mut self, mix: &Mixture, dv: Vec2, exact: Option<Vec2>, e_total: f64) {
        let c = mix.last_coupling();
        let p = mix.momentum();
        let exact = exact.unwrap_or(Vec2::new(f64::NAN, f64::NAN));
        let s = mix.phase(0);
        self.step.push(s.step_count() as f64);
        self.t.push(mix.time());
        self.dt.push(s.view().dt);
        self.dv_x.push(dv.x);
        self.dv_y.push(dv.y);
        self.dv_exact_x.push(exact.x);
        self.dv_exact_y.push(exact.y);
        self.drag_dissipated.push(mix.drag_dissipated());
        self.drag_nodes.push(c.nodes as f64);
        self.drag_stable_dt.push(c.stable_dt);
        self.e_total.push(e_total);
        self.momentum_x.push(p.x);
        self.momentum_y.push(p.y);
    }

    fn write(&self, dir: &Path, csv: bool) -> std::io::Result<()> {
        tables::write_columns(
            &[
                ("step", &self.step),
                ("t", &self.t),
                ("dt", &self.dt),
                ("dv_x", &self.dv_x),
                ("dv_y", &self.dv_y),
                ("dv_exact_x", &self.dv_exact_x),
                ("dv_exact_y", &self.dv_exact_y),
                ("drag_dissipated", &self.drag_dissipated),
                ("drag_nodes", &self.drag_nodes),
                ("drag_stable_dt", &self.drag_stable_dt),
                ("e_total", &self.e_total),
                ("momentum_x", &self.momentum_x),
                ("momentum_y", &self.momentum_y),
            ],
            dir,
            "mixture",
            csv,
        )
    }
}

/// A row of the mixture's own at every timeseries row; `mixture.parquet` at the end.
pub struct MixtureRows {
    columns: Columns,
    /// The drag-decay scene's exact relative velocity, if it is one.
    law: Option<DecayLaw>,
    dir: PathBuf,
    csv: bool,
}

impl MixtureRows {
    pub fn new(law: Option<DecayLaw>, dir: PathBuf, csv: bool) -> Self {
        MixtureRows {
            columns: Columns::default(),
            law,
            dir,
            csv,
        }
    }
}

impl Probe<Mixture> for MixtureRows {
    fn row(&mut self, run: &Run<Mixture>) {
        let mix = run.stepper;
        let exact = self.law.map(|law| law.exact(mix.time()));
        let e_total = mix.energy().total();
        self.columns
            .push(mix, relative_velocity(mix), exact, e_total);
    }

    fn finish(&mut self, _: &Run<Mixture>, _: &mut Simulated) -> std::io::Result<()> {
        self.columns.write(&self.dir, self.csv)
    }
}
