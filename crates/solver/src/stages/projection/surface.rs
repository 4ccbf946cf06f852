//! The fluid's extent on the grid: which cells are fluid (and where the
//! free surface sits between them and the air), the air nodes slaved to
//! their fluid neighbours, the velocity extrapolated into the air band,
//! and the pressure gradient the particles read.

use super::{owner, surface_depth, Scratch, AIR, CACHED_REACH, CORNERS};
use crate::config::{FreeSurface, Holes};
use crate::grid::{Grid, PAD};
use crate::particles::{Particles, Vec2};

/// The gradient of the cell pressure at each fluid cell, by central
/// differences where both neighbours are fluid, one-sided at a wall (no
/// neighbour), and against -p of the cell itself at an air neighbour (p = 0
/// on the face between; under the ghost surfaces against the ghost
/// pressure p (theta - 1) / theta, p = 0 where the surface is): each
/// particle reads p_c + grad . (x - x_c), exact for a linear field, so a
/// resting layer's particles read the hydrostatic pressure where they
/// stand and not their cell centre's (a sampling error of rho0 g h / 4).
pub(super) fn reconstruct(s: &mut Scratch, h: f64, ghost: bool) {
    for k in 0..s.fluid.len() {
        let c = s.fluid[k] as usize;
        let p0 = s.x[k];
        let row = s.neighbours[k];
        let side = |slot: usize, di: i64, dj: i64| -> Option<f64> {
            let m = row[slot];
            if m != AIR {
                return Some(s.x[m as usize]);
            }
            let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
            s.cell_at(ci + di, cj + dj).map(|o| {
                if ghost {
                    let theta = s.surface_share(c, o);
                    p0 * (theta - 1.0) / theta
                } else {
                    -p0
                }
            })
        };
        let slope = |minus: Option<f64>, plus: Option<f64>| match (minus, plus) {
            (Some(a), Some(b)) => (b - a) / (2.0 * h),
            (None, Some(b)) => (b - p0) / h,
            (Some(a), None) => (p0 - a) / h,
            (None, None) => 0.0,
        };
        // Slots: (dx + 1) + 3 (dy + 1).
        s.gradient[c] = Vec2::new(
            slope(side(3, -1, 0), side(5, 1, 0)),
            slope(side(1, 0, -1), side(7, 0, 1)),
        );
    }
}

/// Whether in-box node `n` is an air node: in no fluid cell, so that it
/// takes its fluid neighbours' velocity after the solve (`extrapolate`).
/// A corner of a cell that holds material but is counted as air (the
/// ghost surface's thin surface cells and spray; under the cell surface
/// every such cell is fluid) carries its own momentum and keeps u*, in
/// free flight: overwriting it with its neighbours' velocity drove the
/// ghost surface's injections.
fn is_air_node(grid: &Grid, s: &Scratch, n: usize, light: f64) -> bool {
    let free_flight = grid.mass[n] >= light && s.holds_material_around(grid, n);
    !s.fluid_node[n] && !free_flight
}

/// The fluid nodes an air node's velocity is the mean of: among the eight
/// padded nodes around in-box node `n`, each whose in-box node is a fluid
/// node, as (padded node, in-box node). Under `mirrored` a node beyond a
/// wall counts as its mirror partner (the wall's symmetry, as the fold
/// has it); else only across a periodic edge.
fn masters(grid: &Grid, s: &Scratch, n: usize, mirrored: bool) -> ([(usize, usize); 8], usize) {
    let nx = grid.dims[0] as i64;
    let (mut found, mut count) = ([(0, 0); 8], 0);
    for dj in -1..=1i64 {
        for di in -1..=1i64 {
            if (di, dj) == (0, 0) {
                continue;
            }
            let m = (n as i64 + di + dj * nx) as usize;
            let o = if mirrored {
                grid.partner_image(m, 0.0).0
            } else {
                owner(grid, m)
            };
            if s.fluid_node[o] {
                found[count] = (m, o);
                count += 1;
            }
        }
    }
    (found, count)
}

