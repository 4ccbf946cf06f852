//! Mixed integration of the internal force (`method.quadrature = "mixed"`;
//! Beuth 2012, Al-Kafaji 2013, as in Anura3D): in a cell full of material
//! the force -int sigma grad N_i is integrated at fixed points (the 2 x 2
//! quarter points, each of weight h^2 / 4: the quadrature of an undisturbed
//! 2 x 2 particle lattice), with the stress interpolated from its nodal
//! mass-weighted mean; elsewhere (free surface, thin jets) at the material
//! points as usual. Material points that have drifted into lines or clumps
//! then no longer make the quadrature, so a disordered arrangement cannot
//! hold a pressure that is not the weight above at rest.
//!
//! "Full": every node the cell's points weigh holds at least
//! `FULL_NODE_SHARE` of a full node's mass rho0 h^2 (folded: mirror images
//! at walls count), the test of the volume consistency remedy. Every pass
//! is serial, in a fixed order: deterministic for any thread count.

// The loops walk several arrays in step (weights, nodes, particles).
#![allow(clippy::needless_range_loop)]

use crate::grid::FULL_NODE_SHARE;
use crate::grid::{Grid, Mirrored, PAD};
use crate::particles::{Particles, Vec2};
use crate::shapes::{Shape, Stencil};
use std::ops::AddAssign;

/// Offsets of the integration points in a cell (cell units, per axis).
const POINTS: [f64; 2] = [0.25, 0.75];

/// Per node: sum N m and sum N m (sigma_xx, sigma_xy, sigma_yy).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct NodalStress([f64; 4]);

impl AddAssign for NodalStress {
    fn add_assign(&mut self, o: Self) {
        for k in 0..4 {
            self.0[k] += o.0[k];
        }
    }
}

impl Mirrored for NodalStress {
    /// A reflection reverses the shear stress; the normal stresses stay.
    fn mirror(mut self, _axis: usize) -> Self {
        self.0[2] = -self.0[2];
        self
    }
    /// The no-slip image is geometric for a stress as well.
    fn point_mirror(self) -> Self {
        self.mirror(0)
    }
}

/// Scratch arrays, allocated once.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    /// Per cell: holds a particle, and is integrated at the fixed points.
    occupied: Vec<bool>,
    full: Vec<bool>,
    /// Per padded node: folded mass, and the stress sums.
    node_mass: Vec<f64>,
    node_stress: Vec<NodalStress>,
}

impl Scratch {
    pub fn new(grid: &Grid) -> Self {
        let cells = grid.cells[0] * grid.cells[1];
        let nodes = grid.dims[0] * grid.dims[1];
        Scratch {
            occupied: vec![false; cells],
            full: vec![false; cells],
            node_mass: vec![0.0; nodes],
            node_stress: vec![NodalStress::default(); nodes],
        }
    }
}

/// The real cell holding `x`, if any.
fn cell_of(grid: &Grid, x: Vec2) -> Option<usize> {
    let r = (x - grid.origin) / grid.h;
    let inside = |v: f64, n: usize| v.is_finite() && v >= 0.0 && v < n as f64;
    (inside(r.x, grid.cells[0]) && inside(r.y, grid.cells[1]))
        .then(|| r.x as usize + grid.cells[0] * r.y as usize)
}

/// The internal force plus gravity (m_i g) into `grid.force` on the active
/// nodes, with mixed integration. `grid.mass_raw` must hold this step's P2G
/// mass. `rho0` is the material's density (a single material).
pub fn forces(
    ps: &Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &mut Grid,
    gravity: Vec2,
    rho0: f64,
    s: &mut Scratch,
) {
    crate::shapes::with_width!(shape, W => forces_w::<W>(ps, stencils, shape, grid, gravity, rho0, s))
}

/// Padded node and 1D weights of an integration point at `r` (cells from the origin).
#[inline]
fn point_stencil<const W: usize>(shape: &Shape, r: [f64; 2], nx: usize) -> (usize, [[f64; W]; 4]) {
    let (bx, fx) = shape.locate(r[0]);
    let (by, fy) = shape.locate(r[1]);
    let (wx, dwx) = shape.stencil_weights::<W>(fx, 0.0);
    let (wy, dwy) = shape.stencil_weights::<W>(fy, 0.0);
    let node = (bx + PAD as i64) as usize + (by + PAD as i64) as usize * nx;
    (node, [wx, dwx, wy, dwy])
}

fn forces_w<const W: usize>(
    ps: &Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &mut Grid,
    gravity: Vec2,
    rho0: f64,
    s: &mut Scratch,
) {
    mark_full_cells::<W>(ps, shape, grid, rho0, s);
    particle_forces::<W>(ps, stencils, shape, grid, s);
    cell_point_forces::<W>(shape, grid, s);
    for &n in &grid.active {
        let n = n as usize;
        grid.force[n] += gravity * grid.mass_raw[n];
    }
}

