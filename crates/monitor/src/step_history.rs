//! The last few thousand steps' Courant and nodal advective numbers, so an
//! event can be judged on the window *before* its onset (a kick caught a few
//! steps late has already raised |v| itself).

use serde::{Deserialize, Serialize};

/// Steps remembered: 0.01 s at the smallest fixed step of the bug-report
/// matrix (15 MPa, h = 1 cm, CFL 0.2: dt = 1.6e-5 s) is about 600 steps.
pub const CAPACITY: usize = 4096;

/// A ring of (time, Courant number, nodal advective number), one per step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepHistory {
    t: Vec<f64>,
    courant: Vec<f64>,
    advection: Vec<f64>,
    next: usize,
    filled: usize,
}

impl Default for StepHistory {
    fn default() -> Self {
        StepHistory {
            t: vec![0.0; CAPACITY],
            courant: vec![0.0; CAPACITY],
            advection: vec![0.0; CAPACITY],
            next: 0,
            filled: 0,
        }
    }
}

impl StepHistory {
    pub fn push(&mut self, t: f64, courant: f64, advection: f64) {
        self.t[self.next] = t;
        self.courant[self.next] = courant;
        self.advection[self.next] = advection;
        self.next = (self.next + 1) % CAPACITY;
        self.filled = (self.filled + 1).min(CAPACITY);
    }

    /// The ring's shape is whole (a restored one must be, or pushing would panic).
    pub fn is_whole(&self) -> bool {
        [&self.t, &self.courant, &self.advection]
            .iter()
            .all(|v| v.len() == CAPACITY)
            && self.next < CAPACITY
            && self.filled <= CAPACITY
    }

    /// The largest Courant and advective numbers of the remembered steps at
    /// or after `since` (0 when there are none).
    pub fn max_since(&self, since: f64) -> (f64, f64) {
        let (mut c, mut a) = (0.0f64, 0.0f64);
        for k in 0..self.filled {
            if self.t[k] >= since {
                c = c.max(self.courant[k]);
                a = a.max(self.advection[k]);
            }
        }
        (c, a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_holds_the_steps_since_a_time_and_forgets_the_oldest() {
        let mut h = StepHistory::default();
        assert_eq!(h.max_since(0.0), (0.0, 0.0));
        for k in 0..CAPACITY + 10 {
            let x = k as f64;
            h.push(x, x, 2.0 * x);
        }
        let last = (CAPACITY + 9) as f64;
        assert_eq!(h.max_since(last), (last, 2.0 * last));
        assert_eq!(h.max_since(last + 1.0), (0.0, 0.0));
        // The ring forgot the first ten steps: a window reaching back to them
        // still gives the remembered maximum.
        assert_eq!(h.max_since(-1.0), (last, 2.0 * last));
        let mut g = StepHistory::default();
        g.push(0.0, 3.0, 0.1);
        g.push(1.0, 1.0, 0.4);
        assert_eq!(g.max_since(0.5), (1.0, 0.4));
        assert_eq!(g.max_since(0.0), (3.0, 0.4));
    }
}
