//! The yardsticks a damper cannot pass (docs/physics.md section 7), per
//! method, for the Methods table: from viscous-decay cases (Taylor-Green,
//! `checks.mode_decay`) the fluid's viscosity as the method sees it
//! (nu_phys, mode 1), the method's own dissipation nu_num and beta (least
//! squares over the modes' inviscid rates: rate / (2 k^2) = nu_num +
//! beta k^2, with how far nu_num is from certain); from slosh
//! cases (`checks.slosh`) the period error and the decay ratio at the
//! viscous run; from surge-front cases (`checks.surge_front`, the viscous
//! run on a free-slip floor) the early error after the best time shift and
//! the late front speed; from sound-wave cases (`checks.sound_wave`) the
//! frequency error and the excess decay as a viscosity; from the
//! Taylor-Green modes near k h = pi/4 and pi/2 the measured dissipation at
//! the grid scale (also at 15 MPa); from every inviscid yardstick
//! (`checks.energy_gain`) the growth of the motion's energy and the energy
//! the booked terms moved. All at the reference point h = 1 cm, K = 1.5 MPa. A method
//! is the same method in every study when its resolved `method.*` settings
//! and `scene.ppc` are.

use crate::report::data::{Matrix, Row};
use std::collections::BTreeMap;
use study::output::summary::{Status, Summary};
use study::run::probes::energy_gain::EnergyGainFigures;
use study::run::probes::mode_decay::ModeDecayFigures;
use study::run::probes::slosh::SloshFigures;
use study::run::probes::sound_wave::SoundWaveFigures;
use study::run::probes::surge_front::SurgeFrontFigures;

/// The reference point of the Methods table's yardsticks.
pub const CELL: f64 = 0.01;
pub const BULK_MODULUS: f64 = 1.5e6;
/// A method whose own dissipation exceeds this share of the fluid's
/// viscosity is a damper.
pub const DAMPER_SHARE: f64 = 0.25;
/// The stiffer water of the grid-scale figures (Pa).
pub const STIFF_BULK_MODULUS: f64 = 1.5e7;
/// nu_num and beta are fitted over the Taylor-Green modes up to this one;
/// the higher modes (k h near pi/4 and pi/2) are read as measured.
pub const FIT_MODES_UP_TO: u64 = 3;
/// The verdict's rules, fixed before the runs they judge (docs/physics.md
/// section 7). A *sound damper*: the mode-1 sound wave's excess decay rate
/// above this (1/s): it loses 63 % of its amplitude within a second, the
/// dam break's time scale (the modern baseline: 0.14 /s).
pub const SOUND_DAMPER_RATE: f64 = 1.0;
/// A *grid-scale damper*: the inviscid Taylor-Green mode at k h = pi/4
/// decays faster than this (1/s) at the reference point, twice the modern
/// baseline's 692 /s (measured before the rule was fixed).
pub const GRID_DAMPER_RATE: f64 = 1384.0;
pub use study::run::probes::energy_gain::{CYCLING_SHARE, PUMP_SHARE};
/// The test of the mode fit moves every rate by this share.
const RATE_SHIFT: f64 = 0.01;
/// A mode whose projection comes back above this share after its fit
/// swings rather than decays: it has no decay rate.
const SWINGS_BACK: f64 = 0.5;

