//! [`SuiteConfig`]: which sensors run, at what rate, with what errors.
//!
//! Every table has defaults (`#[serde(default)]`) and rejects unknown keys
//! (`deny_unknown_fields`). A nested noise table (`gyro`, `accel`, `mag`,
//! `noise`) replaces the default spec as a whole: all its fields must be
//! given. Units are SI and radians throughout (degrees appear only in these
//! docs). Sources: "datasheet" (as remembered, to be checked against the PDF),
//! "paper NNN", or "our choice" (nothing to copy from).

use serde::{Deserialize, Serialize};

use crate::noise::{
    DepthSpec, DvlSpec, InertialAxisSpec, LblSpec, MagnetometerSpec, ModemSpec, NoiseError,
};

/// A configuration the suite cannot use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SuiteError {
    /// A noise spec failed its own validation.
    #[error(transparent)]
    Noise(#[from] NoiseError),
    /// A suite parameter is out of range (rates and periods > 0, lengths >= 0, finite).
    #[error("suite parameter {name} out of range: {value}")]
    Invalid {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
    },
    /// The transponders are not a layout (a repeated id, two at one place,
    /// a value out of range).
    #[error("LBL transponders: {0}")]
    Layout(#[from] nauta_estimation::lbl::LayoutError),
    /// An interrogation for a transponder that is not configured.
    #[error("unknown LBL transponder id {0}")]
    UnknownTransponder(u32),
    /// An interrogation while LBL is disabled.
    #[error("LBL is disabled in this suite")]
    LblDisabled,
    /// An IMU interval that is not positive and finite.
    #[error("bad IMU interval {0} s")]
    BadInterval(f64),
}

fn positive(name: &'static str, value: f64) -> Result<(), SuiteError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SuiteError::Invalid { name, value })
    }
}

fn non_negative(name: &'static str, value: f64) -> Result<(), SuiteError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(SuiteError::Invalid { name, value })
    }
}

fn finite(name: &'static str, value: f64) -> Result<(), SuiteError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(SuiteError::Invalid { name, value })
    }
}

/// IMU (`sensor/imu`): gyro, accelerometer and magnetometer at every
/// simulator step (100 Hz).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImuConfig {
    /// Whether the IMU publishes (default true).
    pub enabled: bool,
    /// Gyro axis errors, rad/s (default [`InertialAxisSpec::mti30_gyro`], MTi-30 datasheet).
    pub gyro: InertialAxisSpec,
    /// Accelerometer axis errors, m/s² (default [`InertialAxisSpec::mti30_accel`]).
    pub accel: InertialAxisSpec,
    /// Magnetometer hard/soft iron and noise, tesla inside (published in µT)
    /// (default [`MagnetometerSpec::default`]).
    pub mag: MagnetometerSpec,
}

impl Default for ImuConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            gyro: InertialAxisSpec::mti30_gyro(),
            accel: InertialAxisSpec::mti30_accel(),
            mag: MagnetometerSpec::default(),
        }
    }
}

/// The vehicle's AHRS (`sensor/ahrs`): vendor roll, pitch and magnetic
/// heading. Error model (our choice; the papers give none):
/// roll/pitch = truth + white noise; heading = true heading − declination +
/// b + white noise, with b a first-order Gauss-Markov bias (stationary σ_b,
/// correlation time τ_b) for the slowly varying magnetic disturbances a
/// compass sees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AhrsConfig {
    /// Whether the AHRS publishes (default true).
    pub enabled: bool,
    /// Output rate, Hz (default 10, DESIGN §4).
    pub rate_hz: f64,
    /// Roll and pitch white noise σ, rad (default 0.2°, our choice).
    pub roll_pitch_sigma_rad: f64,
    /// Heading white noise σ, rad (default 1°, our choice).
    pub heading_sigma_rad: f64,
    /// Heading bias stationary σ_b, rad (default 2°, our choice).
    pub heading_bias_sigma_rad: f64,
    /// Heading bias correlation time τ_b, s (default 600, our choice).
    pub heading_bias_time_s: f64,
}

