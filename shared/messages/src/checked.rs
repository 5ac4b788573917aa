//! Checked conversion from wire messages into domain values (STYLE "wire vs
//! domain"). A consumer turns every received message into one of these before an
//! estimator sees it; whatever fails is counted as rejected and the estimator's
//! state is left alone (DESIGN §4, "bad values are part of the contract").

use nauta_estimation::frames::{Frd, Ned, Rotation, Vector, WxyzError};

pub use nauta_estimation::readings::{
    Ahrs, Attitude, BuoyRangeReading, Depth, Dvl, Fix, Gps, Imu, LblNav, LblReplyReading, Nav,
    Propeller, Truth,
};

use crate::{
    AhrsSample, AttitudeEstimate, BuoyRange, DepthSample, DvlSample, GpsFix, GpsFixV1, ImuSample,
    LblReply, LblSolution, NavSolution, PositionFix, PropellerSample, TruthState,
};

/// Why a message was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ValidationError {
    /// A field holds NaN or an infinity.
    #[error("{type_name}.{field} is not finite ({value})")]
    NonFinite {
        /// Message type.
        type_name: &'static str,
        /// Field name.
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// A field lies outside its physical range.
    #[error("{type_name}.{field} = {value} is outside [{min}, {max}]")]
    OutOfRange {
        /// Message type.
        type_name: &'static str,
        /// Field name.
        field: &'static str,
        /// The value.
        value: f64,
        /// Smallest accepted value.
        min: f64,
        /// Largest accepted value.
        max: f64,
    },
    /// A quaternion is far from unit norm.
    #[error("{type_name}.{field} has norm {norm}, not 1")]
    NotUnitQuaternion {
        /// Message type.
        type_name: &'static str,
        /// Field name.
        field: &'static str,
        /// Its norm.
        norm: f64,
    },
    /// The stamp is earlier than the previous one on the same input.
    #[error("stamp {stamp_ns} ns goes backwards (previous {previous_ns} ns)")]
    StampBackwards {
        /// This message's stamp.
        stamp_ns: u64,
        /// The previous accepted stamp.
        previous_ns: u64,
    },
}

impl ValidationError {
    /// A short, stable name of the kind of error, for counting and log-once.
    pub fn kind(&self) -> &'static str {
        match self {
            ValidationError::NonFinite { .. } => "non-finite",
            ValidationError::OutOfRange { .. } => "out-of-range",
            ValidationError::NotUnitQuaternion { .. } => "non-unit-quaternion",
            ValidationError::StampBackwards { .. } => "stamp-backwards",
        }
    }
}

/// Largest deviation of a quaternion's norm from 1 that is accepted (and then
/// renormalised); anything further is a corrupt message, not rounding.
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-3;

/// Checks one scalar: finite and within `[min, max]` (written so that NaN fails).
pub fn scalar(
    type_name: &'static str,
    field: &'static str,
    value: f64,
    min: f64,
    max: f64,
) -> Result<f64, ValidationError> {
    if !value.is_finite() {
        return Err(ValidationError::NonFinite {
            type_name,
            field,
            value,
        });
    }
    if !(value >= min && value <= max) {
        return Err(ValidationError::OutOfRange {
            type_name,
            field,
            value,
            min,
            max,
        });
    }
    Ok(value)
}

/// Checks a 3-vector component by component (each within `±limit`); the
/// frame `F` is the field's (FRD or NED).
pub fn vector<F>(
    type_name: &'static str,
    field: &'static str,
    v: [f64; 3],
    limit: f64,
) -> Result<Vector<F>, ValidationError> {
    for x in v {
        scalar(type_name, field, x, -limit, limit)?;
    }
    Ok(Vector::from_array(v))
}

