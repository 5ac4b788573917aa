//! Error generators for the aiding sensors: DVL, acoustic modem, LBL,
//! pressure depth and magnetometer (DESIGN §10).
//!
//! Each generator is seeded through the random generator the caller passes,
//! runs alone, and returns what happened (valid, dropout, spike, lost,
//! multipath, ...) so tests and evaluation can count events. Defaults marked
//! "our choice" are not from a datasheet or a paper; the papers give none.

use nalgebra::{Matrix3, Vector3};
use rand::Rng;
use serde::{Deserialize, Serialize};

use super::{
    NoiseError, check_finite, check_interval, check_non_negative, check_positive,
    check_probability, std_normal,
};

/// Uniform draw in [lo, hi).
fn uniform<R: Rng + ?Sized>(rng: &mut R, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

/// Bernoulli draw with probability p (p = 0 never, p = 1 always).
fn chance<R: Rng + ?Sized>(rng: &mut R, p: f64) -> bool {
    rng.random::<f64>() < p
}

// ---------------------------------------------------------------------------
// DVL
// ---------------------------------------------------------------------------

/// DVL bottom-track error model (body-frame velocity, m/s), one call per ping
/// (5 Hz in the scenarios).
///
/// ```text
/// ṽ = (1 + s) v + w,   w ~ N(0, σ² I₃),   s ~ N(0, σ_s²) drawn once
/// ```
///
/// then, per sample:
/// - dropout: in the tracking state a sample starts a dropout with
///   probability p_d; the dropout lasts L samples (this one included),
///   L geometric on {1, 2, …} with mean L̄. The stationary fraction of
///   dropped samples is p_d L̄ / (p_d L̄ + 1 − p_d);
/// - spike: a sample that is not dropped is a spike with probability p_s;
///   a spike adds ±a (a uniform in [a_lo, a_hi] m/s, sign equiprobable) to
///   one axis: surge (x) with probability f_x, otherwise sway or heave with
///   equal probability. Paper 002 §1.3 (Fig. 5) shows such spikes on the
///   surge velocity; their magnitude and rate are our choice (DESIGN §10).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DvlSpec {
    /// White noise σ per axis, m/s (default 0.01, our choice for a low-cost
    /// bottom-track DVL single ping).
    pub noise_sigma: f64,
    /// Scale factor error 1σ, fraction (default 0.002 = 0.2 %, our choice,
    /// of the order of the ±0.1–0.3 % accuracy quoted for commercial DVLs).
    pub scale_factor_sigma: f64,
    /// Probability per tracking sample that a dropout starts (default 0.002).
    pub dropout_probability: f64,
    /// Mean dropout length in samples, ≥ 1 (default 5, i.e. 1 s at 5 Hz).
    pub mean_dropout_length: f64,
    /// Probability per non-dropped sample of a spike (default 0.005 = 0.5 %).
    pub spike_probability: f64,
    /// Spike magnitude interval [lo, hi], m/s (default [0.5, 3]).
    pub spike_magnitude: [f64; 2],
    /// Probability that a spike hits surge (x) rather than sway/heave (default 0.8).
    pub spike_surge_fraction: f64,
}

impl Default for DvlSpec {
    fn default() -> Self {
        Self {
            noise_sigma: 0.01,
            scale_factor_sigma: 0.002,
            dropout_probability: 0.002,
            mean_dropout_length: 5.0,
            spike_probability: 0.005,
            spike_magnitude: [0.5, 3.0],
            spike_surge_fraction: 0.8,
        }
    }
}

impl DvlSpec {
    /// Check ranges: σ ≥ 0, probabilities in [0, 1], mean length ≥ 1, interval ordered.
    pub fn validate(&self) -> Result<(), NoiseError> {
        check_non_negative("dvl.noise_sigma", self.noise_sigma)?;
        check_non_negative("dvl.scale_factor_sigma", self.scale_factor_sigma)?;
        check_probability("dvl.dropout_probability", self.dropout_probability)?;
        check_finite("dvl.mean_dropout_length", self.mean_dropout_length)?;
        if !(self.mean_dropout_length >= 1.0) {
            return Err(NoiseError::EmptyInterval {
                name: "dvl.mean_dropout_length (must be >= 1)",
                lo: 1.0,
                hi: self.mean_dropout_length,
            });
        }
        check_probability("dvl.spike_probability", self.spike_probability)?;
        check_interval(
            "dvl.spike_magnitude",
            self.spike_magnitude[0],
            self.spike_magnitude[1],
        )?;
        check_probability("dvl.spike_surge_fraction", self.spike_surge_fraction)?;
        Ok(())
    }

