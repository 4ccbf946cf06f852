//! Pressure smoothing through the nodes (CB-Geo's option),
//! `[method.pressure_smoothing]`: p_i = sum N m p / m_i, p <- sum N p_i after
//! the stress update, the stress following (sigma = viscous - p I).
//!
//! Energy: the work of the pressure change, booked at the grid update that
//! uses it.

use super::averaging::{averaged, Averager};
use super::stress_work::StressWork;
use super::{Descriptor, EnergyChange, GridStep, PressureField, Remedy, Setup, Step, Supports};
use crate::choices::JBarFit;
use crate::particles::Mat2;
use serde::{Deserialize, Serialize};

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "pressure_smoothing",
    main: None,
    old_keys: &[],
};

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Settings {}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn supports(&self) -> Supports {
        Supports {
            solids: false,
            // It reads per-axis weights.
            shapes: crate::shapes::TENSOR_PRODUCT,
            ..Supports::ALL
        }
    }
    fn build(&self, setup: &Setup) -> Box<dyn Remedy> {
        let n = setup.particles;
        Box::new(PressureSmoothing {
            averager: Averager::new(setup.grid, n, false),
            before: vec![Mat2::zeros(); n],
            work: StressWork::new(n),
        })
    }
}

#[derive(Clone)]
struct PressureSmoothing {
    averager: Averager,
    /// Per particle: the stress before smoothing.
    before: Vec<Mat2>,
    work: StressWork,
}

impl Remedy for PressureSmoothing {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }

    fn fit_particles(&mut self, n: usize) {
        self.averager.fit_particles(n);
        if self.before.len() < n {
            self.before.resize(n, Mat2::zeros());
        }
        self.work.fit_particles(n);
    }

    fn after_pressure(&mut self, s: &mut Step) -> EnergyChange {
        let ps = &mut *s.particles;
        let n = ps.len();
        self.before[..n].copy_from_slice(&ps.stress);
        let pressure = std::mem::take(&mut ps.pressure);
        let av = &mut self.averager;
        averaged(ps, &pressure, s.stencils, s.shape, s.grid, JBarFit::Constant, av);
        ps.pressure = pressure;
        for p in 0..n {
            let p_new = av.averaged[p];
            if p_new.is_finite() {
                ps.stress[p] += Mat2::identity() * (ps.pressure[p] - p_new);
                ps.pressure[p] = p_new;
            }
        }
        self.work.record(ps, &ps.vol, &self.before[..n]);
        EnergyChange::default()
    }

    fn after_grid_update(&mut self, g: &mut GridStep) -> EnergyChange {
        EnergyChange {
            work: self.work.book(g),
            ..EnergyChange::default()
        }
    }

    fn pressure_field(&self) -> Option<PressureField<'_>> {
        Some(PressureField::NodalPressure(&self.averager))
    }
}
