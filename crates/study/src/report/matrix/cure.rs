//! The Methods table's cure column: one verdict per method, its rule fixed
//! before the runs it judges (docs/physics.md section 7, "The cure column"). A method is
//! compared with the baseline on the same physics case (the same values of
//! every axis that is not a method key), over each case's ensemble members.

use crate::report::data::{ParamKey, Row};
use crate::report::yardsticks::{Verdict, Yardstick};
use monitor::stats::wilson;
use std::collections::BTreeMap;
use study::replay::explain::counterfactual::{rare, reproduced};

/// A case kicks when its members reproduce a kick (`reproduced`); it is
/// kick-free when kicks are rare among them (`rare`) and none blew up.
fn kicks(runs: &[&Row]) -> bool {
    reproduced(runs.iter().filter(|r| kicked(r)).count(), runs.len())
}

fn clean(runs: &[&Row]) -> bool {
    let k = runs.iter().filter(|r| kicked(r)).count();
    let blew = runs
        .iter()
        .any(|r| r.summary.status == study::output::summary::Status::BlewUp);
    !blew && rare(k, runs.len())
}

fn kicked(r: &Row) -> bool {
    r.summary.events.iter().any(|e| e.is_kick())
}

/// What the method did to the baseline's cases.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Paired {
    /// Cases both ran.
    pub cases: usize,
    /// Cases the baseline kicks in (at least 80 % of its members).
    pub baseline_kicks: usize,
    /// Of those, the cases the method runs kick-free (at most 20 % of its
    /// members kicked, none blew up).
    pub prevented: usize,
    /// Cases the baseline runs kick-free and the method kicks in.
    pub introduced: usize,
}

/// The axes that set the physics case: not a method key, nor one a
/// formulation ignores (`ignored.method.*`).
pub fn case_axes(axes: &[ParamKey]) -> Vec<usize> {
    axes.iter()
        .enumerate()
        .filter(|(_, k)| match k {
            ParamKey::Method(_) => false,
            ParamKey::Other(key) => !key.starts_with("ignored."),
            _ => true,
        })
        .map(|(i, _)| i)
        .collect()
}

/// The physics case of a row: its values at the case axes.
fn case_key(row: &Row, case_axes: &[usize]) -> Vec<String> {
    case_axes.iter().map(|&i| row.params[i].clone()).collect()
}

/// The runs by physics case.
fn by_case<'a>(rows: &[&'a Row], case_axes: &[usize]) -> BTreeMap<Vec<String>, Vec<&'a Row>> {
    let mut cases: BTreeMap<Vec<String>, Vec<&Row>> = BTreeMap::new();
    for r in rows {
        cases.entry(case_key(r, case_axes)).or_default().push(*r);
    }
    cases
}

/// The method's runs against the baseline's, case by case.
pub fn paired(case_axes: &[usize], baseline: &[&Row], method: &[&Row]) -> Paired {
    let (base, own) = (by_case(baseline, case_axes), by_case(method, case_axes));
    let mut p = Paired::default();
    for (case, b) in &base {
        let Some(o) = own.get(case) else { continue };
        p.cases += 1;
        if kicks(b) {
            p.baseline_kicks += 1;
            p.prevented += clean(o) as usize;
        } else if clean(b) && kicks(o) {
            p.introduced += 1;
        }
    }
    p
}

/// The cure verdict: the yardsticks name a damper or a pump first; a
/// method that prevents the baseline's kicks in more than half of its
/// kicking cases and brings none into a clean case is a cure when the
/// yardsticks call it accurate (else it is not judged); one that prevents
/// some and brings others moves the event; else no cure.
pub fn verdict(p: Paired, yardstick: Option<&Yardstick>) -> String {
    let [lo, hi] = wilson(p.prevented, p.baseline_kicks);
    let counts = format!(
        "prevents {} of {} [{lo:.2}, {hi:.2}], brings {}",
        p.prevented, p.baseline_kicks, p.introduced
    );
    let named = yardstick.map(|y| y.verdict());
    let name = match named {
        Some(v @ (Verdict::Damper | Verdict::Pump | Verdict::DamperAndPump)) => v.name(),
        _ if p.cases == 0 => "not judged: no case run by both",
        _ if p.baseline_kicks == 0 => "not judged: the baseline does not kick",
        _ if 2 * p.prevented > p.baseline_kicks && p.introduced == 0 => match named {
            None => "not judged: no yardstick",
            Some(Verdict::Accurate) => "cure",
            Some(_) => "not judged: the yardsticks are undecided",
        },
        _ if p.prevented > 0 && p.introduced > 0 => "moves the event",
        _ => "no cure",
    };
    format!("{name} ({counts})")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every yardstick measured: nu_num decided (0.1 nu, uncertainty 0.01
    /// nu, against the damper share 0.25), the sound, the grid scale.
    fn y(energy_growth: f64, sound_excess_rate: f64) -> Yardstick {
        Yardstick {
            nu: Some(1.0),
            nu_num: Some(0.1),
            nu_num_uncertainty: Some(0.01),
            grid_rate: [Some(100.0), None],
            energy_growth: Some(energy_growth),
            sound_excess_rate: Some(sound_excess_rate),
            ..Yardstick::default()
        }
    }

    #[test]
    fn a_cure_prevents_most_kicks_brings_none_and_is_no_damper_or_pump() {
        let p = |prevented, introduced| Paired {
            cases: 5,
            baseline_kicks: 4,
            prevented,
            introduced,
        };
        let quiet = y(0.0, 0.1);
        assert!(verdict(p(3, 0), Some(&quiet)).starts_with("cure (prevents 3 of 4 ["));
        assert!(verdict(p(2, 0), Some(&quiet)).starts_with("no cure"));
        assert!(verdict(p(3, 1), Some(&quiet)).starts_with("moves the event"));
        assert_eq!(quiet.verdict(), Verdict::Accurate);
        assert!(verdict(p(3, 0), None).starts_with("not judged: no yardstick"));
        let unmeasured = Yardstick {
            nu_num: None,
            ..quiet.clone()
        };
        assert!(verdict(p(3, 0), Some(&unmeasured))
            .starts_with("not judged: the yardsticks are undecided"));
        // The yardsticks name what prevents by damping or by pumping.
        assert!(verdict(p(4, 0), Some(&y(0.0, 50.0))).starts_with("damper ("));
        assert!(verdict(p(4, 0), Some(&y(0.5, 0.1))).starts_with("pump ("));
        let none = Paired::default();
        assert!(verdict(none, Some(&quiet)).starts_with("not judged: no case run by both"));
        let clean = Paired {
            cases: 3,
            ..Paired::default()
        };
        let axes = [
            ParamKey::Method("transfer".into()),
            ParamKey::Other("ignored.method.dt".into()),
            ParamKey::Material {
                name: "water".into(),
                field: "K".into(),
            },
            ParamKey::Other("drag.update".into()),
        ];
        assert_eq!(case_axes(&axes), [2, 3], "an ignored method key is no case");
        assert!(verdict(clean, Some(&quiet)).starts_with("not judged: the baseline"));
    }
}
