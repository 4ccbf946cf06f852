//! Force forensics: an explained step is the step (bit for bit), and the
//! parts of every explained particle's velocity change add up to it.

use solver::forensics::Explained;
use solver::*;

use crate::common;

fn dam_break(method: Method) -> Solver {
    let scene = Scene::dam_break(Material::tait(1.5e4));
    common::solver(scene, method)
}

fn methods() -> Vec<(String, Method)> {
    let mut out = vec![];
    for shape in common::RUN_SHAPES {
        for scheme in common::SCHEMES {
            for (name, transfer, alpha) in [
                ("pic", TransferKind::Pic, 1.0),
                ("flip", TransferKind::Flip, 1.0),
                ("flip0.95", TransferKind::Flip, 0.95),
                ("apic", TransferKind::Apic, 1.0),
                ("xpic", TransferKind::Xpic, 1.0),
            ] {
                // XPIC reads per-axis weights: CPDI is refused with it.
                if shape == ShapeKind::Cpdi && transfer == TransferKind::Xpic {
                    continue;
                }
                let mut m = common::method(shape, transfer, scheme);
                m.flip_alpha = alpha;
                m.xpic_order = 3;
                out.push((format!("{shape:?} {scheme:?} {name}"), m));
            }
        }
    }
    let mut mls = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl);
    mls.force = ForceKind::Mls;
    out.push(("mls".into(), mls));
    out
}

/// The magnitude round-off is measured against: every part's size.
fn scale(e: &Explained) -> f64 {
    e.dv.norm() + e.nodes.iter().map(|n| n.parts_size()).sum::<f64>()
}

/// Away from the walls: every stencil node is an ordinary inside node.
fn interior(s: &Solver, p: usize) -> bool {
    let x = s.view().x[p];
    let size = s.config().scene.size;
    let margin = 4.0 * s.config().scene.cell;
    x.x > margin && x.y > margin && x.x < size[0] - margin && x.y < size[1] - margin
}

#[test]
fn the_parts_add_up_to_the_velocity_change() {
    for (name, method) in methods() {
        let mut s = dam_break(method);
        for _ in 0..40 {
            s.step().unwrap();
        }
        let n = s.particle_count();
        let chosen: Vec<usize> = (0..n).step_by(13).collect();
        let explained = s.step_explained(&chosen).unwrap().explained;
        let mut interior_seen = 0;
        for e in &explained {
            let sc = scale(e);
            assert!(sc > 0.0, "{name}: nothing moved particle {}", e.particle);
            assert!(
                e.rest.norm() <= 1e-9 * sc,
                "{name}: particle {} rest {} of {sc}",
                e.particle,
                e.rest.norm()
            );
            let weights: f64 = e.nodes.iter().map(|n| n.weight).sum();
            assert!((weights - 1.0).abs() < 1e-12, "{name}: weights {weights}");
            if interior(&s, e.particle) {
                interior_seen += 1;
                assert!(e.walls().norm() <= 1e-9 * sc, "{name}: walls {}", e.walls());
                assert!(
                    e.internal_unattributed.norm() <= 1e-9 * sc,
                    "{name}: unattributed {} of {sc}",
                    e.internal_unattributed
                );
                let stress_sum: Vec2 = e.stresses.iter().map(|q| q.pressure + q.deviatoric).sum();
                assert!((stress_sum - e.internal()).norm() <= 1e-9 * sc);
            }
        }
        assert!(
            interior_seen > 5,
            "{name}: only {interior_seen} interior particles"
        );
    }
}

#[test]
fn an_explained_step_is_the_step_bit_for_bit() {
    for transfer in [TransferKind::Flip, TransferKind::Apic, TransferKind::Xpic] {
        let mut m = common::method(ShapeKind::Bspline2, transfer, SchemeKind::Usl);
        m.xpic_order = 3;
        m.dt = DtMode::Dynamic;
        let (mut a, mut b) = (dam_break(m.clone()), dam_break(m));
        for k in 0..30 {
            a.step().unwrap();
            if k % 3 == 0 {
                b.step_explained(&[0, 7, 100]).unwrap();
            } else {
                b.step().unwrap();
            }
            assert_eq!(a.state_hash(), b.state_hash(), "{transfer:?} step {k}");
        }
    }
}

