//! Inflow walls (docs/physics.md section 6): the fluid enters the box
//! through a wall at a prescribed velocity. The wall is open to the fluid
//! (no mirror) and stays a wall for the solid (a filter the grains cannot
//! pass). Each step the fluid's grid velocity on and beyond the wall row is
//! set to the inflow velocity, and a row of fluid particles (the lattice of
//! the fluid at the wall, one spacing l = h / ppc apart) enters each time
//! the inflow has fed one spacing. Between entries the pore pressure's
//! volume balance counts the rows still outside as virtual particles (the
//! lattice continued beyond the wall), so the nodes at the wall read as
//! full whatever the phase of the entry; beyond the wall the pressure is
//! the odd image about the wall row's own, so its gradient carries through.

use crate::checkpoint::{CheckpointError, Reader, Writer};
use crate::config::Wall;
use crate::grid::{Grid, PAD};
use crate::particles::{Mat2, Vec2};
use crate::Solver;

#[derive(Clone, Debug)]
pub struct Inflow {
    /// The fluid's speed into the box (m/s, along the wall's inward normal).
    pub velocity: f64,
    /// Per [axis][low, high] inflow wall: the distance fed since its last
    /// row entered, in [0, l).
    fed: [[Option<f64>; 2]; 2],
    /// Lattice spacing l = h / ppc.
    spacing: f64,
    /// An entering particle: the fluid particle nearest the wall at t = 0.
    mass: f64,
    vol0: f64,
    material: u16,
}

impl Inflow {
    /// Inflow through `walls` at `velocity`, its particles copied from the
    /// fluid particle nearest a wall. None when the fluid has no particles.
    pub(crate) fn new(fluid: &Solver, walls: &[Wall], velocity: f64) -> Option<Self> {
        let scene = fluid.scene();
        let mask = Wall::mask(walls);
        let (lo, size) = (Vec2::from(scene.origin), Vec2::from(scene.size));
        let ps = fluid.particles();
        let gap = |p: usize| {
            let mut best = f64::INFINITY;
            for (axis, sides) in mask.iter().enumerate() {
                for (side, &on) in sides.iter().enumerate() {
                    if on {
                        let wall = lo[axis] + side as f64 * size[axis];
                        best = best.min((ps.x[p][axis] - wall).abs());
                    }
                }
            }
            best
        };
        let nearest = (0..ps.len()).min_by(|&a, &b| gap(a).total_cmp(&gap(b)))?;
        Some(Inflow {
            velocity,
            fed: mask.map(|sides| sides.map(|on| on.then_some(0.0))),
            spacing: scene.cell / scene.ppc as f64,
            mass: ps.mass[nearest],
            vol0: ps.vol0[nearest],
            material: ps.material[nearest],
        })
    }

    /// Open sides [axis][low, high] (the inflow walls).
    pub fn mask(&self) -> [[bool; 2]; 2] {
        self.fed.map(|sides| sides.map(|f| f.is_some()))
    }

    fn walls(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        (0..2).flat_map(move |axis| {
            (0..2).filter_map(move |side| self.fed[axis][side].map(|f| (axis, side, f)))
        })
    }

    /// Particles per row on the wall normal to `axis`.
    fn row_len(&self, fluid: &Solver, axis: usize) -> usize {
        (fluid.scene().size[1 - axis] / self.spacing).round() as usize
    }

    /// Particles that enter by t_end (one row more for the round-off of the
    /// feed), to be reserved at set-up.
    pub(crate) fn expected_entries(&self, fluid: &Solver) -> usize {
        let fed = self.velocity * fluid.scene().t_end;
        self.walls()
            .map(|(axis, _, _)| {
                ((fed / self.spacing).ceil() as usize + 1) * self.row_len(fluid, axis)
            })
            .sum()
    }

    /// The position of a row `depth` inside the wall (negative: outside) and
    /// of its k-th particle.
    fn row_point(&self, fluid: &Solver, axis: usize, side: usize, depth: f64, k: usize) -> Vec2 {
        let s = fluid.scene();
        let mut x = Vec2::zeros();
        x[axis] = if side == 0 {
            s.origin[axis] + depth
        } else {
            s.origin[axis] + s.size[axis] - depth
        };
        x[1 - axis] = s.origin[1 - axis] + (k as f64 + 0.5) * self.spacing;
        x
    }

