//! Stress stage: velocity gradient from the grid, deformation-gradient and J
//! update, EOS pressure plus Newtonian viscosity (plane strain, 3D deviator)
//! plus a solid's neo-Hookean shear stress (softened by its history xi), and
//! the EOS figures the time step and the energy need (one EOS call).

use crate::config::{JUpdate, Material};
use crate::grid::Grid;
use crate::par::{Pieces, CHUNK};
use crate::particles::{Mat2, Particles, Vec2};
use crate::remedies::PointRule;
use crate::shapes::{Shape, Stencil};
use crate::viscosity;
use rayon::prelude::*;
use std::sync::Arc;

/// The most per-particle rules a step applies (each books its own work).
pub use crate::remedies::MAX_POINT_RULES as MAX_RULES;

/// A chunk's sums: the dissipated work, then each rule's share of it.
pub type Partial = [f64; 1 + MAX_RULES];

pub struct Inputs<'a> {
    pub stencils: &'a [Stencil],
    pub shape: &'a Shape,
    pub grid: &'a Grid,
    /// The grid velocity this scheme takes the gradient of.
    pub velocity: &'a [Vec2],
    pub materials: &'a [Material],
    pub j_update: JUpdate,
    pub dt: f64,
    /// MLS-MPM: the velocity gradient is the particle's affine matrix C.
    pub mls: bool,
    /// The remedies' per-particle rules (F kept, extra stress), in order;
    /// at most `MAX_RULES`.
    pub rules: &'a [Arc<dyn PointRule>],
    /// `scene.on_inversion = "delete"`: a particle that inverts here carries
    /// no stress (it is deleted at the end of the step; under USF its
    /// singular pressure would otherwise push its neighbours this step).
    pub drop_inverted: bool,
}

/// Updates F, J, V, stress, pressure, |dev D| and xi; returns the energy
/// dissipated this step (viscous work, the rules' extra stress and what
/// softening released) and each rule's share of it.
pub fn update(
    inputs: &Inputs,
    particles: &mut Particles,
    partials: &mut [Partial],
) -> (f64, [f64; MAX_RULES]) {
    crate::shapes::with_width!(inputs.shape, W => run::<W>(inputs, particles, partials))
}

/// Velocity gradient L = sum v grad N^T at a particle, summed row by row
/// (x inner): column 0 takes dN_x N_y, column 1 N_x dN_y.
#[inline(always)]
pub(crate) fn velocity_gradient<const W: usize>(
    shape: &Shape,
    st: &Stencil,
    velocity: &[Vec2],
    nx: usize,
    inv_h: f64,
) -> Mat2 {
    let (wx, dwx) = shape.stencil_weights::<W>(st.frac[0], st.half[0]);
    let (wy, dwy) = shape.stencil_weights::<W>(st.frac[1], st.half[1]);
    let base = st.node as usize;
    let (mut col0, mut col1) = (Vec2::zeros(), Vec2::zeros());
    for c in 0..W {
        let row = base + c * nx;
        let (mut sw, mut sdw) = (Vec2::zeros(), Vec2::zeros());
        for a in 0..W {
            let vn = velocity[row + a];
            sw += wx[a] * vn;
            sdw += dwx[a] * vn;
        }
        col0 += wy[c] * sdw;
        col1 += dwy[c] * sw;
    }
    Mat2::from_columns(&[col0, col1]) * inv_h
}

