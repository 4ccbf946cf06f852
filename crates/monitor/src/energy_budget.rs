//! Energy budget: the conserved total and the energy injected so far (total
//! minus its running minimum), plus the injection over a short window compared
//! with the explicit-stepping noise floor (solver::energy::injection_noise_floor).

#[derive(Clone, Debug)]
pub struct EnergyBudget {
    minimum: f64,
    /// Totals of the last `window` steps (ring).
    recent: Vec<f64>,
    next: usize,
    filled: usize,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Injection {
    /// E(n) - min_{k <= n} E(k).
    pub total: f64,
    /// E(n) - min over the window.
    pub window: f64,
}

impl EnergyBudget {
    pub fn new(initial_total: f64, window: usize) -> Self {
        EnergyBudget {
            minimum: initial_total,
            recent: vec![initial_total; window.max(1)],
            next: 0,
            filled: 1,
        }
    }

    pub fn observe(&mut self, total: f64) -> Injection {
        self.minimum = self.minimum.min(total);
        let window_min = self.recent[..self.filled]
            .iter()
            .copied()
            .fold(total, f64::min);
        self.recent[self.next] = total;
        self.next = (self.next + 1) % self.recent.len();
        self.filled = (self.filled + 1).min(self.recent.len());
        Injection {
            total: total - self.minimum,
            window: total - window_min,
        }
    }

    /// State for checkpoints: (minimum, ring, next, filled).
    pub fn state(&self) -> (f64, &[f64], usize, usize) {
        (self.minimum, &self.recent, self.next, self.filled)
    }

    pub fn restore(&mut self, minimum: f64, recent: &[f64], next: usize, filled: usize) {
        self.minimum = minimum;
        self.recent.copy_from_slice(recent);
        self.next = next;
        self.filled = filled;
    }
}
