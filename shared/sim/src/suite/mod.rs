//! The sensor suite (DESIGN §4, §10): turns each `(Truth, noise-free IMU)`
//! step of [`crate::trajectory::Simulator`] into the measurements due at that
//! step, one plain struct per wire message of `nauta-messages` (field for
//! field, `header.stamp_ns` → `stamp_ns`; `seq`, `source`, `instance`, `flags`
//! are the publisher's). Fields marked "simulator annotation" are not on the
//! wire; they let tests and evaluation count events.
//!
//! # Time
//!
//! A step's stamp is `round(t_s · 10⁹)` ns. A sensor of rate f samples at the
//! first step whose stamp reaches each multiple of `round(10⁹ / f)` ns
//! (so 10 Hz over the 100 Hz steps gives t = 0.1, 0.2, … s).
//!
//! # Seeds
//!
//! Each sensor draws from its own `ChaCha8Rng::seed_from_u64(seed)` on its
//! own stream ([`rand_chacha::ChaCha8Rng::set_stream`], one fixed stream id
//! per sensor), so enabling, disabling or reconfiguring one sensor does not
//! change the numbers another one draws.
//!
//! # Acoustics (buoy modem and LBL)
//!
//! Straight rays at one true sound speed c ([`SuiteConfig::sound_speed_m_s`]),
//! in the mission's local north/east/depth frame (flat mapping of
//! [`crate::mission::Origin`], the same as [`crate::trajectory::Truth::north_m`]).
//! A signal sent at t_e from a fixed point s reaches the moving vehicle at the
//! first t with c (t − t_e) ≥ |p(t) − s|. The suite checks this at each step;
//! when it first holds, it solves for t by bisection between the previous and
//! the current step with the vehicle position interpolated linearly between
//! the two truths (error ≲ a Δt²/8, below a micrometre at 100 Hz for the
//! vehicle's accelerations; the steps themselves are exact truth). Reception is
//! thus exact to rounding, not a fixed-point iteration on a predicted track.
//!
//! - Buoy: the buoy is taken at its broadcast-time position (it moves a few
//!   cm/s, so ~1 mm during a flight). Time of flight = range / c + clock
//!   jitter ([`ModemNoise`]); the message is stamped with the true reception
//!   time and delivered at the step that contains it.
//! - LBL: [`SensorSuite::interrogate`] registers a ping at `stamp_ns`. Outbound
//!   leg from the vehicle position at `stamp_ns` (interpolated between steps)
//!   to the transponder, turnaround t_ta and the reply's detection jitter
//!   ε (drawn then, its own stream), return leg to the moving vehicle as
//!   above (the reply is heard at the jittered time, so it is delivered at
//!   the step that holds its stamp, never before one already published). [`LblNoise`] then gets the effective range (d_out + d_back) / 2, so
//!   its 2r/c + t_ta is the true two-way time; it decides detection and
//!   multipath and quantises to the 100 µs clock. The reply is stamped
//!   `stamp_ns + ticks · Δ` and delivered at the step where the direct
//!   wavefront arrives (a stamp that the floor quantisation puts up to one tick
//!   before the previous step is still delivered then), or for a multipath
//!   reply at the first step at or after its (later) stamp. Only the interrogated transponder
//!   replies. An interrogation stamped before the last step seen uses that
//!   step's position (interrogate with the latest stamp, as a navigator does).

mod config;
mod readings;

pub use config::{
    AhrsConfig, DepthConfig, DvlConfig, GpsConfig, ImuConfig, LblConfig, LblLayout, ModemConfig,
    PropellerConfig, SuiteConfig, SuiteError, Transponder,
};
pub use readings::{
    AhrsReading, BuoyRangeReading, DepthReading, DvlEvent, DvlReading, GpsReading, ImuReading,
    LblReplyReading, Measurements, PropellerReading, SuiteStats, TruthReading,
};

use nauta_estimation::frames::{Frd, Ned, Rotation};
use std::f64::consts::TAU;

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::environment::{Environment, meridian_radius, transverse_radius};
use crate::mission::Origin;
use crate::noise::{
    DepthNoise, DvlNoise, DvlOutcome, InertialTriadNoise, LblNoise, LblOutcome, MagnetometerNoise,
    ModemNoise, ModemOutcome,
};
use crate::trajectory::{ImuSample, Simulator, Truth};

