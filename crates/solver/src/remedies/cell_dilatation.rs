//! Cell-averaged dilatation (Mast et al. 2012), `[method.cell_dilatation]`:
//! J_c = sum V / sum V0 over the particles of a cell, J_p <- (1 - b) J_p +
//! b J_c after the stress update. A cell holding a particle with J <= 0 (or
//! non-finite) is left alone: a positive J_c would hide it. `carry = false`
//! keeps the particle's own J and F (the average sets this step's pressure
//! and volume only).
//!
//! Energy: the stored energy its J change makes (carried), or the work of
//! the pressure change (`carry = false`).

use super::averaging::{cell_of, set_j_booked, Uncarried};
use super::{Descriptor, EnergyChange, GridStep, PressureField, Remedy, Setup, Step, Supports};
use super::Check;
use crate::config_error::ConfigError;
use serde::{Deserialize, Serialize};

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "cell_dilatation",
    main: Some(("blend", 1.0)),
    old_keys: &[("blend", "cell_dilatation"), ("carry", "carry_averaged_j")],
};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Blend b (0 < b <= 1).
    pub blend: f64,
    /// Whether the particle carries the averaged J to the next step.
    pub carry: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            blend: 1.0,
            carry: true,
        }
    }
}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn supports(&self) -> Supports {
        Supports {
            solids: false,
            ..Supports::ALL
        }
    }
    fn validate(&self, _cfg: &Check) -> Result<(), ConfigError> {
        super::positive_up_to(self.blend, 1.0, "method.cell_dilatation.blend")
    }
    fn build(&self, setup: &Setup) -> Box<dyn Remedy> {
        let cells = setup.grid.cells[0] * setup.grid.cells[1];
        let n = setup.particles;
        Box::new(CellDilatation {
            settings: self.clone(),
            cell_volume: vec![0.0; cells],
            cell_volume0: vec![0.0; cells],
            cell_bad: vec![false; cells],
            uncarried: Uncarried::new(self.carry, n),
        })
    }
}

#[derive(Clone)]
struct CellDilatation {
    settings: Settings,
    /// Per cell: sum V, sum V0, and whether it holds an inverted particle.
    cell_volume: Vec<f64>,
    cell_volume0: Vec<f64>,
    cell_bad: Vec<bool>,
    uncarried: Uncarried,
}

impl Remedy for CellDilatation {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }

    fn fit_particles(&mut self, n: usize) {
        self.uncarried.fit_particles(n);
    }

    fn after_stress(&mut self, s: &mut Step) -> (EnergyChange, bool) {
        self.uncarried.keep(s.particles);
        let stored = self.average(s);
        self.uncarried.averaged(stored)
    }

    fn after_pressure(&mut self, s: &mut Step) -> EnergyChange {
        self.uncarried.restore(s.particles);
        EnergyChange::default()
    }

    fn after_grid_update(&mut self, g: &mut GridStep) -> EnergyChange {
        self.uncarried.book(g)
    }

    fn pressure_field(&self) -> Option<PressureField<'_>> {
        Some(PressureField::CellJ {
            volume: &self.cell_volume,
            volume0: &self.cell_volume0,
        })
    }
}

impl CellDilatation {
    fn average(&mut self, s: &mut Step) -> f64 {
        let (ps, grid, b) = (&mut *s.particles, s.grid, self.settings.blend);
        self.cell_volume.fill(0.0);
        self.cell_volume0.fill(0.0);
        self.cell_bad.fill(false);
        for p in 0..ps.len() {
            let c = cell_of(grid, ps.x[p]);
            if !(ps.j[p] > 0.0 && ps.j[p].is_finite()) {
                self.cell_bad[c] = true;
            }
            self.cell_volume[c] += ps.vol[p];
            self.cell_volume0[c] += ps.vol0[p];
        }
        let mut stored = 0.0;
        for p in 0..ps.len() {
            let c = cell_of(grid, ps.x[p]);
            if self.cell_bad[c] {
                continue;
            }
            let j_c = self.cell_volume[c] / self.cell_volume0[c];
            let j_new = if b == 1.0 {
                j_c
            } else {
                (1.0 - b) * ps.j[p] + b * j_c
            };
            stored += set_j_booked(ps, s.materials, p, j_new);
        }
        stored
    }
}
