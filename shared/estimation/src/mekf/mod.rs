//! Multiplicative extended Kalman filter (MEKF) for attitude and gyro bias,
//! aided by the accelerometer (gravity direction) and the magnetometer
//! (heading only).
//!
//! References: Markley & Crassidis, "Fundamentals of Spacecraft Attitude
//! Determination and Control", Springer 2014, §6.2 (the MEKF: quaternion
//! reference, three-component attitude error, bias states, reset); Markley,
//! "Attitude error representations for Kalman filtering", J. Guidance, Control,
//! and Dynamics 26(2):311-317, 2003 (the multiplicative error and its reset);
//! Solà, "Quaternion kinematics for the error-state Kalman filter",
//! arXiv:1711.02508, 2017, §7 (the same filter with the error in the global
//! frame, as here). Their equation numbers are not quoted below: they could
//! not be checked against the texts here, so the equations are written out in
//! full, numbered (M1)-(M8), derived for this module's conventions.
//!
//! # State and error (M1)
//!
//! The reference state is the attitude `q̂_nb` (Hamilton, body FRD → NED) and the
//! gyro bias `b̂` (FRD, rad/s). The error state is six-dimensional,
//! `x = [δθ; δb]`, defined by
//!
//! ```text
//! q_nb = exp(δθ) ⊗ q̂_nb,   b = b̂ + δb                                     (M1)
//! ```
//!
//! with `δθ` a rotation vector **in NED** (left, "global" error; Markley &
//! Crassidis and Markley 2003 put it on the body side, which only rotates the
//! equations below by `Ĉ`). So the first three rows and columns of the 6×6
//! covariance `P` are the attitude error about north, east and down, as
//! [`AttitudeOutput::std_rad`] and [`AttitudeStateSnapshot::covariance`] say.
//!
//! # Prediction (M2)-(M4)
//!
//! The gyro measures `ω̃ = ω_ib^b + b + η_v`; the bias walks, `ḃ = η_u`, with
//! white `η_v` (density σ_v, rad/√s: the angle random walk) and `η_u` (density
//! σ_u, rad/s/√s = rad/s²/√Hz: the bias random walk). The reference attitude is
//! propagated exactly with the bias-corrected rate, as [`crate::gyro`] does,
//! through [`propagate_attitude`] ((K1) of [`crate::attitude::kinematics`]):
//!
//! ```text
//! q̂_k = exp(−ω_ie^n Δt) ⊗ q̂_{k−1} ⊗ exp((ω̃ − b̂) Δt),   b̂_k = b̂_{k−1}      (M2)
//! ```
//!
//! With `Ĉ = C_b^n(q̂)`, differentiating (M1) gives the error dynamics
//! (`Ċ = C [ω_ib^b ×] − [ω_ie^n ×] C` for truth and reference):
//!
//! ```text
//! δθ̇ = −ω_ie^n × δθ − Ĉ (δb + η_v),   δḃ = η_u                            (M3)
//! ```
//!
//! discretised to first order over one sample, with `Ĉ` held at its value at
//! the start of the interval:
//!
//! ```text
//! Φ = [ I − [ω_ie^n ×] Δt   −Ĉ Δt ]      Q = [ (σ_v² Δt + σ_u² Δt³/3) I   −σ_u² Δt²/2 Ĉ ]
//!     [ 0                    I    ]          [ −σ_u² Δt²/2 Ĉᵀ              σ_u² Δt I    ]
//! P⁻ = Φ P Φᵀ + Q                                                            (M4)
//! ```
//!
//! `Q` is `∫ Φ(s) G Q_c Gᵀ Φ(s)ᵀ ds` over the interval with `Φ(s)` to first order
//! and `Ĉ Ĉᵀ = I` (the discrete process noise of the Markley & Crassidis §6.2
//! filter, rotated into NED). The Earth rate is compensated as in
//! [`crate::gyro`]; the transport rate is neglected for the same reason.
//!
//! # Gravity direction (M5)
//!
//! The specific force `f̃` (FRD) is `−g` along the vertical when the vehicle
//! does not accelerate. It is the average over the sample's interval (DESIGN
//! §4), so it is rotated with the reference attitude at the middle of the
//! interval, `Ĉ_mid` (from (M2) over `Δt/2`; without it, a rotation at ω leaves a
//! tilt lag of `ω Δt / 2`, 0.1° at 20 °/s and 100 Hz). Its direction
//! `v = Ĉ_mid f̃ / |f̃|` differs from `r = [0, 0, −1]` by the tilt part of `δθ`:
//! from (M1), `v = exp(−δθ) r` (to first order in `Δt`). The measurement is the
//! rotation vector that takes `v` to `r`, horizontal by construction,
//!
//! ```text
//! z_g = atan2(|v × r|, v·r) (v × r)/|v × r| = [δθ_N, δθ_E] + noise,   H_g = [I₂ 0₂ₓ₁ 0₂ₓ₃]   (M5)
//! ```
//!
//! (in the body-frame form of Markley & Crassidis this is the vector
//! measurement `b = A r` with `H = [(A r)×  0]`; here it is rotated into NED,
//! where it involves only north and east). Noise per axis:
//!
//! ```text
//! R_g = [σ_a²/Δt + σ_dyn² + (ω_D v_t)² τ_t/Δt + (|f̃| − g)²] / g²
//! ```
//!
//! white noise of density σ_a over the sample's interval; the unmodelled vehicle
//! acceleration σ_dyn; the centripetal acceleration `ω_D v_t` of a turn at rate
//! ω_D (about the vertical, from the gyro) and speed v_t, which lasts the turn's
//! τ_t and is perpendicular to gravity, so weighted as white noise of the same
//! effect over τ_t; and a term that grows with the norm error, the sign of a
//! linear acceleration. The last three are our heuristics (an attitude filter
//! knows no velocity). A sample with `| |f̃| − g | >` the gate is refused.
//!
//! # Heading (M6)
//!
//! The field `m̃` (FRD, µT) rotated with the reference attitude, `m̂ = Ĉ m̃`,
//! has azimuth `ψ̃ = atan2(m̂_E, m̂_N)`; the expected azimuth is the declination
//! `δ` (east positive). This is the tilt-compensated heading (the alignment's
//! eq. 40 of paper 000) expressed as an error. From (M1), `m̂ = exp(−δθ) m`, and
//! to first order
//!
//! ```text
//! z_m = wrap(δ − ψ̃) = δθ_D − tan I (cos δ δθ_N + sin δ δθ_E) + noise      (M6)
//! H_m = [−tan I cos δ, −tan I sin δ, 1, 0, 0, 0],   R_m = σ_ψ²
//! ```
//!
//! with `I` the dip (inclination) of the reference field. Only the horizontal
//! direction of the field enters `z_m`; its norm and dip are only gated
//! (against the reference, [`MagneticReference`]).
//!
//! # Update (M7) and reset (M8)
//!
//! Each measurement is a standard EKF update of the error state from
//! `δx̂ = 0` (the previous reset zeroed it), with the Joseph form:
//!
//! ```text
//! S = H P Hᵀ + R,   K = T P Hᵀ S⁻¹,   δx̂ = K z,
//! P⁺ = (I − K H) P (I − K H)ᵀ + K R Kᵀ                                    (M7)
//! ```
//!
//! `T = I` for gravity. For the heading, `T` keeps only the down-error row and
//! the bias along the body axis that points down (`c = Ĉᵀ e_D`):
//! `T = diag(0, 0, 1, c cᵀ)`. The heading then never moves roll or pitch
//! directly, so a magnetic disturbance that passes the gates turns the heading
//! (a "consider" update in the sense of Schmidt: the tilt errors enter `S`
//! through `H_m` but are not corrected; the Joseph form keeps `P` right for this
//! suboptimal gain). It reaches roll and pitch only later and weakly, through
//! the bias about the body axis that was down, as far as that axis tilts. The reset folds the error into the reference, renormalises,
//! and transforms `P` with the reset's Jacobian (second order; Markley 2003,
//! Solà §7):
//!
//! ```text
//! q̂⁺ = exp(δθ̂) ⊗ q̂ / ‖·‖,   b̂⁺ = b̂ + δb̂,
//! P⁺ = G P Gᵀ,  G = diag(I + ½[δθ̂ ×], I)                                  (M8)
//! ```
//!
//! Gravity is processed first, reset, then the heading with the corrected
//! attitude.
//!
//! # Inputs
//!
//! Non-finite or zero-norm vectors, non-positive intervals and gated samples
//! are refused without touching the state, and counted ([`MekfStats`]).

