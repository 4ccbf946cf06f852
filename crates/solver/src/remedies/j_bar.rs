//! J-bar by particle-grid averaging (Zhao, Jiang & Choo 2023),
//! `[method.j_bar]`: J_i = sum N m J / m_i, J_bar = sum N J_i,
//! J_p <- (1 - b) J_p + b J_bar after the stress update.
//! - `fit = "linear"`: each node fits a plane by mass-weighted least squares
//!   instead of the mean, so a linear J field (the hydrostatic one) is a
//!   fixed point up to the material's edges.
//! - `carry = false`: the averaged J sets this step's pressure and volume
//!   only; the particle keeps its own J and F (repeated replacement diffuses
//!   J every step).
//! - `average_increment = true`: average this step's volume ratio J_new /
//!   J_old instead of J (the incremental form, as Coombs et al. 2018 average
//!   the incremental dF): a field at rest is left alone.
//!
//! Skipped for the whole step when some J <= 0: averaging would hide the
//! inversion. Energy: the stored energy its J change makes (carried), or the
//! work of the stress and volume change (`carry = false`, booked at the grid
//! update that uses it).

use super::averaging::{averaged, set_j_booked, Averager, Uncarried};
use super::{Descriptor, EnergyChange, GridStep, PressureField, Remedy, Setup, Step, Supports};
use crate::choices::JBarFit;
use super::Check;
use crate::config_error::ConfigError;
use serde::{Deserialize, Serialize};

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "j_bar",
    main: Some(("blend", 1.0)),
    old_keys: &[
        ("blend", "j_bar"),
        ("fit", "j_bar_fit"),
        ("carry", "carry_averaged_j"),
        ("average_increment", "average_increment"),
    ],
};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Blend b (0 < b <= 1).
    pub blend: f64,
    /// The nodal reconstruction: `constant` (the paper's mean) or `linear`.
    pub fit: JBarFit,
    /// Whether the particle carries the averaged J to the next step.
    pub carry: bool,
    /// Average this step's volume ratio instead of J.
    pub average_increment: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            blend: 1.0,
            fit: JBarFit::Constant,
            carry: true,
            average_increment: false,
        }
    }
}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn supports(&self) -> Supports {
        Supports {
            // Its J update re-evaluates the EOS only, not the shear part.
            solids: false,
            // It reads per-axis weights.
            shapes: crate::shapes::TENSOR_PRODUCT,
            ..Supports::ALL
        }
    }
    fn validate(&self, cfg: &Check) -> Result<(), ConfigError> {
        super::positive_up_to(self.blend, 1.0, "method.j_bar.blend")?;
        let refuse = |key: &str, message: &str| {
            Err(ConfigError {
                key: key.into(),
                message: message.into(),
            })
        };
        if cfg.remedies.cell_dilatation.is_some() {
            return refuse(
                "method.j_bar",
                "cannot be combined with method.cell_dilatation (two averagings of J: choose one)",
            );
        }
        if self.average_increment && !self.carry {
            return refuse(
                "method.j_bar.average_increment",
                "needs method.j_bar.carry = true (it replaces J by J_old times the averaged ratio)",
            );
        }
        Ok(())
    }
    fn build(&self, setup: &Setup) -> Box<dyn Remedy> {
        let n = setup.particles;
        Box::new(JBar {
            settings: self.clone(),
            averager: Averager::new(setup.grid, n, self.fit == JBarFit::Linear),
            j_before: vec![0.0; if self.average_increment { n } else { 0 }],
            ratio: vec![0.0; n],
            uncarried: Uncarried::new(self.carry, n),
        })
    }
}

#[derive(Clone)]
struct JBar {
    settings: Settings,
    averager: Averager,
    /// Per particle: J before this step's update (`average_increment`).
    j_before: Vec<f64>,
    /// Per particle: this step's volume ratio J_new / J_old.
    ratio: Vec<f64>,
    uncarried: Uncarried,
}

impl Remedy for JBar {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }

    fn fit_particles(&mut self, n: usize) {
        self.averager.fit_particles(n);
        if self.ratio.len() < n {
            self.ratio.resize(n, 0.0);
        }
        if self.settings.average_increment && self.j_before.len() < n {
            self.j_before.resize(n, 0.0);
        }
        self.uncarried.fit_particles(n);
    }

    fn before_stress(&mut self, s: &mut Step) -> EnergyChange {
        if self.settings.average_increment {
            // J before this step's update: the increment is averaged.
            let n = s.particles.len();
            self.j_before[..n].copy_from_slice(&s.particles.j);
        }
        EnergyChange::default()
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
        Some(PressureField::NodalJ(&self.averager))
    }
}

impl JBar {
    /// Replaces J by the blend with its average; returns the stored energy
    /// that changed.
    fn average(&mut self, s: &mut Step) -> f64 {
        let Settings {
            blend: b,
            fit,
            average_increment,
            ..
        } = self.settings;
        let ps = &mut *s.particles;
        if ps.j.iter().any(|j| !(*j > 0.0 && j.is_finite())) {
            return 0.0;
        }
        let av = &mut self.averager;
        if average_increment {
            // A state at rest is left alone.
            let n = ps.len();
            for p in 0..n {
                self.ratio[p] = ps.j[p] / self.j_before[p];
            }
            averaged(ps, &self.ratio[..n], s.stencils, s.shape, s.grid, fit, av);
            for p in 0..n {
                av.averaged[p] *= self.j_before[p];
            }
        } else {
            let j = std::mem::take(&mut ps.j);
            averaged(ps, &j, s.stencils, s.shape, s.grid, fit, av);
            ps.j = j;
        }
        let mut stored = 0.0;
        for p in 0..ps.len() {
            let j_new = if b == 1.0 {
                av.averaged[p]
            } else {
                (1.0 - b) * ps.j[p] + b * av.averaged[p]
            };
            stored += set_j_booked(ps, s.materials, p, j_new);
        }
        stored
    }
}
