//! Attitude error metrics: estimate against truth (or, as in paper 000 Table I,
//! against the aiding attitude).

use nalgebra::UnitQuaternion;

use super::{rotation_angle, to_euler, wrap_pi};

/// Attitude error of an estimate against a reference, per Euler angle and in total.
///
/// - `roll_rad`, `pitch_rad`, `yaw_rad`: differences of the ZYX Euler angles,
///   estimate minus truth, wrapped to [-π, π). Meaningful away from gimbal lock
///   (|pitch| well below 90°), which is where an AUV lives.
/// - `total_rad`: the angle of the rotation `q_truth⁻¹ ⊗ q_est` (the error rotation
///   in the body frame; its angle equals that of the nav-frame error
///   `q_est ⊗ q_truth⁻¹`), in [0, π], independent of any Euler convention.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AttitudeError {
    /// Roll error, rad, in [-π, π).
    pub roll_rad: f64,
    /// Pitch error, rad.
    pub pitch_rad: f64,
    /// Yaw error, rad, in [-π, π).
    pub yaw_rad: f64,
    /// Total rotation angle between estimate and truth, rad, in [0, π].
    pub total_rad: f64,
}

impl AttitudeError {
    /// The error of `estimate` against `truth` (both `q_nb`).
    pub fn between(estimate: &UnitQuaternion<f64>, truth: &UnitQuaternion<f64>) -> Self {
        let (re, pe, ye) = to_euler(estimate);
        let (rt, pt, yt) = to_euler(truth);
        Self {
            roll_rad: wrap_pi(re - rt),
            pitch_rad: wrap_pi(pe - pt),
            yaw_rad: wrap_pi(ye - yt),
            total_rad: rotation_angle(&(truth.inverse() * estimate)),
        }
    }
}

/// Heading and inclination error in the style of the BROAD benchmark (Laidig et
/// al., "BROAD - A Benchmark for Robust Inertial Orientation Estimation", Data
/// 6(7):72, 2021; its `broad_utils.py`).
///
/// The error quaternion is expressed in the navigation (Earth) frame,
/// `q_err = q_est ⊗ q_truth⁻¹ = [w, x, y, z]` (taken with `w ≥ 0`), and split by a
/// swing-twist decomposition about the vertical axis (z, down in NED; BROAD's ENU
/// z is the same line):
///
/// `q_err = q_incl ⊗ q_head`, `q_head = [w, 0, 0, z] / √(w² + z²)`,
///
/// - heading error `= 2 atan2(z, w)`: the angle of the component about the
///   vertical, signed, positive when the estimate is rotated clockwise seen from
///   above (a positive yaw error); BROAD reports its absolute value;
/// - inclination error `= 2 atan2(√(x² + y²), √(w² + z²))` (BROAD:
///   `2 acos(√(w² + z²))`, same value, better conditioned when small): the angle of
///   the remaining rotation `q_incl`, whose axis is horizontal.
///
/// The parts combine as `cos(total/2) = cos(heading/2) cos(inclination/2)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadingInclinationError {
    /// Heading error about the vertical, rad, in (-π, π].
    pub heading_rad: f64,
    /// Inclination (tilt) error, rad, in [0, π].
    pub inclination_rad: f64,
}

