//! Kick events: flagged particles of one step clustered by cell adjacency
//! (8-neighbours), merged with open events nearby in space and time.

use crate::geometry::Geometry;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    Kick,
    BlowOut,
    EnergyInjection,
    NonFinite,
    /// Some particle has J <= 0 or det F <= 0: the run stops there.
    Inversion,
}

impl EventKind {
    /// The kind's name as summaries spell it (its serde name).
    pub fn name(self) -> &'static str {
        match self {
            EventKind::Kick => "kick",
            EventKind::BlowOut => "blow_out",
            EventKind::EnergyInjection => "energy_injection",
            EventKind::NonFinite => "non_finite",
            EventKind::Inversion => "inversion",
        }
    }
}

/// Inclusive cell range.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct CellRange {
    pub i_min: usize,
    pub j_min: usize,
    pub i_max: usize,
    pub j_max: usize,
}

impl CellRange {
    pub fn of(i: usize, j: usize) -> Self {
        CellRange {
            i_min: i,
            j_min: j,
            i_max: i,
            j_max: j,
        }
    }

    pub fn union(&self, o: &CellRange) -> CellRange {
        CellRange {
            i_min: self.i_min.min(o.i_min),
            j_min: self.j_min.min(o.j_min),
            i_max: self.i_max.max(o.i_max),
            j_max: self.j_max.max(o.j_max),
        }
    }

    /// True when the ranges overlap after growing this one by `margin` cells.
    pub fn near(&self, o: &CellRange, margin: usize) -> bool {
        self.i_min <= o.i_max + margin
            && o.i_min <= self.i_max + margin
            && self.j_min <= o.j_max + margin
            && o.j_min <= self.j_max + margin
    }

    pub fn metres(&self, geom: &Geometry) -> Region {
        Region {
            x_min: geom.origin.x + self.i_min as f64 * geom.cell,
            y_min: geom.origin.y + self.j_min as f64 * geom.cell,
            x_max: geom.origin.x + (self.i_max + 1) as f64 * geom.cell,
            y_max: geom.origin.y + (self.j_max + 1) as f64 * geom.cell,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Region {
    pub x_min: f64,
    pub y_min: f64,
    pub x_max: f64,
    pub y_max: f64,
}

/// A detection rule; an event lists the rules that fired.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Rule {
    /// A velocity change the local flow does not share (`jump`).
    VelocityJump,
    InjectionWindow,
    OutsideBox,
    EscapeSpeed,
    NonFinite,
    Inversion,
}

impl Rule {
    /// Every rule, in the order events list them.
    pub const ALL: [Rule; 6] = [
        Rule::VelocityJump,
        Rule::InjectionWindow,
        Rule::OutsideBox,
        Rule::EscapeSpeed,
        Rule::NonFinite,
        Rule::Inversion,
    ];

    /// The rule's name as events spell it (its serde name).
    pub fn name(self) -> &'static str {
        match self {
            Rule::VelocityJump => "velocity_jump",
            Rule::InjectionWindow => "injection_window",
            Rule::OutsideBox => "outside_box",
            Rule::EscapeSpeed => "escape_speed",
            Rule::NonFinite => "non_finite",
            Rule::Inversion => "inversion",
        }
    }

    fn bit(self) -> u32 {
        1 << self as u32
    }
}

/// A set of rules (bit set), serialised as the list of its rules' names in
/// [`Rule::ALL`] order, e.g. `["velocity_jump", "injection_window"]`.
#[derive(Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Rules(u32);

impl std::fmt::Debug for Rules {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_set().entries(self.iter()).finish()
    }
}

impl Rules {
    pub const NONE: Rules = Rules(0);

    pub fn contains(self, r: Rule) -> bool {
        self.0 & r.bit() != 0
    }

    pub fn insert(&mut self, r: Rule) {
        self.0 |= r.bit();
    }

    pub fn union(self, o: Rules) -> Rules {
        Rules(self.0 | o.0)
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    pub fn len(self) -> usize {
        self.0.count_ones() as usize
    }

    /// The rules in the set, in [`Rule::ALL`] order.
    pub fn iter(self) -> impl Iterator<Item = Rule> {
        Rule::ALL.into_iter().filter(move |&r| self.contains(r))
    }

    /// The names of the rules in the set, in [`Rule::ALL`] order.
    pub fn names(self) -> Vec<&'static str> {
        self.iter().map(Rule::name).collect()
    }
}