/// One method's yardstick figures (None where not measured).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Yardstick {
    /// The fluid's kinematic viscosity of the viscous runs (m^2/s).
    pub nu: Option<f64>,
    pub nu_phys: Option<f64>,
    pub nu_num: Option<f64>,
    pub beta: Option<f64>,
    /// How far nu_num is from certain (m^2/s): the larger of its movement
    /// when the rates move by 1 % in alternating senses and, with three
    /// modes or more, its movement when the highest mode is left out (the
    /// line's model error).
    pub nu_num_uncertainty: Option<f64>,
    pub slosh_period_error: Option<f64>,
    pub slosh_decay_ratio: Option<f64>,
    pub surge_early_shifted: Option<f64>,
    pub surge_speed_late: Option<f64>,
    /// The inviscid mode-1 sound wave: frequency error, and its excess
    /// decay as a rate (1/s) and as a viscosity (m^2/s); the excess
    /// viscosity at k h = pi/4.
    pub sound_frequency_error: Option<f64>,
    pub sound_excess_rate: Option<f64>,
    pub sound_excess_nu: Option<f64>,
    pub sound_excess_nu_pi4: Option<f64>,
    /// What the mode-1 sound keeps after a period, and that period (s):
    /// the sound rule's reading of a wave gone before it has a rate.
    pub sound_kept: Option<(f64, f64)>,
    /// The inviscid Taylor-Green decay rates (1/s) at k h = pi/4 and pi/2,
    /// at the reference K and at `STIFF_BULK_MODULUS`.
    pub grid_rate: [Option<f64>; 2],
    pub grid_rate_stiff: [Option<f64>; 2],
    /// Their wavenumbers (1/m).
    pub grid_k: [Option<f64>; 2],
    /// The largest growth of the motion's energy (over 5 s, or over any
    /// 1 s) over the inviscid yardsticks, as a share of the wave's, and the
    /// largest energy the booked terms cycled (the smaller of what they
    /// added and removed) over the wave's.
    pub energy_growth: Option<f64>,
    pub booked_cycled: Option<f64>,
}

/// What a method is, by the yardsticks' rules.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Damper,
    Pump,
    DamperAndPump,
    Accurate,
    Undecided,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Damper => "damper",
            Verdict::Pump => "pump",
            Verdict::DamperAndPump => "damper and pump",
            Verdict::Accurate => "accurate",
            Verdict::Undecided => "undecided",
        }
    }
}

impl Yardstick {
    /// The reasons it damps: nu_num's rule, the sound's, the grid scale's.
    pub fn damps(&self) -> Vec<&'static str> {
        let mut why = vec![];
        if self.is_damper() == Some(true) {
            why.push("nu_num");
        }
        let gone_fast = || {
            self.sound_kept
                .is_some_and(|(kept, period)| kept < (-SOUND_DAMPER_RATE * period).exp())
        };
        let sound = match self.sound_excess_rate {
            Some(r) => r > SOUND_DAMPER_RATE,
            None => gone_fast(),
        };
        if sound {
            why.push("sound");
        }
        if self.grid_rate[0].is_some_and(|r| r > GRID_DAMPER_RATE) {
            why.push("grid scale");
        }
        why
    }

    pub fn is_pump(&self) -> Option<bool> {
        self.energy_growth.map(|g| g > PUMP_SHARE)
    }

    pub fn is_cycling(&self) -> Option<bool> {
        self.booked_cycled.map(|m| m > CYCLING_SHARE)
    }

    /// Damper by any rule, pump by the energy's growth; accurate only when
    /// every rule was measured and none fired (nu_num's decided).
    pub fn verdict(&self) -> Verdict {
        let damper = !self.damps().is_empty();
        match (damper, self.is_pump()) {
            (true, Some(true)) => Verdict::DamperAndPump,
            (true, _) => Verdict::Damper,
            (false, Some(true)) => Verdict::Pump,
            (false, Some(false))
                if self.is_damper() == Some(false)
                    && self.sound_excess_rate.is_some()
                    && self.grid_rate[0].is_some() =>
            {
                Verdict::Accurate
            }
            _ => Verdict::Undecided,
        }
    }

    /// nu_num exceeds `DAMPER_SHARE` of the fluid's viscosity by more than
    /// its uncertainty (Some(true)), or falls short of it by more
    /// (Some(false)); None when unmeasured or when nu_num +- its
    /// uncertainty straddles the share (undecided at this h).
    pub fn is_damper(&self) -> Option<bool> {
        let (nu_num, u) = (self.nu_num?, self.nu_num_uncertainty?);
        let limit = DAMPER_SHARE * self.nu?;
        if nu_num - u > limit {
            Some(true)
        } else if nu_num + u <= limit {
            Some(false)
        } else {
            None
        }
    }
}