/// `s.full`: the cells holding a particle whose fixed points' stencils
/// reach only full nodes.
fn mark_full_cells<const W: usize>(
    ps: &Particles,
    shape: &Shape,
    grid: &Grid,
    rho0: f64,
    s: &mut Scratch,
) {
    let (nx, h) = (grid.dims[0], grid.h);
    let [cx_n, cy_n] = grid.cells;
    // Which cells are full.
    s.node_mass.fill(0.0);
    for &n in &grid.active {
        s.node_mass[n as usize] = grid.mass_raw[n as usize];
    }
    grid.fold(&mut s.node_mass);
    grid.fill(&mut s.node_mass);
    s.occupied.fill(false);
    for &x in &ps.x {
        if let Some(c) = cell_of(grid, x) {
            s.occupied[c] = true;
        }
    }
    let full_mass = FULL_NODE_SHARE * rho0 * h * h;
    for c in 0..cx_n * cy_n {
        s.full[c] = s.occupied[c] && {
            let (cx, cy) = ((c % cx_n) as f64, (c / cx_n) as f64);
            POINTS.iter().all(|&qy| {
                POINTS.iter().all(|&qx| {
                    let (node, [wx, _, wy, _]) = point_stencil::<W>(shape, [cx + qx, cy + qy], nx);
                    (0..W).all(|b| {
                        (0..W).all(|a| {
                            wx[a] * wy[b] == 0.0 || s.node_mass[node + a + b * nx] >= full_mass
                        })
                    })
                })
            })
        };
    }
}

/// The material points' forces outside the full cells, and every
/// particle's mass-weighted stress on the nodes.
fn particle_forces<const W: usize>(
    ps: &Particles,
    stencils: &[Stencil],
    shape: &Shape,
    grid: &mut Grid,
    s: &mut Scratch,
) {
    let (nx, h) = (grid.dims[0], grid.h);
    // Material points outside the full cells; the nodal stress from all.
    for &n in &grid.active {
        grid.force[n as usize] = Vec2::zeros();
    }
    s.node_stress.fill(NodalStress::default());
    for p in 0..ps.len() {
        let st = &stencils[p];
        let (wx, dwx) = shape.stencil_weights::<W>(st.frac[0], st.half[0]);
        let (wy, dwy) = shape.stencil_weights::<W>(st.frac[1], st.half[1]);
        let sigma = ps.stress[p];
        let in_full = cell_of(grid, ps.x[p]).is_some_and(|c| s.full[c]);
        let a_mat = sigma * (-ps.vol[p] / h);
        let m = ps.mass[p];
        let carried = NodalStress([m, m * sigma[(0, 0)], m * sigma[(0, 1)], m * sigma[(1, 1)]]);
        for b in 0..W {
            for a in 0..W {
                let node = st.node as usize + a + b * nx;
                let w = wx[a] * wy[b];
                s.node_stress[node] += NodalStress(carried.0.map(|v| v * w));
                if !in_full {
                    grid.force[node] += a_mat * Vec2::new(dwx[a] * wy[b], wx[a] * dwy[b]);
                }
            }
        }
    }
    grid.fold(&mut s.node_stress);
    grid.fill(&mut s.node_stress);
}

/// The forces of the full cells' fixed points, from the nodal stress.
fn cell_point_forces<const W: usize>(shape: &Shape, grid: &mut Grid, s: &Scratch) {
    let (nx, h) = (grid.dims[0], grid.h);
    let [cx_n, cy_n] = grid.cells;
    // The fixed points of the full cells.
    let weight = 0.25 * h * h;
    for c in (0..cx_n * cy_n).filter(|&c| s.full[c]) {
        let (cx, cy) = ((c % cx_n) as f64, (c / cx_n) as f64);
        for qy in POINTS {
            for qx in POINTS {
                let (node, [wx, dwx, wy, dwy]) = point_stencil::<W>(shape, [cx + qx, cy + qy], nx);
                let mut sigma = [0.0; 3];
                for b in 0..W {
                    for a in 0..W {
                        let NodalStress(q) = s.node_stress[node + a + b * nx];
                        let w = wx[a] * wy[b];
                        for k in 0..3 {
                            sigma[k] += w * q[k + 1] / q[0];
                        }
                    }
                }
                let [sxx, sxy, syy] = sigma.map(|v| v * (-weight / h));
                for b in 0..W {
                    for a in 0..W {
                        let (gx, gy) = (dwx[a] * wy[b], wx[a] * dwy[b]);
                        grid.force[node + a + b * nx] +=
                            Vec2::new(sxx * gx + sxy * gy, sxy * gx + syy * gy);
                    }
                }
            }
        }
    }
}
