//! Particle-to-grid transfer as a gather: every active node sums the particles
//! of the bins whose stencils reach it, in a fixed order. Nodes are independent,
//! so the result is the same for any thread count, with no reduction buffers.

use crate::grid::Grid;
use crate::particles::{Particles, Vec2};
use crate::shape::Weights1d;
use crate::stage_sort::Bins;
use rayon::prelude::*;

/// Which nodal sums a P2G pass computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Terms {
    pub mass: bool,
    pub momentum: bool,
    /// Internal force -sum V sigma grad N plus gravity sum N m g.
    pub force: bool,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct NodeSum {
    mass: f64,
    momentum: Vec2,
    force: Vec2,
}

/// Read-only inputs of a P2G pass.
pub struct Inputs<'a> {
    pub particles: &'a Particles,
    pub weights: &'a [[Weights1d; 2]],
    pub bins: &'a Bins,
    pub width: usize,
    /// Include the APIC affine term in the momentum.
    pub affine: bool,
    pub gravity: Vec2,
}

pub fn p2g(inputs: &Inputs, terms: Terms, buf: &mut Vec<NodeSum>, grid: &mut Grid) {
    buf.clear();
    buf.resize(grid.active.len(), NodeSum::default());
    {
        let grid = &*grid;
        buf.par_iter_mut()
            .zip(grid.active.par_iter())
            .for_each(|(out, &node)| *out = gather(inputs, terms, grid, node as usize));
    }
    for (sum, &node) in buf.iter().zip(grid.active.iter()) {
        let n = node as usize;
        if terms.mass {
            grid.mass_raw[n] = sum.mass;
        }
        if terms.momentum {
            grid.momentum[n] = sum.momentum;
        }
        if terms.force {
            grid.force[n] = sum.force;
        }
    }
}

#[inline]
fn gather(inputs: &Inputs, terms: Terms, grid: &Grid, node: usize) -> NodeSum {
    let Inputs {
        particles: ps,
        weights,
        bins,
        width,
        affine,
        gravity,
    } = *inputs;
    let (i, j) = grid.coords(node);
    let xi = grid.position(node);
    let inv_h = 1.0 / grid.h;
    let mut s = NodeSum::default();
    for bj in j.saturating_sub(width - 1)..=j {
        for bi in i.saturating_sub(width - 1)..=i {
            let (a, c) = (i - bi, j - bj);
            for &p in bins.of(grid.index(bi, bj)) {
                let p = p as usize;
                let [wx, wy] = &weights[p];
                let n = wx.w[a] * wy.w[c];
                let m = ps.mass[p];
                if terms.mass {
                    s.mass += n * m;
                }
                if terms.momentum {
                    let mut vp = ps.v[p];
                    if affine {
                        vp += ps.affine[p] * (xi - ps.x[p]);
                    }
                    s.momentum += (n * m) * vp;
                }
                if terms.force {
                    let grad = Vec2::new(wx.dw[a] * wy.w[c], wx.w[a] * wy.dw[c]) * inv_h;
                    s.force += (n * m) * gravity - ps.vol[p] * (ps.stress[p] * grad);
                }
            }
        }
    }
    s
}