/// Yardsticks by method identity (`method_id`).
#[derive(Clone, Debug, Default)]
pub struct Yardsticks {
    pub by_method: BTreeMap<String, Yardstick>,
}

/// A method's identity across studies (`summary::method_id`).
pub fn method_id(s: &Summary) -> String {
    study::output::summary::method_id(&s.params)
}

fn param(s: &Summary, suffix: &str) -> Option<f64> {
    s.params
        .iter()
        .find(|(k, _)| k.ends_with(suffix))
        .and_then(|(_, v)| v.as_f64())
}

/// `v` is `x` to round-off.
fn near(v: Option<f64>, x: f64) -> bool {
    v.is_some_and(|v| (v / x - 1.0).abs() < 1e-9)
}

/// At the reference cell and K (a case with no K is at it; K = "inf" is not).
fn at_reference(s: &Summary) -> bool {
    let k = s
        .params
        .iter()
        .find(|(k, _)| k.ends_with(".K"))
        .map(|(_, v)| v);
    near(param(s, "scene.cell"), CELL) && k.is_none_or(|k| near(k.as_f64(), BULK_MODULUS))
}

/// At the reference cell with the stiffer water.
fn at_stiff(s: &Summary) -> bool {
    near(param(s, "scene.cell"), CELL) && near(param(s, ".K"), STIFF_BULK_MODULUS)
}

/// 0 for k h near pi/4, 1 near pi/2 (within 10 %), else None.
fn grid_slot(kh: f64) -> Option<usize> {
    let near = |x: f64| (kh / x - 1.0).abs() < 0.1;
    let quarter = std::f64::consts::FRAC_PI_4;
    (0..2).find(|&i| near(quarter * (i + 1) as f64))
}

fn viscous(s: &Summary) -> bool {
    param(s, ".viscosity").is_some_and(|mu| mu > 0.0)
}

/// No wall is no-slip (the surge front's free-slip floor).
fn free_slip(s: &Summary) -> bool {
    s.params
        .get("scene.no_slip")
        .and_then(|v| v.as_array())
        .is_none_or(|walls| walls.is_empty())
}

/// The mode number of a case's initial flow (its first body's).
fn mode(s: &Summary) -> Option<u64> {
    let bodies: Vec<solver::Body> =
        serde_json::from_value(s.params.get("scene.body")?.clone()).ok()?;
    bodies.first()?.flow?.mode().map(u64::from)
}

impl Yardsticks {
    /// The yardsticks of the completed reference-point cases among `rows`
    /// (and the grid-scale figures of the stiffer water's).
    pub fn of(rows: &[Row]) -> Self {
        let mut decay: BTreeMap<String, ModeRates> = BTreeMap::new();
        let mut y = Yardsticks::default();
        for s in rows.iter().map(|r| &r.summary) {
            if s.status != Status::Completed {
                continue;
            }
            let id = method_id(s);
            if at_stiff(s) {
                y.grid_figures(&id, s, true);
                continue;
            }
            if !at_reference(s) {
                continue;
            }
            if viscous(s) {
                let nu = param(s, ".viscosity")
                    .zip(param(s, ".rho0"))
                    .map(|(m, r)| m / r);
                y.by_method.entry(id.clone()).or_default().nu = nu;
            }
            y.grid_figures(&id, s, false);
            y.sound_and_energy(&id, s);
            if let (Some(c), Some(m)) = (s.metrics.check::<ModeDecayFigures>(), mode(s)) {
                let rate = c.rate.filter(|_| c.later_max_ratio <= SWINGS_BACK);
                if m <= FIT_MODES_UP_TO {
                    decay
                        .entry(id)
                        .or_default()
                        .insert((m, viscous(s)), (rate, c.k));
                }
            } else if let Some(c) = s.metrics.check::<SloshFigures>() {
                if viscous(s) {
                    let entry = y.by_method.entry(id).or_default();
                    entry.slosh_period_error = c.period_error;
                    entry.slosh_decay_ratio = c.decay_ratio;
                }
            } else if let Some(c) = s.metrics.check::<SurgeFrontFigures>() {
                if viscous(s) && free_slip(s) {
                    let entry = y.by_method.entry(id).or_default();
                    entry.surge_early_shifted = c.rms_error_early_shifted;
                    entry.surge_speed_late = c.speed_late;
                }
            }
        }
        for (id, modes) in decay {
            let entry = y.by_method.entry(id).or_default();
            fit_decay(entry, &modes);
        }
        y
    }

