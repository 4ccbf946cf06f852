//! Grid-to-particle transfer: particle velocity by PIC, FLIP blend or APIC,
//! position moved with the grid velocity, periodic wrap.

use crate::config::TransferKind;
use crate::grid::Grid;
use crate::particles::{Mat2, Particles, Vec2};
use crate::shape::{Shape, Weights1d};
use rayon::prelude::*;

pub struct Transfer {
    pub kind: TransferKind,
    pub flip_alpha: f64,
}

pub fn g2p(
    particles: &mut Particles,
    weights: &[[Weights1d; 2]],
    grid: &Grid,
    shape: &Shape,
    transfer: &Transfer,
    dt: f64,
) {
    let width = shape.width();
    let pad = crate::grid::PAD as i64;
    let inv_h = 1.0 / grid.h;
    let apic_dinv = shape.apic_inverse_inertia().map(|d| d * inv_h * inv_h);
    let alpha = match transfer.kind {
        TransferKind::Pic | TransferKind::Apic => 0.0,
        TransferKind::Flip => transfer.flip_alpha,
    };
    let apic = transfer.kind == TransferKind::Apic;
    let lo = grid.origin;
    let size = Vec2::new(grid.cells[0] as f64 * grid.h, grid.cells[1] as f64 * grid.h);
    (
        particles.x.par_iter_mut(),
        particles.v.par_iter_mut(),
        particles.affine.par_iter_mut(),
        weights.par_iter(),
    )
        .into_par_iter()
        .for_each(|(x, v, affine, [wx, wy])| {
            let (bi, bj) = ((wx.base + pad) as usize, (wy.base + pad) as usize);
            let mut v_pic = Vec2::zeros();
            let mut dv = Vec2::zeros();
            let mut b = Mat2::zeros();
            for c in 0..width {
                for a in 0..width {
                    let node = grid.index(bi + a, bj + c);
                    let n = wx.w[a] * wy.w[c];
                    let vn = grid.vel_new[node];
                    v_pic += n * vn;
                    if alpha > 0.0 {
                        dv += n * (vn - grid.vel[node]);
                    }
                    if apic {
                        match apic_dinv {
                            // B-splines: C = B D^-1 with constant D.
                            Some(_) => b += (n * vn) * (grid.position(node) - *x).transpose(),
                            // Multilinear/GIMP: C = sum v grad N^T (= B D^-1 for linear).
                            None => {
                                let grad =
                                    Vec2::new(wx.dw[a] * wy.w[c], wx.w[a] * wy.dw[c]) * inv_h;
                                b += vn * grad.transpose();
                            }
                        }
                    }
                }
            }
            *v = if alpha > 0.0 {
                alpha * (*v + dv) + (1.0 - alpha) * v_pic
            } else {
                v_pic
            };
            if apic {
                *affine = b * apic_dinv.unwrap_or(1.0);
            }
            *x += dt * v_pic;
            for k in 0..2 {
                if grid.periodic[k] {
                    x[k] = lo[k] + (x[k] - lo[k]).rem_euclid(size[k]);
                }
            }
        });
}
