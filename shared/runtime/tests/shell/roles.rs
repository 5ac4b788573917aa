//! The test roles: a 1-D position tracker and the relay of the wiring cycle.

use nauta_estimation::readings::{Depth, Imu, LblNav, Nav};
use nauta_estimation::{Estimator, EstimatorError, Stamped};
use nauta_messages::*;
use nauta_runtime::{Shell, services};

/// Position at t seconds, m.
pub fn truth_x(t: f64) -> f64 {
    20.0 + 5.0 * (0.2 * t).sin()
}

pub const IMU_DT_NS: u64 = 10_000_000; // 100 Hz
pub const DEPTH_EVERY: u64 = 20; // 5 Hz
pub const SIGMA_V: f64 = 0.05;
pub const SIGMA_X: f64 = 0.2;

/// splitmix64, for seeded Gaussian noise without a dependency.
pub struct Noise(pub u64);
impl Noise {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn gauss(&mut self) -> f64 {
        let (u1, u2) = (self.uniform().max(1e-300), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

// ---- the minimal role ----------------------------------------------------

#[derive(Debug, Clone, Copy)]
pub enum TrackIn {
    Velocity(Imu),
    Position(Depth),
    Relayed(LblNav),
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackOut {
    pub stamp_ns: u64,
    pub x: f64,
    pub std: f64,
}
impl Stamped for TrackOut {
    fn stamp_ns(&self) -> u64 {
        self.stamp_ns
    }
}

/// A 1-D Kalman filter: velocity integrated at 100 Hz, position fixes at 5 Hz.
#[derive(Debug, Clone)]
pub struct Tracker {
    x: f64,
    p: f64,
    skip_until: Option<u64>,
}

impl Tracker {
    /// Starts at 0 with a σ of 10 m (the truth is near 20 m): a cold start
    /// shows in the published σ for seconds.
    pub fn cold() -> Self {
        Tracker {
            x: 0.0,
            p: 100.0,
            skip_until: None,
        }
    }
    fn update(&mut self, z: f64, r: f64) -> Result<(), EstimatorError> {
        if !(-100.0..=100.0).contains(&z) {
            return Err(EstimatorError::new("implausible-position", z));
        }
        let k = self.p / (self.p + r);
        self.x += k * (z - self.x);
        self.p *= 1.0 - k;
        Ok(())
    }
}

impl Estimator for Tracker {
    type Input = TrackIn;
    type Output = TrackOut;
    type Snapshot = (f64, f64);

    fn on_input(&mut self, i: &TrackIn, out: &mut Vec<TrackOut>) -> Result<(), EstimatorError> {
        let stamp = match i {
            TrackIn::Velocity(m) => m.stamp_ns,
            TrackIn::Position(d) => d.stamp_ns,
            TrackIn::Relayed(l) => l.stamp_ns,
        };
        if self.skip_until.is_some_and(|s| stamp <= s) {
            return Ok(());
        }
        match i {
            TrackIn::Velocity(m) => {
                self.x += m.accel_m_s2[0] * m.interval_s;
                self.p += (SIGMA_V * m.interval_s).powi(2);
                out.push(TrackOut {
                    stamp_ns: stamp,
                    x: self.x,
                    std: self.p.sqrt(),
                });
            }
            TrackIn::Position(d) => self.update(d.depth_m, SIGMA_X * SIGMA_X)?,
            TrackIn::Relayed(l) => self.update(l.x_m, l.p[0][0])?,
        }
        Ok(())
    }

    fn snapshot(&self) -> Option<(f64, f64)> {
        Some((self.x, self.p))
    }

    fn restore(&mut self, s: &(f64, f64), stamp_ns: u64) -> Result<(), EstimatorError> {
        (self.x, self.p) = *s;
        self.skip_until = Some(stamp_ns);
        Ok(())
    }
}

pub fn nav_of(o: &TrackOut) -> Option<NavSolution> {
    Some(NavSolution {
        header: Header::new(o.stamp_ns, 0, Role::Ains, 0),
        depth_m: o.x,
        pos_std_ned_m: [0.0, 0.0, o.std],
        ..Default::default()
    })
}
/// The tracker's (x, p) in the ains snapshot message's opaque state words
/// (the message is the one the test's `ains` role has).
pub fn snapshot_of(s: &(f64, f64), stamp_ns: u64) -> AinsSnapshot {
    let mut m = AinsSnapshot {
        header: Header::new(stamp_ns, 0, Role::Ains, 0),
        variant: nauta_messages::to_fixed_str("track"),
        state_len: 16,
        ..Default::default()
    };
    m.state[0][0] = s.0.to_bits();
    m.state[0][1] = s.1.to_bits();
    m
}
pub fn state_of(m: &AinsSnapshot) -> (f64, f64) {
    (f64::from_bits(m.state[0][0]), f64::from_bits(m.state[0][1]))
}

/// The tracker aided by the sensor's position channel.
pub fn tracker_shell() -> Shell<Tracker> {
    Shell::<Tracker>::new(Role::Ains, &["kf"])
        .input(services::imu(), Role::Sensor, TrackIn::Velocity)
        .aiding(services::depth(), Role::Sensor, TrackIn::Position)
        .output(services::nav_solution(), nav_of)
        .snapshot(services::snapshot(Role::Ains), snapshot_of, state_of)
}

// ---- the relay of the cycle ------------------------------------------------

#[derive(Debug, Clone, Copy)]
pub enum RelayIn {
    Position(Depth),
    Tracked(Nav),
}

/// Blends each position measurement with the tracker's latest estimate and
/// hands it back: its output depends on the tracker's, and the tracker's on
/// it.
#[derive(Debug, Clone, Default)]
pub struct Relay {
    tracked: Option<(f64, f64)>,
}

impl Estimator for Relay {
    type Input = RelayIn;
    type Output = TrackOut;
    type Snapshot = ();

    fn on_input(&mut self, i: &RelayIn, out: &mut Vec<TrackOut>) -> Result<(), EstimatorError> {
        match i {
            RelayIn::Tracked(n) => self.tracked = Some((n.depth_m, n.pos_std_ned_m[2])),
            RelayIn::Position(d) => {
                let r = SIGMA_X * SIGMA_X;
                let (x, var) = match self.tracked {
                    Some((xt, st)) => {
                        let w = st * st / (st * st + r);
                        (xt + w * (d.depth_m - xt), r * (1.0 + w))
                    }
                    None => (d.depth_m, r),
                };
                out.push(TrackOut {
                    stamp_ns: d.stamp_ns,
                    x,
                    std: var.sqrt(),
                });
            }
        }
        Ok(())
    }
    fn snapshot(&self) -> Option<()> {
        None
    }
    fn restore(&mut self, _: &(), _: u64) -> Result<(), EstimatorError> {
        Ok(())
    }
}

pub fn lbl_of(o: &TrackOut) -> Option<LblSolution> {
    let mut m = LblSolution {
        header: Header::new(o.stamp_ns, 0, Role::Lbl, 0),
        x_m: o.x,
        ..Default::default()
    };
    m.p[0][0] = o.std * o.std;
    Some(m)
}

// ---- the cycle ------------------------------------------------------------

/// The tracker aided by the relay, which is aided by the tracker.
pub fn cyclic_tracker_shell() -> Shell<Tracker> {
    Shell::<Tracker>::new(Role::Ains, &["kf"])
        .input(services::imu(), Role::Sensor, TrackIn::Velocity)
        .aiding(services::lbl_solution(), Role::Lbl, TrackIn::Relayed)
        .output(services::nav_solution(), nav_of)
}

pub fn relay_shell() -> Shell<Relay> {
    Shell::<Relay>::new(Role::Lbl, &["relay"])
        .input(services::depth(), Role::Sensor, RelayIn::Position)
        .aiding(services::nav_solution(), Role::Ains, RelayIn::Tracked)
        .output(services::lbl_solution(), lbl_of)
}

/// The tracker with the relay's output as an optional aiding input: a run
/// without a relay passes `--absent lbl/nav`.
pub fn optionally_relayed_tracker_shell() -> Shell<Tracker> {
    Shell::<Tracker>::new(Role::Ains, &["kf"])
        .input(services::imu(), Role::Sensor, TrackIn::Velocity)
        .aiding(services::depth(), Role::Sensor, TrackIn::Position)
        .optional_aiding(services::lbl_solution(), Role::Lbl, TrackIn::Relayed)
        .output(services::nav_solution(), nav_of)
        .snapshot(services::snapshot(Role::Ains), snapshot_of, state_of)
}
