//! Precursors of an explained event (docs/physics.md section 4c): over the
//! quiet window before onset, the share of the event's particle-steps that
//! touch a light node (M1), cross a cell line (M2) or are stress outliers
//! (M3), against the same shares in matched quiet regions of the same run:
//! boxes of the event's size in its own rows (so at the same depth),
//! filled with particles, at least `CONTROL_MARGIN` cells from it and away
//! from every other event of the window. Unlike the shares of the burst,
//! they do not count what the kick itself did. Beside the flags, the quiet
//! window's ringing: the mean drift of the particles from the grid's
//! velocity (M4), over sqrt(g H), for the event's particles and the
//! controls'.

use monitor::mechanisms::Flags;
use monitor::CellRange;
use serde::Serialize;

/// Cells between the event's box and a control box.
pub const CONTROL_MARGIN: usize = 3;
/// Control boxes at most.
pub const CONTROLS: usize = 4;
/// A precursor is named when its share exceeds the controls' by this much.
pub const NAMED_EXCESS: f64 = 0.25;

/// The flags counted in the replay.
#[derive(Clone, Copy, Debug, Default)]
pub struct Counts {
    pub quiet_event: Flags,
    pub quiet_control: Flags,
    pub onset_event: Flags,
    pub onset_control: Flags,
    pub quiet_steps: usize,
}

/// M1, M2 and M3's shares of particle-steps.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Fractions {
    pub m1_light_node: f64,
    pub m2_cell_crossing: f64,
    pub m3_stress_outlier: f64,
}

impl Fractions {
    fn of(f: &Flags) -> Self {
        let [m1, m2, m3] = f.fractions();
        Fractions {
            m1_light_node: m1,
            m2_cell_crossing: m2,
            m3_stress_outlier: m3,
        }
    }

