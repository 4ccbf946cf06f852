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
    /// The image across a no-slip wall: every vector component reversed, so
    /// that the wall node's velocity folds to zero.
    fn point_mirror(self) -> Self;
}

impl Mirrored for f64 {
    #[inline]
    fn mirror(self, _axis: usize) -> Self {
        self
    }
    #[inline]
    fn point_mirror(self) -> Self {
        self
    }
}

impl Mirrored for Vec2 {
    #[inline]
    fn mirror(mut self, axis: usize) -> Self {
        self[axis] = -self[axis];
        self
    }
    #[inline]
    fn point_mirror(self) -> Self {
        -self
    }
}

/// A node counts as full of material when it holds at least this share of a
/// full node's mass rho0 h^2 (folded: mirror images included): near a free
/// surface the grid density says nothing about the particles' volume.
pub const FULL_NODE_SHARE: f64 = 0.75;

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
    /// Velocity p / m of the last projection: v^n after P2G; under MUSL,
    /// after G2P, the velocity re-projected from the updated particles.
    pub vel: Vec<Vec2>,
    /// Velocity after the grid update (v^{n+1}).
    pub vel_new: Vec<Vec2>,
    pub accel: Vec<Vec2>,
    /// Active node indices, ascending.
    pub active: Vec<u32>,
    /// The active nodes inside the box (not ghosts), ascending.
    pub inside: Vec<u32>,
    /// Active nodes as bits, `row_words` u64 per row of nodes.
    active_bits: Vec<u64>,
    row_words: usize,
    /// Two rows of bits for `mark_active` (bins, then their stencils).
    row_scratch: Vec<u64>,
    /// (ghost index, partner index) per axis.
    ghosts: [Vec<(usize, usize)>; 2],
    /// Wall/ghost operations per axis, x then y.
    fold_ops: [Vec<BoundaryOp>; 2],
    fill_ops: [Vec<BoundaryOp>; 2],
    roles: [Vec<NodeRole>; 2],
    /// No-slip walls, [axis][low side, high side].
    no_slip: [[bool; 2]; 2],
    /// Wall ghosts discarded and overwritten, not folded (`WallGhosts`).
    overwrite_ghosts: bool,
    /// Open sides, [axis][low side, high side]: no wall there; the nodes on
    /// and beyond the box edge are plain nodes and particles may leave.
    pub open: [[bool; 2]; 2],
    /// Scratch of `correct_weight_images`: the raw weights folded with the
    /// free-slip images and with the walls' own.
    weight_images: [Vec<Vec2>; 2],
}

impl Grid {
    pub fn new(origin: Vec2, h: f64, cells: [usize; 2], periodic: [bool; 2]) -> Self {
        let dims = [cells[0] + 1 + 2 * PAD, cells[1] + 1 + 2 * PAD];
        let open = [[false; 2]; 2];
        let (roles, ghosts) = roles_and_ghosts(dims, cells, periodic, open);
        let n = dims[0] * dims[1];
        let row_words = dims[0].div_ceil(64);
        Grid {
            ghosts,
            row_words,
            active_bits: vec![0; row_words * dims[1]],
            row_scratch: vec![0; 2 * row_words],
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
            fold_ops: [dims[1], dims[0]].map(|d| Vec::with_capacity(2 * (PAD + 1) * d)),
            fill_ops: [dims[1], dims[0]].map(|d| Vec::with_capacity(2 * (PAD + 1) * d)),
            roles,
            no_slip: [[false; 2]; 2],
            overwrite_ghosts: false,
            open,
            weight_images: [vec![Vec2::zeros(); n], vec![Vec2::zeros(); n]],
        }
    }

    /// Opens the sides marked [axis][low, high] (none on a periodic axis):
    /// their nodes fold and fill nothing, so the material there meets no
    /// mirror and may flow out of the box.
    pub fn set_open(&mut self, open: [[bool; 2]; 2]) {
        (self.roles, self.ghosts) = roles_and_ghosts(self.dims, self.cells, self.periodic, open);
        self.open = open;
    }

    /// Wall ghosts folded onto their partners, or (Uintah) discarded and
    /// overwritten with their partners' images; periodic ghosts always wrap.
    pub fn with_wall_ghosts(mut self, ghosts: crate::choices::WallGhosts) -> Self {
        self.overwrite_ghosts = ghosts == crate::choices::WallGhosts::Overwrite;
        self
    }

    /// Makes the walls marked [axis][low, high] no-slip (zero tangential
    /// velocity as well as normal): their images reverse every component.
    pub fn with_no_slip(mut self, no_slip: [[bool; 2]; 2]) -> Self {
        self.no_slip = no_slip;
        self
    }