impl Default for AhrsConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            rate_hz: 10.0,
            roll_pitch_sigma_rad: 0.2f64.to_radians(),
            heading_sigma_rad: 1f64.to_radians(),
            heading_bias_sigma_rad: 2f64.to_radians(),
            heading_bias_time_s: 600.0,
        }
    }
}

/// DVL bottom track (`sensor/dvl`). Bottom lock needs an altitude
/// (seafloor depth − vehicle depth, flat seafloor) within
/// [`min_altitude_m`](Self::min_altitude_m), [`max_altitude_m`](Self::max_altitude_m);
/// inside it, [`DvlSpec`] decides valid / dropout / spike.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DvlConfig {
    /// Whether the DVL publishes (default true).
    pub enabled: bool,
    /// Ping rate, Hz (default 5, DESIGN §10).
    pub rate_hz: f64,
    /// Depth of the (flat) seafloor, m (default 60, our choice: coastal
    /// water where every scenario keeps lock).
    pub seafloor_depth_m: f64,
    /// Minimum bottom-track altitude, m (default 0.7, Teledyne RDI Workhorse
    /// Navigator 600 kHz datasheet, as remembered).
    pub min_altitude_m: f64,
    /// Maximum bottom-track altitude, m (default 90, same datasheet, as remembered).
    pub max_altitude_m: f64,
    /// Altitude white noise σ, m (default 0.1, our choice).
    pub altitude_sigma_m: f64,
    /// Velocity errors (default [`DvlSpec::default`]).
    pub noise: DvlSpec,
}

impl Default for DvlConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            rate_hz: 5.0,
            seafloor_depth_m: 60.0,
            min_altitude_m: 0.7,
            max_altitude_m: 90.0,
            altitude_sigma_m: 0.1,
            noise: DvlSpec::default(),
        }
    }
}

/// Pressure depth (`sensor/depth`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DepthConfig {
    /// Whether the depth sensor publishes (default true).
    pub enabled: bool,
    /// Rate, Hz (default 10, DESIGN §10).
    pub rate_hz: f64,
    /// Errors (default [`DepthSpec::default`]).
    pub noise: DepthSpec,
}

impl Default for DepthConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            rate_hz: 10.0,
            noise: DepthSpec::default(),
        }
    }
}

/// Surface GPS (`sensor/gps`): a fix only while the antenna is out of the
/// water (depth below [`max_depth_m`](Self::max_depth_m)). North and east
/// errors are each N(0, σ_h²) (σ_h is the per-axis σ, also published as
/// `horizontal_std_m`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GpsConfig {
    /// Whether the GPS publishes (default true).
    pub enabled: bool,
    /// Rate while surfaced, Hz (default 1, DESIGN §4).
    pub rate_hz: f64,
    /// No fix deeper than this, m (default 0.3, DESIGN §10).
    pub max_depth_m: f64,
    /// Horizontal σ per axis, m (default 2.5, our choice for a stand-alone
    /// single-frequency receiver).
    pub horizontal_sigma_m: f64,
    /// Vertical σ, m (default 5, our choice).
    pub vertical_sigma_m: f64,
    /// Fix quality reported (default 1 = GPS).
    pub quality: u32,
    /// Satellites reported (default 8, our choice).
    pub satellites: u32,
    /// Velocity σ per axis, m/s (default 0.05, a Doppler velocity of a
    /// single-frequency receiver; our choice).
    pub velocity_sigma_m_s: f64,
}

impl Default for GpsConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            rate_hz: 1.0,
            max_depth_m: 0.3,
            horizontal_sigma_m: 2.5,
            vertical_sigma_m: 5.0,
            quality: 1,
            satellites: 8,
            velocity_sigma_m_s: 0.05,
        }
    }
}

/// Propeller shaft speed (`sensor/propeller`): truth + white noise.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PropellerConfig {
    /// Whether the shaft encoder publishes (default true).
    pub enabled: bool,
    /// Rate, Hz (default 10, DESIGN §4).
    pub rate_hz: f64,
    /// White noise σ, rad/s (default 0.5, about 0.5 % at survey speed; our choice).
    pub noise_sigma_rad_s: f64,
}

impl Default for PropellerConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            rate_hz: 10.0,
            noise_sigma_rad_s: 0.5,
        }
    }
}

