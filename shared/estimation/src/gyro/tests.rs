//! Tests of the gyro integrator, including the sensor-consistency contract: gyro
//! samples made from a truth attitude sequence with
//! [`body_rate_with_earth`] are integrated back to that truth.

use crate::frames::Vector;
use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};

use super::*;
use crate::attitude::kinematics::{body_rate_between, body_rate_with_earth};
use crate::attitude::{AttitudeError, from_euler, quat_from_rotation_vector};

const RATE_HZ: u64 = 100;
const DT_NS: u64 = 1_000_000_000 / RATE_HZ;
const TEN_MINUTES_STEPS: u64 = 600 * RATE_HZ;
const LAT: f64 = 0.7592; // 43.5° N

fn dt_s() -> f64 {
    DT_NS as f64 / 1e9
}

/// Scripted body rate relative to NED (FRD, rad/s) at time `t`: lawnmower turns
/// (180° in 10 s every minute, alternating), a slow pitch oscillation between
/// legs and a roll oscillation with a 6 s period all the time.
fn scripted_omega_nb(t: f64) -> Vector3<f64> {
    let phase = t % 120.0;
    let r = if (50.0..60.0).contains(&phase) {
        PI / 10.0
    } else if (110.0..120.0).contains(&phase) {
        -PI / 10.0
    } else {
        0.0
    };
    let q = 0.05 * (2.0 * PI * t / 40.0).sin();
    let p = 0.3 * (2.0 * PI / 6.0) * (2.0 * PI * t / 6.0).cos();
    Vector3::new(p, q, r)
}

/// Scripted Euler angles (roll, pitch, yaw), rad, at time `t`.
fn scripted_euler(t: f64) -> (f64, f64, f64) {
    let roll = 0.15 * (2.0 * PI * t / 7.0).sin();
    let pitch = 0.2 * (2.0 * PI * t / 90.0).sin() - 0.05;
    // Constant-rate turns of 90° every 45 s (a 20 s turn, then a 25 s leg).
    let leg = (t / 45.0).floor();
    let in_leg = t - 45.0 * leg;
    let yaw = 0.4 + leg * PI / 2.0 + (in_leg.min(20.0) / 20.0) * PI / 2.0;
    (roll, pitch, yaw)
}

struct Outcome {
    final_error_rad: f64,
    max_error_rad: f64,
    /// Largest angle between the truth and its starting attitude.
    max_excursion_rad: f64,
}

/// Truth from piecewise-constant body rates, gyro via the simulator rule, fed to
/// an integrator at `integrator_lat`.
fn run_body_rate_script(steps: u64, sensor_lat: f64, integrator_lat: f64) -> Outcome {
    let q0 = from_euler(0.05, -0.1, 0.7);
    let dt = dt_s();
    let mut truth = q0;
    let mut est = GyroIntegrator::new(q0, integrator_lat, 0).expect("valid");
    let mut max_error_rad: f64 = 0.0;
    let mut max_excursion_rad: f64 = 0.0;
    for k in 1..=steps {
        let t_mid = (k as f64 - 0.5) * dt;
        let omega_nb = scripted_omega_nb(t_mid);
        let gyro = body_rate_with_earth(&truth, &omega_nb, sensor_lat, dt);
        truth *= quat_from_rotation_vector(&(omega_nb * dt));
        est.integrate(k * DT_NS, &gyro).expect("valid sample");
        max_error_rad = max_error_rad.max(AttitudeError::between(&est.q_nb(), &truth).total_rad);
        max_excursion_rad = max_excursion_rad.max(AttitudeError::between(&truth, &q0).total_rad);
    }
    Outcome {
        final_error_rad: AttitudeError::between(&est.q_nb(), &truth).total_rad,
        max_error_rad,
        max_excursion_rad,
    }
}

