//! Paper 000's attitude particle filter (§III-B-1, eqs. 28-47): particles of
//! attitude quaternions propagated with the gyro, weighted by their
//! difference from the attitude the accelerometer and magnetometer give,
//! resampled when the effective sample size falls, estimated as the weighted
//! mean; with what the paper leaves out and a user needs: gyro bias
//! estimation, disturbance rejection and initialisation from the first
//! samples.
//!
//! # State
//!
//! Particle `i` (eq. 43) is an attitude `q_i` (body FRD → NED) and, beyond
//! the paper, a gyro bias `b_i` (FRD, rad/s), with a weight `w_i`. The
//! estimate is the weighted mean (eq. 47, "the weighted mean of all particle
//! components"): `q̂ = Σ w_i q_i / ‖Σ w_i q_i‖` with each `q_i` taken with the
//! sign that agrees with the previous estimate (q and −q are one attitude),
//! and `b̂ = Σ w_i b_i`.
//!
//! # Prediction (P1): eq. 28 with process noise
//!
//! ```text
//! θ_i = (ω̃ − b_i) Δt + η_i,   η_i ~ N(0, σ_g² Δt I)
//! q_i ← exp(−ω_ie^n Δt) ⊗ q_i ⊗ exp(θ_i)                                  (P1)
//! b_i ← b_i + ζ_i,   ζ_i ~ N(0, σ_b² Δt_b I), every 16 samples (Δt_b their span)
//! ```
//!
//! η_i too is drawn on a grid, every 4 samples with the variance of their
//! span, `N(0, σ_g² Δt_η I)`, and added on that sample: the same diffusion
//! sampled coarser (0.012° steps at 285 Hz with the default σ_g, against a
//! cloud spread of tenths of a degree), for a quarter of the random numbers.
//! On BROAD's eight trials the mean total RMSE moved by less than its
//! seed-to-seed scatter (BENCHMARKS.md, "Attitude").
//!
//! Eq. 28 is `q_i ← (q_i + ½ T_s q_i ⊗ [0, ω]) / ‖·‖`, i.e. `q_i ⊗ exp(θ)` to
//! first order in `|θ|`. Here `exp(θ)` is carried to fourth order,
//! `[1 − |θ|²/8 + |θ|⁴/384, (½ − |θ|²/48) θ]`, which is unit to `|θ|⁶/4608`
//! (5e-12 at 16 rad/s and 285 Hz) without a sine or cosine per particle,
//! and the Earth rate is compensated as in [`crate::gyro`] (one quaternion
//! for all particles), applied every 16 samples with their span: a
//! left (navigation-frame) factor commutes with the right (body-frame)
//! factors, so the product on that grid is the same, and between its points
//! the cloud lags by at most 15 samples of Earth rate (4e-6 rad at 285 Hz);
//! the estimate is moved with it, and each particle is renormalised there
//! by one Newton step (the factors are unit to 5e-12). σ_g is the process noise density: the gyro's angle
//! random walk plus what the gyro model leaves out (`gyro_noise_deg_s_rt_hz`);
//! the bias walks with density σ_b, drawn on a 16-sample grid (the same
//! process sampled coarser, which saves five sixths of the random numbers).
//!
//! # Aiding attitude and attitude difference (P2), eqs. 30-42
//!
//! The paper forms one aiding quaternion `q_am` from the accelerometer (roll,
//! pitch) and the magnetometer compensated for them (yaw) ([`aiding`], eqs.
//! 30-41), and weighs each particle by the component-wise difference
//! `δ_i = q_am − q_i` (eq. 42). Two changes make the weights separable and
//! robust, and keep the paper's weights as a special case:
//!
//! 1. The difference is taken multiplicatively in the navigation frame,
//!    `δq_i = q_a ⊗ q_i⁻¹ = [w, x, y, z]`. Right multiplication by a unit
//!    quaternion preserves the 4-D norm, so `|q_am − q_i|² = (1 − w)² + x² +
//!    y² + z²`: with one σ for every component, the product of eq. 45 over
//!    the components is the paper's weight exactly (and the w term, of
//!    second order, is dropped below). In this frame the components mean
//!    something: `x, y ≈ ½` the north and east (tilt) error, `z ≈ ½` the down
//!    (heading) error, whatever the attitude.
//! 2. Tilt and heading get their own aiding quaternion, so that a disturbed
//!    sensor can be down-weighted alone, and the heading does not inherit the
//!    accelerometer's tilt error times the tangent of the dip (2.5 at 68° dip)
//!    through eq. 40:
//!
//! ```text
//! q_acc = exp(θ_a) ⊗ q̂⁻,   θ_a: the horizontal rotation taking f_lp onto −e_D
//! q_mag = exp(ψ_e e_D) ⊗ q̂⁻,   ψ_e = wrap(δ − azimuth(q̂⁻ m̃))                (P2)
//! ```
//!
//! `q̂⁻` is the predicted estimate. `q_acc` is the attitude that agrees with
//! the accelerometer and has the estimate's heading, `q_mag` the one that
//! agrees with the magnetometer's heading (eq. 40's tilt compensation done
//! with the estimate's roll and pitch) and has the estimate's tilt. Built on
//! `q_acc` instead of `q̂⁻`, the heading aiding recomposes the paper's
//! `q_am` exactly (test `aiding_split_recomposes_q_am`).
//!
//! **Low-passed specific force (P2').** `f_lp` is not one sample but the
//! specific force low-passed in the navigation frame (time constant
//! `accel_lowpass_s`, 3 s): each sample is rotated into NED with the
//! estimate half a gyro interval back (it is an interval average, DESIGN
//! §4), `f_lp ← f_lp + Δt/(τ + Δt) (q̂⁻_mid f̃ − f_lp)`, and after each update
//! `f_lp` is turned by the update's correction `q̂⁺ ⊗ q̂⁻⁻¹`, so that it is
//! the low-pass in the gyro-integrated ("almost inertial") frame that VQF
//! uses (Laidig & Seel, "VQF: Highly accurate IMU orientation estimation
//! with bias estimation and magnetic disturbance rejection", Information
//! Fusion 91, 2023). Accelerations that come and go, and the centripetal
//! acceleration of a turn, average out there; on BROAD it halves the
//! inclination error (measurements in `shared/bench/src/attitude.rs`). At
//! rest (P5) the low-pass restarts from each sample.
//!
//! A magnetometer sample equal to the previous one is not used: a sensor that
//! holds its last value between its own, slower, samples (BROAD's does, for
//! 29 % of the samples) would otherwise weigh a stale heading.
//!
//! # Weights (P3): eq. 45 per component
//!
//! ```text
//! w_i ← w_i · N(x_a,i; 0, s_t²) · N(y_a,i; 0, s_t²) · N(z_m,i; 0, s_h²)    (P3)
//! ```
//!
//! with `[·, x_a, y_a, ·] = q_acc ⊗ q_i⁻¹`, `[·, ·, ·, z_m] = q_mag ⊗ q_i⁻¹`
//! and `s = sin(σ/2)` for the per-sample angle noise σ (a component is half
//! the sine of the angle). The paper keeps a weight per particle and
//! component and resamples components separately, which recombines
//! components of different particles into non-unit quaternions; here a
//! particle's weight is the product of its component likelihoods (the joint
//! likelihood of independent component errors) and resampling moves whole
//! particles. Per sample,
//!
//! ```text
//! σ_t² = σ_f²/(g² Δt) + σ_T²/Δt + ((|f_lp| − g)/g)²
//! σ_h² = σ_H²/Δt + (σ_m/H)² + (|m̃|/|m_ref| − 1)² + (dip − dip_ref)²        (P4)
//! ```
//!
//! σ_f the accelerometer's noise density, σ_m the magnetometer's noise per
//! sample and H the reference's horizontal field, σ_T and σ_H the tilt and
//! heading aiding densities (unmodelled accelerations, magnetic distortion),
//! and the last terms our adaptive down-weighting: the farther the
//! low-passed specific force's norm from gravity, or the field's norm and
//! dip (seen at the estimate) from the reference, the less the sample
//! counts. Beyond the gates (`accel_gate_m_s2` on `|f_lp| − g`,
//! `mag_norm_gate`, `mag_dip_gate_deg`) the factor is left out: the
//! accelerometer during sustained linear acceleration, the magnetometer
//! during magnetic disturbance.
//!
//! # Gyro bias at rest (P5)
//!
//! When the sensor has been still for `rest_min_s` (the gyro and the
//! specific force within their thresholds of their 0.5 s low-pass means, and
//! the mean rate within the threshold of the bias estimate; the test of VQF,
//! Laidig & Seel 2023), the gyro measures the bias plus the Earth rate,
//! `z = ω̃ − Ĉᵀ ω_ie^n`, with the gyro's own scatter about its low-pass mean
//! σ_r² (per sample, floored at (0.001 °/s)²). The measurement is linear
//! and Gaussian in the bias alone, so the biases get its Kalman update as a
//! shift and a contraction of the cloud, per axis:
//!
//! ```text
//! K = P_b / (P_b + σ_r²),   b_i ← b̂ + K (z − b̂) + √(1 − K) (b_i − b̂)      (P5)
//! ```
//!
//! (`P_b` the weighted variance of the biases): exact for a Gaussian cloud,
//! and, unlike a reweighting, it cannot run out of particles near `z` after
//! the cloud has narrowed. At rest the specific force is not low-passed
//! either (nothing to average; the low-pass would only add lag). In motion
//! the bias is estimated only through the attitude it produces (P3).
//!
//! # Resampling (P6): eq. 46 and selection and replacement
//!
//! With the weights normalised, `N_eff = 1 / Σ w_i²` (eq. 46). Below
//! `N_th = resample_threshold · N`, particle `i` is selected `⌊N w_i⌋` times
//! and the remaining places are replaced by systematic draws on the residual
//! weights (residual resampling; the paper's "selection and replace",
//! whose reference [25] is not available here). Copies are then spread by a
//! Gaussian kernel with shrinkage (Liu & West 2001), which keeps the
//! weighted mean and covariance of the cloud, in the 6-D space of the
//! navigation-frame attitude error `δθ_i = log(q_i ⊗ q̂⁻¹)` and the bias:
//! `x_i ← x̄ + a (x_i − x̄) + h L ε_i`, `L Lᵀ` the cloud's covariance,
//! `h = (4 / (N (d + 2)))^{1/(d+4)}` (the Gaussian kernel's optimal
//! bandwidth, d = 6), `a = √(1 − h²)`. Weights are then `1/N`. The attitude
//! error is taken in the chart `δθ_i = 2 s_i vec(q_i ⊗ q̂⁻¹)` (`s_i` the sign
//! that makes the scalar part positive), equal to the logarithm to third
//! order in the angle and inverted exactly by `q_i = [√(1 − |δθ/2|²), δθ/2]
//! ⊗ q̂`: a square root per particle instead of an arc tangent, a sine and a
//! cosine.
//!
//! # Progressive correction (P7)
//!
//! When one update would leave fewer than `N_th` effective particles (a
//! likelihood much narrower than the cloud: at the start, or after a gap in
//! the aiding), it is undone and applied in stages: the largest fraction
//! `α` of the log-likelihood that keeps `N_eff ≥ N_th` (bisection), then
//! (P6), then the rest on the new particles, at most 20 stages (progressive
//! correction, Oudjane & Musso 2000; likelihood tempering). Without it, the
//! first updates from the initial spread could leave one or two particles,
//! whose biases were then the whole cloud's for good (observed before this
//! stage existed, with tilt and heading densities of 0.03 and 0.05 °·√s on
//! BROAD trial 10: a z bias 1.5 °/s off and a 130° heading RMSE).
//!
//! # Initialisation
//!
//! [`ParticleFilter::from_first_sample`] takes the paper's `q_am` of the
//! first specific force and field as the initial attitude, and the field's
//! norm and dip at it as the magnetic reference; the particles are drawn
//! around it with the initial standard deviations, the bias around zero
//! (draws centred, so that the cloud's mean is the initial state).
//!
//! # Determinism
//!
//! Every random number comes from one generator seeded by `seed` (64
//! xoshiro128++ streams, normal draws by (N1) of [`noise`]), every loop runs
//! in particle order, and sums are taken in a fixed order of partial sums:
//! the same seed and inputs give the same output bit for bit. A restore
//! re-seeds the generator from the seed and the snapshot's bits, so
//! restoring a snapshot twice gives the same particles.
//!
//! # Speed
//!
//! The particles are stored as a structure of arrays ([`cloud`]) and every
//! per-sample loop runs over plain slices without a branch or a library
//! call (the weights' exponential in [`math`]), so that the compiler
//! vectorises it; no per-sample allocation. One likelihood pass computes
//! each particle's error `E_i = q̂⁻ ⊗ q_i⁻¹` once and takes from it the tilt
//! and heading differences (P3), the sign alignment and the spread.
//! Each of these loops is compiled for the target, for AVX2 and for
//! AVX-512F, and the form is chosen at run time by the CPU's features
//! ([`isa`]); all give the same bits.

