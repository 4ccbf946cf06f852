//! The moving window (`MonitorConfig::moving_window`, docs/physics.md
//! section 4): a push that builds up over 30 ms in water that moves is
//! found at the explicit and the implicit step alike. The water is a layer
//! at rest in a frame moving at 1 m/s (periodic in x), so every particle
//! is faster than `quiet_speed` and the default window judges none; the
//! view adds the push to a 2 x 2-cell patch followed by id (a test-only
//! ramp on the read-only view, the solver untouched).

use crate::common::*;
use monitor::{Event, Monitor, MonitorConfig};
use solver::*;

const PLANT_T: f64 = 0.2;
const RAMP_SECONDS: f64 = 0.03;
const END_T: f64 = 0.3;
/// The patch where it is at the plant: 0.2 m downstream of its start.
const PATCH: [f64; 4] = [0.19, 0.09, 0.21, 0.11];
const FLOW: f64 = 1.0;

/// The layer of `resting_water`, relaxed at rest in a box periodic in x,
/// then set moving at 1 m/s (a uniform flow is an exact steady state).
fn moving_water(formulation: Formulation) -> Solver {
    let mut cfg = resting_water(formulation).config().clone();
    cfg.scene.periodic = [true, false];
    let mut s = Solver::new(cfg).unwrap();
    for p in 0..s.particle_count() {
        let x = s.view().x[p];
        s.plant_motion(p, x, Vec2::new(FLOW, 0.0));
    }
    s
}

/// The moving window's monitor, judging per step too or not.
fn moving_rule(moving: bool, step_jumps: bool) -> MonitorConfig {
    MonitorConfig {
        moving_window: moving,
        step_jumps,
        ..MonitorConfig::default()
    }
}

/// Watches the moving layer to 0.3 s under `cfg`; from 0.2 s the view
/// adds `ramp` m/s upward to the patch's particles, spread evenly over
/// `seconds` (at least a step: an impulse). The events, the patch's ids
/// and the largest step.
fn ramped_flow(
    formulation: Formulation,
    cfg: MonitorConfig,
    ramp: f64,
    seconds: f64,
) -> (Vec<Event>, Vec<u32>, f64) {
    let mut s = moving_water(formulation);
    let mut m = Monitor::new(cfg, &s.view());
    let added = |t: f64| ramp * ((t - PLANT_T) / seconds).clamp(0.0, 1.0);
    let (mut v, mut v_prev, mut dt_max) = (vec![], vec![], 0.0_f64);
    let mut patch: Option<Vec<bool>> = None;
    while s.time() < END_T {
        s.step().unwrap();
        let view = s.view();
        dt_max = dt_max.max(view.dt);
        if patch.is_none() && view.time >= PLANT_T - view.dt {
            let inside = |x: &Vec2| {
                (PATCH[0]..PATCH[2]).contains(&x.x) && (PATCH[1]..PATCH[3]).contains(&x.y)
            };
            patch = Some(view.x.iter().map(inside).collect());
        }
        let pushed = patch.as_deref().unwrap_or(&[]);
        observe_pushed(&mut m, view, pushed, added, &mut v, &mut v_prev);
    }
    let in_patch = patch.expect("the plant time was reached");
    let ids = (0..in_patch.len())
        .filter(|&p| in_patch[p])
        .map(|p| s.view().id[p])
        .collect::<Vec<_>>();
    assert_eq!(
        ids.len(),
        16,
        "a 2 x 2-cell patch at 2 x 2 particles a cell"
    );
    (m.events().to_vec(), ids, dt_max)
}

/// The kicks, after asserting that every event opened after the plant and
/// holds particles of the patch.
fn kicks_of_the_patch(events: &[Event], ids: &[u32], tag: &str) -> Vec<Event> {
    for e in events {
        let ours = e.particles.iter().any(|p| ids.contains(p));
        assert!(
            ours && e.t >= PLANT_T,
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
fn a_ramp_in_moving_water_is_found_by_the_moving_window_at_both_step_sizes() {
    for (formulation, tag) in STEPS {
        let (events, ids, dt) =
            ramped_flow(formulation, moving_rule(true, true), 0.06, RAMP_SECONDS);
        let kicks = kicks_of_the_patch(&events, &ids, tag);
        assert_first_kick_by(&kicks, PLANT_T + RAMP_SECONDS, dt, tag);
    }
}

#[test]
fn the_default_window_misses_the_same_ramp_in_moving_water() {
    for (formulation, tag) in STEPS {
        let (events, ids, dt) =
            ramped_flow(formulation, moving_rule(false, true), 0.06, RAMP_SECONDS);
        let kicks = kicks_of_the_patch(&events, &ids, tag);
        assert!(kicks.is_empty(), "{tag} (dt {dt}): {kicks:?}");
    }
}

#[test]
fn moving_water_without_a_push_or_below_the_threshold_is_quiet() {
    for (formulation, tag) in STEPS {
        for ramp in [0.0, 0.015] {
            let (events, ids, dt) =
                ramped_flow(formulation, moving_rule(true, true), ramp, RAMP_SECONDS);
            let kicks = kicks_of_the_patch(&events, &ids, tag);
            assert!(kicks.is_empty(), "{tag} ramp {ramp} (dt {dt}): {kicks:?}");
        }
    }
}

#[test]
fn the_layer_moves_at_the_flow_speed_throughout() {
    for (formulation, tag) in STEPS {
        let mut s = moving_water(formulation);
        while s.time() < END_T {
            s.step().unwrap();
        }
        let slowest = s.view().v.iter().map(|v| v.x).fold(f64::INFINITY, f64::min);
        assert!(slowest > 0.99 * FLOW, "{tag}: {slowest}");
    }
}

/// Judged over the window alone, the instrument is the same at every
/// step: a ramp over 30 ms and an impulse of one step are both found,
/// within a judging interval (half a window) of their end, and a ramp
/// below the threshold is not.
#[test]
fn judged_over_the_window_alone_ramps_and_impulses_are_found_at_both_step_sizes() {
    for (formulation, tag) in STEPS {
        for seconds in [RAMP_SECONDS, 1e-9] {
            let (events, ids, dt) =
                ramped_flow(formulation, moving_rule(true, false), 0.06, seconds);
            let kicks = kicks_of_the_patch(&events, &ids, tag);
            let tag = format!("{tag} over {seconds} s");
            assert_first_kick_by(&kicks, PLANT_T + seconds, dt, &tag);
        }
        let (events, ids, dt) = ramped_flow(formulation, moving_rule(true, false), 0.015, 1e-9);
        let kicks = kicks_of_the_patch(&events, &ids, tag);
        assert!(kicks.is_empty(), "{tag} impulse below (dt {dt}): {kicks:?}");
    }
}

#[test]
fn rules_without_the_window_they_need_are_refused() {
    // No jump rule at all; and a moving window, a rule of the window,
    // without it (alone it would judge nothing more).
    let without_window = |step_jumps: bool, moving_window: bool| MonitorConfig {
        step_jumps,
        moving_window,
        windowed_jumps: false,
        ..MonitorConfig::default()
    };
    for (cfg, refused_key) in [
        (without_window(false, false), "step_jumps"),
        (without_window(true, true), "moving_window"),
    ] {
        let (key, message) = cfg.validate().unwrap_err();
        assert_eq!(key, refused_key);
        assert!(message.contains("windowed_jumps"), "{message}");
    }
    assert!(moving_rule(true, false).validate().is_ok());
}