mod params;
#[cfg(test)]
mod tests;

pub use params::{MekfConfig, MekfParams, MekfParamsError};

use nalgebra::{Matrix3, Matrix6, SMatrix, SVector, UnitQuaternion, Vector3, Vector6};
use thiserror::Error;

use crate::attitude::kinematics::propagate_attitude;
use crate::attitude::{quat_from_rotation_vector, wrap_pi};
use crate::earth::{earth_rate_ned, normal_gravity};
use crate::estimator::{
    AttitudeEstimator, AttitudeOutput, AttitudeRestoreError, AttitudeStateSnapshot,
};
use crate::frames::{Frd, Rotation, Vector};

/// The field the magnetometer should see: its norm and dip, e.g. measured during
/// the static alignment ([`MagneticReference::from_mean_field`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagneticReference {
    field_ut: f64,
    dip_rad: f64,
}

/// Why a [`MagneticReference`] cannot be made.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum MagneticReferenceNewError {
    /// The norm is not positive and finite.
    #[error("magnetic field norm {0} µT is not positive and finite")]
    BadNorm(f64),
    /// The dip is not finite or within 1° of vertical (no horizontal field for a
    /// heading).
    #[error("magnetic dip {0} rad is not finite or too close to vertical")]
    BadDip(f64),
}