/// Section 5 of the brief: 10 minutes at 100 Hz of turns, pitch changes and roll
/// oscillation; the integrator must reproduce the truth to rounding.
#[test]
fn recovers_scripted_truth_from_body_rates_over_ten_minutes() {
    let out = run_body_rate_script(TEN_MINUTES_STEPS, LAT, LAT);
    eprintln!(
        "body-rate script: final {:e} rad, max {:e} rad",
        out.final_error_rad, out.max_error_rad
    );
    // Rounding only: 60 000 steps of a few ulp each (observed ~1e-13).
    assert!(out.final_error_rad < 1e-8, "final {}", out.final_error_rad);
    assert!(out.max_error_rad < 1e-8, "max {}", out.max_error_rad);
    // The trajectory does turn (180° turns): it is not a trivial test.
    assert!(
        out.max_excursion_rad > 3.0,
        "excursion {}",
        out.max_excursion_rad
    );
}

/// Same contract starting from a truth attitude sequence (Euler schedule) rather
/// than from body rates: `body_rate_between` then `body_rate_with_earth`.
#[test]
fn recovers_scripted_truth_from_attitude_sequence_over_ten_minutes() {
    let dt = dt_s();
    let at = |k: u64| {
        let (r, p, y) = scripted_euler(k as f64 * dt);
        from_euler(r, p, y)
    };
    let mut est = GyroIntegrator::new(at(0), LAT, 0).expect("valid");
    let mut max_error: f64 = 0.0;
    let mut prev = at(0);
    for k in 1..=TEN_MINUTES_STEPS {
        let next = at(k);
        let omega_nb = body_rate_between(&prev, &next, dt);
        let gyro = body_rate_with_earth(&prev, &omega_nb, LAT, dt);
        est.integrate(k * DT_NS, &gyro).expect("valid sample");
        max_error = max_error.max(AttitudeError::between(&est.q_nb(), &next).total_rad);
        prev = next;
    }
    let final_error = AttitudeError::between(&est.q_nb(), &prev).total_rad;
    eprintln!("attitude-sequence script: final {final_error:e} rad, max {max_error:e} rad");
    assert!(final_error < 1e-8, "final {final_error}");
    assert!(max_error < 1e-8, "max {max_error}");
}

/// The test above would notice a missing or wrong Earth-rate term: integrating at
/// the wrong latitude (here, the equator for a sensor at 43.5° N) drifts by
/// roughly ω_ie |sin L| t ≈ 3e-2 rad in 10 minutes.
#[test]
fn wrong_latitude_drifts_visibly() {
    let out = run_body_rate_script(TEN_MINUTES_STEPS, LAT, 0.0);
    eprintln!("wrong latitude: final {:e} rad", out.final_error_rad);
    assert!(out.final_error_rad > 1e-3, "final {}", out.final_error_rad);
}

#[test]
fn still_vehicle_holds_its_attitude_against_earth_rate() {
    let q0 = from_euler(0.02, 0.01, -1.2);
    let dt = dt_s();
    let gyro = body_rate_with_earth(&q0, &Vector3::zeros(), LAT, dt);
    // A still gyro reads the Earth rate, 7.29e-5 rad/s.
    assert!((gyro.norm() - 7.292_115e-5).abs() < 1e-18);
    let mut est = GyroIntegrator::new(q0, LAT, 0).expect("valid");
    for k in 1..=6000 {
        est.integrate(k * DT_NS, &gyro).expect("valid");
    }
    assert!(AttitudeError::between(&est.q_nb(), &q0).total_rad < 1e-12);
}

#[test]
fn fixed_bias_is_removed_and_uncompensated_bias_drifts() {
    let q0 = from_euler(0.0, 0.0, 0.5);
    let bias = Vector3::new(1e-3, -2e-3, 5e-4);
    let dt = dt_s();
    let steps = 6000; // 60 s
    let mut truth = q0;
    let mut with = GyroIntegrator::new(q0, LAT, 0)
        .expect("valid")
        .with_gyro_bias(bias)
        .expect("finite");
    let mut without = GyroIntegrator::new(q0, LAT, 0).expect("valid");
    for k in 1..=steps {
        let omega_nb = scripted_omega_nb((k as f64 - 0.5) * dt);
        let gyro = body_rate_with_earth(&truth, &omega_nb, LAT, dt) + bias;
        truth *= quat_from_rotation_vector(&(omega_nb * dt));
        with.integrate(k * DT_NS, &gyro).expect("valid");
        without.integrate(k * DT_NS, &gyro).expect("valid");
    }
    assert!(AttitudeError::between(&with.q_nb(), &truth).total_rad < 1e-10);
    // Uncompensated: up to |b| t ≈ 0.14 rad, reduced by the rotation of the body.
    assert!(AttitudeError::between(&without.q_nb(), &truth).total_rad > 1e-2);
}