/// The air nodes' velocity is a constraint, v = the mean of their fluid
/// neighbours' (`extrapolate`); as for any node slaved to others, each of
/// those neighbours takes an equal share of its mass and of its u*
/// momentum (gravity's impulse included) before the solve, lumped. Without
/// it the weight of the material the B-spline carries above the top fluid
/// cells is lost when their velocity is overwritten, and a wave's
/// restoring force is short by the share of the mass it lifts that lands
/// there. The shares are taken in the box's own masses (a wall node owns
/// half its folded mass) and a neighbour beyond a wall is its partner's
/// image, so that a flat layer gives every surface node the same share.
/// A node on a no-slip wall is held at rest by the wall, not by its
/// neighbours: the wall takes its momentum. (The share is one mass for
/// both directions: a slave on a free-slip wall also hands its neighbours
/// the wall-normal inertia the wall holds.)
pub(super) fn slave_air_nodes(grid: &mut Grid, s: &mut Scratch, light: f64) {
    for &n in &grid.active {
        s.slaved_mass[n as usize] = 0.0;
        s.slaved_momentum[n as usize] = Vec2::zeros();
    }
    for &n in &grid.inside {
        let n = n as usize;
        if !is_air_node(grid, s, n, light) || grid.is_pinned(n) {
            continue;
        }
        let (found, count) = masters(grid, s, n, true);
        if count == 0 {
            continue;
        }
        let mass = grid.own_share(n) * grid.mass[n] / count as f64;
        let momentum = mass * grid.vel_new[n];
        for &(m, o) in &found[..count] {
            s.slaved_mass[o] += mass;
            s.slaved_momentum[o] += grid.partner_image(m, momentum).1;
        }
    }
    for &n in &grid.inside {
        let n = n as usize;
        if s.slaved_mass[n] == 0.0 {
            continue;
        }
        // Back to folded values.
        let share = grid.own_share(n);
        let mass = grid.mass[n] + s.slaved_mass[n] / share;
        let v = (grid.mass[n] * grid.vel_new[n] + s.slaved_momentum[n] / share) / mass;
        s.operator_mass[n] = mass;
        grid.vel_new[n] = grid.project_walls(n, v);
    }
    grid.fill_vel_new(false);
    grid.fill(&mut s.operator_mass);
}

/// The nodes a particle reaches beyond its cell's corners (B-splines) are
/// in no fluid cell: no pressure holds them, and left alone they would fall
/// freely and drag the surface particles with them. Each takes the mean
/// velocity of its fluid neighbours (`masters`), as fluid codes
/// extrapolate the velocity into the air band (`is_air_node` says which).
pub(super) fn extrapolate(grid: &mut Grid, s: &Scratch, dt: f64, light: f64, mirrored: bool) {
    let mut changed = false;
    for &n in &grid.inside {
        let n = n as usize;
        if !is_air_node(grid, s, n, light) {
            continue;
        }
        let (found, count) = masters(grid, s, n, mirrored);
        let mut sum = Vec2::zeros();
        for &(m, o) in &found[..count] {
            sum += if mirrored {
                grid.partner_image(m, grid.vel_new[o]).1
            } else {
                grid.vel_new[m]
            };
        }
        if count > 0 {
            let v = grid.project_walls(n, sum / count as f64);
            grid.accel[n] = (v - grid.vel[n]) / dt;
            grid.vel_new[n] = v;
            changed = true;
        }
    }
    if changed {
        grid.fill_vel_new(true);
    }
}