/// Checks a `[w, x, y, z]` quaternion body → NED: finite and of unit norm
/// within [`QUATERNION_NORM_TOLERANCE`]; returns it renormalised
/// ([`Rotation::from_wxyz_within`], the one conversion).
pub fn quaternion(
    type_name: &'static str,
    field: &'static str,
    q: [f64; 4],
) -> Result<Rotation<Frd, Ned>, ValidationError> {
    Rotation::from_wxyz_within(q, QUATERNION_NORM_TOLERANCE).map_err(|e| match e {
        WxyzError::NonFinite => ValidationError::NonFinite {
            type_name,
            field,
            value: q.into_iter().find(|x| !x.is_finite()).unwrap_or(f64::NAN),
        },
        WxyzError::NotUnit(norm) => ValidationError::NotUnitQuaternion {
            type_name,
            field,
            norm,
        },
    })
}

/// Enforces non-decreasing stamps on one input stream.
#[derive(Debug, Clone, Default)]
pub struct StampOrder {
    last_ns: Option<u64>,
}

impl StampOrder {
    /// Accepts `stamp_ns` when it is not earlier than the last accepted one.
    pub fn check(&mut self, stamp_ns: u64) -> Result<(), ValidationError> {
        if let Some(previous_ns) = self.last_ns
            && stamp_ns < previous_ns
        {
            return Err(ValidationError::StampBackwards {
                stamp_ns,
                previous_ns,
            });
        }
        self.last_ns = Some(stamp_ns);
        Ok(())
    }

    /// The last accepted stamp.
    pub fn last(&self) -> Option<u64> {
        self.last_ns
    }
}

/// Physical limits used by the checks (generous: they catch corruption, not outliers).
pub mod limits {
    /// Angular rate, rad/s per axis (±2000 °/s ≈ 35 rad/s gyros exist; 50 leaves margin).
    pub const GYRO_RAD_S: f64 = 50.0;
    /// Specific force, m/s² per axis (±20 g).
    pub const ACCEL_M_S2: f64 = 200.0;
    /// Magnetic flux density, µT per axis (Earth ≤ 65 µT; allows hard iron).
    pub const MAG_UT: f64 = 1000.0;
    /// Smallest accepted depth, m: a little above the surface (waves, offsets).
    pub const DEPTH_MIN_M: f64 = -5.0;
    /// Largest accepted depth, m (the deepest ocean).
    pub const DEPTH_MAX_M: f64 = 11_000.0;
    /// Vehicle speed over ground, m/s per axis.
    pub const SPEED_M_S: f64 = 20.0;
    /// Largest one-way acoustic time of flight, s (30 km at 1500 m/s).
    pub const TIME_OF_FLIGHT_MAX_S: f64 = 20.0;
    /// Plausible sound speed in sea water, m/s.
    pub const SOUND_SPEED_M_S: (f64, f64) = (1400.0, 1600.0);
}

const PI: f64 = core::f64::consts::PI;

impl TryFrom<&ImuSample> for Imu {
    type Error = ValidationError;
    fn try_from(m: &ImuSample) -> Result<Self, Self::Error> {
        const T: &str = "ImuSample";
        Ok(Imu {
            stamp_ns: m.header.stamp_ns,
            interval_s: scalar(T, "interval_s", m.interval_s, 1e-6, 1.0)?,
            gyro_rad_s: vector(T, "gyro_rad_s", m.gyro_rad_s, limits::GYRO_RAD_S)?,
            accel_m_s2: vector(T, "accel_m_s2", m.accel_m_s2, limits::ACCEL_M_S2)?,
            mag_ut: vector(T, "mag_ut", m.mag_ut, limits::MAG_UT)?,
        })
    }
}

impl TryFrom<&DepthSample> for Depth {
    type Error = ValidationError;
    fn try_from(m: &DepthSample) -> Result<Self, Self::Error> {
        Ok(Depth {
            stamp_ns: m.header.stamp_ns,
            depth_m: scalar(
                "DepthSample",
                "depth_m",
                m.depth_m,
                limits::DEPTH_MIN_M,
                limits::DEPTH_MAX_M,
            )?,
        })
    }
}

