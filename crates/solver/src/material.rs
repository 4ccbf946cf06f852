//! A fluid or solid material: a `[materials.NAME]` table of a study file.

use crate::choices::EosKind;
use serde::{Deserialize, Serialize};

/// A fluid material: a `[materials.NAME]` table of a study file. Every key
/// but `K` is optional; the defaults below are the only ones.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// The study file's table name (`water` in `[materials.water]`).
    #[serde(skip)]
    pub name: String,
    /// Reference density (kg/m^3).
    #[serde(default = "defaults::rho0")]
    pub rho0: f64,
    #[serde(default = "defaults::eos")]
    pub eos: EosKind,
    /// Low-pressure bulk modulus K (Pa); "inf" (or TOML's inf): the
    /// incompressible limit, under the pressure-implicit formulation only.
    #[serde(rename = "K", with = "bulk_modulus")]
    pub k: f64,
    /// Power-law exponent (power EOS only).
    #[serde(default = "defaults::gamma")]
    pub gamma: f64,
    /// Dynamic viscosity (Pa s).
    #[serde(default)]
    pub viscosity: f64,
    /// Free thermal-expansion volume ratio: the EOS sees J / j_res.
    #[serde(default = "defaults::j_res")]
    pub j_res: f64,
    /// Tension cutoff (Pa): pressure never goes below this (absent = no cutoff).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure_floor: Option<f64>,
    /// Shear modulus G (Pa) of the neo-Hookean shear part: 0 = a fluid.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub shear_modulus: f64,
    /// Shear softening (the unified model's history variable xi, the
    /// accumulated equivalent shear strain): G(xi) = G exp(-xi /
    /// softening_strain), so a solid sheared far enough becomes the fluid
    /// U(J) + 2 mu dev D. 0 = none (G stays G).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub softening_strain: f64,
}

/// K as a number, or "inf" for the incompressible limit (written back as
/// "inf": JSON has no infinity).
mod bulk_modulus {
    use serde::{de, Deserializer, Serializer};
    use std::fmt;

    pub fn serialize<S: Serializer>(k: &f64, s: S) -> Result<S::Ok, S::Error> {
        if *k == f64::INFINITY {
            s.serialize_str("inf")
        } else {
            s.serialize_f64(*k)
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        struct V;
        impl de::Visitor<'_> for V {
            type Value = f64;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a bulk modulus in Pa, or \"inf\"")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<f64, E> {
                Ok(v)
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<f64, E> {
                Ok(v as f64)
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<f64, E> {
                Ok(v as f64)
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<f64, E> {
                match v {
                    "inf" => Ok(f64::INFINITY),
                    _ => Err(E::custom(format!(
                        "\"{v}\" is not a bulk modulus (a number in Pa, or \"inf\")"
                    ))),
                }
            }
        }
        d.deserialize_any(V)
    }
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// Defaults of the optional material keys (one definition, used by serde and `Material::new`).
mod defaults {
    use crate::choices::EosKind;
    pub fn rho0() -> f64 {
        1000.0
    }
    pub fn eos() -> EosKind {
        EosKind::Power
    }
    pub fn gamma() -> f64 {
        7.0
    }
    pub fn j_res() -> f64 {
        1.0
    }
}

impl Material {
    /// Water with every default (power law, gamma 7) and bulk modulus `k`.
    pub fn new(k: f64) -> Self {
        Material {
            name: String::new(),
            rho0: defaults::rho0(),
            eos: defaults::eos(),
            k,
            gamma: defaults::gamma(),
            viscosity: 0.0,
            j_res: defaults::j_res(),
            pressure_floor: None,
            shear_modulus: 0.0,
            softening_strain: 0.0,
        }
    }

    /// Water with the Tait EOS and bulk modulus `k`, otherwise the defaults.
    pub fn tait(k: f64) -> Self {
        Material {
            eos: EosKind::Tait,
            ..Material::new(k)
        }
    }

    /// The study key of field `field` of this material.
    pub(crate) fn key(&self, index: usize, field: &str) -> String {
        if self.name.is_empty() {
            format!("materials[{index}].{field}")
        } else {
            format!("materials.{}.{field}", self.name)
        }
    }
}
