//! Each remedy's energy booked in the budget (docs/physics.md section 4).
//! Per step, a remedy's net change (`solver::remedies::RemedyEnergy`) is a
//! removal, booked as that remedy's dissipation and so added back to the
//! total the injection test watches, or an addition, booked as that
//! remedy's injection and left in the total, where the test sees it. The
//! parts another term already holds are taken out of that term: an after-G2P
//! kinetic change (the FLIP/PIC blend) out of the transfer loss, a point
//! rule's work (bulk damping) out of the viscous dissipation.

use serde::Serialize;
use solver::remedies::{RemedyEnergy, REMEDY_KEYS};

/// The registry's remedy count: one slot each, in registry order.
pub const REMEDIES: usize = REMEDY_KEYS.len();

/// One remedy's booking since t = 0 (J per metre of thickness).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Booked {
    /// Sum of its net removals over the steps.
    pub dissipated: f64,
    /// Sum of its net additions over the steps.
    pub injected: f64,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct RemedyBooking {
    /// Per registry slot; None for a remedy the method does not have.
    pub booked: [Option<Booked>; REMEDIES],
    /// Signed sum of the after-G2P kinetic changes (in the measured
    /// transfer loss with the opposite sign).
    after_g2p_kinetic: f64,
    /// Signed sum of the point rules' work changes (in the dissipation with
    /// the opposite sign).
    point_work: f64,
}

impl RemedyBooking {
    /// Books one step's changes.
    pub fn book(&mut self, parts: &[RemedyEnergy]) {
        for e in parts {
            let Some(slot) = REMEDY_KEYS.iter().position(|k| *k == e.key) else {
                debug_assert!(false, "remedy {} not in the registry", e.key);
                continue;
            };
            let b = self.booked[slot].get_or_insert_with(Booked::default);
            let net = e.change.total();
            if net < 0.0 {
                b.dissipated -= net;
            } else {
                b.injected += net;
            }
            self.after_g2p_kinetic += e.after_g2p_kinetic;
            self.point_work += e.point_work;
        }
    }

    /// Every remedy's dissipation.
    pub fn dissipated(&self) -> f64 {
        self.booked
            .iter()
            .flatten()
            .fold(0.0, |s, b| s + b.dissipated)
    }

    /// Every remedy's injection.
    pub fn injected(&self) -> f64 {
        self.booked
            .iter()
            .flatten()
            .fold(0.0, |s, b| s + b.injected)
    }

    /// The measured transfer loss's part that is the remedies' (the
    /// FLIP/PIC blend): the transfer's own loss is the measured one plus
    /// this.
    pub fn in_transfer_loss(&self) -> f64 {
        self.after_g2p_kinetic
    }

    /// What the injection test adds to E + L: the removals, with the parts
    /// the dissipation and, where the budget counts it (all but APIC), the
    /// transfer loss already hold taken out of them.
    pub fn detector_offset(&self, transfer_loss_counted: bool) -> f64 {
        let in_loss = if transfer_loss_counted {
            self.after_g2p_kinetic
        } else {
            0.0
        };
        self.dissipated() + in_loss + self.point_work
    }

    /// The state for checkpoints, as f64s (an absent remedy as NaNs).
    pub fn state(&self) -> Vec<f64> {
        let mut s: Vec<f64> = self
            .booked
            .iter()
            .flat_map(|b| b.map_or([f64::NAN; 2], |b| [b.dissipated, b.injected]))
            .collect();
        s.extend([self.after_g2p_kinetic, self.point_work]);
        s
    }

    /// The length of `state`.
    pub const STATE_LEN: usize = 2 * REMEDIES + 2;

    pub fn restore(&mut self, s: &[f64]) {
        for (b, pair) in self.booked.iter_mut().zip(s.chunks(2)) {
            *b = (!pair[0].is_nan()).then_some(Booked {
                dissipated: pair[0],
                injected: pair[1],
            });
        }
        self.after_g2p_kinetic = s[2 * REMEDIES];
        self.point_work = s[2 * REMEDIES + 1];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use solver::EnergyChange;

    fn part(key: &'static str, change: EnergyChange, kinetic: f64, work: f64) -> RemedyEnergy {
        RemedyEnergy {
            key,
            change,
            after_g2p_kinetic: kinetic,
            point_work: work,
        }
    }

    /// A removal is dissipation, an addition injection; the parts that the
    /// transfer loss and the dissipation hold leave the offset unchanged.
    #[test]
    fn removals_and_additions_are_booked_apart() {
        let mut b = RemedyBooking::default();
        let stored = |x| EnergyChange {
            stored: x,
            ..Default::default()
        };
        b.book(&[part("j_bar", stored(-2.0), 0.0, 0.0)]);
        b.book(&[part("j_bar", stored(0.5), 0.0, 0.0)]);
        let j = REMEDY_KEYS.iter().position(|k| *k == "j_bar").unwrap();
        let expected = Booked {
            dissipated: 2.0,
            injected: 0.5,
        };
        assert_eq!(b.booked[j], Some(expected));
        assert_eq!(b.booked[0], None, "absent remedy");
        assert_eq!(b.detector_offset(true), 2.0);
        // Bulk damping's work is in the dissipation already; the blend's
        // kinetic change in the transfer loss (when it is counted).
        let work = EnergyChange {
            work: -0.25,
            ..Default::default()
        };
        let kinetic = EnergyChange {
            kinetic: -0.125,
            ..Default::default()
        };
        b.book(&[part("bulk_damping", work, 0.0, -0.25)]);
        b.book(&[part("pic_damping", kinetic, -0.125, 0.0)]);
        assert_eq!(b.dissipated(), 2.375);
        assert_eq!(b.detector_offset(true), 2.0);
        assert_eq!(b.in_transfer_loss(), -0.125);
        // Under APIC the transfer loss is not counted: the blend is booked.
        assert_eq!(b.detector_offset(false), 2.125);
        let mut restored = RemedyBooking::default();
        restored.restore(&b.state());
        assert_eq!(restored.state().len(), RemedyBooking::STATE_LEN);
        assert_eq!(restored, b);
    }
}
