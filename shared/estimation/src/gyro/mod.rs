//! Pure gyro integration: the baseline attitude estimator of paper 000 Table I
//! (the "Gyroscope integration" column, eq. 28).
//!
//! The attitude is propagated from the gyro alone, with a fixed gyro bias and
//! Earth-rate compensation, and never corrected: its error grows without bound,
//! which is what the aided estimators are measured against.
//!
//! # Update
//!
//! Each sample is the average rate `ω_ib^b` over its interval `Δt` (DESIGN §4), and
//! the update is the exact, closed-form (K1) of [`crate::attitude::kinematics`]:
//!
//! ```text
//! q_nb(k) = exp(-ω_ie^n Δt) ⊗ q_nb(k-1) ⊗ exp((ω_ib^b - b) Δt)
//! ```
//!
//! Paper 000 eq. 28 is the first-order version of the right-hand factor,
//! `q_k = (q_{k-1} + ½ T_s q_{k-1} ⊗ [0, ω]) / ‖·‖`, without Earth rate; the closed
//! form removes its `|ωT_s|³/12` per-step error and the Earth-rate term removes a
//! drift of up to 7.3e-5 rad/s (15°/h), as large as the in-run bias stability of
//! the MTi-30 class gyro the papers used (Xsens MTi 10-series datasheet: 18°/h).
//!
//! To first order in `Δt` the body rate relative to NED is
//! `ω_nb^b = ω_ib^b - b - C_n^b ω_ie^n`; the nav-frame factor applies it exactly.
//!
//! # Transport rate is neglected
//!
//! NED also turns relative to the Earth as the vehicle moves (transport rate,
//! [`crate::earth::transport_rate_ned`]): at AUV speed it is about
//! `1.5 m/s / 6.4e6 m ≈ 2.3e-7 rad/s` (0.05°/h), i.e. at most 6e-4 rad (0.04°) over
//! a 45-minute survey if it all added up (lawnmower legs in opposite directions
//! mostly cancel), some 400 times less than the gyro bias instability above. A
//! simulator that puts transport rate into its gyro samples will therefore show
//! this much extra drift here; [`crate::attitude::kinematics::body_rate_with_earth`]
//! is the Earth-rate-only rule that this integrator inverts exactly.
//!
//! # Aiding
//!
//! None: [`AttitudeEstimator::update`] does nothing. Initialise the attitude from
//! [`crate::alignment::Alignment`] (static coarse alignment).

use nalgebra::{UnitQuaternion, Vector3};
use thiserror::Error;

use crate::attitude::kinematics::propagate_attitude;
use crate::earth::earth_rate_ned;
use crate::estimator::{
    AttitudeEstimator, AttitudeOutput, AttitudeRestoreError, AttitudeStateSnapshot,
};
use crate::frames::{Frd, Ned, Rotation, Vector};

#[cfg(test)]
mod tests;

/// The gyro-integration attitude estimator.
#[derive(Debug, Clone, PartialEq)]
pub struct GyroIntegrator {
    /// Attitude, body → NED.
    q_nb: UnitQuaternion<f64>,
    /// Fixed gyro bias, FRD, rad/s, subtracted from every sample.
    gyro_bias: Vector3<f64>,
    /// Site latitude, rad.
    latitude_rad: f64,
    /// `ω_ie^n` at the site latitude (cached).
    omega_ie_n: Vector3<f64>,
    /// Stamp at which `q_nb` is valid, ns.
    last_stamp_ns: u64,
    /// Calibration bits, passed through to snapshots.
    calibration: u32,
    /// Inputs refused by [`AttitudeEstimator::predict`].
    rejected: u64,
}

/// The integrator's state as plain numbers, for checkpointing and tests.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GyroState {
    /// Attitude body → NED, `[w, x, y, z]`.
    pub q: [f64; 4],
    /// Gyro bias, FRD, rad/s.
    pub gyro_bias: [f64; 3],
    /// Stamp at which `q` is valid, ns.
    pub last_stamp_ns: u64,
}

/// Why a [`GyroIntegrator`] could not be configured.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum GyroIntegratorNewError {
    /// Latitude outside [-π/2, π/2] or NaN.
    #[error("latitude {0} rad is outside [-pi/2, pi/2]")]
    LatitudeOutOfRange(f64),
    /// A gyro-bias component is NaN or infinite.
    #[error("gyro bias is not finite")]
    NonFiniteBias,
}

