//! The monitor's memory as checksummed bytes, so a restart from a checkpoint
//! detects the same events bit for bit: particle histories, energy minimum
//! and window, event membership marks and the events themselves. Per-step
//! scratch (cell bins, window statistics, labels) is rebuilt each step.

use crate::events::Event;
use crate::Monitor;
use solver::checkpoint::{decode, encode, unseal, CheckpointError, Reader, Writer};

// 9: B-spline APIC's transfer loss is measured on the grid and added (an
// older checkpoint's sum is the particle measure, which was not).
// A (10): an eleventh remedy (Uintah's artificial viscosity) lengthens the
// per-remedy booking.
// B (11): the events and the step history through the solver's checkpoint
// codec (solver::checkpoint::encode), where bincode wrote them.
// C (12): the velocity-jump rule and the energy ledger (booked terms by
// their net over the window, gravity's stepping term booked).
// D (13): two more remedies (grid-velocity damping, the speed cap)
// lengthen the per-remedy booking.
const MAGIC: &[u8; 8] = b"KICKMOND";

fn encode_events(events: &[Event]) -> Vec<u8> {
    encode(events).expect("events serialise: known lengths, no maps")
}

/// The events `bytes` hold; the codec's codes named as the events' own.
fn decode_events(bytes: &[u8]) -> Result<Vec<Event>, CheckpointError> {
    decode(bytes).map_err(|e| match e {
        CheckpointError::UnknownCode { what, code } => CheckpointError::UnknownCode {
            what: match what {
                "variant" => "event variant",
                "flag" => "event flag",
                "option tag" => "event option tag",
                other => other,
            },
            code,
        },
        other => other,
    })
}

/// The velocity-jump rule's snapshots (at most three), with their
/// positions when the moving rule wrote them.
fn read_snapshots(
    r: &mut Reader,
    positions: bool,
) -> Result<Vec<crate::jump::Snapshot>, CheckpointError> {
    let count = r.u64()?;
    if count > 3 {
        return Err(CheckpointError::Truncated);
    }
    let mut out = vec![];
    for _ in 0..count {
        let t = r.f64()?;
        let n = r.u64()? as usize;
        if n > r.0.len() / 8 {
            return Err(CheckpointError::Truncated);
        }
        let mut ids = vec![0; n];
        r.u32s(&mut ids)?;
        let mut v = vec![solver::Vec2::zeros(); n];
        r.vec2s(&mut v)?;
        let mut x = vec![];
        if positions {
            x.resize(n, solver::Vec2::zeros());
            r.vec2s(&mut x)?;
        }
        out.push(crate::jump::Snapshot { t, ids, v, x });
    }
    Ok(out)
}

impl Monitor {
    /// The monitor's memory as sealed bytes (see the module docs).
    pub fn save_state(&self) -> Vec<u8> {
        let n = self.history.len();
        let mut w = Writer(Vec::with_capacity(64 + n * 64 + self.event_mark.len() * 8));
        w.0.extend_from_slice(MAGIC);
        w.u64(n as u64);
        w.u64(self.event_mark.len() as u64);
        for a in self.history.arrays() {
            w.f64s(a);
        }
        for a in self.history.level_arrays() {
            w.f64s(a);
        }
        w.u32s(&self.event_mark);
        w.f64(self.prev_time);
        let (ledger, run_minimum) = self.ledger.state();
        w.u64(ledger.len() as u64);
        w.f64s(&ledger);
        w.f64(run_minimum);
        w.u64(self.ledger.present_bits() as u64);
        w.f64s(&self.ledger_terms);
        w.f64(self.gravity_stepping);
        w.f64(self.advection_stepping);
        w.f64(self.prev_potential.unwrap_or(f64::NAN));
        w.f64(self.transfer_loss);
        w.f64s(&self.booking.state());
        w.f64(self.initial_total);
        w.u64(self.events_dropped);
        w.bytes(&encode_events(&self.events));
        w.bytes(&encode(&self.steps).expect("step history serialises"));
        if self.cfg.hallmark_log {
            w.bytes(&encode(&self.hallmark_rows).expect("hallmark rows serialise"));
        }
        w.u64(self.jumps.snaps.len() as u64);
        for snap in &self.jumps.snaps {
            w.f64(snap.t);
            w.u64(snap.ids.len() as u64);
            w.u32s(&snap.ids);
            w.vec2s(&snap.v);
            if self.cfg.moving_rule() {
                w.vec2s(&snap.x);
            }
        }
        w.seal()
    }

