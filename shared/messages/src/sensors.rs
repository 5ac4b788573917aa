//! Sensor messages (DESIGN §4), published by the sensor process.

use iceoryx2::prelude::ZeroCopySend;

use crate::Header;

/// `sensor/imu`, 100 Hz.
pub const IMU_SERVICE: &str = "sensor/imu";
/// `sensor/dvl`, 5 Hz.
pub const DVL_SERVICE: &str = "sensor/dvl";
/// `sensor/depth`, 10 Hz.
pub const DEPTH_SERVICE: &str = "sensor/depth";
/// `sensor/gps`, 1 Hz at the surface.
pub const GPS_SERVICE: &str = "sensor/gps";
/// `sensor/ahrs`, 10 Hz.
pub const AHRS_SERVICE: &str = "sensor/ahrs";
/// `sensor/propeller`, 10 Hz.
pub const PROPELLER_SERVICE: &str = "sensor/propeller";
/// `sensor/modem`, one buoy message every 30 s.
pub const MODEM_SERVICE: &str = "sensor/modem";
/// `sensor/lbl`, one per transponder reply.
pub const LBL_REPLY_SERVICE: &str = "sensor/lbl";
/// `lbl/interrogate`, one per ping (published by the LBL navigator).
pub const LBL_INTERROGATE_SERVICE: &str = "lbl/interrogate";
/// `sim/truth`, 100 Hz, simulator only.
pub const TRUTH_SERVICE: &str = "sim/truth";

message! {
    /// Inertial sample: each vector is the average over the interval
    /// `(stamp_ns - interval_s, stamp_ns]` (increment / dt), body frame FRD.
    #[wire(type_name = "nauta.ImuSample.v1", size = 112)]
    pub struct ImuSample {
        /// Common header; `stamp_ns` is the end of the integration interval.
        pub header: Header,
        /// Angular rate of the body with respect to inertial space, rad/s, FRD.
        pub gyro_rad_s: [f64; 3],
        /// Specific force, m/s², FRD (reads about -9.8 on z when level and still).
        pub accel_m_s2: [f64; 3],
        /// Magnetic flux density, µT, FRD.
        pub mag_ut: [f64; 3],
        /// Length of the integration interval, s.
        pub interval_s: f64,
    }
}

message! {
    /// Doppler velocity log bottom-track sample.
    #[wire(type_name = "nauta.DvlSample.v1", size = 80)]
    pub struct DvlSample {
        /// Common header.
        pub header: Header,
        /// Velocity of the vehicle over the bottom, m/s, FRD.
        pub velocity_body_m_s: [f64; 3],
        /// Altitude above the bottom, m.
        pub altitude_m: f64,
        /// Per-beam validity, bit i for beam i (4 beams).
        pub beams_valid: u32,
        /// 1 when bottom lock is held, else 0.
        pub bottom_lock: u32,
        /// Figure of merit reported by the instrument, m/s (0 when not given).
        pub figure_of_merit_m_s: f64,
    }
}

message! {
    /// Pressure depth.
    #[wire(type_name = "nauta.DepthSample.v1", size = 40)]
    pub struct DepthSample {
        /// Common header.
        pub header: Header,
        /// Depth of the pressure sensor below the surface, m, positive down.
        pub depth_m: f64,
    }
}

message! {
    /// Surface GPS fix, with the receiver's velocity when it reports one.
    #[wire(type_name = "nauta.GpsFix.v2", size = 112)]
    pub struct GpsFix {
        /// Common header.
        pub header: Header,
        /// Geodetic latitude, rad, WGS84.
        pub lat_rad: f64,
        /// Geodetic longitude, rad, WGS84.
        pub lon_rad: f64,
        /// Height above the ellipsoid, m.
        pub height_m: f64,
        /// Horizontal standard deviation, m.
        pub horizontal_std_m: f64,
        /// Fix quality: 0 none, 1 GPS, 2 DGPS, 4 RTK fixed, 5 RTK float.
        pub quality: u32,
        /// Satellites used.
        pub satellites: u32,
        /// Velocity over ground, NED, m/s (when `velocity_valid` is 1).
        pub vel_ned_m_s: [f64; 3],
        /// Velocity standard deviation per axis, m/s.
        pub vel_std_m_s: f64,
        /// 1 when the velocity fields hold a measurement, 0 when the
        /// receiver reported none.
        pub velocity_valid: u32,
        /// Padding, zero.
        pub pad: u32,
    }
}

message! {
    /// Surface GPS fix as recorded before `nauta.GpsFix.v2` (no velocity):
    /// read from old recordings only, and turned into a v2 fix without a
    /// velocity ([`GpsFix::from`]).
    #[wire(type_name = "nauta.GpsFix.v1", size = 72)]
    pub struct GpsFixV1 {
        /// Common header.
        pub header: Header,
        /// Geodetic latitude, rad, WGS84.
        pub lat_rad: f64,
        /// Geodetic longitude, rad, WGS84.
        pub lon_rad: f64,
        /// Height above the ellipsoid, m.
        pub height_m: f64,
        /// Horizontal standard deviation, m.
        pub horizontal_std_m: f64,
        /// Fix quality: 0 none, 1 GPS, 2 DGPS, 4 RTK fixed, 5 RTK float.
        pub quality: u32,
        /// Satellites used.
        pub satellites: u32,
    }
}