/// Why a gyro sample was refused (the state is unchanged).
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum GyroIntegrateError {
    /// A rate component is NaN or infinite.
    #[error("gyro sample is not finite")]
    NonFinite,
    /// The interval is not a positive finite number of seconds.
    #[error("interval {0} s is not positive and finite")]
    BadInterval(f64),
    /// The stamp is not after the last one.
    #[error("stamp {stamp_ns} ns is not after the last one, {last_ns} ns")]
    StampNotIncreasing {
        /// Stamp of the state.
        last_ns: u64,
        /// Stamp of the refused sample.
        stamp_ns: u64,
    },
}

fn check_latitude(latitude_rad: f64) -> Result<(), GyroIntegratorNewError> {
    if latitude_rad.is_nan() || latitude_rad.abs() > std::f64::consts::FRAC_PI_2 {
        return Err(GyroIntegratorNewError::LatitudeOutOfRange(latitude_rad));
    }
    Ok(())
}

impl GyroIntegrator {
    /// Starts from attitude `q_nb` (e.g. from [`crate::alignment::Alignment`]) valid
    /// at `stamp_ns`, at geodetic latitude `latitude_rad`, with zero gyro bias.
    pub fn new(
        q_nb: UnitQuaternion<f64>,
        latitude_rad: f64,
        stamp_ns: u64,
    ) -> Result<Self, GyroIntegratorNewError> {
        check_latitude(latitude_rad)?;
        Ok(Self {
            q_nb,
            gyro_bias: Vector3::zeros(),
            latitude_rad,
            omega_ie_n: earth_rate_ned(latitude_rad),
            last_stamp_ns: stamp_ns,
            calibration: 0,
            rejected: 0,
        })
    }

    /// Sets the fixed gyro bias (FRD, rad/s), e.g. the static-calibration mean of
    /// paper 000 §IV-A.
    pub fn with_gyro_bias(
        mut self,
        gyro_bias: Vector3<f64>,
    ) -> Result<Self, GyroIntegratorNewError> {
        if !gyro_bias.iter().all(|v| v.is_finite()) {
            return Err(GyroIntegratorNewError::NonFiniteBias);
        }
        self.gyro_bias = gyro_bias;
        Ok(self)
    }

    /// Sets the calibration bits reported in snapshots.
    pub fn with_calibration(mut self, calibration: u32) -> Self {
        self.calibration = calibration;
        self
    }

    /// Moves the site (the Earth-rate compensation follows).
    pub fn set_latitude(&mut self, latitude_rad: f64) -> Result<(), GyroIntegratorNewError> {
        check_latitude(latitude_rad)?;
        self.latitude_rad = latitude_rad;
        self.omega_ie_n = earth_rate_ned(latitude_rad);
        Ok(())
    }

    /// Sets the stamp at which the current attitude is valid (e.g. after
    /// [`AttitudeEstimator::restore`], from the snapshot message's header).
    pub fn set_last_stamp_ns(&mut self, stamp_ns: u64) {
        self.last_stamp_ns = stamp_ns;
    }

    /// Attitude, body → NED.
    pub fn q_nb(&self) -> UnitQuaternion<f64> {
        self.q_nb
    }

    /// Fixed gyro bias, FRD, rad/s.
    pub fn gyro_bias(&self) -> Vector3<f64> {
        self.gyro_bias
    }

    /// Site latitude, rad.
    pub fn latitude_rad(&self) -> f64 {
        self.latitude_rad
    }

    /// Stamp at which the attitude is valid, ns.
    pub fn last_stamp_ns(&self) -> u64 {
        self.last_stamp_ns
    }

    /// Calibration bits.
    pub fn calibration(&self) -> u32 {
        self.calibration
    }

    /// Inputs refused through [`AttitudeEstimator::predict`] so far.
    pub fn rejected_count(&self) -> u64 {
        self.rejected
    }

    /// Integrates the sample stamped `stamp_ns`, whose interval runs from the last
    /// stamp to `stamp_ns`.
    pub fn integrate(
        &mut self,
        stamp_ns: u64,
        gyro_rad_s: &Vector3<f64>,
    ) -> Result<(), GyroIntegrateError> {
        if stamp_ns <= self.last_stamp_ns {
            return Err(GyroIntegrateError::StampNotIncreasing {
                last_ns: self.last_stamp_ns,
                stamp_ns,
            });
        }
        // Division by the exact 1e9 keeps e.g. 10_000_000 ns at the f64 nearest 0.01 s.
        let dt_s = (stamp_ns - self.last_stamp_ns) as f64 / 1e9;
        self.propagate(gyro_rad_s, dt_s)?;
        self.last_stamp_ns = stamp_ns;
        Ok(())
    }