#[test]
fn wall_conditions_show_up_as_walls_not_as_force() {
    // A resting layer on the floor: the floor's nodes stop the fall.
    let mut s = dam_break(common::method(
        ShapeKind::Bspline2,
        TransferKind::Flip,
        SchemeKind::Usl,
    ));
    s.step().unwrap();
    let lowest = (0..s.particle_count())
        .min_by(|&a, &b| s.view().x[a].y.total_cmp(&s.view().x[b].y))
        .unwrap();
    let e = &s.step_explained(&[lowest]).unwrap().explained[0];
    // Gravity pulls down, the floor's condition pushes back up.
    assert!(e.external().y < 0.0);
    assert!(e.walls().y > 0.0, "walls {}", e.walls());
    assert!(e.rest.norm() <= 1e-9 * scale(e));
}

fn implicit_method(shape: ShapeKind, transfer: TransferKind, surface: FreeSurface) -> Method {
    Method {
        formulation: Formulation::PressureImplicit,
        projection: ProjectionSettings {
            tolerance: 1e-12,
            free_surface: surface,
            ..Default::default()
        },
        ..common::method(shape, transfer, SchemeKind::Usl)
    }
}

fn incompressible() -> Material {
    Material {
        k: f64::INFINITY,
        ..Material::new(1.0)
    }
}

/// Under implicit pressure the pressure is no nodal force: in an
/// incompressible column at rest (linear shapes, whose projection balances
/// the weight exactly) each particle's gravity is cancelled by the pressure
/// correction, not by the walls, and nothing else acts.
#[test]
fn under_implicit_pressure_the_pressure_correction_holds_the_column_not_the_walls() {
    let scene = common::box_scene([0.2, 0.3], [0.0, 0.0, 0.2, 0.2], incompressible(), 9.81);
    let method = implicit_method(ShapeKind::Linear, TransferKind::Flip, FreeSurface::Cell);
    let mut s = common::solver(scene, method);
    for _ in 0..10 {
        s.step().unwrap();
    }
    let all: Vec<usize> = (0..s.particle_count()).collect();
    let step = s.step_explained(&all).unwrap();
    let gravity_dv = 9.81 * step.dt;
    let mut interior_seen = 0;
    for e in &step.explained {
        let sc = scale(e);
        assert!(e.rest.norm() <= 1e-9 * sc, "rest {} of {sc}", e.rest.norm());
        assert!(e.dv.norm() <= 1e-9 * gravity_dv, "dv {}", e.dv);
        assert!((e.external().y + gravity_dv).abs() <= 1e-12 * gravity_dv);
        assert!(
            e.hourglass().norm() <= 1e-9 * gravity_dv,
            "hourglass {}",
            e.hourglass()
        );
        if interior(&s, e.particle) {
            interior_seen += 1;
            // (At the floor's nodes the wall takes the weight off the force.)
            assert!(
                e.internal().norm() <= 1e-12 * gravity_dv,
                "internal {}",
                e.internal()
            );
            assert!(
                e.walls().norm() <= 1e-12 * gravity_dv,
                "walls {}",
                e.walls()
            );
            assert!(
                (e.pressure_correction().y - gravity_dv).abs() <= 1e-9 * gravity_dv,
                "pressure correction {} against g dt {gravity_dv}",
                e.pressure_correction()
            );
            // The nodal force the picture draws holds the pressure's: it balances.
            for n in &e.nodes {
                assert!(
                    n.force.norm() <= 1e-8 * n.mass * 9.81,
                    "node force {}",
                    n.force
                );
            }
        }
    }
    assert!(
        interior_seen > 20,
        "only {interior_seen} interior particles"
    );
}