impl MagneticReference {
    /// Largest |dip| accepted: within 1° of vertical, heading is undefined.
    pub const MAX_DIP_RAD: f64 = 89.0 * std::f64::consts::PI / 180.0;

    /// A reference of norm `field_ut` (µT) and dip `dip_rad` (positive down).
    pub fn new(field_ut: f64, dip_rad: f64) -> Result<Self, MagneticReferenceNewError> {
        if !(field_ut > 0.0 && field_ut.is_finite()) {
            return Err(MagneticReferenceNewError::BadNorm(field_ut));
        }
        if !(dip_rad.abs() <= Self::MAX_DIP_RAD) {
            return Err(MagneticReferenceNewError::BadDip(dip_rad));
        }
        Ok(Self { field_ut, dip_rad })
    }

    /// The reference seen by a still sensor at attitude `q_nb` whose mean field is
    /// `mean_mag_ut` (FRD, µT): its norm, and the dip of `q_nb · m`.
    pub fn from_mean_field(
        q_nb: &UnitQuaternion<f64>,
        mean_mag_ut: &Vector3<f64>,
    ) -> Result<Self, MagneticReferenceNewError> {
        let m_n = q_nb * mean_mag_ut;
        Self::new(mean_mag_ut.norm(), m_n.z.atan2(m_n.x.hypot(m_n.y)))
    }

    /// Norm, µT.
    pub fn field_ut(&self) -> f64 {
        self.field_ut
    }

    /// Dip, rad, positive down.
    pub fn dip_rad(&self) -> f64 {
        self.dip_rad
    }
}

/// Why an [`Mekf`] could not be made.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum MekfNewError {
    /// Latitude outside [-π/2, π/2] or NaN.
    #[error("latitude {0} rad is outside [-pi/2, pi/2]")]
    LatitudeOutOfRange(f64),
    /// The declination is not finite.
    #[error("declination is not finite")]
    NonFiniteDeclination,
    /// The initial bias or its standard deviation is not finite (or the deviation
    /// is not positive).
    #[error("initial gyro bias or its standard deviation is not valid")]
    BadInitialBias,
    /// An initial attitude standard deviation is not positive and finite.
    #[error("initial attitude standard deviation is not positive and finite")]
    BadInitialAttitudeStd,
}

/// Why a gyro sample was refused (the state is unchanged).
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum MekfPropagateError {
    /// A rate component is NaN or infinite (or the propagation overflowed).
    #[error("gyro sample is not finite")]
    NonFinite,
    /// The interval is not a positive finite number of seconds.
    #[error("interval {0} s is not positive and finite")]
    BadInterval(f64),
}

