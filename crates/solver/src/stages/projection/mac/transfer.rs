//! The particles' transfers to and from the faces: quadratic B-spline
//! weights centred on each component's own faces, APIC's affine part per
//! component (C's row a carries component a's variation).

use super::field::FaceField;
use crate::particles::{Mat2, Particles, Vec2};
use crate::shapes::bspline::quadratic_stencil;

/// APIC's inverse inertia D^-1 h^2 of the quadratic B-spline.
const INVERSE_INERTIA: f64 = 4.0;

/// One particle's weights on one component's faces: the first face (i, j)
/// of its 3 x 3 stencil, the weights and their gradients (per cell), and
/// its offset past the first face in cells.
#[derive(Clone, Copy, Debug)]
pub struct FaceStencil {
    pub first: (i64, i64),
    pub w: [[f64; 3]; 2],
    pub dw: [[f64; 3]; 2],
    pub frac: [f64; 2],
}

/// The stencil of a particle at `x` on `field`'s faces; None when it
/// reaches past the padded faces (a particle far outside the box).
#[inline]
pub fn stencil(field: &FaceField, origin: Vec2, h: f64, x: Vec2) -> Option<FaceStencil> {
    let mut first = [0i64; 2];
    let mut w = [[0.0; 3]; 2];
    let mut dw = [[0.0; 3]; 2];
    let mut frac = [0.0; 2];
    for a in 0..2 {
        let xr = (x[a] - origin[a]) / h - field.offset[a];
        if !xr.is_finite() {
            return None;
        }
        let base = (xr - 0.5).floor() as i64;
        if !field.holds(base, a) || !field.holds(base + 2, a) {
            return None;
        }
        let f = xr - base as f64;
        (w[a], dw[a]) = quadratic_stencil(f);
        first[a] = base;
        frac[a] = f;
    }
    Some(FaceStencil {
        first: (first[0], first[1]),
        w,
        dw,
        frac,
    })
}

/// Component `field.axis` of the faces' new velocity at `x`, linear
/// between the four nearest faces (the MAC grid's bilinear element); None
/// beyond the padded faces.
#[inline]
pub fn linear_velocity(field: &FaceField, origin: Vec2, h: f64, x: Vec2) -> Option<f64> {
    let mut first = [0i64; 2];
    let mut frac = [0.0; 2];
    for a in 0..2 {
        let xr = (x[a] - origin[a]) / h - field.offset[a];
        if !xr.is_finite() {
            return None;
        }
        let base = xr.floor() as i64;
        if !field.holds(base, a) || !field.holds(base + 1, a) {
            return None;
        }
        first[a] = base;
        frac[a] = xr - base as f64;
    }
    let at = |di: i64, dj: i64| field.vel_new[field.index(first[0] + di, first[1] + dj)];
    let (fx, fy) = (frac[0], frac[1]);
    let low = (1.0 - fx) * at(0, 0) + fx * at(1, 0);
    let high = (1.0 - fx) * at(0, 1) + fx * at(1, 1);
    Some((1.0 - fy) * low + fy * high)
}

/// The lowest Raviart-Thomas element: `field`'s component linear between
/// the two faces of the cell holding `x` and constant along them, so its
/// divergence at every point of a cell is that cell's flux balance. None
/// beyond the padded faces.
pub fn flux_velocity(field: &FaceField, origin: Vec2, h: f64, x: Vec2) -> Option<f64> {
    let (a, b) = (field.axis, 1 - field.axis);
    let (along, across) = ((x[a] - origin[a]) / h, (x[b] - origin[b]) / h);
    if !along.is_finite() || !across.is_finite() {
        return None;
    }
    // Normal faces sit on node lines; along the other axis face k spans cell k.
    let (low, row) = (along.floor() as i64, across.floor() as i64);
    if !field.holds(low, a) || !field.holds(low + 1, a) || !field.holds(row, b) {
        return None;
    }
    let at = |k: i64| {
        let (i, j) = if a == 0 { (k, row) } else { (row, k) };
        field.vel_new[field.index(i, j)]
    };
    let frac = along - low as f64;
    Some((1.0 - frac) * at(low) + frac * at(low + 1))
}

/// What P2G reads of the particles.
pub struct Sources<'a> {
    pub particles: &'a Particles,
    pub origin: Vec2,
    pub h: f64,
    /// APIC (else the affine part is left out).
    pub affine: bool,
}

