//! The minimum nodal mass remedy (`[method.min_node_mass] share`,
//! docs/physics.md section 5), the grid update's `after_grid_update` hook: a
//! node with 0 < folded mass <= the threshold ignores its forces and gets
//! a = g (wall-projected); a threshold no node reaches changes no bit and
//! books no work.

use solver::remedies::min_node_mass;
use solver::*;

use crate::common;

const G: f64 = 9.81;

fn dam_break(shape: ShapeKind, transfer: TransferKind, scheme: SchemeKind) -> SolverConfig {
    let mut mat = Material::tait(1.5e4);
    mat.viscosity = 0.5;
    SolverConfig {
        scene: Scene::dam_break(mat),
        method: common::method(shape, transfer, scheme),
        perturb: vec![],
    }
}

/// Smallest folded nodal mass over rho0 h^2 among active nodes with mass.
fn min_mass_ratio(v: &StateView) -> f64 {
    let full = v.materials[0].rho0 * v.grid.h * v.grid.h;
    v.grid
        .active
        .iter()
        .map(|&n| v.grid.mass[n as usize])
        .filter(|&m| m > 0.0)
        .fold(f64::INFINITY, f64::min)
        / full
}

#[test]
fn zero_or_unreached_threshold_changes_no_bit() {
    for (shape, transfer, scheme) in [
        (ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf),
        (ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Musl),
        (ShapeKind::Bspline3, TransferKind::Pic, SchemeKind::Usl),
        (ShapeKind::Gimp, TransferKind::Flip, SchemeKind::Usl),
    ] {
        let base = dam_break(shape, transfer, scheme);
        assert_eq!(base.method.remedies.min_node_mass, None);
        let run = |ratio: Option<f64>| {
            let mut cfg = base.clone();
            cfg.method.remedies.min_node_mass =
                ratio.map(|share| min_node_mass::Settings { share });
            let mut s = Solver::new(cfg).unwrap();
            let mut lightest = f64::INFINITY;
            for _ in 0..300 {
                s.step().unwrap();
                lightest = lightest.min(min_mass_ratio(&s.view()));
                // A remedy that guards no node books no work.
                for (key, e) in s.remedy_energy() {
                    assert_eq!(key, "min_node_mass");
                    assert_eq!(e, EnergyChange::default());
                }
            }
            (s.state_hash(), lightest)
        };
        let tag = format!("{shape:?} {transfer:?} {scheme:?}");
        let (default, lightest) = run(None);
        // A positive threshold below every node's mass exercises the guard's
        // comparison without guarding a node. 1e-12 is not always below:
        // B-spline tails leave nodes near 2e-13 of a full cell.
        let unreached = (0.5 * lightest).min(1e-12);
        assert!(unreached > 0.0, "{tag}: a node of mass ratio {lightest}");
        assert_eq!(
            default,
            run(Some(unreached)).0,
            "{tag}: unreached {unreached:e}"
        );
    }
}

/// Two blocks of a light material (rho0 / 10 of the first, reference
/// material) collide while falling: under threshold 1 every node is guarded,
/// so every nodal acceleration is exactly g and, under FLIP, every particle
/// keeps v = v0 - g t even though the collision builds up pressure; without
/// the guard that pressure changes the velocities.
#[test]
fn guarded_nodes_get_exactly_gravity_despite_stress() {
    let reference = Material {
        name: "reference".into(),
        ..Material::new(1.5e5)
    };
    let light = Material {
        name: "light".into(),
        rho0: 100.0,
        ..Material::new(1.5e5)
    };
    let body = |rect, vx| Body {
        rect,
        material: "light".into(),
        velocity: [vx, 0.0],
        fraction: 1.0,
        phase: None,
        flow: None,
    };
    let mut scene = common::box_scene([1.0, 1.0], [0.0; 4], reference.clone(), G);
    scene.cell = 0.02;
    scene.bodies = vec![
        body([0.3, 0.5, 0.5, 0.7], 0.25),
        body([0.5, 0.5, 0.7, 0.7], -0.25),
    ];
    scene.materials = vec![reference, light];
    let gravity = Vec2::new(0.0, -G);
    for shape in common::RUN_SHAPES {
        for transfer in common::TRANSFERS {
            for scheme in common::SCHEMES {
                let tag = format!("{shape:?} {transfer:?} {scheme:?}");
                let run = |ratio: f64| {
                    let mut method = common::method(shape, transfer, scheme);
                    method.remedies.min_node_mass =
                        (ratio > 0.0).then_some(min_node_mass::Settings { share: ratio });
                    let mut s = common::solver(scene.clone(), method);
                    let v0: Vec<Vec2> = s.view().v.to_vec();
                    for _ in 0..200 {
                        s.step().unwrap();
                        let v = s.view();
                        let full = v.materials[0].rho0 * v.grid.h * v.grid.h;
                        for &n in v.grid.active {
                            let (n, m) = (n as usize, v.grid.mass[n as usize]);
                            if ratio > 0.0 && m > 0.0 {
                                assert!(m < 0.5 * full, "{tag}: node mass {m}");
                                assert_eq!(v.grid.acceleration[n], gravity, "{tag}: node {n}");
                            }
                        }
                    }
                    (s, v0)
                };
                let (guarded, v0) = run(1.0);
                let v = guarded.view();
                let t = v.time;
                let p_max = v.pressure.iter().fold(0.0f64, |a, &p| a.max(p));
                assert!(
                    p_max > 1e4,
                    "{tag}: the collision builds no pressure ({p_max})"
                );
                if transfer != TransferKind::Flip {
                    continue;
                }
                for (p, start) in v0.iter().enumerate() {
                    let dv = v.v[p] - start;
                    assert!((dv.y + G * t).abs() < 1e-10 * G * t, "{tag} p {p}: {dv}");
                    assert!(dv.x.abs() < 1e-12, "{tag} p {p}: {dv}");
                }
                let (free, _) = run(0.0);
                let v = free.view();
                let departure = v0
                    .iter()
                    .enumerate()
                    .map(|(p, start)| (v.v[p] - start - gravity * t).norm())
                    .fold(0.0, f64::max);
                assert!(departure > 0.1, "{tag}: stress moved nothing ({departure})");
            }
        }
    }
}