#[test]
fn closed_form_is_exact_for_a_large_constant_rate() {
    // 1 rad/s about a fixed axis for 1 s at 100 Hz, at the equator; the samples
    // include the Earth rate through the simulator rule.
    let axis = Vector3::new(1.0, 2.0, -2.0) / 3.0;
    let omega = axis * 1.0;
    let q0 = UnitQuaternion::identity();
    let mut truth = q0;
    let mut est = GyroIntegrator::new(q0, 0.0, 0).expect("valid");
    for k in 1..=100 {
        let gyro = body_rate_with_earth(&truth, &omega, 0.0, dt_s());
        truth *= quat_from_rotation_vector(&(omega * dt_s()));
        est.integrate(k * DT_NS, &gyro).expect("valid");
    }
    let want = quat_from_rotation_vector(&omega);
    assert!(truth.angle_to(&want) < 1e-13);
    assert!(est.q_nb().angle_to(&want) < 1e-13);
}

#[test]
fn refuses_bad_samples_and_keeps_state() {
    let mut est = GyroIntegrator::new(UnitQuaternion::identity(), LAT, 1_000).expect("valid");
    let before = est.clone();
    assert_eq!(
        est.integrate(1_000, &Vector3::zeros()),
        Err(GyroIntegrateError::StampNotIncreasing {
            last_ns: 1_000,
            stamp_ns: 1_000
        })
    );
    assert_eq!(
        est.integrate(2_000, &Vector3::new(f64::NAN, 0.0, 0.0)),
        Err(GyroIntegrateError::NonFinite)
    );
    assert_eq!(
        est.propagate(&Vector3::zeros(), 0.0),
        Err(GyroIntegrateError::BadInterval(0.0))
    );
    assert!(matches!(
        est.propagate(&Vector3::zeros(), f64::NAN),
        Err(GyroIntegrateError::BadInterval(_))
    ));
    assert_eq!(est, before);
    est.predict(
        &Vector::from_nalgebra(Vector3::new(0.0, f64::INFINITY, 0.0)),
        0.01,
    );
    est.predict(&Vector::from_nalgebra(Vector3::zeros()), -0.01);
    assert_eq!(est.rejected_count(), 2);
    assert_eq!(est.q_nb(), before.q_nb());
    assert_eq!(est.last_stamp_ns(), 1_000);
}

#[test]
fn constructor_validates() {
    assert!(matches!(
        GyroIntegrator::new(UnitQuaternion::identity(), 1.6, 0),
        Err(GyroIntegratorNewError::LatitudeOutOfRange(_))
    ));
    assert!(matches!(
        GyroIntegrator::new(UnitQuaternion::identity(), f64::NAN, 0),
        Err(GyroIntegratorNewError::LatitudeOutOfRange(_))
    ));
    let est = GyroIntegrator::new(UnitQuaternion::identity(), 0.1, 0).expect("valid");
    assert_eq!(
        est.clone().with_gyro_bias(Vector3::new(0.0, f64::NAN, 0.0)),
        Err(GyroIntegratorNewError::NonFiniteBias)
    );
    let mut est = est;
    assert!(est.set_latitude(-2.0).is_err());
    assert!(est.set_latitude(-0.5).is_ok());
    assert_eq!(est.latitude_rad().to_bits(), (-0.5f64).to_bits());
}