/// Fluid cells (those holding a particle; with `holes` other than air an
/// empty cell each of whose sides is a wall or holds one, and with
/// `"kept"` an emptied one still half full; under the ghost surface also
/// at least half full, or with `spray_fluid` spray: `is_spray`), each
/// particle's cell, the cells' volumes, the unknowns' corners and their
/// neighbours, and how deep each cell lies.
pub(super) fn mark_fluid(
    ps: &Particles,
    grid: &Grid,
    s: &mut Scratch,
    surface: FreeSurface,
    full_mass: f64,
    holes: Holes,
    spray_fluid: bool,
) {
    bin_particles(ps, grid, s);
    let ghost = surface != FreeSurface::Cell;
    if ghost || holes == Holes::Kept {
        fill_levels(grid, s, full_mass);
    }
    s.orthogonal = surface == FreeSurface::GhostOrthogonal;
    s.ghost_surface = ghost;
    mark_cells(grid, s, ghost, holes, spray_fluid);
    fill_reach(s);
    fill_neighbour_rows(s);
    fill_depths(s);
}

/// The collocated pair's extra rows: the unknowns' ghost weights and the
/// checkerboard control's quads (the staggered pair reads neither).
pub(super) fn mark_collocated_rows(s: &mut Scratch, surface: FreeSurface) {
    fill_ghost_weights(s, surface != FreeSurface::Cell);
    fill_full_quads(s);
}

/// Clears the last step's fluid cells, then bins the particles: each one's
/// cell, and the cells' sums of V and V0.
fn bin_particles(ps: &Particles, grid: &Grid, s: &mut Scratch) {
    s.was_fluid.fill(false);
    for c in s.fluid.drain(..) {
        s.was_fluid[c as usize] = true;
        s.unknown[c as usize] = AIR;
        s.rate[c as usize] = 0.0;
    }
    s.vol.fill(0.0);
    s.vol0.fill(0.0);
    for p in 0..ps.len() {
        let c = s.cell_of(grid, ps.x[p]);
        s.particle_cell[p] = c as u32;
        s.vol[c] += ps.vol[p];
        s.vol0[c] += ps.vol0[p];
    }
}

/// Cell `c`'s corners as padded nodes, in `CORNERS` order.
fn cell_corners(s: &Scratch, grid: &Grid, c: usize) -> [u32; 4] {
    let nx = grid.dims[0];
    let (ci, cj) = (c % s.cells[0], c / s.cells[0]);
    let base = (ci + PAD) + (cj + PAD) * nx;
    CORNERS.map(|(a, b, _, _)| (base + a + b * nx) as u32)
}

/// The fluid fraction less a half, per cell: the corners' folded mass
/// over four full nodes' (the B-spline smears the surface over about a
/// cell, evenly about it, so a half marks where it is), times J for the
/// volume.
fn fill_levels(grid: &Grid, s: &mut Scratch, full_mass: f64) {
    let nx = s.cells[0];
    for c in 0..s.level.len() {
        let (i, j) = (c % nx + PAD, c / nx + PAD);
        let mass: f64 = CORNERS
            .iter()
            .map(|&(a, b, _, _)| {
                if grid.is_active_at(i + a, j + b) {
                    grid.mass[grid.index(i + a, j + b)]
                } else {
                    0.0
                }
            })
            .sum();
        s.level[c] = mass / (4.0 * full_mass) * s.cell_j(c) - 0.5;
    }
}

/// With `depth_basis`, the depths (`surface_depth`) of the cells the ghost
/// surface reads: each fluid cell beside an air cell (diagonals too: the
/// collocated pair's corners) and those air cells. Only there, because
/// the bisection is dear and the water's body needs none.
fn fill_depths(s: &mut Scratch) {
    let Some(basis) = s.depth_basis else {
        return;
    };
    s.depth_read.fill(false);
    let read = |s: &mut Scratch, c: usize| {
        if !s.depth_read[c] {
            s.depth[c] = surface_depth::depth_of(basis, s.level[c] + 0.5);
            s.depth_read[c] = true;
        }
    };
    for k in 0..s.fluid.len() {
        let c = s.fluid[k] as usize;
        let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
        let mut beside_air = false;
        for slot in 0..9 {
            let (dx, dy) = (slot as i64 % 3 - 1, slot as i64 / 3 - 1);
            if s.neighbours[k][slot] != AIR {
                continue;
            }
            if let Some(o) = s.cell_at(ci + dx, cj + dy) {
                read(s, o);
                beside_air = true;
            }
        }
        if beside_air {
            read(s, c);
        }
    }
}

