//! A kick that builds up over many steps (docs/physics.md section 4):
//! the velocity-jump rule sees the same change at every step size. The
//! monitor watches water at rest whose view shows a 2 x 2-cell patch
//! speeding up at a constant rate for 30 ms (a test-only ramp on the
//! read-only view, the solver untouched): the kick as the particles carry
//! it, the same at both steps. Judged per step, a 0.06 m/s ramp departs
//! from the flow by 1e-4 m/s a step at the explicit step and 0.013 m/s at
//! the implicit one, both under the 0.02 m/s threshold; over the window
//! it is the whole change.

use crate::common::*;
use monitor::{Event, Monitor, MonitorConfig};
use solver::*;

const PLANT_T: f64 = 0.2;
const RAMP_SECONDS: f64 = 0.03;
const PATCH: [f64; 4] = [0.19, 0.09, 0.21, 0.11];

/// Water at rest, 0.4 m wide and 0.2 m deep (h = 1 cm), watched to 0.3 s;
/// from 0.2 s the view adds `ramp` m/s upward to the patch's particles,
/// spread evenly over 30 ms. The events and the largest step.
fn ramped_water(formulation: Formulation, windowed: bool, ramp: f64) -> (Vec<Event>, f64) {
    let mut s = resting_water(formulation);
    let cfg = MonitorConfig {
        windowed_jumps: windowed,
        ..MonitorConfig::default()
    };
    let mut m = Monitor::new(cfg, &s.view());
    let in_patch: Vec<bool> = s
        .view()
        .x
        .iter()
        .map(|x| (PATCH[0]..PATCH[2]).contains(&x.x) && (PATCH[1]..PATCH[3]).contains(&x.y))
        .collect();
    assert_eq!(in_patch.iter().filter(|&&p| p).count(), 16);
    let added = |t: f64| ramp * ((t - PLANT_T) / RAMP_SECONDS).clamp(0.0, 1.0);
    let (mut v, mut v_prev, mut dt_max) = (vec![], vec![], 0.0_f64);
    while s.time() < 0.3 {
        s.step().unwrap();
        let view = s.view();
        dt_max = dt_max.max(view.dt);
        observe_pushed(&mut m, view, &in_patch, added, &mut v, &mut v_prev);
    }
    (m.events().to_vec(), dt_max)
}

/// The kicks found at the patch (within 3 cells), after asserting that no
/// event opened anywhere else or before the ramp.
fn kicks_at_the_patch(events: &[Event], tag: &str) -> Vec<Event> {
    let [i0, j0, i1, j1] = PATCH.map(|x| (x / 0.01).round() as usize);
    for e in events {
        let c = e.cells;
        let near = c.i_min + 3 >= i0 && c.j_min + 3 >= j0 && c.i_max < i1 + 3 && c.j_max < j1 + 3;
        assert!(
            near && e.t >= PLANT_T,
            "{tag}: event away from the ramp: {e:?}"
        );
    }
    events.iter().filter(|e| e.is_kick()).cloned().collect()
}

const STEPS: [(Formulation, &str); 2] = [
    (Formulation::Explicit, "explicit"),
    (Formulation::PressureImplicit, "pressure-implicit"),
];

#[test]
fn a_ramp_over_30_ms_is_found_over_the_window_at_both_step_sizes() {
    for (formulation, tag) in STEPS {
        let (events, dt) = ramped_water(formulation, true, 0.06);
        let kicks = kicks_at_the_patch(&events, tag);
        assert_first_kick_by(&kicks, PLANT_T + RAMP_SECONDS, dt, tag);
    }
}

#[test]
fn judged_per_step_only_the_same_ramp_is_missed_at_both_step_sizes() {
    for (formulation, tag) in STEPS {
        let (events, dt) = ramped_water(formulation, false, 0.06);
        let kicks = kicks_at_the_patch(&events, tag);
        assert!(kicks.is_empty(), "{tag} (dt {dt}): {kicks:?}");
    }
}

#[test]
fn a_ramp_below_the_threshold_over_the_window_is_not_a_kick() {
    for (formulation, tag) in STEPS {
        let (events, dt) = ramped_water(formulation, true, 0.015);
        let kicks = kicks_at_the_patch(&events, tag);
        assert!(kicks.is_empty(), "{tag} (dt {dt}): {kicks:?}");
    }
}
