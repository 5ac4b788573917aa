//! Discrete attitude kinematics: the exact strapdown attitude update from one gyro
//! sample, and the exactly consistent rule a simulator uses to make gyro samples
//! from a truth attitude sequence.
//!
//! # The convention (shared by the integrator and the sensor simulator)
//!
//! An IMU sample at `t_k` reports the average angular rate over `(t_{k-1}, t_k]`,
//! `ω_ib^b = θ_ib / Δt` (DESIGN §4, "increment / dt"), where `θ_ib` is the
//! **rotation vector** of the body's rotation relative to inertial space over the
//! interval, expressed in the body frame at `t_{k-1}` — what a coning-compensated
//! "strapdown integration" output (e.g. Xsens' Δq) delivers. Over the same
//! interval the navigation frame turns relative to inertial space at `ω_in^n`
//! (Earth rate, plus transport rate when the caller includes it), held constant,
//! i.e. by the rotation vector `θ_in = ω_in^n Δt`. Then exactly
//! (Groves 2013 §5.4-5.5; Titterton & Weston 2004 ch. 11):
//!
//! ```text
//! q_nb(k) = exp(-θ_in) ⊗ q_nb(k-1) ⊗ exp(θ_ib)                      (K1)
//! ```
//!
//! with `exp` the rotation-vector quaternion. [`propagate_attitude`] is (K1); it
//! is closed form, not paper 000 eq. 28's first-order
//! `q_k ∝ q_{k-1} + ½ T_s q_{k-1} ⊗ [0, ω]`, whose per-step angle error is
//! `|ωT_s|³/12` (8e-8 rad at 1 rad/s and 100 Hz).
//!
//! A simulator that moves the truth attitude with a piecewise-constant body rate
//! relative to NED, `q_nb(k) = q_nb(k-1) ⊗ exp(ω_nb^b Δt)`, produces the sample that
//! makes (K1) reproduce it, by solving (K1) for `θ_ib`:
//!
//! ```text
//! exp(θ_ib) = q_nb(k-1)⁻¹ ⊗ exp(θ_in) ⊗ q_nb(k) = exp(C_n^b(k-1) θ_in) ⊗ exp(ω_nb^b Δt)   (K2)
//! ```
//!
//! ([`inertial_body_rate`], with Earth rate only: [`body_rate_with_earth`]). To first
//! order this is the familiar `ω_ib^b = ω_nb^b + C_n^b ω_in^n`; the exact form
//! differs by `½ (C_n^b θ_in) × (ω_nb Δt) / Δt`, ~4e-10 rad/s for a 0.1 rad/s turn
//! at 100 Hz, but it is what makes a noise-free simulated gyro and the
//! integrator agree to rounding (test `recovers_scripted_truth_*` in
//! [`crate::gyro`]). [`nav_relative_body_rate`] / [`body_rate_without_earth`] are
//! the exact inverse (body-frame form of (K1)).

use nalgebra::{UnitQuaternion, Vector3};

use super::{quat_from_rotation_vector, rotation_vector};
use crate::earth::earth_rate_ned;

/// The exact attitude update (K1): `q_k = exp(-ω_in^n Δt) ⊗ q_{k-1} ⊗ exp(ω_ib^b Δt)`.
///
/// `omega_ib_b` is the (bias-corrected) gyro sample, the average rate over the
/// interval; `omega_in_n` the rotation rate of NED relative to inertial space,
/// expressed in NED (Earth rate [`earth_rate_ned`], plus transport rate if wanted).
/// The result is renormalised.
pub fn propagate_attitude(
    q_nb_prev: &UnitQuaternion<f64>,
    omega_ib_b: &Vector3<f64>,
    omega_in_n: &Vector3<f64>,
    dt_s: f64,
) -> UnitQuaternion<f64> {
    let nav = quat_from_rotation_vector(&(-omega_in_n * dt_s));
    let body = quat_from_rotation_vector(&(omega_ib_b * dt_s));
    UnitQuaternion::new_normalize((nav * q_nb_prev * body).into_inner())
}