/// Why a specific-force sample was not used.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum GravityUpdateError {
    /// A component is NaN or infinite.
    #[error("specific force is not finite")]
    NonFinite,
    /// The vector is zero (no direction).
    #[error("specific force is zero")]
    ZeroNorm,
    /// `| |f| − g |` is above the gate (linear acceleration).
    #[error("specific force norm is {deviation_m_s2} m/s^2 away from gravity")]
    Gated {
        /// `|f| − g`, m/s².
        deviation_m_s2: f64,
    },
    /// The innovation covariance could not be inverted (the state is unchanged).
    #[error("innovation covariance is singular")]
    Singular,
}

/// Why a magnetometer sample was not used.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum HeadingUpdateError {
    /// A component is NaN or infinite.
    #[error("magnetic field is not finite")]
    NonFinite,
    /// The vector is zero.
    #[error("magnetic field is zero")]
    ZeroNorm,
    /// The norm differs from the reference by more than the gate.
    #[error("field norm is {ratio} of the reference")]
    NormGated {
        /// `|m| / |m_ref|`.
        ratio: f64,
    },
    /// The dip differs from the reference by more than the gate.
    #[error("field dip differs from the reference by {difference_rad} rad")]
    DipGated {
        /// Dip minus reference dip, rad.
        difference_rad: f64,
    },
    /// The innovation covariance could not be inverted (the state is unchanged).
    #[error("innovation covariance is singular")]
    Singular,
}

/// Counts of what the filter did with its inputs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MekfStats {
    /// Gyro samples refused (non-finite rate, bad interval).
    pub predict_rejected: u64,
    /// Specific-force samples used.
    pub gravity_used: u64,
    /// Specific-force samples refused as invalid (non-finite, zero, singular).
    pub gravity_invalid: u64,
    /// Specific-force samples refused by the gate.
    pub gravity_gated: u64,
    /// Magnetometer samples used.
    pub heading_used: u64,
    /// Magnetometer samples refused as invalid (non-finite, zero, singular).
    pub heading_invalid: u64,
    /// Magnetometer samples refused by the norm or dip gate.
    pub heading_gated: u64,
}

/// The MEKF attitude estimator; see the module documentation.
#[derive(Debug, Clone, PartialEq)]
pub struct Mekf {
    config: MekfConfig,
    /// Reference attitude, body → NED.
    q_nb: UnitQuaternion<f64>,
    /// Reference gyro bias, FRD, rad/s.
    gyro_bias: Vector3<f64>,
    /// Error covariance: attitude error about N, E, D (rad), then bias (rad/s).
    p: Matrix6<f64>,
    /// `ω_ie^n` at the site latitude.
    omega_ie_n: Vector3<f64>,
    /// Normal gravity at the site, m/s².
    gravity_m_s2: f64,
    declination_rad: f64,
    magnetic: MagneticReference,
    /// Interval of the last gyro sample, s: the accelerometer sample that
    /// follows averages over the same interval.
    last_dt_s: Option<f64>,
    /// Rate of turn about the vertical over the last gyro interval, rad/s.
    turn_rate_rad_s: f64,
    /// `q̂_nb(t_k)⁻¹ ⊗ q̂_nb(t_k − Δt/2)`: the attitude at the middle of the last
    /// gyro interval, relative to the current one (body side, so a reset moves
    /// both alike).
    mid_from_end: UnitQuaternion<f64>,
    calibration: u32,
    stats: MekfStats,
}

/// `P` with the configured initial standard deviations: attitude (N, E tilt;
/// D heading) and bias.
fn initial_covariance(config: &MekfConfig, bias_std_rad_s: f64) -> Matrix6<f64> {
    let t = config.initial_tilt_std_rad.powi(2);
    let h = config.initial_heading_std_rad.powi(2);
    let b = bias_std_rad_s.powi(2);
    Matrix6::from_diagonal(&Vector6::new(t, t, h, b, b, b))
}

fn symmetrise(p: &Matrix6<f64>) -> Matrix6<f64> {
    (p + p.transpose()) * 0.5
}

fn is_finite<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> bool {
    m.iter().all(|v| v.is_finite())
}