impl TryFrom<&DvlSample> for Dvl {
    type Error = ValidationError;
    fn try_from(m: &DvlSample) -> Result<Self, Self::Error> {
        const T: &str = "DvlSample";
        scalar(T, "beams_valid", f64::from(m.beams_valid), 0.0, 15.0)?;
        scalar(T, "bottom_lock", f64::from(m.bottom_lock), 0.0, 1.0)?;
        Ok(Dvl {
            stamp_ns: m.header.stamp_ns,
            velocity_body_m_s: vector(
                T,
                "velocity_body_m_s",
                m.velocity_body_m_s,
                limits::SPEED_M_S,
            )?,
            altitude_m: scalar(T, "altitude_m", m.altitude_m, 0.0, 1000.0)?,
            beams_valid: m.beams_valid as u8,
            bottom_lock: m.bottom_lock == 1,
        })
    }
}

impl TryFrom<&GpsFix> for Gps {
    type Error = ValidationError;
    fn try_from(m: &GpsFix) -> Result<Self, Self::Error> {
        const T: &str = "GpsFix";
        scalar(T, "quality", f64::from(m.quality), 0.0, 8.0)?;
        scalar(T, "velocity_valid", f64::from(m.velocity_valid), 0.0, 1.0)?;
        let velocity = if m.velocity_valid == 1 {
            Some((
                vector(T, "vel_ned_m_s", m.vel_ned_m_s, 100.0)?,
                scalar(T, "vel_std_m_s", m.vel_std_m_s, 0.0, 100.0)?,
            ))
        } else {
            None
        };
        Ok(Gps {
            stamp_ns: m.header.stamp_ns,
            lat_rad: scalar(T, "lat_rad", m.lat_rad, -PI / 2.0, PI / 2.0)?,
            lon_rad: scalar(T, "lon_rad", m.lon_rad, -PI, PI)?,
            height_m: scalar(T, "height_m", m.height_m, -1000.0, 10_000.0)?,
            horizontal_std_m: scalar(T, "horizontal_std_m", m.horizontal_std_m, 0.0, 10_000.0)?,
            quality: m.quality,
            velocity,
        })
    }
}

impl TryFrom<&GpsFixV1> for Gps {
    type Error = ValidationError;
    fn try_from(m: &GpsFixV1) -> Result<Self, Self::Error> {
        Gps::try_from(&GpsFix::from(m))
    }
}

impl TryFrom<&AhrsSample> for Ahrs {
    type Error = ValidationError;
    fn try_from(m: &AhrsSample) -> Result<Self, Self::Error> {
        const T: &str = "AhrsSample";
        let heading = scalar(T, "heading_mag_rad", m.heading_mag_rad, -PI, 2.0 * PI)?;
        Ok(Ahrs {
            stamp_ns: m.header.stamp_ns,
            roll_rad: scalar(T, "roll_rad", m.roll_rad, -PI, PI)?,
            pitch_rad: scalar(T, "pitch_rad", m.pitch_rad, -PI / 2.0, PI / 2.0)?,
            heading_mag_rad: heading.rem_euclid(2.0 * PI),
        })
    }
}

impl TryFrom<&PropellerSample> for Propeller {
    type Error = ValidationError;
    fn try_from(m: &PropellerSample) -> Result<Self, Self::Error> {
        Ok(Propeller {
            stamp_ns: m.header.stamp_ns,
            shaft_speed_rad_s: scalar(
                "PropellerSample",
                "shaft_speed_rad_s",
                m.shaft_speed_rad_s,
                -1000.0,
                1000.0,
            )?,
        })
    }
}

