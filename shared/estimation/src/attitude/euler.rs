//! Aerospace ZYX Euler angles (roll φ, pitch θ, yaw ψ) ↔ `q_nb`.

use nalgebra::{Quaternion, UnitQuaternion};

/// `q_nb` from roll, pitch and yaw (rad), ZYX sequence:
/// `q_nb = q_z(ψ) ⊗ q_y(θ) ⊗ q_x(φ)`, i.e. `C_b^n = R_z(ψ) R_y(θ) R_x(φ)`.
///
/// Paper 000 eq. 30 with eqs. 31, 34 and 37 (`q_ψ ⊗ q_θ ⊗ q_φ`, each a half-angle
/// quaternion about one axis); Titterton & Weston (2004) ch. 3.
pub fn from_euler(roll_rad: f64, pitch_rad: f64, yaw_rad: f64) -> UnitQuaternion<f64> {
    let (sr, cr) = (0.5 * roll_rad).sin_cos();
    let (sp, cp) = (0.5 * pitch_rad).sin_cos();
    let (sy, cy) = (0.5 * yaw_rad).sin_cos();
    UnitQuaternion::new_normalize(Quaternion::new(
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ))
}

/// Roll, pitch and yaw (rad) of `q_nb`, ZYX sequence: roll and yaw in [-π, π],
/// pitch in [-π/2, π/2].
///
/// From the elements of `C_b^n` (Titterton & Weston 2004 ch. 3; Groves 2013
/// §2.2): `φ = atan2(C₃₂, C₃₃)`, `θ = atan2(-C₃₁, √(C₃₂² + C₃₃²))`,
/// `ψ = atan2(C₂₁, C₁₁)`. Pitch uses `atan2` rather than `asin(-C₃₁)` so that it
/// stays accurate near ±π/2.
///
/// At gimbal lock (`cos θ` below [`GIMBAL_LOCK_COS`]) only `ψ - φ` (pitch +90°) or
/// `ψ + φ` (pitch -90°) is defined; roll is then set to 0 and yaw to
/// `atan2(-C₁₂, C₂₂)`, which is that combination.
pub fn to_euler(q: &UnitQuaternion<f64>) -> (f64, f64, f64) {
    let (w, x, y, z) = (q.w, q.i, q.j, q.k);
    let c31 = 2.0 * (x * z - w * y);
    let c32 = 2.0 * (y * z + w * x);
    let c33 = 1.0 - 2.0 * (x * x + y * y);
    let cos_pitch = c32.hypot(c33);
    let pitch = (-c31).atan2(cos_pitch);
    if cos_pitch < GIMBAL_LOCK_COS {
        let c12 = 2.0 * (x * y - w * z);
        let c22 = 1.0 - 2.0 * (x * x + z * z);
        return (0.0, pitch, (-c12).atan2(c22));
    }
    let c11 = 1.0 - 2.0 * (y * y + z * z);
    let c21 = 2.0 * (x * y + w * z);
    (c32.atan2(c33), pitch, c21.atan2(c11))
}