#[test]
fn trait_predict_matches_integrate_and_advances_the_stamp() {
    let q0 = from_euler(0.1, 0.2, 0.3);
    let mut a = GyroIntegrator::new(q0, LAT, 5_000).expect("valid");
    let mut b = a.clone();
    for k in 1..=500u64 {
        let g = scripted_omega_nb(k as f64 * 0.01);
        a.integrate(5_000 + k * DT_NS, &g).expect("valid");
        AttitudeEstimator::predict(&mut b, &Vector::from_nalgebra(g), dt_s());
    }
    assert_eq!(a, b);
    assert_eq!(b.last_stamp_ns(), 5_000 + 500 * DT_NS);
    // Aiding is ignored.
    b.update(
        &Vector::from_nalgebra(Vector3::new(0.0, 0.0, -9.8)),
        &Vector::from_nalgebra(Vector3::new(20.0, 0.0, 40.0)),
    );
    assert_eq!(a, b);
    let out = b.estimate();
    assert_eq!(out.q_nb.to_nalgebra(), b.q_nb());
    assert_eq!(out.std_rad, Vector::zeros());
}

/// Runs a fixed pseudo-random sequence; optionally checkpoints at `split` through
/// `GyroState` into a fresh integrator and continues there.
fn run_sequence(split: Option<u64>, through_trait: bool) -> GyroIntegrator {
    let q0 = from_euler(-0.3, 0.1, 2.9);
    let bias = Vector3::new(2e-4, -1e-4, 3e-5);
    let mut est = GyroIntegrator::new(q0, -0.41, 0)
        .expect("valid")
        .with_gyro_bias(bias)
        .expect("finite")
        .with_calibration(1);
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        // xorshift: deterministic, no dependency on a generator's version.
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for k in 1..=20_000u64 {
        if Some(k) == split {
            let mut fresh =
                GyroIntegrator::new(UnitQuaternion::identity(), -0.41, 0).expect("valid");
            if through_trait {
                fresh.restore(&est.snapshot()).expect("valid snapshot");
                fresh.set_last_stamp_ns(est.last_stamp_ns());
            } else {
                fresh.restore_state(&est.state()).expect("valid state");
                fresh = fresh.with_calibration(est.calibration());
            }
            est = fresh;
        }
        let g = Vector3::new(next(), next(), next()) * 2.0;
        est.integrate(k * DT_NS, &g).expect("valid");
    }
    est
}

#[test]
fn deterministic_bit_for_bit() {
    let a = run_sequence(None, false);
    let b = run_sequence(None, false);
    assert_eq!(a.state(), b.state());
    let bits = |s: GyroState| s.q.map(f64::to_bits);
    assert_eq!(bits(a.state()), bits(b.state()));
}

#[test]
fn snapshot_restore_continues_bit_for_bit() {
    let straight = run_sequence(None, false);
    let via_state = run_sequence(Some(7_777), false);
    let via_trait = run_sequence(Some(12_345), true);
    assert_eq!(straight, via_state);
    assert_eq!(straight, via_trait);
    assert_eq!(straight.snapshot().calibration, 1);
}

#[test]
fn restore_refuses_bad_state() {
    let mut est = GyroIntegrator::new(UnitQuaternion::identity(), 0.3, 0).expect("valid");
    let before = est.clone();
    let bad = GyroState {
        q: [2.0, 0.0, 0.0, 0.0],
        gyro_bias: [0.0; 3],
        last_stamp_ns: 9,
    };
    assert!(matches!(
        est.restore_state(&bad),
        Err(AttitudeRestoreError::NotUnit(_))
    ));
    let mut snap = est.snapshot();
    snap.gyro_bias[0] = f64::NAN;
    assert_eq!(est.restore(&snap), Err(AttitudeRestoreError::NonFinite));
    assert_eq!(est, before);
}

#[test]
fn gyro_state_serialises() {
    // Plain data: serde derives are available to checkpoint files.
    fn is_serde<T: serde::Serialize + for<'de> serde::Deserialize<'de>>() {}
    is_serde::<GyroState>();
    is_serde::<AttitudeStateSnapshot>();
}
