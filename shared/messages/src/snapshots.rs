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
    /// Aided-INS state for a warm restart or a hot swap: the variant's exact
    /// state, bincode-encoded (the codec's configuration) from its snapshot
    /// type in `nauta_estimation::ains` (`dr`: `DrSnapshot`, the navigation
    /// state, the spike filter, the depth tare and the error predictor's 13×13
    /// covariance), so that another instance of the variant continues bit for
    /// bit. Opaque on purpose: each variant's state differs, and only an
    /// instance of that variant reads it, checking every value.
    #[wire(type_name = "nauta.AinsSnapshot.v1", size = 2360)]
    pub struct AinsSnapshot {
        /// Common header; `stamp_ns` is the stamp of the last input processed.
        pub header: Header,
        /// The variant whose state this is (`dr`), NUL-padded.
        pub variant: [u8; 16],
        /// Bytes of `state` in use.
        pub state_len: u32,
        /// Zero.
        pub pad: u32,
        /// The variant's state: the first `state_len` bytes of these words,
        /// each little-endian.
        pub state: [[u64; 32]; 9],
    }
}

message! {
    /// Positioning state for a warm restart or a hot swap: the estimator's
    /// state, bincode-encoded (the codec's configuration) from
    /// `nauta_estimation::positioning::PositioningState` (the dead-reckoned
    /// centre, the filter's mean and 11×11 covariance of offset, velocity
    /// correction, sound-speed, scale and heading errors and the buoy's
    /// track, the buoy's reference, the depth tare, the timers and
    /// counters). Both variants share the state: the `ekf` continues bit
    /// for bit, the `pf` redraws its particles from the Gaussian. v2 held a
    /// 4×4 Gaussian in 512 bytes; v1 (a 2×2 Gaussian only) was never
    /// published: no positioning process existed.
    #[wire(type_name = "nauta.PositioningSnapshot.v3", size = 1592)]
    pub struct PositioningSnapshot {
        /// Common header; `stamp_ns` is the stamp of the last input processed.
        pub header: Header,
        /// The variant that wrote it (`pf`, `ekf`), NUL-padded.
        pub variant: [u8; 16],
        /// Bytes of `state` in use.
        pub state_len: u32,
        /// Zero.
        pub pad: u32,
        /// The state: the first `state_len` bytes of these words, each
        /// little-endian.
        pub state: [[u64; 32]; 6],
    }
}

message! {
    /// LBL state for a warm restart or a hot swap: the estimator's whole
    /// state, bincode-encoded (the codec's configuration) from
    /// `nauta_estimation::lbl::LblState`: `E` and `P` (4 or 5 states), the
    /// held inputs and the last steps' ones, the ranges and GPS fix waiting
    /// for the next step, the interrogations, the counters. v1 (`E`, `P`
    /// and the next transponder only) was never published: no LBL process
    /// existed.
    #[wire(type_name = "nauta.LblSnapshot.v2", size = 4152)]
    pub struct LblSnapshot {
        /// Common header; `stamp_ns` is the stamp of the last input processed.
        pub header: Header,
        /// The variant that wrote it (`ekf`), NUL-padded.
        pub variant: [u8; 16],
        /// Bytes of `state` in use.
        pub state_len: u32,
        /// Zero.
        pub pad: u32,
        /// The state: the first `state_len` bytes of these words, each
        /// little-endian.
        pub state: [[u64; 32]; 16],
    }
}
