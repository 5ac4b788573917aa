//! Estimator snapshots (DESIGN §5): everything needed to warm-start a role.
//!
//! Published on `<role>/snapshot` at 1 Hz and on demand. Matrices are row-major
//! nested arrays so that the wire layout is plain and fixed.

use iceoryx2::prelude::ZeroCopySend;

use crate::Header;

/// The snapshot service of a role: `<role>/snapshot`.
pub fn snapshot_service(role: &str) -> String {
    format!("{role}/snapshot")
}

message! {
    /// Attitude estimator state: attitude, gyro bias and their 6×6 error covariance
    /// (attitude error about N, E, D in rad, then gyro bias in rad/s).
    #[wire(type_name = "nauta.AttitudeSnapshot.v1", size = 384)]
    pub struct AttitudeSnapshot {
        /// Common header; `stamp_ns` is the stamp of the last input processed.
        pub header: Header,
        /// Attitude quaternion body → NED, [w, x, y, z].
        pub quat_nb: [f64; 4],
        /// Gyro bias, FRD, rad/s.
        pub gyro_bias_rad_s: [f64; 3],
        /// Error covariance, row-major 6×6.
        pub covariance: [[f64; 6]; 6],
        /// Calibration bits (see `estimates::calibration`).
        pub calibration: u32,
        /// Zero.
        pub pad: u32,
    }
}

message! {
    /// Aided-INS state: position, velocity, attitude, sensor biases and the 15×15
    /// error covariance (position NED m, velocity NED m/s, attitude rad, accel bias
    /// m/s², gyro bias rad/s).
    #[wire(type_name = "nauta.AinsSnapshot.v1", size = 1968)]
    pub struct AinsSnapshot {
        /// Common header.
        pub header: Header,
        /// Latitude, rad.
        pub lat_rad: f64,
        /// Longitude, rad.
        pub lon_rad: f64,
        /// Depth, m.
        pub depth_m: f64,
        /// Velocity NED, m/s.
        pub vel_ned_m_s: [f64; 3],
        /// Attitude quaternion body → NED.
        pub quat_nb: [f64; 4],
        /// Accelerometer bias, FRD, m/s².
        pub accel_bias_m_s2: [f64; 3],
        /// Gyro bias, FRD, rad/s.
        pub gyro_bias_rad_s: [f64; 3],
        /// Error covariance, row-major 15×15.
        pub covariance: [[f64; 15]; 15],
        /// Aiding mode bits.
        pub aiding_mode: u32,
        /// Zero.
        pub pad: u32,
    }
}

message! {
    /// Buoy positioning filter state, summarised as a Gaussian over north/east
    /// offsets from the reference position.
    #[wire(type_name = "nauta.PositioningSnapshot.v1", size = 96)]
    pub struct PositioningSnapshot {
        /// Common header.
        pub header: Header,
        /// Latitude of the mean, rad.
        pub lat_rad: f64,
        /// Longitude of the mean, rad.
        pub lon_rad: f64,
        /// Covariance of north/east position, m², row-major 2×2.
        pub covariance_ne_m2: [[f64; 2]; 2],
        /// Effective particle count at the snapshot.
        pub effective_particles: f64,
        /// Particles in the filter.
        pub particles: u32,
        /// Zero.
        pub pad: u32,
    }
}

message! {
    /// LBL EKF state [x, y, current_x, current_y] and P (paper 003).
    #[wire(type_name = "nauta.LblSnapshot.v1", size = 200)]
    pub struct LblSnapshot {
        /// Common header.
        pub header: Header,
        /// State x̂.
        pub x: [f64; 4],
        /// Covariance P, row-major 4×4.
        pub p: [[f64; 4]; 4],
        /// Next transponder to interrogate.
        pub next_transponder: u32,
        /// Zero.
        pub pad: u32,
    }
}