    /// Expected long-run fraction of samples lost to dropouts:
    /// p_d L̄ / (p_d L̄ + 1 − p_d).
    pub fn dropout_fraction(&self) -> f64 {
        let pl = self.dropout_probability * self.mean_dropout_length;
        pl / (pl + 1.0 - self.dropout_probability)
    }
}

/// What one DVL ping produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DvlOutcome {
    /// A normal measurement (scale error and white noise), m/s.
    Valid(Vector3<f64>),
    /// No bottom lock: no measurement.
    Dropout,
    /// A measurement with a spike on `axis` (0 surge, 1 sway, 2 heave), m/s.
    Spike {
        /// The measured (spiked) velocity, m/s.
        velocity: Vector3<f64>,
        /// The axis the spike hit.
        axis: usize,
    },
}

impl DvlOutcome {
    /// The velocity reported, if any (spikes included: the receiver cannot tell).
    pub fn velocity(&self) -> Option<Vector3<f64>> {
        match self {
            Self::Valid(v) | Self::Spike { velocity: v, .. } => Some(*v),
            Self::Dropout => None,
        }
    }
}

/// DVL error state; see [`DvlSpec`].
#[derive(Debug, Clone)]
pub struct DvlNoise {
    spec: DvlSpec,
    scale_factor: f64,
    dropout_left: u64,
}

impl DvlNoise {
    /// Validate and draw the scale factor error.
    pub fn new<R: Rng + ?Sized>(spec: DvlSpec, rng: &mut R) -> Result<Self, NoiseError> {
        spec.validate()?;
        let scale_factor = spec.scale_factor_sigma * std_normal(rng);
        Ok(Self {
            spec,
            scale_factor,
            dropout_left: 0,
        })
    }

    /// Scale factor error drawn for this instance (fraction).
    pub fn scale_factor_error(&self) -> f64 {
        self.scale_factor
    }

    /// One ping of true body velocity `v` (m/s). Dropouts and noise come
    /// from `rng`, spikes from `spike_rng` alone, so that a run without
    /// spikes (`spike_probability = 0`) draws the same noise and dropouts as
    /// one with them: the two differ by their spikes only (paper 002 Fig. 5's
    /// comparison, `nauta bench nav`'s spike case).
    pub fn next<R: Rng + ?Sized, S: Rng + ?Sized>(
        &mut self,
        rng: &mut R,
        spike_rng: &mut S,
        v: Vector3<f64>,
    ) -> DvlOutcome {
        if self.dropout_left > 0 {
            self.dropout_left -= 1;
            return DvlOutcome::Dropout;
        }
        if chance(rng, self.spec.dropout_probability) {
            // Length L = 1 + K, K geometric (failures before a success of
            // probability 1/L̄), by inversion.
            let p = 1.0 / self.spec.mean_dropout_length;
            let extra = if p >= 1.0 {
                0
            } else {
                let u: f64 = rng.random();
                ((1.0 - u).ln() / (1.0 - p).ln()).floor() as u64
            };
            self.dropout_left = extra;
            return DvlOutcome::Dropout;
        }
        let sigma = self.spec.noise_sigma;
        let mut m = v * (1.0 + self.scale_factor)
            + Vector3::new(
                sigma * std_normal(rng),
                sigma * std_normal(rng),
                sigma * std_normal(rng),
            );
        if chance(spike_rng, self.spec.spike_probability) {
            let axis = if chance(spike_rng, self.spec.spike_surge_fraction) {
                0
            } else if chance(spike_rng, 0.5) {
                1
            } else {
                2
            };
            let [lo, hi] = self.spec.spike_magnitude;
            let a = uniform(spike_rng, lo, hi);
            m[axis] += if chance(spike_rng, 0.5) { a } else { -a };
            DvlOutcome::Spike { velocity: m, axis }
        } else {
            DvlOutcome::Valid(m)
        }
    }
}

// ---------------------------------------------------------------------------
// Acoustic modem (buoy broadcast, paper 000)
// ---------------------------------------------------------------------------