impl From<&GpsFixV1> for GpsFix {
    fn from(m: &GpsFixV1) -> Self {
        GpsFix {
            header: m.header,
            lat_rad: m.lat_rad,
            lon_rad: m.lon_rad,
            height_m: m.height_m,
            horizontal_std_m: m.horizontal_std_m,
            quality: m.quality,
            satellites: m.satellites,
            ..Default::default()
        }
    }
}

message! {
    /// The vehicle's own AHRS output (as on Isurus and Pirajuba).
    #[wire(type_name = "nauta.AhrsSample.v1", size = 56)]
    pub struct AhrsSample {
        /// Common header.
        pub header: Header,
        /// Roll, rad.
        pub roll_rad: f64,
        /// Pitch, rad.
        pub pitch_rad: f64,
        /// Heading with respect to magnetic north, rad, [0, 2π).
        pub heading_mag_rad: f64,
    }
}

message! {
    /// Propeller shaft speed.
    #[wire(type_name = "nauta.PropellerSample.v1", size = 40)]
    pub struct PropellerSample {
        /// Common header.
        pub header: Header,
        /// Shaft speed, rad/s.
        pub shaft_speed_rad_s: f64,
    }
}

message! {
    /// One buoy message received over the acoustic modem: the buoy's GPS
    /// position and the one-way time of flight of the message.
    #[wire(type_name = "nauta.BuoyRange.v1", size = 72)]
    pub struct BuoyRange {
        /// Common header; `stamp_ns` is the time of reception.
        pub header: Header,
        /// Buoy latitude, rad.
        pub buoy_lat_rad: f64,
        /// Buoy longitude, rad.
        pub buoy_lon_rad: f64,
        /// Depth of the buoy's transducer, m.
        pub buoy_depth_m: f64,
        /// One-way time of flight, s.
        pub time_of_flight_s: f64,
        /// Sound speed the buoy reports, m/s.
        pub sound_speed_m_s: f64,
    }
}

message! {
    /// One LBL transponder reply.
    #[wire(type_name = "nauta.LblReply.v1", size = 64)]
    pub struct LblReply {
        /// Common header; `stamp_ns` is the reply's reception time.
        pub header: Header,
        /// Transponder that replied.
        pub transponder_id: u32,
        /// Zero.
        pub pad: u32,
        /// Stamp of the interrogation this replies to, ns.
        pub interrogation_stamp_ns: u64,
        /// Stamp of the reply's reception, ns.
        pub reply_stamp_ns: u64,
        /// Measured round-trip time including the turnaround delay, s.
        pub round_trip_s: f64,
    }
}

message! {
    /// A request to interrogate one LBL transponder.
    #[wire(type_name = "nauta.LblInterrogation.v1", size = 40)]
    pub struct LblInterrogation {
        /// Common header; `stamp_ns` is when the ping is sent.
        pub header: Header,
        /// Transponder to ping.
        pub transponder_id: u32,
        /// Zero.
        pub pad: u32,
    }
}

message! {
    /// The simulator's true state.
    #[wire(type_name = "nauta.TruthState.v1", size = 168)]
    pub struct TruthState {
        /// Common header.
        pub header: Header,
        /// Geodetic latitude, rad.
        pub lat_rad: f64,
        /// Geodetic longitude, rad.
        pub lon_rad: f64,
        /// Depth, m, positive down.
        pub depth_m: f64,
        /// Velocity over ground, NED, m/s.
        pub vel_ned_m_s: [f64; 3],
        /// Attitude quaternion body → NED, [w, x, y, z].
        pub quat_nb: [f64; 4],
        /// Angular rate of body relative to NED, FRD, rad/s.
        pub rate_nb_body_rad_s: [f64; 3],
        /// Water current, NED, m/s.
        pub current_ned_m_s: [f64; 3],
        /// Distance travelled over ground since start, m.
        pub distance_m: f64,
    }
}

/// Any message of the sensor process's data services (the simulator's or a
/// replay's output), with its service and its place in the publishing order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SensorMessage {
    /// `sim/truth`.
    Truth(TruthState),
    /// `sensor/imu`.
    Imu(ImuSample),
    /// `sensor/ahrs`.
    Ahrs(AhrsSample),
    /// `sensor/dvl`.
    Dvl(DvlSample),
    /// `sensor/depth`.
    Depth(DepthSample),
    /// `sensor/gps`.
    Gps(GpsFix),
    /// `sensor/propeller`.
    Propeller(PropellerSample),
    /// `sensor/modem`.
    Modem(BuoyRange),
    /// `sensor/lbl`.
    Lbl(LblReply),
}