    /// An inviscid Taylor-Green mode near k h = pi/4 or pi/2: its rate.
    fn grid_figures(&mut self, id: &str, s: &Summary, stiff: bool) {
        let Some(c) = s.metrics.check::<ModeDecayFigures>() else {
            return;
        };
        let Some(slot) = grid_slot(c.k * CELL).filter(|_| !viscous(s)) else {
            return;
        };
        let e = self.by_method.entry(id.to_string()).or_default();
        let rates = if stiff {
            &mut e.grid_rate_stiff
        } else {
            &mut e.grid_rate
        };
        rates[slot] = c.rate;
        e.grid_k[slot] = Some(c.k);
    }

    /// The inviscid sound wave's figures, and every inviscid yardstick's
    /// energy growth and booked terms (the largest over the yardsticks).
    fn sound_and_energy(&mut self, id: &str, s: &Summary) {
        let (sound, gain) = (
            s.metrics.check::<SoundWaveFigures>(),
            s.metrics.check::<EnergyGainFigures>(),
        );
        if viscous(s) || (sound.is_none() && gain.is_none()) {
            return;
        }
        let e = self.by_method.entry(id.to_string()).or_default();
        if let Some(c) = sound {
            if mode(s) == Some(1) {
                e.sound_frequency_error = c.frequency_error;
                e.sound_excess_rate = c.decay_rate.map(|r| r - c.decay_theory);
                e.sound_excess_nu = c.excess_viscosity;
                e.sound_kept = c.kept_after_period.map(|k| (k, c.period_theory_s));
            } else if grid_slot(c.kh) == Some(0) {
                e.sound_excess_nu_pi4 = c.excess_viscosity;
            }
        }
        if let Some(g) = gain {
            let growth = g.largest_growth();
            e.energy_growth = larger(e.energy_growth, growth);
            e.booked_cycled = larger(e.booked_cycled, Some(g.booked_cycled()));
        }
    }

    /// The yardsticks of a matrix's own cases and of its reference rows
    /// (`kick report --yardsticks`), its own first.
    pub fn of_matrix(m: &Matrix) -> Self {
        Yardsticks::of(&m.rows).merged(Yardsticks::of(&m.reference_rows))
    }

    pub fn is_empty(&self) -> bool {
        self.by_method.is_empty()
    }

    /// The yardsticks of the method that ran `s`, if any were measured.
    pub fn of_method(&self, s: &Summary) -> Option<&Yardstick> {
        self.by_method.get(&method_id(s))
    }