impl From<Rule> for Rules {
    fn from(r: Rule) -> Self {
        Rules(r.bit())
    }
}

impl FromIterator<Rule> for Rules {
    fn from_iter<I: IntoIterator<Item = Rule>>(rules: I) -> Self {
        rules
            .into_iter()
            .fold(Rules::NONE, |s, r| s.union(r.into()))
    }
}

impl Serialize for Rules {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        // The length up front: the checkpoint codec needs it.
        let mut seq = s.serialize_seq(Some(self.len()))?;
        for r in self.iter() {
            seq.serialize_element(&r)?;
        }
        seq.end()
    }
}

impl<'de> Deserialize<'de> for Rules {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(Vec::<Rule>::deserialize(d)?.into_iter().collect())
    }
}

/// Why an event counts as previously deformed: most of its particles were
/// above `deformed_rate` (strain rate) or `distortion_ratio` (distortion).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DeformedBy {
    StrainRate,
    Distortion,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Event {
    pub id: u32,
    pub kind: EventKind,
    pub first_step: u64,
    pub last_step: u64,
    /// Time of the first step, and of the last.
    pub t: f64,
    pub last_t: f64,
    /// Cells flagged at the first step, and in metres.
    pub cells: CellRange,
    pub region: Region,
    /// Union of the cells flagged over the event.
    pub extent: CellRange,
    pub n_particles: usize,
    /// Ids of the first `max_event_ids` particles flagged.
    pub particles: Vec<u32>,
    /// The largest force-driven acceleration of its flagged particles (in g).
    pub peak_accel_g: f64,
    /// The largest departure of a flagged particle's velocity change from
    /// the local flow's (m/s; `Rule::VelocityJump`).
    pub jump_speed: f64,
    /// The largest energy gain over the injection window (J/m; booked terms
    /// counted by their net over it) while the event was open.
    pub energy_injected: f64,
    /// Effective Courant number at the first step.
    pub courant: f64,
    pub quiescent_before: bool,
    /// Strain rate and/or distortion (in that order); empty when the event
    /// was not previously deformed (see [`Event::previously_deformed`]).
    pub deformed_by: Vec<DeformedBy>,
    pub rules: Rules,
    /// Why it happened, by the tests of docs/physics.md section 4b (the first
    /// that holds); re-judged while the event grows.
    #[serde(default)]
    pub cause: Cause,
    /// The evidence for `cause`.
    #[serde(default)]
    pub evidence: Evidence,
    /// How the run went on: recovered, or stopped while the event was open.
    #[serde(default)]
    pub outcome: Outcome,
    /// Filled in by the study runner.
    pub state_hash: Option<String>,
    pub checkpoint: Option<String>,
    /// The mixture phase it happened in (`solid` or `fluid`); None for one
    /// phase. Filled in by the study runner.
    #[serde(default)]
    pub phase: Option<String>,
}

/// NaN and +inf as f64::MAX, -inf as f64::MIN: JSON has no non-finite
/// numbers (serde_json writes them as null, which does not read back as f64),
/// and a blow-up produces them.
fn finite(v: f64) -> f64 {
    if v.is_nan() || v == f64::INFINITY {
        f64::MAX
    } else if v == f64::NEG_INFINITY {
        f64::MIN
    } else {
        v
    }
}

impl Event {
    /// A copy whose floats JSON can hold (see `finite`); the summary stores this.
    pub fn json_safe(&self) -> Event {
        let mut e = self.clone();
        for v in [
            &mut e.t,
            &mut e.last_t,
            &mut e.peak_accel_g,
            &mut e.jump_speed,
            &mut e.energy_injected,
            &mut e.courant,
            &mut e.region.x_min,
            &mut e.region.y_min,
            &mut e.region.x_max,
            &mut e.region.y_max,
            &mut e.evidence.courant_before,
            &mut e.evidence.advection_before,
            &mut e.evidence.critical_courant,
            &mut e.evidence.energy_floor,
            &mut e.evidence.calm_flow_fraction,
            &mut e.evidence.quiescent_fraction,
            &mut e.evidence.deformed_fraction,
            &mut e.evidence.peak_dev_rate,
            &mut e.evidence.speed_before,
        ] {
            *v = finite(*v);
        }
        for v in [&mut e.evidence.t_peak_dev_rate, &mut e.evidence.j_min]
            .into_iter()
            .flatten()
        {
            *v = finite(*v);
        }
        e
    }

