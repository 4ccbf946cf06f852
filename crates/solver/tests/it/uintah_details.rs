//! The details of Uintah's explicit MPM that the faithful replica
//! (studies/faithful.toml, docs/physics.md section 5b) switches on: the
//! per-axis time step from the step-start velocity (the first step from
//! sqrt(K / rho0)), the substepped F update, the deletion of particles
//! whose J passes `scene.max_j`, and the gradient-enhanced velocity
//! projection.

use crate::common;

use solver::*;

fn column(method: Method, velocity: [f64; 2]) -> Solver {
    let mut scene = common::box_scene(
        [0.3, 0.2],
        [0.0, 0.0, 0.1, 0.12],
        Material::new(1.5e5),
        9.81,
    );
    scene.bodies[0].velocity = velocity;
    let cfg = SolverConfig {
        scene,
        method,
        perturb: vec![],
    };
    Solver::new(cfg).unwrap()
}

fn uintah_method() -> Method {
    let mut m = common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usl);
    m.dt = DtMode::PerAxis;
    m.cfl = 0.4;
    m
}

/// The first step takes c = sqrt(K / rho0) (not the tangent's sqrt(gamma K
/// / rho0)) plus the largest velocity component; every later step the
/// largest c_p + max(|v_x|, |v_y|) of the velocities the particles had at
/// the start of the step just taken, c_p the tangent wave speed at their
/// updated J.
#[test]
fn the_per_axis_step_is_uintahs() {
    let mut s = column(uintah_method(), [0.6, -0.8]);
    let h = 0.01;
    let first = 0.4 * h / ((1.5e5f64 / 1000.0).sqrt() + 0.8);
    assert_eq!(s.next_dt(), first);
    for _ in 0..5 {
        s.step().unwrap();
    }
    let v = s.view();
    let m = &s.config().scene.materials[0];
    let speed = (0..v.j.len())
        .map(|p| {
            let c = m.wave_speed_of(&m.eos(v.j[p]), v.j[p]);
            c + v.v_prev[p].x.abs().max(v.v_prev[p].y.abs())
        })
        .fold(0.0, f64::max);
    let want = 0.4 * h / speed;
    assert!(
        (s.next_dt() / want - 1.0).abs() < 1e-14,
        "{} vs {want}",
        s.next_dt()
    );
    // The dynamic step (|v| and the current velocity) is another one.
    let mut dynamic = uintah_method();
    dynamic.dt = DtMode::Dynamic;
    let d = column(dynamic, [0.6, -0.8]);
    assert!(d.next_dt() < first / 2.0, "{} vs {first}", d.next_dt());
}

/// A restart from a checkpoint under the per-axis step continues bit for
/// bit (the step-start velocities travel in the checkpoint).
#[test]
fn a_restart_under_the_per_axis_step_continues_exactly() {
    let mut a = column(uintah_method(), [0.3, 0.0]);
    for _ in 0..20 {
        a.step().unwrap();
    }
    let saved = a.checkpoint();
    let mut b = column(uintah_method(), [0.3, 0.0]);
    b.restore(&saved).unwrap();
    for _ in 0..20 {
        a.step().unwrap();
        b.step().unwrap();
    }
    assert_eq!(a.state_hash(), b.state_hash());
    assert_eq!(a.next_dt(), b.next_dt());
}

/// The substepped F update is the plain one while |L| dt < 1, and (I + dt
/// L / n)^n F with n = 2 floor(|L| dt) beyond, which keeps det F > 0 where
/// the plain update inverts.
#[test]
fn the_substepped_f_update_is_the_plain_one_below_one() {
    use solver::stages::stress::substepped;
    let f = Mat2::new(1.1, 0.05, -0.02, 0.93);
    let l = Mat2::new(-3.0, 1.0, 0.5, 2.0);
    let dt = 0.05; // |L| dt = 0.19
    assert_eq!(substepped(l, dt, f), (Mat2::identity() + dt * l) * f);
    let dt = 0.4; // |L| dt = 1.55: n = 2
    let half = Mat2::identity() + 0.2 * l;
    assert_eq!(substepped(l, dt, f), half * (half * f));
    let squeeze = Mat2::new(-10.0, 0.0, 0.0, 0.0);
    let plain = (Mat2::identity() + 0.15 * squeeze) * f;
    assert!(plain.determinant() < 0.0);
    let sub = substepped(squeeze, 0.15, f);
    assert!(sub.determinant() > 0.0, "{sub}");
}