mod aiding;
mod cloud;
mod isa;
mod math;
mod noise;
mod params;
mod resample;
mod role;
#[cfg(test)]
mod tests;
mod update;

pub use aiding::{AidingError, aiding_quaternion, tilt_quaternions};
pub use params::{MAX_PARTICLES, PfConfig, PfParams, PfParamsError};

use nalgebra::{Matrix6, UnitQuaternion, Vector3, Vector6};
use thiserror::Error;

use cloud::{Cloud, Moments};
use isa::Isa;
use noise::Noise;

use crate::attitude::{quat_from_rotation_vector, wrap_pi};
use crate::earth::{earth_rate_ned, normal_gravity};
use crate::estimator::{
    AttitudeEstimator, AttitudeOutput, AttitudeRestoreError, AttitudeStateSnapshot,
};
use crate::frames::{Frd, Ned, Rotation, Vector};
use crate::mekf::MagneticReference;

/// Samples between two draws of the bias random walk (P1).
const BIAS_WALK_STRIDE: u32 = 16;
/// Samples between two draws of the gyro process noise (P1).
const PROCESS_NOISE_STRIDE: u32 = 4;
/// Time constant of the rest detector's low-pass means, s (P5).
const REST_LOWPASS_S: f64 = 0.5;
/// Smallest per-sample gyro variance of the bias measurement at rest,
/// (rad/s)²: (0.001 °/s)².
const REST_VARIANCE_FLOOR: f64 = 3.046e-10;
/// Most progressive-correction stages per update (P7); the rest of the
/// likelihood is then applied at once.
const MAX_TEMPER_STAGES: usize = 20;
/// Bisection steps for a stage's fraction (P7).
const BISECTION_STEPS: u32 = 12;