    /// Propagates the attitude over `dt_s` with the average rate `gyro_rad_s`
    /// (the stamp is not touched): the exact update (K1),
    /// `q_k = exp(-ω_ie^n Δt) ⊗ q_{k-1} ⊗ exp((ω_ib^b - b) Δt)`.
    pub fn propagate(
        &mut self,
        gyro_rad_s: &Vector3<f64>,
        dt_s: f64,
    ) -> Result<(), GyroIntegrateError> {
        if !gyro_rad_s.iter().all(|v| v.is_finite()) {
            return Err(GyroIntegrateError::NonFinite);
        }
        if !dt_s.is_finite() || dt_s <= 0.0 {
            return Err(GyroIntegrateError::BadInterval(dt_s));
        }
        let omega_ib_b = gyro_rad_s - self.gyro_bias;
        self.q_nb = propagate_attitude(&self.q_nb, &omega_ib_b, &self.omega_ie_n, dt_s);
        Ok(())
    }

    /// The state as plain numbers.
    pub fn state(&self) -> GyroState {
        GyroState {
            q: Rotation::<Frd, Ned>::from_nalgebra(self.q_nb).to_wxyz(),
            gyro_bias: self.gyro_bias.into(),
            last_stamp_ns: self.last_stamp_ns,
        }
    }

    /// Replaces attitude, bias and stamp with `s` (site and calibration are kept).
    /// Refused, with the state unchanged, if a number is not finite or `q` is not
    /// unit to within [`AttitudeStateSnapshot::MAX_NORM_ERROR`].
    pub fn restore_state(&mut self, s: &GyroState) -> Result<(), AttitudeRestoreError> {
        let (q_nb, gyro_bias) = AttitudeStateSnapshot {
            q: s.q,
            gyro_bias: s.gyro_bias,
            covariance: [[0.0; 6]; 6],
            calibration: 0,
        }
        .checked()?;
        self.q_nb = q_nb.to_nalgebra();
        self.gyro_bias = gyro_bias.to_nalgebra();
        self.last_stamp_ns = s.last_stamp_ns;
        Ok(())
    }
}

impl AttitudeEstimator for GyroIntegrator {
    /// [`GyroIntegrator::propagate`]; the stamp advances by `dt_s` rounded to the
    /// nanosecond. A refused sample (non-finite rate, interval not positive) leaves
    /// the state unchanged and is counted in [`GyroIntegrator::rejected_count`].
    fn predict(&mut self, gyro_rad_s: &Vector<Frd>, dt_s: f64) {
        match self.propagate(gyro_rad_s.as_nalgebra(), dt_s) {
            Ok(()) => {
                // dt_s is positive and finite here; `as` saturates absurd values.
                let dt_ns = (dt_s * 1e9).round() as u64;
                self.last_stamp_ns = self.last_stamp_ns.saturating_add(dt_ns);
            }
            Err(_) => self.rejected += 1,
        }
    }

    /// Does nothing: pure gyro integration takes no aiding (it is the unaided
    /// baseline of paper 000 Table I).
    fn update(&mut self, _accel_m_s2: &Vector<Frd>, _mag_ut: &Vector<Frd>) {}

    /// Attitude and bias; `std_rad` is zero (no uncertainty model: "unknown").
    fn estimate(&self) -> AttitudeOutput {
        AttitudeOutput {
            q_nb: Rotation::from_nalgebra(self.q_nb),
            std_rad: Vector::zeros(),
            gyro_bias: Vector::from_nalgebra(self.gyro_bias),
        }
    }

    /// Attitude, bias, calibration bits; the covariance is all zeros (unknown).
    fn snapshot(&self) -> AttitudeStateSnapshot {
        AttitudeStateSnapshot {
            q: Rotation::<Frd, Ned>::from_nalgebra(self.q_nb).to_wxyz(),
            gyro_bias: self.gyro_bias.into(),
            covariance: [[0.0; 6]; 6],
            calibration: self.calibration,
        }
    }

    /// Takes attitude, bias and calibration bits; ignores the covariance; keeps the
    /// site and the stamp (set it with [`GyroIntegrator::set_last_stamp_ns`]).
    fn restore(&mut self, s: &AttitudeStateSnapshot) -> Result<(), AttitudeRestoreError> {
        let (q_nb, gyro_bias) = s.checked()?;
        self.q_nb = q_nb.to_nalgebra();
        self.gyro_bias = gyro_bias.to_nalgebra();
        self.calibration = s.calibration;
        Ok(())
    }
}
