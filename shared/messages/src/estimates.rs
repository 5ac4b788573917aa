//! Estimator outputs (DESIGN §4).

use iceoryx2::prelude::ZeroCopySend;

use crate::Header;

/// `attitude/estimate`, one per IMU sample.
pub const ATTITUDE_ESTIMATE_SERVICE: &str = "attitude/estimate";
/// `ains/nav`, one per IMU sample.
pub const NAV_SOLUTION_SERVICE: &str = "ains/nav";
/// `positioning/fix`, one per buoy range or GPS fix.
pub const POSITION_FIX_SERVICE: &str = "positioning/fix";
/// `lbl/nav`, 10 Hz.
pub const LBL_SOLUTION_SERVICE: &str = "lbl/nav";

/// Calibration state reported in [`AttitudeEstimate::calibration`].
pub mod calibration {
    /// Not calibrated, not aligned.
    pub const NONE: u32 = 0;
    /// Initial alignment done.
    pub const ALIGNED: u32 = 1;
    /// Static gyro/accelerometer calibration done.
    pub const STATIC: u32 = 1 << 1;
    /// Magnetometer calibration applied.
    pub const MAGNETOMETER: u32 = 1 << 2;
}

message! {
    /// Attitude estimate.
    #[wire(type_name = "nauta.AttitudeEstimate.v1", size = 120)]
    pub struct AttitudeEstimate {
        /// Common header; keeps the stamp of the IMU sample it was computed from.
        pub header: Header,
        /// Attitude quaternion body → NED, [w, x, y, z].
        pub quat_nb: [f64; 4],
        /// Standard deviation of the attitude error about N, E, D, rad (0 when unknown).
        pub std_rad: [f64; 3],
        /// Estimated gyro bias, FRD, rad/s.
        pub gyro_bias_rad_s: [f64; 3],
        /// [`calibration`] bits.
        pub calibration: u32,
        /// Zero.
        pub pad: u32,
    }
}

message! {
    /// Aided-INS navigation solution.
    #[wire(type_name = "nauta.NavSolution.v1", size = 176)]
    pub struct NavSolution {
        /// Common header; keeps the IMU stamp it was computed from.
        pub header: Header,
        /// Geodetic latitude, rad.
        pub lat_rad: f64,
        /// Geodetic longitude, rad.
        pub lon_rad: f64,
        /// Depth, m.
        pub depth_m: f64,
        /// Velocity over ground, NED, m/s.
        pub vel_ned_m_s: [f64; 3],
        /// Attitude quaternion body → NED, [w, x, y, z].
        pub quat_nb: [f64; 4],
        /// Position standard deviation N, E, D, m.
        pub pos_std_ned_m: [f64; 3],
        /// Velocity standard deviation N, E, D, m/s.
        pub vel_std_ned_m_s: [f64; 3],
        /// Predicted accumulated horizontal position error (paper 002), m.
        pub predicted_drift_m: f64,
        /// Aiding mode bits (0 free inertial, 1 DVL, 2 GPS, 4 buoy/acoustic fix,
        /// 8 heading, 16 depth; `nauta_estimation::ains::aiding`).
        pub aiding_mode: u32,
        /// Advisory bits (1: surfacing advised, the predicted horizontal
        /// error above the manifest's threshold;
        /// `nauta_estimation::ains::advisory`). Zero in recordings made
        /// before the bits existed (it was padding, always zero).
        pub advisory: u32,
    }
}

message! {
    /// A position fix from the buoy positioning filter or GPS.
    #[wire(type_name = "nauta.PositionFix.v1", size = 88)]
    pub struct PositionFix {
        /// Common header.
        pub header: Header,
        /// Geodetic latitude, rad.
        pub lat_rad: f64,
        /// Geodetic longitude, rad.
        pub lon_rad: f64,
        /// Standard deviation north, m.
        pub std_north_m: f64,
        /// Standard deviation east, m.
        pub std_east_m: f64,
        /// Correlation between north and east errors, [-1, 1].
        pub corr_ne: f64,
        /// Effective particle count (paper 000, eq. 46) after the update.
        pub effective_particles: f64,
        /// 1 buoy range, 2 GPS.
        pub fix_source: u32,
        /// Zero.
        pub pad: u32,
    }
}

message! {
    /// LBL EKF solution (paper 003): state [x, y, current_x, current_y] in the
    /// local frame (x north, y east, m, from the declared origin).
    #[wire(type_name = "nauta.LblSolution.v1", size = 232)]
    pub struct LblSolution {
        /// Common header.
        pub header: Header,
        /// North of the origin, m.
        pub x_m: f64,
        /// East of the origin, m.
        pub y_m: f64,
        /// Water current north, m/s.
        pub current_x_m_s: f64,
        /// Water current east, m/s.
        pub current_y_m_s: f64,
        /// State covariance P, row-major 4×4.
        pub p: [[f64; 4]; 4],
        /// Semi-major axis of the 1σ position ellipse, m.
        pub ellipse_major_m: f64,
        /// Semi-minor axis of the 1σ position ellipse, m.
        pub ellipse_minor_m: f64,
        /// Orientation of the major axis from north towards east, rad.
        pub ellipse_orientation_rad: f64,
        /// Last range innovation, m.
        pub last_innovation_m: f64,
        /// Transponder of the last range.
        pub transponder_id: u32,
        /// 1 when the last range was accepted, 0 when rejected.
        pub accepted: u32,
    }
}
