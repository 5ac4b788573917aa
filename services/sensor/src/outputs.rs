//! The sensor's publishers and the conversion of the simulator's readings to
//! wire messages (DESIGN §4). The readings already carry wire units (µT, rad,
//! m/s); their simulator annotations (event kinds, true ranges) stay behind.

use nauta_messages::*;
use nauta_runtime::{Context, PortDescription, Publisher, services};
use nauta_sim::suite::Measurements;

/// Every output of the sensor process.
pub struct Outputs {
    truth: Publisher<TruthState>,
    imu: Publisher<ImuSample>,
    ahrs: Publisher<AhrsSample>,
    dvl: Publisher<DvlSample>,
    depth: Publisher<DepthSample>,
    gps: Publisher<GpsFix>,
    propeller: Publisher<PropellerSample>,
    modem: Publisher<BuoyRange>,
    lbl: Publisher<LblReply>,
    /// `sensor/progress`: watermarks and the end of stream.
    pub progress: Publisher<Progress>,
    lbl_scratch: Vec<LblReply>,
}

/// The data outputs, for `--describe`.
pub fn describe() -> Vec<PortDescription> {
    vec![
        PortDescription::of(&services::imu()),
        PortDescription::of(&services::ahrs()),
        PortDescription::of(&services::dvl()),
        PortDescription::of(&services::depth()),
        PortDescription::of(&services::gps()),
        PortDescription::of(&services::propeller()),
        PortDescription::of(&services::modem()),
        PortDescription::of(&services::lbl_reply()),
        PortDescription::of(&services::truth()),
        PortDescription::of(&services::progress(Role::Sensor)),
    ]
}

fn header(stamp_ns: u64) -> Header {
    Header::new(stamp_ns, 0, Role::Sensor, 0)
}

impl Outputs {
    /// Opens every publisher.
    pub fn open(ctx: &Context) -> anyhow::Result<Self> {
        Ok(Self {
            truth: ctx.publisher(&services::truth())?,
            imu: ctx.publisher(&services::imu())?,
            ahrs: ctx.publisher(&services::ahrs())?,
            dvl: ctx.publisher(&services::dvl())?,
            depth: ctx.publisher(&services::depth())?,
            gps: ctx.publisher(&services::gps())?,
            propeller: ctx.publisher(&services::propeller())?,
            modem: ctx.publisher(&services::modem())?,
            lbl: ctx.publisher(&services::lbl_reply())?,
            progress: ctx.publisher(&services::progress(Role::Sensor))?,
            lbl_scratch: Vec::new(),
        })
    }

