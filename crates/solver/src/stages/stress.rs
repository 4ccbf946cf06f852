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
    let (mut col0, mut col1) = (Vec2::zeros(), Vec2::zeros());
    shape.each_piece::<W>(st, nx, |p| {
        for c in 0..W {
            let row = p.node + c * nx;
            let (mut sw, mut sdw) = (Vec2::zeros(), Vec2::zeros());
            for a in 0..W {
                let vn = velocity[row + a];
                sw += p.wx[a] * vn;
                sdw += p.dwx[a] * vn;
            }
            col0 += p.wy[c] * sdw;
            col1 += p.dwy[c] * sw;
        }
    });
    Mat2::from_columns(&[col0, col1]) * inv_h
}

/// One chunk of particles as the stage sees it: what it writes, then
/// what it reads.
struct Chunk<'a> {
    f: &'a mut [Mat2],
    j: &'a mut [f64],
    vol: &'a mut [f64],
    stress: &'a mut [Mat2],
    pressure: &'a mut [f64],
    dev_rate: &'a mut [f64],
    history: &'a mut [f64],
    wave: &'a mut [f64],
    stored: &'a mut [f64],
    vol0: &'a [f64],
    material: &'a [u16],
    stencils: &'a [Stencil],
    affine: &'a [Mat2],
}

fn run<const W: usize>(
    inputs: &Inputs,
    particles: &mut Particles,
    partials: &mut [Partial],
) -> (f64, [f64; MAX_RULES]) {
    let solids = inputs.materials.iter().any(|m| m.shear_modulus > 0.0);
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
        inputs
            .stencils
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
                material,
                (stencils, affine),
                work,
            )| {
                let mut c = Chunk {
                    f,
                    j,
                    vol,
                    stress,
                    pressure,
                    dev_rate,
                    history,
                    wave,
                    stored,
                    vol0,
                    material,
                    stencils,
                    affine,
                };
                let (acc, rule_acc) = update_chunk::<W>(inputs, &mut c, solids);
                work[0] = acc;
                work[1..].copy_from_slice(&rule_acc);
            },
        );
    sum_partials(&partials[..n_chunks])
}

/// One chunk's stage: F, J, the viscous and extra stress, the EOS, the
/// solids' softening and the inverted particles' stress; the chunk's
/// dissipated work and each rule's share.
#[inline(always)]
fn update_chunk<const W: usize>(
    inputs: &Inputs,
    c: &mut Chunk,
    solids: bool,
) -> (f64, [f64; MAX_RULES]) {
    // This step's history increments (softening solids only).
    let mut dxi = [0.0; CHUNK];
    let (mut acc, rule_acc) = deform::<W>(inputs, c, &mut dxi);
    pressure_from_eos(inputs.materials, c);
    if solids {
        acc = soften(inputs.materials, c, &dxi, acc);
    }
    if inputs.drop_inverted {
        drop_inverted_stress(inputs.j_update, c);
    }
    (acc, rule_acc)
}

/// The dissipated work and each rule's share, summed over the chunks in order.
fn sum_partials(parts: &[Partial]) -> (f64, [f64; MAX_RULES]) {
    let mut rule_work = [0.0; MAX_RULES];
    for (r, w) in rule_work.iter_mut().enumerate() {
        *w = parts.iter().map(|p| p[1 + r]).sum();
    }
    (parts.iter().map(|p| p[0]).sum(), rule_work)
}

