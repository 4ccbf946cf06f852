//! Background grid over the box plus `PAD` ghost layers. Walls are symmetry
//! planes implemented as true mirrors: ghost-node contributions are folded onto
//! their mirror nodes (normal component reflected), and after the grid update
//! ghost nodes are refilled with the mirror image, so wide kernels near a wall
//! see a symmetric neighbourhood. Periodic axes fold and fill by wrapping.
//! Only active nodes (touched by some particle's stencil) are worked on.

use crate::particles::Vec2;
use std::ops::AddAssign;

/// Ghost layers on each side: enough for the cubic B-spline.
pub const PAD: usize = 2;

/// Where a padded node index sits on one axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeRole {
    Interior,
    /// On a symmetry wall: folds onto itself.
    Wall,
    /// Outside the box: folds onto (and is filled from) `partner`.
    Ghost {
        partner: usize,
        flip: bool,
    },
}

/// Values the wall fold knows how to mirror.
pub trait Mirrored: Copy + AddAssign {
    /// Reflection across a wall normal to `axis`.
    fn mirror(self, axis: usize) -> Self;
}

impl Mirrored for f64 {
    #[inline]
    fn mirror(self, _axis: usize) -> Self {
        self
    }
}

impl Mirrored for Vec2 {
    #[inline]
    fn mirror(mut self, axis: usize) -> Self {
        self[axis] = -self[axis];
        self
    }
}

#[derive(Clone, Debug)]
pub struct Grid {
    pub h: f64,
    /// Position of physical node (0, 0).
    pub origin: Vec2,
    pub cells: [usize; 2],
    /// Padded node count per axis.
    pub dims: [usize; 2],
    pub periodic: [bool; 2],
    /// P2G mass of the real particles only (before folding).
    pub mass_raw: Vec<f64>,
    /// Folded mass (mirror images included): what velocities are divided by.
    pub mass: Vec<f64>,
    pub momentum: Vec<Vec2>,
    pub force: Vec<Vec2>,
    /// Velocity after P2G (v^n).
    pub vel: Vec<Vec2>,
    /// Velocity after the grid update (v^{n+1}).
    pub vel_new: Vec<Vec2>,
    pub accel: Vec<Vec2>,
    /// Active node indices, ascending.
    pub active: Vec<u32>,
    active_flag: Vec<bool>,
    roles: [Vec<NodeRole>; 2],
}

impl Grid {
    pub fn new(origin: Vec2, h: f64, cells: [usize; 2], periodic: [bool; 2]) -> Self {
        let dims = [cells[0] + 1 + 2 * PAD, cells[1] + 1 + 2 * PAD];
        let roles = [0, 1].map(|a| {
            (0..dims[a])
                .map(|i| role(i as i64 - PAD as i64, cells[a] as i64, periodic[a]))
                .collect()
        });
        let n = dims[0] * dims[1];
        Grid {
            h,
            origin,
            cells,
            dims,
            periodic,
            mass_raw: vec![0.0; n],
            mass: vec![0.0; n],
            momentum: vec![Vec2::zeros(); n],
            force: vec![Vec2::zeros(); n],
            vel: vec![Vec2::zeros(); n],
            vel_new: vec![Vec2::zeros(); n],
            accel: vec![Vec2::zeros(); n],
            active: Vec::with_capacity(n),
            active_flag: vec![false; n],
            roles,
        }
    }

    pub fn node_count(&self) -> usize {
        self.dims[0] * self.dims[1]
    }

    #[inline]
    pub fn index(&self, i: usize, j: usize) -> usize {
        i + j * self.dims[0]
    }

    #[inline]
    pub fn coords(&self, node: usize) -> (usize, usize) {
        (node % self.dims[0], node / self.dims[0])
    }

    /// Position of a padded node.
    #[inline]
    pub fn position(&self, node: usize) -> Vec2 {
        let (i, j) = self.coords(node);
        self.origin
            + Vec2::new(
                (i as f64 - PAD as f64) * self.h,
                (j as f64 - PAD as f64) * self.h,
            )
    }

