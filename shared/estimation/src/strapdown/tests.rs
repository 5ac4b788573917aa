//! Tests of the strapdown mechanization against a truth that does not share its
//! discretisation.
//!
//! # The truth generator
//!
//! A trajectory is defined in continuous time by analytic profiles: speed `u(t)`,
//! flight-path angle `γ(t)`, heading rate `r(t)`, roll `φ(t)`, pitch `γ(t) + θ₀`;
//! the NED velocity is `u [cos γ cos ψ, cos γ sin ψ, -sin γ]` and the attitude
//! `from_euler(φ, γ + θ₀, ψ)`. Latitude, longitude, height and heading `ψ` are
//! integrated with RK4 at ten times the IMU rate (1 kHz for a 100 Hz IMU).
//!
//! The IMU is then made from the fine truth without any of the mechanization's
//! formulas:
//! - gyro: the rotation vector of the body's rotation relative to *inertial space*
//!   between the two interval ends, divided by `Δt`. The inertial attitude is built
//!   from geometry, `q_ib(t) = q_ie(t) ⊗ q_en(L, λ) ⊗ q_nb(t)` with
//!   `q_ie = R_z(ω_ie t)` and `C_n^e(L, λ) = R_z(λ) R_y(-L - π/2)`: no Earth-rate or
//!   transport-rate formula, no (K1)/(K2).
//! - accelerometer: the Simpson average over the interval (ten fine steps) of the
//!   true specific force in body axes, `f^b = C_n^b C_e^n (r̈^e + 2 ω_ie^e × ṙ^e) - C_n^b g^n`,
//!   where `ṙ^e = C_n^e v^n` and `r̈^e = Ċ_n^e v^n + C_n^e v̇^n` with `Ċ_n^e` the
//!   analytic derivative of the matrix through `L̇`, `λ̇` (ECEF kinematics, again
//!   without the NED rate formulas).
//!
//! `generator_agrees_with_the_ned_equations` checks that this truth satisfies the
//! textbook NED equations of [`crate::earth`] at the continuous level, so the
//! mechanization is tested only on its discretisation.

use std::f64::consts::PI;

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use super::*;
use crate::attitude::kinematics::body_rate_between;
use crate::attitude::{AttitudeError, from_euler, quat_from_rotation_vector, rotation_vector};
use crate::earth::wgs84;

/// Fine truth steps per IMU interval (even, for Simpson's rule).
const SUB: usize = 10;

/// A continuous trajectory definition.
#[derive(Clone, Copy)]
struct Profile {
    lat0_rad: f64,
    lon0_rad: f64,
    height0_m: f64,
    heading0_rad: f64,
    /// Pitch minus flight-path angle, rad.
    pitch_offset_rad: f64,
    /// Speed and its derivative.
    speed: fn(f64) -> (f64, f64),
    /// Flight-path angle (positive climbing) and its derivative.
    flight_path: fn(f64) -> (f64, f64),
    /// Heading rate, rad/s.
    heading_rate: fn(f64) -> f64,
    /// Roll, rad.
    roll: fn(f64) -> f64,
}

// --- The survey leg -------------------------------------------------------------

const SURVEY_TURN_RATE_RAD_S: f64 = 3.0 * PI / 180.0;
/// Cosine ramp in and out of each turn, s.
const TURN_RAMP_S: f64 = 6.0;
/// Full-rate part of a turn: the ramps count half, so 180° needs
/// `r (plateau + ramp) = π`.
const TURN_PLATEAU_S: f64 = PI / SURVEY_TURN_RATE_RAD_S - TURN_RAMP_S;
/// Start of the two turns (right, then left), s.
const TURN_STARTS_S: [(f64, f64); 2] = [(150.0, 1.0), (390.0, -1.0)];

