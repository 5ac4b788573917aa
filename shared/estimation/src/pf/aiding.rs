//! The aiding attitude of paper 000 (eqs. 30-41): roll and pitch from the
//! accelerometer, yaw from the magnetometer compensated for roll and pitch,
//! each a half-angle quaternion about one axis, composed
//! `q_am = q_ψ ⊗ q_θ ⊗ q_φ` (eq. 30, = eq. 41 with eq. 37).
//!
//! Written for nauta's conventions: FRD body, NED navigation frame, the
//! accelerometer's specific force `f = C_n^b [0, 0, −g]` at rest (so
//! `f̂_x = sin θ`, `f̂_y = −sin φ cos θ`, `f̂_z = −cos φ cos θ` for the
//! normalised `f̂`), the yaw true (magnetic yaw plus the declination δ).
//!
//! - Pitch (eqs. 31-33): `cos θ = √(1 − f̂_x²)`, `cos(θ/2) = √((1 + cos θ)/2)`,
//!   `sin(θ/2) = sig(f̂_x) √((1 − cos θ)/2)`, written
//!   `sin(θ/2) = f̂_x / (2 cos(θ/2))` (the same value, no cancellation).
//! - Roll (eqs. 34-36) from the normalised y and z components,
//!   `sin φ = −f_y/ρ`, `cos φ = −f_z/ρ`, `ρ = √(f_y² + f_z²)`; the paper's
//!   `√(1 − ā_y²)` for `cos φ` holds only for |φ| ≤ 90°, so the sign of
//!   `cos φ` is taken from `f_z` here (an IMU may be upside down).
//! - Yaw (eqs. 37-39) from the field levelled by the roll and pitch just
//!   found (eq. 40, `m^E = C(q_θ ⊗ q_φ) m`): `cos ψ_m = m^E_x / |m^E_xy|`,
//!   `sin ψ_m = −m^E_y / |m^E_xy|`; the paper's case split on the sign of
//!   `m^E_x` (eq. 38) picks the half-angle formula without cancellation:
//!   for `cos ψ_m ≥ 0`, `cos(ψ_m/2) = √((1 + cos ψ_m)/2)` and
//!   `sin(ψ_m/2) = sin ψ_m / (2 cos(ψ_m/2))`; otherwise
//!   `sin(ψ_m/2) = sig(sin ψ_m) √((1 − cos ψ_m)/2)` and
//!   `cos(ψ_m/2) = sin ψ_m / (2 sin(ψ_m/2))`. The same split is used for roll.
//!   The declination enters as `q_ψ = q_z(δ) ⊗ q_z(ψ_m)`.
//!
//! The result is a rotation that levels `f` and points the field's
//! horizontal part at azimuth δ; at ±90° of pitch, where roll and yaw are not
//! separable, roll is set to 0 and the yaw absorbs it (the composed rotation
//! is still right).

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use thiserror::Error;

/// Why no aiding attitude could be formed from a sample pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum AidingError {
    /// A component is NaN or infinite.
    #[error("accelerometer or magnetometer sample is not finite")]
    NonFinite,
    /// The specific force is zero (no vertical).
    #[error("specific force is zero")]
    NoGravity,
    /// The levelled field has no horizontal part (no heading).
    #[error("magnetic field has no horizontal component")]
    NoHorizontalField,
}

/// `sig()` of the paper: +1 for zero and positive numbers, −1 otherwise.
fn sig(x: f64) -> f64 {
    if x < 0.0 { -1.0 } else { 1.0 }
}

/// Half-angle cosine and sine from the full angle's cosine and sine, with the
/// case split of paper 000 eq. 38 (no cancellation on either side).
fn half_angle(cos: f64, sin: f64) -> (f64, f64) {
    if cos >= 0.0 {
        let c = (0.5 * (1.0 + cos)).sqrt();
        (c, sin / (2.0 * c))
    } else {
        let s = sig(sin) * (0.5 * (1.0 - cos)).sqrt();
        (sin / (2.0 * s), s)
    }
}

/// Roll and pitch quaternions `q_φ`, `q_θ` (eqs. 31-36) from a specific force.
pub fn tilt_quaternions(
    accel_m_s2: &Vector3<f64>,
) -> Result<(UnitQuaternion<f64>, UnitQuaternion<f64>), AidingError> {
    if !accel_m_s2.iter().all(|v| v.is_finite()) {
        return Err(AidingError::NonFinite);
    }
    let norm = accel_m_s2.norm();
    if !(norm > 0.0 && norm.is_finite()) {
        return Err(AidingError::NoGravity);
    }
    let f = accel_m_s2 / norm;
    // Pitch, eqs. 31-33 (|θ| ≤ 90°, so cos θ ≥ 0 and cos(θ/2) ≥ 1/√2).
    let sin_pitch = f.x.clamp(-1.0, 1.0);
    let cos_pitch = f.y.hypot(f.z);
    let cp2 = (0.5 * (1.0 + cos_pitch)).sqrt();
    let q_theta =
        UnitQuaternion::new_normalize(Quaternion::new(cp2, 0.0, sin_pitch / (2.0 * cp2), 0.0));
    // Roll, eqs. 34-36, from the y-z plane; undefined at ±90° of pitch (0).
    let rho = f.y.hypot(f.z);
    let (cos_roll, sin_roll) = if rho > 1e-12 {
        (-f.z / rho, -f.y / rho)
    } else {
        (1.0, 0.0)
    };
    let (cr2, sr2) = half_angle(cos_roll, sin_roll);
    let q_phi = UnitQuaternion::new_normalize(Quaternion::new(cr2, sr2, 0.0, 0.0));
    Ok((q_phi, q_theta))
}

/// The aiding attitude `q_am = q_ψ ⊗ q_θ ⊗ q_φ` (paper 000 eqs. 30-41) from one
/// specific force (m/s², FRD) and one calibrated field (any unit, FRD), with
/// declination `declination_rad` (east positive).
pub fn aiding_quaternion(
    accel_m_s2: &Vector3<f64>,
    mag: &Vector3<f64>,
    declination_rad: f64,
) -> Result<UnitQuaternion<f64>, AidingError> {
    if !(mag.iter().all(|v| v.is_finite()) && declination_rad.is_finite()) {
        return Err(AidingError::NonFinite);
    }
    let (q_phi, q_theta) = tilt_quaternions(accel_m_s2)?;
    let q_tilt = q_theta * q_phi;
    // Eq. 40: the field in the level frame that shares the body's heading.
    let m_e = q_tilt * mag;
    let horizontal = m_e.x.hypot(m_e.y);
    if !(horizontal > 1e-9 * mag.norm()) {
        return Err(AidingError::NoHorizontalField);
    }
    // Eqs. 37-39 with the case split of eq. 38.
    let (c, s) = half_angle(m_e.x / horizontal, -m_e.y / horizontal);
    let q_psi_m = UnitQuaternion::new_normalize(Quaternion::new(c, 0.0, 0.0, s));
    let (sd, cd) = (0.5 * declination_rad).sin_cos();
    let q_decl = UnitQuaternion::new_unchecked(Quaternion::new(cd, 0.0, 0.0, sd));
    // Eq. 30 / eq. 41.
    Ok(q_decl * q_psi_m * q_tilt)
}