/// The stress stage skips `substepped` when `needs_substeps` says one
/// substep: over |L| dt swept through 0.85 .. 1.05, wherever it skips,
/// `substepped` is bit for bit the plain update, and it skips below 0.9.
#[test]
fn the_substep_shortcut_never_changes_the_f_update() {
    use solver::stages::stress::{needs_substeps, substepped};
    let f = Mat2::new(1.1, 0.05, -0.02, 0.93);
    let l = Mat2::new(-3.0, 1.0, 0.5, 2.0);
    let norm = l.norm();
    let (mut skipped, mut taken) = (0, 0);
    for i in 0..=20_000 {
        let dt = (0.85 + 0.2 * i as f64 / 20_000.0) / norm;
        if needs_substeps(l, dt) {
            taken += 1;
        } else {
            skipped += 1;
            assert_eq!(
                substepped(l, dt, f),
                (Mat2::identity() + dt * l) * f,
                "dt {dt}"
            );
        }
        if norm * dt < 0.9 {
            assert!(!needs_substeps(l, dt), "|L| dt = {}", norm * dt);
        }
    }
    assert!(skipped > 0 && taken > 0);
}

/// Under on_inversion = "delete" a particle whose J passes scene.max_j is
/// deleted at the end of the step and counted as inverted; without
/// max_j it stays. One whose J is not a number is deleted either way
/// (Uintah's `!(J > 0)`).
#[test]
fn a_particle_past_max_j_is_deleted() {
    for (max_j, deleted) in [(Some(1e5), 1), (None, 0)] {
        // A particle whose J is not a number goes too, with or without max_j.
        let mut scene = common::box_scene(
            [0.3, 0.2],
            [0.0, 0.0, 0.1, 0.12],
            Material::new(1.5e5),
            9.81,
        );
        scene.on_inversion = OnLoss::Delete;
        scene.max_j = max_j;
        let mut ps = solver::scene::seed(&scene);
        ps.f[7] = Mat2::new(1e3, 0.0, 0.0, 1e3);
        ps.j[7] = 1e6;
        ps.f[9] = Mat2::new(f64::NAN, 0.0, 0.0, 1.0);
        let cfg = SolverConfig {
            scene,
            method: uintah_method(),
            perturb: vec![],
        };
        let mut s = Solver::with_particles(cfg, ps);
        let n = s.particle_count();
        s.step().unwrap();
        assert_eq!(s.losses().inverted, deleted + 1, "max_j {max_j:?}");
        assert_eq!(s.particle_count(), n - 1 - deleted as usize);
        assert!(s.view().j.iter().all(|j| j.is_finite()));
    }
}

