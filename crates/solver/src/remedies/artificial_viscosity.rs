//! Uintah's artificial bulk viscosity (`[method.artificial_viscosity]`,
//! off by default there as here): in compression only (tr D < 0),
//! q = rho (A1 |c tr(D) h| + A2 (tr(D) h)^2), with rho = rho0 / J the
//! current density, c = sqrt(K / rho) from the bulk modulus K (not the
//! tangent modulus) and h the mean cell size; q adds to the pressure in the
//! next internal force only (the EOS pressure the monitor reads is left
//! alone). Defaults A1 = 0.2, A2 = 2.0 (MPMFlags).
//!
//! Energy: its work, -dt sum V q tr(D) <= 0 (also counted as dissipated).

use super::Check;
use super::{Descriptor, EnergyChange, PointRule, Remedy, Setup};
use crate::material::Material;
use crate::particles::Mat2;
use crate::ConfigError;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "artificial_viscosity",
    main: None,
    old_keys: &[],
};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// A1, the linear coefficient.
    pub linear: f64,
    /// A2, the quadratic coefficient.
    pub quadratic: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            linear: 0.2,
            quadratic: 2.0,
        }
    }
}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn validate(&self, _cfg: &Check) -> Result<(), ConfigError> {
        super::positive_up_to(self.linear, 10.0, "method.artificial_viscosity.linear")?;
        super::positive_up_to(
            self.quadratic,
            100.0,
            "method.artificial_viscosity.quadratic",
        )
    }
    fn build(&self, setup: &Setup) -> Box<dyn Remedy> {
        let h = setup.grid.h;
        Box::new(ArtificialViscosity {
            linear: self.linear,
            quadratic: self.quadratic,
            length: setup.slab.map(|dz| (2.0 * h + dz) / 3.0),
        })
    }
}

#[derive(Clone)]
struct ArtificialViscosity {
    linear: f64,
    quadratic: f64,
    /// Uintah's mean cell size (dx + dy + dz) / 3 when the scene has a
    /// slab (`scene.slab`); else the cell h.
    length: Option<f64>,
}

/// q for a material at J under the rate of deformation d, cell size h (Pa).
pub fn bulk_q(linear: f64, quadratic: f64, m: &Material, j: f64, h: f64, d: &Mat2) -> f64 {
    let rate = d.trace();
    if rate >= 0.0 || j <= 0.0 {
        return 0.0;
    }
    let rho = m.rho0 / j;
    let c = (m.k / rho).sqrt();
    let (a, b) = (rate * h, c * rate * h);
    rho * (linear * b.abs() + quadratic * a * a)
}

impl PointRule for ArtificialViscosity {
    #[inline]
    fn extra_stress(
        &self,
        m: &Material,
        _wave_speed: f64,
        j: f64,
        h: f64,
        d: &Mat2,
    ) -> Option<(Mat2, f64)> {
        let q = bulk_q(self.linear, self.quadratic, m, j, self.length.unwrap_or(h), d);
        // sigma_q = -q I; its power per volume is -sigma_q : D = q tr(D) <= 0
        // on the motion, so what it dissipates is -q tr(D).
        (q > 0.0).then(|| (-q * Mat2::identity(), -q * d.trace()))
    }
}

impl Remedy for ArtificialViscosity {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Compression only; both terms as written, with c from K (not gamma K).
    #[test]
    fn q_is_uintahs_formula_in_compression_only() {
        let mut m = Material::new(1.5e6);
        m.gamma = 7.0;
        let d = Mat2::new(-3.0, 0.4, 0.4, 1.0); // tr D = -2
        let (j, h) = (0.8, 0.01);
        let rho: f64 = 1000.0 / 0.8;
        let c = (1.5e6 / rho).sqrt();
        let want = rho * (0.2 * (c * 2.0 * h) + 2.0 * (2.0 * h) * (2.0 * h));
        let q = bulk_q(0.2, 2.0, &m, j, h, &d);
        assert!((q / want - 1.0).abs() < 1e-14, "{q} vs {want}");
        let expanding = Mat2::new(1.0, 0.0, 0.0, 0.5);
        assert_eq!(bulk_q(0.2, 2.0, &m, j, h, &expanding), 0.0);
        let rule = ArtificialViscosity {
            linear: 0.2,
            quadratic: 2.0,
            length: None,
        };
        let (s, power) = rule.extra_stress(&m, 0.0, j, h, &d).unwrap();
        assert_eq!(s, -q * Mat2::identity());
        assert!((power - s.component_mul(&d).sum()).abs() < 1e-9 * power);
        assert!(power > 0.0);
    }

    /// With a slab (`scene.slab`) the length is Uintah's (dx + dy + dz) / 3.
    #[test]
    fn a_slab_sets_the_length_to_the_mean_of_the_three_axes() {
        let h = 0.01;
        let grid = crate::grid::Grid::new(crate::particles::Vec2::zeros(), h, [4, 4], [false; 2]);
        let mut m = Material::new(1.5e6);
        m.gamma = 7.0;
        let d = Mat2::new(-3.0, 0.4, 0.4, 1.0);
        for (slab, length) in [(None, h), (Some(0.004), (2.0 * h + 0.004) / 3.0)] {
            let setup = Setup {
                grid: &grid,
                particles: 0,
                ppc: 2,
                rho0: 1000.0,
                slab,
            };
            let rule = super::super::Settings::build(&Settings::default(), &setup)
                .point_rule()
                .unwrap();
            let (s, _) = rule.extra_stress(&m, 0.0, 0.8, h, &d).unwrap();
            let q = bulk_q(0.2, 2.0, &m, 0.8, length, &d);
            assert_eq!(s, -q * Mat2::identity(), "{slab:?}");
        }
    }
}
