//! Sensor error processes and the statistics that check them (DESIGN §10).
//!
//! Every generator here is a plain value with its own state; the random
//! numbers come from a generator the caller passes in (in nauta, a
//! `rand_chacha::ChaCha8Rng::seed_from_u64(seed)` per sensor), so each sensor
//! can run alone, and the same seed gives the same series bit for bit.
//!
//! - [`allan`]: overlapping Allan deviation and the read-outs of its curve
//!   (angle random walk N, bias instability B, rate random walk K).
//! - [`inertial`]: gyro / accelerometer axis error model (white noise, bias
//!   instability as a sum of Gauss-Markov processes, rate random walk,
//!   turn-on bias, scale factor), with Xsens MTi-30 class defaults.
//! - [`sensors`]: DVL, acoustic modem, LBL, depth and magnetometer error
//!   generators; each returns what happened (valid, dropout, spike, lost,
//!   multipath, ...) so that tests and evaluation can count events.
//!
//! All quantities are SI inside (rad, s, m, m/s, m/s², T); [`units`] holds
//! the conversions from datasheet units. Every configuration is checked by
//! a `validate` method (called by the constructors) that rejects NaN,
//! infinities, negative standard deviations and probabilities outside
//! [0, 1] with a typed [`NoiseError`].

pub mod allan;
pub mod inertial;
pub mod sensors;
pub mod units;

pub use allan::{
    AllanPoint, FLICKER_FLOOR_FACTOR, allan_deviation, angle_random_walk, average_down,
    bias_instability, log_spaced_taus, rate_random_walk,
};
pub use inertial::{InertialAxisNoise, InertialAxisSpec, InertialTriadNoise};
pub use sensors::{
    DepthNoise, DepthSpec, DvlNoise, DvlOutcome, DvlSpec, LblNoise, LblOutcome, LblReply, LblSpec,
    MagnetometerNoise, MagnetometerSpec, ModemNoise, ModemOutcome, ModemReception, ModemSpec,
};

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// A configuration or an input that a noise model cannot use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NoiseError {
    /// The value is NaN or infinite.
    #[error("{name} must be finite, got {value}")]
    NotFinite {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
    },
    /// A standard deviation, density or length is negative.
    #[error("{name} must be >= 0, got {value}")]
    Negative {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
    },
    /// A rate, period or scale must be strictly positive.
    #[error("{name} must be > 0, got {value}")]
    NotPositive {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
    },
    /// A probability outside [0, 1].
    #[error("{name} must be a probability in [0, 1], got {value}")]
    NotAProbability {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
    },
    /// An interval whose lower end exceeds its upper end.
    #[error("{name} must satisfy lo <= hi, got [{lo}, {hi}]")]
    EmptyInterval {
        /// Parameter name.
        name: &'static str,
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
    /// A matrix that must be invertible (soft iron) is singular or badly conditioned.
    #[error("{name} must be invertible (|det| = {det})")]
    Singular {
        /// Parameter name.
        name: &'static str,
        /// Its determinant.
        det: f64,
    },
    /// Too few samples for the statistic asked for.
    #[error("{what}: need at least {needed} samples, got {got}")]
    TooFewSamples {
        /// The statistic.
        what: &'static str,
        /// Samples needed.
        needed: usize,
        /// Samples given.
        got: usize,
    },
}

pub(crate) fn check_finite(name: &'static str, value: f64) -> Result<(), NoiseError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(NoiseError::NotFinite { name, value })
    }
}

pub(crate) fn check_non_negative(name: &'static str, value: f64) -> Result<(), NoiseError> {
    check_finite(name, value)?;
    if !(value >= 0.0) {
        return Err(NoiseError::Negative { name, value });
    }
    Ok(())
}

pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<(), NoiseError> {
    check_finite(name, value)?;
    if !(value > 0.0) {
        return Err(NoiseError::NotPositive { name, value });
    }
    Ok(())
}

pub(crate) fn check_probability(name: &'static str, value: f64) -> Result<(), NoiseError> {
    // `contains` is false for NaN, so NaN is rejected too.
    if !(0.0..=1.0).contains(&value) {
        return Err(NoiseError::NotAProbability { name, value });
    }
    Ok(())
}

pub(crate) fn check_interval(name: &'static str, lo: f64, hi: f64) -> Result<(), NoiseError> {
    check_non_negative(name, lo)?;
    check_non_negative(name, hi)?;
    if !(lo <= hi) {
        return Err(NoiseError::EmptyInterval { name, lo, hi });
    }
    Ok(())
}

/// One draw of a standard normal variable N(0, 1).
#[inline]
pub(crate) fn std_normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

/// Sample mean and (n-1) standard deviation; test and evaluation helper.
pub fn mean_std(samples: &[f64]) -> (f64, f64) {
    let n = samples.len();
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let mean = samples.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return (mean, 0.0);
    }
    let var = samples.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64;
    (mean, var.sqrt())
}
