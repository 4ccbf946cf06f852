//! The pressure solve on the staggered grid: with m_f a face's mass, the
//! fluid cell's pressure solves
//!
//!   alpha p_c + sum_f (h^2 / m_f) (p_c - p_across) = alpha p(J^n) - (h^2 / dt) D u*
//!
//! over its four faces (a wall face: none; an air cell across: p = 0 at
//! its centre, or under the ghost surface at the share theta of the way
//! there, which scales that face's coupling by 1 / theta),
//! alpha = h^2 / (K_t dt^2); then u_f = u*_f - dt h (p_hi - p_lo) / m_f.
//! Under the theta rule p is the mix theta p^{n+1} + (1 - theta) p^n:
//! alpha becomes alpha / theta^2 and D u* becomes D u* + (1 - theta) /
//! theta D u^n (p^{n+1} - p^n = -K dt D u_theta, u_theta the same mix).
//! D u is the exact flux balance of the cell's faces, so the gradient's
//! only kernel is the constant of a closed box.

use super::super::{surface_depth, Scratch, SolveStats, AIR};
use super::field::FaceField;
use crate::config::Material;

/// A cell's four faces, left, right, below and above: the slot of the
/// cell across in 3 x 3 order ((dx + 1) + 3 (dy + 1)), the face's
/// component and its index from the cell's (ci, cj).
const SIDES: [(usize, usize, i64, i64); 4] = [
    // (slot, axis, face di, face dj)
    (3, 0, 0, 0),
    (5, 0, 1, 0),
    (1, 1, 0, 0),
    (7, 1, 0, 1),
];

/// Fills the matrix rows (3 x 3 slots), right-hand side, diagonal and
/// starting guess of every fluid cell.
pub fn assemble(
    faces: &[FaceField; 2],
    s: &mut Scratch,
    mat: &Material,
    h: f64,
    dt: f64,
    light: f64,
    theta: f64,
) {
    let h2 = h * h;
    let incompressible = mat.k == f64::INFINITY;
    for v in [&mut s.alpha, &mut s.target, &mut s.b, &mut s.diag, &mut s.x] {
        v.clear();
    }
    s.matrix.clear();
    s.shift.clear();
    for k in 0..s.fluid.len() {
        let c = s.fluid[k] as usize;
        let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
        let (alpha, p_eos) = if incompressible {
            (0.0, 0.0)
        } else {
            let state = mat.eos(s.cell_j(c));
            (
                h2 / (state.tangent_modulus.max(1e-300) * dt * dt * theta * theta),
                state.pressure,
            )
        };
        let mut row = [0.0; 9];
        row[4] = alpha;
        for &(slot, axis, fi, fj) in &SIDES {
            let field = &faces[axis];
            let (i, j) = (ci + fi, cj + fj);
            if field.on_wall(i, j) {
                continue;
            }
            let coupling = h2 / field.operator_mass[field.index(i, j)].max(light);
            if s.neighbours[k][slot] != AIR {
                row[4] += coupling;
                row[slot] = -coupling;
            } else {
                row[4] += coupling / field.share[field.index(i, j)];
            }
        }
        s.alpha.push(alpha);
        s.target.push(0.0);
        let mut div = divergence(faces, ci, cj, h);
        if theta < 1.0 {
            div += (1.0 - theta) / theta * flux_balance(faces, ci, cj, h, |f| &f.vel);
        }
        s.b.push(alpha * p_eos - h2 / dt * div);
        s.diag.push(row[4]);
        s.matrix.push(row);
        s.x.push(s.pressure[c]);
    }
}

/// D u of cell (ci, cj): its faces' net outflow over h, of `vel_new` (u*
/// with the air faces' shares before the correction, u^{n+1} after it).
pub fn divergence(faces: &[FaceField; 2], ci: i64, cj: i64, h: f64) -> f64 {
    flux_balance(faces, ci, cj, h, |f| &f.vel_new)
}