/// Stream ids of the per-sensor generators (fixed: changing them changes every run).
mod stream {
    pub const GYRO: u64 = 1;
    pub const ACCEL: u64 = 2;
    pub const MAG: u64 = 3;
    pub const AHRS: u64 = 4;
    pub const DVL: u64 = 5;
    pub const DEPTH: u64 = 6;
    pub const GPS: u64 = 7;
    pub const PROPELLER: u64 = 8;
    pub const MODEM: u64 = 9;
    pub const BUOY: u64 = 10;
    pub const LBL: u64 = 11;
    /// DVL spikes apart from the DVL's noise (a spike-free run differs only by its spikes).
    pub const DVL_SPIKE: u64 = 12;
    /// GPS velocity noise, apart from the position's (`nauta.GpsFix.v2`
    /// added the velocity; the positions of v1 runs stay as they were).
    pub const GPS_VELOCITY: u64 = 13;
    /// The modem's multipath outliers, apart from its losses and jitter.
    pub const MODEM_MULTIPATH: u64 = 14;
    /// LBL detection jitter, apart from detection and multipath (a run
    /// without jitter has the same replies and outliers).
    pub const LBL_JITTER: u64 = 15;
}

fn sensor_rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// Stamp of a time in seconds, ns.
pub fn stamp_ns(t_s: f64) -> u64 {
    (t_s * 1e9).round().max(0.0) as u64
}

fn seconds(stamp_ns: u64) -> f64 {
    stamp_ns as f64 * 1e-9
}

fn wrap_2pi(a: f64) -> f64 {
    let w = a.rem_euclid(TAU);
    if w >= TAU { 0.0 } else { w }
}

#[derive(Debug, Clone, Copy)]
struct Schedule {
    period_ns: u64,
    next_ns: u64,
}

impl Schedule {
    fn new(rate_hz: f64) -> Self {
        Self::every(1.0 / rate_hz)
    }

    fn every(period_s: f64) -> Self {
        let period_ns = stamp_ns(period_s).max(1);
        Self {
            period_ns,
            next_ns: period_ns,
        }
    }

    fn due(&mut self, stamp: u64) -> bool {
        if stamp < self.next_ns {
            return false;
        }
        while self.next_ns <= stamp {
            self.next_ns += self.period_ns;
        }
        true
    }
}

fn position(t: &Truth) -> Vector3<f64> {
    Vector3::new(t.north_m, t.east_m, t.depth_m)
}

