//! The speed the velocity-jump rule should find at each planted patch,
//! read from the twin's own step after the plant: the plant goes in after
//! G2P, so over that step each patch particle's change is the twin's plus
//! dv under every method. A particle is found when its departure from the
//! local flow, plus dv along the plant's direction, reaches the rule's
//! threshold in a calm local flow; the patch is found when
//! `monitor.min_cluster_particles` of them are. So the prediction is that
//! many particles' smallest such dv (docs/findings/detector_calibration.md).
//! A jump must also add kinetic energy: a push against a particle's motion
//! counts only once it leaves the particle faster than at the start of its
//! step. The prediction counts only the patch's own particles (a cluster
//! may also take in particles already flagged beside it) and leaves out
//! the energy test: a finding well below or above it names one of those.

use super::{stepped_once, Bracket, Twin};
use crate::study_file::Case;
use monitor::jump::Margin;
use solver::Vec2;

/// Sets each placed bracket's `predicted` from one step of the twin.
pub(super) fn fill(case: &Case, twin: &Twin, brackets: &mut [Bracket]) -> Result<(), String> {
    if brackets.iter().all(|b| b.region.is_none()) {
        return Ok(());
    }
    let Some((solver, mut watches)) = stepped_once(case, twin, vec![])? else {
        return Ok(());
    };
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
        let d = Vec2::new(d[0], d[1]);
        let needs: Vec<Option<f64>> = inside
            .iter()
            .zip(&margins)
            .map(|(&p, m)| {
                m.filter(|m| m.calm)
                    .map(|m| gaining_from(needed(&m, d), v.v[p], v.v_prev[p], d))
            })
            .collect();
        b.predicted = smallest_found(&needs, least);
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

/// The smallest dv from `from` on along `d` after which the particle's
/// speed exceeds its speed at the start of the step: |v + dv d| > |v_prev|,
/// that is dv^2 + 2 (v . d) dv + |v|^2 - |v_prev|^2 > 0.
fn gaining_from(from: f64, v: Vec2, v_prev: Vec2, d: Vec2) -> f64 {
    let along = v.dot(&d);
    let c = v.norm_squared() - v_prev.norm_squared();
    let from = from.max(0.0);
    if from * from + 2.0 * along * from + c > 0.0 {
        return from;
    }
    // It fails at `from`: it holds past the larger root.
    -along + (along * along - c).max(0.0).sqrt()
}

/// The `least`-th smallest dv over the calm, judged particles (None: fewer).
fn smallest_found(needs: &[Option<f64>], least: usize) -> Option<f64> {
    let mut needs: Vec<f64> = needs.iter().flatten().map(|n| n.max(0.0)).collect();
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
        // The 4th smallest; a ring of spray or an unsettled flow (None)
        // does not count.
        let mut needs = vec![
            Some(0.02),
            Some(0.019),
            Some(0.018),
            Some(0.017),
            Some(0.016),
        ];
        assert!((smallest_found(&needs, 4).unwrap() - 0.019).abs() < 1e-15);
        needs[0] = None;
        needs[1] = None;
        assert_eq!(smallest_found(&needs, 4), None);
        // Falling at 0.07 m/s (and at the start of the step): an upward
        // push adds kinetic energy only past 0.14 m/s.
        let down = Vec2::new(0.0, -0.07);
        assert!((gaining_from(0.02, down, down, up) - 0.14).abs() < 1e-12);
        // Rising, or sped up by the step already: the threshold's dv gains.
        assert_eq!(gaining_from(0.02, -down, -down * 0.5, up), 0.02);
        assert_eq!(
            gaining_from(0.02, Vec2::new(0.1, 0.0), Vec2::new(0.05, 0.0), up),
            0.02
        );
        // Falling faster than at the start of the step: a small push still
        // leaves it faster (dv < 0.02 here), a middling one does not.
        let (v, v_prev) = (Vec2::new(0.0, -0.07), Vec2::new(0.0, -0.05));
        assert_eq!(gaining_from(0.01, v, v_prev, up), 0.01);
        assert!((gaining_from(0.05, v, v_prev, up) - 0.12).abs() < 1e-12);
    }
}