/// D of the face values `velocity` picks (`vel`: the P2G u^n) at cell (ci, cj).
fn flux_balance(
    faces: &[FaceField; 2],
    ci: i64,
    cj: i64,
    h: f64,
    velocity: fn(&FaceField) -> &[f64],
) -> f64 {
    let [fx, fy] = faces;
    let u = |field: &FaceField, i: i64, j: i64| velocity(field)[field.index(i, j)];
    (u(fx, ci + 1, cj) - u(fx, ci, cj) + u(fy, ci, cj + 1) - u(fy, ci, cj)) / h
}

/// The two cells a face of `field` at (i, j) separates, below and above
/// along its component's axis.
fn cells_beside(field: &FaceField, i: i64, j: i64) -> [(i64, i64); 2] {
    if field.axis == 0 {
        [(i - 1, j), (i, j)]
    } else {
        [(i, j - 1), (i, j)]
    }
}

/// How far apart, in cells, a flat surface's two readings of theta fall
/// at two particles a cell: the cells' fractions and the face's mass
/// (the face's at most 0.024 above on 99 % of a slosh's faces normal to
/// the surface). Beyond it the face's mass bounds theta; within it the
/// bound would rectify the readings' noise and move the wave's surface
/// (its period shortens 0.8 % at h = 1 cm without this slack).
const READINGS_SPREAD: f64 = 0.05;

/// Each solved face's theta (`FaceField::share`): where a ghost surface
/// crosses it, the share of the way from its fluid cell's centre to its
/// air cell's at which p = 0 sits (`Scratch::surface_share`); with
/// `face_mass`, at least the share at which a flat surface would give the
/// face its own mass (`surface_depth::face_share`), less
/// `READINGS_SPREAD`.
/// Elsewhere 1.
pub fn fill_shares(field: &mut FaceField, s: &Scratch, full_mass: f64, face_mass: bool) {
    let mut share = std::mem::take(&mut field.share);
    for (f, theta) in share.iter_mut().enumerate() {
        *theta = 1.0;
        if !s.ghost_surface || !field.solved[f] {
            continue;
        }
        let (i, j) = field.coords(f);
        let [lo, hi] = cells_beside(field, i, j).map(|(ci, cj)| s.cell_at(ci, cj));
        let fluid = |c: Option<usize>| c.is_some_and(|c| s.unknown[c] != AIR);
        let (c, o) = match (lo, hi) {
            (Some(c), Some(o)) if fluid(lo) && !fluid(hi) => (c, o),
            (Some(o), Some(c)) if fluid(hi) && !fluid(lo) => (c, o),
            _ => continue,
        };
        *theta = s.surface_share(c, o);
        if face_mass {
            let by_mass = surface_depth::face_share(field.mass[f] / full_mass);
            *theta = theta.max(by_mass - READINGS_SPREAD);
        }
    }
    field.share = share;
}

/// p_hi - p_lo across a face between in-box cells `lo` and `hi`: an air
/// cell reads p = 0 at its centre, or under a ghost surface the ghost
/// pressure p (theta - 1) / theta of its fluid neighbour's p (`share`:
/// the face's theta), so that the jump is p / theta: the surface moves
/// through the cell with the fluid fraction instead of jumping a cell
/// when a particle crosses a cell's edge.
fn pressure_jump(s: &Scratch, lo: (i64, i64), hi: (i64, i64), share: f64) -> f64 {
    let [c_lo, c_hi] = [lo, hi].map(|(i, j)| i as usize + j as usize * s.cells[0]);
    let solved = |c: usize| match s.unknown[c] {
        AIR => None,
        k => Some(s.x[k as usize]),
    };
    match (solved(c_lo), solved(c_hi)) {
        (Some(p_lo), Some(p_hi)) => p_hi - p_lo,
        (Some(p_lo), None) => -p_lo / share,
        (None, Some(p_hi)) => p_hi / share,
        (None, None) => 0.0,
    }
}

/// u^{n+1} = u* - dt h (p_hi - p_lo) / m_f on every in-box face beside a
/// fluid cell (walls held); the cells' pressures stored for the next solve.
pub fn correct(faces: &mut [FaceField; 2], s: &mut Scratch, h: f64, dt: f64, light: f64) {
    for (k, &c) in s.fluid.iter().enumerate() {
        s.pressure[c as usize] = s.x[k];
    }
    for field in faces.iter_mut() {
        let mut vel = std::mem::take(&mut field.vel_new);
        apply_gradient(field, s, h, dt, light, &mut vel);
        field.vel_new = vel;
    }
}