/// Why a [`ParticleFilter`] could not be made.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum PfNewError {
    /// Latitude outside [-π/2, π/2] or NaN.
    #[error("latitude {0} rad is outside [-pi/2, pi/2]")]
    LatitudeOutOfRange(f64),
    /// The declination is not finite.
    #[error("declination is not finite")]
    NonFiniteDeclination,
    /// An initial bias, or a standard deviation, is not finite (or negative).
    #[error("initial bias or standard deviation is not valid")]
    BadInitialState,
    /// No aiding attitude from the first samples.
    #[error("no attitude from the first samples: {0}")]
    Aiding(#[from] AidingError),
    /// The first field gives no magnetic reference.
    #[error("no magnetic reference from the first field: {0}")]
    Magnetic(#[from] crate::mekf::MagneticReferenceNewError),
}

/// Why a gyro sample was refused (the state is unchanged).
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum PfPropagateError {
    /// A rate component is NaN or infinite.
    #[error("gyro sample is not finite")]
    NonFinite,
    /// The interval is not a positive finite number of seconds.
    #[error("interval {0} s is not positive and finite")]
    BadInterval(f64),
}

/// What an aiding pair did (each sensor is used, gated or invalid on its own).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AidingUse {
    /// The sensor weighted the particles.
    Used,
    /// Refused by its gate (disturbance).
    Gated,
    /// Not finite, zero, or no direction to compare.
    Invalid,
    /// The same field as the previous sample: not a new measurement.
    Repeated,
}

