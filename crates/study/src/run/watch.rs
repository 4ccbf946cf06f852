//! One phase's monitor and the timeseries it feeds, and the summary's
//! figures drawn from them (per phase in a mixture, and for the run).

use super::{RunOptions, Simulated, Stepper};
use crate::output::metrics;
use crate::output::summary::{LossFigures, Metrics, PhaseSummary};
use crate::output::tables;
use crate::output::timeseries::{Peaks, Timeseries};
use monitor::hallmark_log::HallmarkRow;
use monitor::{Monitor, MonitorConfig, StepReport};
use solver::StateView;

pub struct Watch {
    pub monitor: Monitor,
    pub series: Timeseries,
    /// Extremes since the last row.
    peaks: Peaks,
}

impl Watch {
    pub fn new(cfg: MonitorConfig, v: &StateView) -> Self {
        Watch {
            monitor: Monitor::new(cfg, v),
            series: Timeseries::new(),
            peaks: Peaks::default(),
        }
    }

    /// Observes the phase's last step: the events it opened and the
    /// monitor's blow-out reason, if any.
    pub fn observe(&mut self, v: &StateView) -> (usize, Option<String>) {
        // The monitor is serial: keep the other worker awake for the next step.
        let monitor = &mut self.monitor;
        solver::par::keep_warm(|| {
            monitor.observe(v);
        });
        let report = self.monitor.report();
        self.peaks.add(report);
        (report.events_opened, report.blow_out.clone())
    }

    /// Stamps the `n` latest events with the phase (in a mixture), the state
    /// hash and the checkpoint before them; their ids.
    pub fn stamp_latest(
        &mut self,
        n: usize,
        phase: Option<&str>,
        hash: &str,
        checkpoint: Option<&str>,
    ) -> Vec<u32> {
        let total = self.monitor.events().len();
        self.monitor.events_mut()[total - n..]
            .iter_mut()
            .map(|e| {
                if let Some(phase) = phase {
                    e.phase = Some(phase.into());
                }
                e.state_hash = Some(hash.into());
                e.checkpoint = checkpoint.map(Into::into);
                e.id
            })
            .collect()
    }

    /// A timeseries row at the phase's current step (field metrics computed
    /// now); `event_row` when it is written only for an event or the stop.
    pub fn push_row(&mut self, v: &StateView, event_row: bool) {
        let fields = self.monitor.field_metrics(v);
        let report = if v.step == 0 || self.monitor.report().step != v.step {
            // Before the first observed step: energies from the state itself.
            StepReport::of_state(v)
        } else {
            self.monitor.report().clone()
        };
        self.series.push(&report, &self.peaks, &fields, event_row);
        self.peaks.reset();
    }
}

/// Each phase's timeseries table, and the outcome's events, particle count
/// and figures: a mixture's per phase, and the run's (its primary phase's
/// timeseries with every event, and the losses of all phases).
pub(super) fn summarise<S: Stepper>(
    stepper: &S,
    watches: &[Watch],
    opts: &RunOptions,
    completed: bool,
    outcome: &mut Simulated,
) -> std::io::Result<()> {
    let mixture = watches.len() > 1;
    for (k, w) in watches.iter().enumerate() {
        if let Some(dir) = &opts.dir {
            tables::write_timeseries_as(&w.series, dir, &stepper.timeseries_stem(k), opts.csv)?;
            write_hallmark(w.monitor.hallmark_rows(), dir, &stepper.timeseries_stem(k))?;
        }
        let own = w.monitor.events().to_vec();
        outcome.particles += stepper.phase(k).initial_particle_count();
        if mixture {
            let mut m = metrics::summarise(&w.series, &own, completed);
            fill_losses(&mut m, stepper, watches, &[k]);
            outcome.phases.push(PhaseSummary {
                phase: stepper.phase_name(k).unwrap_or_default().into(),
                particles: stepper.phase(k).initial_particle_count(),
                n_events: own.len(),
                metrics: m,
            });
        }
        outcome.events.extend(own);
    }
    if mixture {
        outcome.events.sort_by(|a, b| a.t.total_cmp(&b.t));
    }
    let Some(primary) = watches.get(stepper.primary_phase()) else {
        return Ok(());
    };
    outcome.metrics = metrics::summarise(&primary.series, &outcome.events, completed);
    let all: Vec<usize> = (0..watches.len()).collect();
    fill_losses(&mut outcome.metrics, stepper, watches, &all);
    Ok(())
}

/// The hallmark log (`[monitor] hallmark_log`) as `hallmark.csv` and
/// `.parquet` beside the timeseries (a mixture's phase: its stem's suffix).
fn write_hallmark(rows: &[HallmarkRow], dir: &std::path::Path, stem: &str) -> std::io::Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    let col = |f: fn(&HallmarkRow) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let columns = [
        ("event", col(|r| r.event as f64)),
        ("particle", col(|r| r.particle as f64)),
        ("t", col(|r| r.t)),
        ("speed_factor", col(|r| r.speed_factor)),
        ("quiet_for", col(|r| r.quiet_for)),
        ("peak_rate", col(|r| r.peak_rate)),
        ("peak_rate_t", col(|r| r.peak_rate_t)),
        ("distortion", col(|r| r.distortion)),
    ];
    let refs: Vec<(&str, &[f64])> = columns.iter().map(|(n, v)| (*n, v.as_slice())).collect();
    let name = stem.replacen("timeseries", "hallmark", 1);
    tables::write_columns(&refs, dir, &name, true)
}

/// Dropped events and particles deleted, drained and injected in `phases`,
/// masses as shares of their initial mass.
fn fill_losses<S: Stepper>(m: &mut Metrics, stepper: &S, watches: &[Watch], phases: &[usize]) {
    let losses: Vec<_> = phases.iter().map(|&k| stepper.phase(k).losses()).collect();
    let initial_mass: f64 = phases
        .iter()
        .map(|&k| watches[k].monitor.initial_mass())
        .sum();
    let count = |f: fn(&solver::Losses) -> u64| losses.iter().map(f).sum::<u64>();
    let share = |f: fn(&solver::Losses) -> f64| losses.iter().map(f).sum::<f64>() / initial_mass;
    m.events_dropped = phases
        .iter()
        .map(|&k| watches[k].monitor.events_dropped())
        .sum();
    m.losses = LossFigures {
        particles_escaped: count(|l| l.escaped),
        particles_inverted: count(|l| l.inverted),
        mass_lost_fraction: share(|l| l.mass()),
        t_first_loss: losses.iter().filter_map(|l| l.t_first).reduce(f64::min),
        particles_drained: count(|l| l.drained),
        mass_drained_fraction: share(|l| l.mass_drained),
        particles_injected: count(|l| l.injected),
        mass_injected_fraction: share(|l| l.mass_injected),
    };
}
