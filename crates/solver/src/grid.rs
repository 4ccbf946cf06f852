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
    /// The active nodes inside the box (not ghosts), ascending.
    pub inside: Vec<u32>,
    active_flag: Vec<bool>,
    /// First and last interior node index per axis (no ghost, no wall).
    interior: [(usize, usize); 2],
    /// Wall/ghost operations per axis, x then y.
    fold_ops: [Vec<BoundaryOp>; 2],
    fill_ops: [Vec<BoundaryOp>; 2],
    roles: [Vec<NodeRole>; 2],
}

impl Grid {
    pub fn new(origin: Vec2, h: f64, cells: [usize; 2], periodic: [bool; 2]) -> Self {
        let dims = [cells[0] + 1 + 2 * PAD, cells[1] + 1 + 2 * PAD];
        let roles: [Vec<NodeRole>; 2] = [0, 1].map(|a| {
            (0..dims[a])
                .map(|i| role(i as i64 - PAD as i64, cells[a] as i64, periodic[a]))
                .collect()
        });
        let n = dims[0] * dims[1];
        let interior = [0, 1].map(|a: usize| {
            let inner = |i: &usize| roles[a][*i] == NodeRole::Interior;
            let first = (0..dims[a]).find(inner).unwrap_or(dims[a]);
            let last = (0..dims[a]).rev().find(inner).unwrap_or(0);
            (first, last)
        });
        Grid {
            interior,
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
            inside: Vec::with_capacity(n),
            active_flag: vec![false; n],
            fold_ops: [dims[1], dims[0]].map(|d| Vec::with_capacity(2 * (PAD + 1) * d)),
            fill_ops: [dims[1], dims[0]].map(|d| Vec::with_capacity(2 * (PAD + 1) * d)),
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

    /// Rebuilds the active set (ascending) from the occupied bins (a bin is
    /// the stencil origin node; `occupied(b)` says whether it holds particles)
    /// and the lists the grid stage walks: in-box active nodes and the
    /// wall/ghost operations of `fold` and `fill` in their fixed order.
    pub(crate) fn mark_active(&mut self, occupied: impl Fn(usize) -> bool, width: usize) {
        for &n in &self.active {
            self.active_flag[n as usize] = false;
        }
        self.active.clear();
        let [nx, ny] = self.dims;
        let (mut lo, mut hi) = ([usize::MAX; 2], [0usize; 2]);
        for bj in 0..ny.saturating_sub(width - 1) {
            for bi in 0..nx.saturating_sub(width - 1) {
                if !occupied(bi + bj * nx) {
                    continue;
                }
                lo = [lo[0].min(bi), lo[1].min(bj)];
                hi = [hi[0].max(bi + width - 1), hi[1].max(bj + width - 1)];
                let interior = |axis: usize, b: usize| {
                    let (first, last) = self.interior[axis];
                    b >= first && b + width - 1 <= last
                };
                if interior(0, bi) && interior(1, bj) {
                    // No ghost in the stencil: no mirror partners to mark.
                    for j in bj..bj + width {
                        self.active_flag[bi + j * nx..bi + width + j * nx].fill(true);
                    }
                    continue;
                }
                for j in bj..bj + width {
                    let pj = self.partner_or_self(1, j);
                    for i in bi..bi + width {
                        let pi = self.partner_or_self(0, i);
                        for (a, b) in [(i, j), (pi, j), (i, pj), (pi, pj)] {
                            self.active_flag[a + b * nx] = true;
                            lo = [lo[0].min(a), lo[1].min(b)];
                            hi = [hi[0].max(a), hi[1].max(b)];
                        }
                    }
                }
            }
        }
        self.inside.clear();
        for ops in [&mut self.fold_ops, &mut self.fill_ops] {
            ops.iter_mut().for_each(Vec::clear);
        }
        if lo[0] > hi[0] {
            return;
        }
        let ghost = |r: NodeRole| matches!(r, NodeRole::Ghost { .. });
        for j in lo[1]..=hi[1] {
            let role_y = self.roles[1][j];
            for i in lo[0]..=hi[0] {
                let n = i + j * nx;
                if !self.active_flag[n] {
                    continue;
                }
                self.active.push(n as u32);
                let role_x = self.roles[0][i];
                if !ghost(role_x) && !ghost(role_y) {
                    self.inside.push(n as u32);
                }
                for (axis, role) in [(0, role_x), (1, role_y)] {
                    let other = |partner: usize| {
                        (if axis == 0 {
                            partner + j * nx
                        } else {
                            i + partner * nx
                        }) as u32
                    };
                    let op = |other, flip| BoundaryOp {
                        node: n as u32,
                        other,
                        axis: axis as u8,
                        flip,
                    };
                    // Fold in y only over in-box columns (x ghosts are folded first).
                    if !(axis == 1 && ghost(role_x)) {
                        match role {
                            NodeRole::Interior => {}
                            NodeRole::Wall => self.fold_ops[axis].push(op(n as u32, true)),
                            NodeRole::Ghost { partner, flip } => {
                                self.fold_ops[axis].push(op(other(partner), flip))
                            }
                        }
                    }
                    // Fill in x only over in-box rows (y ghosts are filled after).
                    if !(axis == 0 && ghost(role_y)) {
                        if let NodeRole::Ghost { partner, flip } = role {
                            self.fill_ops[axis].push(op(other(partner), flip));
                        }
                    }
                }
            }
        }
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
        for op in self.fold_ops.iter().flatten() {
            let v = values[op.node as usize];
            let v = if op.flip {
                v.mirror(op.axis as usize)
            } else {
                v
            };
            values[op.other as usize] += v;
        }
    }

    /// Sets every active ghost node to the (mirrored) value of its partner.
    pub fn fill<T: Mirrored>(&self, values: &mut [T]) {
        for op in self.fill_ops.iter().flatten() {
            let v = values[op.other as usize];
            values[op.node as usize] = if op.flip {
                v.mirror(op.axis as usize)
            } else {
                v
            };
        }
    }
}

/// One wall or ghost operation: fold adds `node` (mirrored if `flip`) onto
/// `other`; fill copies `other` (mirrored if `flip`) into `node`. A wall node
/// folds onto itself with `flip`.
#[derive(Clone, Copy, Debug)]
struct BoundaryOp {
    node: u32,
    other: u32,
    axis: u8,
    flip: bool,
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