/// Below this `cos(pitch)` (|pitch| within ~1e-12 rad of 90°), [`to_euler`] treats
/// the attitude as gimbal-locked.
pub const GIMBAL_LOCK_COS: f64 = 1e-12;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::wrap_pi;
    use nalgebra::{Matrix3, Vector3};
    use proptest::prelude::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    /// The golden rotation: roll 30°, pitch 20°, yaw 120°, written out by hand
    /// as R_z(ψ) R_y(θ) R_x(φ).
    #[test]
    fn golden_rotation_matrix() {
        let (r, p, y) = (30f64.to_radians(), 20f64.to_radians(), 120f64.to_radians());
        let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, r.cos(), -r.sin(), 0.0, r.sin(), r.cos());
        let ry = Matrix3::new(p.cos(), 0.0, p.sin(), 0.0, 1.0, 0.0, -p.sin(), 0.0, p.cos());
        let rz = Matrix3::new(y.cos(), -y.sin(), 0.0, y.sin(), y.cos(), 0.0, 0.0, 0.0, 1.0);
        let c_bn = rz * ry * rx;
        let q = from_euler(r, p, y);
        assert!((q.to_rotation_matrix().into_inner() - c_bn).abs().max() < 1e-15);
        // Same convention as nalgebra's `from_euler_angles(roll, pitch, yaw)`.
        assert!(q.angle_to(&UnitQuaternion::from_euler_angles(r, p, y)) < 1e-15);
        // A forward-pointing body axis, pitched up 20° and yawed to 120°.
        let fwd = q * Vector3::x();
        let want = Vector3::new(y.cos() * p.cos(), y.sin() * p.cos(), -p.sin());
        assert!((fwd - want).norm() < 1e-15);
    }

    #[test]
    fn golden_quaternion_values() {
        // 90° yaw: the body x axis points east.
        let q = from_euler(0.0, 0.0, FRAC_PI_2);
        let h = 0.5f64.sqrt();
        assert!((q.coords - nalgebra::Vector4::new(0.0, 0.0, h, h)).norm() < 1e-15);
        assert!((q * Vector3::x() - Vector3::y()).norm() < 1e-15);
        // Pitch up 90°: the body x axis points up (-down).
        let q = from_euler(0.0, FRAC_PI_2, 0.0);
        assert!((q * Vector3::x() - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-15);
        // Roll 90° right: the body y (starboard) axis points down.
        let q = from_euler(FRAC_PI_2, 0.0, 0.0);
        assert!((q * Vector3::y() - Vector3::z()).norm() < 1e-15);
    }

    #[test]
    fn to_euler_golden_and_gimbal_lock_is_finite() {
        let (r, p, y) = to_euler(&from_euler(0.1, -0.2, 3.0));
        assert!((r - 0.1).abs() < 1e-15 && (p + 0.2).abs() < 1e-15 && (y - 3.0).abs() < 1e-15);
        // At gimbal lock only yaw - roll (pitch +90°) or yaw + roll (pitch -90°) is
        // defined: roll is reported as 0 and yaw carries the combination.
        let (r, p, y) = to_euler(&from_euler(0.3, FRAC_PI_2, 0.5));
        assert!((p - FRAC_PI_2).abs() < 1e-7);
        assert_eq!(r.to_bits(), 0.0f64.to_bits());
        assert!((y - 0.2).abs() < 1e-12, "{y}");
        let (r, p, y) = to_euler(&from_euler(0.3, -FRAC_PI_2, 0.5));
        assert!((p + FRAC_PI_2).abs() < 1e-7);
        assert_eq!(r.to_bits(), 0.0f64.to_bits());
        assert!((y - 0.8).abs() < 1e-12, "{y}");
        // The reported angles describe the same rotation.
        let q = from_euler(-2.0, FRAC_PI_2, 1.0);
        let (r, p, y) = to_euler(&q);
        assert!(from_euler(r, p, y).angle_to(&q) < 1e-7);
    }

    proptest! {
        #[test]
        fn euler_round_trip(
            r in -PI..PI,
            p in (-FRAC_PI_2 + 1e-3)..(FRAC_PI_2 - 1e-3),
            y in -PI..PI,
        ) {
            let (r2, p2, y2) = to_euler(&from_euler(r, p, y));
            prop_assert!(wrap_pi(r2 - r).abs() < 1e-12, "roll {} vs {}", r2, r);
            prop_assert!((p2 - p).abs() < 1e-12, "pitch {} vs {}", p2, p);
            prop_assert!(wrap_pi(y2 - y).abs() < 1e-12, "yaw {} vs {}", y2, y);
        }

        #[test]
        fn quaternion_round_trip(w in -1.0f64..1.0, x in -1.0f64..1.0, y in -1.0f64..1.0, z in -1.0f64..1.0) {
            let q4 = Quaternion::new(w, x, y, z);
            prop_assume!(q4.norm() > 0.1);
            let q = UnitQuaternion::new_normalize(q4);
            let (r, p, yaw) = to_euler(&q);
            prop_assume!(p.abs() < FRAC_PI_2 - 1e-3);
            prop_assert!(from_euler(r, p, yaw).angle_to(&q) < 1e-12);
        }

        /// Independent implementation: nalgebra's own Euler conversion.
        #[test]
        fn agrees_with_nalgebra(
            r in -PI..PI,
            p in (-FRAC_PI_2 + 1e-3)..(FRAC_PI_2 - 1e-3),
            y in -PI..PI,
        ) {
            let ours = from_euler(r, p, y);
            let theirs = UnitQuaternion::from_euler_angles(r, p, y);
            prop_assert!(ours.angle_to(&theirs) < 1e-14);
            let (r2, p2, y2) = theirs.euler_angles();
            let (r3, p3, y3) = to_euler(&theirs);
            prop_assert!(wrap_pi(r2 - r3).abs() < 1e-9);
            prop_assert!((p2 - p3).abs() < 1e-9);
            prop_assert!(wrap_pi(y2 - y3).abs() < 1e-9);
        }
    }
}
