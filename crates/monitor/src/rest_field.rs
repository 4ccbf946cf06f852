//! The exact rest field the hydrostatic departure is scored against for its
//! floor: a flat layer spanning the box width W that holds the
//! particles' mass M, at rest under the first material's EOS. Its bottom
//! pressure is p_b = g M / W and, with J(p) the inverse EOS,
//! dp/dy = -rho0 g / J(p), p = 0 at the surface. Depth below the surface as
//! a function of pressure, z(p) = integral_0^p J(p') dp' / (rho0 g), is
//! tabulated once at a fixed pressure step (extended when p_b grows) and
//! inverted per particle by cubic Hermite interpolation (dz/dp = J / (rho0 g)
//! is known at every node). In a column that has not moved this is
//! rho0 g (H0 - Y), Y the particle's height in the unstressed lattice.

use crate::geometry::Geometry;
use solver::{Material, Vec2};

/// Table steps per rho0 g h of pressure: the interpolation error (fourth
/// order in the step) is then far below round-off of the departure sums.
const STEPS_PER_CELL_PRESSURE: f64 = 32.0;

#[derive(Clone, Debug)]
pub struct RestField {
    material: Option<Material>,
    rho0_g: f64,
    /// Pressure step of the table (Pa); 0 without gravity.
    dp: f64,
    /// z_k = z(k dp) and J_k = J(k dp).
    depth: Vec<f64>,
    j: Vec<f64>,
    /// p_rest at each particle's current height.
    pub pressure: Vec<f64>,
    /// p_b = g M / W of the last `compute`.
    pub bottom_pressure: f64,
    /// The layer's surface above the box's bottom, z(p_b).
    pub surface_height: f64,
}

impl RestField {
    pub fn new(geom: &Geometry, particles: usize) -> Self {
        let rho0_g = geom.rho0 * geom.gravity;
        let dp = (rho0_g * geom.cell / STEPS_PER_CELL_PRESSURE).max(0.0);
        // Room for a layer twice the box height before the table reallocates.
        let rows = 2.0 * geom.size.y / geom.cell * STEPS_PER_CELL_PRESSURE;
        let capacity = if rows.is_finite() {
            rows as usize + 2
        } else {
            2
        };
        let mut field = RestField {
            material: geom.material.clone(),
            rho0_g,
            dp,
            depth: Vec::with_capacity(capacity),
            j: Vec::with_capacity(capacity),
            pressure: vec![0.0; particles],
            bottom_pressure: 0.0,
            surface_height: 0.0,
        };
        field.depth.push(0.0);
        field.j.push(field.j_at(0.0));
        field
    }

    /// J at pressure p: the first material's inverse EOS (1 without one).
    fn j_at(&self, p: f64) -> f64 {
        self.material.as_ref().map_or(1.0, |m| m.j_at_pressure(p))
    }

    /// integral_a^b J dp by Simpson's rule (one table step or less).
    fn integral_of_j(&self, a: f64, b: f64, ja: f64, jb: f64) -> f64 {
        (b - a) / 6.0 * (ja + 4.0 * self.j_at(0.5 * (a + b)) + jb)
    }

    /// Extends the table until it covers pressure `p`.
    fn extend_to(&mut self, p: f64) {
        while ((self.depth.len() - 1) as f64) * self.dp < p {
            let k = self.depth.len() - 1;
            let (a, b) = (k as f64 * self.dp, (k + 1) as f64 * self.dp);
            let jb = self.j_at(b);
            let step = self.integral_of_j(a, b, self.j[k], jb) / self.rho0_g;
            self.depth.push(self.depth[k] + step);
            self.j.push(jb);
        }
    }

    /// z(p) for p within the table.
    fn depth_at(&self, p: f64) -> f64 {
        let k = ((p / self.dp) as usize).min(self.depth.len() - 2);
        let a = k as f64 * self.dp;
        self.depth[k] + self.integral_of_j(a, p, self.j[k], self.j_at(p)) / self.rho0_g
    }

    /// p at depth z below the surface (0 above it).
    fn pressure_at_depth(&self, z: f64) -> f64 {
        if z.is_nan() || z <= 0.0 {
            return 0.0;
        }
        let last = self.depth.len() - 1;
        let k = self.depth.partition_point(|&d| d <= z).saturating_sub(1);
        if k >= last {
            // Below the table (a particle under the floor): the last slope.
            return last as f64 * self.dp + (z - self.depth[last]) * self.rho0_g / self.j[last];
        }
        let (z0, z1) = (self.depth[k], self.depth[k + 1]);
        let span = z1 - z0;
        let t = (z - z0) / span;
        // dp/dz = rho0 g / J at both ends.
        let (s0, s1) = (self.rho0_g / self.j[k], self.rho0_g / self.j[k + 1]);
        let (p0, p1) = (k as f64 * self.dp, (k + 1) as f64 * self.dp);
        let (t2, t3) = (t * t, t * t * t);
        (2.0 * t3 - 3.0 * t2 + 1.0) * p0
            + (t3 - 2.0 * t2 + t) * span * s0
            + (-2.0 * t3 + 3.0 * t2) * p1
            + (t3 - t2) * span * s1
    }

    /// p_rest at height `y` (m, absolute) for the layer of the last `compute`.
    pub fn pressure_at(&self, geom: &Geometry, y: f64) -> f64 {
        if self.bottom_pressure <= 0.0 {
            return 0.0;
        }
        self.pressure_at_depth(self.surface_height - (y - geom.origin.y))
    }

    /// Fills `self.pressure` for the layer holding the particles' total mass.
    pub fn compute(&mut self, geom: &Geometry, x: &[Vec2], mass: &[f64]) {
        if x.len() > self.pressure.len() {
            // Particles entered through an inflow wall.
            self.pressure.resize(x.len(), 0.0);
        }
        let total: f64 = mass.iter().sum();
        let p_b = geom.gravity * total / geom.size.x;
        if !(self.dp > 0.0 && p_b > 0.0 && p_b.is_finite()) {
            // No gravity or no mass: a layer without pressure (and no 0 / 0).
            self.bottom_pressure = 0.0;
            self.surface_height = 0.0;
            self.pressure.fill(0.0);
            return;
        }
        self.extend_to(p_b);
        self.bottom_pressure = p_b;
        self.surface_height = self.depth_at(p_b);
        for (p, xp) in x.iter().enumerate() {
            self.pressure[p] = self.pressure_at(geom, xp.y);
        }
    }
}
