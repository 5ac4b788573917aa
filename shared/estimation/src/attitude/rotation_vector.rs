//! Rotation vector ↔ unit quaternion, accurate at small angles.
//!
//! The exact attitude update and its inverse ([`super::kinematics`]) go through
//! these functions once per IMU sample, with rotations of 1e-6 to 1e-2 rad. An
//! `acos`-based angle loses ~1e-13 rad per call at that size, which adds up to
//! 1e-8 over an hour at 100 Hz; the forms here stay at the rounding level.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

/// Unit quaternion of the rotation vector `θ` (angle `|θ|` about `θ/|θ|`):
/// `exp(θ) = [cos(|θ|/2), sin(|θ|/2) θ/|θ|]`.
///
/// Titterton & Weston (2004) ch. 3; Groves (2013) §2.2 and §5.5 (the exact form that
/// paper 000 eq. 28 approximates to first order).
pub fn quat_from_rotation_vector(theta: &Vector3<f64>) -> UnitQuaternion<f64> {
    let angle = theta.norm();
    let half = 0.5 * angle;
    // sin(|θ|/2)/|θ| = ½ sinc(|θ|/2); the series is exact to rounding below 1e-4.
    let k = if half < 1e-4 {
        0.5 * (1.0 - half * half / 6.0)
    } else {
        half.sin() / angle
    };
    // cos² + sin² = 1 to rounding, so the result is unit by construction; normalise
    // anyway so that the invariant holds to the last bit.
    UnitQuaternion::new_normalize(Quaternion::new(
        half.cos(),
        k * theta.x,
        k * theta.y,
        k * theta.z,
    ))
}

/// Rotation vector of a unit quaternion (inverse of [`quat_from_rotation_vector`]),
/// taking the shorter way round: the angle is in [0, π].
///
/// `θ = 2 atan2(|v|, w) v / |v|` with `w ≥ 0` (flip `q` to `-q` otherwise).
pub fn rotation_vector(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let (w, v) = if q.w < 0.0 {
        (-q.w, -q.imag())
    } else {
        (q.w, q.imag())
    };
    let s = v.norm();
    if s == 0.0 {
        return Vector3::zeros();
    }
    v * (2.0 * s.atan2(w) / s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn matches_nalgebra_axis_angle() {
        let axis = Vector3::new(0.3, -0.5, 0.8).normalize();
        for angle in [1e-12, 1e-6, 1e-3, 0.5, 2.0, 3.1] {
            let q = quat_from_rotation_vector(&(axis * angle));
            let r = UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle);
            assert!(q.angle_to(&r) < 1e-14, "angle {angle}");
            let back = rotation_vector(&q);
            assert!(
                (back - axis * angle).norm() <= 1e-15 * angle.max(1.0),
                "angle {angle}"
            );
        }
        assert_eq!(
            rotation_vector(&UnitQuaternion::identity()),
            Vector3::zeros()
        );
    }

    #[test]
    fn small_angles_are_exact_to_rounding() {
        let theta = Vector3::new(1e-3, -2e-3, 0.5e-3);
        let back = rotation_vector(&quat_from_rotation_vector(&theta));
        assert!((back - theta).norm() < 1e-19);
    }

    proptest! {
        #[test]
        fn round_trip(x in -1.8f64..1.8, y in -1.8f64..1.8, z in -1.8f64..1.8) {
            let theta = Vector3::new(x, y, z);
            prop_assume!(theta.norm() < 3.1);
            let back = rotation_vector(&quat_from_rotation_vector(&theta));
            prop_assert!((back - theta).norm() < 1e-14);
        }
    }
}