impl SensorMessage {
    /// The services in publishing order within one stamp (the simulator's
    /// order: the truth first).
    pub const SERVICES: [&'static str; 9] = [
        TRUTH_SERVICE,
        IMU_SERVICE,
        AHRS_SERVICE,
        DVL_SERVICE,
        DEPTH_SERVICE,
        GPS_SERVICE,
        PROPELLER_SERVICE,
        MODEM_SERVICE,
        LBL_REPLY_SERVICE,
    ];

    /// Index of its service in [`SensorMessage::SERVICES`].
    pub fn order(&self) -> usize {
        match self {
            Self::Truth(_) => 0,
            Self::Imu(_) => 1,
            Self::Ahrs(_) => 2,
            Self::Dvl(_) => 3,
            Self::Depth(_) => 4,
            Self::Gps(_) => 5,
            Self::Propeller(_) => 6,
            Self::Modem(_) => 7,
            Self::Lbl(_) => 8,
        }
    }

    /// Its service.
    pub fn service(&self) -> &'static str {
        Self::SERVICES[self.order()]
    }

    /// Its header.
    pub fn header(&self) -> &Header {
        use crate::Message;
        match self {
            Self::Truth(m) => m.header(),
            Self::Imu(m) => m.header(),
            Self::Ahrs(m) => m.header(),
            Self::Dvl(m) => m.header(),
            Self::Depth(m) => m.header(),
            Self::Gps(m) => m.header(),
            Self::Propeller(m) => m.header(),
            Self::Modem(m) => m.header(),
            Self::Lbl(m) => m.header(),
        }
    }

    /// Its header, mutable.
    pub fn header_mut(&mut self) -> &mut Header {
        use crate::Message;
        match self {
            Self::Truth(m) => m.header_mut(),
            Self::Imu(m) => m.header_mut(),
            Self::Ahrs(m) => m.header_mut(),
            Self::Dvl(m) => m.header_mut(),
            Self::Depth(m) => m.header_mut(),
            Self::Gps(m) => m.header_mut(),
            Self::Propeller(m) => m.header_mut(),
            Self::Modem(m) => m.header_mut(),
            Self::Lbl(m) => m.header_mut(),
        }
    }

    /// Decodes a recorded payload of `service`, a message of `type_name`;
    /// `None` for a service that is not a sensor service. A `GpsFix.v1` of
    /// an older recording becomes a v2 fix without a velocity.
    pub fn decode(
        service: &str,
        type_name: &str,
        data: &[u8],
    ) -> Option<Result<SensorMessage, crate::codec::DecodeError>> {
        use crate::Message;
        use crate::codec::decode;
        if service == GPS_SERVICE && type_name == GpsFixV1::TYPE_NAME {
            return Some(decode::<GpsFixV1>(data).map(|m| Self::Gps(GpsFix::from(&m))));
        }
        Some(match service {
            TRUTH_SERVICE => decode(data).map(Self::Truth),
            IMU_SERVICE => decode(data).map(Self::Imu),
            AHRS_SERVICE => decode(data).map(Self::Ahrs),
            DVL_SERVICE => decode(data).map(Self::Dvl),
            DEPTH_SERVICE => decode(data).map(Self::Depth),
            GPS_SERVICE => decode(data).map(Self::Gps),
            PROPELLER_SERVICE => decode(data).map(Self::Propeller),
            MODEM_SERVICE => decode(data).map(Self::Modem),
            LBL_REPLY_SERVICE => decode(data).map(Self::Lbl),
            _ => return None,
        })
    }

    /// Its bincode encoding (see [`crate::codec`]).
    pub fn encode(&self) -> Result<Vec<u8>, crate::codec::EncodeError> {
        use crate::codec::encode;
        match self {
            Self::Truth(m) => encode(m),
            Self::Imu(m) => encode(m),
            Self::Ahrs(m) => encode(m),
            Self::Dvl(m) => encode(m),
            Self::Depth(m) => encode(m),
            Self::Gps(m) => encode(m),
            Self::Propeller(m) => encode(m),
            Self::Modem(m) => encode(m),
            Self::Lbl(m) => encode(m),
        }
    }

    /// The type of its service.
    pub fn type_info(&self) -> crate::TypeInfo {
        use crate::TypeInfo;
        match self {
            Self::Truth(_) => TypeInfo::of::<TruthState>(),
            Self::Imu(_) => TypeInfo::of::<ImuSample>(),
            Self::Ahrs(_) => TypeInfo::of::<AhrsSample>(),
            Self::Dvl(_) => TypeInfo::of::<DvlSample>(),
            Self::Depth(_) => TypeInfo::of::<DepthSample>(),
            Self::Gps(_) => TypeInfo::of::<GpsFix>(),
            Self::Propeller(_) => TypeInfo::of::<PropellerSample>(),
            Self::Modem(_) => TypeInfo::of::<BuoyRange>(),
            Self::Lbl(_) => TypeInfo::of::<LblReply>(),
        }
    }
}