/// Smooth turn-rate shape: 0 → 1 → 0 with cosine ramps (continuous derivative).
fn turn_shape(s: f64) -> f64 {
    let (ramp, plateau) = (TURN_RAMP_S, TURN_PLATEAU_S);
    if !(0.0..=2.0 * ramp + plateau).contains(&s) {
        0.0
    } else if s < ramp {
        0.5 * (1.0 - (PI * s / ramp).cos())
    } else if s <= ramp + plateau {
        1.0
    } else {
        0.5 * (1.0 + (PI * (s - ramp - plateau) / ramp).cos())
    }
}

fn survey_heading_rate(t: f64) -> f64 {
    TURN_STARTS_S
        .iter()
        .map(|&(t0, sign)| sign * SURVEY_TURN_RATE_RAD_S * turn_shape(t - t0))
        .sum()
}

/// 1.5 m/s with a ±0.05 m/s surge oscillation.
fn survey_speed(t: f64) -> (f64, f64) {
    let w = 2.0 * PI / 100.0;
    (1.5 + 0.05 * (w * t).sin(), 0.05 * w * (w * t).cos())
}

/// ±10° dive/climb with a 120 s period: the depth swings between about 10 and 20 m.
fn survey_flight_path(t: f64) -> (f64, f64) {
    let (a, w) = (10f64.to_radians(), 2.0 * PI / 120.0);
    (a * (w * t).cos(), -a * w * (w * t).sin())
}

/// ±2° roll oscillation, 7 s period.
fn survey_roll(t: f64) -> f64 {
    2f64.to_radians() * (2.0 * PI * t / 7.0).sin()
}

/// Off Lisbon (38.6° N, 9.3° W) at 15 m depth, heading 030°.
fn survey() -> Profile {
    Profile {
        lat0_rad: 38.6f64.to_radians(),
        lon0_rad: (-9.3f64).to_radians(),
        height0_m: -15.0,
        heading0_rad: 30f64.to_radians(),
        pitch_offset_rad: 0.0,
        speed: survey_speed,
        flight_path: survey_flight_path,
        heading_rate: survey_heading_rate,
        roll: survey_roll,
    }
}

// --- A vehicle at rest ------------------------------------------------------------

fn zero_pair(_t: f64) -> (f64, f64) {
    (0.0, 0.0)
}

fn zero(_t: f64) -> f64 {
    0.0
}

fn still_roll(_t: f64) -> f64 {
    3f64.to_radians()
}

/// At rest at 45° N, 5 m depth, roll 3°, pitch -2°, heading 070°.
fn still() -> Profile {
    Profile {
        lat0_rad: 45f64.to_radians(),
        lon0_rad: 0.3,
        height0_m: -5.0,
        heading0_rad: 70f64.to_radians(),
        pitch_offset_rad: (-2f64).to_radians(),
        speed: zero_pair,
        flight_path: zero_pair,
        heading_rate: zero,
        roll: still_roll,
    }
}

// --- Truth generator ------------------------------------------------------------

/// RK4 state: latitude, longitude, height, heading.
type Y = [f64; 4];

/// The truth at one fine node.
#[derive(Debug, Clone, Copy)]
struct Node {
    lat: f64,
    lon: f64,
    h: f64,
    q_nb: UnitQuaternion<f64>,
    v: Vector3<f64>,
    /// Velocity derivative (NED components), m/s².
    v_dot: Vector3<f64>,
    /// Specific force, body axes, m/s².
    f_b: Vector3<f64>,
    /// Attitude relative to inertial space (ECI at t = 0 coincides with ECEF).
    q_ib: UnitQuaternion<f64>,
}

impl Node {
    fn state(&self) -> StrapdownState {
        StrapdownState {
            q_nb: Rotation::from_nalgebra(self.q_nb),
            v_ned_m_s: Vector::from_nalgebra(self.v),
            lat_rad: self.lat,
            lon_rad: self.lon,
            height_m: self.h,
        }
    }
}