/// First reception time in (max(t_prev, t_emit), t_now] of a signal sent at
/// `t_emit` from `source`, if it has reached the vehicle by `now`.
fn reception(
    c: f64,
    t_emit: f64,
    source: &Vector3<f64>,
    prev: Option<&Truth>,
    now: &Truth,
) -> Option<f64> {
    let p1 = position(now);
    let t1 = now.t_s;
    if c * (t1 - t_emit) < (p1 - source).norm() {
        return None;
    }
    let Some(prev) = prev else {
        return Some(t1);
    };
    let (t0, p0) = (prev.t_s, position(prev));
    let at = |t: f64| {
        let f = if t1 > t0 { (t - t0) / (t1 - t0) } else { 1.0 };
        p0 + (p1 - p0) * f
    };
    let g = |t: f64| c * (t - t_emit) - (at(t) - source).norm();
    let mut lo = t0.max(t_emit);
    let mut hi = t1;
    if g(lo) >= 0.0 {
        return Some(lo);
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if g(mid) >= 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(hi)
}

#[derive(Debug, Clone)]
struct ImuState {
    gyro: InertialTriadNoise,
    accel: InertialTriadNoise,
    mag: MagnetometerNoise,
    rng_gyro: ChaCha8Rng,
    rng_accel: ChaCha8Rng,
    rng_mag: ChaCha8Rng,
}

#[derive(Debug, Clone)]
struct AhrsState {
    schedule: Schedule,
    bias_rad: f64,
    phi: f64,
    rng: ChaCha8Rng,
}

#[derive(Debug, Clone)]
struct DvlState {
    schedule: Schedule,
    noise: DvlNoise,
    rng: ChaCha8Rng,
    spike_rng: ChaCha8Rng,
}

#[derive(Debug, Clone)]
struct Broadcast {
    send_s: f64,
    send_ns: u64,
    buoy: Vector3<f64>,
    lat_rad: f64,
    lon_rad: f64,
}

#[derive(Debug, Clone)]
struct ModemState {
    schedule: Schedule,
    noise: ModemNoise,
    rng: ChaCha8Rng,
    multipath_rng: ChaCha8Rng,
    buoy_rng: ChaCha8Rng,
    walk: [f64; 2],
    walk_t_s: f64,
    in_flight: Vec<Broadcast>,
}

#[derive(Debug, Clone, Copy)]
enum PingLeg {
    /// Send time not reached by the steps yet.
    Waiting,
    /// Reply emitted from the transponder at `emit_s`, travelling back.
    Returning {
        d_out: f64,
        emit_s: f64,
        /// The reply's detection jitter, s (in `emit_s` already).
        jitter_s: f64,
    },
}

#[derive(Debug, Clone, Copy)]
struct Ping {
    transponder: Transponder,
    send_ns: u64,
    leg: PingLeg,
}

#[derive(Debug, Clone)]
struct LblState {
    noise: LblNoise,
    rng: ChaCha8Rng,
    jitter_rng: ChaCha8Rng,
    tick_ns: u64,
    pings: Vec<Ping>,
    replies: Vec<LblReplyReading>,
}

/// The seeded sensor suite; see the module docs.
#[derive(Debug, Clone)]
pub struct SensorSuite {
    config: SuiteConfig,
    origin: Origin,
    declination_rad: f64,
    sound_speed_m_s: f64,
    imu: Option<ImuState>,
    ahrs: Option<AhrsState>,
    dvl: Option<DvlState>,
    depth: Option<(Schedule, DepthNoise, ChaCha8Rng)>,
    gps: Option<(Schedule, ChaCha8Rng, ChaCha8Rng)>,
    propeller: Option<(Schedule, ChaCha8Rng)>,
    modem: Option<ModemState>,
    lbl: Option<LblState>,
    prev: Option<Truth>,
    stats: SuiteStats,
}

impl SensorSuite {
    /// A suite for a run from `origin` in `env` (declination from
    /// `env.magnetic`, sound speed from `env.water` unless configured).
    pub fn new(
        config: SuiteConfig,
        seed: u64,
        origin: Origin,
        env: &Environment,
    ) -> Result<Self, SuiteError> {
        config.validate()?;
        let c = config
            .sound_speed_m_s
            .unwrap_or_else(|| env.water.sound_speed_m_s(10.0));
        let imu = if config.imu.enabled {
            let mut rng_gyro = sensor_rng(seed, stream::GYRO);
            let mut rng_accel = sensor_rng(seed, stream::ACCEL);
            Some(ImuState {
                gyro: InertialTriadNoise::new(config.imu.gyro, &mut rng_gyro)?,
                accel: InertialTriadNoise::new(config.imu.accel, &mut rng_accel)?,
                mag: MagnetometerNoise::new(config.imu.mag)?,
                rng_gyro,
                rng_accel,
                rng_mag: sensor_rng(seed, stream::MAG),
            })
        } else {
            None
        };
        let ahrs = config.ahrs.enabled.then(|| {
            let a = &config.ahrs;
            let mut rng = sensor_rng(seed, stream::AHRS);
            let bias_rad = a.heading_bias_sigma_rad * normal(&mut rng);
            AhrsState {
                schedule: Schedule::new(a.rate_hz),
                bias_rad,
                phi: (-1.0 / (a.rate_hz * a.heading_bias_time_s)).exp(),
                rng,
            }
        });
        let dvl = if config.dvl.enabled {
            let mut rng = sensor_rng(seed, stream::DVL);
            Some(DvlState {
                schedule: Schedule::new(config.dvl.rate_hz),
                noise: DvlNoise::new(config.dvl.noise, &mut rng)?,
                rng,
                spike_rng: sensor_rng(seed, stream::DVL_SPIKE),
            })
        } else {
            None
        };
        let depth = if config.depth.enabled {
            Some((
                Schedule::new(config.depth.rate_hz),
                DepthNoise::new(config.depth.noise)?,
                sensor_rng(seed, stream::DEPTH),
            ))
        } else {
            None
        };
        let gps = config.gps.enabled.then(|| {
            (
                Schedule::new(config.gps.rate_hz),
                sensor_rng(seed, stream::GPS),
                sensor_rng(seed, stream::GPS_VELOCITY),
            )
        });
        let propeller = config.propeller.enabled.then(|| {
            (
                Schedule::new(config.propeller.rate_hz),
                sensor_rng(seed, stream::PROPELLER),
            )
        });
        let modem = if config.modem.enabled {
            let mut spec = config.modem.noise;
            spec.sound_speed = c;
            Some(ModemState {
                schedule: Schedule::every(config.modem.period_s),
                noise: ModemNoise::new(spec)?,
                rng: sensor_rng(seed, stream::MODEM),
                multipath_rng: sensor_rng(seed, stream::MODEM_MULTIPATH),
                buoy_rng: sensor_rng(seed, stream::BUOY),
                walk: [0.0; 2],
                walk_t_s: 0.0,
                in_flight: Vec::new(),
            })
        } else {
            None
        };
        let lbl = if config.lbl.enabled {
            let mut spec = config.lbl.noise;
            spec.sound_speed = c;
            Some(LblState {
                noise: LblNoise::new(spec)?,
                rng: sensor_rng(seed, stream::LBL),
                jitter_rng: sensor_rng(seed, stream::LBL_JITTER),
                tick_ns: stamp_ns(spec.clock_resolution).max(1),
                pings: Vec::new(),
                replies: Vec::new(),
            })
        } else {
            None
        };
        Ok(Self {
            config,
            origin,
            declination_rad: env.magnetic.declination_rad,
            sound_speed_m_s: c,
            imu,
            ahrs,
            dvl,
            depth,
            gps,
            propeller,
            modem,
            lbl,
            prev: None,
            stats: SuiteStats::default(),
        })
    }

    /// A suite for `sim`'s mission origin and environment.
    pub fn for_simulator(
        config: SuiteConfig,
        seed: u64,
        sim: &Simulator,
    ) -> Result<Self, SuiteError> {
        Self::new(config, seed, sim.mission().origin(), sim.environment())
    }

    /// The configuration.
    pub fn config(&self) -> &SuiteConfig {
        &self.config
    }

    /// The true sound speed used for acoustics, m/s.
    pub fn sound_speed_m_s(&self) -> f64 {
        self.sound_speed_m_s
    }

    /// Magnetic declination used by the AHRS, rad.
    pub fn declination_rad(&self) -> f64 {
        self.declination_rad
    }

    /// Event counters so far.
    pub fn stats(&self) -> SuiteStats {
        self.stats
    }

    /// Registers a ping to `transponder_id` requested at `stamp_ns`; it leaves
    /// at the next tick of the LBL clock at or after it (see the module docs),
    /// which is the reply's `interrogation_stamp_ns`. Errors if LBL is
    /// disabled or the id unknown.
    pub fn interrogate(&mut self, transponder_id: u32, stamp_ns: u64) -> Result<(), SuiteError> {
        let lbl = self.lbl.as_mut().ok_or(SuiteError::LblDisabled)?;
        let transponder = *self
            .config
            .lbl
            .transponders
            .iter()
            .find(|t| t.id == transponder_id)
            .ok_or(SuiteError::UnknownTransponder(transponder_id))?;
        // The acoustic system fires on its own clock: the next tick at or
        // after the request, so every reply stamp is a whole number of ticks.
        let send_ns = stamp_ns.div_ceil(lbl.tick_ns) * lbl.tick_ns;
        let mut ping = Ping {
            transponder,
            send_ns,
            leg: PingLeg::Waiting,
        };
        if let Some(last) = &self.prev
            && send_ns <= self::stamp_ns(last.t_s)
        {
            ping.leg = outbound(self.sound_speed_m_s, lbl, &ping, &position(last));
        }
        lbl.pings.push(ping);
        self.stats.lbl_interrogations += 1;
        Ok(())
    }

    /// Pings still waiting for their reply (or its detection).
    pub fn pending_interrogations(&self) -> usize {
        self.lbl
            .as_ref()
            .map_or(0, |l| l.pings.len() + l.replies.len())
    }

    /// The measurements due at this step (`truth`, `imu` from one
    /// [`Simulator::step`]).
    pub fn step(&mut self, truth: &Truth, imu: &ImuSample) -> Result<Measurements, SuiteError> {
        if !(imu.dt_s.is_finite() && imu.dt_s > 0.0) {
            return Err(SuiteError::BadInterval(imu.dt_s));
        }
        let stamp = stamp_ns(truth.t_s);
        let mut out = Measurements {
            stamp_ns: stamp,
            truth: TruthReading::from_truth(truth),
            imu: None,
            ahrs: None,
            dvl: None,
            depth: None,
            gps: None,
            modem: None,
            propeller: None,
            lbl: Vec::new(),
        };
        if let Some(s) = &mut self.imu {
            let gyro = s.gyro.next(&mut s.rng_gyro, imu.gyro_rad_s, imu.dt_s)?;
            let accel = s.accel.next(&mut s.rng_accel, imu.accel_m_s2, imu.dt_s)?;
            let mag = s.mag.next(&mut s.rng_mag, imu.mag_t) * 1e6;
            out.imu = Some(ImuReading {
                stamp_ns: stamp,
                gyro_rad_s: gyro.into(),
                accel_m_s2: accel.into(),
                mag_ut: mag.into(),
                interval_s: imu.dt_s,
            });
        }
        let (roll, pitch, yaw) = truth.euler_rad();
        if let Some(s) = &mut self.ahrs
            && s.schedule.due(stamp)
        {
            let a = &self.config.ahrs;
            let rp = a.roll_pitch_sigma_rad;
            let roll_rad = roll + rp * normal(&mut s.rng);
            let pitch_rad = pitch + rp * normal(&mut s.rng);
            let heading =
                yaw - self.declination_rad + s.bias_rad + a.heading_sigma_rad * normal(&mut s.rng);
            s.bias_rad = s.phi * s.bias_rad
                + a.heading_bias_sigma_rad * (1.0 - s.phi * s.phi).sqrt() * normal(&mut s.rng);
            out.ahrs = Some(AhrsReading {
                stamp_ns: stamp,
                roll_rad,
                pitch_rad,
                heading_mag_rad: wrap_2pi(heading),
            });
        }
        if let Some(s) = &mut self.dvl
            && s.schedule.due(stamp)
        {
            let d = &self.config.dvl;
            let altitude = d.seafloor_depth_m - truth.depth_m;
            let v_body = truth.q_nb.inverse_transform_vector(&truth.v_ned_m_s);
            let in_range = altitude >= d.min_altitude_m && altitude <= d.max_altitude_m;
            let (event, velocity) = if in_range {
                match s.noise.next(&mut s.rng, &mut s.spike_rng, v_body) {
                    DvlOutcome::Valid(v) => (DvlEvent::Valid, Some(v)),
                    DvlOutcome::Spike { velocity, axis } => {
                        (DvlEvent::Spike { axis }, Some(velocity))
                    }
                    DvlOutcome::Dropout => (DvlEvent::Dropout, None),
                }
            } else {
                (DvlEvent::OutOfRange, None)
            };
            match event {
                DvlEvent::Valid => self.stats.dvl_valid += 1,
                DvlEvent::Spike { .. } => self.stats.dvl_spikes += 1,
                DvlEvent::Dropout => self.stats.dvl_dropouts += 1,
                DvlEvent::OutOfRange => self.stats.dvl_out_of_range += 1,
            }
            out.dvl = Some(match velocity {
                Some(v) => DvlReading {
                    stamp_ns: stamp,
                    velocity_body_m_s: v.into(),
                    altitude_m: altitude + d.altitude_sigma_m * normal(&mut s.rng),
                    beams_valid: 0b1111,
                    bottom_lock: 1,
                    figure_of_merit_m_s: d.noise.noise_sigma,
                    event,
                },
                None => DvlReading {
                    stamp_ns: stamp,
                    velocity_body_m_s: [0.0; 3],
                    altitude_m: 0.0,
                    beams_valid: 0,
                    bottom_lock: 0,
                    figure_of_merit_m_s: 0.0,
                    event,
                },
            });
        }
        if let Some((schedule, noise, rng)) = &mut self.depth
            && schedule.due(stamp)
        {
            out.depth = Some(DepthReading {
                stamp_ns: stamp,
                depth_m: noise.next(rng, truth.depth_m),
            });
        }
        if let Some((schedule, rng, vel_rng)) = &mut self.gps {
            let g = &self.config.gps;
            if schedule.due(stamp) && truth.depth_m < g.max_depth_m {
                let dn = g.horizontal_sigma_m * normal(rng);
                let de = g.horizontal_sigma_m * normal(rng);
                let dh = g.vertical_sigma_m * normal(rng);
                let lat = truth.lat_rad;
                out.gps = Some(GpsReading {
                    stamp_ns: stamp,
                    lat_rad: lat + dn / meridian_radius(lat),
                    lon_rad: truth.lon_rad + de / (transverse_radius(lat) * lat.cos()),
                    height_m: truth.height_m() + dh,
                    horizontal_std_m: g.horizontal_sigma_m,
                    quality: g.quality,
                    satellites: g.satellites,
                    vel_ned_m_s: std::array::from_fn(|i| {
                        truth.v_ned_m_s[i] + g.velocity_sigma_m_s * normal(vel_rng)
                    }),
                    vel_std_m_s: g.velocity_sigma_m_s,
                });
            }
        }
        if let Some((schedule, rng)) = &mut self.propeller
            && schedule.due(stamp)
        {
            out.propeller = Some(PropellerReading {
                stamp_ns: stamp,
                shaft_speed_rad_s: truth.propeller_rad_s
                    + self.config.propeller.noise_sigma_rad_s * normal(rng),
            });
        }
        self.step_modem(truth, stamp, &mut out);
        self.step_lbl(truth, stamp, &mut out);
        self.prev = Some(*truth);
        Ok(out)
    }

    fn step_modem(&mut self, truth: &Truth, stamp: u64, out: &mut Measurements) {
        let Some(s) = &mut self.modem else {
            return;
        };
        let m = &self.config.modem;
        let c = self.sound_speed_m_s;
        if s.schedule.due(stamp) {
            let t = truth.t_s;
            let q = m.buoy_random_walk_m_rt_s * (t - s.walk_t_s).max(0.0).sqrt();
            s.walk[0] += q * normal(&mut s.buoy_rng);
            s.walk[1] += q * normal(&mut s.buoy_rng);
            s.walk_t_s = t;
            let buoy = Vector3::new(
                m.buoy_north_m + m.buoy_drift_north_m_s * t + s.walk[0],
                m.buoy_east_m + m.buoy_drift_east_m_s * t + s.walk[1],
                m.buoy_depth_m,
            );
            let gn = buoy.x + m.buoy_gps_sigma_m * normal(&mut s.buoy_rng);
            let ge = buoy.y + m.buoy_gps_sigma_m * normal(&mut s.buoy_rng);
            let (lat_rad, lon_rad) = self.origin.to_geodetic(gn, ge);
            s.in_flight.push(Broadcast {
                send_s: t,
                send_ns: stamp,
                buoy,
                lat_rad,
                lon_rad,
            });
            self.stats.modem_sent += 1;
        }
        let prev = self.prev.as_ref();
        let mut i = 0;
        while i < s.in_flight.len() {
            let b = &s.in_flight[i];
            let Some(t_r) = reception(c, b.send_s, &b.buoy, prev, truth) else {
                i += 1;
                continue;
            };
            let b = s.in_flight.remove(i);
            let range = c * (t_r - b.send_s);
            let outcome = s.noise.next(&mut s.rng, &mut s.multipath_rng, range);
            match outcome {
                ModemOutcome::Lost => self.stats.modem_lost += 1,
                ModemOutcome::Multipath(_) => self.stats.modem_multipath += 1,
                ModemOutcome::Received(_) => {}
            }
            // A multipath message keeps the direct path's reception stamp
            // (its later arrival, 13-133 ms, is 0.02-0.2 m of the vehicle's
            // motion); its time of flight carries the extra path.
            if let Some(r) = outcome.reception() {
                out.modem = Some(BuoyRangeReading {
                    stamp_ns: stamp_ns(t_r),
                    buoy_lat_rad: b.lat_rad,
                    buoy_lon_rad: b.lon_rad,
                    buoy_depth_m: m.buoy_depth_m,
                    time_of_flight_s: r.time_of_flight,
                    sound_speed_m_s: c * (1.0 + m.noise.sound_speed_error),
                    send_stamp_ns: b.send_ns,
                    true_range_m: range,
                    true_buoy_north_east_m: [b.buoy.x, b.buoy.y],
                });
            }
        }
    }

    fn step_lbl(&mut self, truth: &Truth, stamp: u64, out: &mut Measurements) {
        let Some(s) = &mut self.lbl else {
            return;
        };
        let c = self.sound_speed_m_s;
        let blackout = self.config.lbl.blackout_s;
        let prev = self.prev.as_ref();
        let mut i = 0;
        while i < s.pings.len() {
            let mut ping = s.pings[i];
            if let PingLeg::Waiting = ping.leg {
                if ping.send_ns > stamp {
                    i += 1;
                    continue;
                }
                // Vehicle at the send time, interpolated between the steps.
                let p1 = position(truth);
                let send_s = seconds(ping.send_ns);
                let p = match prev {
                    Some(pr) if truth.t_s > pr.t_s && send_s >= pr.t_s => {
                        let f = (send_s - pr.t_s) / (truth.t_s - pr.t_s);
                        position(pr) + (p1 - position(pr)) * f
                    }
                    Some(pr) => position(pr),
                    None => p1,
                };
                ping.leg = outbound(c, s, &ping, &p);
                s.pings[i] = ping;
            }
            let PingLeg::Returning {
                d_out,
                emit_s,
                jitter_s,
            } = ping.leg
            else {
                i += 1;
                continue;
            };
            let tx = &ping.transponder;
            let src = Vector3::new(tx.north_m, tx.east_m, tx.depth_m);
            let Some(t_r) = reception(c, emit_s, &src, prev, truth) else {
                i += 1;
                continue;
            };
            s.pings.remove(i);
            let d_back = c * (t_r - emit_s);
            let r_eff = 0.5 * (d_out + d_back);
            let true_rt = (d_out + d_back) / c + tx.turnaround_s;
            let outcome = s.noise.next(&mut s.rng, r_eff, tx.turnaround_s + jitter_s);
            // The draws are made whatever the blackout: a run with one
            // differs from one without only by the replies it loses.
            if blackout.is_some_and(|[a, b]| t_r >= a && t_r <= b) {
                self.stats.lbl_blackout += 1;
                continue;
            }
            let (reply, multipath) = match outcome {
                LblOutcome::NoReply => {
                    self.stats.lbl_no_reply += 1;
                    continue;
                }
                LblOutcome::Direct(r) => (r, false),
                LblOutcome::Multipath(r) => {
                    self.stats.lbl_multipath += 1;
                    (r, true)
                }
            };
            let reply_ns = ping.send_ns + reply.ticks * s.tick_ns;
            s.replies.push(LblReplyReading {
                stamp_ns: reply_ns,
                transponder_id: tx.id,
                interrogation_stamp_ns: ping.send_ns,
                reply_stamp_ns: reply_ns,
                round_trip_s: reply.round_trip,
                multipath,
                true_round_trip_s: true_rt,
            });
        }
        let mut due: Vec<LblReplyReading> = Vec::new();
        s.replies.retain(|r| {
            if r.stamp_ns <= stamp {
                due.push(*r);
                false
            } else {
                true
            }
        });
        due.sort_by_key(|r| r.stamp_ns);
        out.lbl = due;
    }
}

/// The outbound leg of a ping from vehicle position `p` at its send time;
/// the reply's detection jitter is drawn now and carried by the return leg
/// (the reply is heard at the jittered time).
fn outbound(c: f64, s: &mut LblState, ping: &Ping, p: &Vector3<f64>) -> PingLeg {
    let tx = &ping.transponder;
    let d_out = (Vector3::new(tx.north_m, tx.east_m, tx.depth_m) - p).norm();
    let jitter_s = s.noise.jitter(&mut s.jitter_rng);
    PingLeg::Returning {
        d_out,
        emit_s: seconds(ping.send_ns) + d_out / c + tx.turnaround_s + jitter_s,
        jitter_s,
    }
}

#[cfg(test)]
mod tests;