/// Scatters mass, momentum and the viscous force of every particle onto
/// `field`'s faces (serial, in particle order: bit-identical for any
/// thread count), raw mass kept before the fold.
pub fn scatter(src: &Sources, field: &mut FaceField) {
    field.clear();
    let ps = src.particles;
    let a = field.axis;
    let inv_h = 1.0 / src.h;
    for p in 0..ps.len() {
        let Some(st) = stencil(field, src.origin, src.h, ps.x[p]) else {
            continue;
        };
        let m = ps.mass[p];
        // The pressure is the solve's: only the viscous stress scatters.
        let sigma = ps.stress[p] + ps.pressure[p] * Mat2::identity();
        let row = Vec2::new(sigma[(a, 0)], sigma[(a, 1)]);
        let c_row = Vec2::new(ps.affine[p][(a, 0)], ps.affine[p][(a, 1)]);
        let v = ps.v[p][a];
        let vol = ps.vol[p];
        for jy in 0..3 {
            for ix in 0..3 {
                let weight = st.w[0][ix] * st.w[1][jy];
                let grad =
                    Vec2::new(st.dw[0][ix] * st.w[1][jy], st.w[0][ix] * st.dw[1][jy]) * inv_h;
                let f = field.index(st.first.0 + ix as i64, st.first.1 + jy as i64);
                let dx = Vec2::new(ix as f64 - st.frac[0], jy as f64 - st.frac[1]) * src.h;
                let affine = if src.affine { c_row.dot(&dx) } else { 0.0 };
                field.mass_raw[f] += weight * m;
                field.momentum[f] += weight * m * (v + affine);
                field.force[f] -= vol * row.dot(&grad);
            }
        }
    }
}

/// What G2P gathers at a particle from one component's faces: the new
/// velocity, its change, the affine row and the velocity gradient's row.
pub struct Gathered {
    pub v: f64,
    pub dv: f64,
    pub c_row: Vec2,
    pub l_row: Vec2,
}