/// Uintah's symmetry walls (`scene.wall_ghosts = "overwrite"`): what a
/// uGIMP particle near a wall puts on a ghost node is discarded, so no
/// in-box node off the walls holds more than its own particles' mass,
/// where the fold adds the ghosts' share to their partners. Linear shapes
/// never reach a ghost: their runs are the folded ones bit for bit. (The
/// column is pushed into the left wall, so that its particles crowd within
/// a quarter cell of it, where uGIMP reaches the ghost.)
#[test]
fn overwritten_wall_ghosts_discard_the_images_and_leave_linear_runs_unchanged() {
    let run = |shape: ShapeKind, ghosts: WallGhosts| {
        let mut m = uintah_method();
        m.shape = shape;
        let mut s = column(m, [-1.0, 0.0]);
        let mut cfg = s.config().clone();
        cfg.scene.wall_ghosts = ghosts;
        s = Solver::new(cfg).unwrap();
        for _ in 0..20 {
            s.step().unwrap();
        }
        s
    };
    let (fold, overwrite) = (
        run(ShapeKind::Linear, WallGhosts::Fold),
        run(ShapeKind::Linear, WallGhosts::Overwrite),
    );
    assert_eq!(fold.state_hash(), overwrite.state_hash());
    // Off the walls, the share the fold added: (largest, nodes that gained).
    let gained = |s: &Solver| -> (f64, usize) {
        let v = s.view();
        let g = v.grid;
        let (origin, size) = (Vec2::from(v.scene.origin), Vec2::from(v.scene.size));
        let mut out = (0.0f64, 0);
        for &n in g.active {
            let n = n as usize;
            let x =
                g.padded_origin + g.h * Vec2::new((n % g.dims[0]) as f64, (n / g.dims[0]) as f64);
            let inside = (0..2)
                .all(|k| x[k] > origin[k] + 0.5 * g.h && x[k] < origin[k] + size[k] - 0.5 * g.h);
            if inside && g.mass[n] != g.mass_raw[n] {
                out = (
                    out.0.max((g.mass[n] - g.mass_raw[n]) / g.mass_raw[n]),
                    out.1 + 1,
                );
            }
        }
        out
    };
    let folded = gained(&run(ShapeKind::Gimp, WallGhosts::Fold));
    assert!(
        folded.1 > 5 && folded.0 > 1e-4,
        "the fold adds the ghosts' share: {folded:?}"
    );
    assert_eq!(
        gained(&run(ShapeKind::Gimp, WallGhosts::Overwrite)),
        (0.0, 0)
    );
}

#[test]
fn overwritten_wall_ghosts_are_refused_under_the_pressure_implicit_formulation() {
    let mut cfg = column(uintah_method(), [0.0, 0.0]).config().clone();
    cfg.scene.wall_ghosts = WallGhosts::Overwrite;
    cfg.method.formulation = Formulation::PressureImplicit;
    cfg.method.dt = DtMode::Dynamic;
    let err = Solver::new(cfg).err().expect("refused");
    assert_eq!(err.key, "scene.wall_ghosts", "{err}");
}

/// A slab thinner than the cell (`scene.slab`) joins Uintah's per-axis
/// step: from rest the first step is CFL dz / sqrt(K / rho0); a slab as
/// thick as the cell or more leaves the plane's step as it was.
#[test]
fn a_thin_slab_sets_the_per_axis_step_through_its_z_axis() {
    let with_slab = |slab: Option<f64>| {
        let mut cfg = column(uintah_method(), [0.0, 0.0]).config().clone();
        cfg.scene.slab = slab;
        Solver::new(cfg).unwrap()
    };
    let c = (1.5e5f64 / 1000.0).sqrt();
    let plane = with_slab(None).next_dt();
    assert_eq!(plane, 0.4 * 0.01 / c);
    assert_eq!(with_slab(Some(0.004)).next_dt(), 0.4 * 0.004 / c);
    assert_eq!(with_slab(Some(0.01)).next_dt(), plane);
    assert_eq!(with_slab(Some(0.05)).next_dt(), plane);
    let mut bad = column(uintah_method(), [0.0, 0.0]).config().clone();
    bad.scene.slab = Some(0.0);
    assert_eq!(Solver::new(bad).err().unwrap().key, "scene.slab");
}

/// A block of particles, 2 x 2 a cell at the sub-cell centres, carrying
/// v = A x + b and, as a G2P of that field leaves it, L = A; no stress
/// and no gravity, so the grid keeps the projected velocity.
fn affine_block(shape: ShapeKind, gradient_enhanced: bool, a: Mat2, b: Vec2) -> Solver {
    let scene = common::box_scene([0.3, 0.3], [0.1, 0.1, 0.2, 0.2], Material::new(1.5e5), 0.0);
    let method = Method {
        gradient_enhanced,
        dt_value: Some(1e-5),
        ..common::method(shape, TransferKind::Flip, SchemeKind::Usl)
    };
    let mut ps = particles::Particles::default();
    let q = 0.005;
    for i in 0..20 {
        for j in 0..20 {
            let x = Vec2::new(0.1 + q * (i as f64 + 0.5), 0.1 + q * (j as f64 + 0.5));
            ps.push(x, a * x + b, 0.025, q * q, 0);
            ps.affine[i * 20 + j] = a;
        }
    }
    let cfg = SolverConfig {
        scene,
        method,
        perturb: vec![],
    };
    Solver::with_particles(cfg, ps)
}

