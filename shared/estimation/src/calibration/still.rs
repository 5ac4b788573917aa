//! Static calibration (paper 000 §IV-A): with the IMU still, the gyro and
//! accelerometer offsets are the means of the samples less what a still
//! sensor reads: the Earth rate and the specific force of gravity at its
//! attitude. The paper holds the IMU levelled and averages 400 samples
//! ([`crate::alignment::PAPER_000_STATIC_SAMPLES`]); a levelled FRD sensor
//! reads `f = [0, 0, −g]`.
//!
//! An accelerometer offset is only separable from a tilt when the attitude is
//! known (levelled on a reference surface); from an unknown attitude the
//! alignment absorbs it into roll and pitch. The gyro offset needs no attitude
//! beyond the Earth rate's few °/h, which the caller may subtract or not.

use nalgebra::Vector3;
use thiserror::Error;

/// Accumulates still gyro and accelerometer samples (Welford means and spreads).
#[derive(Debug, Clone, PartialEq)]
pub struct StillCalibration {
    min_samples: usize,
    count: usize,
    mean_gyro: Vector3<f64>,
    mean_accel: Vector3<f64>,
    m2_gyro: Vector3<f64>,
    m2_accel: Vector3<f64>,
}

/// The offsets of a still period and how still it was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaticOffsets {
    /// Gyro offset (bias), rad/s: mean reading less the expected rate.
    pub gyro_offset_rad_s: Vector3<f64>,
    /// Accelerometer offset, m/s²: mean reading less the expected specific force.
    pub accel_offset_m_s2: Vector3<f64>,
    /// Standard deviation of the gyro samples per axis, rad/s.
    pub gyro_std_rad_s: Vector3<f64>,
    /// Standard deviation of the accelerometer samples per axis, m/s².
    pub accel_std_m_s2: Vector3<f64>,
    /// Samples averaged.
    pub samples: usize,
}

/// Why a still calibration gave no offsets.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum StillCalibrationError {
    /// A sample or an expected value is not finite (the sample was dropped).
    #[error("sample or expected value is not finite")]
    NonFinite,
    /// Fewer samples than required.
    #[error("only {got} samples, need at least {need}")]
    TooFewSamples {
        /// Samples accumulated.
        got: usize,
        /// Samples required.
        need: usize,
    },
}

impl StillCalibration {
    /// An accumulator that [`finish`](Self::finish)es after at least
    /// `min_samples` samples (at least 1).
    pub fn new(min_samples: usize) -> Self {
        Self {
            min_samples: min_samples.max(1),
            count: 0,
            mean_gyro: Vector3::zeros(),
            mean_accel: Vector3::zeros(),
            m2_gyro: Vector3::zeros(),
            m2_accel: Vector3::zeros(),
        }
    }

    /// Adds one still sample (gyro rad/s, specific force m/s²); a non-finite
    /// sample is refused and changes nothing.
    pub fn push(
        &mut self,
        gyro_rad_s: &Vector3<f64>,
        accel_m_s2: &Vector3<f64>,
    ) -> Result<(), StillCalibrationError> {
        if !(gyro_rad_s.iter().all(|v| v.is_finite()) && accel_m_s2.iter().all(|v| v.is_finite())) {
            return Err(StillCalibrationError::NonFinite);
        }
        self.count += 1;
        let n = self.count as f64;
        let dg = gyro_rad_s - self.mean_gyro;
        self.mean_gyro += dg / n;
        self.m2_gyro += dg.component_mul(&(gyro_rad_s - self.mean_gyro));
        let da = accel_m_s2 - self.mean_accel;
        self.mean_accel += da / n;
        self.m2_accel += da.component_mul(&(accel_m_s2 - self.mean_accel));
        Ok(())
    }

    /// Samples so far.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Offsets against what a still sensor should read: `expected_gyro_rad_s`
    /// (the Earth rate in the body frame, or zeros to keep it in the offset)
    /// and `expected_specific_force_m_s2` (`[0, 0, −g]` for a levelled FRD
    /// sensor, the paper's case).
    pub fn finish(
        &self,
        expected_gyro_rad_s: &Vector3<f64>,
        expected_specific_force_m_s2: &Vector3<f64>,
    ) -> Result<StaticOffsets, StillCalibrationError> {
        if self.count < self.min_samples {
            return Err(StillCalibrationError::TooFewSamples {
                got: self.count,
                need: self.min_samples,
            });
        }
        if !(expected_gyro_rad_s.iter().all(|v| v.is_finite())
            && expected_specific_force_m_s2.iter().all(|v| v.is_finite()))
        {
            return Err(StillCalibrationError::NonFinite);
        }
        let n = self.count as f64;
        Ok(StaticOffsets {
            gyro_offset_rad_s: self.mean_gyro - expected_gyro_rad_s,
            accel_offset_m_s2: self.mean_accel - expected_specific_force_m_s2,
            gyro_std_rad_s: (self.m2_gyro / n).map(f64::sqrt),
            accel_std_m_s2: (self.m2_accel / n).map(f64::sqrt),
            samples: self.count,
        })
    }
}