/// `C_n^e(L, λ)`, NED → ECEF (Groves 2013 §2.4), written out.
fn c_ne(lat: f64, lon: f64) -> Matrix3<f64> {
    let (sl, cl) = lat.sin_cos();
    let (so, co) = lon.sin_cos();
    Matrix3::new(
        -sl * co,
        -so,
        -cl * co,
        -sl * so,
        co,
        -cl * so,
        cl,
        0.0,
        -sl,
    )
}

/// `∂C_n^e/∂L` and `∂C_n^e/∂λ`.
fn c_ne_partials(lat: f64, lon: f64) -> (Matrix3<f64>, Matrix3<f64>) {
    let (sl, cl) = lat.sin_cos();
    let (so, co) = lon.sin_cos();
    let d_lat = Matrix3::new(
        -cl * co,
        0.0,
        sl * co,
        -cl * so,
        0.0,
        sl * so,
        -sl,
        0.0,
        -cl,
    );
    let d_lon = Matrix3::new(
        sl * so,
        -co,
        cl * so,
        -sl * co,
        -so,
        -cl * co,
        0.0,
        0.0,
        0.0,
    );
    (d_lat, d_lon)
}

/// `q_en` as a product of elementary rotations, `R_z(λ) R_y(-L - π/2)`.
fn q_en(lat: f64, lon: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), lon)
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -lat - 0.5 * PI)
}

struct Truth {
    p: Profile,
    fine_dt: f64,
    j: u64,
    y: Y,
}

impl Truth {
    fn new(p: Profile, imu_dt: f64) -> Self {
        Self {
            p,
            fine_dt: imu_dt / SUB as f64,
            j: 0,
            y: [p.lat0_rad, p.lon0_rad, p.height0_m, p.heading0_rad],
        }
    }

    fn t(&self) -> f64 {
        self.j as f64 * self.fine_dt
    }

    /// NED velocity and its derivative at time `t`, heading `psi`.
    fn velocity(p: &Profile, t: f64, psi: f64) -> (Vector3<f64>, Vector3<f64>) {
        let (u, u_dot) = (p.speed)(t);
        let (g, g_dot) = (p.flight_path)(t);
        let r = (p.heading_rate)(t);
        let (sg, cg) = g.sin_cos();
        let (sp, cp) = psi.sin_cos();
        let dir = Vector3::new(cg * cp, cg * sp, -sg);
        let dir_dot = Vector3::new(
            -sg * g_dot * cp - cg * sp * r,
            -sg * g_dot * sp + cg * cp * r,
            -cg * g_dot,
        );
        (u * dir, u_dot * dir + u * dir_dot)
    }

    fn deriv(p: &Profile, t: f64, y: &Y) -> Y {
        let (v, _) = Self::velocity(p, t, y[3]);
        let (lat, h) = (y[0], y[2]);
        [
            v.x / (meridian_radius(lat) + h),
            v.y / ((transverse_radius(lat) + h) * lat.cos()),
            -v.z,
            (p.heading_rate)(t),
        ]
    }