    /// Most of the event's particles were highly deformed before it (by `deformed_by`).
    pub fn previously_deformed(&self) -> bool {
        !self.deformed_by.is_empty()
    }

    /// The seed's trait: quiet before, and highly deformed earlier (by the
    /// strain-rate peak; a large distortion of F only grows in a sloshing
    /// fluid, so it is logged but not part of the hallmark).
    pub fn hallmark(&self) -> bool {
        self.quiescent_before && self.deformed_by.contains(&DeformedBy::StrainRate)
    }

    /// A kick: a burst that is a numerical failure (`inversion`), adds
    /// energy (`injection`) or jumps against a calm local flow (`jump`), as
    /// opposed to time-step instability or physics.
    pub fn is_kick(&self) -> bool {
        matches!(
            self.cause,
            Cause::Inversion | Cause::Injection | Cause::Jump
        )
    }

    /// The kinematic anomaly proper: a kick with the hallmark.
    pub fn is_anomaly(&self) -> bool {
        self.is_kick() && self.hallmark()
    }

    /// Sets `cause` from the kind and the evidence: inversion, then
    /// injection, then cfl (time-step instability must not hide an
    /// injection), then a velocity jump, else impact.
    pub fn classify(&mut self) {
        let e = &self.evidence;
        self.cause = if self.kind == EventKind::Inversion {
            Cause::Inversion
        } else if self.energy_injected > e.energy_floor {
            Cause::Injection
        } else if e.courant_before >= e.critical_courant || e.advection_before >= ADVECTION_LIMIT {
            Cause::Cfl
        } else if self.rules.contains(Rule::VelocityJump) && e.calm_flow_fraction >= 0.5 {
            Cause::Jump
        } else {
            Cause::Impact
        };
    }
}

/// Nodal advective number |v_i| dt / h above which a burst counts as time-step instability.
pub const ADVECTION_LIMIT: f64 = 0.5;

/// Why an event happened (docs/physics.md section 4b).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Cause {
    /// Some particle in the region has J <= 0 (a kick: numerical failure).
    Inversion,
    /// The energy rose above its floor over the injection window while the
    /// event was open (a kick).
    Injection,
    /// The Courant or nodal advective number before onset reached its limit
    /// (time-step instability, reported apart).
    Cfl,
    /// A velocity jump the local flow does not share, adding kinetic energy
    /// (a kick too small for the energy test to see).
    Jump,
    /// None of these: a burst that moves energy without adding any (physics).
    #[default]
    Impact,
}

impl Cause {
    pub const ALL: [Cause; 5] = [
        Cause::Inversion,
        Cause::Injection,
        Cause::Cfl,
        Cause::Jump,
        Cause::Impact,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Cause::Inversion => "inversion",
            Cause::Cfl => "cfl",
            Cause::Injection => "injection",
            Cause::Jump => "jump",
            Cause::Impact => "impact",
        }
    }
}

