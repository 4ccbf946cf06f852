//! The FLIP/PIC blend as a damping time tau (`[method.pic_damping] time`):
//! each step's FLIP fraction is 1 - min(dt / tau, 1), so the PIC share damps
//! at one rate per unit time whatever dt is (PIC's own damping grows as dt
//! shrinks, i.e. with the fluid's stiffness).
//!
//! Energy: the kinetic energy the blend takes from pure FLIP's velocities,
//! sum 1/2 m (|v|^2 - |v_FLIP|^2) with v_FLIP = v^n + sum N (v_i^{n+1} - v_i^n),
//! so that it can be taken out of the transfer loss, not counted twice.

// The loop walks the particles and their stencils in step.
#![allow(clippy::needless_range_loop)]

use super::{Descriptor, EnergyChange, Remedy, Setup, Step, Supports};
use crate::choices::TransferKind;
use super::Check;
use crate::particles::Vec2;
use crate::shapes::with_width;
use crate::config_error::ConfigError;
use serde::{Deserialize, Serialize};

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "pic_damping",
    main: Some(("time", 5e-5)),
    old_keys: &[("time", "pic_damping_time")],
};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// The damping time tau (s).
    pub time: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { time: 5e-5 }
    }
}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn supports(&self) -> Supports {
        Supports {
            transfers: &[TransferKind::Flip],
            // It reads per-axis weights.
            shapes: crate::shapes::TENSOR_PRODUCT,
            ..Supports::ALL
        }
    }
    fn validate(&self, cfg: &Check) -> Result<(), ConfigError> {
        super::positive_up_to(self.time, 1e3, "method.pic_damping.time")?;
        if cfg.flip_alpha != 1.0 {
            return Err(ConfigError {
                key: "method.pic_damping".into(),
                message: format!(
                    "needs method.flip_alpha left at 1 (it sets the blend each step; got {})",
                    cfg.flip_alpha
                ),
            });
        }
        Ok(())
    }
    fn build(&self, _setup: &Setup) -> Box<dyn Remedy> {
        Box::new(PicDamping { tau: self.time })
    }
}

#[derive(Clone)]
struct PicDamping {
    tau: f64,
}

impl Remedy for PicDamping {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }

    fn flip_fraction(&self, dt: f64) -> Option<f64> {
        Some((1.0 - dt / self.tau).max(0.0))
    }

    fn after_g2p(&mut self, s: &mut Step) -> EnergyChange {
        let kinetic = with_width!(s.shape, W => blend_loss::<W>(s));
        EnergyChange {
            kinetic,
            ..EnergyChange::default()
        }
    }
}

/// sum 1/2 m (|v|^2 - |v^n + sum N (v_i^{n+1} - v_i^n)|^2).
fn blend_loss<const W: usize>(s: &Step) -> f64 {
    let (ps, grid) = (&*s.particles, s.grid);
    let nx = grid.dims[0];
    let mut sum = 0.0;
    for (p, st) in s.stencils.iter().enumerate() {
        let (wx, _) = s.shape.stencil_weights::<W>(st.frac[0], st.half[0]);
        let (wy, _) = s.shape.stencil_weights::<W>(st.frac[1], st.half[1]);
        let mut dv = Vec2::zeros();
        for c in 0..W {
            let row = st.node as usize + c * nx;
            for a in 0..W {
                dv += (wx[a] * wy[c]) * (grid.vel_new[row + a] - grid.vel[row + a]);
            }
        }
        let flip = ps.v_prev[p] + dv;
        sum += 0.5 * ps.mass[p] * (ps.v[p].norm_squared() - flip.norm_squared());
    }
    sum
}
