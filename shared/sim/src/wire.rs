//! The simulator's readings as wire messages (DESIGN §4), in the order the
//! sensor process publishes them: the truth, then the IMU, AHRS, DVL, depth,
//! GPS, propeller, modem and the LBL replies in stamp order. The readings
//! already carry wire units (µT, rad, m/s); their simulator annotations (event
//! kinds, true ranges) stay behind. Headers carry the stamp and the sensor role;
//! a publisher fills in the sequence and instance.

use nauta_messages::*;

use crate::suite::Measurements;

fn header(stamp_ns: u64) -> Header {
    Header::new(stamp_ns, 0, Role::Sensor, 0)
}

/// Appends one step's messages to `out`.
pub fn to_wire(m: &Measurements, out: &mut Vec<SensorMessage>) {
    let t = &m.truth;
    out.push(SensorMessage::Truth(TruthState {
        header: header(t.stamp_ns),
        lat_rad: t.lat_rad,
        lon_rad: t.lon_rad,
        depth_m: t.depth_m,
        vel_ned_m_s: t.vel_ned_m_s,
        quat_nb: t.quat_nb,
        rate_nb_body_rad_s: t.rate_nb_body_rad_s,
        current_ned_m_s: t.current_ned_m_s,
        distance_m: t.distance_m,
    }));
    if let Some(r) = &m.imu {
        out.push(SensorMessage::Imu(ImuSample {
            header: header(r.stamp_ns),
            gyro_rad_s: r.gyro_rad_s,
            accel_m_s2: r.accel_m_s2,
            mag_ut: r.mag_ut,
            interval_s: r.interval_s,
        }));
    }
    if let Some(r) = &m.ahrs {
        out.push(SensorMessage::Ahrs(AhrsSample {
            header: header(r.stamp_ns),
            roll_rad: r.roll_rad,
            pitch_rad: r.pitch_rad,
            heading_mag_rad: r.heading_mag_rad,
        }));
    }
    if let Some(r) = &m.dvl {
        out.push(SensorMessage::Dvl(DvlSample {
            header: header(r.stamp_ns),
            velocity_body_m_s: r.velocity_body_m_s,
            altitude_m: r.altitude_m,
            beams_valid: r.beams_valid,
            bottom_lock: r.bottom_lock,
            figure_of_merit_m_s: r.figure_of_merit_m_s,
        }));
    }
    if let Some(r) = &m.depth {
        out.push(SensorMessage::Depth(DepthSample {
            header: header(r.stamp_ns),
            depth_m: r.depth_m,
        }));
    }
    if let Some(r) = &m.gps {
        out.push(SensorMessage::Gps(GpsFix {
            header: header(r.stamp_ns),
            lat_rad: r.lat_rad,
            lon_rad: r.lon_rad,
            height_m: r.height_m,
            horizontal_std_m: r.horizontal_std_m,
            quality: r.quality,
            satellites: r.satellites,
            vel_ned_m_s: r.vel_ned_m_s,
            vel_std_m_s: r.vel_std_m_s,
            velocity_valid: 1,
            pad: 0,
        }));
    }
    if let Some(r) = &m.propeller {
        out.push(SensorMessage::Propeller(PropellerSample {
            header: header(r.stamp_ns),
            shaft_speed_rad_s: r.shaft_speed_rad_s,
        }));
    }
    if let Some(r) = &m.modem {
        out.push(SensorMessage::Modem(BuoyRange {
            header: header(r.stamp_ns),
            buoy_lat_rad: r.buoy_lat_rad,
            buoy_lon_rad: r.buoy_lon_rad,
            buoy_depth_m: r.buoy_depth_m,
            time_of_flight_s: r.time_of_flight_s,
            sound_speed_m_s: r.sound_speed_m_s,
        }));
    }
    if !m.lbl.is_empty() {
        let first = out.len();
        out.extend(m.lbl.iter().map(|r| {
            SensorMessage::Lbl(LblReply {
                header: header(r.stamp_ns),
                transponder_id: r.transponder_id,
                pad: 0,
                interrogation_stamp_ns: r.interrogation_stamp_ns,
                reply_stamp_ns: r.reply_stamp_ns,
                round_trip_s: r.round_trip_s,
            })
        }));
        out[first..].sort_by_key(|r| match r {
            SensorMessage::Lbl(l) => (l.header.stamp_ns, l.transponder_id),
            other => (other.header().stamp_ns, 0),
        });
    }
}