    /// Both sets, `other`'s figures filling what this one lacks (the energy
    /// figures: the larger of the two).
    pub fn merged(mut self, other: Yardsticks) -> Self {
        for (id, o) in other.by_method {
            let e = self.by_method.entry(id).or_default();
            let fill = |a: &mut Option<f64>, b: Option<f64>| *a = a.or(b);
            fill(&mut e.nu, o.nu);
            fill(&mut e.nu_phys, o.nu_phys);
            fill(&mut e.nu_num, o.nu_num);
            fill(&mut e.beta, o.beta);
            fill(&mut e.nu_num_uncertainty, o.nu_num_uncertainty);
            fill(&mut e.slosh_period_error, o.slosh_period_error);
            fill(&mut e.slosh_decay_ratio, o.slosh_decay_ratio);
            fill(&mut e.surge_early_shifted, o.surge_early_shifted);
            fill(&mut e.surge_speed_late, o.surge_speed_late);
            fill(&mut e.sound_frequency_error, o.sound_frequency_error);
            fill(&mut e.sound_excess_rate, o.sound_excess_rate);
            fill(&mut e.sound_excess_nu, o.sound_excess_nu);
            fill(&mut e.sound_excess_nu_pi4, o.sound_excess_nu_pi4);
            e.sound_kept = e.sound_kept.or(o.sound_kept);
            for i in 0..2 {
                fill(&mut e.grid_rate[i], o.grid_rate[i]);
                fill(&mut e.grid_rate_stiff[i], o.grid_rate_stiff[i]);
                fill(&mut e.grid_k[i], o.grid_k[i]);
            }
            // The energy figures are the largest over every yardstick.
            e.energy_growth = larger(e.energy_growth, o.energy_growth);
            e.booked_cycled = larger(e.booked_cycled, o.booked_cycled);
        }
        self
    }
}

/// The larger of two optional figures (either alone if the other is None).
fn larger(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    a.into_iter().chain(b).reduce(f64::max)
}

/// A method's decay rate (None: no rate) and wavenumber by (mode, viscous).
type ModeRates = BTreeMap<(u64, bool), (Option<f64>, f64)>;

/// nu_phys from mode 1's viscous and inviscid rates; nu_num and beta by
/// least squares over every mode's inviscid rate (exact through two), only
/// when mode 1 has a rate (an intercept from the small scales alone is an
/// extrapolation), and nu_num's uncertainty: the larger of its movement
/// when the rates move by 1 % and, from three modes, when the highest mode
/// is left out (at h = 1 cm the J remedies' intercept moves from 0.55 nu
/// through modes 1-3 to 0.12 nu through modes 1-2: rate / (2 k^2) is not a
/// line in k^2 there, and 1 % on the rates does not show it).
fn fit_decay(y: &mut Yardstick, modes: &ModeRates) {
    let rate = |m: u64, v: bool| modes.get(&(m, v)).and_then(|r| r.0.map(|x| (x, r.1)));
    let Some((a, k)) = rate(1, false) else {
        return;
    };
    if let Some((b, _)) = rate(1, true) {
        y.nu_phys = Some((b - a) / (2.0 * k * k));
    }
    let rates: Vec<(f64, f64)> = modes
        .iter()
        .filter(|((_, v), _)| !v)
        .filter_map(|(_, r)| r.0.map(|x| (x, r.1)))
        .collect();
    let Some((beta, nu_num)) = line_of(&rates, 0.0) else {
        return;
    };
    y.beta = Some(beta);
    y.nu_num = Some(nu_num);
    let mut moved: Vec<f64> = [RATE_SHIFT, -RATE_SHIFT]
        .iter()
        .map(|&e| line_of(&rates, e).map_or(f64::INFINITY, |l| l.1))
        .collect();
    if rates.len() >= 3 {
        let lower = &rates[..rates.len() - 1];
        moved.push(line_of(lower, 0.0).map_or(f64::INFINITY, |l| l.1));
    }
    y.nu_num_uncertainty = Some(
        moved
            .iter()
            .fold(0.0, |m: f64, n| m.max((n - nu_num).abs())),
    );
}

/// (beta, nu_num) of rate / (2 k^2) = nu_num + beta k^2 over (rate, k),
/// each rate moved by `shift` in alternating senses.
fn line_of(rates: &[(f64, f64)], shift: f64) -> Option<(f64, f64)> {
    let points: Vec<(f64, f64)> = rates
        .iter()
        .enumerate()
        .map(|(i, &(r, k))| {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            (k * k, r * (1.0 + sign * shift) / (2.0 * k * k))
        })
        .collect();
    study::output::metrics::line_fit(&points)
}

