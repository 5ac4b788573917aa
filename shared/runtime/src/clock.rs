//! The run clock (DESIGN §7). Estimators never read it: all their time comes from
//! message stamps. Only sources (the sensor, replay) use it, to decide how fast
//! to publish.

use std::time::{Duration, Instant};

/// How a run's sources pace themselves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ClockMode {
    /// As fast as the pipeline consumes, lossless and deterministic.
    Sim,
    /// Real time times `rate` (1.0 = real time); slow consumers lose data, counted.
    Wall {
        /// Multiple of real time.
        rate: f64,
    },
}

impl ClockMode {
    /// Parses `sim` or `wall` with a rate.
    pub fn parse(name: &str, rate: f64) -> anyhow::Result<Self> {
        match name {
            "sim" => Ok(ClockMode::Sim),
            "wall" if rate.is_finite() && rate > 0.0 => Ok(ClockMode::Wall { rate }),
            "wall" => anyhow::bail!("clock rate must be a positive number, got {rate}"),
            other => anyhow::bail!("unknown clock {other:?}: use \"sim\" or \"wall\""),
        }
    }

    /// True in `sim` mode (lossless delivery).
    pub fn is_lossless(&self) -> bool {
        matches!(self, ClockMode::Sim)
    }

    /// The mode's name.
    pub fn name(&self) -> &'static str {
        match self {
            ClockMode::Sim => "sim",
            ClockMode::Wall { .. } => "wall",
        }
    }
}

/// Paces a source to the wall clock: a message stamped `t` is released at
/// `start + (t - t0) / rate`. In `sim` mode it never waits.
#[derive(Debug, Clone)]
pub struct Pacer {
    mode: ClockMode,
    start: Option<(Instant, u64)>,
}

impl Pacer {
    /// A pacer for `mode`; the first stamp it sees is aligned with "now".
    pub fn new(mode: ClockMode) -> Self {
        Pacer { mode, start: None }
    }

    /// How long to wait before releasing a message stamped `stamp_ns` (zero in `sim`).
    pub fn delay_for(&mut self, stamp_ns: u64) -> Duration {
        let ClockMode::Wall { rate } = self.mode else {
            return Duration::ZERO;
        };
        let (t0, s0) = *self.start.get_or_insert((Instant::now(), stamp_ns));
        let mission = Duration::from_nanos(stamp_ns.saturating_sub(s0));
        let due = t0 + mission.div_f64(rate);
        due.saturating_duration_since(Instant::now())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sim_never_waits_and_wall_paces() {
        let mut p = Pacer::new(ClockMode::Sim);
        assert_eq!(p.delay_for(10_000_000_000), Duration::ZERO);
        let mut w = Pacer::new(ClockMode::Wall { rate: 10.0 });
        assert_eq!(w.delay_for(5_000_000_000), Duration::ZERO);
        // 10 s of mission later at 10x is due about 1 s from the start.
        let d = w.delay_for(15_000_000_000);
        assert!(
            d > Duration::from_millis(900) && d <= Duration::from_secs(1),
            "{d:?}"
        );
        assert!(ClockMode::parse("wall", f64::NAN).is_err());
        assert!(ClockMode::parse("fast", 1.0).is_err());
    }
}
