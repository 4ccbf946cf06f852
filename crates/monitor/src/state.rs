//! The monitor's memory as checksummed bytes, so a restart from a checkpoint
//! detects the same events bit for bit: particle histories, energy minimum
//! and window, event membership marks and the events themselves. Per-step
//! scratch (cell bins, window statistics, labels) is rebuilt each step.

use crate::events::{CellRange, Event, EventKind, Region};
use crate::Monitor;
use solver::checkpoint::{unseal, CheckpointError, Reader, Writer};

const MAGIC: &[u8; 8] = b"KICKMON1";

fn kind_code(k: EventKind) -> u64 {
    match k {
        EventKind::Kick => 0,
        EventKind::BlowOut => 1,
        EventKind::EnergyInjection => 2,
        EventKind::NonFinite => 3,
    }
}

fn kind_of(code: u64) -> Result<EventKind, CheckpointError> {
    Ok(match code {
        0 => EventKind::Kick,
        1 => EventKind::BlowOut,
        2 => EventKind::EnergyInjection,
        3 => EventKind::NonFinite,
        _ => return Err(CheckpointError::Truncated),
    })
}

fn put_cells(w: &mut Writer, c: &CellRange) {
    for v in [c.i_min, c.j_min, c.i_max, c.j_max] {
        w.u64(v as u64);
    }
}

fn get_cells(r: &mut Reader) -> Result<CellRange, CheckpointError> {
    Ok(CellRange {
        i_min: r.u64()? as usize,
        j_min: r.u64()? as usize,
        i_max: r.u64()? as usize,
        j_max: r.u64()? as usize,
    })
}

fn put_strings(w: &mut Writer, v: &[String]) {
    w.u64(v.len() as u64);
    v.iter().for_each(|s| w.str(s));
}

fn get_strings(r: &mut Reader) -> Result<Vec<String>, CheckpointError> {
    let n = r.u64()? as usize;
    (0..n).map(|_| r.str()).collect()
}

fn put_option(w: &mut Writer, s: &Option<String>) {
    w.bool(s.is_some());
    if let Some(s) = s {
        w.str(s);
    }
}

fn get_option(r: &mut Reader) -> Result<Option<String>, CheckpointError> {
    Ok(if r.bool()? { Some(r.str()?) } else { None })
}

fn put_event(w: &mut Writer, e: &Event) {
    w.u64(e.id as u64);
    w.u64(kind_code(e.kind));
    w.u64(e.first_step);
    w.u64(e.last_step);
    w.f64(e.t);
    w.f64(e.last_t);
    put_cells(w, &e.cells);
    w.f64s(&[
        e.region.x_min,
        e.region.y_min,
        e.region.x_max,
        e.region.y_max,
    ]);
    put_cells(w, &e.extent);
    w.u64(e.n_particles as u64);
    w.u64(e.particles.len() as u64);
    w.u32s(&e.particles);
    w.f64s(&[e.peak_accel_g, e.peak_z, e.energy_injected, e.courant]);
    w.bool(e.quiescent_before);
    w.bool(e.previously_deformed);
    put_strings(w, &e.deformed_by);
    put_strings(w, &e.rules);
    put_option(w, &e.state_hash);
    put_option(w, &e.checkpoint);
    w.u64(e.rule_bits as u64);
    w.f64(e.injected_at_open);
}

fn get_event(r: &mut Reader) -> Result<Event, CheckpointError> {
    let id = r.u64()? as u32;
    let kind = kind_of(r.u64()?)?;
    let first_step = r.u64()?;
    let last_step = r.u64()?;
    let t = r.f64()?;
    let last_t = r.f64()?;
    let cells = get_cells(r)?;
    let region = Region {
        x_min: r.f64()?,
        y_min: r.f64()?,
        x_max: r.f64()?,
        y_max: r.f64()?,
    };
    let extent = get_cells(r)?;
    let n_particles = r.u64()? as usize;
    let mut particles = vec![0u32; r.u64()? as usize];
    r.u32s(&mut particles)?;
    Ok(Event {
        id,
        kind,
        first_step,
        last_step,
        t,
        last_t,
        cells,
        region,
        extent,
        n_particles,
        particles,
        peak_accel_g: r.f64()?,
        peak_z: r.f64()?,
        energy_injected: r.f64()?,
        courant: r.f64()?,
        quiescent_before: r.bool()?,
        previously_deformed: r.bool()?,
        deformed_by: get_strings(r)?,
        rules: get_strings(r)?,
        state_hash: get_option(r)?,
        checkpoint: get_option(r)?,
        rule_bits: r.u64()? as u32,
        injected_at_open: r.f64()?,
    })
}

impl Monitor {
    /// The monitor's memory as sealed bytes (see the module docs).
    pub fn save_state(&self) -> Vec<u8> {
        let n = self.event_mark.len();
        let mut w = Writer(Vec::with_capacity(64 + n * 56));
        w.0.extend_from_slice(MAGIC);
        w.u64(n as u64);
        let h = &self.history;
        w.f64s(&h.ke_recent);
        w.i64s(&h.last_fast_step);
        w.i64s(&h.last_deformed_step);
        w.f64s(&h.max_dev_rate);
        w.i64s(&h.max_dev_rate_step);
        w.u32s(&self.event_mark);
        let (minimum, recent, next, filled) = self.energy.state();
        w.f64(minimum);
        w.u64(recent.len() as u64);
        w.f64s(recent);
        w.u64(next as u64);
        w.u64(filled as u64);
        w.f64(self.prev_injected);
        w.u64(self.events_dropped);
        w.u64(self.events.len() as u64);
        self.events.iter().for_each(|e| put_event(&mut w, e));
        w.seal()
    }

    /// Restores what `save_state` wrote; the monitor must be built for the same scene and config.
    pub fn restore_state(&mut self, bytes: &[u8]) -> Result<(), CheckpointError> {
        let mut r = Reader(unseal(bytes, MAGIC)?);
        let n = r.u64()?;
        let expected = self.event_mark.len() as u64;
        if n != expected {
            return Err(CheckpointError::ParticleCount {
                stored: n,
                expected,
            });
        }
        self.accel_step = None;
        let h = &mut self.history;
        r.f64s(&mut h.ke_recent)?;
        r.i64s(&mut h.last_fast_step)?;
        r.i64s(&mut h.last_deformed_step)?;
        r.f64s(&mut h.max_dev_rate)?;
        r.i64s(&mut h.max_dev_rate_step)?;
        r.u32s(&mut self.event_mark)?;
        let minimum = r.f64()?;
        let mut recent = vec![0.0; r.u64()? as usize];
        if recent.len() != self.energy.state().1.len() {
            return Err(CheckpointError::Truncated);
        }
        r.f64s(&mut recent)?;
        let next = r.u64()? as usize;
        let filled = r.u64()? as usize;
        self.energy.restore(minimum, &recent, next, filled);
        self.prev_injected = r.f64()?;
        self.events_dropped = r.u64()?;
        let events = r.u64()? as usize;
        self.events = (0..events)
            .map(|_| get_event(&mut r))
            .collect::<Result<_, _>>()?;
        if !r.is_empty() {
            return Err(CheckpointError::Truncated);
        }
        Ok(())
    }
}