/// One-way acoustic time of flight from the buoy's modem message (paper 000:
/// one positioning message every 30 s; the schedule is the scenario's).
///
/// A message is lost with probability p_loss. Otherwise the measured time of
/// flight and the range the receiver computes from it are
///
/// ```text
/// t̃ = max(0, r / c + ε_t),   ε_t ~ N(0, σ_t²)   (clock-synchronisation jitter, s)
/// r̃ = ĉ t̃,                   ĉ = c (1 + e_c)    (assumed sound speed, m/s)
/// ```
///
/// so a sound-speed error e_c scales every range by (1 + e_c). A multipath
/// message (probability p_mp, its own random stream) adds δ ~ U[δ_lo, δ_hi]
/// to t̃.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModemSpec {
    /// Probability a message is lost (default 0.1, our choice).
    pub loss_probability: f64,
    /// Clock-synchronisation jitter σ_t, s (default 1 ms, our choice).
    pub clock_jitter_sigma: f64,
    /// True sound speed c, m/s (default 1500).
    pub sound_speed: f64,
    /// Relative error e_c of the sound speed the receiver assumes (default
    /// 0.003, i.e. 4.5 m/s, our choice); must be > −1.
    pub sound_speed_error: f64,
    /// Probability a received message came by a longer path (a reflection
    /// off the surface or the bottom, as the LBL model's late replies)
    /// (default 0: the paper's case; issue 14's robustness case 0.02).
    #[serde(default)]
    pub multipath_probability: f64,
    /// Its extra travel time, uniform in [δ_lo, δ_hi], s (default
    /// [0.0133, 0.133]: +20 to +200 m at 1500 m/s, our choice).
    #[serde(default = "default_modem_multipath_delay")]
    pub multipath_delay: [f64; 2],
}

fn default_modem_multipath_delay() -> [f64; 2] {
    [0.0133, 0.133]
}

impl Default for ModemSpec {
    fn default() -> Self {
        Self {
            loss_probability: 0.1,
            clock_jitter_sigma: 1e-3,
            sound_speed: 1500.0,
            sound_speed_error: 0.003,
            multipath_probability: 0.0,
            multipath_delay: default_modem_multipath_delay(),
        }
    }
}

impl ModemSpec {
    /// Check ranges.
    pub fn validate(&self) -> Result<(), NoiseError> {
        check_probability("modem.loss_probability", self.loss_probability)?;
        check_non_negative("modem.clock_jitter_sigma", self.clock_jitter_sigma)?;
        check_positive("modem.sound_speed", self.sound_speed)?;
        check_finite("modem.sound_speed_error", self.sound_speed_error)?;
        check_positive("modem 1 + sound_speed_error", 1.0 + self.sound_speed_error)?;
        check_probability("modem.multipath_probability", self.multipath_probability)?;
        check_interval(
            "modem.multipath_delay",
            self.multipath_delay[0],
            self.multipath_delay[1],
        )?;
        Ok(())
    }
}

/// A received modem message's timing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModemReception {
    /// Measured one-way time of flight t̃, s.
    pub time_of_flight: f64,
    /// Range computed with the assumed sound speed, r̃ = ĉ t̃, m.
    pub range: f64,
}

/// What one modem message produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ModemOutcome {
    /// The message did not arrive.
    Lost,
    /// The message arrived by the direct path.
    Received(ModemReception),
    /// The message arrived by a longer path (its time of flight too long).
    Multipath(ModemReception),
}

impl ModemOutcome {
    /// The reception, if any (the receiver cannot tell the paths apart).
    pub fn reception(&self) -> Option<ModemReception> {
        match self {
            Self::Received(r) | Self::Multipath(r) => Some(*r),
            Self::Lost => None,
        }
    }
}

/// Acoustic modem error generator; see [`ModemSpec`].
#[derive(Debug, Clone)]
pub struct ModemNoise {
    spec: ModemSpec,
}

impl ModemNoise {
    /// Validate the spec.
    pub fn new(spec: ModemSpec) -> Result<Self, NoiseError> {
        spec.validate()?;
        Ok(Self { spec })
    }

    /// The spec.
    pub fn spec(&self) -> &ModemSpec {
        &self.spec
    }