/// The figures `Event::classify` judges by.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Evidence {
    /// Largest effective Courant number max_p (c_p + |v_p|) dt / h over the
    /// merge window (`merge_seconds`) before onset, onset included.
    pub courant_before: f64,
    /// Largest nodal advective number |v_i| dt / h over the same window.
    pub advection_before: f64,
    /// The shape's critical Courant number (1 linear and uGIMP, 1.7
    /// quadratic, 1.9 cubic B-spline).
    pub critical_courant: f64,
    /// The floor of `Event::energy_injected`: the kinetic energy of the
    /// event's mass m (its particle count times the mean particle mass; the
    /// whole mass for an energy-injection event) at `jump_speed`, 1/2 m u^2,
    /// plus the energy sums' round-off. The same physical scale at every
    /// time step: gravity's stepping term, which a dt-scaled floor only
    /// bounded, is booked exactly.
    pub energy_floor: f64,
    /// The booked terms (a remedy's, the transfer's, the projection's) that
    /// added energy, net, over the injection window while the event was open.
    #[serde(default)]
    pub booked_added: crate::energy_budget::Terms,
    /// The share of the particles flagged at onset whose local flow was
    /// calm (`jump`): a velocity jump is a kick when at least half were.
    #[serde(default)]
    pub calm_flow_fraction: f64,
    /// Hallmark evidence over the particles flagged at onset (docs/physics.md
    /// section 4b): the fraction quiet over `quiet_seconds` before their
    /// burst, and the fraction whose in-plane |dev D| peaked above
    /// `deformed_rate` before that window.
    #[serde(default)]
    pub quiescent_fraction: f64,
    #[serde(default)]
    pub deformed_fraction: f64,
    /// Their largest earlier peak in-plane |dev D| (1/s) and its time.
    #[serde(default)]
    pub peak_dev_rate: f64,
    #[serde(default)]
    pub t_peak_dev_rate: Option<f64>,
    /// Their smallest J and largest speed at the start of the onset step.
    #[serde(default)]
    pub j_min: Option<f64>,
    #[serde(default)]
    pub speed_before: f64,
    /// Their largest transfer jump |v - v_prev - dt a_p| at onset (m/s): the
    /// velocity change the transfer made beside the force-driven one (a kick
    /// can arrive through the transfer).
    #[serde(default)]
    pub transfer_jump: f64,
}

