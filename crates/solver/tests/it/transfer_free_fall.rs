//! An unsupported block in free fall: v = -g t to round-off and the position
//! within g t dt / 2 of the exact one (symplectic Euler), and a force-driven
//! acceleration of exactly g, for every shape, transfer and scheme.

use solver::*;

use crate::common;

#[test]
fn free_fall_is_exact() {
    let g = 9.81;
    for shape in common::RUN_SHAPES {
        for transfer in common::TRANSFERS {
            for scheme in common::SCHEMES {
                let scene =
                    common::box_scene([0.6, 0.6], [0.2, 0.3, 0.3, 0.4], Material::tait(1.5e5), g);
                let mut s = common::solver(scene, common::method(shape, transfer, scheme));
                let x0: Vec<Vec2> = s.view().x.to_vec();
                for _ in 0..200 {
                    s.step().unwrap();
                }
                let v = s.view();
                let t = v.time;
                let dt = v.dt;
                for (p, start) in x0.iter().enumerate() {
                    let tag = format!("{shape:?} {transfer:?} {scheme:?} p {p}");
                    assert!(
                        (v.v[p].y + g * t).abs() < 1e-10 * g * t,
                        "{tag}: v {}",
                        v.v[p]
                    );
                    assert!(v.v[p].x.abs() < 1e-12, "{tag}: vx {}", v.v[p].x);
                    let exact = start.y - 0.5 * g * t * t;
                    let err = (v.x[p].y - exact).abs();
                    assert!(err <= 0.5 * g * t * dt * (1.0 + 1e-9), "{tag}: {err}");
                    assert!((v.j[p] - 1.0).abs() < 1e-12, "{tag}: J {}", v.j[p]);
                    // The force-driven acceleration is gravity alone.
                    let a = v.accel[p] - Vec2::new(0.0, -g);
                    assert!(a.norm() < 1e-9 * g, "{tag}: a {}", v.accel[p]);
                }
            }
        }
    }
}
