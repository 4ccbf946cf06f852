//! The speed the velocity-jump rule should find at each planted patch,
//! read from the twin's own step after the plant: the plant goes in after
//! G2P, so over that step each patch particle's change is the twin's plus
//! dv under every method. A particle is found when its departure from the
//! local flow, plus dv along the plant's direction, reaches the rule's
//! threshold in a calm local flow; the patch is found when
//! `monitor.min_cluster_particles` of them are. So the prediction is that
//! many particles' smallest such dv (docs/findings/detector_calibration.md).
//! It leaves out the energy test, the gain condition and the merging with
//! open events: a finding well below or above it names one of those.

use super::{Bracket, Twin};
use crate::run::case::watches;
use crate::run::Stepper;
use crate::study_file::Case;
use monitor::jump::Margin;
use solver::{Solver, Vec2};

/// Sets each placed bracket's `predicted` from one step of the twin.
pub(super) fn fill(case: &Case, twin: &Twin, brackets: &mut [Bracket]) -> Result<(), String> {
    if brackets.iter().all(|b| b.region.is_none()) {
        return Ok(());
    }
    let mut cfg = case.solver.clone();
    cfg.perturb.clear();
    cfg.scene.initial = solver::InitialState::ZeroStress;
    let mut solver = Solver::new(cfg).map_err(|e| format!("setup: {e}"))?;
    let mut watches = watches(&solver, case);
    solver
        .load(&twin.checkpoint, &mut watches)
        .map_err(|e| e.to_string())?;
    if solver.finished() {
        return Ok(());
    }
    Stepper::advance(&mut solver)?;
    let v = solver.view();
    watches[0].observe(&v);
    let least = case.monitor.min_cluster_particles.max(1);
    for b in brackets.iter_mut() {
        let (Some(region), Some(d)) = (b.region, b.direction) else {
            continue;
        };
        let inside: Vec<usize> = (0..v.x.len())
            .filter(|&p| solver::perturb::covers(region, v.x[p]))
            .collect();
        let margins = watches[0].monitor.jump_margins(&v, &inside);
        b.predicted = smallest_found(&margins, Vec2::new(d[0], d[1]), least);
    }
    Ok(())
}

/// The dv along `d` that takes a departure to its threshold (0 when it is
/// there already).
fn needed(m: &Margin, d: Vec2) -> f64 {
    let along = m.departure.dot(&d);
    let across2 = (m.departure.norm_squared() - along * along).max(0.0);
    if m.departure.norm() >= m.threshold {
        return 0.0;
    }
    (m.threshold * m.threshold - across2).max(0.0).sqrt() - along
}

/// The `least`-th smallest dv over the calm, judged particles (None: fewer).
fn smallest_found(margins: &[Option<Margin>], d: Vec2, least: usize) -> Option<f64> {
    let mut needs: Vec<f64> = margins
        .iter()
        .flatten()
        .filter(|m| m.calm)
        .map(|m| needed(m, d).max(0.0))
        .collect();
    if needs.len() < least {
        return None;
    }
    needs.sort_by(f64::total_cmp);
    Some(needs[least - 1])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn margin(x: f64, y: f64, threshold: f64) -> Option<Margin> {
        Some(Margin {
            departure: Vec2::new(x, y),
            threshold,
            calm: true,
        })
    }

    #[test]
    fn the_prediction_is_the_clusters_last_particle_to_cross() {
        let up = Vec2::new(0.0, 1.0);
        // Along the plant: 0.02 - 0.005; against it: 0.02 + 0.005.
        assert!((needed(&margin(0.0, 0.005, 0.02).unwrap(), up) - 0.015).abs() < 1e-15);
        assert!((needed(&margin(0.0, -0.005, 0.02).unwrap(), up) - 0.025).abs() < 1e-15);
        // Across it: sqrt(0.02^2 - 0.012^2) = 0.016.
        assert!((needed(&margin(0.012, 0.0, 0.02).unwrap(), up) - 0.016).abs() < 1e-12);
        // Over the threshold already.
        assert_eq!(needed(&margin(0.0, -0.03, 0.02).unwrap(), up), 0.0);
        // The 4th smallest of the calm ones; a ring of spray and an
        // unsettled flow do not count.
        let mut ms: Vec<Option<Margin>> = [0.0, 0.001, 0.002, 0.003, 0.004]
            .iter()
            .map(|&a| margin(0.0, a, 0.02))
            .collect();
        assert!((smallest_found(&ms, up, 4).unwrap() - 0.019).abs() < 1e-15);
        ms[0] = None;
        ms[1] = ms[1].map(|m| Margin { calm: false, ..m });
        assert_eq!(smallest_found(&ms, up, 4), None);
    }
}