/// The buoy's acoustic broadcast (`sensor/modem`, paper 000): every
/// [`period_s`](Self::period_s) the buoy sends its GPS position; the vehicle
/// measures the one-way time of flight.
///
/// The buoy drifts: p(t) = p₀ + v_d t + w(t), w a 2-D random walk of
/// coefficient q (m/√s), sampled at each broadcast. The position it
/// broadcasts is p + GPS noise (σ per axis). [`ModemSpec`] gives losses, clock
/// jitter and the relative error of the sound speed the buoy reports; its
/// `sound_speed` is replaced by the suite's true sound speed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ModemConfig {
    /// Whether buoy messages arrive (default true).
    pub enabled: bool,
    /// Broadcast period, s (default 30, paper 000 / DESIGN §10).
    pub period_s: f64,
    /// Buoy start, north of the mission origin, m (default 300: middle of the
    /// default survey box; our choice).
    pub buoy_north_m: f64,
    /// Buoy start, east of the mission origin, m (default 125, idem).
    pub buoy_east_m: f64,
    /// Depth of the buoy's transducer, m (default 1, our choice).
    pub buoy_depth_m: f64,
    /// Constant drift, north, m/s (default 0.02, our choice).
    pub buoy_drift_north_m_s: f64,
    /// Constant drift, east, m/s (default 0.01, our choice).
    pub buoy_drift_east_m_s: f64,
    /// Random-walk coefficient q, m/√s (default 0.05, our choice).
    pub buoy_random_walk_m_rt_s: f64,
    /// Buoy GPS σ per horizontal axis, m (default 2.5, our choice).
    pub buoy_gps_sigma_m: f64,
    /// Timing errors (default [`ModemSpec::default`]).
    pub noise: ModemSpec,
}

impl Default for ModemConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            period_s: 30.0,
            buoy_north_m: 300.0,
            buoy_east_m: 125.0,
            buoy_depth_m: 1.0,
            buoy_drift_north_m_s: 0.02,
            buoy_drift_east_m_s: 0.01,
            buoy_random_walk_m_rt_s: 0.05,
            buoy_gps_sigma_m: 2.5,
            noise: ModemSpec::default(),
        }
    }
}

/// One LBL transponder, fixed, in the mission's local frame, with its own
/// turnaround delay (the site's, `[site] transponders`: the vehicle's
/// configuration and the simulator's truth are one list).
pub use nauta_estimation::lbl::Transponder;

/// Transponder layouts for the `lbl` scenario ([`crate::mission::lbl`]: a
/// 500 m (north) × 400 m (east) box from the origin).
///
/// Paper 003 (Isurus): two transponders, a 600 m baseline (the vehicle came
/// within 30 m of it, "about 1/20th of the baseline length"), and a best
/// operating box from L/4 to L away from the baseline, never crossing it.
/// Our layouts follow that rule; the depths are our choice (moored 20 m down).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LblLayout {
    /// Ids 1, 2 at (−50, −150) and (550, −150): a 600 m north-south
    /// baseline 150 m (L/4) west of the box, which lies 150-550 m from it.
    Two,
    /// The two above plus ids 3, 4 at (−50, 550) and (550, 550), east of the box.
    Four,
}

impl LblLayout {
    /// The layout's name (`"Two"`, `"Four"`), as manifests write it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Two => "Two",
            Self::Four => "Four",
        }
    }

    /// The transponders of this layout ([`nauta_estimation::lbl::layout::preset`]).
    pub fn transponders(self) -> Vec<Transponder> {
        nauta_estimation::lbl::layout::preset(self.name()).unwrap_or_default()
    }
}

/// LBL transponders answering interrogations (`sensor/lbl`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LblConfig {
    /// Whether the transponders answer (default false; on in [`SuiteConfig::lbl`]).
    pub enabled: bool,
    /// The transponders (default [`LblLayout::Two`]).
    pub transponders: Vec<Transponder>,
    /// Round-trip errors (default [`LblSpec::default`]: 100 µs clock, paper
    /// 003; 0.4 ms detection jitter); its `sound_speed` is replaced by the
    /// suite's true sound speed.
    pub noise: LblSpec,
    /// `[start, end]`, s of the run's clock: no reply is heard in this
    /// window (a blackout: the transponders' batteries, a thermocline, a
    /// ship's noise). Default none.
    pub blackout_s: Option<[f64; 2]>,
}

