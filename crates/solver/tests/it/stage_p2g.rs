//! The MLS-MPM force (Hu et al. 2018), f_i = -V sigma D^-1 (x_i - x_p) N_i
//! with L = C: it sums to zero and does the work -V sigma : C on the APIC
//! grid velocity, to round-off; it is refused where D is singular.

use crate::common;

use solver::*;

/// One particle with stress `sigma`, affine C and velocity v, away from the walls.
fn one_particle(shape: ShapeKind, sigma: Mat2, c: Mat2, v: Vec2) -> Solver {
    let material = Material::tait(1e5);
    let scene = common::box_scene([1.0, 1.0], [0.4, 0.4, 0.6, 0.6], material, 0.0);
    let method = Method {
        force: ForceKind::Mls,
        dt_value: Some(1e-4),
        ..common::method(shape, TransferKind::Apic, SchemeKind::Usl)
    };
    let mut ps = particles::Particles::default();
    ps.push(Vec2::new(0.4337, 0.5712), v, 0.3, 1.2e-4, 0);
    ps.stress[0] = sigma;
    ps.affine[0] = c;
    Solver::with_particles(
        SolverConfig {
            scene,
            method,
            perturb: vec![],
        },
        ps,
    )
}

#[test]
fn mls_force_sums_to_zero_and_works_on_c() {
    let sigma = Mat2::new(-2.0e3, 350.0, 350.0, -1.1e3);
    let c = Mat2::new(0.7, -1.3, 2.1, -0.4);
    let v = Vec2::new(0.25, -0.6);
    for shape in [ShapeKind::Bspline2, ShapeKind::Bspline3] {
        let mut s = one_particle(shape, sigma, c, v);
        s.run_stage(Stage::Sort).unwrap();
        s.run_stage(Stage::P2g).unwrap();
        s.run_stage(Stage::Grid).unwrap();
        let view = s.view();
        let g = view.grid;
        let dt = view.dt;
        let (mut total, mut power, mut scale) = (Vec2::zeros(), 0.0, 0.0);
        let kernel = shapes::Shape::new(shape, 2);
        let x_p = view.x[0];
        let inertia = kernel.apic_inverse_inertia().unwrap() / (g.h * g.h);
        let mut checked = 0;
        for &n in g.active {
            let n = n as usize;
            let f = g.mass[n] * g.acceleration[n];
            // Node by node the MLS form itself (the gradient force also sums
            // to zero and does the same work on an affine field).
            let x_i =
                g.padded_origin + g.h * Vec2::new((n % g.dims[0]) as f64, (n / g.dims[0]) as f64);
            let r = (x_i - x_p) / g.h;
            let weight = kernel.kernel(r.x).0 * kernel.kernel(r.y).0;
            if weight > 0.0 {
                let expected = -view.volume[0] * sigma * inertia * (x_i - x_p) * weight;
                assert!(
                    (f - expected).norm() <= 1e-12 * view.volume[0] * sigma.norm() / g.h,
                    "{shape:?} node {n}: f {f}, MLS {expected}"
                );
                checked += 1;
            }
            let v_n = g.velocity[n] - g.acceleration[n] * dt;
            total += f;
            power += f.dot(&v_n);
            scale += f.norm() * v_n.norm();
        }
        assert_eq!(checked, kernel.width() * kernel.width(), "{shape:?}");
        let volume = view.volume[0];
        let expected = -volume * sigma.component_mul(&c).sum();
        let f_scale = volume * sigma.norm() / 0.01;
        assert!(
            total.norm() <= 1e-12 * f_scale,
            "{shape:?}: sum f = {total}"
        );
        assert!(
            (power - expected).abs() <= 1e-12 * scale,
            "{shape:?}: sum f.v = {power}, -V sigma:C = {expected}"
        );
    }
}

#[test]
fn mls_is_refused_for_linear_and_gimp_shapes_and_without_apic() {
    for (shape, transfer) in [
        (ShapeKind::Linear, TransferKind::Apic),
        (ShapeKind::Gimp, TransferKind::Apic),
        (ShapeKind::Bspline2, TransferKind::Flip),
    ] {
        let scene = common::box_scene([1.0, 1.0], [0.4, 0.4, 0.6, 0.6], Material::tait(1e5), 9.81);
        let method = Method {
            force: ForceKind::Mls,
            ..common::method(shape, transfer, SchemeKind::Usl)
        };
        let err = common::refusal(scene, method)
            .unwrap_or_else(|| panic!("{shape:?} {transfer:?} accepted"));
        assert_eq!(err.key, "method.force", "{err:?}");
        assert!(err.message.contains("bspline2"), "{err:?}");
    }
}
