//! Departure from hydrostatic pressure by docs/physics.md's clamped mass-above
//! reference: in grid column strip s (width h),
//! p_h(p) = (g / h) sum_{q in strip} m_q clamp((y_q - y_p) / l + 1/2, 0, 1),
//! l = h / ppc. Exact to round-off on a hydrostatic lattice of any
//! compressibility and any ppc.

use crate::geometry::Geometry;
use solver::Vec2;

#[derive(Clone, Debug)]
pub struct Hydrostatic {
    /// Particle indices grouped by strip, sorted by height within a strip.
    order: Vec<u32>,
    start: Vec<u32>,
    fill: Vec<u32>,
    /// Mass above (inclusive suffix sums) in `order`.
    suffix: Vec<f64>,
    pub reference: Vec<f64>,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Departure {
    /// sqrt(sum V (p - p_h)^2 / sum V p_h^2).
    pub rel_rms: f64,
    /// max |p - p_h| / (rho0 g H).
    pub max: f64,
}

impl Hydrostatic {
    pub fn new(geom: &Geometry, particles: usize) -> Self {
        Hydrostatic {
            order: vec![0; particles],
            start: vec![0; geom.cells[0] + 1],
            fill: vec![0; geom.cells[0] + 1],
            suffix: vec![0.0; particles + 1],
            reference: vec![0.0; particles],
        }
    }

    /// Fills `self.reference` with p_h for every particle.
    pub fn compute(&mut self, geom: &Geometry, x: &[Vec2], mass: &[f64]) {
        let nx = geom.cells[0];
        let strip = |xp: &Vec2| geom.cell_of(*xp).0;
        if x.len() > self.order.len() {
            // Particles entered through an inflow wall.
            self.order.resize(x.len(), 0);
            self.suffix.resize(x.len() + 1, 0.0);
            self.reference.resize(x.len(), 0.0);
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
        let g_over_h = geom.gravity / geom.cell;
        for s in 0..nx {
            let (a, b) = (self.start[s] as usize, self.start[s + 1] as usize);
            let idx = &mut self.order[a..b];
            idx.sort_unstable_by(|&p, &q| {
                x[p as usize].y.total_cmp(&x[q as usize].y).then(p.cmp(&q))
            });
            self.suffix[b] = 0.0;
            for k in (a..b).rev() {
                self.suffix[k] = self.suffix[k + 1] + mass[self.order[k] as usize];
            }
            for k in a..b {
                let p = self.order[k] as usize;
                let yp = x[p].y;
                let ys = |k: usize| x[self.order[k] as usize].y;
                // First index at or above y_p + l/2 counts fully (sorted ascending).
                let full = a + partition(a, b, |k| ys(k) - yp < 0.5 * l);
                let lo = a + partition(a, b, |k| ys(k) - yp <= -0.5 * l);
                let mut above = self.suffix[full];
                for q in lo..full {
                    let yq = ys(q);
                    above += mass[self.order[q] as usize] * ((yq - yp) / l + 0.5).clamp(0.0, 1.0);
                }
                self.reference[p] = g_over_h * above;
            }
        }
    }

    pub fn departure(&self, geom: &Geometry, volume: &[f64], pressure: &[f64]) -> Departure {
        let (mut num, mut den, mut max) = (0.0, 0.0, 0.0f64);
        for p in 0..pressure.len() {
            let d = pressure[p] - self.reference[p];
            num += volume[p] * d * d;
            den += volume[p] * self.reference[p] * self.reference[p];
            max = max.max(d.abs());
        }
        Departure {
            rel_rms: if den > 0.0 { (num / den).sqrt() } else { 0.0 },
            max: max / (geom.rho0 * geom.gravity * geom.column_height).max(1e-300),
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
