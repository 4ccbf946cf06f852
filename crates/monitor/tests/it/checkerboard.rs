//! Checkerboard index on synthetic fields: 1 for a pure zero-mean
//! checkerboard, ~0 for a hydrostatic (linear) field on a partly filled box;
//! the intra-cell spread of a uniform-per-cell field is zero.

use monitor::checkerboard::{index, intra_cell_spread, CellField};
use monitor::Geometry;
use solver::{Material, Scene, Vec2};

fn geometry(ppc: usize) -> Geometry {
    let mut scene = Scene::dam_break(Material::tait(1e5));
    scene.size = [0.3, 0.2];
    scene.ppc = ppc;
    Geometry::from_scene(&scene)
}

/// Particles on the ppc lattice of cells [i0, i1) x [j0, j1), valued by `f(i, j, x)`.
fn lattice(
    g: &Geometry,
    (i0, j0, i1, j1): (usize, usize, usize, usize),
    f: impl Fn(usize, usize, Vec2) -> f64,
) -> (Vec<Vec2>, Vec<f64>) {
    let (mut x, mut v) = (vec![], vec![]);
    let l = g.cell / g.ppc as f64;
    for j in j0..j1 {
        for i in i0..i1 {
            for b in 0..g.ppc {
                for a in 0..g.ppc {
                    let p = Vec2::new(
                        i as f64 * g.cell + (a as f64 + 0.5) * l,
                        j as f64 * g.cell + (b as f64 + 0.5) * l,
                    );
                    x.push(p);
                    v.push(f(i, j, p));
                }
            }
        }
    }
    (x, v)
}

#[test]
fn pure_checkerboard_scores_one() {
    for ppc in [1, 2, 3] {
        let g = geometry(ppc);
        // 10 x 10 block: its 8 x 8 interior holds 32 + and 32 - cells.
        let (x, p) = lattice(&g, (3, 4, 13, 14), |i, j, _| {
            if (i + j) % 2 == 0 {
                7.0
            } else {
                -7.0
            }
        });
        let mut field = CellField::new(&g);
        field.accumulate(&g, &x, &p);
        let cb = index(&g, &field).unwrap();
        assert!((cb - 1.0).abs() < 1e-12, "ppc {ppc}: CB = {cb}");
        assert!(intra_cell_spread(&g, &field, &x, &p) < 1e-12);
    }
}

#[test]
fn hydrostatic_field_scores_near_zero() {
    let g = geometry(2);
    // Partly filled: a 12 x 9 block against the floor, p = rho g (H - y).
    let (x, p) = lattice(&g, (0, 0, 12, 9), |_, _, x| 1000.0 * 9.81 * (0.09 - x.y));
    let mut field = CellField::new(&g);
    field.accumulate(&g, &x, &p);
    let cb = index(&g, &field).unwrap();
    assert!(cb < 1e-3, "CB = {cb}");
    // Within a cell the linear field spreads by rho g l / 2 around the cell mean.
    let spread = intra_cell_spread(&g, &field, &x, &p);
    assert!((spread - 0.25).abs() < 1e-9, "spread {spread}");
    // A checkerboard patch added on top of it is seen.
    let (x2, p2) = lattice(&g, (0, 0, 12, 9), |i, j, x| {
        1000.0 * 9.81 * (0.09 - x.y)
            + if (i + j) % 2 == 0 && i < 6 {
                300.0
            } else {
                0.0
            }
    });
    field.accumulate(&g, &x2, &p2);
    let cb2 = index(&g, &field).unwrap();
    assert!(cb2 > 0.05, "CB = {cb2}");
}