/// Whether cell `c` holds particles at a fluid fraction below a half with
/// none of its four neighbours at a half or more: a drop or a thin sheet
/// away from the water's body, which the ghost surface would leave in free
/// flight (the staggered scheme keeps it fluid, at p = 0 around it, so
/// that it lands with its volume).
fn is_spray(s: &Scratch, c: usize) -> bool {
    let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
    s.vol0[c] > 0.0
        && s.level[c] < 0.0
        && [(-1, 0), (1, 0), (0, -1), (0, 1)]
            .iter()
            .all(|&(di, dj)| s.cell_at(ci + di, cj + dj).is_none_or(|d| s.level[d] < 0.0))
}

/// Whether cell `c` is empty with each of its four sides a wall or a
/// cell holding particles (the staggered scheme's box is walled).
fn is_hole(s: &Scratch, c: usize) -> bool {
    let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
    s.vol0[c] == 0.0
        && [(-1, 0), (1, 0), (0, -1), (0, 1)]
            .iter()
            .all(|&(di, dj)| s.cell_at(ci + di, cj + dj).is_none_or(|d| s.vol0[d] > 0.0))
}

/// The unknowns: each fluid cell numbered, its corners kept and flagged as
/// fluid nodes; a cell left out reads p = 0.
fn mark_cells(grid: &Grid, s: &mut Scratch, ghost: bool, holes: Holes, spray_fluid: bool) {
    // The flags live on the owner nodes (a periodic edge's two sides are one node).
    for c in &s.corners {
        for &n in c {
            s.fluid_node[owner(grid, n as usize)] = false;
        }
    }
    s.corners.clear();
    for c in 0..s.unknown.len() {
        let held = s.vol0[c] > 0.0
            || match holes {
                Holes::Air => false,
                Holes::Fluid => is_hole(s, c),
                Holes::Kept => is_hole(s, c) || s.was_fluid[c] && s.level[c] >= 0.0,
            };
        // A cell whose corners the particles' stencils do not all reach (a
        // particle clamped into it from outside the box) has no operator row.
        let surface_side = !ghost || s.level[c] >= 0.0 || spray_fluid && is_spray(s, c);
        let corners = (held && surface_side)
            .then(|| cell_corners(s, grid, c))
            .filter(|corners| corners.iter().all(|&n| grid.is_active(n as usize)));
        if let Some(corners) = corners {
            s.unknown[c] = s.fluid.len() as u32;
            s.fluid.push(c as u32);
            for n in corners {
                s.fluid_node[owner(grid, n as usize)] = true;
            }
            s.corners.push(corners);
        } else {
            // No row: its particles (above a ghost surface, or clamped in
            // from outside the box) read p = 0, not a gradient left over.
            s.pressure[c] = 0.0;
            s.gradient[c] = Vec2::zeros();
        }
    }
}

/// Per cell, how deep inside the fluid it lies (`Scratch::reach`): the
/// fluid mask eroded by 3 x 3 blocks `CACHED_REACH` times, a row pass then
/// a column pass each (a rectangle's 3 x 3 block is the two passes'
/// product), cells off a walled box passing as the wall's image.
fn fill_reach(s: &mut Scratch) {
    let [mut cur, mut tmp] = std::mem::take(&mut s.eroded);
    for (c, (r, m)) in s.reach.iter_mut().zip(cur.iter_mut()).enumerate() {
        *m = (s.unknown[c] != AIR) as u8;
        *r = *m;
    }
    for _ in 0..CACHED_REACH {
        erode(s, &cur, &mut tmp, 0);
        erode(s, &tmp, &mut cur, 1);
        for (r, &m) in s.reach.iter_mut().zip(&cur) {
            *r += m;
        }
    }
    s.eroded = [cur, tmp];
}

