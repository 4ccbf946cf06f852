//! A mixture case (docs/physics.md section 6): the two phases stepped
//! together by `solver::Mixture`, each watched by its own monitor (events
//! carry their phase), one timeseries per phase (`timeseries.parquet` the
//! fluid's, `timeseries_solid.parquet` the solid's), the mixture's own rows
//! in `mixture.parquet`, particle files per phase, ring checkpoints of the
//! mixture and both monitors, and the verification checks its scene allows.

use crate::run::probes::darcy::DarcyColumn;
use crate::run::probes::drag_decay::{DecayCheck, DecayLaw};
use crate::run::probes::drag_layer::LayerCheck;
use crate::run::probes::mixture_conservation::MixtureConservation;
use crate::run::probes::mixture_rows::MixtureRows;
use crate::run::probes::surface::SurfaceCheck;
use crate::run::probes::terzaghi::{Terzaghi, TerzaghiCheck};
use crate::run::Runner;
use crate::study_file::{Case, MixtureSpec};
use solver::{Mixture, Solver};

/// The mixture a case describes, at t = 0.
pub(crate) fn build(case: &Case, spec: &MixtureSpec) -> Result<Mixture, String> {
    let [solid, fluid] = case.phase_configs();
    let phases = [solid, fluid].map(Solver::new);
    let [solid, fluid] = phases;
    let solid = solid.map_err(|e| format!("setup (solid): {e}"))?;
    let fluid = fluid.map_err(|e| format!("setup (fluid): {e}"))?;
    let mut mix = Mixture::new([solid, fluid], spec.drag).map_err(|e| format!("setup: {e}"))?;
    if spec.fixed_solid {
        mix = mix.fix_solid();
    }
    if spec.pore_pressure {
        mix = mix.with_pore_pressure();
    }
    if spec.pore_node_average {
        mix = mix
            .with_pore_node_average()
            .map_err(|e| format!("setup: {e}"))?;
    }
    if spec.volume_constraint {
        mix = mix.with_volume_constraint();
    }
    if spec.top_traction > 0.0 {
        mix = mix.with_top_load(spec.top_traction, spec.traction_ramp);
    }
    if !spec.drained.is_empty() {
        mix = mix
            .with_drained(&spec.drained, spec.drained_pressure)
            .map_err(|e| format!("setup: {e}"))?;
    }
    if !spec.inflow.is_empty() {
        mix = mix
            .with_inflow(&spec.inflow, spec.inflow_velocity)
            .map_err(|e| format!("setup: {e}"))?;
    }
    Ok(mix)
}

/// The mixture's own rows and the checks its scene allows, in the order
/// they write their parts of the summary.
pub(crate) fn attach_checks(runner: &mut Runner<Mixture>, case: &Case, spec: &MixtureSpec) {
    let scene = &case.solver.scene;
    let dir = runner.options().dir.clone().unwrap_or_default();
    let csv = runner.options().csv;
    let mix = &runner.stepper;
    let law = DecayLaw::of(scene, spec, mix);
    let decay = law.map(|law| DecayCheck::new(law, spec.drag.update));
    let layer = LayerCheck::new(scene, spec, mix);
    let terzaghi = TerzaghiCheck::new(scene, spec, mix).map(|check| Terzaghi {
        check,
        dir: dir.clone(),
        csv,
    });
    let surface = SurfaceCheck::new(scene);
    let darcy = DarcyColumn::new(scene, spec);
    let conservation = MixtureConservation::new(scene, spec, mix);
    runner.attach(MixtureRows::new(law, dir, csv));
    if let Some(p) = decay {
        runner.attach(p);
    }
    if let Some(p) = layer {
        runner.attach(p);
    }
    if let Some(p) = terzaghi {
        runner.attach(p);
    }
    if let Some(p) = surface {
        runner.attach(p);
    }
    if let Some(p) = darcy {
        runner.attach(p);
    }
    runner.attach(conservation);
}