    fn rk4_step(&mut self) {
        let (p, t, h, y) = (&self.p, self.t(), self.fine_dt, self.y);
        let add = |a: &Y, k: &Y, s: f64| -> Y {
            [
                a[0] + s * k[0],
                a[1] + s * k[1],
                a[2] + s * k[2],
                a[3] + s * k[3],
            ]
        };
        let k1 = Self::deriv(p, t, &y);
        let k2 = Self::deriv(p, t + 0.5 * h, &add(&y, &k1, 0.5 * h));
        let k3 = Self::deriv(p, t + 0.5 * h, &add(&y, &k2, 0.5 * h));
        let k4 = Self::deriv(p, t + h, &add(&y, &k3, h));
        for i in 0..4 {
            self.y[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        self.j += 1;
    }

    /// The truth at the current fine node.
    fn node(&self) -> Node {
        let p = &self.p;
        let t = self.t();
        let [lat, lon, h, psi] = self.y;
        let (v, v_dot) = Self::velocity(p, t, psi);
        let (gamma, _) = (p.flight_path)(t);
        let q_nb = from_euler((p.roll)(t), gamma + p.pitch_offset_rad, psi);

        // Specific force from ECEF kinematics (module doc).
        let c = c_ne(lat, lon);
        let (d_lat, d_lon) = c_ne_partials(lat, lon);
        let lat_dot = v.x / (meridian_radius(lat) + h);
        let lon_dot = v.y / ((transverse_radius(lat) + h) * lat.cos());
        let c_dot = d_lat * lat_dot + d_lon * lon_dot;
        let r_dot_e = c * v;
        let r_ddot_e = c_dot * v + c * v_dot;
        let omega_ie_e = Vector3::new(0.0, 0.0, wgs84::OMEGA_IE_RAD_S);
        let g_n = Vector3::new(0.0, 0.0, normal_gravity(lat, h));
        let f_n = c.transpose() * (r_ddot_e + 2.0 * omega_ie_e.cross(&r_dot_e)) - g_n;
        let f_b = q_nb.inverse_transform_vector(&f_n);

        let q_ie = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), wgs84::OMEGA_IE_RAD_S * t);
        let q_ib = q_ie * q_en(lat, lon) * q_nb;
        Node {
            lat,
            lon,
            h,
            q_nb,
            v,
            v_dot,
            f_b,
            q_ib,
        }
    }