/// Taylor-Green cases at the reference point, for tests of the sections
/// that show the yardsticks.
#[cfg(test)]
pub mod test_rows {
    use super::*;
    use serde_json::json;
    use study::output::summary::{Metrics, SCHEMA_VERSION};

    pub fn summary(method: &str, mode: u64, mu: f64, check: impl FnOnce(&mut Metrics)) -> Row {
        let mut metrics = Metrics::default();
        check(&mut metrics);
        let params = BTreeMap::from([
            ("method.transfer".to_string(), json!(method)),
            ("method.j_bar".to_string(), json!(true)),
            ("method.j_bar.fit".to_string(), json!("linear")),
            ("scene.ppc".to_string(), json!(2)),
            ("scene.cell".to_string(), json!(0.01)),
            ("materials.water.K".to_string(), json!(1.5e6)),
            ("materials.water.rho0".to_string(), json!(1000.0)),
            ("materials.water.viscosity".to_string(), json!(mu)),
            (
                "scene.body".to_string(),
                json!([{
                    "rect": [0.0, 0.0, 0.2, 0.2],
                    "flow": { "kind": "taylor_green", "amplitude": 0.01, "mode": mode },
                }]),
            ),
        ]);
        let s = Summary {
            schema_version: SCHEMA_VERSION,
            case: format!("{method}_m{mode}_mu{mu}"),
            params,
            status: Status::Completed,
            reason: String::new(),
            steps: 1,
            t_end: 1.0,
            wall_s: 1.0,
            particles: 1,
            particle_steps_per_s: 1.0,
            final_state_hash: "0".into(),
            events: vec![],
            metrics,
            phases: vec![],
        };
        Row::for_test(s, vec![])
    }