/// values_f -= scale h (x_hi - x_lo) / m'_f on the solved faces, for the
/// solved cell values `s.x` (air: 0); the air faces then follow their
/// neighbours and the ghosts are filled.
pub fn apply_gradient(
    field: &FaceField,
    s: &Scratch,
    h: f64,
    scale: f64,
    light: f64,
    values: &mut [f64],
) {
    for (f, value) in values.iter_mut().enumerate() {
        if !field.solved[f] {
            continue;
        }
        let (i, j) = field.coords(f);
        let [lo, hi] = cells_beside(field, i, j);
        let jump = pressure_jump(s, lo, hi, field.share[f]);
        *value -= scale * h * jump / field.operator_mass[f].max(light);
    }
    follow_neighbours(field, values);
    field.fill(values);
}

/// Flags the faces this step's solve sets: in the box, not a wall's, and
/// bordering a fluid cell (once a step, after the fluid cells are marked).
pub fn mark_solved(field: &mut FaceField, s: &Scratch) {
    let mut solved = std::mem::take(&mut field.solved);
    for (f, flag) in solved.iter_mut().enumerate() {
        let (i, j) = field.coords(f);
        *flag = field.in_box(i, j)
            && !field.on_wall(i, j)
            && cells_beside(field, i, j)
                .iter()
                .any(|&(ci, cj)| s.cell_at(ci, cj).is_some_and(|c| s.unknown[c] != AIR));
    }
    field.solved = solved;
}

/// An air face's solved neighbours (same component, one face away), and
/// how many: None for a face that is solved, a wall's, outside the box or
/// empty.
fn air_neighbours(field: &FaceField, f: usize) -> Option<([usize; 4], usize)> {
    let (i, j) = field.coords(f);
    if field.mass[f] <= 0.0 || !field.in_box(i, j) || field.on_wall(i, j) || field.solved[f] {
        return None;
    }
    let mut out = [0; 4];
    let mut count = 0;
    for (di, dj) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
        // One face beyond the box is still inside the padding.
        let n = field.index(i + di, j + dj);
        if field.solved[n] {
            out[count] = n;
            count += 1;
        }
    }
    (count > 0).then_some((out, count))
}

/// The air faces' velocity is their solved neighbours' mean (a kinematic
/// constraint), so their mass and u* momentum join those neighbours' in
/// equal shares before the solve: the weight of the material the
/// B-spline carries beyond the fluid cells rests on the pressure. Sets
/// `operator_mass` and the neighbours' u* (in `vel_new`); with `material`
/// = Some(rho0 h^2), the operator takes the material's density instead
/// (`material_density`).
pub fn slave_air_faces(field: &mut FaceField, s: &Scratch, material: Option<f64>) {
    let mut op = std::mem::take(&mut field.operator_mass);
    op.copy_from_slice(&field.mass);
    // Momentum first, in `vel_new` as m u*; divided once all shares are in.
    for f in 0..op.len() {
        field.vel_new[f] = field.mass[f] * field.vel_star[f];
    }
    for f in 0..op.len() {
        if let Some((neighbours, count)) = air_neighbours(field, f) {
            let share = field.mass[f] / count as f64;
            for &n in &neighbours[..count] {
                op[n] += share;
                field.vel_new[n] += share * field.vel_star[f];
            }
        }
    }
    for ((u, &m), &star) in field.vel_new.iter_mut().zip(&op).zip(&field.vel_star) {
        *u = if m > 0.0 { *u / m } else { star };
    }
    if let Some(full) = material {
        material_density(field, s, full, &mut op);
    }
    field.operator_mass = op;
}