impl Mekf {
    /// A filter at attitude `q_nb` (e.g. from [`crate::alignment::Alignment`]) with
    /// zero gyro bias, at geodetic latitude `latitude_rad`, with magnetic
    /// declination `declination_rad` (east positive) and the expected field
    /// `magnetic`; initial covariance from `config`.
    pub fn new(
        config: &MekfConfig,
        q_nb: UnitQuaternion<f64>,
        latitude_rad: f64,
        declination_rad: f64,
        magnetic: MagneticReference,
    ) -> Result<Self, MekfNewError> {
        if !(latitude_rad.abs() <= std::f64::consts::FRAC_PI_2) {
            return Err(MekfNewError::LatitudeOutOfRange(latitude_rad));
        }
        if !declination_rad.is_finite() {
            return Err(MekfNewError::NonFiniteDeclination);
        }
        Ok(Self {
            config: *config,
            q_nb,
            gyro_bias: Vector3::zeros(),
            p: initial_covariance(config, config.initial_bias_std_rad_s),
            omega_ie_n: earth_rate_ned(latitude_rad),
            gravity_m_s2: normal_gravity(latitude_rad, 0.0),
            declination_rad,
            magnetic,
            last_dt_s: None,
            turn_rate_rad_s: 0.0,
            mid_from_end: UnitQuaternion::identity(),
            calibration: 0,
            stats: MekfStats::default(),
        })
    }

