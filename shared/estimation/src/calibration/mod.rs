//! Sensor calibration before (or beside) attitude estimation, as paper 000
//! §IV-A does it:
//!
//! - [`StillCalibration`]: gyro and accelerometer offsets as the means of a
//!   still period ("calculated as the average of 400 measurements" with the
//!   IMU static and levelled), less what a still sensor should read there.
//! - [`MagCalibration`]: the magnetometer's hard iron `h` and soft iron `S`
//!   (`m̃ = S m + h + w`, the model of `shared/sim`'s `MagnetometerSpec`),
//!   undone as `m = W (m̃ − h)` with `W ≈ S⁻¹`. Fitted from samples taken
//!   while the sensor turns through many attitudes, either by particle swarm
//!   optimisation ([`fit_pso`], as the paper does: the calibrated locus is a
//!   centred sphere) or by the closed-form least-squares ellipsoid fit beside
//!   it ([`fit_ellipsoid`]). The figure of merit is the spread of the
//!   calibrated field's norm ([`NormSpread`]): a perfect calibration leaves
//!   only the sensor noise.
//!
//! Which fit is the default ([`MagFitMethod::default`]) was decided by that
//! figure on the tests' distorted field (`tests.rs`,
//! `least_squares_and_pso_cut_the_norm_spread_tenfold`).

mod magnetometer;
mod pso;
mod still;
#[cfg(test)]
mod tests;

pub use magnetometer::{
    MagCalibration, MagCalibrationError, MagFitMethod, NormSpread, fit_ellipsoid,
};
pub use pso::{PsoParams, fit_pso};
pub use still::{StaticOffsets, StillCalibration, StillCalibrationError};

use nalgebra::Vector3;

// Here rather than in `magnetometer.rs`, which `pso.rs` builds on: the two
// fits import one way only.
/// Fits with `method` ([`fit_ellipsoid`], or [`fit_pso`] with `pso` and `seed`).
pub fn fit(
    samples: &[Vector3<f64>],
    reference_norm_ut: f64,
    method: MagFitMethod,
    pso: &PsoParams,
    seed: u64,
) -> Result<MagCalibration, MagCalibrationError> {
    match method {
        MagFitMethod::LeastSquares => fit_ellipsoid(samples, reference_norm_ut),
        MagFitMethod::Pso => fit_pso(samples, reference_norm_ut, pso, seed),
    }
}
