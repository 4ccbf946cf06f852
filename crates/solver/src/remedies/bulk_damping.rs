//! Artificial bulk viscosity (`[method.bulk_damping] coefficient = b`):
//! sigma += zeta tr(D) I with zeta = b rho0 c h, the linear bulk viscosity
//! of explicit codes. It damps acoustic ringing at a rate that vanishes as
//! h -> 0; stable for b < 1 / (2 cfl). The wave speed is the previous
//! step's (the stress stage evaluates the EOS after its loop).
//!
//! Energy: its work, -dt sum V zeta tr(D)^2 (also counted as dissipated).

use super::{Descriptor, EnergyChange, PointRule, Remedy, Setup};
use crate::material::Material;
use super::Check;
use crate::particles::Mat2;
use crate::{viscosity, ConfigError};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "bulk_damping",
    main: Some(("coefficient", 0.3)),
    old_keys: &[("coefficient", "bulk_damping")],
};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// The dimensionless coefficient b (0 < b <= 1 / (2 cfl)).
    pub coefficient: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { coefficient: 0.3 }
    }
}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn validate(&self, cfg: &Check) -> Result<(), ConfigError> {
        super::positive_up_to(
            self.coefficient,
            0.5 / cfg.cfl,
            "method.bulk_damping.coefficient",
        )
    }
    fn build(&self, _setup: &Setup) -> Box<dyn Remedy> {
        Box::new(BulkDamping {
            b: self.coefficient,
        })
    }
}

#[derive(Clone)]
struct BulkDamping {
    b: f64,
}

impl PointRule for BulkDamping {
    #[inline]
    fn extra_stress(
        &self,
        m: &Material,
        wave_speed: f64,
        _j: f64,
        h: f64,
        d: &Mat2,
    ) -> Option<(Mat2, f64)> {
        let zeta = self.b * m.rho0 * wave_speed * h;
        Some(viscosity::bulk(zeta, d))
    }
}

impl Remedy for BulkDamping {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }
    fn point_rule(&self) -> Option<Arc<dyn PointRule>> {
        Some(Arc::new(self.clone()))
    }
    fn point_work(&self, dissipated: f64) -> EnergyChange {
        EnergyChange {
            work: -dissipated,
            ..EnergyChange::default()
        }
    }
}
