//! The energy ledger the injection test reads (docs/physics.md section 4b).
//! The *base* is the total the method does not book: the kinetic,
//! gravitational and stored energies and the viscous dissipation, with
//! gravity's stepping term booked
//! exactly (the position update's potential change against gravity's work
//! at the time-centred velocity). Each *booked term* (the transfer's loss
//! where the budget counts it, each remedy, the projection and the
//! hourglass control of the pressure-implicit step) keeps its cumulative
//! net removal. The gain over a window is the base's rise plus each term's
//! net removal over it, credited only when the term removed energy, net: a
//! term that adds energy stays visible, and a sign-noisy term that adds
//! and removes alike counts for nothing.

use crate::remedy_booking::REMEDIES;
use crate::step_history::CAPACITY;
use serde::{Deserialize, Serialize};
use solver::remedies::REMEDY_KEYS;

/// The booked terms: the transfer, the projection, the hourglass control,
/// the advection (positions moved other than by the particles' velocity),
/// then the remedies in registry order.
pub const TERMS: usize = FIRST_REMEDY + REMEDIES;
pub const TRANSFER: usize = 0;
pub const PROJECTION: usize = 1;
pub const HOURGLASS: usize = 2;
pub const ADVECTION: usize = 3;
pub const FIRST_REMEDY: usize = 4;
// Terms are a bit set in a u32.
const _: () = assert!(TERMS <= 32);

/// A booked term's name as events spell it.
pub fn term_name(k: usize) -> &'static str {
    match k {
        TRANSFER => "transfer",
        PROJECTION => "projection",
        HOURGLASS => "hourglass",
        ADVECTION => "advection",
        _ => REMEDY_KEYS[k - FIRST_REMEDY],
    }
}

/// A set of booked terms, serialised as their names.
#[derive(Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Terms(u32);

impl Terms {
    pub fn insert(&mut self, k: usize) {
        self.0 |= 1 << k;
    }

    pub fn contains(self, k: usize) -> bool {
        self.0 & (1 << k) != 0
    }

    pub fn union(self, o: Terms) -> Terms {
        Terms(self.0 | o.0)
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    pub fn names(self) -> Vec<&'static str> {
        (0..TERMS)
            .filter(|&k| self.contains(k))
            .map(term_name)
            .collect()
    }
}

impl std::fmt::Debug for Terms {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_set().entries(self.names()).finish()
    }
}

impl Serialize for Terms {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        let names = self.names();
        let mut seq = s.serialize_seq(Some(names.len()))?;
        for n in names {
            seq.serialize_element(n)?;
        }
        seq.end()
    }
}

impl<'de> Deserialize<'de> for Terms {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let mut t = Terms::default();
        for name in Vec::<String>::deserialize(d)? {
            let k = (0..TERMS)
                .find(|&k| term_name(k) == name)
                .ok_or_else(|| serde::de::Error::custom(format!("unknown booked term {name:?}")))?;
            t.insert(k);
        }
        Ok(t)
    }
}

/// One step of the ledger: the base and each term's cumulative net removal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry {
    pub t: f64,
    pub base: f64,
    pub terms: [f64; TERMS],
}

/// What a window gained, and the terms that added energy over it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Gain {
    pub gain: f64,
    pub added: Terms,
}

/// The ledger: the last steps within the window (a ring of `CAPACITY`),
/// the terms the method has, and the whole run's credited total and its
/// running minimum (the pump figure).
#[derive(Clone, Debug)]
pub struct Ledger {
    pub window: f64,
    pub present: Terms,
    ring: Vec<Entry>,
    next: usize,
    filled: usize,
    /// The run's credited total's running minimum.
    pub run_minimum: f64,
}

impl Ledger {
    pub fn new(window: f64, first: Entry) -> Self {
        let mut l = Ledger {
            window,
            present: Terms::default(),
            ring: vec![first; CAPACITY],
            next: 0,
            filled: 0,
            run_minimum: first.base,
        };
        l.push(first);
        l
    }

    fn push(&mut self, e: Entry) {
        self.ring[self.next] = e;
        self.next = (self.next + 1) % CAPACITY;
        self.filled = (self.filled + 1).min(CAPACITY);
    }

    /// The credit of entry `now` over entry `then`: each present term's net
    /// removal between them where it is a removal; the terms that added.
    fn credit(&self, now: &Entry, then: &Entry) -> (f64, Terms) {
        let (mut credit, mut added) = (0.0, Terms::default());
        for k in (0..TERMS).filter(|&k| self.present.contains(k)) {
            let net = now.terms[k] - then.terms[k];
            if net > 0.0 {
                credit += net;
            } else if net < 0.0 {
                added.insert(k);
            }
        }
        (credit, added)
    }

    /// Records a step; the largest gain over the window ending now (against
    /// each earlier step within it), with the terms that added over that
    /// stretch, and the run's credited gain (the credited total now over its
    /// running minimum).
    pub fn observe(&mut self, now: Entry) -> (Gain, f64) {
        let mut best = Gain::default();
        for k in 1..=self.filled {
            let then = self.ring[(self.next + CAPACITY - k) % CAPACITY];
            if then.t < now.t - self.window {
                break;
            }
            let (credit, added) = self.credit(&now, &then);
            let gain = now.base - then.base + credit;
            if gain > best.gain {
                best = Gain { gain, added };
            }
        }
        let whole = now.base + (0..TERMS).map(|k| now.terms[k].max(0.0)).sum::<f64>();
        self.run_minimum = self.run_minimum.min(whole);
        self.push(now);
        (best, whole - self.run_minimum)
    }