/// Counts of what the filter did with its inputs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PfStats {
    /// Gyro samples refused.
    pub predict_rejected: u64,
    /// Accelerometer samples that weighted the particles.
    pub tilt_used: u64,
    /// Accelerometer samples refused by the gate.
    pub tilt_gated: u64,
    /// Accelerometer samples refused as invalid.
    pub tilt_invalid: u64,
    /// Magnetometer samples that weighted the particles.
    pub heading_used: u64,
    /// Magnetometer samples refused by the norm or dip gate.
    pub heading_gated: u64,
    /// Magnetometer samples refused as invalid.
    pub heading_invalid: u64,
    /// Samples taken as a bias measurement at rest (P5).
    pub rest_samples: u64,
    /// Resamplings (P6), tempering stages included.
    pub resamples: u64,
    /// Progressive-correction stages (P7): updates split because one would
    /// have left fewer than N_th effective particles.
    pub tempering_stages: u64,
    /// Magnetometer samples equal to the previous one (a sensor that holds
    /// its last value between its own, slower, samples), not used.
    pub heading_repeated: u64,
}

/// The rest detector's state (P5).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Rest {
    started: bool,
    gyro_lp: Vector3<f64>,
    accel_lp: Vector3<f64>,
    /// Low-passed squared deviation of the gyro from its mean, per axis.
    gyro_var: f64,
    still_s: f64,
}

