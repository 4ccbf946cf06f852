//! Initial flow fields on a body (docs/physics.md section 7): exact or
//! linear-theory velocity fields whose decay measures a method's own
//! dissipation against the fluid's viscosity.

use crate::config_error::ConfigError;
use crate::particles::{Mat2, Vec2};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A body's initial flow, added to its uniform `velocity`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Flow {
    /// u = U sin(k x) cos(k y), v = -U cos(k x) sin(k y), k = m pi / L,
    /// x and y from the body's lower-left corner, on a square body L x L;
    /// p = rho0 U^2 / 4 (cos 2kx + cos 2ky). Without gravity, in a walled
    /// box the body fills, an exact free-slip Navier-Stokes solution whose
    /// velocity decays as exp(-2 nu k^2 t).
    TaylorGreen { amplitude: f64, mode: u32 },
    /// u = U sin(2 pi y / L), v = 0, L the body's height; periodic on both
    /// axes, decaying as exp(-nu k^2 t), k = 2 pi / L.
    ShearWave { amplitude: f64 },
    /// Mode m of a tank as wide as the body, of the body's depth d, with a
    /// flat surface, at the instant of largest velocity (linear theory's
    /// potential): k = m pi / W, omega^2 = g k tanh(k d), surface amplitude
    /// a; u = -a omega cosh(k y) sin(k x) / sinh(k d),
    /// v = a omega sinh(k y) cos(k x) / sinh(k d).
    StandingWave { amplitude: f64, mode: u32 },
    /// Brackbill's ringing test (docs/physics.md section 7b): a seed on the
    /// body's uniform `velocity` U, of speed `share` |U|, mode m waves
    /// across a square body (k = 2 pi m / L, near the grid scale when L / m
    /// is a few cells): u' = (sin kx + sin ky, sin kx - sin ky) / 2, both
    /// compressive and rotational. Periodic on both axes; a uniform flow
    /// alone is an exact discrete steady state and seeds only round-off.
    GridSeed { share: f64, mode: u32 },
    /// A standing sound wave along x in a closed box the body fills,
    /// without gravity: u = U sin(k x), v = 0, k = m pi / W, at the instant
    /// of largest velocity (uniform pressure). Linear acoustics: frequency
    /// c k, amplitude decay (2/3) nu k^2 (the 3D deviator of plane strain,
    /// no bulk viscosity).
    SoundWave { amplitude: f64, mode: u32 },
}

impl Flow {
    /// The mode number m (None for the shear wave, which has one mode).
    pub fn mode(&self) -> Option<u32> {
        match *self {
            Flow::TaylorGreen { mode, .. }
            | Flow::StandingWave { mode, .. }
            | Flow::GridSeed { mode, .. }
            | Flow::SoundWave { mode, .. } => Some(mode),
            Flow::ShearWave { .. } => None,
        }
    }

    /// The wavenumber k of the flow on a body `rect`.
    pub fn wavenumber(&self, rect: [f64; 4]) -> f64 {
        let (w, h) = (rect[2] - rect[0], rect[3] - rect[1]);
        match *self {
            Flow::TaylorGreen { mode, .. }
            | Flow::StandingWave { mode, .. }
            | Flow::SoundWave { mode, .. } => mode as f64 * PI / w,
            Flow::ShearWave { .. } => 2.0 * PI / h,
            Flow::GridSeed { mode, .. } => 2.0 * PI * mode as f64 / w,
        }
    }

    /// The standing wave's angular frequency, sqrt(g k tanh(k d)).
    pub fn omega(&self, rect: [f64; 4], gravity: f64) -> f64 {
        let k = self.wavenumber(rect);
        (gravity * k * (k * (rect[3] - rect[1])).tanh()).sqrt()
    }

    fn amplitude(&self) -> f64 {
        match *self {
            Flow::TaylorGreen { amplitude, .. }
            | Flow::ShearWave { amplitude }
            | Flow::StandingWave { amplitude, .. }
            | Flow::SoundWave { amplitude, .. } => amplitude,
            Flow::GridSeed { share, .. } => share,
        }
    }

    /// The factor the flow's speed scale is multiplied by on a body moving
    /// at `drift`: |U| for the grid seed (its speed is a share of the
    /// drift), 1 for the others (their amplitude is a speed).
    pub fn drift_scale(&self, drift: [f64; 2]) -> f64 {
        match self {
            Flow::GridSeed { .. } => drift[0].hypot(drift[1]),
            _ => 1.0,
        }
    }

    /// The flow's velocity at `x` over its body `rect` (gravity for the
    /// standing wave's frequency).
    pub fn velocity(&self, x: Vec2, rect: [f64; 4], gravity: f64) -> Vec2 {
        self.shape(x, rect, gravity) * self.speed(rect, gravity)
    }

