//! What sensors and estimators report, as checked domain values: finite, in
//! range, unit quaternions renormalised. Estimators consume these and never a
//! wire message. They are built from wire messages by the checked conversions
//! of `nauta-messages` (`nauta_messages::checked`, which re-exports them), the
//! only place that turns raw arrays into them; tests and benchmarks may build
//! them directly from a simulator.
//!
//! They are defined here, in the pure crate, so that an estimator depends on
//! no IPC crate at all (`nauta-messages` builds on this crate, not the reverse).

use crate::frames::{Frd, Ned, Rotation, Vector};

/// A checked IMU sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Imu {
    /// End of the integration interval, ns.
    pub stamp_ns: u64,
    /// Interval length, s.
    pub interval_s: f64,
    /// Angular rate, FRD, rad/s.
    pub gyro_rad_s: Vector<Frd>,
    /// Specific force, FRD, m/s².
    pub accel_m_s2: Vector<Frd>,
    /// Magnetic flux density, FRD, µT.
    pub mag_ut: Vector<Frd>,
}

/// A checked depth sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Depth {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Depth, m, positive down.
    pub depth_m: f64,
}

/// A checked DVL sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dvl {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Velocity over the bottom, FRD, m/s.
    pub velocity_body_m_s: Vector<Frd>,
    /// Altitude, m.
    pub altitude_m: f64,
    /// Bit i: beam i valid.
    pub beams_valid: u8,
    /// Bottom lock held.
    pub bottom_lock: bool,
}

/// A checked GPS fix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gps {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Ellipsoidal height, m.
    pub height_m: f64,
    /// Horizontal standard deviation, m.
    pub horizontal_std_m: f64,
    /// Fix quality code.
    pub quality: u32,
    /// Velocity over ground, NED, m/s, and its standard deviation per axis,
    /// m/s, when the receiver reports one (`nauta.GpsFix.v2`; none from v1).
    pub velocity: Option<(Vector<Ned>, f64)>,
}

/// A checked vendor AHRS sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ahrs {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Roll, rad, (-π, π].
    pub roll_rad: f64,
    /// Pitch, rad, [-π/2, π/2].
    pub pitch_rad: f64,
    /// Magnetic heading, rad, normalised to [0, 2π).
    pub heading_mag_rad: f64,
}

/// A checked propeller sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Propeller {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Shaft speed, rad/s.
    pub shaft_speed_rad_s: f64,
}

/// A checked buoy range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuoyRangeReading {
    /// Reception stamp, ns.
    pub stamp_ns: u64,
    /// Buoy latitude, rad.
    pub buoy_lat_rad: f64,
    /// Buoy longitude, rad.
    pub buoy_lon_rad: f64,
    /// Buoy transducer depth, m.
    pub buoy_depth_m: f64,
    /// One-way time of flight, s.
    pub time_of_flight_s: f64,
    /// Sound speed, m/s.
    pub sound_speed_m_s: f64,
}

/// A checked LBL reply.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LblReplyReading {
    /// Reception stamp, ns.
    pub stamp_ns: u64,
    /// Transponder.
    pub transponder_id: u32,
    /// Interrogation stamp, ns.
    pub interrogation_stamp_ns: u64,
    /// Round-trip time, s.
    pub round_trip_s: f64,
}

/// A checked true state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Depth, m.
    pub depth_m: f64,
    /// Velocity NED, m/s.
    pub vel_ned_m_s: Vector<Ned>,
    /// Attitude body → NED.
    pub attitude: Rotation<Frd, Ned>,
    /// Distance travelled over ground since the start, m.
    pub distance_m: f64,
}

/// A checked attitude estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attitude {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Attitude body → NED.
    pub attitude: Rotation<Frd, Ned>,
    /// Error standard deviation about N, E, D, rad.
    pub std_rad: Vector<Ned>,
    /// Gyro bias, FRD, rad/s.
    pub gyro_bias_rad_s: Vector<Frd>,
}

/// A checked navigation solution of the aided INS (`ains/nav`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nav {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Depth, m.
    pub depth_m: f64,
    /// Velocity over ground, NED, m/s.
    pub vel_ned_m_s: Vector<Ned>,
    /// Attitude body → NED, when the solution carries one (the wire's zero
    /// quaternion means none).
    pub attitude: Option<Rotation<Frd, Ned>>,
    /// Position standard deviation N, E, D, m.
    pub pos_std_ned_m: Vector<Ned>,
    /// Velocity standard deviation N, E, D, m/s.
    pub vel_std_ned_m_s: Vector<Ned>,
    /// Predicted accumulated horizontal position error (paper 002), m.
    pub predicted_drift_m: f64,
    /// Aiding mode bits ([`crate::ains::aiding`]).
    pub aiding_mode: u32,
    /// Advisory bits ([`crate::ains::advisory`]).
    pub advisory: u32,
}

/// A checked position fix (`positioning/fix`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fix {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Standard deviation north, m.
    pub std_north_m: f64,
    /// Standard deviation east, m.
    pub std_east_m: f64,
    /// Correlation of the north and east errors, [-1, 1].
    pub corr_ne: f64,
    /// Effective particle count.
    pub effective_particles: f64,
    /// 1 buoy range, 2 GPS.
    pub source: u32,
}

/// A checked LBL solution (`lbl/nav`): local north/east metres from the
/// run's origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LblNav {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// North of the origin, m.
    pub x_m: f64,
    /// East of the origin, m.
    pub y_m: f64,
    /// Water current north and east, m/s.
    pub current_m_s: [f64; 2],
    /// State covariance P (x, y, current x, current y), symmetric.
    pub p: [[f64; 4]; 4],
    /// Last range innovation, m.
    pub last_innovation_m: f64,
    /// Transponder of the last range.
    pub transponder_id: u32,
    /// The last range was accepted by the validation gate.
    pub accepted: bool,
    /// The estimate is on the other side of a two-transponder baseline
    /// from where the vehicle started (paper 003 §III's ambiguity): the
    /// wire's `DEGRADED` flag.
    pub baseline_crossed: bool,
}