impl TryFrom<&BuoyRange> for BuoyRangeReading {
    type Error = ValidationError;
    fn try_from(m: &BuoyRange) -> Result<Self, Self::Error> {
        const T: &str = "BuoyRange";
        let (cmin, cmax) = limits::SOUND_SPEED_M_S;
        Ok(BuoyRangeReading {
            stamp_ns: m.header.stamp_ns,
            buoy_lat_rad: scalar(T, "buoy_lat_rad", m.buoy_lat_rad, -PI / 2.0, PI / 2.0)?,
            buoy_lon_rad: scalar(T, "buoy_lon_rad", m.buoy_lon_rad, -PI, PI)?,
            buoy_depth_m: scalar(
                T,
                "buoy_depth_m",
                m.buoy_depth_m,
                limits::DEPTH_MIN_M,
                1000.0,
            )?,
            time_of_flight_s: scalar(
                T,
                "time_of_flight_s",
                m.time_of_flight_s,
                0.0,
                limits::TIME_OF_FLIGHT_MAX_S,
            )?,
            sound_speed_m_s: scalar(T, "sound_speed_m_s", m.sound_speed_m_s, cmin, cmax)?,
        })
    }
}

impl TryFrom<&LblReply> for LblReplyReading {
    type Error = ValidationError;
    fn try_from(m: &LblReply) -> Result<Self, Self::Error> {
        const T: &str = "LblReply";
        if m.reply_stamp_ns < m.interrogation_stamp_ns {
            return Err(ValidationError::StampBackwards {
                stamp_ns: m.reply_stamp_ns,
                previous_ns: m.interrogation_stamp_ns,
            });
        }
        Ok(LblReplyReading {
            stamp_ns: m.header.stamp_ns,
            transponder_id: m.transponder_id,
            interrogation_stamp_ns: m.interrogation_stamp_ns,
            round_trip_s: scalar(
                T,
                "round_trip_s",
                m.round_trip_s,
                0.0,
                2.0 * limits::TIME_OF_FLIGHT_MAX_S,
            )?,
        })
    }
}

impl TryFrom<&TruthState> for Truth {
    type Error = ValidationError;
    fn try_from(m: &TruthState) -> Result<Self, Self::Error> {
        const T: &str = "TruthState";
        Ok(Truth {
            stamp_ns: m.header.stamp_ns,
            lat_rad: scalar(T, "lat_rad", m.lat_rad, -PI / 2.0, PI / 2.0)?,
            lon_rad: scalar(T, "lon_rad", m.lon_rad, -PI, PI)?,
            depth_m: scalar(
                T,
                "depth_m",
                m.depth_m,
                limits::DEPTH_MIN_M,
                limits::DEPTH_MAX_M,
            )?,
            vel_ned_m_s: vector(T, "vel_ned_m_s", m.vel_ned_m_s, limits::SPEED_M_S)?,
            attitude: quaternion(T, "quat_nb", m.quat_nb)?,
            distance_m: scalar(T, "distance_m", m.distance_m, 0.0, 1e9)?,
        })
    }
}

impl TryFrom<&AttitudeEstimate> for Attitude {
    type Error = ValidationError;
    fn try_from(m: &AttitudeEstimate) -> Result<Self, Self::Error> {
        const T: &str = "AttitudeEstimate";
        for s in m.std_rad {
            scalar(T, "std_rad", s, 0.0, 2.0 * PI)?;
        }
        Ok(Attitude {
            stamp_ns: m.header.stamp_ns,
            attitude: quaternion(T, "quat_nb", m.quat_nb)?,
            std_rad: Vector::from_array(m.std_rad),
            gyro_bias_rad_s: vector(T, "gyro_bias_rad_s", m.gyro_bias_rad_s, limits::GYRO_RAD_S)?,
        })
    }
}

/// Largest standard deviation an estimate may publish, m (or m/s): beyond it
/// the estimate says nothing and is corrupt rather than uncertain.
const STD_MAX: f64 = 1e7;