impl LblConfig {
    /// The transponder ids, in configuration order.
    pub fn ids(&self) -> Vec<u32> {
        self.transponders.iter().map(|t| t.id).collect()
    }
}

impl Default for LblConfig {
    fn default() -> Self {
        Self {
            enabled: false,
            transponders: LblLayout::Two.transponders(),
            noise: LblSpec::default(),
            blackout_s: None,
        }
    }
}

/// The whole sensor suite. `Default` is [`SuiteConfig::survey`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SuiteConfig {
    /// IMU.
    pub imu: ImuConfig,
    /// AHRS.
    pub ahrs: AhrsConfig,
    /// DVL.
    pub dvl: DvlConfig,
    /// Pressure depth.
    pub depth: DepthConfig,
    /// Surface GPS.
    pub gps: GpsConfig,
    /// Propeller shaft speed.
    pub propeller: PropellerConfig,
    /// Buoy modem.
    pub modem: ModemConfig,
    /// LBL transponders.
    pub lbl: LblConfig,
    /// True sound speed of the (isovelocity) water, m/s. `None` (default):
    /// the environment's Mackenzie (1981) sound speed at 10 m depth.
    pub sound_speed_m_s: Option<f64>,
}

impl Default for SuiteConfig {
    fn default() -> Self {
        Self::survey()
    }
}

impl SuiteConfig {
    /// [`crate::mission::survey`] (paper 000): IMU, AHRS, DVL, depth, GPS,
    /// propeller and the buoy modem; no LBL.
    pub fn survey() -> Self {
        Self {
            imu: ImuConfig::default(),
            ahrs: AhrsConfig::default(),
            dvl: DvlConfig::default(),
            depth: DepthConfig::default(),
            gps: GpsConfig::default(),
            propeller: PropellerConfig::default(),
            modem: ModemConfig::default(),
            lbl: LblConfig::default(),
            sound_speed_m_s: None,
        }
    }

    /// [`crate::mission::lbl`] (papers 003/004, Isurus): AHRS (compass, tilt),
    /// propeller, depth, GPS at the surface and the LBL transponders of
    /// `layout`; no DVL and no buoy (Isurus had neither). The IMU stays on.
    pub fn lbl(layout: LblLayout) -> Self {
        let mut c = Self::survey();
        c.dvl.enabled = false;
        c.modem.enabled = false;
        c.lbl.enabled = true;
        c.lbl.transponders = layout.transponders();
        c
    }

    /// [`crate::mission::dr`] (paper 002, Pirajuba): IMU, AHRS, DVL, depth,
    /// propeller, and GPS only at the surface (start and end); no acoustics.
    pub fn dr() -> Self {
        let mut c = Self::survey();
        c.modem.enabled = false;
        c.lbl.enabled = false;
        c
    }

    /// The same sensors with every error switched off: zero noise, biases,
    /// scale factors, offsets and probabilities, identity soft iron, zero
    /// hard iron. Clock quantisation (LBL) and turnaround stay.
    pub fn noise_free(mut self) -> Self {
        let zero_axis = InertialAxisSpec {
            noise_density: 0.0,
            bias_instability: 0.0,
            rate_random_walk: 0.0,
            turn_on_bias_sigma: 0.0,
            scale_factor_sigma: 0.0,
        };
        self.imu.gyro = zero_axis;
        self.imu.accel = zero_axis;
        self.imu.mag = MagnetometerSpec {
            noise_sigma: 0.0,
            hard_iron: [0.0; 3],
            soft_iron: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        };
        self.ahrs.roll_pitch_sigma_rad = 0.0;
        self.ahrs.heading_sigma_rad = 0.0;
        self.ahrs.heading_bias_sigma_rad = 0.0;
        self.dvl.altitude_sigma_m = 0.0;
        self.dvl.noise.noise_sigma = 0.0;
        self.dvl.noise.scale_factor_sigma = 0.0;
        self.dvl.noise.dropout_probability = 0.0;
        self.dvl.noise.spike_probability = 0.0;
        self.depth.noise = DepthSpec {
            noise_sigma: 0.0,
            offset: 0.0,
        };
        self.gps.horizontal_sigma_m = 0.0;
        self.gps.vertical_sigma_m = 0.0;
        self.gps.velocity_sigma_m_s = 0.0;
        self.propeller.noise_sigma_rad_s = 0.0;
        self.modem.buoy_gps_sigma_m = 0.0;
        self.modem.buoy_random_walk_m_rt_s = 0.0;
        self.modem.noise.loss_probability = 0.0;
        self.modem.noise.clock_jitter_sigma = 0.0;
        self.modem.noise.sound_speed_error = 0.0;
        self.lbl.noise.timing_jitter_sigma = 0.0;
        self.lbl.noise.multipath_probability = 0.0;
        // Detection certain at any range the scenarios reach.
        self.lbl.noise.detection_range_50 = 1e9;
        self
    }