/// Uintah's `UseGradientEnhancedVelocityProjection`: P2G of
/// m (v_p + L_p (x_i - x_p)) gives every node the affine field's own
/// velocity A x_i + b, where the plain FLIP projection of the same field
/// misses it at the block's edge; the FLIP G2P then keeps v and recovers
/// L = A at every particle (sum x_i grad N_i^T = I).
#[test]
fn the_gradient_enhanced_projection_carries_an_affine_field_exactly() {
    let (a, b) = (Mat2::new(0.7, -1.3, 2.1, -0.4), Vec2::new(0.25, -0.6));
    for shape in [ShapeKind::Linear, ShapeKind::Gimp] {
        let mut errors = [0.0; 2];
        for (k, enhanced) in [false, true].into_iter().enumerate() {
            let mut s = affine_block(shape, enhanced, a, b);
            for stage in [Stage::Sort, Stage::P2g, Stage::Grid] {
                s.run_stage(stage).unwrap();
            }
            let view = s.view();
            let g = view.grid;
            // GIMP's stencil marks nodes its particle does not reach: no mass, no velocity.
            for n in g
                .active
                .iter()
                .map(|&n| n as usize)
                .filter(|&n| g.mass[n] > 0.0)
            {
                let x_i = g.padded_origin
                    + g.h * Vec2::new((n % g.dims[0]) as f64, (n / g.dims[0]) as f64);
                errors[k] = f64::max(errors[k], (g.velocity[n] - (a * x_i + b)).norm());
            }
        }
        let scale = a.norm() * 0.3 + b.norm();
        assert!(
            errors[1] <= 1e-12 * scale,
            "{shape:?}: enhanced error {}",
            errors[1]
        );
        assert!(
            errors[0] >= 1e-3 * scale,
            "{shape:?}: plain FLIP error {}",
            errors[0]
        );
        let mut s = affine_block(shape, true, a, b);
        let v0 = s.view().v.to_vec();
        for stage in [Stage::Sort, Stage::P2g, Stage::Grid, Stage::G2p] {
            s.run_stage(stage).unwrap();
        }
        let view = s.view();
        assert_eq!(view.affine.len(), v0.len());
        for (p, (l, (v, v0))) in view.affine.iter().zip(view.v.iter().zip(&v0)).enumerate() {
            assert!((l - a).norm() <= 1e-11 * a.norm(), "{shape:?} p {p}: L {l}");
            assert!((v - v0).norm() <= 1e-12 * scale, "{shape:?} p {p}");
        }
    }
}

/// The switch belongs to FLIP's explicit USL step: refused with APIC and
/// with MUSL (whose second P2G would carry the new L too).
#[test]
fn the_gradient_enhanced_projection_is_refused_off_flips_usl() {
    for (transfer, scheme) in [
        (TransferKind::Apic, SchemeKind::Usl),
        (TransferKind::Flip, SchemeKind::Musl),
    ] {
        let mut cfg = SolverConfig {
            scene: common::box_scene([0.3, 0.3], [0.1, 0.1, 0.2, 0.2], Material::new(1.5e5), 0.0),
            method: common::method(ShapeKind::Gimp, transfer, scheme),
            perturb: vec![],
        };
        assert!(
            cfg.validate().is_ok(),
            "{transfer:?} {scheme:?} without the switch"
        );
        cfg.method.gradient_enhanced = true;
        let e = cfg.validate().unwrap_err().to_string();
        assert!(e.contains("method.gradient_enhanced"), "{e}");
    }
}
