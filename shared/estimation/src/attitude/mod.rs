//! Attitude conventions, Euler angles, rotation vectors, attitude kinematics and
//! attitude error metrics.
//!
//! # Conventions
//!
//! - Attitude is a [`nalgebra::UnitQuaternion<f64>`] `q_nb` (Hamilton, `w, x, y, z`)
//!   that rotates body (FRD: x forward, y starboard, z down) vectors into the
//!   navigation frame (NED): `v^n = q_nb ⊗ v^b ⊗ q_nb⁻¹`, written `q_nb * v_b` in
//!   nalgebra. Its rotation matrix is `C_b^n`; `C_n^b = (C_b^n)ᵀ` is `q_nb⁻¹`.
//! - Composition: `q_nc = q_nb ⊗ q_bc`. A rotation vector `θ` expressed in the
//!   right-hand frame is applied on the right (`q ⊗ exp(θ)`), one expressed in the
//!   navigation frame on the left (`exp(θ) ⊗ q`).
//! - Euler angles are the aerospace ZYX sequence (roll φ, pitch θ, yaw ψ):
//!   `C_b^n = R_z(ψ) R_y(θ) R_x(φ)` (Titterton & Weston 2004 ch. 3; Groves 2013
//!   §2.2), which is paper 000 eq. 30 `q_am = q_ψ ⊗ q_θ ⊗ q_φ`.
//! - `exp(θ)` here means the unit quaternion of the rotation vector `θ`,
//!   `[cos(|θ|/2), sin(|θ|/2) θ/|θ|]`, i.e. the quaternion exponential of `θ/2`
//!   (see [`quat_from_rotation_vector`]).

mod error;
mod euler;
pub mod kinematics;
mod rotation_vector;

pub use error::{AttitudeError, HeadingInclinationError};
pub use euler::{GIMBAL_LOCK_COS, from_euler, to_euler};
pub use rotation_vector::{quat_from_rotation_vector, rotation_vector};

use std::f64::consts::{PI, TAU};

/// Wraps an angle to [-π, π).
pub fn wrap_pi(angle_rad: f64) -> f64 {
    (angle_rad + PI).rem_euclid(TAU) - PI
}

/// The rotation angle of a unit quaternion, in [0, π] (the shorter way round).
///
/// `2 atan2(|v|, |w|)`, accurate for small angles, unlike `2 acos(|w|)`.
pub fn rotation_angle(q: &nalgebra::UnitQuaternion<f64>) -> f64 {
    2.0 * q.imag().norm().atan2(q.w.abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_pi_range() {
        for (a, want) in [
            (0.0, 0.0),
            (PI, -PI),
            (-PI, -PI),
            (3.0 * PI / 2.0, -PI / 2.0),
            (-3.0 * PI / 2.0, PI / 2.0),
            (7.0 * TAU + 0.25, 0.25),
        ] {
            assert!((wrap_pi(a) - want).abs() < 1e-12, "{a} -> {}", wrap_pi(a));
        }
    }

    #[test]
    fn rotation_angle_is_accurate_when_small() {
        let q = nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::x_axis(), 1e-9);
        assert!((rotation_angle(&q) - 1e-9).abs() < 1e-24);
        let q = nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), -3.0);
        assert!((rotation_angle(&q) - 3.0).abs() < 1e-14);
        // q and -q are the same rotation.
        let neg = nalgebra::UnitQuaternion::new_unchecked(-q.into_inner());
        assert!((rotation_angle(&neg) - 3.0).abs() < 1e-14);
    }
}
