//! End-of-step figures in one pass over the particles: the energies, the
//! blow-out counters, and the signal speed max(c + |v|) the next CFL step
//! needs (velocities and cached wave speeds do not change until then), and
//! Uintah's per-axis one from the step-start velocity.

use crate::energy::Energy;
use crate::par;
use crate::particles::{Particles, Vec2};

/// Per-chunk partial results (sums in chunk order; max is exact in any order).
#[derive(Clone, Copy, Debug, Default)]
pub struct Partial {
    kinetic: f64,
    affine: f64,
    gravitational: f64,
    stored: f64,
    outside: usize,
    nonfinite: usize,
    signal_speed: f64,
    axis_signal_speed: f64,
    wave_speed: f64,
}

pub struct Measured {
    pub energy: Energy,
    pub n_outside: usize,
    pub n_nonfinite: usize,
    pub signal_speed: f64,
    /// max_p(c_p + the largest |component| of the step-start velocity):
    /// Uintah's per-axis signal speed (`DtMode::PerAxis`).
    pub axis_signal_speed: f64,
    /// max_p c_p: the signal speed along a slab's z axis (`scene.slab`).
    pub wave_speed: f64,
}

/// The box walls a particle may not cross (periodic axes excepted).
pub struct Bounds {
    pub lo: Vec2,
    pub hi: Vec2,
    pub periodic: [bool; 2],
}

/// `affine_inertia`: APIC's D (m^2, D = d I) where it is constant, else None.
pub fn measure(
    particles: &Particles,
    gravity: f64,
    bounds: &Bounds,
    dissipated: f64,
    affine_inertia: Option<f64>,
    partials: &mut [Partial],
) -> Measured {
    let ps = particles;
    let (lo, hi, periodic) = (bounds.lo, bounds.hi, bounds.periodic);
    let floor = lo.y;
    let item = |acc: &mut Partial, p: usize| {
        let (m, x, v) = (ps.mass[p], ps.x[p], ps.v[p]);
        acc.kinetic += 0.5 * m * v.norm_squared();
        if let Some(d) = affine_inertia {
            acc.affine += 0.5 * m * d * ps.affine[p].norm_squared();
        }
        acc.gravitational += m * gravity * (x.y - floor);
        acc.stored += ps.stored_energy[p];
        let finite = x.iter().chain(v.iter()).all(|c| c.is_finite())
            && ps.j[p].is_finite()
            && ps.pressure[p].is_finite();
        let out = (0..2).any(|k| !periodic[k] && (x[k] < lo[k] || x[k] > hi[k]));
        acc.outside += out as usize;
        acc.nonfinite += !finite as usize;
        acc.signal_speed = acc.signal_speed.max(ps.wave_speed[p] + v.norm());
        acc.axis_signal_speed = acc
            .axis_signal_speed
            .max(crate::timestep::axis_signal_speed_of(ps, p));
        acc.wave_speed = acc.wave_speed.max(ps.wave_speed[p]);
    };
    let combine = |total: &mut Partial, part: &Partial| {
        total.kinetic += part.kinetic;
        total.affine += part.affine;
        total.gravitational += part.gravitational;
        total.stored += part.stored;
        total.outside += part.outside;
        total.nonfinite += part.nonfinite;
        total.signal_speed = total.signal_speed.max(part.signal_speed);
        total.axis_signal_speed = total.axis_signal_speed.max(part.axis_signal_speed);
        total.wave_speed = total.wave_speed.max(part.wave_speed);
    };
    let init = Partial {
        signal_speed: f64::NEG_INFINITY,
        axis_signal_speed: f64::NEG_INFINITY,
        wave_speed: f64::NEG_INFINITY,
        ..Partial::default()
    };
    let total = par::fold(ps.len(), partials, init, item, combine);
    Measured {
        energy: Energy {
            kinetic: total.kinetic,
            affine: total.affine,
            gravitational: total.gravitational,
            stored: total.stored,
            dissipated,
        },
        n_outside: total.outside,
        n_nonfinite: total.nonfinite,
        signal_speed: total.signal_speed,
        axis_signal_speed: total.axis_signal_speed,
        wave_speed: total.wave_speed,
    }
}