    /// The flow's peak speed scale: U, or a omega / sinh(k d) for the wave.
    pub fn speed(&self, rect: [f64; 4], gravity: f64) -> f64 {
        match *self {
            Flow::StandingWave { amplitude, .. } => {
                let k = self.wavenumber(rect);
                amplitude * self.omega(rect, gravity) / (k * (rect[3] - rect[1])).sinh()
            }
            _ => self.amplitude(),
        }
    }

    /// The velocity field of unit speed scale: the mode that a probe
    /// projects the velocity on.
    pub fn shape(&self, x: Vec2, rect: [f64; 4], _gravity: f64) -> Vec2 {
        let k = self.wavenumber(rect);
        let (dx, dy) = (x.x - rect[0], x.y - rect[1]);
        match *self {
            Flow::TaylorGreen { .. } => Vec2::new(
                (k * dx).sin() * (k * dy).cos(),
                -(k * dx).cos() * (k * dy).sin(),
            ),
            Flow::ShearWave { .. } => Vec2::new((k * dy).sin(), 0.0),
            Flow::StandingWave { .. } => Vec2::new(
                -(k * dy).cosh() * (k * dx).sin(),
                (k * dy).sinh() * (k * dx).cos(),
            ),
            Flow::GridSeed { .. } => {
                let (sx, sy) = ((k * dx).sin(), (k * dy).sin());
                Vec2::new(0.5 * (sx + sy), 0.5 * (sx - sy))
            }
            Flow::SoundWave { .. } => Vec2::new((k * dx).sin(), 0.0),
        }
    }

    /// The velocity gradient (d v_i / d x_j) at `x`: the APIC affine
    /// velocity a particle starts with.
    pub fn gradient(&self, x: Vec2, rect: [f64; 4], gravity: f64) -> Mat2 {
        let (k, a) = (self.wavenumber(rect), self.speed(rect, gravity));
        let (dx, dy) = (x.x - rect[0], x.y - rect[1]);
        let (sx, cx) = (k * dx).sin_cos();
        let (sy, cy) = (k * dy).sin_cos();
        let ak = a * k;
        match *self {
            Flow::TaylorGreen { .. } => {
                Mat2::new(ak * cx * cy, -ak * sx * sy, ak * sx * sy, -ak * cx * cy)
            }
            Flow::ShearWave { .. } => Mat2::new(0.0, ak * cy, 0.0, 0.0),
            Flow::StandingWave { .. } => {
                let (sh, ch) = ((k * dy).sinh(), (k * dy).cosh());
                Mat2::new(-ak * ch * cx, -ak * sh * sx, -ak * sh * sx, ak * ch * cx)
            }
            Flow::GridSeed { .. } => {
                let h = 0.5 * ak;
                Mat2::new(h * cx, h * cy, h * cx, -h * cy)
            }
            Flow::SoundWave { .. } => Mat2::new(ak * cx, 0.0, 0.0, 0.0),
        }
    }

    /// The pressure that goes with the flow (Taylor-Green only; zero for
    /// the others, whose pressure is the hydrostatic one or none).
    pub fn pressure(&self, x: Vec2, rect: [f64; 4], rho0: f64) -> f64 {
        match *self {
            Flow::TaylorGreen { amplitude, .. } => {
                let k = self.wavenumber(rect);
                let (dx, dy) = (x.x - rect[0], x.y - rect[1]);
                rho0 * amplitude * amplitude / 4.0 * ((2.0 * k * dx).cos() + (2.0 * k * dy).cos())
            }
            _ => 0.0,
        }
    }