    /// Starts from gyro bias `gyro_bias` (FRD, rad/s) known to `std_rad_s` (1σ per
    /// axis), e.g. the mean of a still period less the Earth rate (sets the bias
    /// block of the covariance, uncorrelated with the attitude).
    pub fn with_initial_bias(
        mut self,
        gyro_bias: Vector3<f64>,
        std_rad_s: f64,
    ) -> Result<Self, MekfNewError> {
        if !(gyro_bias.iter().all(|v| v.is_finite()) && std_rad_s > 0.0 && std_rad_s.is_finite()) {
            return Err(MekfNewError::BadInitialBias);
        }
        self.gyro_bias = gyro_bias;
        self.p.fixed_view_mut::<3, 3>(0, 3).fill(0.0);
        self.p.fixed_view_mut::<3, 3>(3, 0).fill(0.0);
        self.p
            .fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Matrix3::identity() * (std_rad_s * std_rad_s)));
        Ok(self)
    }

    /// Starts with attitude errors of `tilt_std_rad` (north, east) and
    /// `heading_std_rad` (down), 1σ, instead of the configured ones (e.g. after an
    /// alignment made while the vehicle moved; sets the attitude block of the
    /// covariance, uncorrelated with the bias). Both must be positive and finite.
    pub fn with_initial_attitude_std(
        mut self,
        tilt_std_rad: f64,
        heading_std_rad: f64,
    ) -> Result<Self, MekfNewError> {
        let ok = |v: f64| v > 0.0 && v.is_finite();
        if !(ok(tilt_std_rad) && ok(heading_std_rad)) {
            return Err(MekfNewError::BadInitialAttitudeStd);
        }
        self.p.fixed_view_mut::<3, 3>(0, 0).fill(0.0);
        self.p.fixed_view_mut::<3, 3>(0, 3).fill(0.0);
        self.p.fixed_view_mut::<3, 3>(3, 0).fill(0.0);
        self.p[(0, 0)] = tilt_std_rad * tilt_std_rad;
        self.p[(1, 1)] = tilt_std_rad * tilt_std_rad;
        self.p[(2, 2)] = heading_std_rad * heading_std_rad;
        Ok(self)
    }

    /// Sets the calibration bits reported in snapshots.
    pub fn with_calibration(mut self, calibration: u32) -> Self {
        self.calibration = calibration;
        self
    }

    /// Reference attitude, body → NED.
    pub fn q_nb(&self) -> UnitQuaternion<f64> {
        self.q_nb
    }

    /// Gyro bias estimate, FRD, rad/s.
    pub fn gyro_bias(&self) -> Vector3<f64> {
        self.gyro_bias
    }

    /// Error covariance (attitude error N, E, D in rad, then bias in rad/s).
    pub fn covariance(&self) -> &Matrix6<f64> {
        &self.p
    }

    /// What the filter did with its inputs so far.
    pub fn stats(&self) -> MekfStats {
        self.stats
    }

    /// The expected field.
    pub fn magnetic_reference(&self) -> MagneticReference {
        self.magnetic
    }

    /// Propagation (M2)-(M4) over `dt_s` with the average rate `gyro_rad_s`.
    /// Refused (state unchanged) if the rate is not finite or the interval not
    /// positive and finite.
    pub fn propagate(
        &mut self,
        gyro_rad_s: &Vector3<f64>,
        dt_s: f64,
    ) -> Result<(), MekfPropagateError> {
        if !gyro_rad_s.iter().all(|v| v.is_finite()) {
            return Err(MekfPropagateError::NonFinite);
        }
        if !(dt_s > 0.0 && dt_s.is_finite()) {
            return Err(MekfPropagateError::BadInterval(dt_s));
        }
        let c_bn = *self.q_nb.to_rotation_matrix().matrix();
        let omega_ib_b = gyro_rad_s - self.gyro_bias;
        let q = propagate_attitude(&self.q_nb, &omega_ib_b, &self.omega_ie_n, dt_s);
        let q_mid = propagate_attitude(&self.q_nb, &omega_ib_b, &self.omega_ie_n, 0.5 * dt_s);

        // (M4): Φ and Q to first order, Ĉ at the start of the interval.
        let mut phi = Matrix6::<f64>::identity();
        phi.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() - self.omega_ie_n.cross_matrix() * dt_s));
        phi.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-c_bn * dt_s));
        let sv2 = self.config.gyro_noise_rad_rt_s.powi(2);
        let su2 = self.config.gyro_bias_walk_rad_s_rt_s.powi(2);
        let mut q_d = Matrix6::<f64>::zeros();
        q_d.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * (sv2 * dt_s + su2 * dt_s.powi(3) / 3.0)));
        let cross = c_bn * (-0.5 * su2 * dt_s * dt_s);
        q_d.fixed_view_mut::<3, 3>(0, 3).copy_from(&cross);
        q_d.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&cross.transpose());
        q_d.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Matrix3::identity() * (su2 * dt_s)));
        let p = symmetrise(&(phi * self.p * phi.transpose() + q_d));
        if !is_finite(&p) || !q.coords.iter().all(|v| v.is_finite()) {
            return Err(MekfPropagateError::NonFinite);
        }
        self.q_nb = q;
        self.p = p;
        self.last_dt_s = Some(dt_s);
        self.mid_from_end = q.inverse() * q_mid;
        // ω_nb in NED, to first order: Ĉ (ω̃ − b̂) − ω_ie^n; its down component.
        self.turn_rate_rad_s = (c_bn * omega_ib_b - self.omega_ie_n).z;
        Ok(())
    }

    /// Gravity-direction update (M5), (M7), (M8) with specific force `accel_m_s2`
    /// (FRD, m/s²). Refused, state unchanged, when invalid or gated.
    pub fn update_gravity(&mut self, accel_m_s2: &Vector3<f64>) -> Result<(), GravityUpdateError> {
        if !accel_m_s2.iter().all(|v| v.is_finite()) {
            return Err(GravityUpdateError::NonFinite);
        }
        let norm = accel_m_s2.norm();
        if !(norm > 0.0 && norm.is_finite()) {
            return Err(GravityUpdateError::ZeroNorm);
        }
        let g = self.gravity_m_s2;
        let deviation = norm - g;
        if !(deviation.abs() <= self.config.accel_gate_m_s2) {
            return Err(GravityUpdateError::Gated {
                deviation_m_s2: deviation,
            });
        }
        let v = (self.q_nb * self.mid_from_end) * (accel_m_s2 / norm);
        let r = Vector3::new(0.0, 0.0, -1.0);
        let axis = v.cross(&r);
        let s = axis.norm();
        let angle = s.atan2(v.dot(&r));
        // z = rotation vector taking v to r (horizontal); zero when aligned.
        let z_n = if s > 0.0 {
            axis * (angle / s)
        } else {
            Vector3::zeros()
        };
        let z = SVector::<f64, 2>::new(z_n.x, z_n.y);
        let mut h = SMatrix::<f64, 2, 6>::zeros();
        h[(0, 0)] = 1.0;
        h[(1, 1)] = 1.0;
        let (white, turn) = match self.last_dt_s {
            Some(dt) => (
                self.config.accel_noise_m_s2_rt_hz.powi(2) / dt,
                (self.turn_rate_rad_s * self.config.turn_speed_m_s).powi(2)
                    * self.config.turn_duration_s
                    / dt,
            ),
            None => (0.0, 0.0),
        };
        let var =
            (white + self.config.accel_dynamic_sigma_m_s2.powi(2) + turn + deviation * deviation)
                / (g * g);
        let r_g = SMatrix::<f64, 2, 2>::identity() * var;
        self.correct(&h, &z, &r_g, None)
            .map_err(|Singular| GravityUpdateError::Singular)
    }

    /// Heading update (M6), (M7), (M8) with the magnetic field `mag_ut` (FRD,
    /// µT). Refused, state unchanged, when invalid or gated.
    pub fn update_heading(&mut self, mag_ut: &Vector3<f64>) -> Result<(), HeadingUpdateError> {
        if !mag_ut.iter().all(|v| v.is_finite()) {
            return Err(HeadingUpdateError::NonFinite);
        }
        let norm = mag_ut.norm();
        if !(norm > 0.0 && norm.is_finite()) {
            return Err(HeadingUpdateError::ZeroNorm);
        }
        let ratio = norm / self.magnetic.field_ut;
        if !((ratio - 1.0).abs() <= self.config.mag_norm_gate) {
            return Err(HeadingUpdateError::NormGated { ratio });
        }
        let m_n = self.q_nb * mag_ut;
        let horizontal = m_n.x.hypot(m_n.y);
        let dip = m_n.z.atan2(horizontal);
        let difference = dip - self.magnetic.dip_rad;
        // A field with no horizontal part has no heading, whatever the gate.
        if !(difference.abs() <= self.config.mag_dip_gate_rad && horizontal > 0.0) {
            return Err(HeadingUpdateError::DipGated {
                difference_rad: difference,
            });
        }
        let psi = m_n.y.atan2(m_n.x);
        let z = SVector::<f64, 1>::new(wrap_pi(self.declination_rad - psi));
        let tan_dip = self.magnetic.dip_rad.tan();
        let (sd, cd) = self.declination_rad.sin_cos();
        let h = SMatrix::<f64, 1, 6>::from_row_slice(&[
            -tan_dip * cd,
            -tan_dip * sd,
            1.0,
            0.0,
            0.0,
            0.0,
        ]);
        let r_m = SMatrix::<f64, 1, 1>::new(self.config.mag_heading_sigma_rad.powi(2));
        // T: the down-error row and the bias along the body axis that points down.
        let c = self.q_nb.inverse_transform_vector(&Vector3::z());
        let mut t = Matrix6::<f64>::zeros();
        t[(2, 2)] = 1.0;
        t.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(c * c.transpose()));
        self.correct(&h, &z, &r_m, Some(&t))
            .map_err(|Singular| HeadingUpdateError::Singular)
    }

    /// (M7) then (M8); the state changes only if every result is finite.
    fn correct<const M: usize>(
        &mut self,
        h: &SMatrix<f64, M, 6>,
        z: &SVector<f64, M>,
        r: &SMatrix<f64, M, M>,
        restrict: Option<&Matrix6<f64>>,
    ) -> Result<(), Singular> {
        let pht = self.p * h.transpose();
        let s = h * pht + r;
        let s_inv = s.try_inverse().ok_or(Singular)?;
        let mut k = pht * s_inv;
        if let Some(t) = restrict {
            k = t * k;
        }
        let dx: Vector6<f64> = k * z;
        let ikh = Matrix6::identity() - k * h;
        let p = ikh * self.p * ikh.transpose() + k * r * k.transpose();
        // (M8): reset.
        let dtheta = Vector3::new(dx[0], dx[1], dx[2]);
        let q = UnitQuaternion::new_normalize(
            (quat_from_rotation_vector(&dtheta) * self.q_nb).into_inner(),
        );
        let mut g = Matrix6::<f64>::identity();
        g.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() + dtheta.cross_matrix() * 0.5));
        let p = symmetrise(&(g * p * g.transpose()));
        if !(is_finite(&p) && is_finite(&dx) && q.coords.iter().all(|v| v.is_finite())) {
            return Err(Singular);
        }
        self.q_nb = q;
        self.gyro_bias += Vector3::new(dx[3], dx[4], dx[5]);
        self.p = p;
        Ok(())
    }
}