/// The gyro sample (K2) that turns `q_nb_prev` into `q_nb_prev ⊗ exp(ω_nb^b Δt)`
/// under [`propagate_attitude`] with nav rate `omega_in_n`:
/// `ω_ib^b = log(exp(C_n^b ω_in^n Δt) ⊗ exp(ω_nb^b Δt)) / Δt`.
///
/// `dt_s` must be positive.
pub fn inertial_body_rate(
    q_nb_prev: &UnitQuaternion<f64>,
    omega_nb_b: &Vector3<f64>,
    omega_in_n: &Vector3<f64>,
    dt_s: f64,
) -> Vector3<f64> {
    let theta_in_b = q_nb_prev.inverse_transform_vector(&(omega_in_n * dt_s));
    let inc =
        quat_from_rotation_vector(&theta_in_b) * quat_from_rotation_vector(&(omega_nb_b * dt_s));
    rotation_vector(&inc) / dt_s
}

/// Exact inverse of [`inertial_body_rate`]: the body rate relative to NED,
/// `ω_nb^b = log(exp(-C_n^b ω_in^n Δt) ⊗ exp(ω_ib^b Δt)) / Δt`, such that
/// `q_nb_prev ⊗ exp(ω_nb^b Δt)` equals [`propagate_attitude`]`(q_nb_prev, ω_ib^b, ω_in^n, Δt)`.
///
/// `dt_s` must be positive.
pub fn nav_relative_body_rate(
    q_nb_prev: &UnitQuaternion<f64>,
    omega_ib_b: &Vector3<f64>,
    omega_in_n: &Vector3<f64>,
    dt_s: f64,
) -> Vector3<f64> {
    let theta_in_b = q_nb_prev.inverse_transform_vector(&(omega_in_n * dt_s));
    let inc =
        quat_from_rotation_vector(&(-theta_in_b)) * quat_from_rotation_vector(&(omega_ib_b * dt_s));
    rotation_vector(&inc) / dt_s
}

/// The sensor simulator's rule: the noise-free gyro sample `ω_ib^b` for a body
/// that turns at `omega_nb_b` relative to NED over an interval of `dt_s` starting
/// at attitude `q_nb_prev`, at geodetic latitude `lat_rad`, with the Earth rate as
/// the only nav-frame rotation (transport rate neglected, as in
/// [`crate::gyro::GyroIntegrator`]).
///
/// [`inertial_body_rate`] with `ω_in^n = ω_ie^n(lat)`, i.e. (K2); to first order
/// `ω_nb^b + C_n^b(q_nb_prev) ω_ie^n`. Feeding the result to
/// [`crate::gyro::GyroIntegrator`] (same latitude, zero bias) reproduces
/// `q_nb_prev ⊗ exp(omega_nb_b dt_s)` to rounding.
pub fn body_rate_with_earth(
    q_nb_prev: &UnitQuaternion<f64>,
    omega_nb_b: &Vector3<f64>,
    lat_rad: f64,
    dt_s: f64,
) -> Vector3<f64> {
    inertial_body_rate(q_nb_prev, omega_nb_b, &earth_rate_ned(lat_rad), dt_s)
}

/// Exact inverse of [`body_rate_with_earth`]: removes the Earth rate from a gyro
/// sample, `ω_nb^b = log(exp(-C_n^b ω_ie^n Δt) ⊗ exp(ω_ib^b Δt)) / Δt`.
pub fn body_rate_without_earth(
    q_nb_prev: &UnitQuaternion<f64>,
    omega_ib_b: &Vector3<f64>,
    lat_rad: f64,
    dt_s: f64,
) -> Vector3<f64> {
    nav_relative_body_rate(q_nb_prev, omega_ib_b, &earth_rate_ned(lat_rad), dt_s)
}