    /// The wall a wall or ghost node at padded index `i` on `axis` belongs to is no-slip.
    fn no_slip_at(&self, axis: usize, i: usize) -> bool {
        self.no_slip[axis][usize::from(i > PAD)]
    }

    /// The node (padded index) is in this step's active set.
    #[inline]
    pub fn is_active(&self, node: usize) -> bool {
        self.is_active_at(node % self.dims[0], node / self.dims[0])
    }

    /// The node at padded coordinates (i, j) is in this step's active set.
    #[inline]
    pub fn is_active_at(&self, i: usize, j: usize) -> bool {
        self.active_bits[j * self.row_words + (i >> 6)] >> (i & 63) & 1 == 1
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

    /// The in-box node whose value padded node `node` holds (itself, or its
    /// partner across a periodic edge or a wall), and `v` as `node` holds
    /// it given the partner's value: mirrored across each wall `node` lies
    /// beyond (every component reversed for a no-slip wall), unchanged
    /// across a periodic edge. The image is its own inverse, so it also
    /// carries a value at `node` onto the partner.
    pub fn partner_image<T: Mirrored>(&self, node: usize, mut v: T) -> (usize, T) {
        let (mut i, mut j) = self.coords(node);
        for axis in 0..2 {
            let k = if axis == 0 { &mut i } else { &mut j };
            if let NodeRole::Ghost { partner, flip } = self.roles[axis][*k] {
                if flip {
                    v = if self.no_slip_at(axis, *k) {
                        v.point_mirror()
                    } else {
                        v.mirror(axis)
                    };
                }
                *k = partner;
            }
        }
        (self.index(i, j), v)
    }

    /// The node lies on a no-slip wall: its velocity is held at zero.
    /// The no-slip walls, [axis][low side, high side].
    pub fn no_slip_walls(&self) -> [[bool; 2]; 2] {
        self.no_slip
    }

    pub fn is_pinned(&self, node: usize) -> bool {
        let (i, j) = self.coords(node);
        [(0, i), (1, j)]
            .into_iter()
            .any(|(axis, k)| self.roles[axis][k] == NodeRole::Wall && self.no_slip_at(axis, k))
    }

    /// The share of a folded nodal value that is the node's own: 1/2 per
    /// wall the node lies on (folding adds its mirror image, the other
    /// half), 1 elsewhere. A node's kinetic energy in the box is
    /// 1/2 share m |v|^2 with m its folded mass.
    pub fn own_share(&self, node: usize) -> f64 {
        let (i, j) = self.coords(node);
        let half = |axis: usize, k: usize| {
            if self.roles[axis][k] == NodeRole::Wall {
                0.5
            } else {
                1.0
            }
        };
        half(0, i) * half(1, j)
    }

    /// `v` with its wall-normal components set to zero at `node`: the
    /// symmetry-plane condition that folding imposes on a wall node's
    /// momentum and force (periodic axes have no wall nodes).
    #[inline]
    pub fn project_walls(&self, node: usize, mut v: Vec2) -> Vec2 {
        let (i, j) = self.coords(node);
        for (axis, k) in [(0, i), (1, j)] {
            if self.roles[axis][k] == NodeRole::Wall {
                if self.no_slip_at(axis, k) {
                    return Vec2::zeros();
                }
                v[axis] = 0.0;
            }
        }
        v
    }

    /// Rebuilds the active set (ascending) from the occupied bins (a bin is
    /// the stencil origin node; `occupied(b)` says whether it holds particles)
    /// and the lists the grid stage walks: in-box active nodes and the
    /// wall/ghost operations of `fold` and `fill` in their fixed order.
    ///
    /// The set is built as one bit per node: each row of occupied bins is
    /// widened by the stencil in x with shifts, ORed into the `width` rows it
    /// covers, then mirrored onto the ghosts' partners (x, then y).
    pub(crate) fn mark_active(&mut self, occupied: impl Fn(usize) -> bool, width: usize) {
        self.set_active_bits(occupied, width);
        self.mirror_active_bits();
        self.list_active();
    }

    /// One bit per node reached by the stencil of an occupied bin.
    fn set_active_bits(&mut self, occupied: impl Fn(usize) -> bool, width: usize) {
        let [nx, ny] = self.dims;
        let words = self.row_words;
        self.active_bits.fill(0);
        let (bin_row, stencil_row) = self.row_scratch.split_at_mut(words);
        for bj in 0..ny.saturating_sub(width - 1) {
            let (row, bins) = (bj * nx, nx - (width - 1));
            for (k, word) in bin_row.iter_mut().enumerate() {
                // A local word: no store-to-load chain through memory per bin.
                let mut w = 0u64;
                for bi in k * 64..((k + 1) * 64).min(bins) {
                    w |= (occupied(row + bi) as u64) << (bi & 63);
                }
                *word = w;
            }
            if bin_row.iter().all(|&w| w == 0) {
                continue;
            }
            // Bin i covers nodes i..i + width: OR of the row shifted by 0..width.
            stencil_row.copy_from_slice(bin_row);
            for shift in 1..width {
                for k in 0..words {
                    let carry = if k > 0 {
                        bin_row[k - 1] >> (64 - shift)
                    } else {
                        0
                    };
                    stencil_row[k] |= (bin_row[k] << shift) | carry;
                }
            }
            for j in bj..bj + width {
                let dst = &mut self.active_bits[j * words..(j + 1) * words];
                for (d, s) in dst.iter_mut().zip(stencil_row.iter()) {
                    *d |= s;
                }
            }
        }
    }

    /// The ghosts' partners of the active bits, so that fold and fill see both.
    fn mirror_active_bits(&mut self) {
        let [_, ny] = self.dims;
        let words = self.row_words;
        // Mirror partners: ghost columns first, then whole ghost rows (which
        // carries the corner partners along). Partners are never ghosts.
        for j in 0..ny {
            let row = &mut self.active_bits[j * words..(j + 1) * words];
            for &(i, partner) in &self.ghosts[0] {
                if row[i >> 6] >> (i & 63) & 1 == 1 {
                    row[partner >> 6] |= 1 << (partner & 63);
                }
            }
        }
        for &(j, partner) in &self.ghosts[1] {
            for k in 0..words {
                self.active_bits[partner * words + k] |= self.active_bits[j * words + k];
            }
        }
    }

    /// The active and in-box lists, and the fold and fill operations in
    /// their fixed order, from the bits.
    fn list_active(&mut self) {
        let [nx, ny] = self.dims;
        let words = self.row_words;
        self.active.clear();
        self.inside.clear();
        for ops in [&mut self.fold_ops, &mut self.fill_ops] {
            ops.iter_mut().for_each(Vec::clear);
        }
        let ghost = |r: NodeRole| matches!(r, NodeRole::Ghost { .. });
        for j in 0..ny {
            let role_y = self.roles[1][j];
            for k in 0..words {
                let mut bits = self.active_bits[j * words + k];
                while bits != 0 {
                    let i = k * 64 + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    let n = i + j * nx;
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
                        let point = self.no_slip_at(axis, if axis == 0 { i } else { j });
                        let op = |other, flip| BoundaryOp {
                            node: n as u32,
                            other,
                            axis: axis as u8,
                            flip,
                            point,
                        };
                        // Fold in y only over in-box columns (x ghosts are folded first).
                        if !(axis == 1 && ghost(role_x)) {
                            match role {
                                NodeRole::Interior => {}
                                NodeRole::Wall => self.fold_ops[axis].push(op(n as u32, true)),
                                NodeRole::Ghost { partner, flip } => {
                                    // Periodic ghosts always wrap.
                                    if !self.overwrite_ghosts || self.periodic[axis] {
                                        self.fold_ops[axis].push(op(other(partner), flip))
                                    }
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
    }

    /// Adds every active ghost node's (mirrored) value onto its partner and
    /// self-mirrors wall nodes, x first, then y over in-box columns.
    pub fn fold<T: Mirrored>(&self, values: &mut [T]) {
        self.fold_by(values, BoundaryOp::image);
    }

    /// `fold` with the images `image` gives each operation's value.
    fn fold_by<T: Mirrored>(&self, values: &mut [T], image: impl Fn(&BoundaryOp, T) -> T) {
        for op in self.fold_ops.iter().flatten() {
            let v = image(op, values[op.node as usize]);
            values[op.other as usize] += v;
        }
    }

    /// Corrects a folded `force` for gravity at no-slip walls. The fold's
    /// no-slip image reverses every component (so that the wall node's
    /// velocity folds to zero), but the image material's weight points the
    /// way the real material's does: only its wall-normal component
    /// reverses, as at a free-slip wall. Without this the weight the
    /// stencils put beyond a no-slip side wall was subtracted from its
    /// partner node's, and a resting column by such a wall could not rest.
    /// Adds fold_free_slip(m g) - fold(m g) (m the raw P2G mass) to the
    /// in-box nodes not held by a no-slip wall, where it is not zero: no
    /// change without a no-slip wall, nor under a no-slip floor with
    /// vertical gravity.
    pub fn correct_weight_images(&mut self, force: &mut [Vec2], gravity: Vec2) {
        if gravity == Vec2::zeros() || !self.no_slip.iter().flatten().any(|&b| b) {
            return;
        }
        let [mut free, mut walls] = std::mem::take(&mut self.weight_images);
        for &n in &self.active {
            let n = n as usize;
            free[n] = gravity * self.mass_raw[n];
            walls[n] = free[n];
        }
        self.fold_by(&mut free, |op, v| {
            if op.flip {
                v.mirror(op.axis as usize)
            } else {
                v
            }
        });
        self.fold(&mut walls);
        for &n in &self.inside {
            let n = n as usize;
            let correction = free[n] - walls[n];
            if correction != Vec2::zeros() && !self.is_pinned(n) {
                force[n] += correction;
            }
        }
        self.weight_images = [free, walls];
    }

    /// Sets every active ghost node to the (mirrored) value of its partner.
    pub fn fill<T: Mirrored>(&self, values: &mut [T]) {
        for op in self.fill_ops.iter().flatten() {
            values[op.node as usize] = op.image(values[op.other as usize]);
        }
    }

    /// `fill` of the updated velocities (and of the accelerations with them).
    pub fn fill_vel_new(&mut self, with_accel: bool) {
        let mut vel = std::mem::take(&mut self.vel_new);
        self.fill(&mut vel);
        self.vel_new = vel;
        if with_accel {
            let mut accel = std::mem::take(&mut self.accel);
            self.fill(&mut accel);
            self.accel = accel;
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
    /// A no-slip wall's image (every component reversed).
    point: bool,
}

impl BoundaryOp {
    #[inline]
    fn image<T: Mirrored>(&self, v: T) -> T {
        match (self.flip, self.point) {
            (false, _) => v,
            (true, false) => v.mirror(self.axis as usize),
            (true, true) => v.point_mirror(),
        }
    }
}

type Roles = ([Vec<NodeRole>; 2], [Vec<(usize, usize)>; 2]);

/// Each padded index's role per axis, and the (ghost, partner) pairs.
fn roles_and_ghosts(
    dims: [usize; 2],
    cells: [usize; 2],
    periodic: [bool; 2],
    open: [[bool; 2]; 2],
) -> Roles {
    let roles: [Vec<NodeRole>; 2] = [0, 1].map(|a| {
        (0..dims[a])
            .map(|i| {
                let i = i as i64 - PAD as i64;
                let n = cells[a] as i64;
                let side_open = !periodic[a] && ((i <= 0 && open[a][0]) || (i >= n && open[a][1]));
                if side_open {
                    NodeRole::Interior
                } else {
                    role(i, n, periodic[a])
                }
            })
            .collect()
    });
    let ghosts = [0, 1].map(|a: usize| {
        (0..dims[a])
            .filter_map(|i| match roles[a][i] {
                NodeRole::Ghost { partner, .. } => Some((i, partner)),
                _ => None,
            })
            .collect()
    });
    (roles, ghosts)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The active set node by node: every stencil node of an occupied bin and
    /// its mirror partners in x, y and both.
    fn reference_active(grid: &Grid, occupied: &[bool], width: usize) -> Vec<u32> {
        let [nx, ny] = grid.dims;
        let partner = |axis: usize, i: usize| match grid.roles[axis][i] {
            NodeRole::Ghost { partner, .. } => partner,
            _ => i,
        };
        let mut flag = vec![false; nx * ny];
        for bj in 0..ny - (width - 1) {
            for bi in 0..nx - (width - 1) {
                if !occupied[bi + bj * nx] {
                    continue;
                }
                for j in bj..bj + width {
                    for i in bi..bi + width {
                        let (pi, pj) = (partner(0, i), partner(1, j));
                        for (a, b) in [(i, j), (pi, j), (i, pj), (pi, pj)] {
                            flag[a + b * nx] = true;
                        }
                    }
                }
            }
        }
        (0..nx * ny)
            .filter(|&n| flag[n])
            .map(|n| n as u32)
            .collect()
    }

    #[test]
    fn active_set_matches_the_node_by_node_marking() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut coin = |p_percent: u64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed % 100 < p_percent
        };
        // Widths of every shape, one and two words per row, walls and periodic axes.
        for cells in [[6, 5], [70, 9], [130, 66]] {
            for periodic in [[false, false], [true, false], [false, true], [true, true]] {
                for width in 2..=4 {
                    for density in [0, 1, 10, 60] {
                        let mut grid = Grid::new(Vec2::zeros(), 0.1, cells, periodic);
                        let [nx, ny] = grid.dims;
                        let occupied: Vec<bool> = (0..nx * ny)
                            .map(|n| {
                                let (i, j) = (n % nx, n / nx);
                                i + width <= nx && j + width <= ny && coin(density)
                            })
                            .collect();
                        grid.mark_active(|b| occupied[b], width);
                        let expected = reference_active(&grid, &occupied, width);
                        assert_eq!(grid.active, expected, "{cells:?} {periodic:?} w{width}");
                        let inside: Vec<u32> = expected
                            .iter()
                            .copied()
                            .filter(|&n| {
                                let (i, j) = grid.coords(n as usize);
                                !matches!(grid.roles[0][i], NodeRole::Ghost { .. })
                                    && !matches!(grid.roles[1][j], NodeRole::Ghost { .. })
                            })
                            .collect();
                        assert_eq!(grid.inside, inside);
                    }
                }
            }
        }
    }

    /// An open side has no wall and no ghosts: its nodes are plain nodes,
    /// nothing is projected there, while the other walls keep their mirrors.
    #[test]
    fn an_open_side_is_neither_wall_nor_ghost() {
        let (cells, top) = ([4, 3], PAD + 3);
        let mut grid = Grid::new(Vec2::zeros(), 0.1, cells, [false; 2]);
        grid.set_open([[false; 2], [false, true]]);
        for j in top..grid.dims[1] {
            assert_eq!(grid.roles[1][j], NodeRole::Interior, "row {j}");
        }
        assert_eq!(grid.roles[1][PAD], NodeRole::Wall);
        assert_eq!(grid.ghosts[1].len(), PAD, "the floor's ghosts only");
        assert_eq!(grid.ghosts[0].len(), 2 * PAD);
        let v = Vec2::new(1.0, 2.0);
        assert_eq!(grid.project_walls(grid.index(PAD + 1, top), v), v);
        assert_eq!(
            grid.project_walls(grid.index(PAD + 1, PAD), v),
            Vec2::new(1.0, 0.0)
        );
        let closed = Grid::new(Vec2::zeros(), 0.1, cells, [false; 2]);
        assert_eq!(closed.roles[1][top], NodeRole::Wall);
        assert_eq!(closed.ghosts[1].len(), 2 * PAD);
    }

    /// Under gravity, a no-slip wall's images carry the weight as a
    /// free-slip wall's do (only its normal component reversed): the
    /// folded and corrected force equals the free-slip fold's at every
    /// node the wall does not hold, for every choice of no-slip walls;
    /// the fold alone is off by the reversed weight by a no-slip side wall.
    #[test]
    fn no_slip_images_carry_the_weight_as_free_slip_ones() {
        let cells = [5, 4];
        let gravity = Vec2::new(0.0, -9.81);
        let weight = |no_slip: [[bool; 2]; 2], correct: bool| {
            let mut grid = Grid::new(Vec2::zeros(), 0.1, cells, [false; 2]).with_no_slip(no_slip);
            grid.mark_active(|_| true, 3);
            let mut force = vec![Vec2::zeros(); grid.dims[0] * grid.dims[1]];
            for &n in &grid.active {
                // Uneven raw masses, as stencils leave them.
                let n = n as usize;
                grid.mass_raw[n] = 1.0 + 0.1 * (n % 7) as f64;
                force[n] = gravity * grid.mass_raw[n];
            }
            grid.fold(&mut force);
            if correct {
                grid.correct_weight_images(&mut force, gravity);
            }
            (grid, force)
        };
        let (free_grid, free) = weight([[false; 2]; 2], true);
        let side_wall_node = free_grid.index(PAD + 1, PAD + 2);
        for no_slip in [
            [[true, true], [false, false]],
            [[false, false], [true, false]],
            [[true, false], [true, true]],
            [[true, true], [true, true]],
        ] {
            let (grid, force) = weight(no_slip, true);
            for &n in &grid.inside {
                let n = n as usize;
                if grid.is_pinned(n) {
                    continue;
                }
                let d = (force[n] - free[n]).norm();
                assert!(
                    d <= 1e-12 * free[n].norm(),
                    "{no_slip:?}: node {n}: {:?} against {:?}",
                    force[n],
                    free[n]
                );
            }
            if no_slip[0][0] {
                let (_, uncorrected) = weight(no_slip, false);
                // Off by the image's reversed weight, 2 g m of the ghosts by the wall.
                let off = (free[side_wall_node] - uncorrected[side_wall_node]).norm();
                assert!(off > 1.0, "{no_slip:?}: the fold alone off by {off} N");
            }
        }
    }
}
