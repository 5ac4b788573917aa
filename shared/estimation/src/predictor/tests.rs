//! The predictor against closed-form results for one error at a time.

use super::*;

/// A spec with every error off; the tests switch one on.
fn quiet() -> PredictorParams {
    PredictorParams {
        sensors: SensorErrorSpec {
            dvl: DvlErrorSpec {
                noise_sigma_m_s: 0.0,
                scale_factor_sigma: 0.0,
                ..Default::default()
            },
            ahrs: AhrsErrorSpec {
                roll_pitch_sigma_deg: 0.0,
                heading_sigma_deg: 0.0,
                heading_bias_sigma_deg: 0.0,
                ..Default::default()
            },
            depth: DepthErrorSpec::default(),
        },
        unaided_velocity_walk_m_s_rt_s: 0.0,
        ..Default::default()
    }
}

fn predictor(p: PredictorParams) -> ErrorPredictor {
    let mut e = ErrorPredictor::new(p.check().expect("valid"), 0.0);
    e.reset_horizontal(0.0);
    e
}

/// Straight at `v` m/s heading `yaw` for `t` s in steps of 0.1 s.
fn straight(e: &mut ErrorPredictor, v: f64, yaw: f64, t: f64, aided: bool) {
    let m = Motion {
        v_b: [v, 0.0, 0.0],
        euler: [0.0, 0.0, yaw],
        aided,
    };
    for _ in 0..(t / 0.1).round() as usize {
        e.propagate(0.1, &m);
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b
}

#[test]
fn a_constant_heading_bias_grows_linearly() {
    let mut p = quiet();
    p.sensors.ahrs.heading_bias_sigma_deg = 2.0;
    p.sensors.ahrs.heading_bias_time_s = f64::INFINITY;
    let mut e = predictor(p);
    straight(&mut e, 1.2, 0.3, 1000.0, true);
    let expect = 1.2 * 1000.0 * 2f64.to_radians();
    assert!(
        rel(e.horizontal_rms_m(), expect) < 1e-9,
        "{}",
        e.horizontal_rms_m()
    );
}

#[test]
fn a_gauss_markov_heading_bias_grows_as_its_integral() {
    let mut p = quiet();
    let (sigma, tau, v, t) = (2f64.to_radians(), 600.0, 1.2, 3000.0);
    p.sensors.ahrs.heading_bias_sigma_deg = sigma.to_degrees();
    p.sensors.ahrs.heading_bias_time_s = tau;
    let mut e = predictor(p);
    straight(&mut e, v, -1.0, t, true);
    // Var ∫b = σ² 2τ² (T/τ − 1 + e^{−T/τ}), times v² across track.
    let expect = v * sigma * (2.0 * tau * tau * (t / tau - 1.0 + (-t / tau).exp())).sqrt();
    assert!(
        rel(e.horizontal_rms_m(), expect) < 1e-3,
        "{} vs {expect}",
        e.horizontal_rms_m()
    );
    // Well below the constant-error figure.
    assert!(e.horizontal_rms_m() < 0.6 * v * t * sigma);
}

#[test]
fn constant_errors_cancel_on_a_closed_track() {
    let mut p = quiet();
    p.sensors.ahrs.heading_bias_sigma_deg = 3.0;
    p.sensors.ahrs.heading_bias_time_s = f64::INFINITY;
    p.sensors.dvl.scale_factor_sigma = 0.05;
    let mut e = predictor(p);
    for k in 0..4 {
        straight(
            &mut e,
            1.0,
            k as f64 * std::f64::consts::FRAC_PI_2,
            200.0,
            true,
        );
        if k == 1 {
            assert!(e.horizontal_rms_m() > 10.0);
        }
    }
    assert!(e.horizontal_rms_m() < 1e-6, "{}", e.horizontal_rms_m());
}

#[test]
fn white_velocity_noise_is_a_random_walk() {
    let mut p = quiet();
    p.sensors.dvl.noise_sigma_m_s = 0.01;
    p.sensors.dvl.rate_hz = 5.0;
    let mut e = predictor(p);
    straight(&mut e, 1.0, 0.0, 1000.0, true);
    let expect = (2.0 * 0.01f64.powi(2) / 5.0 * 1000.0).sqrt();
    assert!(rel(e.horizontal_rms_m(), expect) < 1e-9);
    let s = e.velocity_std_m_s(&Motion {
        v_b: [1.0, 0.0, 0.0],
        euler: [0.0; 3],
        aided: true,
    });
    assert!(rel(s[0], 0.01) < 1e-12 && rel(s[1], 0.01) < 1e-12, "{s:?}");
}

#[test]
fn unaided_velocity_error_grows_and_stops_with_the_dvl() {
    let mut p = quiet();
    p.unaided_velocity_walk_m_s_rt_s = 0.05;
    let mut e = predictor(p);
    straight(&mut e, 1.0, 0.0, 10.0, false);
    // Per axis q² T³ / 3.
    let expect = (2.0 * 0.05f64.powi(2) * 1000.0 / 3.0).sqrt();
    assert!(
        rel(e.horizontal_rms_m(), expect) < 0.02,
        "{}",
        e.horizontal_rms_m()
    );
    let after = e.horizontal_rms_m();
    straight(&mut e, 1.0, 0.0, 10.0, true);
    assert_eq!(e.horizontal_rms_m(), after);
}

#[test]
fn a_fix_resets_and_the_advisory_follows_the_threshold() {
    let mut p = quiet();
    p.sensors.ahrs.heading_bias_sigma_deg = 2.0;
    p.surfacing_threshold_m = 10.0;
    let mut e = predictor(p);
    assert!(!e.surfacing_advised());
    straight(&mut e, 1.0, 0.0, 600.0, true);
    assert!(e.surfacing_advised());
    e.reset_horizontal(2.5);
    assert!(rel(e.horizontal_rms_m(), 2.5 * 2f64.sqrt()) < 1e-12);
    assert!(!e.surfacing_advised());
    e.reset_down();
    assert_eq!(e.position_std_m()[2], 0.02);
}

#[test]
fn the_covariance_round_trips_and_bad_ones_are_refused() {
    let p = PredictorParams {
        unaided_velocity_walk_m_s_rt_s: 0.1,
        ..Default::default()
    };
    let mut e = predictor(p);
    straight(&mut e, 1.3, 0.7, 50.0, false);
    let c = e.covariance();
    let mut f = predictor(PredictorParams::default());
    f.set_covariance(&c).expect("valid");
    assert_eq!(f.covariance(), c);
    let mut bad = c;
    bad[0][1] += 1.0;
    assert_eq!(f.set_covariance(&bad), Err(NotCovariance));
    let mut bad = c;
    bad[4][4] = f64::NAN;
    assert_eq!(f.set_covariance(&bad), Err(NotCovariance));
    assert_eq!(f.covariance(), c);
}

#[test]
fn bad_parameters_are_refused_by_name() {
    let p = PredictorParams {
        surfacing_threshold_m: 0.0,
        ..Default::default()
    };
    assert!(matches!(
        p.check(),
        Err(PredictorParamsError::OutOfRange {
            name: "surfacing_threshold_m",
            ..
        })
    ));
    let p = PredictorParams {
        unaided_velocity_walk_m_s_rt_s: f64::NAN,
        ..Default::default()
    };
    assert!(p.check().is_err());
    let p: PredictorParams = toml::from_str("form = \"eq14\"").expect("valid");
    assert_eq!(p.form, Form::Eq14);
    assert!(toml::from_str::<PredictorParams>("form = \"eq18\"").is_err());
}