fn run<const W: usize>(
    inputs: &Inputs,
    particles: &mut Particles,
    partials: &mut [Partial],
) -> (f64, [f64; MAX_RULES]) {
    let Inputs {
        stencils,
        shape,
        grid,
        velocity,
        materials,
        j_update,
        dt,
        mls,
        rules,
        drop_inverted,
    } = *inputs;
    let nx = grid.dims[0];
    let inv_h = 1.0 / grid.h;
    let solids = materials.iter().any(|m| m.shear_modulus > 0.0);
    let n_chunks = crate::par::chunk_count(particles.len());
    let piece = crate::par::piece_chunks(particles.len());
    (
        particles.f.par_chunks_mut(CHUNK),
        particles.j.par_chunks_mut(CHUNK),
        particles.vol.par_chunks_mut(CHUNK),
        particles.stress.par_chunks_mut(CHUNK),
        particles.pressure.par_chunks_mut(CHUNK),
        particles
            .dev_rate
            .par_chunks_mut(CHUNK)
            .zip(particles.history.par_chunks_mut(CHUNK)),
        particles.wave_speed.par_chunks_mut(CHUNK),
        particles.stored_energy.par_chunks_mut(CHUNK),
        particles.vol0.par_chunks(CHUNK),
        particles.material.par_chunks(CHUNK),
        stencils
            .par_chunks(CHUNK)
            .zip(particles.affine.par_chunks(CHUNK)),
        partials[..n_chunks].par_iter_mut(),
    )
        .into_par_iter()
        .pieces(piece)
        .for_each(
            |(
                f,
                j,
                vol,
                stress,
                pressure,
                (dev_rate, history),
                wave,
                stored,
                vol0,
                mat,
                (st, affine),
                work,
            )| {
                let (mut acc, mut rule_acc) = (0.0, [0.0; MAX_RULES]);
                // This step's history increments (softening solids only).
                let mut dxi = [0.0; CHUNK];
                for k in 0..f.len() {
                    let l = if mls {
                        affine[k]
                    } else {
                        velocity_gradient::<W>(shape, &st[k], velocity, nx, inv_h)
                    };
                    let f_new = (Mat2::identity() + dt * l) * f[k];
                    let det = f_new.determinant();
                    let (f_next, j_next) = match j_update {
                        JUpdate::Det => (f_new, det),
                        // One substep is the plain update: reuse it.
                        JUpdate::Substeps if !needs_substeps(l, dt) => (f_new, det),
                        JUpdate::Substeps => {
                            let f_sub = substepped(l, dt, f[k]);
                            (f_sub, f_sub.determinant())
                        }
                        JUpdate::Exp => {
                            let jn = j[k] * (dt * l.trace()).exp();
                            // Rescale F's volumetric part so that det F = J still holds.
                            (f_new * (jn / det).abs().sqrt(), jn)
                        }
                    };
                    let mut f_kept = f_next;
                    for rule in rules {
                        f_kept = rule.deformation(f_kept, j_next);
                    }
                    f[k] = f_kept;
                    j[k] = j_next;
                    vol[k] = vol0[k] * j_next;
                    let m = &materials[mat[k] as usize];
                    let d = 0.5 * (l + l.transpose());
                    let visc = viscosity::newtonian(m.viscosity, &d);
                    stress[k] = visc.stress;
                    dev_rate[k] = visc.dev_rate;
                    if m.softening_strain > 0.0 {
                        dxi[k] = crate::solid_neo_hookean::history_increment(&d, dt);
                    }
                    acc += visc.power * vol[k] * dt;
                    for (r, rule) in rules.iter().enumerate() {
                        // The wave speed is the previous step's (the EOS runs below).
                        if let Some((s, power)) = rule.extra_stress(m, wave[k], j_next, grid.h, &d)
                        {
                            stress[k] += s;
                            acc += power * vol[k] * dt;
                            if let Some(w) = rule_acc.get_mut(r) {
                                *w += power * vol[k] * dt;
                            }
                        }
                    }
                }
                // The EOS over the chunk in one loop per material (vectorised).
                let out = (&mut pressure[..], &mut wave[..], &mut stored[..]);
                if let [m] = materials {
                    m.eval_run(j, vol0, out);
                } else {
                    eval_mixed(materials, mat, j, vol0, out);
                }
                for (s, &p) in stress.iter_mut().zip(pressure.iter()) {
                    *s -= p * Mat2::identity();
                }
                if solids {
                    for k in 0..f.len() {
                        let m = &materials[mat[k] as usize];
                        let (s, w, e) = (&mut stress[k], &mut wave[k], &mut stored[k]);
                        let xi_before = history[k];
                        history[k] += dxi[k];
                        let xi = history[k];
                        // The energy softening released is dissipated.
                        acc += crate::solid_neo_hookean::add_to(
                            m, &f[k], vol0[k], xi_before, xi, s, w, e,
                        );
                    }
                }
                if drop_inverted {
                    for k in 0..f.len() {
                        if j[k].is_nan()
                            || j[k] <= 0.0
                            || (j_update == JUpdate::Exp && f[k].determinant() <= 0.0)
                        {
                            stress[k] = Mat2::zeros();
                            pressure[k] = 0.0;
                        }
                    }
                }
                work[0] = acc;
                work[1..].copy_from_slice(&rule_acc);
            },
        );
    let parts = &partials[..n_chunks];
    let mut rule_work = [0.0; MAX_RULES];
    for (r, w) in rule_work.iter_mut().enumerate() {
        *w = parts.iter().map(|p| p[1 + r]).sum();
    }
    (parts.iter().map(|p| p[0]).sum(), rule_work)
}

/// False when `substepped` takes one substep (|L| dt < 1), decided without
/// its square root: |L|^2 dt^2 < 0.81 keeps |L| dt below 0.91 whatever the
/// rounding, so the answer never differs from `substepped`'s own count.
#[inline]
pub fn needs_substeps(l: Mat2, dt: f64) -> bool {
    l.norm_squared() * (dt * dt) >= 0.81
}

/// Uintah's F update: (I + dt L / n)^n F with n = min(max(1, 2 floor(|L|
/// dt)), 10000), |L| the Frobenius norm: the plain update while |L| dt < 1.
#[inline]
pub fn substepped(l: Mat2, dt: f64, f: Mat2) -> Mat2 {
    let n = (2.0 * (l.norm() * dt).floor()).clamp(1.0, 10000.0) as usize;
    let step = Mat2::identity() + (dt / n as f64) * l;
    (0..n).fold(f, |acc, _| step * acc)
}

/// The EOS particle by particle when several materials are present.
fn eval_mixed(
    materials: &[Material],
    mat: &[u16],
    j: &[f64],
    vol0: &[f64],
    (pressure, wave, stored): (&mut [f64], &mut [f64], &mut [f64]),
) {
    for k in 0..j.len() {
        let m = &materials[mat[k] as usize];
        let state = m.eos(j[k]);
        pressure[k] = m.cut(state.pressure);
        wave[k] = m.wave_speed_of(&state, j[k]);
        stored[k] = vol0[k] * state.energy;
    }
}