impl TryFrom<&NavSolution> for Nav {
    type Error = ValidationError;
    fn try_from(m: &NavSolution) -> Result<Self, Self::Error> {
        const T: &str = "NavSolution";
        let attitude = if m.quat_nb == [0.0; 4] {
            None
        } else {
            Some(quaternion(T, "quat_nb", m.quat_nb)?)
        };
        for s in m.pos_std_ned_m {
            scalar(T, "pos_std_ned_m", s, 0.0, STD_MAX)?;
        }
        for s in m.vel_std_ned_m_s {
            scalar(T, "vel_std_ned_m_s", s, 0.0, STD_MAX)?;
        }
        Ok(Nav {
            stamp_ns: m.header.stamp_ns,
            lat_rad: scalar(T, "lat_rad", m.lat_rad, -PI / 2.0, PI / 2.0)?,
            lon_rad: scalar(T, "lon_rad", m.lon_rad, -PI, PI)?,
            depth_m: scalar(
                T,
                "depth_m",
                m.depth_m,
                limits::DEPTH_MIN_M,
                limits::DEPTH_MAX_M,
            )?,
            vel_ned_m_s: vector(T, "vel_ned_m_s", m.vel_ned_m_s, limits::SPEED_M_S)?,
            attitude,
            pos_std_ned_m: Vector::from_array(m.pos_std_ned_m),
            vel_std_ned_m_s: Vector::from_array(m.vel_std_ned_m_s),
            predicted_drift_m: scalar(T, "predicted_drift_m", m.predicted_drift_m, 0.0, STD_MAX)?,
            aiding_mode: m.aiding_mode,
            advisory: m.advisory,
        })
    }
}

impl TryFrom<&PositionFix> for Fix {
    type Error = ValidationError;
    fn try_from(m: &PositionFix) -> Result<Self, Self::Error> {
        const T: &str = "PositionFix";
        Ok(Fix {
            stamp_ns: m.header.stamp_ns,
            lat_rad: scalar(T, "lat_rad", m.lat_rad, -PI / 2.0, PI / 2.0)?,
            lon_rad: scalar(T, "lon_rad", m.lon_rad, -PI, PI)?,
            std_north_m: scalar(T, "std_north_m", m.std_north_m, 0.0, STD_MAX)?,
            std_east_m: scalar(T, "std_east_m", m.std_east_m, 0.0, STD_MAX)?,
            corr_ne: scalar(T, "corr_ne", m.corr_ne, -1.0, 1.0)?,
            effective_particles: scalar(T, "effective_particles", m.effective_particles, 0.0, 1e9)?,
            source: m.fix_source,
        })
    }
}

impl TryFrom<&LblSolution> for LblNav {
    type Error = ValidationError;
    fn try_from(m: &LblSolution) -> Result<Self, Self::Error> {
        const T: &str = "LblSolution";
        // A local frame of at most the Earth's circumference.
        const LOCAL_MAX_M: f64 = 4.1e7;
        for row in m.p {
            for v in row {
                scalar(T, "p", v, -STD_MAX * STD_MAX, STD_MAX * STD_MAX)?;
            }
        }
        for i in 0..4 {
            scalar(T, "p", m.p[i][i], 0.0, STD_MAX * STD_MAX)?;
        }
        scalar(T, "accepted", f64::from(m.accepted), 0.0, 1.0)?;
        Ok(LblNav {
            stamp_ns: m.header.stamp_ns,
            x_m: scalar(T, "x_m", m.x_m, -LOCAL_MAX_M, LOCAL_MAX_M)?,
            y_m: scalar(T, "y_m", m.y_m, -LOCAL_MAX_M, LOCAL_MAX_M)?,
            current_m_s: [
                scalar(
                    T,
                    "current_x_m_s",
                    m.current_x_m_s,
                    -limits::SPEED_M_S,
                    limits::SPEED_M_S,
                )?,
                scalar(
                    T,
                    "current_y_m_s",
                    m.current_y_m_s,
                    -limits::SPEED_M_S,
                    limits::SPEED_M_S,
                )?,
            ],
            p: m.p,
            last_innovation_m: scalar(
                T,
                "last_innovation_m",
                m.last_innovation_m,
                -LOCAL_MAX_M,
                LOCAL_MAX_M,
            )?,
            transponder_id: m.transponder_id,
            accepted: m.accepted == 1,
            baseline_crossed: m.header.flags().contains(crate::Flags::DEGRADED),
        })
    }
}