impl HeadingInclinationError {
    /// The error of `estimate` against `truth` (both `q_nb`).
    pub fn between(estimate: &UnitQuaternion<f64>, truth: &UnitQuaternion<f64>) -> Self {
        let q = estimate * truth.inverse();
        let s = if q.w < 0.0 { -1.0 } else { 1.0 };
        let (w, x, y, z) = (s * q.w, s * q.i, s * q.j, s * q.k);
        Self {
            heading_rad: 2.0 * z.atan2(w),
            inclination_rad: 2.0 * x.hypot(y).atan2(w.hypot(z)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::{from_euler, quat_from_rotation_vector};
    use nalgebra::Vector3;
    use proptest::prelude::*;

    const D: f64 = 0.01;

    fn truth() -> UnitQuaternion<f64> {
        from_euler(0.2, -0.3, 2.5)
    }

    #[test]
    fn roll_about_body_x() {
        // R_z R_y R_x(φ) ⊗ R_x(δ) = R_z R_y R_x(φ + δ): a pure roll error.
        let est = truth() * quat_from_rotation_vector(&Vector3::new(D, 0.0, 0.0));
        let e = AttitudeError::between(&est, &truth());
        assert!((e.roll_rad - D).abs() < 1e-14, "{e:?}");
        assert!(
            e.pitch_rad.abs() < 1e-14 && e.yaw_rad.abs() < 1e-14,
            "{e:?}"
        );
        assert!((e.total_rad - D).abs() < 1e-14, "{e:?}");
    }

    #[test]
    fn pitch_about_the_intermediate_y_axis() {
        // R_z R_y(θ) R_y(δ) R_x(φ): pitch error only; body-frame axis R_x(-φ) ŷ.
        let (r, p, y) = to_euler(&truth());
        let est = from_euler(r, p - D, y);
        let e = AttitudeError::between(&est, &truth());
        assert!((e.pitch_rad + D).abs() < 1e-14, "{e:?}");
        assert!(e.roll_rad.abs() < 1e-14 && e.yaw_rad.abs() < 1e-14, "{e:?}");
        assert!((e.total_rad - D).abs() < 1e-14, "{e:?}");
    }

    #[test]
    fn yaw_about_nav_down() {
        let est = quat_from_rotation_vector(&Vector3::new(0.0, 0.0, D)) * truth();
        let e = AttitudeError::between(&est, &truth());
        assert!((e.yaw_rad - D).abs() < 1e-14, "{e:?}");
        assert!(
            e.roll_rad.abs() < 1e-14 && e.pitch_rad.abs() < 1e-14,
            "{e:?}"
        );
        assert!((e.total_rad - D).abs() < 1e-14, "{e:?}");
        let hi = HeadingInclinationError::between(&est, &truth());
        assert!((hi.heading_rad - D).abs() < 1e-14, "{hi:?}");
        assert!(hi.inclination_rad.abs() < 1e-14, "{hi:?}");
    }

    #[test]
    fn yaw_wraps_across_pi() {
        let t = from_euler(0.0, 0.0, 3.1);
        let est = from_euler(0.0, 0.0, -3.1);
        let e = AttitudeError::between(&est, &t);
        let want = std::f64::consts::TAU - 6.2;
        assert!((e.yaw_rad - want).abs() < 1e-12, "{e:?}");
        assert!((e.total_rad - want).abs() < 1e-12, "{e:?}");
    }

    #[test]
    fn tilt_about_horizontal_nav_axes_is_inclination() {
        for axis in [
            Vector3::x(),
            Vector3::y(),
            Vector3::new(1.0, -1.0, 0.0).normalize(),
        ] {
            let est = quat_from_rotation_vector(&(axis * -D)) * truth();
            let hi = HeadingInclinationError::between(&est, &truth());
            assert!((hi.inclination_rad - D).abs() < 1e-14, "{hi:?}");
            assert!(hi.heading_rad.abs() < 1e-14, "{hi:?}");
        }
        // Level vehicle: a roll error is a pure inclination error.
        let level = from_euler(0.0, 0.0, 1.0);
        let est = from_euler(D, 0.0, 1.0);
        let hi = HeadingInclinationError::between(&est, &level);
        assert!((hi.inclination_rad - D).abs() < 1e-14 && hi.heading_rad.abs() < 1e-14);
    }

    #[test]
    fn identical_attitudes_have_zero_error() {
        let e = AttitudeError::between(&truth(), &truth());
        assert!(e.roll_rad.abs() < 1e-15 && e.pitch_rad.abs() < 1e-15);
        assert!(e.yaw_rad.abs() < 1e-15 && e.total_rad.abs() < 1e-15);
        let hi = HeadingInclinationError::between(&truth(), &truth());
        assert!(hi.heading_rad.abs() < 1e-15 && hi.inclination_rad.abs() < 1e-15);
    }

    proptest! {
        /// The two parts recompose the total angle, and q and -q give the same split.
        #[test]
        fn heading_and_inclination_recompose_total(
            a in -1.0f64..1.0, b in -1.0f64..1.0, c in -1.0f64..1.0,
            r in -3.0f64..3.0, p in -1.4f64..1.4, y in -3.0f64..3.0,
        ) {
            let t = from_euler(r, p, y);
            let est = quat_from_rotation_vector(&Vector3::new(a, b, c)) * t;
            let hi = HeadingInclinationError::between(&est, &t);
            let total = AttitudeError::between(&est, &t).total_rad;
            let lhs = (0.5 * total).cos();
            let rhs = (0.5 * hi.heading_rad).cos() * (0.5 * hi.inclination_rad).cos();
            prop_assert!((lhs - rhs).abs() < 1e-12);
            prop_assert!(hi.inclination_rad >= 0.0 && hi.inclination_rad <= std::f64::consts::PI);
            let neg = UnitQuaternion::new_unchecked(-est.into_inner());
            let hi2 = HeadingInclinationError::between(&neg, &t);
            prop_assert!((hi.heading_rad - hi2.heading_rad).abs() < 1e-15);
            prop_assert!((hi.inclination_rad - hi2.inclination_rad).abs() < 1e-15);
        }
    }
}