/// F, J and V from the velocity gradient, the viscous stress and the
/// rules' extra stress; returns the chunk's dissipated work and each
/// rule's share, and leaves each softening particle's history increment.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // k indexes a dozen parallel slices
fn deform<const W: usize>(
    inputs: &Inputs,
    c: &mut Chunk,
    dxi: &mut [f64; CHUNK],
) -> (f64, [f64; MAX_RULES]) {
    let (shape, velocity, dt, rules) = (inputs.shape, inputs.velocity, inputs.dt, inputs.rules);
    let nx = inputs.grid.dims[0];
    let inv_h = 1.0 / inputs.grid.h;
    let (mut acc, mut rule_acc) = (0.0, [0.0; MAX_RULES]);
    for k in 0..c.f.len() {
        let l = if inputs.mls {
            c.affine[k]
        } else {
            velocity_gradient::<W>(shape, &c.stencils[k], velocity, nx, inv_h)
        };
        let (f_next, j_next) = next_deformation(inputs.j_update, l, dt, c.f[k], c.j[k]);
        let mut f_kept = f_next;
        for rule in rules {
            f_kept = rule.deformation(f_kept, j_next);
        }
        c.f[k] = f_kept;
        c.j[k] = j_next;
        c.vol[k] = c.vol0[k] * j_next;
        let m = &inputs.materials[c.material[k] as usize];
        let d = 0.5 * (l + l.transpose());
        let visc = viscosity::newtonian(m.viscosity, &d);
        c.stress[k] = visc.stress;
        c.dev_rate[k] = visc.dev_rate;
        if m.softening_strain > 0.0 {
            dxi[k] = crate::solid_neo_hookean::history_increment(&d, dt);
        }
        acc += visc.power * c.vol[k] * dt;
        for (r, rule) in rules.iter().enumerate() {
            // The wave speed is the previous step's (the EOS runs below).
            if let Some((s, power)) = rule.extra_stress(m, c.wave[k], j_next, inputs.grid.h, &d) {
                c.stress[k] += s;
                acc += power * c.vol[k] * dt;
                if let Some(w) = rule_acc.get_mut(r) {
                    *w += power * c.vol[k] * dt;
                }
            }
        }
    }
    (acc, rule_acc)
}

/// F and J after a step with velocity gradient `l`, by the J update chosen.
#[inline(always)]
fn next_deformation(j_update: JUpdate, l: Mat2, dt: f64, f: Mat2, j: f64) -> (Mat2, f64) {
    let f_new = (Mat2::identity() + dt * l) * f;
    let det = f_new.determinant();
    match j_update {
        JUpdate::Det => (f_new, det),
        // One substep is the plain update: reuse it.
        JUpdate::Substeps if !needs_substeps(l, dt) => (f_new, det),
        JUpdate::Substeps => {
            let f_sub = substepped(l, dt, f);
            (f_sub, f_sub.determinant())
        }
        JUpdate::Exp => {
            let jn = j * (dt * l.trace()).exp();
            // Rescale F's volumetric part so that det F = J still holds.
            (f_new * (jn / det).abs().sqrt(), jn)
        }
    }
}

/// The EOS over the chunk in one loop per material (vectorised), and the
/// pressure into the stress.
#[inline(always)]
fn pressure_from_eos(materials: &[Material], c: &mut Chunk) {
    let out = (&mut c.pressure[..], &mut c.wave[..], &mut c.stored[..]);
    if let [m] = materials {
        m.eval_run(c.j, c.vol0, out);
    } else {
        eval_mixed(materials, c.material, c.j, c.vol0, out);
    }
    for (s, &p) in c.stress.iter_mut().zip(c.pressure.iter()) {
        *s -= p * Mat2::identity();
    }
}

/// The solids' neo-Hookean stress, softened by the history's increments
/// `dxi`; returns `acc` plus the energy softening released (dissipated).
#[inline(always)]
fn soften(materials: &[Material], c: &mut Chunk, dxi: &[f64; CHUNK], mut acc: f64) -> f64 {
    for k in 0..c.f.len() {
        let m = &materials[c.material[k] as usize];
        let (s, w, e) = (&mut c.stress[k], &mut c.wave[k], &mut c.stored[k]);
        let xi_before = c.history[k];
        c.history[k] += dxi[k];
        let xi = c.history[k];
        acc += crate::solid_neo_hookean::add_to(m, &c.f[k], c.vol0[k], xi_before, xi, s, w, e);
    }
    acc
}

/// No stress on a particle that inverted (`Inputs::drop_inverted`).
#[inline(always)]
fn drop_inverted_stress(j_update: JUpdate, c: &mut Chunk) {
    for k in 0..c.f.len() {
        if c.j[k].is_nan()
            || c.j[k] <= 0.0
            || (j_update == JUpdate::Exp && c.f[k].determinant() <= 0.0)
        {
            c.stress[k] = Mat2::zeros();
            c.pressure[k] = 0.0;
        }
    }
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
        stored[k] = vol0[k] * m.energy_of(j[k], &state);
    }
}