    pub fn role(&self, axis: usize, i: usize) -> NodeRole {
        self.roles[axis][i]
    }

    /// True when the node lies in the box (not a ghost on either axis).
    pub fn is_canonical(&self, node: usize) -> bool {
        let (i, j) = self.coords(node);
        !matches!(self.roles[0][i], NodeRole::Ghost { .. })
            && !matches!(self.roles[1][j], NodeRole::Ghost { .. })
    }

    /// Rebuilds the active set from the stencil origins of occupied bins.
    pub(crate) fn mark_active(&mut self, occupied_bins: impl Iterator<Item = usize>, width: usize) {
        for &n in &self.active {
            self.active_flag[n as usize] = false;
        }
        self.active.clear();
        for bin in occupied_bins {
            let (bi, bj) = self.coords(bin);
            for dj in 0..width {
                for di in 0..width {
                    let (i, j) = (bi + di, bj + dj);
                    let pi = self.partner_or_self(0, i);
                    let pj = self.partner_or_self(1, j);
                    for (a, b) in [(i, j), (pi, j), (i, pj), (pi, pj)] {
                        let n = self.index(a, b);
                        if !self.active_flag[n] {
                            self.active_flag[n] = true;
                            self.active.push(n as u32);
                        }
                    }
                }
            }
        }
        self.active.sort_unstable();
    }

    fn partner_or_self(&self, axis: usize, i: usize) -> usize {
        match self.roles[axis][i] {
            NodeRole::Ghost { partner, .. } => partner,
            _ => i,
        }
    }

    /// Adds every active ghost node's (mirrored) value onto its partner and
    /// self-mirrors wall nodes, x first, then y over in-box columns.
    pub fn fold<T: Mirrored>(&self, values: &mut [T]) {
        for axis in 0..2 {
            for &n in &self.active {
                let n = n as usize;
                let (i, j) = self.coords(n);
                if axis == 1 && matches!(self.roles[0][i], NodeRole::Ghost { .. }) {
                    continue;
                }
                let k = if axis == 0 { i } else { j };
                match self.roles[axis][k] {
                    NodeRole::Interior => {}
                    NodeRole::Wall => {
                        let v = values[n];
                        values[n] += v.mirror(axis);
                    }
                    NodeRole::Ghost { partner, flip } => {
                        let target = if axis == 0 {
                            self.index(partner, j)
                        } else {
                            self.index(i, partner)
                        };
                        let v = values[n];
                        values[target] += if flip { v.mirror(axis) } else { v };
                    }
                }
            }
        }
    }

    /// Sets every active ghost node to the (mirrored) value of its partner.
    pub fn fill<T: Mirrored>(&self, values: &mut [T]) {
        for axis in 0..2 {
            for &n in &self.active {
                let n = n as usize;
                let (i, j) = self.coords(n);
                if axis == 0 && matches!(self.roles[1][j], NodeRole::Ghost { .. }) {
                    continue;
                }
                let k = if axis == 0 { i } else { j };
                if let NodeRole::Ghost { partner, flip } = self.roles[axis][k] {
                    let source = if axis == 0 {
                        self.index(partner, j)
                    } else {
                        self.index(i, partner)
                    };
                    let v = values[source];
                    values[n] = if flip { v.mirror(axis) } else { v };
                }
            }
        }
    }
}

fn role(i: i64, n: i64, periodic: bool) -> NodeRole {
    if periodic {
        if (0..n).contains(&i) {
            NodeRole::Interior
        } else {
            NodeRole::Ghost {
                partner: (i.rem_euclid(n) + PAD as i64) as usize,
                flip: false,
            }
        }
    } else if i == 0 || i == n {
        NodeRole::Wall
    } else if i < 0 {
        NodeRole::Ghost {
            partner: (-i + PAD as i64) as usize,
            flip: true,
        }
    } else if i > n {
        NodeRole::Ghost {
            partner: (2 * n - i + PAD as i64) as usize,
            flip: true,
        }
    } else {
        NodeRole::Interior
    }
}
