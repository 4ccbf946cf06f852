//! Equations of state (docs/physics.md section 2): pressure positive in compression,
//! U' = -p, K_t = -J dp/dJ. The thermal option evaluates them at J / j_res.

use crate::choices::EosKind;
use crate::material::Material;
mod linear;
mod power;
pub mod tait;

/// Pressure, tangent bulk modulus and stored energy per reference volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EosState {
    pub pressure: f64,
    pub tangent_modulus: f64,
    pub energy: f64,
}

impl Material {
    /// Unclamped EOS at the mechanical J (thermal J_res applied here).
    #[inline]
    pub fn eos(&self, j: f64) -> EosState {
        if self.k == f64::INFINITY {
            // Incompressible: no EOS pressure (the projection's is the
            // pressure) and no stored energy.
            return EosState {
                pressure: 0.0,
                tangent_modulus: f64::INFINITY,
                energy: 0.0,
            };
        }
        // j / 1 is j exactly: skip the division in the usual case.
        let je = if self.j_res == 1.0 { j } else { j / self.j_res };
        self.eos_at(je)
    }

    /// The EOS at the effective J / j_res.
    #[inline]
    fn eos_at(&self, je: f64) -> EosState {
        let (p, kt, u) = match self.eos {
            EosKind::Power => power::eval(self.k, self.gamma, je),
            EosKind::Tait => tait::eval(self.k, je),
            EosKind::Linear => linear::eval(self.k, je),
        };
        EosState {
            pressure: p,
            tangent_modulus: kt,
            energy: u,
        }
    }

    /// Cut pressure, wave speed and stored energy V0 U(J) of a run of
    /// particles of this material (`out` = pressure, wave speed, stored).
    /// The power law with integer gamma and the linear EOS run as branch-free
    /// loops the compiler vectorises; the results are the bits of `eos`.
    pub fn eval_run(&self, j: &[f64], vol0: &[f64], out: (&mut [f64], &mut [f64], &mut [f64])) {
        let (k, gamma) = (self.k, self.gamma);
        match (self.eos, power::integer_exponent(gamma)) {
            (EosKind::Power, Some(n)) if n != 1 => {
                self.run_with(|je| power::eval_integer(k, gamma, n, je), j, vol0, out)
            }
            (EosKind::Linear, _) => self.run_with(|je| linear::eval(k, je), j, vol0, out),
            _ => self.run_with(
                |je| {
                    let s = self.eos_at(je);
                    (s.pressure, s.tangent_modulus, s.energy)
                },
                j,
                vol0,
                out,
            ),
        }
    }

    /// `eval_run` for one EOS form, with the cutoff and J / j_res hoisted.
    #[inline(always)]
    fn run_with(
        &self,
        eos: impl Fn(f64) -> (f64, f64, f64),
        j: &[f64],
        vol0: &[f64],
        (pressure, wave, stored): (&mut [f64], &mut [f64], &mut [f64]),
    ) {
        let n = j.len();
        let (vol0, pressure, wave, stored) = (
            &vol0[..n],
            &mut pressure[..n],
            &mut wave[..n],
            &mut stored[..n],
        );
        let rho0 = self.rho0;
        macro_rules! go {
            ($je:expr, $cut:expr, $energy:expr) => {
                for i in 0..n {
                    let je = $je(j[i]);
                    let (p, kt, u) = eos(je);
                    pressure[i] = $cut(p);
                    wave[i] = (kt * j[i] / rho0).max(0.0).sqrt();
                    stored[i] = vol0[i] * $energy(je, p, u);
                }
            };
        }
        let j_res = self.j_res;
        let uncut = |_: f64, _: f64, u: f64| u;
        // The corner is the material's: found once for the run.
        let corner = self.cut_corner().unwrap_or_default();
        let cut = |je: f64, p: f64, u: f64| cut_energy_at(corner, je, p, u);
        match (j_res == 1.0, self.pressure_floor) {
            (true, None) => go!(|j: f64| j, |p: f64| p, uncut),
            (true, Some(floor)) => go!(|j: f64| j, |p: f64| p.max(floor), cut),
            (false, None) => go!(|j: f64| j / j_res, |p: f64| p, uncut),
            (false, Some(floor)) => go!(|j: f64| j / j_res, |p: f64| p.max(floor), cut),
        }
    }

