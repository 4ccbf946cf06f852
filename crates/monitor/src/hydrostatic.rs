//! Departure from hydrostatic pressure by docs/physics.md's clamped mass-above
//! reference: in grid column strip s (width h),
//! p_h(p) = (g / h) sum_{q in strip} m_q clamp((y_q - y_p) / l + 1/2, 0, 1),
//! l = h / ppc. Exact to round-off on a hydrostatic lattice of any
//! compressibility and any ppc.
//!
//! Beside it, the pressure the flow's own vertical accelerations demand:
//! p_a(p) = (1 / h) sum_{q in strip} m_q (g + a_y,q) clamp(...), from
//! dp/dy = -rho (g + a_y). Departure from p_h that is also departure from
//! p_a is not explained by the motion (sloshing, a run-up at a wall): it is
//! the pressure's own error, or the reference's sampling of a disordered
//! strip.
//!
//! The same score of an exact rest field (`rest_field`) on the same
//! particles is the floor this reference's sampling sets: on a disordered
//! arrangement even the exact pressure scores above 0.

use crate::geometry::Geometry;
use crate::rest_field::RestField;
use solver::Vec2;

#[derive(Clone, Debug)]
pub struct Hydrostatic {
    /// Particle indices grouped by strip, sorted by height within a strip.
    order: Vec<u32>,
    start: Vec<u32>,
    fill: Vec<u32>,
    /// Mass above (inclusive suffix sums) in `order`.
    suffix: Vec<f64>,
    /// m (g + a_y) above, likewise.
    suffix_load: Vec<f64>,
    pub reference: Vec<f64>,
    /// p_a: the weight and the vertical inertia above.
    pub with_accel: Vec<f64>,
    /// The flat layer's exact rest pressure at each particle.
    pub rest: RestField,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Departure {
    /// sqrt(sum V (p - p_h)^2 / sum V p_h^2).
    pub rel_rms: f64,
    /// max |p - p_h| / (rho0 g H).
    pub max: f64,
    /// sqrt(sum V (p - p_a)^2 / sum V p_h^2): the part the accelerations do not explain.
    pub unexplained_rel_rms: f64,
    /// sqrt(sum V (p_rest - p_h)^2 / sum V p_h^2): the exact rest field's score.
    pub floor_rel_rms: f64,
    /// sqrt(max(rel_rms^2 - floor_rel_rms^2, 0)).
    pub excess_rel_rms: f64,
}

impl Hydrostatic {
    pub fn new(geom: &Geometry, particles: usize) -> Self {
        Hydrostatic {
            order: vec![0; particles],
            start: vec![0; geom.cells[0] + 1],
            fill: vec![0; geom.cells[0] + 1],
            suffix: vec![0.0; particles + 1],
            suffix_load: vec![0.0; particles + 1],
            reference: vec![0.0; particles],
            with_accel: vec![0.0; particles],
            rest: RestField::new(geom, particles),
        }
    }

    /// Fills `self.reference` with p_h, `self.with_accel` with p_a and
    /// `self.rest` with the rest field for every particle (`accel`: the
    /// particles' accelerations, gravity included).
    pub fn compute(&mut self, geom: &Geometry, x: &[Vec2], mass: &[f64], accel: &[Vec2]) {
        self.rest.compute(geom, x, mass);
        let nx = geom.cells[0];
        let strip = |xp: &Vec2| geom.cell_of(*xp).0;
        if x.len() > self.order.len() {
            // Particles entered through an inflow wall.
            self.order.resize(x.len(), 0);
            self.suffix.resize(x.len() + 1, 0.0);
            self.suffix_load.resize(x.len() + 1, 0.0);
            self.reference.resize(x.len(), 0.0);
            self.with_accel.resize(x.len(), 0.0);
        }
        self.start.fill(0);
        for xp in x {
            self.start[strip(xp) + 1] += 1;
        }
        for s in 1..=nx {
            self.start[s] += self.start[s - 1];
        }
        self.fill.copy_from_slice(&self.start);
        for (p, xp) in x.iter().enumerate() {
            let s = strip(xp);
            self.order[self.fill[s] as usize] = p as u32;
            self.fill[s] += 1;
        }
        let l = geom.cell / geom.ppc as f64;
        let g = geom.gravity;
        let g_over_h = g / geom.cell;
        for s in 0..nx {
            let (a, b) = (self.start[s] as usize, self.start[s + 1] as usize);
            let idx = &mut self.order[a..b];
            idx.sort_unstable_by(|&p, &q| {
                x[p as usize].y.total_cmp(&x[q as usize].y).then(p.cmp(&q))
            });
            self.suffix[b] = 0.0;
            self.suffix_load[b] = 0.0;
            for k in (a..b).rev() {
                let q = self.order[k] as usize;
                self.suffix[k] = self.suffix[k + 1] + mass[q];
                self.suffix_load[k] = self.suffix_load[k + 1] + mass[q] * (g + accel[q].y);
            }
            for k in a..b {
                let p = self.order[k] as usize;
                let yp = x[p].y;
                let ys = |k: usize| x[self.order[k] as usize].y;
                // First index at or above y_p + l/2 counts fully (sorted ascending).
                let full = a + partition(a, b, |k| ys(k) - yp < 0.5 * l);
                let lo = a + partition(a, b, |k| ys(k) - yp <= -0.5 * l);
                let mut above = self.suffix[full];
                let mut load = self.suffix_load[full];
                for k in lo..full {
                    let q = self.order[k] as usize;
                    let share = mass[q] * ((ys(k) - yp) / l + 0.5).clamp(0.0, 1.0);
                    above += share;
                    load += share * (g + accel[q].y);
                }
                self.reference[p] = g_over_h * above;
                self.with_accel[p] = load / geom.cell;
            }
        }
    }

    pub fn departure(&self, geom: &Geometry, volume: &[f64], pressure: &[f64]) -> Departure {
        let (mut num, mut den, mut max, mut rest) = (0.0, 0.0, 0.0f64, 0.0);
        let mut floor = 0.0;
        for p in 0..pressure.len() {
            let d = pressure[p] - self.reference[p];
            let e = pressure[p] - self.with_accel[p];
            let f = self.rest.pressure[p] - self.reference[p];
            num += volume[p] * d * d;
            rest += volume[p] * e * e;
            floor += volume[p] * f * f;
            den += volume[p] * self.reference[p] * self.reference[p];
            max = max.max(d.abs());
        }
        let relative = |x: f64| if den > 0.0 { (x / den).sqrt() } else { 0.0 };
        let (rel_rms, floor_rel_rms) = (relative(num), relative(floor));
        Departure {
            rel_rms,
            max: max / (geom.rho0 * geom.gravity * geom.column_height).max(1e-300),
            unexplained_rel_rms: relative(rest),
            floor_rel_rms,
            excess_rel_rms: (rel_rms * rel_rms - floor_rel_rms * floor_rel_rms)
                .max(0.0)
                .sqrt(),
        }
    }
}

/// Number of leading indices in a..b for which `pred` holds (pred monotone).
fn partition(a: usize, b: usize, pred: impl Fn(usize) -> bool) -> usize {
    let (mut lo, mut hi) = (a, b);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if pred(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo - a
}