/// `face_density = "material"`: a face whose two cells and their
/// neighbours are all fluid takes the material's mass rho0 h^2 / J (J the
/// mean of its two cells' particle volumes over their rest volumes); a
/// face nearer the surface keeps the particles' mass (its fill), capped
/// there; under the ghost surface every face beside a fluid cell takes the
/// material's mass, since theta places the surface. The particles' mass
/// varies with their packing, and a projection that reads it as density
/// lets gravity sink the denser packing and lift the looser (docs/findings/projection_mac.md, "The packing's buoyancy").
fn material_density(field: &FaceField, s: &Scratch, full: f64, op: &mut [f64]) {
    let compression = |c: usize| {
        if s.vol[c] > 0.0 && s.vol0[c] > 0.0 {
            s.vol0[c] / s.vol[c]
        } else {
            1.0
        }
    };
    for (f, m) in op.iter_mut().enumerate() {
        let (i, j) = field.coords(f);
        if !field.in_box(i, j) || field.on_wall(i, j) {
            continue;
        }
        let beside = cells_beside(field, i, j).map(|(ci, cj)| s.cell_at(ci, cj));
        let [Some(lo), Some(hi)] = beside else {
            *m = m.min(full);
            continue;
        };
        let material = full * 0.5 * (compression(lo) + compression(hi));
        let inside = if s.ghost_surface {
            // The ghost surface's theta places p = 0; a face's fill would
            // place it a second time.
            [lo, hi].iter().any(|&c| s.unknown[c] != AIR)
        } else {
            [lo, hi]
                .iter()
                .all(|&c| s.unknown[c] != AIR && s.deep(c, 1))
        };
        *m = if inside { material } else { m.min(material) };
    }
}

/// Each slaved air face takes its solved neighbours' mean value.
fn follow_neighbours(field: &FaceField, values: &mut [f64]) {
    for f in 0..values.len() {
        if let Some((neighbours, count)) = air_neighbours(field, f) {
            let sum: f64 = neighbours[..count].iter().map(|&n| values[n]).sum();
            values[f] = sum / count as f64;
        }
    }
}

/// The cells' J rate e = D u_theta (D u^{n+1} under backward Euler), and
/// the energy the projection removed: minus the pressure's work on the
/// faces at the time-centred velocity, plus what the stored energy lost
/// (minus its change, at the mean of p^n and p^{n+1}): the solved
/// pressure's work on e and (2 theta - 1) K dt^2 e^2 / 2 a unit volume
/// (the backward-Euler loss at theta = 1, none under the trapezoidal
/// rule).
pub fn book(faces: &[FaceField; 2], s: &mut Scratch, h: f64, dt: f64, theta: f64) {
    let (mut pressure_work, mut compression_loss) = (0.0, 0.0);
    for (k, &c) in s.fluid.iter().enumerate() {
        let c = c as usize;
        let (ci, cj) = ((c % s.cells[0]) as i64, (c / s.cells[0]) as i64);
        let mut e = divergence(faces, ci, cj, h);
        if theta < 1.0 {
            e = theta * e + (1.0 - theta) * flux_balance(faces, ci, cj, h, |f| &f.vel);
        }
        s.rate[c] = e;
        pressure_work += s.x[k] * s.vol[c] * dt * e;
        if s.alpha[k] > 0.0 {
            // s.alpha holds h^2 / (K dt^2 theta^2).
            compression_loss += (2.0 * theta - 1.0) * (h * h * s.vol[c] * e * e)
                / (2.0 * s.alpha[k] * theta * theta);
        }
    }
    let mut work = 0.0;
    let mut kinetic_change = 0.0;
    for field in faces {
        for f in 0..field.vel_new.len() {
            let m = field.mass_raw[f];
            if m == 0.0 {
                continue;
            }
            let du = field.vel_new[f] - field.vel_star[f];
            work += m * du * 0.5 * (field.vel[f] + field.vel_new[f]);
            kinetic_change += m * (du * field.vel_new[f] - 0.5 * du * du);
        }
    }
    s.stats.kinetic_change = kinetic_change;
    s.stats.dissipated_projection = -work + pressure_work + compression_loss;
    s.stats.dissipated_hourglass = 0.0;
}

/// The stats of a fresh solve over `fluid` cells.
pub fn fresh_stats(fluid: usize) -> SolveStats {
    SolveStats {
        fluid_cells: fluid,
        ..SolveStats::default()
    }
}
