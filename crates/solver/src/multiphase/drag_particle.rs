//! Particle-based drag (docs/physics.md section 6). Bang-bang: each particle
//! of a phase that sits inside the other phase (every node of its stencil
//! carries the other phase's mass) feels f_p = B V_p^mix (v^other(x_p) -
//! v_p) with V_p^mix = V_p / n_p its mixture volume. SVF: every particle
//! feels that force times the other phase's smooth fraction at x_p,
//! sum_i N_ip phi_i^other. Either is spread to the nodes by N_ip. The
//! phases' nodal sums differ where only one phase's particles interact, so
//! the nodal equilibrium correction subtracts half their sum from each:
//! f_i^a = -f_i^b node by node. Explicit over the step, with v^n on the grid
//! and on the particles.

// The loops walk the weights and the stencil rows in step.
#![allow(clippy::needless_range_loop)]

use crate::grid::Grid;
use crate::multiphase::drag::{mixture_volume, set_pair, Coupling, Drag, DragModel, Scratch};
use crate::particles::Vec2;
use crate::Solver;

/// Spreads `from`'s particle drag against `other`'s grid velocity into
/// `force` (folded). With `other_fraction` (SVF: the other phase's nodal
/// presence) each particle's force is weighted by the presence interpolated
/// to it over h^2; without, only particles inside the other phase feel it
/// (bang-bang).
fn spread<const W: usize>(
    from: &Solver,
    other: &Grid,
    drag: &Drag,
    porosity: impl Fn(usize) -> f64,
    other_fraction: Option<&[f64]>,
    force: &mut [Vec2],
) {
    let g = from.grid();
    let nx = g.dims[0];
    for &n in &g.active {
        force[n as usize] = Vec2::zeros();
    }
    let present = |n: usize| other.is_active(n) && other.mass[n] > 0.0;
    let capacity = g.h * g.h;
    for (p, st) in from.stencils().iter().enumerate() {
        let (wx, _) = from.shape().stencil_weights::<W>(st.frac[0], st.half[0]);
        let (wy, _) = from.shape().stencil_weights::<W>(st.frac[1], st.half[1]);
        let (mut v_other, mut n_p, mut inside, mut phi) = (Vec2::zeros(), 0.0, true, 0.0);
        for c in 0..W {
            let row = st.node as usize + c * nx;
            for a in 0..W {
                let w = wx[a] * wy[c];
                if w == 0.0 {
                    continue;
                }
                let node = row + a;
                if !present(node) {
                    inside = false;
                }
                v_other += w * other.vel[node];
                n_p += w * porosity(node);
                if let Some(presence) = other_fraction {
                    if present(node) {
                        phi += w * presence[node];
                    }
                }
            }
        }
        let weight = match other_fraction {
            Some(_) => phi / capacity,
            None if inside => 1.0,
            None => continue,
        };
        if weight == 0.0 {
            continue;
        }
        let f = (drag.coefficient_at(n_p) * mixture_volume(from, p) * weight)
            * (v_other - from.particles().v[p]);
        for c in 0..W {
            let row = st.node as usize + c * nx;
            for a in 0..W {
                force[row + a] += (wx[a] * wy[c]) * f;
            }
        }
    }
    g.fold(force);
}

/// Both phases' particle drag, corrected to equilibrium node by node, added
/// to v^{n+1} over `dt`. With `fixed_a` phase a's velocity stays zero.
pub(crate) fn couple(
    a: &mut Solver,
    b: &mut Solver,
    drag: &Drag,
    scratch: &mut Scratch,
    dt: f64,
    fixed_a: bool,
    out: &mut Coupling,
) {
    let [va, vb] = &scratch.volume;
    let porosity = |n: usize| {
        let v = va[n] + vb[n];
        if v > 0.0 {
            vb[n] / v
        } else {
            1.0
        }
    };
    let [fa, fb] = &mut scratch.force;
    let [phi_a, phi_b] = &scratch.presence;
    let (of_b, of_a) = if drag.model == DragModel::SvfParticle {
        (Some(&phi_b[..]), Some(&phi_a[..]))
    } else {
        (None, None)
    };
    crate::shapes::with_width!(a.shape(), W => {
        spread::<W>(a, b.grid(), drag, porosity, of_b, fa);
        spread::<W>(b, a.grid(), drag, porosity, of_a, fb);
    });
    let (ga, gb) = (a.grid_mut(), b.grid_mut());
    for k in 0..ga.inside.len() {
        let n = ga.inside[k] as usize;
        let (ma, mb) = (ga.mass[n], gb.mass[n]);
        if !(gb.is_active(n) && ma > 0.0 && mb > 0.0) {
            continue;
        }
        out.nodes += 1;
        let inv_a = if fixed_a { 0.0 } else { 1.0 / ma };
        let volume = va[n] + vb[n];
        let k = drag.coefficient_at(vb[n] / volume) * volume * (inv_a + 1.0 / mb);
        out.stable_dt = out.stable_dt.min(2.0 / k);
        // Nodal equilibrium: remove half the pair's sum from each.
        let correction = 0.5 * (fa[n] + fb[n]);
        let (force_a, force_b) = (fa[n] - correction, fb[n] - correction);
        let da = (dt * inv_a) * force_a;
        let db = (dt / mb) * force_b;
        let new = [ga.vel_new[n] + da, gb.vel_new[n] + db];
        set_pair(ga, gb, n, new, dt, fixed_a, out);
    }
}
