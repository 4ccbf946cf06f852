//! One velocity component's faces on the staggered grid: the x component
//! on the faces normal to x (node lines in x, cell centres in y), the y
//! component on those normal to y. Padded by `PAD` faces on every side;
//! the walls are mirrors, as on the nodal grid: a ghost face's value
//! folds onto its partner inside the box and is filled back from it.

use crate::grid::Grid;

/// Ghost faces on each side: a quadratic B-spline reaches 1.5 cells.
pub const PAD: usize = 2;

#[derive(Clone, Debug, Default)]
pub struct FaceField {
    /// The component these faces carry (0: x, 1: y).
    pub axis: usize,
    /// Faces per axis inside the box: the normal axis holds one more
    /// than its cells (both walls), the other as many as its cells.
    pub inside: [usize; 2],
    /// Padded faces per axis.
    pub dims: [usize; 2],
    /// Face (0, 0)'s offset from node (0, 0), in cells.
    pub offset: [f64; 2],
    /// Per axis, low and high wall: whether the tangential component's
    /// image reverses (no slip) there.
    pub no_slip: [[bool; 2]; 2],
    /// P2G mass of the real particles (ghosts included) and folded.
    pub mass_raw: Vec<f64>,
    pub mass: Vec<f64>,
    /// The solve's mass: the folded mass with the air faces' shares.
    pub operator_mass: Vec<f64>,
    pub momentum: Vec<f64>,
    pub force: Vec<f64>,
    /// The P2G velocity u^n, then u* after gravity and the viscous force,
    /// then u^{n+1} after the pressure.
    pub vel: Vec<f64>,
    pub vel_new: Vec<f64>,
    /// u* kept for the projection's booking.
    pub vel_star: Vec<f64>,
    /// The packing correction's displacement.
    pub shift: Vec<f64>,
    /// Per face: whether this step's solve sets it (it borders a fluid
    /// cell and is not a wall's), filled by `solve::mark_solved`.
    pub solved: Vec<bool>,
    /// Per face: the share theta of the way from its fluid cell's centre
    /// to its air cell's at which a ghost surface puts p = 0 (1 off the
    /// surface), filled by `solve::fill_shares`.
    pub share: Vec<f64>,
}

impl FaceField {
    pub fn new(grid: &Grid, axis: usize, no_slip: [[bool; 2]; 2]) -> Self {
        let mut inside = grid.cells;
        inside[axis] += 1;
        let dims = inside.map(|n| n + 2 * PAD);
        let mut offset = [0.5, 0.5];
        offset[axis] = 0.0;
        let n = dims[0] * dims[1];
        FaceField {
            axis,
            inside,
            dims,
            offset,
            no_slip,
            mass_raw: vec![0.0; n],
            mass: vec![0.0; n],
            operator_mass: vec![0.0; n],
            momentum: vec![0.0; n],
            force: vec![0.0; n],
            vel: vec![0.0; n],
            vel_new: vec![0.0; n],
            vel_star: vec![0.0; n],
            shift: vec![0.0; n],
            solved: vec![false; n],
            share: vec![1.0; n],
        }
    }

    /// The padded index of face (i, j) (in-box faces from 0).
    #[inline]
    pub fn index(&self, i: i64, j: i64) -> usize {
        (i + PAD as i64) as usize + (j + PAD as i64) as usize * self.dims[0]
    }

    /// Face (i, j) of padded index `f`.
    #[inline]
    pub fn coords(&self, f: usize) -> (i64, i64) {
        (
            (f % self.dims[0]) as i64 - PAD as i64,
            (f / self.dims[0]) as i64 - PAD as i64,
        )
    }

    /// Whether face `k` on axis `a` lies inside the padded range.
    #[inline]
    pub fn holds(&self, k: i64, a: usize) -> bool {
        k >= -(PAD as i64) && k < (self.inside[a] + PAD) as i64
    }

    /// Whether face (i, j) is held by a wall: the faces of the normal
    /// component on the box's edges.
    #[inline]
    pub fn on_wall(&self, i: i64, j: i64) -> bool {
        let k = if self.axis == 0 { i } else { j };
        k == 0 || k == self.inside[self.axis] as i64 - 1
    }

    /// Whether face (i, j) is inside the box (walls included).
    #[inline]
    pub fn in_box(&self, i: i64, j: i64) -> bool {
        (0..self.inside[0] as i64).contains(&i) && (0..self.inside[1] as i64).contains(&j)
    }