/// The constant body rate relative to NED that turns `q_nb_prev` into `q_nb_next`
/// in `dt_s`: `ω_nb^b = log(q_nb_prev⁻¹ ⊗ q_nb_next) / Δt` (the shorter way round).
///
/// With [`body_rate_with_earth`], this turns any truth attitude sequence into
/// exactly consistent gyro samples.
pub fn body_rate_between(
    q_nb_prev: &UnitQuaternion<f64>,
    q_nb_next: &UnitQuaternion<f64>,
    dt_s: f64,
) -> Vector3<f64> {
    rotation_vector(&(q_nb_prev.inverse() * q_nb_next)) / dt_s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::from_euler;

    fn q0() -> UnitQuaternion<f64> {
        from_euler(0.3, -0.2, 2.0)
    }

    #[test]
    fn without_nav_rate_it_is_the_body_increment() {
        let w = Vector3::new(0.1, -0.05, 0.2);
        let q = propagate_attitude(&q0(), &w, &Vector3::zeros(), 0.01);
        let want = q0() * quat_from_rotation_vector(&(w * 0.01));
        assert!(q.angle_to(&want) < 1e-15);
    }

    #[test]
    fn a_still_body_sees_the_earth_rate_and_stays_still() {
        let lat = 0.75;
        let g = body_rate_with_earth(&q0(), &Vector3::zeros(), lat, 0.01);
        // Exactly C_n^b ω_ie^n: a single rotation about a fixed axis.
        let want = q0().inverse_transform_vector(&earth_rate_ned(lat));
        assert!((g - want).norm() < 1e-18);
        let q = propagate_attitude(&q0(), &g, &earth_rate_ned(lat), 0.01);
        assert!(q.angle_to(&q0()) < 1e-15);
    }

    #[test]
    fn first_order_form_agrees_to_second_order() {
        let lat = -0.4;
        let dt = 0.01;
        let w = Vector3::new(0.05, 0.02, 0.1);
        let exact = body_rate_with_earth(&q0(), &w, lat, dt);
        let first = w + q0().inverse_transform_vector(&earth_rate_ned(lat));
        let diff = (exact - first).norm();
        // ½ |ω_ie| |ω_nb| Δt ≈ 4e-9 rad/s here.
        assert!(diff < 0.5 * 7.3e-5 * w.norm() * dt * 1.01, "{diff}");
    }

    #[test]
    fn with_and_without_earth_are_exact_inverses() {
        let lat = 1.1;
        for w in [
            Vector3::new(0.2, -0.1, 0.4),
            Vector3::zeros(),
            Vector3::new(-2.0, 1.0, 3.0),
        ] {
            let g = body_rate_with_earth(&q0(), &w, lat, 0.01);
            let back = body_rate_without_earth(&q0(), &g, lat, 0.01);
            assert!(
                (back - w).norm() < 1e-14 * w.norm().max(1.0),
                "{w:?} -> {back:?}"
            );
        }
    }

    #[test]
    fn body_form_and_nav_form_of_k1_agree() {
        let omega_in = earth_rate_ned(0.5) + Vector3::new(1e-7, -2e-7, 3e-8);
        let gyro = Vector3::new(0.3, 0.01, -0.2);
        let dt = 0.02;
        let nav_form = propagate_attitude(&q0(), &gyro, &omega_in, dt);
        let w_nb = nav_relative_body_rate(&q0(), &gyro, &omega_in, dt);
        let body_form = q0() * quat_from_rotation_vector(&(w_nb * dt));
        assert!(nav_form.angle_to(&body_form) < 1e-15);
        // And the generator inverts it.
        let g = inertial_body_rate(&q0(), &w_nb, &omega_in, dt);
        assert!((g - gyro).norm() < 1e-14);
    }

    #[test]
    fn body_rate_between_recovers_the_rate() {
        let w = Vector3::new(0.02, -0.3, 0.1);
        let q1 = q0() * quat_from_rotation_vector(&(w * 0.01));
        assert!((body_rate_between(&q0(), &q1, 0.01) - w).norm() < 1e-13);
    }
}
