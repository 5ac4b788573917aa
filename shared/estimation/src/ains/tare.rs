//! The depth gauge's tare: its offset, measured at the surface where the
//! depth is zero (DESIGN §2; every aided-INS variant uses it).
//!
//! A pressure gauge reads `d̃ = d + d₀ + w`: the offset `d₀` (atmospheric
//! pressure, water density, mounting) is the mean of its readings at the
//! surface. The variant decides when the vehicle is at the surface (for
//! `dr`: a GPS fix within the last second or so, the antenna out of the
//! water, and no vertical motion) and hands those readings to
//! [`DepthTare::push_surface`]; a reading taken below the surface ends the
//! surface session ([`DepthTare::end_session`]). A session averages its
//! readings, the first `n` equally, then each new one with weight `1/n` (a
//! moving average of about `n` readings, so that the readings of the last
//! decimetres of a slow ascent are forgotten once the vehicle floats); the
//! average becomes the offset once the session holds `n` readings, so a
//! new surfacing re-tares the gauge. Until the first session the offset
//! is 0.

/// The tare's state, plain (for a snapshot).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct TareState {
    /// The offset in use `d₀`, m.
    pub offset_m: f64,
    /// Average of the current surface session's readings, m.
    pub session_mean_m: f64,
    /// Readings in the current surface session (0: submerged).
    pub session_count: u64,
}

/// The depth gauge's tare (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct DepthTare {
    samples: u64,
    state: TareState,
}

/// The largest offset a surface session may set, m: a gauge's offset is
/// the atmospheric pressure's change and its mounting (tenths of a metre);
/// a "surface" session that reads metres is not at the surface (a fix taken
/// under way, as A-KIT's imported initial fix at 20 m), and is ignored.
pub const MAX_OFFSET_M: f64 = 2.0;

impl DepthTare {
    /// A tare averaging about `samples` readings (at least 1).
    pub fn new(samples: u64) -> Self {
        Self {
            samples: samples.max(1),
            state: TareState::default(),
        }
    }

    /// A raw reading taken at the surface (true depth zero), m.
    pub fn push_surface(&mut self, raw_m: f64) {
        let s = &mut self.state;
        s.session_count = s.session_count.saturating_add(1);
        let weight = s.session_count.min(self.samples) as f64;
        s.session_mean_m += (raw_m - s.session_mean_m) / weight;
        if s.session_count >= self.samples && s.session_mean_m.abs() <= MAX_OFFSET_M {
            s.offset_m = s.session_mean_m;
        }
    }

    /// The vehicle left the surface: the next surface reading starts a new
    /// session (the offset is kept).
    pub fn end_session(&mut self) {
        self.state.session_count = 0;
        self.state.session_mean_m = 0.0;
    }

    /// The depth of a raw reading, m: `d̃ − d₀`.
    pub fn depth_m(&self, raw_m: f64) -> f64 {
        raw_m - self.state.offset_m
    }

    /// The offset in use, m.
    pub fn offset_m(&self) -> f64 {
        self.state.offset_m
    }

    /// The state.
    pub fn state(&self) -> TareState {
        self.state
    }

    /// Replaces the state (a snapshot's; the caller checks it is finite).
    pub fn set_state(&mut self, state: TareState) {
        self.state = state;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_session_that_reads_metres_is_not_at_the_surface() {
        let mut t = DepthTare::new(3);
        for _ in 0..5 {
            t.push_surface(20.0);
        }
        assert_eq!(t.offset_m(), 0.0);
        assert_eq!(t.depth_m(20.0), 20.0);
    }

    #[test]
    fn the_offset_is_the_surface_mean_and_a_new_surfacing_retares() {
        let mut t = DepthTare::new(3);
        assert_eq!(t.depth_m(3.0), 3.0);
        t.push_surface(0.04);
        t.push_surface(0.06);
        assert_eq!(t.offset_m(), 0.0, "too few readings yet");
        t.push_surface(0.05);
        assert!((t.offset_m() - 0.05).abs() < 1e-15);
        t.end_session();
        assert!(
            (t.depth_m(3.05) - 3.0).abs() < 1e-12,
            "kept while submerged"
        );
        for _ in 0..3 {
            t.push_surface(0.10);
        }
        assert!((t.offset_m() - 0.10).abs() < 1e-15);
        // Later readings move the average with weight 1/3.
        t.push_surface(0.13);
        assert!((t.offset_m() - 0.11).abs() < 1e-15);
    }
}