    pub fn clear(&mut self) {
        for v in [
            &mut self.mass_raw,
            &mut self.mass,
            &mut self.momentum,
            &mut self.force,
        ] {
            v.fill(0.0);
        }
    }

    /// The in-box partner of ghost index `k` on axis `a`, and the sign its
    /// value takes there (None: `k` is inside the box).
    fn partner(&self, k: i64, a: usize) -> Option<(i64, f64)> {
        let n = self.inside[a] as i64;
        let side = if k < 0 {
            0
        } else if k >= n {
            1
        } else {
            return None;
        };
        let normal = a == self.axis;
        // Normal faces sit on node lines (0 and n - 1 on the walls); the
        // others at cell centres, half a cell in from the walls.
        let partner = match (normal, side) {
            (true, 0) => -k,
            (true, _) => 2 * (n - 1) - k,
            (false, 0) => -1 - k,
            (false, _) => 2 * n - 1 - k,
        };
        let sign = if normal || self.no_slip[a][side] {
            -1.0
        } else {
            1.0
        };
        Some((partner, sign))
    }

    /// Adds each ghost face's value onto its partner (x first over every
    /// row, then y over the in-box columns) with its sign (`signed`: the
    /// mirror's, else +1 as for mass).
    pub fn fold(&self, values: &mut [f64], signed: bool) {
        let [nx, ny] = self.dims.map(|d| d as i64 - PAD as i64);
        for j in -(PAD as i64)..ny {
            for i in -(PAD as i64)..nx {
                if let Some((p, sign)) = self.partner(i, 0) {
                    let v = values[self.index(i, j)];
                    values[self.index(p, j)] += if signed { sign * v } else { v };
                }
            }
        }
        for j in -(PAD as i64)..ny {
            for i in 0..self.inside[0] as i64 {
                if let Some((p, sign)) = self.partner(j, 1) {
                    let v = values[self.index(i, j)];
                    values[self.index(i, p)] += if signed { sign * v } else { v };
                }
            }
        }
    }

    /// Sets each ghost face to its partner's value with the mirror's sign
    /// (y over the in-box columns first, then x over every row).
    pub fn fill(&self, values: &mut [f64]) {
        let [nx, ny] = self.dims.map(|d| d as i64 - PAD as i64);
        for j in -(PAD as i64)..ny {
            for i in 0..self.inside[0] as i64 {
                if let Some((p, sign)) = self.partner(j, 1) {
                    values[self.index(i, j)] = sign * values[self.index(i, p)];
                }
            }
        }
        for j in -(PAD as i64)..ny {
            for i in -(PAD as i64)..nx {
                if let Some((p, sign)) = self.partner(i, 0) {
                    values[self.index(i, j)] = sign * values[self.index(p, j)];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Walls are mirrors: a ghost face's value folds onto its partner with
    /// the normal component reversed (and the tangential one at a no-slip
    /// wall), and filling copies it back with the same sign.
    #[test]
    fn ghost_faces_fold_onto_and_fill_from_their_mirror_partners() {
        let grid = Grid::new(crate::particles::Vec2::zeros(), 0.1, [4, 3], [false, false]);
        let no_slip = [[false, false], [true, false]];
        let x = FaceField::new(&grid, 0, no_slip);
        // x faces: x on node lines 0..=4 (4 a wall), y at cell centres 0..3.
        for (ghost, partner, sign) in [
            ((-1, 1), (1, 1), -1.0), // beyond the left wall: normal
            ((5, 2), (3, 2), -1.0),  // beyond the right wall: normal
            ((2, -1), (2, 0), -1.0), // below a no-slip floor: tangential
            ((2, 3), (2, 2), 1.0),   // above a free-slip top: tangential
            ((2, -2), (2, 1), -1.0),
        ] {
            let mut v = vec![0.0; x.vel.len()];
            v[x.index(ghost.0, ghost.1)] = 2.0;
            v[x.index(partner.0, partner.1)] = 1.0;
            let mut masses = v.clone();
            x.fold(&mut v, true);
            x.fold(&mut masses, false);
            assert_eq!(
                v[x.index(partner.0, partner.1)],
                1.0 + 2.0 * sign,
                "{ghost:?}"
            );
            assert_eq!(masses[x.index(partner.0, partner.1)], 3.0, "{ghost:?}");
            x.fill(&mut v);
            let filled = v[x.index(ghost.0, ghost.1)];
            assert_eq!(filled, sign * (1.0 + 2.0 * sign), "{ghost:?}");
        }
        assert!(x.on_wall(0, 1) && x.on_wall(4, 1) && !x.on_wall(2, 1));
    }
}
