//! Magnetometer hard- and soft-iron calibration: the model, its inverse, the
//! closed-form least-squares ellipsoid fit and the figure of merit.
//!
//! # Model (C1)
//!
//! ```text
//! m̃ = S m + h + w                                                       (C1)
//! ```
//!
//! (`shared/sim/src/noise/sensors.rs`, `MagnetometerSpec`): the true field `m`
//! (body frame) seen through the soft-iron matrix `S`, offset by the hard
//! iron `h`, plus white noise `w`. As the sensor turns in a constant field of
//! norm `R`, `m̃` lies on the ellipsoid `(m̃ − h)ᵀ S⁻ᵀ S⁻¹ (m̃ − h) = R²`; the
//! calibration `m = W (m̃ − h)` maps it back onto the centred sphere of
//! radius `R`. Only `WᵀW = S⁻ᵀ S⁻¹` is observable from the norm, so `W` is
//! taken symmetric positive definite (a rotation left in `S` is not
//! recoverable from one sensor and is not removed).
//!
//! # Least-squares ellipsoid (C2)
//!
//! The samples, centred on their mean `μ` and scaled by their mean distance
//! `s` from it (`u = (m̃ − μ)/s`, for conditioning), are fitted with the
//! general quadric `uᵀ A u + 2 bᵀ u = 1` (nine unknowns: the six of the
//! symmetric `A`, the three of `b`) in the least-squares sense, by the normal
//! equations of the rows `[u_x², u_y², u_z², 2u_xu_y, 2u_xu_z, 2u_yu_z, 2u_x,
//! 2u_y, 2u_z] v = 1`. Completing the square, the centre is `c = −A⁻¹ b`
//! and `(u − c)ᵀ (A/k) (u − c) = 1` with `k = 1 + cᵀ A c`; so
//!
//! ```text
//! h = μ + s c,   W = R (A / (k s²))^½                                      (C2)
//! ```
//!
//! with the symmetric square root (eigen-decomposition). `A/k` must be
//! positive definite, else the samples do not outline an ellipsoid (too few
//! attitudes) and the fit is refused. This is the algebraic fit of the
//! standard magnetometer-calibration literature (e.g. Vasconcelos et al.,
//! "Geometric approach to strapdown magnetometer calibration in sensor
//! frame", IEEE TAES 47(2), 2011, which refines it iteratively); it minimises
//! the algebraic, not the geometric, distance.

use nalgebra::{Matrix3, SMatrix, SVector, SymmetricEigen, Vector3};
use thiserror::Error;

/// A magnetometer calibration: `m = W (m̃ − h)` (C1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagCalibration {
    /// Hard iron `h`, µT, sensor frame.
    pub hard_iron_ut: Vector3<f64>,
    /// `W`, the inverse of the soft iron (symmetric when fitted here).
    pub soft_iron_inv: Matrix3<f64>,
}

impl Default for MagCalibration {
    fn default() -> Self {
        Self::identity()
    }
}

impl MagCalibration {
    /// No correction.
    pub fn identity() -> Self {
        Self {
            hard_iron_ut: Vector3::zeros(),
            soft_iron_inv: Matrix3::identity(),
        }
    }

    /// A calibration from its parts; refused unless every number is finite and
    /// `W` invertible (|det W| > 1e-9).
    pub fn new(
        hard_iron_ut: Vector3<f64>,
        soft_iron_inv: Matrix3<f64>,
    ) -> Result<Self, MagCalibrationError> {
        if !(hard_iron_ut.iter().all(|v| v.is_finite())
            && soft_iron_inv.iter().all(|v| v.is_finite()))
        {
            return Err(MagCalibrationError::NonFinite);
        }
        if !(soft_iron_inv.determinant().abs() > 1e-9) {
            return Err(MagCalibrationError::NotEllipsoid);
        }
        Ok(Self {
            hard_iron_ut,
            soft_iron_inv,
        })
    }

    /// The calibrated field `W (m̃ − h)`, µT.
    pub fn apply(&self, raw_ut: &Vector3<f64>) -> Vector3<f64> {
        self.soft_iron_inv * (raw_ut - self.hard_iron_ut)
    }
}

/// Which fit [`fit`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MagFitMethod {
    /// The closed-form least-squares ellipsoid (C2). The default: on the
    /// tests' distorted field it leaves the same norm spread as the swarm (to
    /// six digits), in one pass over the data instead of 16,040, and needs no
    /// seed.
    #[default]
    LeastSquares,
    /// Particle swarm optimisation of the norm error (paper 000 §IV-A).
    Pso,
}

/// Why a calibration could not be fitted.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum MagCalibrationError {
    /// Fewer samples than [`MIN_SAMPLES`].
    #[error("only {0} samples; a fit needs at least {MIN_SAMPLES}")]
    TooFewSamples(usize),
    /// A sample, the reference norm or a parameter is not finite (or the
    /// reference norm is not positive).
    #[error("a sample or the reference norm is not finite and positive")]
    NonFinite,
    /// The samples do not outline an ellipsoid (too few attitudes), or the
    /// result is singular.
    #[error("the samples do not outline an ellipsoid")]
    NotEllipsoid,
}