    /// One message over a true range `range` (m): loss and jitter from
    /// `rng`, the multipath from `multipath_rng` (its own stream: a run
    /// with multipath differs from one without only by its outliers; both
    /// draws are made for every message, so the outliers do not depend on
    /// the losses either).
    pub fn next<R: Rng + ?Sized, M: Rng + ?Sized>(
        &mut self,
        rng: &mut R,
        multipath_rng: &mut M,
        range: f64,
    ) -> ModemOutcome {
        let s = &self.spec;
        let multipath = chance(multipath_rng, s.multipath_probability);
        let delay = uniform(multipath_rng, s.multipath_delay[0], s.multipath_delay[1]);
        if chance(rng, s.loss_probability) {
            return ModemOutcome::Lost;
        }
        let extra = if multipath { delay } else { 0.0 };
        let tof = (range / s.sound_speed + extra + s.clock_jitter_sigma * std_normal(rng)).max(0.0);
        let r = ModemReception {
            time_of_flight: tof,
            range: s.sound_speed * (1.0 + s.sound_speed_error) * tof,
        };
        if multipath {
            ModemOutcome::Multipath(r)
        } else {
            ModemOutcome::Received(r)
        }
    }
}

// ---------------------------------------------------------------------------
// LBL (paper 003)
// ---------------------------------------------------------------------------

/// LBL interrogation round trip (paper 003: the on-board micro-controller
/// time-stamps interrogations and replies with a 100 µs clock; late
/// multipath replies are rejected by the navigation's range validation).
///
/// For a slant range r (m):
/// - the reply is detected with probability
///   p(r) = 1 / (1 + exp((r − r₅₀) / w)) (logistic: p(0) ≈ 1 when r₅₀ ≫ w,
///   p(r₅₀) = ½); otherwise no reply;
/// - a detected reply is a multipath (late, longer path) reply with
///   probability p_mp, with extra delay δ uniform in [δ_lo, δ_hi];
/// - the round trip is t = 2r/c + t_ta + ε + δ (t_ta the transponder's
///   turnaround, given per transponder; ε ~ N(0, σ²) detection jitter,
///   δ = 0 for the direct path),
///   and is measured on the clock as n = ⌊t / Δ⌋ ticks of Δ = 100 µs
///   (events time-stamped on the tick before them), t̃ = n Δ.
///
/// The range the vehicle computes is r̃ = c (t̃ − t_ta) / 2
/// ([`LblSpec::range_from_round_trip`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LblSpec {
    /// Clock resolution Δ, s (default 100 µs, paper 003).
    pub clock_resolution: f64,
    /// Sound speed c, m/s (default 1500).
    pub sound_speed: f64,
    /// Detection jitter σ, s (default 0.4 ms, 0.30 m of range: our choice
    /// for threshold detection on an analog envelope (paper 003 §IV): a
    /// tone's envelope rises over a few cycles of its 20-30 kHz carrier,
    /// and noise moves the crossing by a fraction of that rise; real LBL
    /// ranges are good to decimetres, not the clock's 2 cm).
    pub timing_jitter_sigma: f64,
    /// Range r₅₀ at which half the replies are detected, m (default 2000, our choice).
    pub detection_range_50: f64,
    /// Width w of the logistic detection fall-off, m (default 100, our choice).
    pub detection_range_width: f64,
    /// Probability a detected reply is a multipath one (default 0.05, our choice).
    pub multipath_probability: f64,
    /// Multipath extra delay interval [δ_lo, δ_hi], s (default [1 ms, 20 ms], our choice).
    pub multipath_delay: [f64; 2],
}

impl Default for LblSpec {
    fn default() -> Self {
        Self {
            clock_resolution: 100e-6,
            sound_speed: 1500.0,
            timing_jitter_sigma: 0.4e-3,
            detection_range_50: 2000.0,
            detection_range_width: 100.0,
            multipath_probability: 0.05,
            multipath_delay: [1e-3, 20e-3],
        }
    }
}

impl LblSpec {
    /// Check ranges.
    pub fn validate(&self) -> Result<(), NoiseError> {
        check_positive("lbl.clock_resolution", self.clock_resolution)?;
        check_positive("lbl.sound_speed", self.sound_speed)?;
        check_non_negative("lbl.timing_jitter_sigma", self.timing_jitter_sigma)?;
        check_non_negative("lbl.detection_range_50", self.detection_range_50)?;
        check_positive("lbl.detection_range_width", self.detection_range_width)?;
        check_probability("lbl.multipath_probability", self.multipath_probability)?;
        check_interval(
            "lbl.multipath_delay",
            self.multipath_delay[0],
            self.multipath_delay[1],
        )?;
        Ok(())
    }