    /// Publishes one step's measurements (the truth first). LBL replies of one
    /// step go out in stamp order.
    pub fn publish(&mut self, m: &Measurements) -> anyhow::Result<()> {
        let t = &m.truth;
        self.truth.publish(TruthState {
            header: header(t.stamp_ns),
            lat_rad: t.lat_rad,
            lon_rad: t.lon_rad,
            depth_m: t.depth_m,
            vel_ned_m_s: t.vel_ned_m_s,
            quat_nb: t.quat_nb,
            rate_nb_body_rad_s: t.rate_nb_body_rad_s,
            current_ned_m_s: t.current_ned_m_s,
            distance_m: t.distance_m,
        })?;
        if let Some(r) = &m.imu {
            self.imu.publish(ImuSample {
                header: header(r.stamp_ns),
                gyro_rad_s: r.gyro_rad_s,
                accel_m_s2: r.accel_m_s2,
                mag_ut: r.mag_ut,
                interval_s: r.interval_s,
            })?;
        }
        if let Some(r) = &m.ahrs {
            self.ahrs.publish(AhrsSample {
                header: header(r.stamp_ns),
                roll_rad: r.roll_rad,
                pitch_rad: r.pitch_rad,
                heading_mag_rad: r.heading_mag_rad,
            })?;
        }
        if let Some(r) = &m.dvl {
            self.dvl.publish(DvlSample {
                header: header(r.stamp_ns),
                velocity_body_m_s: r.velocity_body_m_s,
                altitude_m: r.altitude_m,
                beams_valid: r.beams_valid,
                bottom_lock: r.bottom_lock,
                figure_of_merit_m_s: r.figure_of_merit_m_s,
            })?;
        }
        if let Some(r) = &m.depth {
            self.depth.publish(DepthSample {
                header: header(r.stamp_ns),
                depth_m: r.depth_m,
            })?;
        }
        if let Some(r) = &m.gps {
            self.gps.publish(GpsFix {
                header: header(r.stamp_ns),
                lat_rad: r.lat_rad,
                lon_rad: r.lon_rad,
                height_m: r.height_m,
                horizontal_std_m: r.horizontal_std_m,
                quality: r.quality,
                satellites: r.satellites,
            })?;
        }
        if let Some(r) = &m.propeller {
            self.propeller.publish(PropellerSample {
                header: header(r.stamp_ns),
                shaft_speed_rad_s: r.shaft_speed_rad_s,
            })?;
        }
        if let Some(r) = &m.modem {
            self.modem.publish(BuoyRange {
                header: header(r.stamp_ns),
                buoy_lat_rad: r.buoy_lat_rad,
                buoy_lon_rad: r.buoy_lon_rad,
                buoy_depth_m: r.buoy_depth_m,
                time_of_flight_s: r.time_of_flight_s,
                sound_speed_m_s: r.sound_speed_m_s,
            })?;
        }
        if !m.lbl.is_empty() {
            self.lbl_scratch.clear();
            self.lbl_scratch.extend(m.lbl.iter().map(|r| LblReply {
                header: header(r.stamp_ns),
                transponder_id: r.transponder_id,
                pad: 0,
                interrogation_stamp_ns: r.interrogation_stamp_ns,
                reply_stamp_ns: r.reply_stamp_ns,
                round_trip_s: r.round_trip_s,
            }));
            self.lbl_scratch
                .sort_by_key(|r| (r.header.stamp_ns, r.transponder_id));
            for r in &self.lbl_scratch {
                self.lbl.publish(*r)?;
            }
        }
        Ok(())
    }

    /// Wakes the subscribers of everything published since the last flush.
    pub fn flush(&mut self) {
        self.truth.flush();
        self.imu.flush();
        self.ahrs.flush();
        self.dvl.flush();
        self.depth.flush();
        self.gps.flush();
        self.propeller.flush();
        self.modem.flush();
        self.lbl.flush();
        self.progress.flush();
    }

    /// Data messages published (progress excluded).
    pub fn published(&self) -> u64 {
        self.truth.published()
            + self.imu.published()
            + self.ahrs.published()
            + self.dvl.published()
            + self.depth.published()
            + self.gps.published()
            + self.propeller.published()
            + self.modem.published()
            + self.lbl.published()
    }

    /// Deliveries given up on back-pressure deadlines.
    pub fn given_up(&self) -> u64 {
        self.truth.given_up()
            + self.imu.given_up()
            + self.ahrs.given_up()
            + self.dvl.given_up()
            + self.depth.given_up()
            + self.gps.given_up()
            + self.propeller.given_up()
            + self.modem.given_up()
            + self.lbl.given_up()
            + self.progress.given_up()
    }

    /// Per-service counts, for the log line at the end.
    pub fn counts(&self) -> Vec<(&str, u64)> {
        vec![
            (self.truth.service(), self.truth.published()),
            (self.imu.service(), self.imu.published()),
            (self.ahrs.service(), self.ahrs.published()),
            (self.dvl.service(), self.dvl.published()),
            (self.depth.service(), self.depth.published()),
            (self.gps.service(), self.gps.published()),
            (self.propeller.service(), self.propeller.published()),
            (self.modem.service(), self.modem.published()),
            (self.lbl.service(), self.lbl.published()),
        ]
    }
}