/// In the dam break, the nodes at or below the threshold (free surface,
/// column edges, splashes) get a = g with the wall-normal component removed
/// on wall nodes; the test is strict (m > threshold keeps its force).
#[test]
fn guarded_nodes_get_wall_projected_gravity_in_the_dam_break() {
    let ratio = 0.6;
    let mut cfg = dam_break(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf);
    cfg.method.remedies.min_node_mass = Some(min_node_mass::Settings { share: ratio });
    let (origin, size) = (cfg.scene.origin, cfg.scene.size);
    let mut s = Solver::new(cfg).unwrap();
    let (mut guarded, mut on_walls, mut forced) = (0, 0, 0);
    for _ in 0..100 {
        s.step().unwrap();
        let v = s.view();
        let grid = v.grid;
        let threshold = ratio * (v.materials[0].rho0 * grid.h * grid.h);
        let on_wall = |x: f64, lo: f64, hi: f64| {
            (x - lo).abs() < 1e-9 * grid.h || (x - hi).abs() < 1e-9 * grid.h
        };
        for &n in grid.active {
            let n = n as usize;
            let (i, j) = (n % grid.dims[0], n / grid.dims[0]);
            let x = grid.padded_origin + Vec2::new(i as f64, j as f64) * grid.h;
            let inside = (0..2).all(|a| {
                x[a] > origin[a] - 1e-9 * grid.h && x[a] < origin[a] + size[a] + 1e-9 * grid.h
            });
            let m = grid.mass[n];
            if !inside || m <= 0.0 {
                continue;
            }
            if m > threshold {
                forced += 1;
                continue;
            }
            let mut expected = Vec2::new(0.0, -G);
            let wall = [0, 1].map(|a| on_wall(x[a], origin[a], origin[a] + size[a]));
            for a in 0..2 {
                if wall[a] {
                    expected[a] = 0.0;
                }
            }
            guarded += 1;
            on_walls += wall.iter().any(|&w| w) as usize;
            assert_eq!(grid.acceleration[n], expected, "node ({i}, {j}) at {x}");
        }
    }
    assert!(
        guarded > 0 && on_walls > 0 && forced > 0,
        "{guarded} {on_walls} {forced}"
    );
}

#[test]
fn threshold_out_of_range_is_refused() {
    // Off is None: a share of 0 is out of range too.
    for bad in [-1e-3, 0.0, 1.5, f64::NAN, f64::INFINITY] {
        let mut cfg = dam_break(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf);
        cfg.method.remedies.min_node_mass = Some(min_node_mass::Settings { share: bad });
        let err = cfg.validate().unwrap_err();
        assert_eq!(err.key, "method.min_node_mass.share", "{bad}");
    }
    let mut cfg = dam_break(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf);
    for ok in [1e-12, 0.25, 1.0] {
        cfg.method.remedies.min_node_mass = Some(min_node_mass::Settings { share: ok });
        cfg.validate().unwrap();
    }
}

/// A no-slip floor: the grid velocity on the floor's nodes is zero in both
/// components after every update, and a block sliding on it loses its
/// tangential momentum; refused on a periodic axis.
#[test]
fn a_no_slip_floor_stops_the_fluid_at_the_wall() {
    let run = |no_slip: Vec<Wall>| {
        let mut scene =
            common::box_scene([0.6, 0.3], [0.1, 0.0, 0.3, 0.1], Material::tait(1e5), 9.81);
        scene.bodies[0].velocity = [1.0, 0.0];
        scene.no_slip = no_slip;
        let mut s = common::solver(
            scene,
            common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl),
        );
        let mut floor_speed: f64 = 0.0;
        for _ in 0..100 {
            s.step().unwrap();
            let v = s.view();
            let g = v.grid;
            for &n in g.active {
                let y = g.padded_origin.y + (n as usize / g.dims[0]) as f64 * g.h;
                if y.abs() < 1e-12 && g.mass[n as usize] > 0.0 {
                    floor_speed = floor_speed.max(g.velocity[n as usize].norm());
                }
            }
        }
        let v = s.view();
        let px: f64 = v.v.iter().zip(v.mass).map(|(u, m)| u.x * m).sum();
        (floor_speed, px, v.mass.iter().sum::<f64>())
    };
    let (free_speed, free_px, mass) = run(vec![]);
    let (stuck_speed, stuck_px, _) = run(vec![Wall::Floor]);
    assert_eq!(stuck_speed, 0.0, "no-slip floor nodes move");
    assert!(
        free_speed > 0.5,
        "free-slip floor nodes slide: {free_speed}"
    );
    assert!(
        (free_px / mass - 1.0).abs() < 1e-9,
        "free slip keeps x momentum: {free_px}"
    );
    assert!(
        stuck_px < 0.95 * free_px,
        "no slip drags: {stuck_px} vs {free_px}"
    );
    // On a periodic axis there is no wall to stick to.
    let mut scene = common::box_scene([0.6, 0.3], [0.1, 0.0, 0.3, 0.1], Material::tait(1e5), 9.81);
    scene.periodic = [true, false];
    scene.no_slip = vec![Wall::Left];
    let err = common::refusal(scene, Method::baseline()).unwrap();
    assert_eq!(err.key, "scene.no_slip");
}
