//! A made-up kinematic anomaly: shear a patch of a column at rest hard, let it
//! come to rest, then push it gently. The push is an `injection` with the
//! hallmark (quiet before, highly deformed earlier); the same push into a
//! patch that was never sheared is an `injection` without it.

use monitor::{Cause, DeformedBy, Event, EventKind, Monitor};
use solver::*;

use crate::common;

const H: f64 = 0.01;
/// The sheared patch, cells [i0, j0, i1, j1), and a never-sheared one.
const SHEARED: [usize; 4] = [6, 16, 14, 24];
const UNTOUCHED: [usize; 4] = [26, 16, 34, 24];
/// Shear rate of the made-up deformation (1/s): in-plane |dev D| = rate / sqrt 2.
const SHEAR_RATE: f64 = 150.0;
const SHEAR_STEP: u64 = 20;
/// Viscosity (Pa s): high, so that the shear settles within 0.1 s.
const VISCOSITY: f64 = 50.0;
/// The gentle push (m/s, upwards) about 0.15 s after the shear.
const PUSH_STEP: u64 = 3000;
const PUSH_DV: [f64; 2] = [0.0, 0.3];

struct Run {
    monitor: Monitor,
    /// Largest speed and in-plane |dev D| in the sheared patch per step after the shear.
    calm: Vec<(f64, f64, f64)>,
}

/// A viscous column at rest (VISCOSITY, so that the shear settles), sheared row by row at SHEAR_STEP (v_x = rate (y -
/// y_c)), then pushed by `push_dv` at `push_step` over `push` cells.
fn run(push: [usize; 4], push_step: u64, push_dv: [f64; 2], steps: u64) -> Run {
    run_watched(
        monitor::MonitorConfig::default(),
        push,
        push_step,
        push_dv,
        steps,
    )
}

/// `run` under a monitor with `mcfg`.
fn run_watched(
    mcfg: monitor::MonitorConfig,
    push: [usize; 4],
    push_step: u64,
    push_dv: [f64; 2],
    steps: u64,
) -> Run {
    let mut scene = Scene::dam_break(common::tait(1.5e6, VISCOSITY));
    scene.size = [0.4, 0.6];
    scene.bodies[0].rect = [0.0, 0.0, 0.4, 0.4];
    scene.initial = InitialState::Hydrostatic;
    let [i0, j0, i1, j1] = SHEARED;
    let y_c = 0.5 * (j0 + j1) as f64 * H;
    let mut perturb: Vec<Perturb> = (j0..j1)
        .map(|j| {
            Perturb::at_step(
                SHEAR_STEP,
                common::region(H, i0, j, i1, j + 1),
                [SHEAR_RATE * ((j as f64 + 0.5) * H - y_c), 0.0],
            )
        })
        .collect();
    perturb.push(Perturb::at_step(
        push_step,
        common::region(H, push[0], push[1], push[2], push[3]),
        push_dv,
    ));
    let cfg = SolverConfig {
        scene,
        method: common::method(ShapeKind::Bspline2, TransferKind::Apic),
        perturb,
    };
    let mut s = Solver::new(cfg).unwrap();
    let mut m = Monitor::new(mcfg, &s.view());
    let inside = |x: Vec2| {
        let r = common::region(H, i0, j0, i1, j1);
        x.x >= r[0] && x.x <= r[2] && x.y >= r[1] && x.y <= r[3]
    };
    let mut calm = vec![];
    for _ in 0..steps {
        s.step().unwrap();
        let v = s.view();
        let r = m.observe(&v);
        assert!(r.blow_out.is_none(), "{:?}", r.blow_out);
        if v.step > SHEAR_STEP {
            let (mut speed, mut rate) = (0.0f64, 0.0f64);
            for p in (0..v.x.len()).filter(|&p| inside(v.x[p])) {
                speed = speed.max(v.v[p].norm());
                rate = rate.max(v.dev_rate[p]);
            }
            calm.push((v.time, speed, rate));
        }
    }
    Run { monitor: m, calm }
}

/// The event opened by the push.
fn push_event(m: &Monitor, tag: &str) -> Event {
    m.events()
        .iter()
        .find(|e| e.kind == EventKind::Kick && (PUSH_STEP..=PUSH_STEP + 1).contains(&e.first_step))
        .unwrap_or_else(|| panic!("{tag}: no kick at the push: {:#?}", m.events()))
        .clone()
}