/// Paper 000's attitude particle filter; see the module documentation.
#[derive(Debug, Clone)]
pub struct ParticleFilter {
    config: PfConfig,
    particles: Cloud,
    /// Normalised weights of the last update.
    weights: Vec<f64>,
    /// Scratch, kept between samples (no allocation per sample): the
    /// resampled cloud, random draws, log-likelihoods, the errors
    /// `E_i = q̂ ⊗ q_i⁻¹`, resampling parents, ESS exponents, signed
    /// weights.
    scratch: Cloud,
    normals: Vec<f64>,
    delta: Vec<f64>,
    errors: [Vec<f64>; 4],
    parents: Vec<u32>,
    exponents: Vec<f64>,
    signed: Vec<f64>,
    rng: Noise,
    /// The compiled form of the loops that runs (same bits either way).
    isa: Isa,
    q_hat: UnitQuaternion<f64>,
    bias_hat: Vector3<f64>,
    /// Weighted spread of the attitude about the estimate, N, E, D, rad.
    spread: Vector3<f64>,
    omega_ie_n: Vector3<f64>,
    gravity_m_s2: f64,
    declination_rad: f64,
    magnetic: MagneticReference,
    /// The last gyro sample and its interval (the update's rest test and
    /// mid-interval attitude use them).
    last_gyro: Option<(Vector3<f64>, f64)>,
    bias_walk_steps: u32,
    bias_walk_s: f64,
    /// Samples and seconds since the last process-noise draw (P1).
    noise_steps: u32,
    noise_s: f64,
    /// Earth-rate angle not yet applied to the particles and the estimate
    /// (P1), rad, NED.
    nav_pending: Vector3<f64>,
    rest: Rest,
    /// The low-passed specific force in the navigation frame (P2').
    accel_lp: Option<Vector3<f64>>,
    /// The previous field sample (a repeated one is not new).
    last_mag: Option<Vector3<f64>>,
    calibration: u32,
    stats: PfStats,
}

fn finite3(v: &Vector3<f64>) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// A particle's attitude (body → NED) as its stored `[w, x, y, z]`.
fn to_array(q: &UnitQuaternion<f64>) -> [f64; 4] {
    Rotation::<Frd, Ned>::from_nalgebra(*q).to_wxyz()
}