/// The fewest samples a fit accepts (nine unknowns, with margin).
pub const MIN_SAMPLES: usize = 20;

/// Spread of the calibrated field's norm, the figure of merit: for a perfect
/// calibration in a constant field, only the sensor noise remains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormSpread {
    /// Mean norm, µT.
    pub mean_ut: f64,
    /// Standard deviation of the norm, µT.
    pub std_ut: f64,
    /// Smallest norm, µT.
    pub min_ut: f64,
    /// Largest norm, µT.
    pub max_ut: f64,
}

impl NormSpread {
    /// The spread of `|cal(m̃)|` over `samples`; `None` when there are none.
    pub fn of(samples: &[Vector3<f64>], cal: &MagCalibration) -> Option<Self> {
        if samples.is_empty() {
            return None;
        }
        let n = samples.len() as f64;
        let (mut sum, mut min, mut max) = (0.0, f64::INFINITY, f64::NEG_INFINITY);
        for m in samples {
            let r = cal.apply(m).norm();
            sum += r;
            min = min.min(r);
            max = max.max(r);
        }
        let mean = sum / n;
        let var = samples
            .iter()
            .map(|m| (cal.apply(m).norm() - mean).powi(2))
            .sum::<f64>()
            / n;
        Some(Self {
            mean_ut: mean,
            std_ut: var.sqrt(),
            min_ut: min,
            max_ut: max,
        })
    }
}

/// Checks the inputs common to both fits.
pub(super) fn check_inputs(
    samples: &[Vector3<f64>],
    reference_norm_ut: f64,
) -> Result<(), MagCalibrationError> {
    if samples.len() < MIN_SAMPLES {
        return Err(MagCalibrationError::TooFewSamples(samples.len()));
    }
    if !(reference_norm_ut > 0.0
        && reference_norm_ut.is_finite()
        && samples.iter().flatten().all(|v| v.is_finite()))
    {
        return Err(MagCalibrationError::NonFinite);
    }
    Ok(())
}

/// Mean of the samples and their mean distance from it.
pub(super) fn centre_and_scale(samples: &[Vector3<f64>]) -> (Vector3<f64>, f64) {
    let n = samples.len() as f64;
    let mu = samples.iter().sum::<Vector3<f64>>() / n;
    let s = samples.iter().map(|m| (m - mu).norm()).sum::<f64>() / n;
    (mu, s)
}

/// The closed-form least-squares ellipsoid fit (C2), scaled so that the
/// calibrated norm is `reference_norm_ut` (e.g. the field's known intensity,
/// or the mean raw norm when it is unknown).
pub fn fit_ellipsoid(
    samples: &[Vector3<f64>],
    reference_norm_ut: f64,
) -> Result<MagCalibration, MagCalibrationError> {
    check_inputs(samples, reference_norm_ut)?;
    let (mu, s) = centre_and_scale(samples);
    if !(s > 0.0) {
        return Err(MagCalibrationError::NotEllipsoid);
    }
    let mut dtd = SMatrix::<f64, 9, 9>::zeros();
    let mut dt1 = SVector::<f64, 9>::zeros();
    for m in samples {
        let u = (m - mu) / s;
        let row = SVector::<f64, 9>::from_column_slice(&[
            u.x * u.x,
            u.y * u.y,
            u.z * u.z,
            2.0 * u.x * u.y,
            2.0 * u.x * u.z,
            2.0 * u.y * u.z,
            2.0 * u.x,
            2.0 * u.y,
            2.0 * u.z,
        ]);
        dtd += row * row.transpose();
        dt1 += row;
    }
    let v = dtd
        .cholesky()
        .ok_or(MagCalibrationError::NotEllipsoid)?
        .solve(&dt1);
    let a = Matrix3::new(v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2]);
    let b = Vector3::new(v[6], v[7], v[8]);
    let a_inv = a.try_inverse().ok_or(MagCalibrationError::NotEllipsoid)?;
    let c = -(a_inv * b);
    let k = 1.0 + (c.transpose() * a * c)[0];
    let m_norm = a / (k * s * s);
    let w = symmetric_sqrt(&m_norm).ok_or(MagCalibrationError::NotEllipsoid)?;
    MagCalibration::new(mu + c * s, w * reference_norm_ut)
}

/// The symmetric square root of a symmetric positive definite matrix; `None`
/// if an eigenvalue is not positive or a number not finite.
fn symmetric_sqrt(m: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    if !m.iter().all(|v| v.is_finite()) {
        return None;
    }
    let eig = SymmetricEigen::new((m + m.transpose()) * 0.5);
    if !eig.eigenvalues.iter().all(|l| *l > 0.0) {
        return None;
    }
    let d = Matrix3::from_diagonal(&eig.eigenvalues.map(f64::sqrt));
    Some(eig.eigenvectors * d * eig.eigenvectors.transpose())
}