/// A breaking dam under implicit pressure, both free surfaces: the parts
/// (the projection's three included) add up to each particle's velocity
/// change; the surface particles get a share through the extrapolated
/// nodes above the water (B-splines reach them); an explained step is
/// the step bit for bit.
#[test]
fn under_implicit_pressure_the_parts_add_up_and_the_step_is_the_step() {
    for surface in [FreeSurface::Cell, FreeSurface::Ghost] {
        let make = || {
            let scene = Scene::dam_break(Material::tait(1.5e6));
            common::solver(
                scene,
                implicit_method(ShapeKind::Bspline2, TransferKind::Apic, surface),
            )
        };
        let (mut a, mut b) = (make(), make());
        for _ in 0..40 {
            a.step().unwrap();
            b.step().unwrap();
        }
        let chosen: Vec<usize> = (0..b.particle_count()).step_by(7).collect();
        let step = b.step_explained(&chosen).unwrap();
        a.step().unwrap();
        assert_eq!(a.state_hash(), b.state_hash(), "{surface:?}");
        let (mut extrapolated, mut corrected) = (0, 0);
        for e in &step.explained {
            let sc = scale(e);
            assert!(sc > 0.0);
            assert!(
                e.rest.norm() <= 1e-9 * sc,
                "{surface:?}: particle {} rest {} of {sc}",
                e.particle,
                e.rest.norm()
            );
            if interior(&b, e.particle) {
                assert!(
                    e.walls().norm() <= 1e-9 * sc,
                    "{surface:?}: walls {}",
                    e.walls()
                );
            }
            extrapolated += (e.extrapolation().norm() > 1e-6 * sc) as usize;
            corrected += (e.pressure_correction().norm() > 1e-3 * sc) as usize;
        }
        assert!(
            extrapolated > 0,
            "{surface:?}: no particle reads an extrapolated node"
        );
        assert!(
            corrected * 2 > step.explained.len(),
            "{surface:?}: {corrected} corrected"
        );
    }
}

/// A plant with a duration is the impulse part of every step it spans:
/// summed over them, each particle it holds has the plant's dv as its
/// impulse, every other particle none, and the parts still add up.
#[test]
fn a_plant_with_a_duration_is_the_impulse_part_of_the_steps_it_spans() {
    let scene = common::box_scene([0.4, 0.3], [0.1, 0.1, 0.3, 0.2], Material::tait(1e5), 0.0);
    let method = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl);
    let plant = Perturb {
        t: Some(0.002),
        step: None,
        duration: Some(0.005),
        ..Perturb::at_step(1, [0.18, 0.14, 0.2, 0.16], [0.05, 0.0])
    };
    let mut s = Solver::new(SolverConfig {
        scene,
        method,
        perturb: vec![plant],
    })
    .unwrap();
    let mut impulse: std::collections::BTreeMap<u32, Vec2> = Default::default();
    let mut pushing_steps = 0;
    while s.time() < 0.01 {
        let all: Vec<usize> = (0..s.particle_count()).collect();
        let step = s.step_explained(&all).unwrap();
        let mut pushed = false;
        for e in &step.explained {
            assert!(e.rest.norm() <= 1e-9 * scale(e), "rest {}", e.rest);
            *impulse.entry(step.id[e.particle]).or_insert(Vec2::zeros()) += e.impulse;
            pushed |= e.impulse != Vec2::zeros();
        }
        pushing_steps += usize::from(pushed);
    }
    let held: Vec<&Vec2> = impulse.values().filter(|i| i.norm() > 0.0).collect();
    assert_eq!(held.len(), 16, "the patch's 2 x 2 cells");
    for i in held {
        assert!((i - Vec2::new(0.05, 0.0)).norm() < 1e-12, "{i}");
    }
    assert!(pushing_steps > 1, "spread over {pushing_steps} steps");
}
