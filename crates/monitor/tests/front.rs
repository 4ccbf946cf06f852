//! Surge front: furthest filled cell connected to the floor; strays and
//! detached blobs do not move it.

use monitor::checkerboard::CellField;
use monitor::front::{dimensionless, Front};
use monitor::Geometry;
use solver::{Material, Scene, Vec2};

#[test]
fn front_ignores_strays_and_detached_blobs() {
    let sc = Scene::dam_break(Material::tait(1e5));
    let g = Geometry::from_scene(&sc);
    let mut x = vec![];
    let mut put = |i: usize, j: usize, n: usize| {
        for k in 0..n {
            x.push(Vec2::new(
                (i as f64 + 0.2 + 0.1 * k as f64) * 0.01,
                (j as f64 + 0.5) * 0.01,
            ));
        }
    };
    for i in 0..10 {
        put(i, 0, 4);
        put(i, 1, 4);
    }
    put(10, 2, 4); // meets the floor block only at a corner: not 4-connected
    put(25, 0, 1); // a stray particle: not a filled cell
    for i in 30..34 {
        put(i, 12, 4); // a filled blob, not connected to the floor
    }
    let values = vec![0.0; x.len()];
    let mut field = CellField::new(&g);
    field.accumulate(&g, &x, &values);
    let mut front = Front::new(&g);
    let xf = front.position(&g, &field).unwrap();
    assert!((xf - 0.10).abs() < 1e-12, "front at {xf}");
    let (z, t) = dimensionless(&g, xf, 0.5);
    assert!((z - 0.5).abs() < 1e-12);
    assert!((t - 0.5 * (2.0f64 * 9.81 / 0.2).sqrt()).abs() < 1e-12);
}
