//! The inputs of the last steps, newest first, for moving the state back to
//! the middle of a round trip ([`crate::lbl::range`]): each entry is the
//! held `a` of eq. 3 over one step.

use serde::{Deserialize, Serialize};

use crate::lbl::model::Basis;

/// Steps kept: 12.8 s at 10 Hz, more than half the round trip of the
/// longest range accepted (9 km: 12 s there and back).
pub const CAPACITY: usize = 128;

/// The held `a` of the last [`CAPACITY`] steps, newest first.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct History {
    bases: std::collections::VecDeque<Basis>,
}

impl History {
    /// Records the `a` that drove the step just taken.
    pub fn push(&mut self, a: Basis) {
        if self.bases.len() == CAPACITY {
            self.bases.pop_back();
        }
        self.bases.push_front(a);
    }

    /// Forgets everything (after a jump over a gap in the inputs).
    pub fn clear(&mut self) {
        self.bases.clear();
    }

    /// How many steps are kept.
    pub fn len(&self) -> usize {
        self.bases.len()
    }

    /// Whether nothing is kept.
    pub fn is_empty(&self) -> bool {
        self.bases.is_empty()
    }

    /// `∫ a dτ` over the last `lag_s` seconds (`lag_s ≥ 0`) of steps of
    /// `period_s`; beyond what is kept the oldest `a` (else `fallback`)
    /// continues.
    pub fn integral(&self, lag_s: f64, period_s: f64, fallback: Basis) -> Basis {
        let mut left = lag_s.max(0.0);
        let mut sum = [0.0; 2];
        let mut last = fallback;
        for a in &self.bases {
            if left <= 0.0 {
                break;
            }
            let dt = left.min(period_s);
            sum[0] += a[0] * dt;
            sum[1] += a[1] * dt;
            left -= dt;
            last = *a;
        }
        if left > 0.0 {
            sum[0] += last[0] * left;
            sum[1] += last[1] * left;
        }
        sum
    }

    /// Whether the history is within its bounds (a snapshot's check).
    pub fn is_valid(&self) -> bool {
        self.bases.len() <= CAPACITY && self.bases.iter().flatten().all(|v| v.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_integral_walks_back_step_by_step() {
        let mut h = History::default();
        h.push([1.0, 0.0]);
        h.push([2.0, 0.0]); // newest
        let i = h.integral(0.15, 0.1, [9.0, 9.0]);
        assert!((i[0] - (0.2 + 0.05)).abs() < 1e-12, "{i:?}");
        // Beyond the history the oldest continues.
        let i = h.integral(0.4, 0.1, [9.0, 9.0]);
        assert!((i[0] - (0.2 + 0.1 + 0.2)).abs() < 1e-12, "{i:?}");
        assert_eq!(
            History::default().integral(1.0, 0.1, [3.0, 1.0]),
            [3.0, 1.0]
        );
        for _ in 0..CAPACITY + 5 {
            h.push([0.0; 2]);
        }
        assert_eq!(h.len(), CAPACITY);
    }
}