    /// Check every parameter (the noise specs with their own `validate`).
    pub fn validate(&self) -> Result<(), SuiteError> {
        self.imu.gyro.validate()?;
        self.imu.accel.validate()?;
        self.imu.mag.validate()?;
        let a = &self.ahrs;
        positive("ahrs.rate_hz", a.rate_hz)?;
        non_negative("ahrs.roll_pitch_sigma_rad", a.roll_pitch_sigma_rad)?;
        non_negative("ahrs.heading_sigma_rad", a.heading_sigma_rad)?;
        non_negative("ahrs.heading_bias_sigma_rad", a.heading_bias_sigma_rad)?;
        positive("ahrs.heading_bias_time_s", a.heading_bias_time_s)?;
        let d = &self.dvl;
        positive("dvl.rate_hz", d.rate_hz)?;
        finite("dvl.seafloor_depth_m", d.seafloor_depth_m)?;
        non_negative("dvl.min_altitude_m", d.min_altitude_m)?;
        positive("dvl.max_altitude_m", d.max_altitude_m)?;
        non_negative("dvl.altitude_sigma_m", d.altitude_sigma_m)?;
        d.noise.validate()?;
        positive("depth.rate_hz", self.depth.rate_hz)?;
        self.depth.noise.validate()?;
        let g = &self.gps;
        positive("gps.rate_hz", g.rate_hz)?;
        finite("gps.max_depth_m", g.max_depth_m)?;
        non_negative("gps.horizontal_sigma_m", g.horizontal_sigma_m)?;
        non_negative("gps.vertical_sigma_m", g.vertical_sigma_m)?;
        non_negative("gps.velocity_sigma_m_s", g.velocity_sigma_m_s)?;
        positive("propeller.rate_hz", self.propeller.rate_hz)?;
        non_negative(
            "propeller.noise_sigma_rad_s",
            self.propeller.noise_sigma_rad_s,
        )?;
        let m = &self.modem;
        positive("modem.period_s", m.period_s)?;
        finite("modem.buoy_north_m", m.buoy_north_m)?;
        finite("modem.buoy_east_m", m.buoy_east_m)?;
        finite("modem.buoy_depth_m", m.buoy_depth_m)?;
        finite("modem.buoy_drift_north_m_s", m.buoy_drift_north_m_s)?;
        finite("modem.buoy_drift_east_m_s", m.buoy_drift_east_m_s)?;
        non_negative("modem.buoy_random_walk_m_rt_s", m.buoy_random_walk_m_rt_s)?;
        non_negative("modem.buoy_gps_sigma_m", m.buoy_gps_sigma_m)?;
        m.noise.validate()?;
        self.lbl.noise.validate()?;
        nauta_estimation::lbl::Layout::new(self.lbl.transponders.clone())?;
        if let Some([a, b]) = self.lbl.blackout_s {
            non_negative("lbl.blackout_s", a)?;
            if !(b >= a && b.is_finite()) {
                return Err(SuiteError::Invalid {
                    name: "lbl.blackout_s",
                    value: b,
                });
            }
        }
        if let Some(c) = self.sound_speed_m_s {
            positive("sound_speed_m_s", c)?;
        }
        Ok(())
    }
}
