//! The normalised-innovation (χ²) gate every aiding measurement passes,
//! against the particles' spread, and its re-anchoring: after
//! `max_rejections` gated measurements of one kind in a row, the next gated
//! one re-anchors the filter on itself, so that a filter that has drifted
//! away (or a sensor that has jumped) cannot be locked out for good.

use super::snapshot::GateStats;

/// What to do with one measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decision {
    /// Weigh the particles with it.
    Use,
    /// Refuse it.
    Gated,
    /// Draw the particles around it.
    Reanchor,
}

/// `d² = Σᵢ νᵢ² / (s²ᵢ + σ²ᵢ)`: the innovations `ν = z − x̂` normalised by
/// the particles' variances `s²` plus the measurement's `σ²` (the
/// components are separate filters, eqs. 13-16: no cross terms).
pub fn normalised_innovation(nu: &[f64], particle_var: &[f64], meas_var: &[f64]) -> f64 {
    nu.iter()
        .zip(particle_var.iter().zip(meas_var))
        .map(|(n, (s, r))| n * n / (s + r))
        .sum()
}

/// The gate's decision for `d2` against `limit` (0: no gate), counted in
/// `stats`.
pub fn decide(stats: &mut GateStats, d2: f64, limit: f64, max_rejections: u32) -> Decision {
    if limit == 0.0 || d2 <= limit {
        stats.used += 1;
        stats.gated_in_a_row = 0;
        return Decision::Use;
    }
    if stats.gated_in_a_row >= max_rejections {
        stats.reanchored += 1;
        stats.gated_in_a_row = 0;
        return Decision::Reanchor;
    }
    stats.gated += 1;
    stats.gated_in_a_row += 1;
    Decision::Gated
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gated_in_a_row_then_reanchored() {
        let mut s = GateStats::default();
        let d2 = normalised_innovation(&[3.0, 4.0], &[0.5, 0.5], &[0.5, 0.5]);
        assert_eq!(d2, 25.0);
        assert_eq!(decide(&mut s, 1.0, 13.8, 2), Decision::Use);
        assert_eq!(decide(&mut s, d2, 13.8, 2), Decision::Gated);
        assert_eq!(decide(&mut s, d2, 13.8, 2), Decision::Gated);
        assert_eq!(decide(&mut s, d2, 13.8, 2), Decision::Reanchor);
        assert_eq!(decide(&mut s, d2, 0.0, 2), Decision::Use, "0: no gate");
        assert_eq!(decide(&mut s, f64::NAN, 13.8, 0), Decision::Reanchor);
        assert_eq!((s.used, s.gated, s.reanchored), (2, 2, 2));
    }
}