    /// Restores what `save_state` wrote; the monitor must be built for the same scene and config.
    pub fn restore_state(&mut self, bytes: &[u8]) -> Result<(), CheckpointError> {
        let mut r = Reader(unseal(bytes, MAGIC)?);
        // Particles deleted before the checkpoint leave fewer histories
        // than the scene seeded: the next observation takes the restored
        // solver's ids as they are (without compacting again).
        let n = r.u64()?;
        let ids = self.event_mark.len() as u64;
        if n > ids {
            return Err(CheckpointError::ParticleCount {
                stored: n,
                expected: ids,
            });
        }
        let marks = r.u64()?;
        if marks != ids {
            return Err(CheckpointError::ParticleCount {
                stored: marks,
                expected: ids,
            });
        }
        self.accel_step = None;
        for a in self.history.arrays_mut() {
            a.resize(n as usize, 0.0);
            r.f64s(a)?;
        }
        for a in self.history.level_arrays_mut() {
            a.resize(n as usize, 0.0);
            r.f64s(a)?;
        }
        self.adopt_ids = true;
        r.u32s(&mut self.event_mark)?;
        self.prev_time = r.f64()?;
        let len = r.u64()? as usize;
        if len > r.0.len() / 8 {
            return Err(CheckpointError::Truncated);
        }
        let mut ledger = vec![0.0; len];
        r.f64s(&mut ledger)?;
        let run_minimum = r.f64()?;
        self.ledger
            .restore(&ledger, run_minimum)
            .ok_or(CheckpointError::Truncated)?;
        self.ledger.set_present_bits(r.u64()? as u32);
        r.f64s(&mut self.ledger_terms)?;
        self.gravity_stepping = r.f64()?;
        self.advection_stepping = r.f64()?;
        let potential = r.f64()?;
        self.prev_potential = (!potential.is_nan()).then_some(potential);
        self.transfer_loss = r.f64()?;
        let mut booking = vec![0.0; crate::remedy_booking::RemedyBooking::STATE_LEN];
        r.f64s(&mut booking)?;
        self.booking.restore(&booking);
        self.initial_total = r.f64()?;
        self.events_dropped = r.u64()?;
        let events = decode_events(r.bytes()?)?;
        let steps: crate::step_history::StepHistory = decode(r.bytes()?)?;
        if !steps.is_whole() {
            return Err(CheckpointError::Truncated);
        }
        self.steps = steps;
        if self.cfg.hallmark_log {
            self.hallmark_rows = decode(r.bytes()?)?;
        }
        self.jumps.snaps = read_snapshots(&mut r, self.cfg.moving_rule())?;
        r.finish()?;
        self.events = events;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::{CellRange, DeformedBy, EventKind, Region, Rule};

    fn event(id: u32) -> Event {
        let cells = CellRange::of(1, 2);
        Event {
            id,
            kind: EventKind::EnergyInjection,
            first_step: 3,
            last_step: 4,
            t: -0.0,
            last_t: f64::MIN_POSITIVE / 2.0,
            cells,
            region: Region {
                x_min: f64::NAN,
                y_min: f64::INFINITY,
                x_max: f64::NEG_INFINITY,
                y_max: 1.0 / 3.0,
            },
            extent: cells,
            n_particles: usize::MAX,
            particles: vec![0, u32::MAX],
            peak_accel_g: f64::from_bits(0x7ff8_dead_beef_0001),
            jump_speed: f64::MAX,
            energy_injected: 1e-300,
            courant: 0.1 + 0.2,
            quiescent_before: false,
            deformed_by: vec![DeformedBy::Distortion],
            rules: Rule::InjectionWindow.into(),
            cause: crate::events::Cause::Cfl,
            evidence: crate::events::Evidence {
                courant_before: f64::from_bits(0x7ff8_0000_0000_0002),
                advection_before: -0.0,
                critical_courant: 1.7,
                energy_floor: 5e-324,
                booked_added: Default::default(),
                calm_flow_fraction: 0.5,
                quiescent_fraction: 1.0 / 3.0,
                deformed_fraction: 0.0,
                peak_dev_rate: f64::MAX,
                t_peak_dev_rate: None,
                j_min: Some(-0.0),
                speed_before: 1e-300,
                transfer_jump: f64::INFINITY,
            },
            outcome: crate::events::Outcome::NonFinite,
            state_hash: None,
            checkpoint: Some("ckpt_000004.bin".into()),
            phase: Some("fluid".into()),
        }
    }

    fn bits(e: &Event) -> Vec<u64> {
        let r = &e.region;
        [
            e.t,
            e.last_t,
            r.x_min,
            r.y_min,
            r.x_max,
            r.y_max,
            e.peak_accel_g,
            e.jump_speed,
            e.energy_injected,
            e.courant,
        ]
        .map(f64::to_bits)
        .to_vec()
    }

    #[test]
    fn events_round_trip_bit_for_bit_including_nan_and_infinities() {
        let events = vec![event(1), event(2)];
        let back = decode_events(&encode_events(&events)).unwrap();
        assert_eq!(back.len(), 2);
        for (a, b) in events.iter().zip(&back) {
            assert_eq!(bits(a), bits(b));
            assert_eq!(
                (&a.deformed_by, a.rules, &a.particles, a.n_particles),
                (&b.deformed_by, b.rules, &b.particles, b.n_particles)
            );
            assert_eq!(
                (&a.state_hash, &a.checkpoint),
                (&b.state_hash, &b.checkpoint)
            );
        }
    }

    #[test]
    fn damaged_event_bytes_are_refused() {
        let bytes = encode_events(&[event(1)]);
        for cut in [0, 1, bytes.len() / 2, bytes.len() - 1] {
            assert_eq!(
                decode_events(&bytes[..cut]).unwrap_err(),
                CheckpointError::Truncated,
                "cut at {cut}"
            );
        }
        let mut long = bytes.clone();
        long.extend_from_slice(&[0, 0]);
        assert_eq!(
            decode_events(&long).unwrap_err(),
            CheckpointError::TrailingBytes { count: 2 }
        );
        // Varint layout: [event count, id, kind, ...]: an unknown kind.
        let mut kind = bytes.clone();
        assert_eq!(kind[2], 2, "EnergyInjection");
        kind[2] = 9;
        assert_eq!(
            decode_events(&kind).unwrap_err(),
            CheckpointError::UnknownCode {
                what: "event variant",
                code: 9
            }
        );
    }

    #[test]
    fn snapshots_keep_positions_only_under_the_moving_rule() {
        // The positions are the moving rule's memory alone: without it a
        // snapshot copies none, and the saved state holds none.
        let snaps_of = |moving_window: bool| {
            let cfg = solver::SolverConfig {
                scene: solver::Scene::dam_break(solver::Material::tait(1.5e5)),
                method: solver::Method::baseline(),
                perturb: vec![],
            };
            let mut s = solver::Solver::new(cfg).unwrap();
            let mcfg = crate::MonitorConfig {
                moving_window,
                ..crate::MonitorConfig::default()
            };
            let mut m = Monitor::new(mcfg, &s.view());
            for _ in 0..150 {
                s.step().unwrap();
                m.observe(&s.view());
            }
            (m.jumps.snaps.clone(), m.save_state().len())
        };
        let (plain, plain_bytes) = snaps_of(false);
        let (moving, moving_bytes) = snaps_of(true);
        assert!(plain.len() >= 2, "{} snapshots", plain.len());
        assert!(plain.iter().all(|s| s.x.is_empty() && !s.ids.is_empty()));
        assert!(moving.iter().all(|s| s.x.len() == s.ids.len()));
        let positions: usize = moving.iter().map(|s| 16 * s.x.len()).sum();
        assert_eq!(moving_bytes, plain_bytes + positions);
    }
}