    fn named(&self) -> [(&'static str, f64); 3] {
        [
            ("M1 small-mass node", self.m1_light_node),
            ("M2 cell crossing", self.m2_cell_crossing),
            ("M3 stress outlier", self.m3_stress_outlier),
        ]
    }
}

/// explain.json's `precursors`.
#[derive(Clone, Debug, Serialize)]
pub struct Precursors {
    /// Steps of the quiet window counted (the onset window excluded).
    pub quiet_steps: usize,
    pub quiet_event: Fractions,
    pub quiet_control: Fractions,
    /// At the event's first step's P2G: the state the burst started from.
    pub onset_event: Fractions,
    pub onset_control: Fractions,
    pub control_boxes: usize,
    pub control_particles: usize,
    /// The quiet window's mean drift |v_p - sum N v_i| per particle-step
    /// over sqrt(g H) (M4's unit, H the column's height), of the event's
    /// particles and of the controls': ringing the grid does not carry.
    /// Not a flag, so it names no precursor.
    pub ringing_event: f64,
    pub ringing_control: f64,
    /// The precursor whose quiet-window share exceeds the controls' most,
    /// by at least `NAMED_EXCESS`; "none" otherwise, and "no control" when
    /// no matched box was found.
    pub named: String,
    pub excess: f64,
}

impl Precursors {
    /// `gravity_wave` is sqrt(g H) (m/s); 0 without gravity (ringing NaN).
    pub fn new(
        c: &Counts,
        control_boxes: usize,
        control_particles: usize,
        gravity_wave: f64,
    ) -> Self {
        let ringing = |f: &Flags| {
            if gravity_wave > 0.0 {
                f.mean_drift() / gravity_wave
            } else {
                f64::NAN
            }
        };
        let (event, control) = (
            Fractions::of(&c.quiet_event),
            Fractions::of(&c.quiet_control),
        );
        let best = event
            .named()
            .iter()
            .zip(control.named())
            .map(|(&(name, e), (_, k))| (name, e - if k.is_finite() { k } else { 0.0 }))
            .filter(|(_, x)| x.is_finite())
            .fold(
                ("none", f64::NEG_INFINITY),
                |a, b| if b.1 > a.1 { b } else { a },
            );
        Precursors {
            quiet_steps: c.quiet_steps,
            quiet_event: event,
            quiet_control: control,
            onset_event: Fractions::of(&c.onset_event),
            onset_control: Fractions::of(&c.onset_control),
            control_boxes,
            control_particles,
            ringing_event: ringing(&c.quiet_event),
            ringing_control: ringing(&c.quiet_control),
            named: if control_boxes == 0 || c.quiet_control.particles == 0 {
                "no control".into()
            } else if best.1 >= NAMED_EXCESS {
                best.0.into()
            } else {
                "none".into()
            },
            excess: best.1,
        }
    }
}

/// The control boxes: the event's box shifted along its rows, nearest
/// first, inside `cells_x`, with at least half as many `occupied` cells as
/// the event's box (and one), at least `CONTROL_MARGIN` cells from the
/// event and clear of `others` and of each other.
pub fn control_boxes(
    event: CellRange,
    cells_x: usize,
    occupied: impl Fn(usize, usize) -> bool,
    others: &[CellRange],
) -> Vec<CellRange> {
    let width = event.i_max - event.i_min + 1;
    let filled = |b: &CellRange| {
        (b.i_min..=b.i_max)
            .flat_map(|i| (b.j_min..=b.j_max).map(move |j| (i, j)))
            .filter(|&(i, j)| occupied(i, j))
            .count()
    };
    let needed = filled(&event).div_ceil(2).max(1);
    let mut shifts: Vec<i64> = (1..cells_x as i64).flat_map(|s| [s, -s]).collect();
    shifts.sort_by_key(|s| s.abs());
    let mut kept: Vec<CellRange> = vec![];
    for s in shifts {
        if kept.len() == CONTROLS {
            break;
        }
        let i_min = event.i_min as i64 + s;
        if i_min < 0 || i_min as usize + width > cells_x {
            continue;
        }
        let b = CellRange {
            i_min: i_min as usize,
            i_max: i_min as usize + width - 1,
            ..event
        };
        let full = filled(&b) >= needed;
        let clear = !event.near(&b, CONTROL_MARGIN - 1)
            && others.iter().all(|o| !o.near(&b, 1))
            && kept.iter().all(|k| !k.near(&b, 0));
        if full && clear {
            kept.push(b);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    fn range(i_min: usize, i_max: usize) -> CellRange {
        CellRange {
            i_min,
            j_min: 5,
            i_max,
            j_max: 6,
        }
    }

    #[test]
    fn control_boxes_keep_the_rows_the_margin_and_clear_of_other_events() {
        let event = range(10, 11);
        let boxes = control_boxes(event, 40, |_, _| true, &[range(5, 5)]);
        assert_eq!(boxes.len(), CONTROLS);
        for b in &boxes {
            assert_eq!((b.j_min, b.j_max, b.i_max - b.i_min), (5, 6, 1));
            assert!(b.i_min >= 14 || b.i_max + 3 <= 10, "{b:?}");
            assert!(!range(5, 5).near(b, 1), "{b:?}");
        }
        // Nearest first: 3 cells clear on the right, then the left past the other event.
        assert_eq!(boxes[0].i_min, 14);
        // A box needs half the event box's filled cells: here the event's
        // 4 are filled and elsewhere one column in 4 is (2 of 4 cells).
        let some = control_boxes(event, 40, |i, _| (9..=12).contains(&i) || i % 4 == 0, &[]);
        assert!(!some.is_empty());
        let none = control_boxes(
            event,
            40,
            |i, j| (9..=12).contains(&i) || (i % 4 == 0 && j == 5),
            &[],
        );
        assert!(none.is_empty(), "{none:?}");
    }

    #[test]
    fn the_named_precursor_exceeds_its_control_by_the_margin() {
        let flags = |n, l, c, o, drift: f64| Flags {
            particles: n,
            light_node: l,
            crossed: c,
            outlier: o,
            drift_sum: drift * n as f64,
        };
        let counts = Counts {
            quiet_event: flags(100, 80, 10, 5, 0.02),
            quiet_control: flags(400, 40, 40, 0, 0.01),
            ..Counts::default()
        };
        let p = Precursors::new(&counts, 4, 100, 2.0);
        assert_eq!(p.named, "M1 small-mass node");
        assert_eq!(Precursors::new(&counts, 0, 0, 2.0).named, "no control");
        assert!((p.excess - 0.7).abs() < 1e-12);
        // Mean drifts of 0.02 and 0.01 m/s per particle-step, over sqrt(g H) = 2 m/s.
        assert!((p.ringing_event - 0.01).abs() < 1e-15, "{p:?}");
        assert!((p.ringing_control - 0.005).abs() < 1e-15, "{p:?}");
        assert!(Precursors::new(&counts, 4, 100, 0.0).ringing_event.is_nan());
        let counts = Counts {
            quiet_event: flags(100, 20, 10, 5, 0.02),
            ..counts
        };
        assert_eq!(Precursors::new(&counts, 4, 100, 2.0).named, "none");
    }
}