    /// The present terms as bits (for checkpoints).
    pub fn present_bits(&self) -> u32 {
        self.present.0
    }

    pub fn set_present_bits(&mut self, bits: u32) {
        self.present = Terms(bits);
    }

    /// State for checkpoints: the entries within the window as f64s (oldest
    /// first; the newest's own window is all a later step reads), and the
    /// run minimum.
    pub fn state(&self) -> (Vec<f64>, f64) {
        let newest = self.ring[(self.next + CAPACITY - 1) % CAPACITY].t;
        let within = (1..=self.filled)
            .take_while(|&k| {
                self.ring[(self.next + CAPACITY - k) % CAPACITY].t >= newest - self.window
            })
            .count();
        let mut out = Vec::with_capacity(within * (2 + TERMS));
        for k in (1..=within).rev() {
            let e = &self.ring[(self.next + CAPACITY - k) % CAPACITY];
            out.push(e.t);
            out.push(e.base);
            out.extend_from_slice(&e.terms);
        }
        (out, self.run_minimum)
    }

    /// Restores what `state` gave (`None` when its length is not whole entries).
    pub fn restore(&mut self, flat: &[f64], run_minimum: f64) -> Option<()> {
        let width = 2 + TERMS;
        if !flat.len().is_multiple_of(width) || flat.len() / width > CAPACITY {
            return None;
        }
        self.filled = 0;
        self.next = 0;
        for c in flat.chunks(width) {
            let mut terms = [0.0; TERMS];
            terms.copy_from_slice(&c[2..]);
            self.push(Entry {
                t: c[0],
                base: c[1],
                terms,
            });
        }
        self.run_minimum = run_minimum;
        Some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(t: f64, base: f64, term: f64) -> Entry {
        let mut terms = [0.0; TERMS];
        terms[PROJECTION] = term;
        Entry { t, base, terms }
    }

    #[test]
    fn the_window_is_in_seconds_whatever_the_step() {
        for dt in [1e-5f64, 1e-4, 1e-3] {
            let mut l = Ledger::new(0.005, entry(0.0, 1.0, 0.0));
            // A dip at t = 0.01, then a steady base: it counts while it is
            // within 5 ms, not after.
            let mut t = 0.0f64;
            while t < 0.02 {
                t += dt;
                let e = if (t - 0.01).abs() < 0.5 * dt {
                    0.5
                } else {
                    1.0
                };
                let (g, _) = l.observe(entry(t, e, 0.0));
                if t > 0.01 + 0.5 * dt && t < 0.015 - 1.5 * dt {
                    assert_eq!(g.gain, 0.5, "dt {dt} t {t}");
                }
                if t > 0.015 + 1.5 * dt {
                    assert_eq!(g.gain, 0.0, "dt {dt} t {t}");
                }
            }
        }
    }

    #[test]
    fn a_term_counts_by_its_net_over_the_window() {
        let mut l = Ledger::new(0.01, entry(0.0, 1.0, 0.0));
        l.present.insert(PROJECTION);
        // The term removes 0.1 from the base: credited, no gain.
        let (g, _) = l.observe(entry(0.001, 0.9, 0.1));
        assert!(g.gain.abs() < 1e-12, "{g:?}");
        // It puts 0.3 back (net addition 0.2 since t = 0, 0.3 over the last
        // step): not credited, the gain shows; the run's gain is the net 0.2.
        let (g, run) = l.observe(entry(0.002, 1.2, -0.2));
        assert!((g.gain - 0.3).abs() < 1e-12 && g.added.names() == ["projection"]);
        assert!((run - 0.2).abs() < 1e-12);
        // A term alternating +-0.05 a step, with the base mirroring it: the
        // window sees at most one half-cycle, however long it runs, where
        // crediting each step's removal would ratchet up by 0.05 every two
        // steps; the run's credited total stays flat.
        let mut l = Ledger::new(0.01, entry(0.0, 1.0, 0.0));
        l.present.insert(PROJECTION);
        let (mut worst, mut worst_run): (f64, f64) = (0.0, 0.0);
        for k in 1..1000 {
            let c = if k % 2 == 1 { 0.05 } else { 0.0 };
            let (g, run) = l.observe(entry(k as f64 * 1e-4, 1.0 - c, c));
            worst = worst.max(g.gain);
            worst_run = worst_run.max(run);
        }
        assert!(
            worst <= 0.05 + 1e-12 && worst_run < 1e-12,
            "{worst} {worst_run}"
        );
    }

    #[test]
    fn terms_read_back_by_name() {
        let mut t = Terms::default();
        t.insert(HOURGLASS);
        t.insert(FIRST_REMEDY);
        let json = serde_json::to_string(&t).unwrap();
        assert_eq!(json, format!("[\"hourglass\",\"{}\"]", REMEDY_KEYS[0]));
        let back: Terms = serde_json::from_str(&json).unwrap();
        assert_eq!(back, t);
        assert!(serde_json::from_str::<Terms>("[\"hunch\"]").is_err());
    }
}
