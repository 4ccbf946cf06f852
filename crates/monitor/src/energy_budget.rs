//! Energy budget: the conserved total and the energy injected so far (total
//! minus its running minimum), plus the injection over a short window in
//! seconds compared with the explicit-stepping noise floor
//! (solver::energy::injection_noise_floor). The total the monitor passes in
//! includes the transfer loss accumulated so far (docs/physics.md section 4b).

use crate::step_history::CAPACITY;

#[derive(Clone, Debug)]
pub struct EnergyBudget {
    minimum: f64,
    /// Window length in seconds.
    window: f64,
    /// (time, total) of the last steps (ring of `CAPACITY`).
    t: Vec<f64>,
    recent: Vec<f64>,
    next: usize,
    filled: usize,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Injection {
    /// E(n) - min_{k <= n} E(k).
    pub total: f64,
    /// E(n) - min E(k) over the steps within the window (and the last `CAPACITY`).
    pub window: f64,
}

impl EnergyBudget {
    pub fn new(initial_total: f64, t0: f64, window_seconds: f64) -> Self {
        let mut b = EnergyBudget {
            minimum: initial_total,
            window: window_seconds,
            t: vec![0.0; CAPACITY],
            recent: vec![0.0; CAPACITY],
            next: 0,
            filled: 0,
        };
        b.push(t0, initial_total);
        b
    }

    fn push(&mut self, t: f64, total: f64) {
        self.t[self.next] = t;
        self.recent[self.next] = total;
        self.next = (self.next + 1) % CAPACITY;
        self.filled = (self.filled + 1).min(CAPACITY);
    }

    /// Observes the total at time `t`.
    pub fn observe(&mut self, t: f64, total: f64) -> Injection {
        self.minimum = self.minimum.min(total);
        let start = t - self.window;
        let mut window_min = total;
        // Newest first, back to the window's start.
        for k in 1..=self.filled {
            let i = (self.next + CAPACITY - k) % CAPACITY;
            if self.t[i] < start {
                break;
            }
            window_min = window_min.min(self.recent[i]);
        }
        self.push(t, total);
        Injection {
            total: total - self.minimum,
            window: total - window_min,
        }
    }

    /// State for checkpoints: (minimum, times, totals, next, filled).
    pub fn state(&self) -> (f64, &[f64], &[f64], usize, usize) {
        (self.minimum, &self.t, &self.recent, self.next, self.filled)
    }

    pub fn restore(&mut self, minimum: f64, t: &[f64], recent: &[f64], next: usize, filled: usize) {
        self.minimum = minimum;
        self.t.copy_from_slice(t);
        self.recent.copy_from_slice(recent);
        self.next = next;
        self.filled = filled;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_is_in_seconds_whatever_the_step() {
        for dt in [1e-5f64, 1e-4, 1e-3] {
            let mut b = EnergyBudget::new(1.0, 0.0, 0.005);
            // A dip at t = 0.01, then a steady total: the dip counts while it
            // is within 5 ms, not after.
            let mut t = 0.0f64;
            let mut last = Injection::default();
            while t < 0.02 {
                t += dt;
                let e = if (t - 0.01).abs() < 0.5 * dt {
                    0.5
                } else {
                    1.0
                };
                last = b.observe(t, e);
                if t > 0.01 + 0.5 * dt && t < 0.015 - 1.5 * dt {
                    assert_eq!(last.window, 0.5, "dt {dt} t {t}");
                }
                if t > 0.015 + 1.5 * dt {
                    assert_eq!(last.window, 0.0, "dt {dt} t {t}");
                }
            }
            assert_eq!(last.total, 0.5);
        }
    }
}