    /// Advances one IMU interval from `start` (the node at the current time);
    /// returns the gyro and accelerometer samples and the node at the end.
    fn next_imu(&mut self, start: &Node) -> (Vector3<f64>, Vector3<f64>, Node) {
        // Simpson's rule over SUB fine steps.
        let mut sum = start.f_b;
        let mut end = *start;
        for i in 1..=SUB {
            self.rk4_step();
            end = self.node();
            let w = if i == SUB {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            sum += w * end.f_b;
        }
        let accel = sum / (3.0 * SUB as f64);
        let imu_dt = self.fine_dt * SUB as f64;
        let gyro = rotation_vector(&(start.q_ib.inverse() * end.q_ib)) / imu_dt;
        (gyro, accel, end)
    }
}

// --- Running the mechanization against the truth --------------------------------

/// Position error of `est` against `truth` in metres: north, east, down.
fn ned_error(est: &StrapdownState, truth: &Node) -> Vector3<f64> {
    let rn = meridian_radius(truth.lat) + truth.h;
    let re = transverse_radius(truth.lat) + truth.h;
    Vector3::new(
        (est.lat_rad - truth.lat) * rn,
        crate::attitude::wrap_pi(est.lon_rad - truth.lon) * re * truth.lat.cos(),
        -(est.height_m - truth.h),
    )
}

#[derive(Debug, Default, Clone, Copy)]
struct Outcome {
    final_ned_m: Vector3<f64>,
    final_att_rad: f64,
    max_horizontal_m: f64,
    max_vertical_m: f64,
    max_att_rad: f64,
    /// Per-axis maxima of |error|, m.
    max_abs_ned_m: Vector3<f64>,
    final_vel_m_s: Vector3<f64>,
    distance_m: f64,
}

/// Runs the mechanization for `duration_s` against the truth of `profile`, from
/// the true initial state modified by `perturb`.
fn run(
    profile: Profile,
    imu_dt: f64,
    duration_s: f64,
    perturb: impl Fn(StrapdownState) -> StrapdownState,
) -> (Outcome, Strapdown, Node) {
    let mut truth = Truth::new(profile, imu_dt);
    let mut node = truth.node();
    let mut ins = Strapdown::new(perturb(node.state())).expect("valid start");
    let steps = (duration_s / imu_dt).round() as u64;
    let mut o = Outcome::default();
    for _ in 0..steps {
        let (gyro, accel, end) = truth.next_imu(&node);
        o.distance_m += 0.5 * (node.v.xy().norm() + end.v.xy().norm()) * imu_dt;
        node = end;
        ins.update(
            &Vector::from_nalgebra(gyro),
            &Vector::from_nalgebra(accel),
            imu_dt,
        )
        .expect("valid sample");
        let s = ins.state();
        let e = ned_error(&s, &node);
        o.max_horizontal_m = o.max_horizontal_m.max(e.xy().norm());
        o.max_vertical_m = o.max_vertical_m.max(e.z.abs());
        o.max_abs_ned_m = o.max_abs_ned_m.sup(&e.abs());
        o.max_att_rad = o
            .max_att_rad
            .max(AttitudeError::between(s.q_nb.as_nalgebra(), &node.q_nb).total_rad);
    }
    let s = ins.state();
    o.final_ned_m = ned_error(&s, &node);
    o.final_att_rad = AttitudeError::between(s.q_nb.as_nalgebra(), &node.q_nb).total_rad;
    o.final_vel_m_s = s.v_ned_m_s.to_nalgebra() - node.v;
    (o, ins, node)
}

fn report(name: &str, o: &Outcome) {
    println!(
        "{name}: final error N {:+.4e} E {:+.4e} D {:+.4e} m, attitude {:.3e} deg; \
         max |N| {:.4e} |E| {:.4e} |D| {:.4e} m, max horizontal {:.4e} m, \
         max attitude {:.3e} deg; final velocity error {:.2e} m/s; distance {:.0} m",
        o.final_ned_m.x,
        o.final_ned_m.y,
        o.final_ned_m.z,
        o.final_att_rad.to_degrees(),
        o.max_abs_ned_m.x,
        o.max_abs_ned_m.y,
        o.max_abs_ned_m.z,
        o.max_horizontal_m,
        o.max_att_rad.to_degrees(),
        o.final_vel_m_s.norm(),
        o.distance_m,
    );
}

// --- Tests ----------------------------------------------------------------------

/// The acceptance test: a 10-minute lawnmower survey leg at 100 Hz with two 180°
/// turns at 3°/s, dives and climbs between about 10 and 20 m at ±10° pitch and a
/// roll oscillation; free inertial, vertical channel undamped.
#[test]
fn survey_leg_follows_the_truth() {
    let (o, ins, truth) = run(survey(), 0.01, 600.0, |s| s);
    report("survey 100 Hz", &o);
    // The profile is what it claims to be.
    assert!(o.distance_m > 850.0, "{o:?}");
    assert!(
        (truth.h + 15.0).abs() < 6.0 && ins.step_count() == 60_000,
        "{truth:?}"
    );
    assert!(o.max_horizontal_m < 1.0, "{o:?}");
    assert!(o.max_vertical_m < 1.0, "{o:?}");
    assert!(o.max_att_rad < 0.01f64.to_radians(), "{o:?}");
}

/// The discretisation error falls when the IMU rate rises (it is the
/// mechanization's, not the truth's): 50, 100 and 200 Hz over 5 minutes.
#[test]
fn error_falls_with_the_imu_rate() {
    let mut errors = Vec::new();
    for hz in [50.0, 100.0, 200.0] {
        let (o, _, _) = run(survey(), 1.0 / hz, 300.0, |s| s);
        report(&format!("survey 5 min {hz} Hz"), &o);
        errors.push(o.max_horizontal_m.max(o.max_vertical_m));
    }
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "{errors:?}");
}