/// The innovation covariance was singular or the update not finite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Singular;

/// A snapshot's covariance is usable: symmetric to rounding with a positive
/// diagonal. All zeros means "unknown" (a snapshot of an estimator without
/// uncertainty, such as [`crate::gyro::GyroIntegrator`]).
fn snapshot_covariance(c: &[[f64; 6]; 6]) -> Result<Option<Matrix6<f64>>, AttitudeRestoreError> {
    let p = Matrix6::from_fn(|i, j| c[i][j]);
    if p.iter().all(|v| *v == 0.0) {
        return Ok(None);
    }
    let scale = p.diagonal().amax();
    let asymmetric = (p - p.transpose()).amax() > 1e-9 * scale;
    if asymmetric || !p.diagonal().iter().all(|d| *d > 0.0) {
        return Err(AttitudeRestoreError::NotCovariance);
    }
    Ok(Some(p))
}

impl AttitudeEstimator for Mekf {
    /// [`Mekf::propagate`]; a refused sample is counted in
    /// [`MekfStats::predict_rejected`].
    fn predict(&mut self, gyro_rad_s: &Vector<Frd>, dt_s: f64) {
        if self.propagate(gyro_rad_s.as_nalgebra(), dt_s).is_err() {
            self.stats.predict_rejected += 1;
        }
    }