    /// Pressure with the optional tension cutoff.
    #[inline]
    pub fn pressure(&self, j: f64) -> f64 {
        self.cut(self.eos(j).pressure)
    }

    /// Longitudinal wave speed c = sqrt(K_t J / rho0).
    #[inline]
    pub fn wave_speed(&self, j: f64) -> f64 {
        self.wave_speed_of(&self.eos(j), j)
    }

    #[inline]
    pub fn wave_speed_of(&self, state: &EosState, j: f64) -> f64 {
        (state.tangent_modulus * j / self.rho0).max(0.0).sqrt()
    }

    /// Stored energy per reference volume of `state` = `eos(j)`, consistent
    /// with the tension cutoff: U_cut(J) = -int_1^J max(p, floor) dJ'
    /// (docs/physics.md section 2). Without a floor, the EOS's U.
    #[inline]
    pub fn energy_of(&self, j: f64, state: &EosState) -> f64 {
        if self.pressure_floor.is_none() || self.k == f64::INFINITY {
            return state.energy;
        }
        let je = if self.j_res == 1.0 { j } else { j / self.j_res };
        self.cut_energy(je, state.pressure, state.energy)
    }

    /// V0-free stored energy at J under the cutoff (`energy_of(j, eos(j))`).
    #[inline]
    pub fn stored(&self, j: f64) -> f64 {
        self.energy_of(j, &self.eos(j))
    }

    /// U_cut at the effective J `je`, from the uncut pressure `p` and
    /// energy `u` there (the cut's corner found only where it is needed).
    #[inline]
    fn cut_energy(&self, je: f64, p: f64, u: f64) -> f64 {
        let Some(f) = self.pressure_floor else {
            return u;
        };
        if f <= 0.0 && p >= f {
            return u;
        }
        self.cut_corner()
            .map_or(u, |corner| cut_energy_at(corner, je, p, u))
    }

    /// The cut's corner: the floor f, the effective J_f where p(J_f) = f,
    /// and U(J_f); None without a floor.
    fn cut_corner(&self) -> Option<(f64, f64, f64)> {
        let f = self.pressure_floor?;
        let jf = self.je_at_pressure(f);
        Some((f, jf, self.eos_at(jf).energy))
    }

    /// The tension cutoff applied to an EOS pressure.
    #[inline]
    pub fn cut(&self, p: f64) -> f64 {
        match self.pressure_floor {
            Some(floor) => p.max(floor),
            None => p,
        }
    }

    /// J at which the (uncut) pressure equals `p`: the inverse EOS.
    pub fn j_at_pressure(&self, p: f64) -> f64 {
        self.je_at_pressure(p) * self.j_res
    }

    /// The effective J / j_res at which the (uncut) pressure equals `p`.
    fn je_at_pressure(&self, p: f64) -> f64 {
        match self.eos {
            EosKind::Power => power::j_at(self.k, self.gamma, p),
            EosKind::Tait => tait::j_at(self.k, p),
            EosKind::Linear => linear::j_at(self.k, p),
        }
    }
}

/// U_cut at the effective J `je` from the uncut pressure `p` and energy `u`
/// there, and the cut's corner (f, J_f, U(J_f)). p decreases with J, so
/// max(p(x), f) = p(min(x, J_f)): below J_f the EOS's U (shifted by a
/// constant when f > 0 puts J_f below 1), beyond it the floor's work -f dJ.
#[inline(always)]
fn cut_energy_at((f, jf, u_f): (f64, f64, f64), je: f64, p: f64, u: f64) -> f64 {
    match (f <= 0.0, p >= f) {
        (true, true) => u,
        (true, false) => u_f - f * (je - jf),
        (false, true) => u - u_f - f * (jf - 1.0),
        (false, false) => -f * (je - 1.0),
    }
}