    /// The flow is defined on this body of a scene with these periodic
    /// axes and gravity: a finite positive amplitude, a mode of at least 1,
    /// a square body for Taylor-Green and the grid seed, both axes periodic
    /// for the shear wave and the grid seed, gravity for the standing wave,
    /// none and walls on x for the sound wave.
    pub fn check(
        &self,
        rect: [f64; 4],
        periodic: [bool; 2],
        gravity: f64,
        key: &str,
    ) -> Result<(), ConfigError> {
        let bad = |field: &str, message: &str| ConfigError {
            key: format!("{key}.{field}"),
            message: message.into(),
        };
        let a = self.amplitude();
        if !(a.is_finite() && a > 0.0) {
            let field = match self {
                Flow::GridSeed { .. } => "share",
                _ => "amplitude",
            };
            return Err(bad(field, "must be finite and > 0"));
        }
        let (w, h) = (rect[2] - rect[0], rect[3] - rect[1]);
        match *self {
            Flow::TaylorGreen { mode, .. }
            | Flow::StandingWave { mode, .. }
            | Flow::GridSeed { mode, .. }
            | Flow::SoundWave { mode, .. }
                if mode == 0 =>
            {
                Err(bad("mode", "must be >= 1"))
            }
            Flow::TaylorGreen { .. } | Flow::GridSeed { .. } if (w - h).abs() > 1e-9 * w.max(h) => {
                Err(bad("kind", "needs a square body (width = height)"))
            }
            Flow::GridSeed { .. } if periodic != [true, true] => {
                Err(bad("kind", "grid_seed needs scene.periodic = [true, true]"))
            }
            Flow::ShearWave { .. } if periodic != [true, true] => Err(bad(
                "kind",
                "shear_wave needs scene.periodic = [true, true]",
            )),
            Flow::StandingWave { .. } if gravity <= 0.0 => {
                Err(bad("kind", "standing_wave needs scene.gravity > 0"))
            }
            Flow::SoundWave { .. } if gravity != 0.0 || periodic[0] => Err(bad(
                "kind",
                "sound_wave needs scene.gravity = 0 and walls on x (scene.periodic[0] = false)",
            )),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BOX: [f64; 4] = [0.0, 0.0, 0.2, 0.2];

    /// Taylor-Green: no normal velocity at the walls, divergence free (by
    /// central differences), and the momentum balance's pressure: grad p =
    /// -rho (u . grad) u.
    #[test]
    fn taylor_green_is_walled_divergence_free_and_balanced() {
        let f = Flow::TaylorGreen {
            amplitude: 0.01,
            mode: 2,
        };
        for s in [0.0, 0.07, 0.13, 0.2] {
            assert!(f.velocity(Vec2::new(0.0, s), BOX, 0.0).x.abs() < 1e-15);
            assert!(f.velocity(Vec2::new(0.2, s), BOX, 0.0).x.abs() < 1e-15);
            assert!(f.velocity(Vec2::new(s, 0.0), BOX, 0.0).y.abs() < 1e-15);
            assert!(f.velocity(Vec2::new(s, 0.2), BOX, 0.0).y.abs() < 1e-15);
        }
        let e = 1e-6;
        let u = |x: f64, y: f64| f.velocity(Vec2::new(x, y), BOX, 0.0);
        let p = |x: f64, y: f64| f.pressure(Vec2::new(x, y), BOX, 1000.0);
        for (x, y) in [(0.031, 0.077), (0.15, 0.02), (0.11, 0.19)] {
            let div = (u(x + e, y).x - u(x - e, y).x + u(x, y + e).y - u(x, y - e).y) / (2.0 * e);
            assert!(div.abs() < 1e-8, "{div}");
            let v = u(x, y);
            let dudx = (u(x + e, y) - u(x - e, y)) / (2.0 * e);
            let dudy = (u(x, y + e) - u(x, y - e)) / (2.0 * e);
            let advection = dudx * v.x + dudy * v.y;
            let grad_p = Vec2::new(
                (p(x + e, y) - p(x - e, y)) / (2.0 * e),
                (p(x, y + e) - p(x, y - e)) / (2.0 * e),
            );
            let residual = grad_p + 1000.0 * advection;
            assert!(residual.norm() < 1e-7, "{residual:?}");
        }
    }

    /// The standing wave of the tank (W = 0.4 m, d = 0.2 m, mode
    /// 1): period 0.747 s; the potential flow is divergence free, has no
    /// normal velocity at the walls and floor, and its surface rises at
    /// a omega cos(k x) (the flat surface's largest velocity).
    #[test]
    fn standing_wave_has_linear_theorys_period_and_walls() {
        let tank = [0.0, 0.0, 0.4, 0.2];
        let f = Flow::StandingWave {
            amplitude: 0.005,
            mode: 1,
        };
        let period = 2.0 * PI / f.omega(tank, 9.81);
        assert!((period - 0.7474).abs() < 5e-4, "{period}");
        let u = |x: f64, y: f64| f.velocity(Vec2::new(x, y), tank, 9.81);
        for s in [0.0, 0.05, 0.2] {
            assert!(u(0.0, s).x.abs() < 1e-15 && u(0.4, s).x.abs() < 1e-15);
        }
        assert!(u(0.1, 0.0).y.abs() < 1e-15);
        let omega = f.omega(tank, 9.81);
        let k = PI / 0.4;
        let top = u(0.1, 0.2).y;
        assert!(
            (top - 0.005 * omega * (k * 0.1).cos()).abs() < 1e-12,
            "{top}"
        );
        let e = 1e-6;
        let div = (u(0.13 + e, 0.07).x - u(0.13 - e, 0.07).x + u(0.13, 0.07 + e).y
            - u(0.13, 0.07 - e).y)
            / (2.0 * e);
        assert!(div.abs() < 1e-7, "{div}");
    }

    /// The sound wave has no normal velocity at the x walls, and mode 5 of
    /// the 0.2 m box at h = 1 cm is the one with k h = pi / 4.
    #[test]
    fn sound_wave_is_walled_and_its_mode_sets_k() {
        let f = Flow::SoundWave {
            amplitude: 1e-3,
            mode: 5,
        };
        for y in [0.0, 0.07, 0.2] {
            assert!(f.velocity(Vec2::new(0.0, y), BOX, 0.0).x.abs() < 1e-18);
            assert!(f.velocity(Vec2::new(0.2, y), BOX, 0.0).x.abs() < 1e-17);
            assert_eq!(f.velocity(Vec2::new(0.03, y), BOX, 0.0).y, 0.0);
        }
        assert!((f.wavenumber(BOX) * 0.01 - PI / 4.0).abs() < 1e-12);
        assert_eq!(f.mode(), Some(5));
    }

    /// The gradient is the velocity's, by central differences, for each flow.
    #[test]
    fn gradients_match_the_velocity_fields() {
        let tank = [0.0, 0.0, 0.4, 0.2];
        let flows = [
            (
                Flow::TaylorGreen {
                    amplitude: 0.01,
                    mode: 2,
                },
                BOX,
            ),
            (Flow::ShearWave { amplitude: 0.01 }, BOX),
            (
                Flow::StandingWave {
                    amplitude: 0.005,
                    mode: 1,
                },
                tank,
            ),
            (
                Flow::GridSeed {
                    share: 0.01,
                    mode: 3,
                },
                BOX,
            ),
            (
                Flow::SoundWave {
                    amplitude: 0.001,
                    mode: 5,
                },
                BOX,
            ),
        ];
        let e = 1e-7;
        for (f, rect) in flows {
            for x in [Vec2::new(0.031, 0.077), Vec2::new(0.15, 0.12)] {
                let u = |p: Vec2| f.velocity(p, rect, 9.81);
                let ddx = (u(x + Vec2::new(e, 0.0)) - u(x - Vec2::new(e, 0.0))) / (2.0 * e);
                let ddy = (u(x + Vec2::new(0.0, e)) - u(x - Vec2::new(0.0, e))) / (2.0 * e);
                let g = f.gradient(x, rect, 9.81);
                let numeric = Mat2::new(ddx.x, ddy.x, ddx.y, ddy.y);
                assert!(
                    (g - numeric).norm() < 1e-6 * (1.0 + g.norm()),
                    "{f:?}: {g} vs {numeric}"
                );
            }
        }
    }

    #[test]
    fn flows_outside_their_conditions_are_refused_by_key() {
        let tg = |mode| Flow::TaylorGreen {
            amplitude: 0.01,
            mode,
        };
        let key = "scene.body[0].flow";
        assert_eq!(
            tg(0).check(BOX, [false, false], 9.81, key).unwrap_err().key,
            "scene.body[0].flow.mode"
        );
        let wide = [0.0, 0.0, 0.4, 0.2];
        assert!(tg(1).check(wide, [false, false], 9.81, key).is_err());
        assert!(tg(1).check(BOX, [false, false], 9.81, key).is_ok());
        let shear = Flow::ShearWave { amplitude: 0.01 };
        assert!(shear.check(BOX, [false, false], 9.81, key).is_err());
        assert!(shear.check(BOX, [true, true], 0.0, key).is_ok());
        let bad = Flow::ShearWave {
            amplitude: f64::NAN,
        };
        assert_eq!(
            bad.check(BOX, [true, true], 0.0, key).unwrap_err().key,
            "scene.body[0].flow.amplitude"
        );
        let seed = |share| Flow::GridSeed { share, mode: 3 };
        assert!(seed(1e-4).check(BOX, [true, true], 0.0, key).is_ok());
        assert!(seed(1e-4).check(BOX, [true, false], 0.0, key).is_err());
        assert!(seed(1e-4).check(wide, [true, true], 0.0, key).is_err());
        assert_eq!(
            seed(0.0)
                .check(BOX, [true, true], 0.0, key)
                .unwrap_err()
                .key,
            "scene.body[0].flow.share"
        );
        let sound = Flow::SoundWave {
            amplitude: 1e-3,
            mode: 5,
        };
        assert!(sound.check(wide, [false, false], 0.0, key).is_ok());
        assert!(sound.check(wide, [false, false], 9.81, key).is_err());
        assert!(sound.check(wide, [true, false], 0.0, key).is_err());
        let silent = Flow::SoundWave {
            amplitude: 1e-3,
            mode: 0,
        };
        assert_eq!(
            silent
                .check(wide, [false, false], 0.0, key)
                .unwrap_err()
                .key,
            "scene.body[0].flow.mode"
        );
        assert_eq!(seed(1e-4).drift_scale([3.0, 4.0]), 5.0);
        assert_eq!(tg(1).drift_scale([3.0, 4.0]), 1.0);
    }
}