#[test]
fn a_push_into_a_once_sheared_patch_at_rest_is_an_anomaly() {
    let cfg = monitor::MonitorConfig::default();
    let steps = PUSH_STEP + 100;
    let sheared = run(SHEARED, PUSH_STEP, PUSH_DV, steps);
    // The set-up holds: the patch was sheared above D_high, then quiet (by
    // the monitor's own thresholds) over the quiet window before the push.
    let peak = sheared.calm.iter().map(|c| c.2).fold(0.0, f64::max);
    assert!(peak > 1.5 * cfg.deformed_rate, "peak |dev D| {peak}");
    let t_push = sheared.calm[(PUSH_STEP - SHEAR_STEP - 1) as usize].0;
    let before: Vec<_> = sheared
        .calm
        .iter()
        .filter(|c| c.0 < t_push && c.0 >= t_push - cfg.quiet_seconds)
        .collect();
    assert!(before.len() > 100);
    let (speed, rate) = before
        .iter()
        .fold((0.0f64, 0.0f64), |(s, r), c| (s.max(c.1), r.max(c.2)));
    assert!(
        speed < cfg.quiet_speed && rate < cfg.quiet_rate,
        "not at rest: {speed} m/s, {rate} 1/s"
    );

    let e = push_event(&sheared.monitor, "sheared");
    assert_eq!(e.cause, Cause::Injection, "{e:?}");
    assert!(e.quiescent_before, "{e:?}");
    assert!(e.deformed_by.contains(&DeformedBy::StrainRate), "{e:?}");
    assert!(e.hallmark() && e.is_anomaly(), "{e:?}");
    let shear_t = sheared.calm[0].0;
    let t_peak = e.evidence.t_peak_dev_rate.unwrap();
    assert!(t_peak <= shear_t + 0.01, "the peak is the shear's: {e:?}");
    assert!(e.evidence.peak_dev_rate >= cfg.deformed_rate, "{e:?}");

    // The same push into a patch never sheared: a kick, quiet before, no hallmark.
    let untouched = run(UNTOUCHED, PUSH_STEP, PUSH_DV, steps);
    let e = push_event(&untouched.monitor, "untouched");
    assert_eq!(e.cause, Cause::Injection, "{e:?}");
    assert!(e.quiescent_before, "{e:?}");
    assert!(!e.deformed_by.contains(&DeformedBy::StrainRate), "{e:?}");
    assert!(!e.hallmark() && !e.is_anomaly(), "{e:?}");
    assert!(e.evidence.peak_dev_rate < cfg.deformed_rate, "{e:?}");
}

/// The hallmark log of the same anomaly, re-applied offline: at the
/// monitor's own thresholds it gives the event's own fractions and
/// hallmark; the logging changes no event; and the hallmark moves with
/// each threshold the way its definition says.
#[test]
fn the_logged_hallmark_reapplied_offline_matches_the_monitor_and_moves_with_its_thresholds() {
    use monitor::hallmark_log::{reapply, Setting};
    let cfg = monitor::MonitorConfig {
        hallmark_log: true,
        ..monitor::MonitorConfig::default()
    };
    let steps = PUSH_STEP + 100;
    let logged = run_watched(cfg.clone(), SHEARED, PUSH_STEP, PUSH_DV, steps);
    let plain = run(SHEARED, PUSH_STEP, PUSH_DV, steps);
    assert_eq!(logged.monitor.events(), plain.monitor.events());
    assert!(plain.monitor.hallmark_rows().is_empty());
    let e = push_event(&logged.monitor, "logged");
    let rows = logged.monitor.hallmark_rows();
    let at = |speed_factor: f64, quiet: f64, deformed: f64| {
        let setting = Setting {
            speed_factor,
            quiet_seconds: quiet * cfg.quiet_seconds,
            deformed_rate: deformed * cfg.deformed_rate,
            distortion_ratio: cfg.distortion_ratio,
        };
        reapply(rows, e.id, &setting)
    };
    let own = at(1.0, 1.0, 1.0);
    assert!(own.particles >= cfg.min_cluster_particles, "{own:?}");
    assert_eq!(
        own.quiescent, e.evidence.quiescent_fraction,
        "{own:?} {e:?}"
    );
    assert_eq!(
        own.deformed_rate, e.evidence.deformed_fraction,
        "{own:?} {e:?}"
    );
    assert!(own.hallmark() && e.hallmark(), "{own:?}");
    // Every logged quiet speed has the same particles.
    for f in monitor::particle_history::SPEED_FACTORS {
        assert_eq!(at(f, 1.0, 1.0).particles, own.particles);
    }
    // The shear's in-plane |dev D| (150 / sqrt 2 = 106 1/s) is below three
    // times the default deformed rate: no longer highly deformed.
    assert!(!at(1.0, 1.0, 3.0).hallmark(), "{:?}", at(1.0, 1.0, 3.0));
    // A quiet window three times as long reaches back into the shear's
    // settling: no longer quiet before.
    let long = at(1.0, 3.0, 1.0);
    assert!(long.quiescent < 0.5 && !long.hallmark(), "{long:?}");
    // A higher quiet speed keeps it quiet at least as long.
    assert!(at(3.0, 1.0, 1.0).quiescent >= own.quiescent);
}