    /// Detection probability p(r) at slant range r (m).
    pub fn detection_probability(&self, range: f64) -> f64 {
        1.0 / (1.0 + ((range - self.detection_range_50) / self.detection_range_width).exp())
    }

    /// Range the vehicle computes from a round trip to a transponder of
    /// turnaround `turnaround`: c (t − t_ta) / 2, m.
    pub fn range_from_round_trip(&self, round_trip: f64, turnaround: f64) -> f64 {
        self.sound_speed * (round_trip - turnaround) / 2.0
    }
}

/// A measured LBL round trip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LblReply {
    /// Round trip in clock ticks.
    pub ticks: u64,
    /// Round trip, s: `ticks` × clock resolution.
    pub round_trip: f64,
}

/// What one LBL interrogation of one transponder produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LblOutcome {
    /// No reply detected.
    NoReply,
    /// The direct-path reply.
    Direct(LblReply),
    /// A late multipath reply.
    Multipath(LblReply),
}

impl LblOutcome {
    /// The reply, if any (the receiver cannot tell direct from multipath).
    pub fn reply(&self) -> Option<LblReply> {
        match self {
            Self::Direct(r) | Self::Multipath(r) => Some(*r),
            Self::NoReply => None,
        }
    }
}

/// LBL round-trip generator; see [`LblSpec`].
#[derive(Debug, Clone)]
pub struct LblNoise {
    spec: LblSpec,
}

impl LblNoise {
    /// Validate the spec.
    pub fn new(spec: LblSpec) -> Result<Self, NoiseError> {
        spec.validate()?;
        Ok(Self { spec })
    }

    /// The spec.
    pub fn spec(&self) -> &LblSpec {
        &self.spec
    }

    /// The detection jitter ε of one reply, s (N(0, σ²); no draw when σ is
    /// 0). The suite draws it when the reply leaves the transponder, so
    /// that the reply is heard, and delivered, at its jittered time (a
    /// reply is never stamped before a step already published), and passes
    /// it to [`LblNoise::next`] inside `turnaround`.
    pub fn jitter<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        if self.spec.timing_jitter_sigma > 0.0 {
            self.spec.timing_jitter_sigma * std_normal(rng)
        } else {
            0.0
        }
    }

    /// One interrogation of a transponder of turnaround `turnaround` (s,
    /// with the reply's detection jitter added, [`LblNoise::jitter`]) at true
    /// slant range `range` (m).
    pub fn next<R: Rng + ?Sized>(
        &mut self,
        rng: &mut R,
        range: f64,
        turnaround: f64,
    ) -> LblOutcome {
        let s = &self.spec;
        if !chance(rng, s.detection_probability(range)) {
            return LblOutcome::NoReply;
        }
        let multipath = chance(rng, s.multipath_probability);
        let mut t = 2.0 * range / s.sound_speed + turnaround;
        if multipath {
            t += uniform(rng, s.multipath_delay[0], s.multipath_delay[1]);
        }
        let ticks = (t.max(0.0) / s.clock_resolution).floor() as u64;
        let reply = LblReply {
            ticks,
            round_trip: ticks as f64 * s.clock_resolution,
        };
        if multipath {
            LblOutcome::Multipath(reply)
        } else {
            LblOutcome::Direct(reply)
        }
    }
}

// ---------------------------------------------------------------------------
// Depth
// ---------------------------------------------------------------------------

/// Pressure depth sensor (10 Hz in the scenarios): d̃ = d + d₀ + w,
/// w ~ N(0, σ²), d in m (positive down).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthSpec {
    /// White noise σ, m (default 0.02, our choice).
    pub noise_sigma: f64,
    /// Fixed offset d₀, m (default 0.05, our choice: e.g. a 0.5 % water
    /// density error at 10 m, or a 5 hPa atmospheric pressure error).
    pub offset: f64,
}

impl Default for DepthSpec {
    fn default() -> Self {
        Self {
            noise_sigma: 0.02,
            offset: 0.05,
        }
    }
}

impl DepthSpec {
    /// Check ranges.
    pub fn validate(&self) -> Result<(), NoiseError> {
        check_non_negative("depth.noise_sigma", self.noise_sigma)?;
        check_finite("depth.offset", self.offset)?;
        Ok(())
    }
}