/// The gather of component `field.axis` at a particle with stencil `st`.
#[inline]
pub fn gather(field: &FaceField, st: &FaceStencil, h: f64) -> Gathered {
    let inv_h = 1.0 / h;
    let (mut v, mut dv) = (0.0, 0.0);
    let (mut b, mut l) = (Vec2::zeros(), Vec2::zeros());
    for jy in 0..3 {
        for ix in 0..3 {
            let weight = st.w[0][ix] * st.w[1][jy];
            let grad = Vec2::new(st.dw[0][ix] * st.w[1][jy], st.w[0][ix] * st.dw[1][jy]) * inv_h;
            let f = field.index(st.first.0 + ix as i64, st.first.1 + jy as i64);
            let u = field.vel_new[f];
            let dx = Vec2::new(ix as f64 - st.frac[0], jy as f64 - st.frac[1]) * h;
            v += weight * u;
            dv += weight * (u - field.vel[f]);
            b += weight * u * dx;
            l += u * grad;
        }
    }
    Gathered {
        v,
        dv,
        c_row: b * (INVERSE_INERTIA * inv_h * inv_h),
        l_row: l,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;

    /// An 8 x 8 box of 1 cm cells.
    fn field(axis: usize) -> FaceField {
        let grid = Grid::new(Vec2::zeros(), 0.01, [8, 8], [false, false]);
        FaceField::new(&grid, axis, [[false; 2]; 2])
    }

    /// A velocity affine in x: v(x) = v0 + C0 (x - x0).
    const V0: [f64; 2] = [0.3, -0.2];
    const C0: [[f64; 2]; 2] = [[1.5, -0.7], [0.4, 2.0]];

    fn affine(x: Vec2) -> Vec2 {
        let c = Mat2::new(C0[0][0], C0[0][1], C0[1][0], C0[1][1]);
        Vec2::new(V0[0], V0[1]) + c * (x - Vec2::new(0.04, 0.04))
    }

    /// P2G puts each particle's momentum on its component's faces exactly
    /// (the affine part sums to zero: sum w (x_f - x_p) = 0), and G2P of a
    /// face field that is affine returns its value and gradient exactly, as
    /// does the bilinear element.
    #[test]
    fn the_face_transfers_keep_momentum_and_read_an_affine_field_exactly() {
        let mut ps = Particles::default();
        for (k, x) in [[0.031, 0.042], [0.0475, 0.0333], [0.05, 0.05]]
            .into_iter()
            .enumerate()
        {
            ps.push(
                Vec2::from(x),
                Vec2::new(0.1 * k as f64, -0.3),
                0.25,
                2.5e-5,
                0,
            );
            ps.affine[k] = Mat2::new(3.0, -1.0, 0.5, 2.0);
        }
        let src = Sources {
            particles: &ps,
            origin: Vec2::zeros(),
            h: 0.01,
            affine: true,
        };
        for (axis, c_row) in C0.iter().enumerate() {
            let mut f = field(axis);
            scatter(&src, &mut f);
            let on_faces: f64 = f.momentum.iter().sum();
            let on_particles: f64 = (0..ps.len()).map(|p| ps.mass[p] * ps.v[p][axis]).sum();
            assert!((on_faces - on_particles).abs() < 1e-15, "axis {axis}");
            for g in 0..f.vel_new.len() {
                let (i, j) = f.coords(g);
                let at = Vec2::new(i as f64 + f.offset[0], j as f64 + f.offset[1]) * 0.01;
                f.vel_new[g] = affine(at)[axis];
            }
            for p in 0..ps.len() {
                let st = stencil(&f, Vec2::zeros(), 0.01, ps.x[p]).unwrap();
                let got = gather(&f, &st, 0.01);
                assert!((got.v - affine(ps.x[p])[axis]).abs() < 1e-14, "axis {axis}");
                let linear = linear_velocity(&f, Vec2::zeros(), 0.01, ps.x[p]).unwrap();
                assert!(
                    (linear - affine(ps.x[p])[axis]).abs() < 1e-14,
                    "axis {axis}"
                );
                for (b, want) in c_row.iter().enumerate() {
                    assert!((got.c_row[b] - want).abs() < 1e-11, "C[{axis}][{b}]");
                    assert!((got.l_row[b] - want).abs() < 1e-11, "L[{axis}][{b}]");
                }
            }
        }
    }

    /// Faces 1 cm apart holding the discrete curl of the nodal stream
    /// function psi(i, j) = sin(1.3 i + 0.4) cos(0.9 j) + 0.1 i j: every
    /// cell's flux balance is zero.
    fn curl_faces() -> [FaceField; 2] {
        let psi = |i: i64, j: i64| {
            let (x, y) = (i as f64, j as f64);
            (1.3 * x + 0.4).sin() * (0.9 * y).cos() + 0.1 * x * y
        };
        [0, 1].map(|axis| {
            let mut f = field(axis);
            for g in 0..f.vel_new.len() {
                let (i, j) = f.coords(g);
                f.vel_new[g] = if axis == 0 {
                    (psi(i, j + 1) - psi(i, j)) / 0.01
                } else {
                    -(psi(i + 1, j) - psi(i, j)) / 0.01
                };
            }
            f
        })
    }

    /// The divergence at `x` of the element `velocity`, by central
    /// differences 1e-6 cells wide.
    fn divergence(
        faces: &[FaceField; 2],
        x: Vec2,
        velocity: fn(&FaceField, Vec2, f64, Vec2) -> Option<f64>,
    ) -> f64 {
        let d = 1e-8;
        (0..2)
            .map(|a| {
                let mut step = Vec2::zeros();
                step[a] = d;
                let v = |x: Vec2| velocity(&faces[a], Vec2::zeros(), 0.01, x).unwrap();
                (v(x + step) - v(x - step)) / (2.0 * d)
            })
            .sum()
    }

    /// In cells whose flux balance is zero the flux element is
    /// divergence-free at every point, where the bilinear element is not
    /// (its divergence is zero only on average over a cell); and it keeps
    /// each face's value, so the normal velocity is continuous.
    #[test]
    fn the_flux_element_is_divergence_free_inside_balanced_cells() {
        let faces = curl_faces();
        let (mut flux_worst, mut bilinear_worst) = (0.0f64, 0.0f64);
        for k in 0..40 {
            // Cell (1 + k % 6, 1 + k / 7), away from its faces.
            let (i, j) = ((1 + k % 6) as f64, (1 + k / 7) as f64);
            let frac = 0.05 + 0.9 * (0.37 * k as f64).fract();
            let x = 0.01 * Vec2::new(i + frac, j + 1.0 - frac);
            flux_worst = flux_worst.max(divergence(&faces, x, flux_velocity).abs());
            bilinear_worst = bilinear_worst.max(divergence(&faces, x, linear_velocity).abs());
        }
        // The faces hold about 100 m/s; the field's gradients about 1e4 /s.
        assert!(flux_worst < 1e-5, "flux element: {flux_worst}");
        assert!(bilinear_worst > 1.0, "bilinear element: {bilinear_worst}");
        let fx = &faces[0];
        let on_face = Vec2::new(0.03, 0.045);
        let want = fx.vel_new[fx.index(3, 4)];
        for side in [-1e-12, 1e-12] {
            let got =
                flux_velocity(fx, Vec2::zeros(), 0.01, on_face + Vec2::new(side, 0.0)).unwrap();
            assert!((got - want).abs() < 1e-8, "{got} against {want}");
        }
    }
}