/// The generator's truth satisfies the textbook NED equations of
/// [`crate::earth`] (T&W 2004 ch. 3): the ECEF-built specific force equals
/// `v̇ + (2ω_ie + ω_en) × v - g`, and the inertial-space gyro equals, to first
/// order, `ω_nb^b + C_n^b (ω_ie^n + ω_en^n)`.
#[test]
fn generator_agrees_with_the_ned_equations() {
    let dt = 0.01;
    let mut truth = Truth::new(survey(), dt);
    let mut node = truth.node();
    let mut checked = 0;
    for k in 0..30_000 {
        let (gyro, accel, end) = truth.next_imu(&node);
        if k % 1000 == 0 {
            // Specific force at the node, from the NED equations.
            let w_ie = earth_rate_ned(end.lat);
            let w_en = transport_rate_ned(end.lat, end.h, &end.v);
            let g = Vector3::new(0.0, 0.0, normal_gravity(end.lat, end.h));
            let f_n = end.v_dot + (2.0 * w_ie + w_en).cross(&end.v) - g;
            let f_b = end.q_nb.inverse_transform_vector(&f_n);
            assert!((f_b - end.f_b).norm() < 1e-12, "{f_b:?} vs {:?}", end.f_b);
            // Gyro, first order: the nav-frame rates at mid-interval.
            let lat_m = 0.5 * (node.lat + end.lat);
            let h_m = 0.5 * (node.h + end.h);
            let v_m = 0.5 * (node.v + end.v);
            let w_in = earth_rate_ned(lat_m) + transport_rate_ned(lat_m, h_m, &v_m);
            let w_nb = body_rate_between(&node.q_nb, &end.q_nb, dt);
            let q_m = node.q_nb.slerp(&end.q_nb, 0.5);
            let first = w_nb + q_m.inverse_transform_vector(&w_in);
            assert!((gyro - first).norm() < 2e-9, "{gyro:?} vs {first:?}");
            // The accelerometer sample is near the mid-interval specific force.
            assert!(accel.norm() > 9.7 && accel.norm() < 9.9, "{accel:?}");
            checked += 1;
        }
        node = end;
    }
    assert_eq!(checked, 30);
    // And the C_n^e quaternion is the written-out matrix.
    for (lat, lon) in [(0.3, -2.0), (-1.2, 0.4), (0.0, 0.0)] {
        let m = q_en(lat, lon).to_rotation_matrix().into_inner();
        assert!((m - c_ne(lat, lon)).abs().max() < 1e-15);
    }
}

/// At rest at 45° N for 10 minutes with an exact IMU the navigator stays put.
#[test]
fn still_vehicle_stays_within_a_centimetre() {
    let p = still();
    let q = from_euler(3f64.to_radians(), (-2f64).to_radians(), 70f64.to_radians());
    let start = StrapdownState::at_depth(
        Rotation::from_nalgebra(q),
        Vector::zeros(),
        p.lat0_rad,
        p.lon0_rad,
        5.0,
    );
    // Exact still IMU: the Earth rate and the reaction to gravity, in body axes.
    let gyro = q.inverse_transform_vector(&earth_rate_ned(p.lat0_rad));
    let accel =
        q.inverse_transform_vector(&Vector3::new(0.0, 0.0, -normal_gravity(p.lat0_rad, -5.0)));
    let mut ins = Strapdown::new(start).expect("valid");
    let mut max_m: f64 = 0.0;
    let truth = Node {
        lat: start.lat_rad,
        lon: start.lon_rad,
        h: start.height_m,
        q_nb: q,
        v: Vector3::zeros(),
        v_dot: Vector3::zeros(),
        f_b: accel,
        q_ib: q,
    };
    for _ in 0..60_000 {
        ins.update(
            &Vector::from_nalgebra(gyro),
            &Vector::from_nalgebra(accel),
            0.01,
        )
        .expect("valid");
        max_m = max_m.max(ned_error(&ins.state(), &truth).norm());
    }
    let s = ins.state();
    let att = AttitudeError::between(s.q_nb.as_nalgebra(), &q).total_rad;
    println!(
        "still 45N 10 min: max position error {max_m:.3e} m, final {:.3e} m, velocity {:.3e} m/s, attitude {:.3e} rad",
        ned_error(&s, &truth).norm(),
        s.v_ned_m_s.norm(),
        att
    );
    assert!(max_m < 0.01, "{max_m}");
    assert!(att < 1e-9, "{att}");

    // The truth generator's still profile gives the same IMU, to rounding.
    let mut gen_truth = Truth::new(p, 0.01);
    let n0 = gen_truth.node();
    let (g2, a2, _) = gen_truth.next_imu(&n0);
    assert!((g2 - gyro).norm() < 1e-13, "{g2:?} vs {gyro:?}");
    assert!((a2 - accel).norm() < 1e-12, "{a2:?} vs {accel:?}");
    // And a generator-driven still run agrees too.
    let (o, _, _) = run(p, 0.01, 600.0, |s| s);
    report("still (generator)", &o);
    assert!(o.max_horizontal_m.max(o.max_vertical_m) < 0.01, "{o:?}");
}

