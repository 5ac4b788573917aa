//! What the sensor suite produces at one step: each sensor's reading
//! (with the diagnostic fields the wire messages do not carry), the truth,
//! and the suite's counters.

use super::*;

/// `sensor/imu` (`ImuSample`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuReading {
    /// End of the integration interval, ns.
    pub stamp_ns: u64,
    /// Angular rate w.r.t. inertial space, interval average, rad/s, FRD.
    pub gyro_rad_s: [f64; 3],
    /// Specific force, interval average, m/s², FRD.
    pub accel_m_s2: [f64; 3],
    /// Magnetic flux density, µT, FRD.
    pub mag_ut: [f64; 3],
    /// Interval, s.
    pub interval_s: f64,
}

/// `sensor/ahrs` (`AhrsSample`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AhrsReading {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Roll, rad.
    pub roll_rad: f64,
    /// Pitch, rad.
    pub pitch_rad: f64,
    /// Heading w.r.t. magnetic north, rad, [0, 2π).
    pub heading_mag_rad: f64,
}

/// What the DVL model did for one ping (simulator annotation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DvlEvent {
    /// Normal measurement.
    Valid,
    /// Spiked measurement on `axis` (0 surge, 1 sway, 2 heave).
    Spike {
        /// Axis hit.
        axis: usize,
    },
    /// Dropout ([`crate::noise::DvlSpec`]).
    Dropout,
    /// Altitude outside the bottom-track window: no lock.
    OutOfRange,
}

/// `sensor/dvl` (`DvlSample`). Without lock: velocity and altitude 0,
/// `beams_valid` 0, `bottom_lock` 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DvlReading {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Velocity over ground, m/s, FRD.
    pub velocity_body_m_s: [f64; 3],
    /// Altitude above the bottom, m.
    pub altitude_m: f64,
    /// Bit i for beam i (0b1111 with lock, 0 without).
    pub beams_valid: u32,
    /// 1 with bottom lock, else 0.
    pub bottom_lock: u32,
    /// Figure of merit: the configured white-noise σ with lock, else 0, m/s.
    pub figure_of_merit_m_s: f64,
    /// Simulator annotation: what happened.
    pub event: DvlEvent,
}

/// `sensor/depth` (`DepthSample`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthReading {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Depth, m, positive down.
    pub depth_m: f64,
}

/// `sensor/gps` (`GpsFix`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsReading {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Height above the ellipsoid, m.
    pub height_m: f64,
    /// Horizontal σ (per axis), m.
    pub horizontal_std_m: f64,
    /// Fix quality.
    pub quality: u32,
    /// Satellites used.
    pub satellites: u32,
    /// Velocity over ground, NED, m/s.
    pub vel_ned_m_s: [f64; 3],
    /// Velocity σ per axis, m/s.
    pub vel_std_m_s: f64,
}

/// `sensor/propeller` (`PropellerSample`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PropellerReading {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Shaft speed, rad/s.
    pub shaft_speed_rad_s: f64,
}

/// `sensor/modem` (`BuoyRange`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuoyRangeReading {
    /// Time of reception, ns.
    pub stamp_ns: u64,
    /// Buoy latitude as broadcast (its GPS), rad.
    pub buoy_lat_rad: f64,
    /// Buoy longitude as broadcast, rad.
    pub buoy_lon_rad: f64,
    /// Depth of the buoy's transducer, m.
    pub buoy_depth_m: f64,
    /// Measured one-way time of flight, s.
    pub time_of_flight_s: f64,
    /// Sound speed the buoy reports, m/s.
    pub sound_speed_m_s: f64,
    /// Simulator annotation: broadcast time, ns.
    pub send_stamp_ns: u64,
    /// Simulator annotation: true slant range (buoy at send → vehicle at reception), m.
    pub true_range_m: f64,
    /// Simulator annotation: true buoy (north, east), m.
    pub true_buoy_north_east_m: [f64; 2],
}

/// `sensor/lbl` (`LblReply`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LblReplyReading {
    /// Reception time, ns (= `reply_stamp_ns`).
    pub stamp_ns: u64,
    /// Transponder that replied.
    pub transponder_id: u32,
    /// Stamp of the interrogation, ns.
    pub interrogation_stamp_ns: u64,
    /// Stamp of the reply's reception, ns.
    pub reply_stamp_ns: u64,
    /// Measured round trip including turnaround, s (multiple of the clock resolution).
    pub round_trip_s: f64,
    /// Simulator annotation: a late multipath reply.
    pub multipath: bool,
    /// Simulator annotation: the true direct-path round trip, s.
    pub true_round_trip_s: f64,
}

/// `sim/truth` (`TruthState`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthReading {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Depth, m.
    pub depth_m: f64,
    /// Velocity over ground, NED, m/s.
    pub vel_ned_m_s: [f64; 3],
    /// Attitude body → NED, [w, x, y, z].
    pub quat_nb: [f64; 4],
    /// Body rate relative to NED, FRD, rad/s.
    pub rate_nb_body_rad_s: [f64; 3],
    /// Water current, NED, m/s.
    pub current_ned_m_s: [f64; 3],
    /// Distance over ground since start, m.
    pub distance_m: f64,
}

impl TruthReading {
    /// The wire form of a [`Truth`].
    pub fn from_truth(t: &Truth) -> Self {
        Self {
            stamp_ns: stamp_ns(t.t_s),
            lat_rad: t.lat_rad,
            lon_rad: t.lon_rad,
            depth_m: t.depth_m,
            vel_ned_m_s: t.v_ned_m_s.into(),
            quat_nb: Rotation::<Frd, Ned>::from_nalgebra(t.q_nb).to_wxyz(),
            rate_nb_body_rad_s: t.body_rate_nb_rad_s.into(),
            current_ned_m_s: t.current_ned_m_s.into(),
            distance_m: t.distance_m,
        }
    }
}

/// Everything due at one step.
#[derive(Debug, Clone, PartialEq)]
pub struct Measurements {
    /// The step's stamp, ns.
    pub stamp_ns: u64,
    /// Truth passthrough, every step.
    pub truth: TruthReading,
    /// IMU, every step (when enabled).
    pub imu: Option<ImuReading>,
    /// AHRS.
    pub ahrs: Option<AhrsReading>,
    /// DVL.
    pub dvl: Option<DvlReading>,
    /// Depth.
    pub depth: Option<DepthReading>,
    /// GPS (only near the surface).
    pub gps: Option<GpsReading>,
    /// Buoy message received during this step.
    pub modem: Option<BuoyRangeReading>,
    /// Propeller.
    pub propeller: Option<PropellerReading>,
    /// LBL replies whose stamp falls in this step, in stamp order.
    pub lbl: Vec<LblReplyReading>,
}

/// Event counters (simulator annotation).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SuiteStats {
    /// DVL pings by outcome.
    pub dvl_valid: u64,
    /// DVL spikes.
    pub dvl_spikes: u64,
    /// DVL dropouts.
    pub dvl_dropouts: u64,
    /// DVL pings without lock because of altitude.
    pub dvl_out_of_range: u64,
    /// Buoy messages sent.
    pub modem_sent: u64,
    /// Buoy messages lost.
    pub modem_lost: u64,
    /// Buoy messages received by a longer path (multipath outliers).
    pub modem_multipath: u64,
    /// LBL interrogations registered.
    pub lbl_interrogations: u64,
    /// LBL interrogations without reply.
    pub lbl_no_reply: u64,
    /// LBL multipath replies.
    pub lbl_multipath: u64,
    /// LBL replies lost in the blackout window.
    pub lbl_blackout: u64,
}