/// Depth sensor error generator; see [`DepthSpec`].
#[derive(Debug, Clone)]
pub struct DepthNoise {
    spec: DepthSpec,
}

impl DepthNoise {
    /// Validate the spec.
    pub fn new(spec: DepthSpec) -> Result<Self, NoiseError> {
        spec.validate()?;
        Ok(Self { spec })
    }

    /// One sample of true depth `depth` (m).
    pub fn next<R: Rng + ?Sized>(&mut self, rng: &mut R, depth: f64) -> f64 {
        depth + self.spec.offset + self.spec.noise_sigma * std_normal(rng)
    }
}

// ---------------------------------------------------------------------------
// Magnetometer
// ---------------------------------------------------------------------------

/// Magnetometer with hard- and soft-iron distortion (body frame, tesla):
///
/// ```text
/// m̃ = S m + h + w,   w ~ N(0, σ² I₃)
/// ```
///
/// S (3×3, soft iron, invertible) and h (hard iron, T) are fixed; the
/// calibration (paper 000) estimates them. Local declination belongs to
/// the Earth-field model that produces m, not to this sensor model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MagnetometerSpec {
    /// White noise σ per axis, T (default 0.05 µT = 0.5 mG RMS, Xsens MTi
    /// 10-series datasheet as remembered; check against the PDF).
    pub noise_sigma: f64,
    /// Hard-iron offset h, T (default [2, −1.5, 0.8] µT, our choice).
    pub hard_iron: [f64; 3],
    /// Soft-iron matrix S, rows (default a few % from identity, our choice).
    pub soft_iron: [[f64; 3]; 3],
}

impl Default for MagnetometerSpec {
    fn default() -> Self {
        Self {
            noise_sigma: 0.05e-6,
            hard_iron: [2.0e-6, -1.5e-6, 0.8e-6],
            soft_iron: [[1.02, 0.01, 0.0], [0.01, 0.97, 0.005], [0.0, 0.005, 1.01]],
        }
    }
}

impl MagnetometerSpec {
    /// Hard-iron vector h.
    pub fn hard_iron_vector(&self) -> Vector3<f64> {
        Vector3::from(self.hard_iron)
    }

    /// Soft-iron matrix S.
    pub fn soft_iron_matrix(&self) -> Matrix3<f64> {
        let r = &self.soft_iron;
        Matrix3::new(
            r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
        )
    }

    /// Check ranges; S must be invertible (|det S| > 1e-6).
    pub fn validate(&self) -> Result<(), NoiseError> {
        check_non_negative("mag.noise_sigma", self.noise_sigma)?;
        for &h in &self.hard_iron {
            check_finite("mag.hard_iron", h)?;
        }
        for row in &self.soft_iron {
            for &x in row {
                check_finite("mag.soft_iron", x)?;
            }
        }
        let det = self.soft_iron_matrix().determinant();
        if !(det.abs() > 1e-6) {
            return Err(NoiseError::Singular {
                name: "mag.soft_iron",
                det,
            });
        }
        Ok(())
    }
}

/// Magnetometer error generator; see [`MagnetometerSpec`].
#[derive(Debug, Clone)]
pub struct MagnetometerNoise {
    spec: MagnetometerSpec,
    soft_iron: Matrix3<f64>,
    hard_iron: Vector3<f64>,
}

impl MagnetometerNoise {
    /// Validate the spec.
    pub fn new(spec: MagnetometerSpec) -> Result<Self, NoiseError> {
        spec.validate()?;
        Ok(Self {
            spec,
            soft_iron: spec.soft_iron_matrix(),
            hard_iron: spec.hard_iron_vector(),
        })
    }

    /// The spec.
    pub fn spec(&self) -> &MagnetometerSpec {
        &self.spec
    }

    /// One sample of the true body-frame field `m` (T).
    pub fn next<R: Rng + ?Sized>(&mut self, rng: &mut R, m: Vector3<f64>) -> Vector3<f64> {
        let s = self.spec.noise_sigma;
        self.soft_iron * m
            + self.hard_iron
            + Vector3::new(
                s * std_normal(rng),
                s * std_normal(rng),
                s * std_normal(rng),
            )
    }
}

#[cfg(test)]
mod tests;