    /// Sets the fluid's v^{n+1} on and beyond each inflow wall row to the
    /// inflow velocity (its nodal acceleration with it); returns the grid
    /// kinetic energy this gave.
    pub(crate) fn impose(&self, fluid: &mut Solver) -> f64 {
        let dt = fluid.dt();
        let g = fluid.grid_mut();
        let before = crate::multiphase::drag::grid_kinetic(g);
        for idx in 0..g.active.len() {
            let n = g.active[idx] as usize;
            if g.mass[n] <= 0.0 {
                continue;
            }
            let ij = g.coords(n);
            for (axis, side, _) in self.walls() {
                let k = [ij.0, ij.1][axis];
                let wall = PAD + side * g.cells[axis];
                let on_or_beyond = if side == 0 { k <= wall } else { k >= wall };
                if on_or_beyond {
                    let target = self.velocity * inward(axis, side);
                    g.accel[n] += (target - g.vel_new[n]) / dt;
                    g.vel_new[n] = target;
                }
            }
        }
        crate::multiphase::drag::refill(g);
        crate::multiphase::drag::grid_kinetic(g) - before
    }

    /// Feeds the step's `dt` at each wall and lets a row in for every
    /// spacing fed, l past the row before it; returns the particles let in.
    pub(crate) fn enter(&mut self, fluid: &mut Solver, dt: f64) -> usize {
        let mut entered = 0;
        for axis in 0..2 {
            for side in 0..2 {
                let Some(mut fed) = self.fed[axis][side] else {
                    continue;
                };
                fed += self.velocity * dt;
                while fed >= self.spacing {
                    fed -= self.spacing;
                    let depth = 0.5 * self.spacing + fed;
                    let v = self.velocity * inward(axis, side);
                    for k in 0..self.row_len(fluid, axis) {
                        let x = self.row_point(fluid, axis, side, depth, k);
                        fluid.inject(x, v, self.mass, self.vol0, self.material);
                        entered += 1;
                    }
                }
                self.fed[axis][side] = Some(fed);
            }
        }
        entered
    }

    /// Adds the reference volumes of the rows still outside (the lattice
    /// continued beyond each wall, to two cells out) to raw nodal sums.
    pub(crate) fn add_outside_rows(&self, fluid: &Solver, out: &mut [f64]) {
        crate::shapes::with_width!(fluid.shape(), W => self.add_rows::<W>(fluid, out))
    }

    fn add_rows<const W: usize>(&self, fluid: &Solver, out: &mut [f64]) {
        let (g, shape) = (fluid.grid(), fluid.shape());
        let half = shape.half_widths(&Mat2::identity());
        let reach = PAD as f64 * g.h;
        for (axis, side, fed) in self.walls() {
            let mut depth = 0.5 * self.spacing + fed - self.spacing;
            while depth > -reach {
                for k in 0..self.row_len(fluid, axis) {
                    let x = self.row_point(fluid, axis, side, depth, k);
                    add_point::<W>(g, shape, half, x, self.vol0, out);
                }
                depth -= self.spacing;
            }
        }
    }

    pub(crate) fn save(&self, w: &mut Writer) {
        for f in self.fed.iter().flatten() {
            w.f64(f.unwrap_or(f64::NAN));
        }
    }

    pub(crate) fn load(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        for f in self.fed.iter_mut().flatten() {
            let stored = r.f64()?;
            if let Some(fed) = f {
                *fed = stored;
            }
        }
        Ok(())
    }
}

/// The unit normal into the box of the wall normal to `axis` on `side`.
fn inward(axis: usize, side: usize) -> Vec2 {
    let mut v = Vec2::zeros();
    v[axis] = if side == 0 { 1.0 } else { -1.0 };
    v
}

/// q N_i(x) added to each node of x's stencil that lies on the padded grid.
pub(crate) fn add_point<const W: usize>(
    g: &Grid,
    shape: &crate::shapes::Shape,
    half: [f64; 2],
    x: Vec2,
    q: f64,
    out: &mut [f64],
) {
    let r = (x - g.origin) / g.h;
    let (bx, fx) = shape.locate(r.x);
    let (by, fy) = shape.locate(r.y);
    let (wx, _) = shape.stencil_weights::<W>(fx, half[0]);
    let (wy, _) = shape.stencil_weights::<W>(fy, half[1]);
    let (pad, nx, ny) = (PAD as i64, g.dims[0] as i64, g.dims[1] as i64);
    for (c, wyc) in wy.iter().enumerate() {
        let j = by + pad + c as i64;
        for (a, wxa) in wx.iter().enumerate() {
            let i = bx + pad + a as i64;
            if (0..nx).contains(&i) && (0..ny).contains(&j) {
                out[(i + j * nx) as usize] += q * wxa * wyc;
            }
        }
    }
}
