//! A simulator step's readings as the aided INS's inputs
//! (`nauta_estimation::ains::AinsInput`), for tests and benchmarks that run
//! an estimator in process on the simulator.

use nauta_estimation::ains::AinsInput;
use nauta_estimation::frames::Vector;
use nauta_estimation::readings::{Ahrs, Depth, Dvl, Gps, Imu};

use crate::suite::{ImuReading, Measurements};

/// The IMU reading as a checked-shape IMU sample.
pub fn imu(r: &ImuReading) -> Imu {
    Imu {
        stamp_ns: r.stamp_ns,
        interval_s: r.interval_s,
        gyro_rad_s: Vector::from_array(r.gyro_rad_s),
        accel_m_s2: Vector::from_array(r.accel_m_s2),
        mag_ut: Vector::from_array(r.mag_ut),
    }
}

/// The step's DVL, depth, GPS and AHRS readings, in that order, appended to
/// `out`; GPS fixes with their velocity when `gps_velocity`.
pub fn aiding(m: &Measurements, gps_velocity: bool, out: &mut Vec<AinsInput>) {
    if let Some(r) = &m.dvl {
        out.push(AinsInput::Dvl(Dvl {
            stamp_ns: r.stamp_ns,
            velocity_body_m_s: Vector::from_array(r.velocity_body_m_s),
            altitude_m: r.altitude_m,
            beams_valid: r.beams_valid as u8,
            bottom_lock: r.bottom_lock != 0,
        }));
    }
    if let Some(r) = &m.depth {
        out.push(AinsInput::Depth(Depth {
            stamp_ns: r.stamp_ns,
            depth_m: r.depth_m,
        }));
    }
    if let Some(r) = &m.gps {
        out.push(AinsInput::Gps(Gps {
            stamp_ns: r.stamp_ns,
            lat_rad: r.lat_rad,
            lon_rad: r.lon_rad,
            height_m: r.height_m,
            horizontal_std_m: r.horizontal_std_m,
            quality: r.quality,
            velocity: gps_velocity.then(|| (Vector::from_array(r.vel_ned_m_s), r.vel_std_m_s)),
        }));
    }
    if let Some(r) = &m.ahrs {
        out.push(AinsInput::Ahrs(Ahrs {
            stamp_ns: r.stamp_ns,
            roll_rad: r.roll_rad,
            pitch_rad: r.pitch_rad,
            heading_mag_rad: r.heading_mag_rad,
        }));
    }
}