/// FNV-1a over 64-bit words: mixes a snapshot into the restore seed.
fn fnv1a(words: impl IntoIterator<Item = u64>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for w in words {
        for byte in w.to_le_bytes() {
            h ^= u64::from(byte);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

impl ParticleFilter {
    /// A filter whose particles are drawn around `q_nb` (tilt and heading 1σ
    /// from `config`) with biases around zero, at geodetic latitude
    /// `latitude_rad`, with declination `declination_rad` (east positive) and
    /// the expected field `magnetic`.
    pub fn new(
        config: &PfConfig,
        q_nb: UnitQuaternion<f64>,
        latitude_rad: f64,
        declination_rad: f64,
        magnetic: MagneticReference,
    ) -> Result<Self, PfNewError> {
        if !(latitude_rad.abs() <= std::f64::consts::FRAC_PI_2) {
            return Err(PfNewError::LatitudeOutOfRange(latitude_rad));
        }
        if !declination_rad.is_finite() {
            return Err(PfNewError::NonFiniteDeclination);
        }
        let n = config.particles;
        let mut pf = Self {
            config: *config,
            particles: Cloud::new(n, to_array(&q_nb)),
            weights: vec![1.0 / n as f64; n],
            scratch: Cloud::new(n, to_array(&q_nb)),
            normals: Vec::with_capacity(6 * n),
            delta: Vec::with_capacity(n),
            errors: [
                Vec::with_capacity(n),
                Vec::with_capacity(n),
                Vec::with_capacity(n),
                Vec::with_capacity(n),
            ],
            parents: Vec::with_capacity(n),
            exponents: Vec::with_capacity(n),
            signed: Vec::with_capacity(n),
            rng: Noise::new(config.seed),
            isa: Isa::detect(),
            q_hat: q_nb,
            bias_hat: Vector3::zeros(),
            spread: Vector3::zeros(),
            omega_ie_n: earth_rate_ned(latitude_rad),
            gravity_m_s2: normal_gravity(latitude_rad, 0.0),
            declination_rad,
            magnetic,
            last_gyro: None,
            bias_walk_steps: 0,
            bias_walk_s: 0.0,
            noise_steps: 0,
            noise_s: 0.0,
            nav_pending: Vector3::zeros(),
            rest: Rest {
                started: false,
                gyro_lp: Vector3::zeros(),
                accel_lp: Vector3::zeros(),
                gyro_var: 0.0,
                still_s: 0.0,
            },
            accel_lp: None,
            last_mag: None,
            calibration: 0,
            stats: PfStats::default(),
        };
        let t = config.initial_tilt_std_rad;
        let h = config.initial_heading_std_rad;
        let b = config.initial_bias_std_rad_s;
        let cov = Matrix6::from_diagonal(&Vector6::new(t * t, t * t, h * h, b * b, b * b, b * b));
        pf.draw_particles(&q_nb, &Vector3::zeros(), &cov);
        Ok(pf)
    }

    /// A filter initialised from the first accelerometer and magnetometer
    /// samples: the attitude is paper 000's `q_am` (eqs. 30-41) of the pair,
    /// the magnetic reference the field's norm and dip at that attitude.
    pub fn from_first_sample(
        config: &PfConfig,
        accel_m_s2: &Vector3<f64>,
        mag_ut: &Vector3<f64>,
        latitude_rad: f64,
        declination_rad: f64,
    ) -> Result<Self, PfNewError> {
        let q = aiding_quaternion(accel_m_s2, mag_ut, declination_rad)?;
        let reference = MagneticReference::from_mean_field(&q, mag_ut)?;
        Self::new(config, q, latitude_rad, declination_rad, reference)
    }

    /// Redraws the biases around `gyro_bias` (FRD, rad/s) with `std_rad_s` 1σ
    /// per axis, e.g. a static calibration's gyro offset (paper 000 §IV-A).
    pub fn with_initial_bias(
        mut self,
        gyro_bias: Vector3<f64>,
        std_rad_s: f64,
    ) -> Result<Self, PfNewError> {
        if !(finite3(&gyro_bias) && std_rad_s >= 0.0 && std_rad_s.is_finite()) {
            return Err(PfNewError::BadInitialState);
        }
        let n = self.particles.len();
        self.normals.resize(3 * n, 0.0);
        self.rng.fill_normal(self.isa, &mut self.normals, std_rad_s);
        for (k, (b, e)) in self
            .particles
            .b
            .iter_mut()
            .zip(self.normals.chunks_exact(n))
            .enumerate()
        {
            for (b, e) in b.iter_mut().zip(e) {
                *b = gyro_bias[k] + e;
            }
        }
        self.refresh_estimate();
        Ok(self)
    }

    /// Redraws the attitudes around the estimate with `tilt_std_rad` (north,
    /// east) and `heading_std_rad` (down) 1σ, e.g. after an alignment made
    /// while the vehicle moved.
    pub fn with_initial_attitude_std(
        mut self,
        tilt_std_rad: f64,
        heading_std_rad: f64,
    ) -> Result<Self, PfNewError> {
        let ok = |v: f64| v >= 0.0 && v.is_finite();
        if !(ok(tilt_std_rad) && ok(heading_std_rad)) {
            return Err(PfNewError::BadInitialState);
        }
        let q0 = self.q_hat;
        let n = self.particles.len();
        self.normals.resize(3 * n, 0.0);
        self.rng.fill_normal(self.isa, &mut self.normals, 1.0);
        for i in 0..n {
            let e = Vector3::new(
                self.normals[i] * tilt_std_rad,
                self.normals[n + i] * tilt_std_rad,
                self.normals[2 * n + i] * heading_std_rad,
            );
            let q = to_array(&(quat_from_rotation_vector(&e) * q0));
            self.particles.set_q(i, q);
        }
        self.refresh_estimate();
        Ok(self)
    }

    /// The same filter running the loops' `isa` form (the test of
    /// [`isa`]'s claim that every form gives the same bits).
    #[cfg(test)]
    fn with_isa(mut self, isa: Isa) -> Self {
        self.isa = isa;
        self
    }

    /// Sets the calibration bits reported in snapshots.
    pub fn with_calibration(mut self, calibration: u32) -> Self {
        self.calibration = calibration;
        self
    }

    /// The attitude estimate, body → NED.
    pub fn q_nb(&self) -> UnitQuaternion<f64> {
        self.q_hat
    }

    /// The gyro bias estimate, FRD, rad/s.
    pub fn gyro_bias(&self) -> Vector3<f64> {
        self.bias_hat
    }

    /// What the filter did with its inputs so far.
    pub fn stats(&self) -> PfStats {
        self.stats
    }

    /// The expected field.
    pub fn magnetic_reference(&self) -> MagneticReference {
        self.magnetic
    }

    /// The number of particles.
    pub fn len(&self) -> usize {
        self.particles.len()
    }

    /// Always false (a filter has at least two particles).
    pub fn is_empty(&self) -> bool {
        self.particles.len() == 0
    }

    /// Effective sample size of the current weights (eq. 46).
    pub fn effective_sample_size(&self) -> f64 {
        1.0 / self.weights.iter().map(|w| w * w).sum::<f64>()
    }

    /// Weighted sample covariance of the attitude error about N, E, D
    /// (`δθ_i = 2 s_i vec(q_i ⊗ q̂⁻¹)`, the chart of (P6): `log(q_i ⊗ q̂⁻¹)`
    /// to third order, rad) and the bias (rad/s), 6×6.
    pub fn covariance(&self) -> Matrix6<f64> {
        let mut errors = Default::default();
        self.particles
            .errors(self.isa, &to_array(&self.q_hat), &mut errors);
        resample::cloud_covariance(
            self.isa,
            &self.particles,
            &errors,
            &self.weights,
            &self.bias_hat,
        )
    }

    /// Whether the rest detector currently holds the sensor still (P5).
    pub fn at_rest(&self) -> bool {
        self.rest.still_s >= self.config.rest_min_s
    }

    /// Draws every particle from N(`q` ⊕ δθ, `b` + δb) with covariance `cov`
    /// (attitude error in NED, then bias), the draws centred on their sample
    /// mean so that the cloud's mean is `q`, `b`; equal weights.
    fn draw_particles(&mut self, q: &UnitQuaternion<f64>, b: &Vector3<f64>, cov: &Matrix6<f64>) {
        let l = resample::cholesky_floor(cov);
        let n = self.particles.len();
        self.normals.resize(6 * n, 0.0);
        self.rng.fill_normal(self.isa, &mut self.normals, 1.0);
        let draws: Vec<Vector6<f64>> = (0..n)
            .map(|i| l * Vector6::from_fn(|k, _| self.normals[k * n + i]))
            .collect();
        let mean = draws.iter().sum::<Vector6<f64>>() / n as f64;
        for (i, x) in draws.iter().enumerate() {
            let x = x - mean;
            let dq = quat_from_rotation_vector(&Vector3::new(x[0], x[1], x[2]));
            self.particles.set_q(i, to_array(&(dq * q)));
            for k in 0..3 {
                self.particles.b[k][i] = b[k] + x[3 + k];
            }
            self.particles.lw[i] = 0.0;
        }
        self.weights.iter_mut().for_each(|w| *w = 1.0 / n as f64);
        self.q_hat = *q;
        self.refresh_estimate();
    }

    /// The weighted means (eq. 47) with the current weights: attitude
    /// components sign-aligned with the previous estimate, renormalised; bias;
    /// and the attitude spread.
    fn refresh_estimate(&mut self) {
        let r = to_array(&self.q_hat);
        self.particles.errors(self.isa, &r, &mut self.errors);
        let m = cloud::moments(
            self.isa,
            &self.errors,
            &self.particles.b,
            &self.weights,
            &r,
            &mut self.signed,
        );
        self.finish_moments(&m);
    }

    /// Takes the estimate and spread from accumulated moments (unchanged if
    /// they are not finite).
    fn finish_moments(&mut self, m: &Moments) {
        let q = Rotation::<Frd, Ned>::quaternion_from_wxyz(m.attitude_sum());
        if q.norm() > 0.0 && q.coords.iter().all(|v| v.is_finite()) {
            self.q_hat = UnitQuaternion::new_normalize(q);
        }
        if m.w > 0.0 {
            let b = Vector3::from(m.b) / m.w;
            if finite3(&b) {
                self.bias_hat = b;
            }
            let spread = Vector3::from(m.spread());
            if finite3(&spread) {
                self.spread = spread;
            }
        }
    }

    /// Prediction (P1) over `dt_s` with the average rate `gyro_rad_s`.
    /// Refused (state unchanged) if the rate is not finite or the interval
    /// not positive and finite.
    pub fn propagate(
        &mut self,
        gyro_rad_s: &Vector3<f64>,
        dt_s: f64,
    ) -> Result<(), PfPropagateError> {
        if !finite3(gyro_rad_s) {
            return Err(PfPropagateError::NonFinite);
        }
        if !(dt_s > 0.0 && dt_s.is_finite()) {
            return Err(PfPropagateError::BadInterval(dt_s));
        }
        let n = self.particles.len();
        let w = [gyro_rad_s.x, gyro_rad_s.y, gyro_rad_s.z];
        // The process noise on a grid of PROCESS_NOISE_STRIDE samples, with
        // the variance of their span (P1).
        self.noise_steps += 1;
        self.noise_s += dt_s;
        if self.noise_steps >= PROCESS_NOISE_STRIDE {
            let sigma = self.config.gyro_noise_rad_rt_s * self.noise_s.sqrt();
            self.normals.resize(3 * n, 0.0);
            self.rng.fill_normal(self.isa, &mut self.normals, sigma);
            self.particles
                .propagate(self.isa, w, dt_s, Some(&self.normals));
            self.noise_steps = 0;
            self.noise_s = 0.0;
        } else {
            self.particles.propagate(self.isa, w, dt_s, None);
        }
        // The predicted estimate: the previous one moved by the mean rate (the
        // weighted mean of the moved particles to second order in their
        // spread; the update takes the exact mean).
        let rate = gyro_rad_s - self.bias_hat;
        self.q_hat = UnitQuaternion::new_normalize(
            (self.q_hat * quat_from_rotation_vector(&(rate * dt_s))).into_inner(),
        );
        // The Earth rate, and the bias random walk, on a coarser grid (P1).
        self.nav_pending -= self.omega_ie_n * dt_s;
        self.bias_walk_steps += 1;
        self.bias_walk_s += dt_s;
        if self.bias_walk_steps >= BIAS_WALK_STRIDE {
            let nav = quat_from_rotation_vector(&self.nav_pending);
            self.particles.rotate_nav(self.isa, to_array(&nav));
            self.q_hat = UnitQuaternion::new_normalize((nav * self.q_hat).into_inner());
            self.nav_pending = Vector3::zeros();
            let s = self.config.gyro_bias_walk_rad_s_rt_s * self.bias_walk_s.sqrt();
            if s > 0.0 {
                self.normals.resize(3 * n, 0.0);
                self.rng.fill_normal(self.isa, &mut self.normals, s);
                self.particles.add_bias(self.isa, &self.normals);
            }
            self.bias_walk_steps = 0;
            self.bias_walk_s = 0.0;
        }
        self.last_gyro = Some((*gyro_rad_s, dt_s));
        Ok(())
    }

    /// The rest test (P5) with the latest gyro and accelerometer samples.
    fn update_rest(&mut self, accel_m_s2: &Vector3<f64>) -> bool {
        let Some((gyro, dt)) = self.last_gyro else {
            return false;
        };
        if !self.rest.started {
            self.rest = Rest {
                started: true,
                gyro_lp: gyro,
                accel_lp: *accel_m_s2,
                gyro_var: self.config.gyro_noise_rad_rt_s.powi(2) / dt,
                still_s: 0.0,
            };
            return false;
        }
        let alpha = dt / (REST_LOWPASS_S + dt);
        self.rest.gyro_lp += (gyro - self.rest.gyro_lp) * alpha;
        let dev2 = (gyro - self.rest.gyro_lp).norm_squared() / 3.0;
        self.rest.gyro_var += (dev2 - self.rest.gyro_var) * alpha;
        self.rest.accel_lp += (accel_m_s2 - self.rest.accel_lp) * alpha;
        let th_g = self.config.rest_gyro_rad_s;
        let still = (gyro - self.rest.gyro_lp).norm() <= th_g
            && (accel_m_s2 - self.rest.accel_lp).norm() <= self.config.rest_accel_m_s2
            && (self.rest.gyro_lp - self.bias_hat).norm() <= th_g;
        self.rest.still_s = if still { self.rest.still_s + dt } else { 0.0 };
        self.at_rest()
    }
}