    /// [`Mekf::update_gravity`] then [`Mekf::update_heading`], each counted in
    /// [`MekfStats`]; either may be refused on its own.
    fn update(&mut self, accel_m_s2: &Vector<Frd>, mag_ut: &Vector<Frd>) {
        match self.update_gravity(accel_m_s2.as_nalgebra()) {
            Ok(()) => self.stats.gravity_used += 1,
            Err(GravityUpdateError::Gated { .. }) => self.stats.gravity_gated += 1,
            Err(_) => self.stats.gravity_invalid += 1,
        }
        match self.update_heading(mag_ut.as_nalgebra()) {
            Ok(()) => self.stats.heading_used += 1,
            Err(HeadingUpdateError::NormGated { .. } | HeadingUpdateError::DipGated { .. }) => {
                self.stats.heading_gated += 1
            }
            Err(_) => self.stats.heading_invalid += 1,
        }
    }

    /// Attitude, the square roots of the attitude block's diagonal (N, E, D) and
    /// the bias.
    fn estimate(&self) -> AttitudeOutput {
        AttitudeOutput {
            q_nb: Rotation::from_nalgebra(self.q_nb),
            std_rad: Vector::from_nalgebra(
                Vector3::new(self.p[(0, 0)], self.p[(1, 1)], self.p[(2, 2)]).map(f64::sqrt),
            ),
            gyro_bias: Vector::from_nalgebra(self.gyro_bias),
        }
    }

    /// Attitude, bias, the full 6×6 covariance (row-major) and the calibration bits.
    fn snapshot(&self) -> AttitudeStateSnapshot {
        let mut covariance = [[0.0; 6]; 6];
        for (i, row) in covariance.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = self.p[(i, j)];
            }
        }
        AttitudeStateSnapshot {
            q: Rotation::<Frd, crate::frames::Ned>::from_nalgebra(self.q_nb).to_wxyz(),
            gyro_bias: self.gyro_bias.into(),
            covariance,
            calibration: self.calibration,
        }
    }

    /// Takes attitude, bias, covariance and calibration bits; keeps the
    /// parameters, site and magnetic reference. The quaternion is taken bit for
    /// bit when it is unit to rounding (so a restored instance continues exactly),
    /// else renormalised. An all-zero covariance ("unknown", e.g. from the `gyro`
    /// variant) is replaced by the configured initial one; a covariance that is
    /// not symmetric with a positive diagonal is refused. The values of the last
    /// gyro interval (its length, turn rate, mid-interval attitude) are not in a
    /// snapshot: the next `predict` sets them, so restore before a `predict`
    /// (as the attitude service does) to continue exactly.
    fn restore(&mut self, s: &AttitudeStateSnapshot) -> Result<(), AttitudeRestoreError> {
        let (q_checked, gyro_bias) = s.checked()?;
        let p = snapshot_covariance(&s.covariance)?.unwrap_or_else(|| {
            initial_covariance(&self.config, self.config.initial_bias_std_rad_s)
        });
        self.q_nb = Rotation::from_wxyz_exact(s.q)
            .unwrap_or(q_checked)
            .to_nalgebra();
        self.gyro_bias = gyro_bias.to_nalgebra();
        self.p = p;
        self.calibration = s.calibration;
        Ok(())
    }
}