    pub fn decay(rate: f64, k: f64, later: f64) -> impl FnOnce(&mut Metrics) {
        move |m| {
            m.set_check(&ModeDecayFigures {
                k,
                rate: Some(rate),
                later_max_ratio: later,
                ..Default::default()
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::test_rows::{decay, summary};
    use super::*;
    use serde_json::json;

    /// Rates made from nu_num = 1e-4, beta = 1e-6 and nu = 5e-4 give those
    /// back; a damper is named; a mode that swings back gives no rate.
    #[test]
    fn the_decay_rates_give_nu_num_beta_and_nu_phys_back() {
        let (nu_num, beta, nu) = (1e-4, 1e-6, 5e-4);
        let (k1, k2) = (15.0, 30.0);
        let rate = |k: f64, nu_fluid: f64| 2.0 * k * k * (nu_num + beta * k * k + nu_fluid);
        let rows = vec![
            summary("apic", 1, 0.0, decay(rate(k1, 0.0), k1, 0.01)),
            summary("apic", 2, 0.0, decay(rate(k2, 0.0), k2, 0.01)),
            summary("apic", 1, 0.5, decay(rate(k1, nu), k1, 0.01)),
            summary("flip", 1, 0.0, decay(1.0, k1, 0.99)),
            summary("flip", 2, 0.0, decay(2.0, k2, 0.01)),
        ];
        let y = Yardsticks::of(&rows);
        let apic = y.of_method(&rows[0].summary).expect("measured");
        assert!(
            (apic.nu_num.unwrap() / nu_num - 1.0).abs() < 1e-9,
            "{apic:?}"
        );
        assert!((apic.beta.unwrap() / beta - 1.0).abs() < 1e-9, "{apic:?}");
        assert!((apic.nu_phys.unwrap() / nu - 1.0).abs() < 1e-9, "{apic:?}");
        assert_eq!(apic.nu, Some(5e-4));
        assert_eq!(apic.is_damper(), Some(false));
        // Through two modes, 1 % on the rates moves nu_num by
        // (2 k1^2 k2^2 / (k2^2 - k1^2)) (r1 / k1^2 + r2 / k2^2) 0.01 / 2.
        let (y1, y2) = (rate(k1, 0.0) / (k1 * k1), rate(k2, 0.0) / (k2 * k2));
        let expected = 0.01 * (y1 * k2 * k2 + y2 * k1 * k1) / (k2 * k2 - k1 * k1) / 2.0;
        let moved = apic.nu_num_uncertainty.unwrap();
        assert!(
            (moved / expected - 1.0).abs() < 1e-6,
            "{moved} vs {expected}"
        );
        let flip = y.of_method(&rows[3].summary).expect("measured");
        assert_eq!(flip.nu_num, None, "mode 1 swings back: one rate only");
        // Three modes on the line: the same figures by least squares.
        let k3 = 45.0;
        let three = vec![
            summary("apic", 1, 0.0, decay(rate(k1, 0.0), k1, 0.01)),
            summary("apic", 2, 0.0, decay(rate(k2, 0.0), k2, 0.01)),
            summary("apic", 3, 0.0, decay(rate(k3, 0.0), k3, 0.01)),
        ];
        let y3 = Yardsticks::of(&three);
        let apic = y3.of_method(&three[0].summary).unwrap();
        assert!(
            (apic.nu_num.unwrap() / nu_num - 1.0).abs() < 1e-9,
            "{apic:?}"
        );
        assert!((apic.beta.unwrap() / beta - 1.0).abs() < 1e-9, "{apic:?}");
    }

    /// The inviscid rates measured at h = 1 cm (docs/findings/yardsticks.md):
    /// J-bar's rate / (2 k^2) bends over modes 1-3, so its intercept
    /// (0.55 nu through three modes, 0.12 nu through two) is uncertain by
    /// their difference and straddles 0.25 nu: undecided. The baseline's
    /// (1.74 nu, 1.94 nu through two) is a damper whichever modes.
    #[test]
    fn a_bending_mode_line_leaves_the_verdict_undecided() {
        let nu = 5e-4;
        let k = |m: f64| m * std::f64::consts::PI / 0.2;
        let method = |name: &str, rates: [f64; 3]| {
            let mut rows: Vec<Row> = (1..=3)
                .map(|m| {
                    summary(
                        name,
                        m,
                        0.0,
                        decay(rates[m as usize - 1], k(m as f64), 0.01),
                    )
                })
                .collect();
            let viscous = rates[0] + 2.0 * k(1.0) * k(1.0) * nu;
            rows.push(summary(name, 1, 0.5, decay(viscous, k(1.0), 0.01)));
            let y = Yardsticks::of(&rows);
            y.of_method(&rows[0].summary).unwrap().clone()
        };
        let j_bar = method("j_bar", [1.29, 20.28, 98.97]);
        let (n, u) = (
            j_bar.nu_num.unwrap() / nu,
            j_bar.nu_num_uncertainty.unwrap() / nu,
        );
        assert!((n - 0.554).abs() < 0.002, "{n}");
        // The line through modes 1-2 alone: 0.122 nu.
        assert!((n - u - 0.122).abs() < 0.002, "{n} - {u}");
        assert_eq!(j_bar.is_damper(), None);
        let base = method("base", [1.639, 20.48, 99.86]);
        let (n, u) = (
            base.nu_num.unwrap() / nu,
            base.nu_num_uncertainty.unwrap() / nu,
        );
        assert!(
            (n - 1.739).abs() < 0.002 && (u - 0.201).abs() < 0.002,
            "{n} {u}"
        );
        assert_eq!(base.is_damper(), Some(true));
        assert!((base.nu_phys.unwrap() / nu - 1.0).abs() < 1e-9);
    }

    /// The verdict's rules: accurate with every figure measured and none
    /// over its line; a damper by the sound or by the grid scale whatever
    /// its nu_num; a pump by the motion's growth; undecided without the
    /// grid-scale figure; and the higher modes stay out of the nu_num fit.
    #[test]
    fn each_rule_decides_the_verdict_it_names() {
        use study::output::summary::Metrics;
        let k = |m: f64| m * std::f64::consts::PI / 0.2;
        let tg = |rate: f64, m: u64| {
            move |x: &mut Metrics| {
                x.set_check(&ModeDecayFigures {
                    k: k(m as f64),
                    rate: Some(rate),
                    later_max_ratio: 0.01,
                    ..Default::default()
                })
            }
        };
        let method = |name: &str, sound_rate: f64, grid: Option<f64>, growth: f64| {
            let mut rows = vec![
                summary(name, 1, 0.0, tg(2.0 * k(1.0).powi(2) * 1e-5, 1)),
                summary(name, 2, 0.0, tg(2.0 * k(2.0).powi(2) * 1.2e-5, 2)),
                summary(name, 1, 0.5, tg(2.0 * k(1.0).powi(2) * 5.1e-4, 1)),
                summary(name, 1, 0.0, move |x: &mut Metrics| {
                    x.set_check(&SoundWaveFigures {
                        k: k(1.0),
                        kh: k(1.0) * CELL,
                        frequency_error: Some(-0.003),
                        decay_rate: Some(sound_rate),
                        excess_viscosity: Some(sound_rate / (2.0 / 3.0 * k(1.0).powi(2))),
                        ..Default::default()
                    });
                    x.set_check(&EnergyGainFigures {
                        wave_energy: 1.0,
                        growth: Some(growth),
                        largest_growth_1s: Some(growth.max(0.0)),
                        ..Default::default()
                    });
                }),
            ];
            if let Some(rate) = grid {
                rows.push(summary(name, 5, 0.0, tg(rate, 5)));
            }
            let y = Yardsticks::of(&rows);
            y.of_method(&rows[0].summary).unwrap().clone()
        };
        let accurate = method("apic", 0.14, Some(692.0), -0.3);
        assert_eq!(accurate.grid_rate[0], Some(692.0));
        assert!(
            (accurate.nu_num.unwrap() / 1e-5 - 1.0).abs() < 0.5,
            "{accurate:?}"
        );
        assert_eq!(accurate.verdict(), Verdict::Accurate, "{accurate:?}");
        let sound = method("av", 4.8, Some(700.0), -0.3);
        assert_eq!(
            (sound.verdict(), sound.damps()),
            (Verdict::Damper, vec!["sound"])
        );
        let grid = method("pic", 0.1, Some(20000.0), -0.9);
        assert_eq!(
            (grid.verdict(), grid.damps()),
            (Verdict::Damper, vec!["grid scale"])
        );
        assert_eq!(
            method("pump", 0.1, Some(600.0), 0.05).verdict(),
            Verdict::Pump
        );
        assert_eq!(
            method("both", 5.0, Some(600.0), 0.05).verdict(),
            Verdict::DamperAndPump
        );
        assert_eq!(
            method("unknown", 0.1, None, -0.3).verdict(),
            Verdict::Undecided
        );
        // A sound gone before it has a rate: what it keeps after a period.
        let gone = |kept: f64| Yardstick {
            sound_excess_rate: None,
            sound_kept: Some((kept, 0.0103)),
            ..accurate.clone()
        };
        assert_eq!(gone(0.05).damps(), vec!["sound"]);
        assert!(gone(0.999).damps().is_empty());
    }

    /// `j_bar = true` beside its settings is the same method as the
    /// settings alone; another setting is another method.
    #[test]
    fn a_method_is_known_by_its_resolved_settings() {
        let a = summary("apic", 1, 0.0, |_| {});
        let mut b = a.summary.clone();
        b.params.remove("method.j_bar");
        assert_eq!(method_id(&a.summary), method_id(&b));
        b.params
            .insert("method.j_bar.fit".into(), json!("constant"));
        assert_ne!(method_id(&a.summary), method_id(&b));
    }
}
