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

/// A droplet that lands on the floor ahead of the front (a filled floor cell
/// not connected to the column) does not move it; once the front reaches it,
/// it counts.
#[test]
fn a_droplet_ahead_on_the_floor_does_not_move_the_front() {
    let sc = Scene::dam_break(Material::tait(1e5));
    let g = Geometry::from_scene(&sc);
    let fill = |cells: &[(usize, usize)]| {
        let mut x = vec![];
        for &(i, j) in cells {
            for k in 0..4 {
                x.push(Vec2::new(
                    (i as f64 + 0.2 + 0.2 * k as f64) * 0.01,
                    (j as f64 + 0.5) * 0.01,
                ));
            }
        }
        let mut field = CellField::new(&g);
        field.accumulate(&g, &x, &vec![0.0; x.len()]);
        Front::new(&g).position(&g, &field)
    };
    // The collapsing column: rows 0-2 filled to i = 29.
    let mut cells: Vec<(usize, usize)> =
        (0..30).flat_map(|i| (0..3).map(move |j| (i, j))).collect();
    // A droplet of two filled floor cells at i = 50, 51.
    cells.extend([(50, 0), (51, 0)]);
    let xf = fill(&cells).unwrap();
    assert!(
        (xf - 0.30).abs() < 1e-12,
        "front at {xf}, not the droplet's 0.52"
    );
    // The surge reaches it: the front is now the droplet's far edge.
    cells.extend((30..50).map(|i| (i, 0)));
    let xf = fill(&cells).unwrap();
    assert!((xf - 0.52).abs() < 1e-12, "front at {xf}");
    // Only the droplet, no column base: no front.
    assert_eq!(fill(&[(50, 0), (51, 0)]), None);
}
