//! The checkerboard of the fields a method builds its forces from
//! (docs/physics.md section 4), beside the index of the cell means of
//! particle pressure (`checkerboard`), which J-bar blinds by construction:
//!
//! - nodal: the pressure per node that drives the nodal forces: J-bar's
//!   nodal J through the EOS, pressure smoothing's nodal p, else the
//!   projection sum N m p / sum N m of the particle pressure;
//! - cell: the cell pressure of a method that carries one (the
//!   pressure-implicit step's solved pressure, cell
//!   dilatation's cell J through the EOS).
//!
//! Each is the alternating amplitude A = sqrt(mean (L q)^2) / 8 over the
//! interior points (L the 5-point Laplacian), over rho0 g h: a unit
//! checkerboard (-1)^(i + j) rho0 g h reads 1, any linear field 0.

use solver::grid::{FULL_NODE_SHARE, PAD};
use solver::remedies::PressureField;
use solver::shapes::Shape;
use solver::{Material, StateView, Vec2};

/// Cells with at least this share of a full cell's V0 carry a cell pressure
/// (half, as the cell means' `filled_min`).
const CELL_FILLED_SHARE: f64 = 0.5;

/// The alternating amplitude of a field on an `nx` x `ny` lattice over its
/// interior points: those with a value whose four edge neighbours have one,
/// off the lattice's outer ring. None without interior points.
pub fn alternating_amplitude(
    [nx, ny]: [usize; 2],
    value: impl Fn(usize, usize) -> Option<f64>,
) -> Option<f64> {
    let (mut n, mut sum) = (0usize, 0.0);
    for j in 1..ny.saturating_sub(1) {
        for i in 1..nx.saturating_sub(1) {
            let (Some(c), Some(e), Some(w), Some(no), Some(s)) = (
                value(i, j),
                value(i + 1, j),
                value(i - 1, j),
                value(i, j + 1),
                value(i, j - 1),
            ) else {
                continue;
            };
            let lap = e + w + no + s - 4.0 * c;
            sum += lap * lap;
            n += 1;
        }
    }
    (n > 0).then(|| (sum / n as f64).sqrt() / 8.0)
}

/// The nodal and cell measures, with the scratch of the particle
/// projection (allocated once).
#[derive(Clone, Debug, Default)]
pub struct FieldCheckerboard {
    node_sum: Vec<f64>,
    node_mass: Vec<f64>,
}

/// The pressure the EOS of `m` gives at J (with its tension cut).
fn pressure_of(m: &Material, j: f64) -> f64 {
    m.cut(m.eos(j).pressure)
}

impl FieldCheckerboard {
    /// The nodal measure over the nodes of a box of `cells`: the last nodal
    /// field of a remedy (registry order: pressure smoothing acts after
    /// J-bar), else the particle projection.
    pub fn nodal(&mut self, v: &StateView, cells: [usize; 2], scale: f64) -> Option<f64> {
        let g = &v.grid;
        let full = FULL_NODE_SHARE * v.materials[0].rho0 * g.h * g.h;
        let nodal = v
            .remedies
            .pressure_fields()
            .filter(|(_, f)| !matches!(f, PressureField::CellJ { .. }))
            .last()
            .map(|(_, f)| f);
        // Nodes of the box only (walls included): ghosts hold mirror data.
        let nx = g.dims[0];
        let at = |i: usize, j: usize| (i + PAD) + (j + PAD) * nx;
        let dims = [cells[0] + 1, cells[1] + 1];
        let amplitude = match nodal {
            Some(PressureField::NodalJ(av)) => alternating_amplitude(dims, |i, j| {
                let (jac, w) = av.node_value(at(i, j))?;
                (w >= full).then(|| pressure_of(&v.materials[0], jac))
            }),
            Some(PressureField::NodalPressure(av)) => alternating_amplitude(dims, |i, j| {
                let (p, w) = av.node_value(at(i, j))?;
                (w >= full).then_some(p)
            }),
            _ => {
                self.project(v);
                let (sum, mass) = (&self.node_sum, &self.node_mass);
                alternating_amplitude(dims, |i, j| {
                    let n = at(i, j);
                    (mass[n] >= full).then(|| sum[n] / mass[n])
                })
            }
        };
        amplitude.map(|a| a / scale)
    }

    /// The cell measure over a box of `cells`, for a method that carries a
    /// cell pressure.
    pub fn cell(&self, v: &StateView, cells: [usize; 2], scale: f64) -> Option<f64> {
        let h = v.grid.h;
        let filled = CELL_FILLED_SHARE * h * h;
        if let Some(pi) = &v.projection {
            // The pressure-implicit step's solved cell pressure.
            return alternating_amplitude(cells, |i, j| {
                let c = i + j * cells[0];
                (pi.volume0[c] >= filled).then(|| pi.pressure[c])
            })
            .map(|a| a / scale);
        }
        let (volume, volume0) = v.remedies.pressure_fields().find_map(|(_, f)| match f {
            PressureField::CellJ { volume, volume0 } => Some((volume, volume0)),
            _ => None,
        })?;
        alternating_amplitude(cells, |i, j| {
            let c = i + j * cells[0];
            (volume0[c] >= filled).then(|| pressure_of(&v.materials[0], volume[c] / volume0[c]))
        })
        .map(|a| a / scale)
    }

    /// sum N m p and sum N m per padded node, with the scene's shape.
    fn project(&mut self, v: &StateView) {
        let g = &v.grid;
        let nodes = g.dims[0] * g.dims[1];
        self.node_sum.resize(nodes, 0.0);
        self.node_mass.resize(nodes, 0.0);
        self.node_sum.fill(0.0);
        self.node_mass.fill(0.0);
        let shape = Shape::new(v.shape, v.scene.ppc);
        let origin = Vec2::from(v.scene.origin);
        let inside = |k: i64, n: usize| {
            let k = k + PAD as i64;
            (k >= 0 && (k as usize) < n).then_some(k as usize)
        };
        for p in 0..v.x.len() {
            let r = (v.x[p] - origin) / g.h;
            let (m, mp) = (v.mass[p], v.mass[p] * v.pressure[p]);
            if !(r.x.is_finite() && r.y.is_finite() && mp.is_finite()) {
                continue;
            }
            shape.each_weight([r.x, r.y], &v.deformation[p], |[i, j], w, _| {
                let (Some(col), Some(row)) = (inside(i, g.dims[0]), inside(j, g.dims[1])) else {
                    return;
                };
                let n = col + row * g.dims[0];
                self.node_sum[n] += w * mp;
                self.node_mass[n] += w * m;
            });
        }
    }
}