/// `to` = `from`'s minimum over each cell and its two neighbours along
/// `axis` that are in the box (across a periodic edge, the wrapped one).
fn erode(s: &Scratch, from: &[u8], to: &mut [u8], axis: usize) {
    let [nx, ny] = s.cells;
    // Lines along `axis`: their count, length and strides.
    let (lines, len, along, across) = if axis == 0 {
        (ny, nx, 1, nx)
    } else {
        (nx, ny, nx, 1)
    };
    let wrap = s.periodic[axis] && len > 1;
    for line in 0..lines {
        let at = |k: usize| line * across + k * along;
        for k in 0..len {
            let mut m = from[at(k)];
            if k > 0 {
                m = m.min(from[at(k - 1)]);
            } else if wrap {
                m = m.min(from[at(len - 1)]);
            }
            if k + 1 < len {
                m = m.min(from[at(k + 1)]);
            } else if wrap {
                m = m.min(from[at(0)]);
            }
            to[at(k)] = m;
        }
    }
}

/// Each unknown's corner weights: 1 / theta across a corner whose cell is
/// air under the ghost surfaces, else 1.
fn fill_ghost_weights(s: &mut Scratch, ghost: bool) {
    s.ghost.clear();
    for k in 0..s.fluid.len() {
        let c = s.fluid[k] as usize;
        let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
        let weights = CORNERS.map(|(a, b, _, _)| {
            if !ghost {
                return 1.0;
            }
            // The cell across this corner; off a walled box the fold stands for it.
            let across = s.cell_at(ci + 2 * a as i64 - 1, cj + 2 * b as i64 - 1);
            match across {
                Some(o) if s.unknown[o] == AIR => 1.0 / s.surface_share(c, o),
                _ => 1.0,
            }
        });
        s.ghost.push(weights);
    }
}

/// Each unknown's 3 x 3 block of neighbouring unknowns (`AIR` for none).
pub(super) fn fill_neighbour_rows(s: &mut Scratch) {
    s.neighbours.clear();
    for k in 0..s.fluid.len() {
        let c = s.fluid[k] as usize;
        let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
        let row = std::array::from_fn(|slot| {
            let (dx, dy) = (slot as i64 % 3 - 1, slot as i64 / 3 - 1);
            s.cell_at(ci + dx, cj + dy).map_or(AIR, |c| s.unknown[c])
        });
        s.neighbours.push(row);
    }
}