/// Schuler: an initial tilt of 1e-6 rad about north makes an east acceleration
/// error `g δ`, and the east position error follows `R δ (1 - cos ω_s t)`,
/// `ω_s = √(g/R)` (84-minute period): ≈ 1.7 m after 10 minutes.
#[test]
fn schuler_tilt_gives_the_expected_error() {
    let p = still();
    let tilt = 1e-6;
    let (o, _, truth) = run(p, 0.01, 600.0, |s| StrapdownState {
        q_nb: Rotation::from_nalgebra(
            quat_from_rotation_vector(&Vector3::new(tilt, 0.0, 0.0)) * s.q_nb.to_nalgebra(),
        ),
        ..s
    });
    report("Schuler 1e-6 rad tilt", &o);
    let r = (meridian_radius(truth.lat) * transverse_radius(truth.lat)).sqrt() + truth.h;
    let w_s = (normal_gravity(truth.lat, truth.h) / r).sqrt();
    let want = r * tilt * (1.0 - (w_s * 600.0).cos());
    println!("Schuler: expected east error {want:.4} m");
    assert!((1.0..3.0).contains(&o.final_ned_m.y), "{o:?}");
    assert!(
        (o.final_ned_m.y - want).abs() < 0.1 * want,
        "{o:?} vs {want}"
    );
    assert!(o.final_ned_m.x.abs() < 0.1 * want, "{o:?}");
}

/// Same inputs, same outputs, to the bit; the pure step and the navigator agree.
#[test]
fn deterministic_and_pure() {
    let bits = |s: &StrapdownState| {
        [
            s.q_nb.to_wxyz()[0],
            s.q_nb.to_wxyz()[1],
            s.q_nb.to_wxyz()[2],
            s.q_nb.to_wxyz()[3],
            s.v_ned_m_s.x(),
            s.v_ned_m_s.y(),
            s.v_ned_m_s.z(),
            s.lat_rad,
            s.lon_rad,
            s.height_m,
        ]
        .map(f64::to_bits)
    };
    let (_, a, _) = run(survey(), 0.01, 60.0, |s| s);
    let (_, b, _) = run(survey(), 0.01, 60.0, |s| s);
    assert_eq!(bits(&a.state()), bits(&b.state()));

    let s0 = a.state();
    let (gyro, accel) = (
        Vector3::new(0.01, -0.02, 0.05),
        Vector3::new(0.3, 0.1, -9.8),
    );
    let pure = propagate(
        &s0,
        &Vector::from_nalgebra(gyro),
        &Vector::from_nalgebra(accel),
        0.01,
    )
    .expect("valid");
    let mut nav = Strapdown::new(s0).expect("valid");
    nav.update(
        &Vector::from_nalgebra(gyro),
        &Vector::from_nalgebra(accel),
        0.01,
    )
    .expect("valid");
    assert_eq!(bits(&pure.state), bits(&nav.state()));
    assert_eq!(pure.specific_force_ned_m_s2, nav.specific_force_ned_m_s2());
    // Resolved at the mid-interval attitude (the nav-frame half-turn, ~4e-7 rad, aside).
    let q_m = s0.q_nb.to_nalgebra() * quat_from_rotation_vector(&(gyro * 0.005));
    assert!((pure.specific_force_ned_m_s2.to_nalgebra() - q_m * accel).norm() < 1e-5);
}