/// How the run went on after an event.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    #[default]
    Recovered,
    /// The run stopped while it was open: particles left the box or passed the escape speed.
    BlowOut,
    /// ... a particle inverted.
    Inverted,
    /// ... the state went non-finite.
    NonFinite,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_names_are_the_serde_names() {
        for kind in [
            EventKind::Kick,
            EventKind::BlowOut,
            EventKind::EnergyInjection,
            EventKind::NonFinite,
            EventKind::Inversion,
        ] {
            assert_eq!(serde_json::to_value(kind).unwrap(), kind.name());
        }
    }

    fn event() -> Event {
        let cells = CellRange::of(3, 4);
        Event {
            id: 7,
            kind: EventKind::Kick,
            first_step: 120,
            last_step: 125,
            t: 0.25,
            last_t: 0.26,
            cells,
            region: Region {
                x_min: 0.03,
                y_min: 0.04,
                x_max: 0.04,
                y_max: 0.05,
            },
            extent: cells.union(&CellRange::of(5, 6)),
            n_particles: 9,
            particles: vec![4, 8, 15],
            peak_accel_g: 120.5,
            jump_speed: 0.31,
            energy_injected: 1e-3,
            courant: 0.2,
            quiescent_before: true,
            deformed_by: vec![DeformedBy::StrainRate, DeformedBy::Distortion],
            rules: [Rule::InjectionWindow, Rule::VelocityJump]
                .into_iter()
                .collect(),
            cause: Cause::Injection,
            evidence: Evidence {
                courant_before: 0.3,
                advection_before: 0.1,
                critical_courant: 1.7,
                energy_floor: 1e-4,
                booked_added: Default::default(),
                calm_flow_fraction: 1.0,
                quiescent_fraction: 0.75,
                deformed_fraction: 0.5,
                peak_dev_rate: 80.0,
                t_peak_dev_rate: Some(0.1),
                j_min: Some(0.97),
                speed_before: 0.02,
                transfer_jump: 0.4,
            },
            outcome: Outcome::Recovered,
            state_hash: Some("00ff".into()),
            checkpoint: None,
            phase: None,
        }
    }

    #[test]
    fn json_lists_rules_and_deformations_by_name() {
        let e = event();
        let json = serde_json::to_value(&e).unwrap();
        assert_eq!(
            json["rules"],
            serde_json::json!(["velocity_jump", "injection_window"])
        );
        assert_eq!(
            json["deformed_by"],
            serde_json::json!(["strain_rate", "distortion"])
        );
        // One stored fact each: no bit set, flag or bookkeeping beside them.
        for key in ["rule_bits", "previously_deformed"] {
            assert!(json.get(key).is_none(), "{key} in {json}");
        }
        let back: Event = serde_json::from_value(json).unwrap();
        assert_eq!(back, e);
    }

    #[test]
    fn summaries_with_the_former_previously_deformed_key_still_read() {
        let mut json = serde_json::to_value(event()).unwrap();
        json["previously_deformed"] = serde_json::json!(true);
        let back: Event = serde_json::from_value(json).unwrap();
        assert!(back.previously_deformed());
    }

    #[test]
    fn previously_deformed_is_a_nonempty_deformed_by() {
        let mut e = event();
        assert!(e.previously_deformed());
        e.deformed_by.clear();
        assert!(!e.previously_deformed());
        let json = serde_json::to_value(&e).unwrap();
        assert_eq!(json["deformed_by"], serde_json::json!([]));
    }

    #[test]
    fn rule_names_are_their_serde_names_in_bit_order() {
        let all: Rules = Rule::ALL.into_iter().collect();
        assert_eq!(all.len(), Rule::ALL.len());
        assert_eq!(
            all.names(),
            [
                "velocity_jump",
                "injection_window",
                "outside_box",
                "escape_speed",
                "non_finite",
                "inversion"
            ]
        );
        for r in Rule::ALL {
            assert_eq!(serde_json::to_value(r).unwrap(), r.name());
            assert_eq!(all.iter().position(|x| x == r), Some(r as usize));
        }
    }

    #[test]
    fn rules_set_operations() {
        let mut rules = Rules::NONE;
        assert!(rules.is_empty() && rules.names().is_empty());
        rules.insert(Rule::EscapeSpeed);
        rules.insert(Rule::EscapeSpeed);
        assert_eq!(rules.len(), 1);
        assert!(rules.contains(Rule::EscapeSpeed) && !rules.contains(Rule::OutsideBox));
        let both = rules.union(Rule::OutsideBox.into());
        assert_eq!(both.names(), ["outside_box", "escape_speed"]);
        assert_eq!(both.union(rules), both);
        assert_eq!(serde_json::to_string(&Rules::NONE).unwrap(), "[]");
        assert_eq!(format!("{both:?}"), "{OutsideBox, EscapeSpeed}");
    }

    #[test]
    fn unknown_rule_names_are_refused() {
        let r: Result<Rules, _> = serde_json::from_str(r#"["velocity_jump", "gut_feeling"]"#);
        assert!(r.is_err());
    }

    #[test]
    fn causes_are_judged_in_order_inversion_injection_cfl_jump_impact() {
        let mut e = event();
        let judge = |e: &mut Event| {
            e.classify();
            e.cause
        };
        assert_eq!(judge(&mut e), Cause::Injection, "energy above its floor");
        e.energy_injected = e.evidence.energy_floor;
        assert_eq!(
            judge(&mut e),
            Cause::Jump,
            "a velocity jump, not above the floor"
        );
        e.rules = Rule::InjectionWindow.into();
        assert_eq!(judge(&mut e), Cause::Impact, "neither");
        e.evidence.advection_before = ADVECTION_LIMIT;
        assert_eq!(judge(&mut e), Cause::Cfl, "nodal advection at its limit");
        e.evidence.advection_before = 0.0;
        e.evidence.courant_before = e.evidence.critical_courant;
        e.energy_injected = 1.0;
        assert_eq!(
            judge(&mut e),
            Cause::Injection,
            "cfl does not hide an injection"
        );
        e.kind = EventKind::Inversion;
        assert_eq!(judge(&mut e), Cause::Inversion, "inversion first");
        assert!(e.is_kick());
        e.kind = EventKind::Kick;
        e.evidence.courant_before = 0.0;
        assert!(judge(&mut e) == Cause::Injection && e.is_kick() && e.is_anomaly());
        e.energy_injected = 0.0;
        e.rules = Rule::VelocityJump.into();
        assert!(judge(&mut e) == Cause::Jump && e.is_kick() && e.is_anomaly());
        e.quiescent_before = false;
        assert!(
            e.is_kick() && !e.is_anomaly(),
            "no hallmark without quiescence"
        );
        let json = serde_json::to_value(&e).unwrap();
        assert_eq!(json["cause"], "jump");
        assert_eq!(json["outcome"], "recovered");
        assert_eq!(json["evidence"]["critical_courant"], 1.7);
    }
}