/// The nodes whose four cells are all fluid (walls: no image cells), as
/// their cells' unknowns: the checkerboard control's rows.
fn fill_full_quads(s: &mut Scratch) {
    s.quads.clear();
    let [cx, cy] = s.cells.map(|n| n as i64);
    let node_range = |axis: usize, n: i64| if s.periodic[axis] { 0..n } else { 1..n };
    for nj in node_range(1, cy) {
        for ni in node_range(0, cx) {
            let around = [(-1, -1), (0, -1), (-1, 0), (0, 0)]
                .map(|(a, b)| s.cell_at(ni + a, nj + b).map(|c| s.unknown[c]));
            if let [Some(sw), Some(se), Some(nw), Some(ne)] = around {
                if [sw, se, nw, ne].iter().all(|&u| u != AIR) {
                    s.quads.push([sw, se, nw, ne]);
                }
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::AIR;
    use crate::config::*;
    use crate::{Solver, Vec2};

    /// A 0.1 x 0.1 m column at rest in a 0.1 x 0.3 m box, h = 1 cm, no
    /// gravity, incompressible, on the staggered scheme; a `pocket`
    /// ([x0, y0, x1, y1]) is left empty at t = 0.
    pub(crate) fn column(holes: Holes, pocket: Option<[f64; 4]>) -> Solver {
        let base = Scene::dam_break(Material::new(f64::INFINITY)).bodies[0].clone();
        let body = |rect| Body {
            rect,
            ..base.clone()
        };
        let bodies = match pocket {
            None => vec![body([0.0, 0.0, 0.1, 0.1])],
            // The column less the pocket: below, above, left, right.
            Some([x0, y0, x1, y1]) => vec![
                body([0.0, 0.0, 0.1, y0]),
                body([0.0, y1, 0.1, 0.1]),
                body([0.0, y0, x0, y1]),
                body([x1, y0, 0.1, y1]),
            ],
        };
        let scene = Scene {
            size: [0.1, 0.3],
            cell: 0.01,
            ppc: 2,
            gravity: 0.0,
            bodies,
            materials: vec![Material::new(f64::INFINITY)],
            ..Scene::default()
        };
        let mut method = Method {
            formulation: Formulation::PressureImplicit,
            shape: ShapeKind::Bspline2,
            transfer: TransferKind::Apic,
            ..Method::default()
        };
        method.projection.scheme = ProjectionScheme::Mac;
        method.projection.face_density = FaceDensity::Material;
        method.projection.drift = 0.0;
        method.projection.holes = holes;
        Solver::new(SolverConfig {
            scene,
            method,
            perturb: vec![],
        })
        .unwrap()
    }

    /// The erosion reads `deep` as the cell-by-cell search does, on a
    /// ragged mask in a walled box and in boxes periodic along either axis.
    #[test]
    fn the_cached_depth_is_the_searched_one() {
        for periodic in [[false, false], [true, false], [false, true], [true, true]] {
            let cells = [12, 10];
            let n = cells[0] * cells[1];
            let mut s = super::Scratch {
                cells,
                periodic,
                reach: vec![0; n],
                eroded: [vec![0; n], vec![0; n]],
                ..super::Scratch::default()
            };
            // Fluid but for a diagonal scatter of air cells in the upper
            // rows and one near the floor.
            s.unknown = (0..n as u32)
                .map(|c| {
                    let (i, j) = (c % 12, c / 12);
                    let air = (i * 5 + j * 3) % 17 == 0 && j >= 4 || (i, j) == (3, 1);
                    if air {
                        AIR
                    } else {
                        c
                    }
                })
                .collect();
            super::fill_reach(&mut s);
            let mut deep_counts = [0; 3];
            for c in 0..n {
                for reach in 0..=super::super::CACHED_REACH as i64 {
                    let found = s.deep_by_search(c, reach);
                    assert_eq!(
                        s.deep(c, reach),
                        found,
                        "{periodic:?} cell {c} reach {reach}"
                    );
                    deep_counts[reach as usize] += found as usize;
                }
            }
            // The mask exercises every reach: some cells pass each, some fail.
            assert!(
                deep_counts.iter().all(|&k| k > 0 && k < n),
                "{deep_counts:?}"
            );
        }
    }

    /// Whether cells (4, 5) and (5, 5) are fluid after the last step.
    fn pocket_is_fluid(s: &Solver) -> [bool; 2] {
        [4, 5].map(|i| s.projection.unknown[i + 5 * s.projection.cells[0]] != AIR)
    }

    /// One step, then the particles inside `region` ([x0, y0, x1, y1])
    /// moved by `by`, then another step.
    fn empty_after_a_step(holes: Holes, region: [f64; 4], by: Vec2) -> Solver {
        let mut s = column(holes, None);
        s.step().unwrap();
        assert_eq!(pocket_is_fluid(&s), [true, true], "{holes:?}");
        for x in s.particles.x.iter_mut() {
            if (region[0]..region[2]).contains(&x.x) && (region[1]..region[3]).contains(&x.y) {
                *x += by;
            }
        }
        s.step().unwrap();
        s
    }

    /// Cells (4, 5) and (5, 5) are fluid; their particles then move one
    /// cell down, leaving a two-cell pocket inside the water: under `kept`
    /// it stays fluid (its corners' mass fills more than half of it), under
    /// `fluid` (not a one-cell hole) and `air` it turns to air. Emptied
    /// four cells wide and three deep (its particles moved into the air
    /// above), the pocket's middle is air under `kept` too; and a pocket
    /// that was never water (left empty at t = 0) is air.
    #[test]
    fn a_pocket_that_was_water_stays_fluid_and_air_stays_air() {
        let down = Vec2::new(0.0, -0.01);
        for (holes, kept) in [
            (Holes::Kept, true),
            (Holes::Fluid, false),
            (Holes::Air, false),
        ] {
            let s = empty_after_a_step(holes, [0.04, 0.05, 0.06, 0.06], down);
            assert_eq!(pocket_is_fluid(&s), [kept, kept], "{holes:?}");
        }
        let up = Vec2::new(0.0, 0.15);
        let s = empty_after_a_step(Holes::Kept, [0.03, 0.04, 0.07, 0.07], up);
        assert_eq!(pocket_is_fluid(&s), [false, false], "wide pocket");
        let mut s = column(Holes::Kept, Some([0.04, 0.05, 0.06, 0.06]));
        s.step().unwrap();
        assert_eq!(pocket_is_fluid(&s), [false, false], "planted pocket");
    }
}

#[cfg(test)]
mod ghost_tests {
    use super::tests::column;
    use crate::config::{FreeSurface, Holes, ShareFloor, SurfaceLevel};
    use crate::{Solver, SolverConfig};

    /// The column of `tests::column` (0.1 m of water, h = 1 cm) under
    /// gravity with the packing correction on, on the staggered scheme
    /// with `surface`.
    fn standing_column(surface: FreeSurface) -> Solver {
        let mut cfg: SolverConfig = column(Holes::Kept, None).cfg.clone();
        cfg.scene.gravity = 9.81;
        cfg.method.projection.drift = 0.3;
        cfg.method.projection.free_surface = surface;
        Solver::new(cfg).unwrap()
    }

    /// Resting water stays at rest and reads its packing as exact under
    /// either surface. Under the ghost surface the top cell's pressure is
    /// the weight of the water above its centre, half a cell (p = 0 at the
    /// particles' top, where the grid's fluid fraction crosses a half); at
    /// the air cell's centre it reads 3 % more.
    #[test]
    fn the_ghost_surface_sits_at_the_top_of_a_resting_column() {
        let half_cell_weight = 1000.0 * 9.81 * 0.005;
        for (surface, want_exact) in [(FreeSurface::Cell, false), (FreeSurface::Ghost, true)] {
            let mut s = standing_column(surface);
            for _ in 0..20 {
                s.step().unwrap();
            }
            let speed = s.particles.v.iter().map(|v| v.norm()).fold(0.0, f64::max);
            assert!(speed < 1e-8, "{surface:?}: speed {speed}");
            let packing = s.projection.stats.packing_error;
            assert!(packing.abs() < 1e-9, "{surface:?}: packing {packing}");
            let top = 5 + 9 * s.projection.cells[0];
            let error = s.projection.pressure[top] / half_cell_weight - 1.0;
            assert_eq!(
                error.abs() < 1e-6,
                want_exact,
                "{surface:?}: top cell {error}"
            );
        }
    }

    /// A drop of one cell's particles (fluid fraction about a quarter)
    /// falling 10 cm above the column: the ghost surface leaves it fluid on
    /// the staggered scheme (spray keeps its volume), while a skin of one
    /// particle row on the column's top, beside the water's body, is air.
    #[test]
    fn the_ghost_surface_keeps_spray_fluid_and_thin_surface_cells_air() {
        let mut cfg: SolverConfig = column(Holes::Kept, None).cfg.clone();
        let drop = crate::config::Body {
            rect: [0.04, 0.2, 0.05, 0.21],
            ..cfg.scene.bodies[0].clone()
        };
        let skin = crate::config::Body {
            rect: [0.04, 0.1, 0.05, 0.105],
            ..cfg.scene.bodies[0].clone()
        };
        cfg.scene.bodies.extend([drop, skin]);
        cfg.scene.gravity = 9.81;
        cfg.method.projection.free_surface = FreeSurface::Ghost;
        let mut s = Solver::new(cfg).unwrap();
        s.step().unwrap();
        let p = &s.projection;
        let cell = |i: usize, j: usize| i + j * p.cells[0];
        let (drop, skin) = (cell(4, 20), cell(4, 10));
        assert!(p.level[drop] < 0.0, "drop level {}", p.level[drop]);
        assert_ne!(p.unknown[drop], super::AIR, "the drop is air");
        assert!(p.level[skin] < 0.0, "skin level {}", p.level[skin]);
        assert_eq!(p.unknown[skin], super::AIR, "the skin is fluid");
    }

    /// A column whose top sits a quarter cell above a cell's edge (4 x 4
    /// particles a cell): its top fluid cell's pressure, rho0 g theta h
    /// at rest, reads where the surface is placed. Read by depth it is
    /// the weight of the 0.75 cells above the centre within 0.1 %; read
    /// linearly in the fraction, 2 % short (the surface placed 0.017 cells
    /// low). Cell (5, 9) is the top fluid cell either way.
    #[test]
    fn the_distance_level_places_a_surface_between_cell_edges() {
        let weight = 1000.0 * 9.81 * 0.0075;
        for (level, low, high) in [
            (SurfaceLevel::Distance, -0.001, 0.001),
            (SurfaceLevel::Fraction, -0.03, -0.015),
        ] {
            let mut cfg = standing_column(FreeSurface::Ghost).cfg.clone();
            cfg.scene.ppc = 4;
            cfg.scene.bodies[0].rect[3] = 0.1025;
            cfg.method.projection.surface_level = level;
            let mut s = Solver::new(cfg).unwrap();
            s.step().unwrap();
            let top = 5 + 9 * s.projection.cells[0];
            let above = top + s.projection.cells[0];
            assert_eq!(s.projection.unknown[above], super::AIR, "{level:?}");
            let error = s.projection.pressure[top] / weight - 1.0;
            assert!((low..high).contains(&error), "{level:?}: top cell {error}");
        }
    }

    /// The face-mass bound on theta binds only where a face carries more
    /// mass than the surface the cells place allows: on a resting column
    /// whose top sits anywhere in its cell, at 2 and 4 particles a cell,
    /// every face's theta is the cells' reading, and the top faces' lies
    /// inside the cell (so the comparison is not of ones).
    #[test]
    fn the_face_mass_bound_leaves_a_flat_surface_alone() {
        for (ppc, top) in [(2, 0.1), (2, 0.105), (4, 0.1025), (4, 0.1075)] {
            let shares = |floor: ShareFloor| {
                let mut cfg = standing_column(FreeSurface::Ghost).cfg.clone();
                cfg.scene.ppc = ppc;
                cfg.scene.bodies[0].rect[3] = top;
                cfg.method.projection.surface_level = SurfaceLevel::Distance;
                cfg.method.projection.share_floor = floor;
                let mut s = Solver::new(cfg).unwrap();
                s.step().unwrap();
                s.projection.faces.fields[1].share.clone()
            };
            let (fixed, by_mass) = (shares(ShareFloor::Fixed), shares(ShareFloor::FaceMass));
            assert_eq!(fixed, by_mass, "ppc {ppc}, top {top}");
            let inside = fixed.iter().filter(|&&theta| theta < 0.99).count();
            assert!(inside >= 8, "ppc {ppc}, top {top}: {inside} surface faces");
        }
    }
}
