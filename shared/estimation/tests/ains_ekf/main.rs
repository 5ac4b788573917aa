// Integration tests of the aided INS's `ekf` variant (it needs the simulator,
// which depends on this crate).
//! The error-state EKF against the simulator's survey (paper 000's
//! 43-minute parallel-transect survey, GPS only at the surface) without
//! position aiding (paper 000's "DVL-aided INS"), heading from the shipped
//! attitude PF and from the attitude role's `mekf`, run in-process with the
//! calibrated magnetometer; and, on
//! synthetic inputs: initialisation, bad input, the gate and its
//! re-anchoring, fixes, snapshot and restore.
//!
//! The whole survey takes about 3 s in release (the simulator, the `mekf`
//! and the EKF); the figures over seeds 100-109 and the EKF's time per
//! IMU sample are printed by
//! `cargo run --release -p nauta-estimation --example ains_ekf_survey`.

mod harness;
mod size;

use harness::*;
use nauta_estimation::ains::AinsInput;
use nauta_estimation::ains::aiding;
use nauta_estimation::ains::dr::Site;
use nauta_estimation::ains::ekf::{Ekf, EkfParams, EkfSnapshot};
use nauta_estimation::frames::{Rotation, Vector};
use nauta_estimation::readings::{Ahrs, Depth, Dvl, Fix, Gps, Imu, Nav};
use nauta_estimation::{Estimator, Stamped};
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioParams};
use nauta_sim::suite::SuiteConfig;

/// Paper 000's DVL-aided INS: no `positioning/fix`.
fn no_fix() -> EkfParams {
    EkfParams {
        position_aiding: false,
        ..Default::default()
    }
}

/// The issue's targets on one run, but for the upper bound of the 95 %
/// region's coverage (≤ 98 %), which seed 7 does not meet: its truth is
/// inside 100 % of the time with either attitude input (a run is one dive, and its error is mostly all
/// inside or all outside the region; over seeds 100-109 the coverage is
/// checked by the crate's example `ains_ekf_survey`, which exits 1 when a
/// target is missed).
fn check_targets(name: &str, f: &Figures) {
    let d = f.dive_drift_m_per_km();
    assert!(!f.dives.is_empty(), "{name}: no dive");
    for k in 0..3 {
        assert!(d[k] <= 5.0, "{name}: end-of-dive drift {d:?} m/km");
        assert!(
            f.slope_m_per_km[k].abs() <= 5.0,
            "{name}: drift slope {:?} m/km",
            f.slope_m_per_km
        );
        assert!(
            f.vel_rms_m_s[k] <= 0.010,
            "{name}: velocity RMS {:?} m/s",
            f.vel_rms_m_s
        );
    }
    assert!(
        f.inside_95 >= 0.90,
        "{name}: truth inside the 95 % region {:.1} % of the time",
        100.0 * f.inside_95
    );
}

/// The whole survey, seed 7 (the development seed), heading from the
/// shipped attitude PF (whose errors of about 1° in the turns its published
/// σ does not say: `heading_manoeuvre_factor`) and from the `mekf`: drift
/// ≤ 5 m/km on each axis (end of the dive and least-squares slope),
/// velocity RMS ≤ 0.010 m/s per axis, truth inside the published 95 %
/// region at least 90 % of the time ([`check_targets`]); outputs once per
/// IMU sample; the aiding bits.
#[test]
fn survey_without_position_aiding_meets_the_issue_targets() {
    let f = run(7, 3000.0, &no_fix(), attitude_pf());
    report("survey seed 7, attitude pf heading", &f);
    check_targets("survey seed 7, attitude pf", &f);
    assert!(f.stats.heading.used > 2_000, "{:?}", f.stats.heading);
    let f = run(7, 3000.0, &no_fix(), attitude_mekf());
    report("survey seed 7, mekf heading", &f);
    assert_eq!(f.outputs as u64, f.stats.imu_samples);
    assert_eq!(f.stats.fix.used, 0);
    // Submerged: DVL, heading and depth; never GPS or FIX.
    let submerged: Vec<_> = f
        .trace
        .iter()
        .filter(|p| p.t_s > 100.0 && p.t_s < 2500.0)
        .collect();
    assert!(!submerged.is_empty());
    let all = aiding::DVL | aiding::HEADING | aiding::DEPTH;
    let full = submerged.iter().filter(|p| p.aiding_mode == all).count();
    assert!(
        full as f64 > 0.95 * submerged.len() as f64,
        "{full} of {}",
        submerged.len()
    );
    assert!(
        f.trace[5].aiding_mode & aiding::GPS != 0,
        "GPS at the start"
    );
    check_targets("survey seed 7", &f);
}

/// The AHRS alone (2° Gauss-Markov heading bias in the simulator) as the
/// heading source: the EKF runs and its yaw σ says the heading is known to
/// about 2°, not better (the bias state); printed for the report.
#[test]
fn with_the_ahrs_only_the_yaw_sigma_is_honest() {
    let f = run(7, 3000.0, &no_fix(), Heading::Ahrs);
    report("survey seed 7, AHRS heading", &f);
    assert!(f.yaw_rms_rad[1].to_degrees() > 1.0, "{:?}", f.yaw_rms_rad);
    assert!(
        f.yaw_rms_rad[0] < 2.0 * f.yaw_rms_rad[1],
        "{:?}",
        f.yaw_rms_rad
    );
}

/// 60 s without DVL samples mid-survey: the DVL bit drops once the aiding
/// timeout has passed, the velocity σ grows (free inertial), and both come
/// back after.
#[test]
fn a_dvl_gap_degrades_to_free_inertial_and_says_so() {
    let f = run_with(
        7,
        1000.0,
        &no_fix(),
        Heading::Ahrs,
        SuiteConfig::survey(),
        Some((600.0, 660.0)),
    );
    let at = |t: f64| *f.trace.iter().find(|p| p.t_s >= t).expect("trace");
    let (before, during, end, after) = (at(590.0), at(630.0), at(659.0), at(700.0));
    assert!(before.aiding_mode & aiding::DVL != 0);
    assert!(during.aiding_mode & aiding::DVL == 0);
    assert!(during.aiding_mode & aiding::HEADING != 0);
    assert!(after.aiding_mode & aiding::DVL != 0);
    assert!(
        end.vel_std_n_m_s > 5.0 * before.vel_std_n_m_s,
        "{before:?} {end:?}"
    );
    assert!(end.predicted_drift_m > before.predicted_drift_m);
    assert!(after.vel_std_n_m_s < end.vel_std_n_m_s);
}

const SITE: Site = Site {
    lat_rad: 0.6736970912698112,   // 38.6°
    lon_rad: -0.16231562043547265, // −9.3°
    declination_rad: 0.05,
};

fn ns(t_s: f64) -> u64 {
    (t_s * 1e9).round() as u64
}

/// At rest, level, heading north: the specific force of gravity.
fn imu(t_s: f64) -> AinsInput {
    AinsInput::Imu(Imu {
        stamp_ns: ns(t_s),
        interval_s: 0.01,
        gyro_rad_s: Vector::zeros(),
        accel_m_s2: Vector::new(0.0, 0.0, -9.8),
        mag_ut: Vector::new(20.0, 0.0, 40.0),
    })
}

fn gps(t_s: f64, lat_rad: f64) -> AinsInput {
    AinsInput::Gps(Gps {
        stamp_ns: ns(t_s),
        lat_rad,
        lon_rad: SITE.lon_rad,
        height_m: 0.0,
        horizontal_std_m: 2.5,
        quality: 1,
        velocity: None,
    })
}

fn ahrs(t_s: f64) -> AinsInput {
    AinsInput::Ahrs(Ahrs {
        stamp_ns: ns(t_s),
        roll_rad: 0.0,
        pitch_rad: 0.0,
        heading_mag_rad: -SITE.declination_rad + std::f64::consts::TAU,
    })
}

fn dvl(t_s: f64, v: [f64; 3]) -> AinsInput {
    AinsInput::Dvl(Dvl {
        stamp_ns: ns(t_s),
        velocity_body_m_s: Vector::from_array(v),
        altitude_m: 20.0,
        beams_valid: 0b1111,
        bottom_lock: true,
    })
}

fn feed(e: &mut Ekf, inputs: &[AinsInput]) -> Vec<Nav> {
    let mut out = Vec::new();
    for i in inputs {
        e.on_input(i, &mut out).expect("valid input");
    }
    out
}

/// A filter initialised at the site, at rest, heading true north.
fn started() -> Ekf {
    let mut e = Ekf::new(&EkfParams::default(), SITE).expect("valid");
    let out = feed(&mut e, &[ahrs(0.0), gps(0.0, SITE.lat_rad), imu(0.01)]);
    assert_eq!(out.len(), 1);
    e
}

#[test]
fn nothing_is_published_before_a_position_and_a_heading() {
    let mut e = Ekf::new(&EkfParams::default(), SITE).expect("valid");
    assert!(feed(&mut e, &[imu(0.01), imu(0.02)]).is_empty());
    assert!(
        feed(&mut e, &[ahrs(0.03), imu(0.04)]).is_empty(),
        "no position"
    );
    let out = feed(&mut e, &[gps(0.05, SITE.lat_rad), imu(0.06), imu(0.07)]);
    assert_eq!(out.len(), 2, "one per IMU sample from the first after both");
    let n = out[0];
    assert_eq!(n.stamp_ns, ns(0.06));
    assert!((n.lat_rad - SITE.lat_rad).abs() < 1e-12);
    // The AHRS's magnetic heading plus the declination: true north.
    let (_, _, yaw) = n.attitude.expect("attitude").euler();
    assert!(yaw.abs() < 1e-9, "{yaw}");
    assert!((n.pos_std_ned_m.x() - 2.5).abs() < 0.01);
    assert!(n.predicted_drift_m > 3.5 && n.predicted_drift_m < 3.6);
    assert!(n.aiding_mode & aiding::GPS != 0 && n.aiding_mode & aiding::DVL == 0);
    assert!(
        Ekf::new(
            &EkfParams {
                dvl_std_m_s: -1.0,
                ..Default::default()
            },
            SITE
        )
        .is_err()
    );
    assert!(
        Ekf::new(
            &EkfParams::default(),
            Site {
                lat_rad: 2.0,
                ..SITE
            }
        )
        .is_err()
    );
}

#[test]
fn bad_input_is_refused_and_the_state_kept() {
    let mut e = started();
    let before = e.snapshot().expect("snapshot");
    let bad = [
        AinsInput::Imu(Imu {
            interval_s: 0.0,
            ..match imu(1.0) {
                AinsInput::Imu(m) => m,
                _ => unreachable!(),
            }
        }),
        dvl(1.0, [20.0, 0.0, 0.0]),
        AinsInput::Depth(Depth {
            stamp_ns: ns(1.0),
            depth_m: 20_000.0,
        }),
        AinsInput::Gps(Gps {
            quality: 0,
            ..match gps(1.0, SITE.lat_rad) {
                AinsInput::Gps(g) => g,
                _ => unreachable!(),
            }
        }),
        AinsInput::Fix(Fix {
            stamp_ns: ns(1.0),
            lat_rad: SITE.lat_rad,
            lon_rad: SITE.lon_rad,
            std_north_m: 3.0,
            std_east_m: 3.0,
            corr_ne: 1.5,
            effective_particles: 100.0,
            source: 1,
        }),
        imu(0.0), // before the last stamp
    ];
    let mut out = Vec::new();
    for b in &bad {
        let r = e.on_input(b, &mut out);
        assert!(r.is_err(), "{b:?} accepted");
        assert!(out.is_empty());
        assert_eq!(e.snapshot().expect("snapshot"), before, "{b:?}");
    }
    assert!(feed(&mut e, &[imu(0.02)]).len() == 1, "goes on");
}

/// A DVL that says 2 m/s forward while the IMU says the vehicle is still:
/// refused by the gate `max_consecutive_rejections` times, then the next
/// one re-anchors the velocity; the counters say so.
#[test]
fn the_gate_cannot_lock_the_filter_out() {
    let mut e = started();
    let mut t = 0.01;
    let mut inputs = Vec::new();
    for k in 0..20 {
        t += 0.01;
        inputs.push(imu(t));
        if k % 2 == 0 {
            inputs.push(dvl(t, [0.0; 3]));
        }
    }
    feed(&mut e, &inputs);
    let s = e.stats().dvl;
    assert_eq!((s.used, s.rejected), (10, 0));
    let max = EkfParams::default().max_consecutive_rejections as u64;
    let mut out = Vec::new();
    for _ in 0..max {
        t += 0.01;
        out.extend(feed(&mut e, &[imu(t), dvl(t, [2.0, 0.0, 0.0])]));
    }
    let s = e.stats().dvl;
    assert_eq!(
        (s.rejected, s.reanchored, s.rejected_in_a_row as u64),
        (max, 0, max)
    );
    assert!(out.last().expect("out").vel_ned_m_s.x().abs() < 0.1);
    t += 0.01;
    let out = feed(&mut e, &[dvl(t, [2.0, 0.0, 0.0]), imu(t + 0.01)]);
    let s = e.stats().dvl;
    assert_eq!((s.reanchored, s.rejected_in_a_row), (1, 0));
    let v = out[0].vel_ned_m_s;
    assert!((v.x() - 2.0).abs() < 0.01, "re-anchored to the DVL: {v:?}");
    // A GPS fix 500 m off: gated, then re-anchored.
    let lat = SITE.lat_rad + 500.0 / 6_363_000.0;
    for _ in 0..max {
        t += 0.02;
        feed(&mut e, &[imu(t), gps(t, lat)]);
    }
    assert_eq!(e.stats().gps.rejected, max);
    t += 0.02;
    let out = feed(&mut e, &[gps(t, lat), imu(t + 0.01)]);
    assert_eq!(e.stats().gps.reanchored, 1);
    assert!((out[0].lat_rad - lat).abs() * 6.36e6 < 1.0);
}

/// A `positioning/fix` is used with `position_aiding` and ignored
/// without.
#[test]
fn fixes_are_used_only_with_position_aiding() {
    let fix = |t: f64| {
        AinsInput::Fix(Fix {
            stamp_ns: ns(t),
            lat_rad: SITE.lat_rad + 1.0 / 6_363_000.0,
            lon_rad: SITE.lon_rad,
            std_north_m: 1.0,
            std_east_m: 2.0,
            corr_ne: 0.3,
            effective_particles: 100.0,
            source: 1,
        })
    };
    let mut e = started();
    let out = feed(&mut e, &[fix(0.02), imu(0.03)]);
    assert_eq!(e.stats().fix.used, 1);
    assert!(out[0].aiding_mode & aiding::FIX != 0);
    assert!(out[0].pos_std_ned_m.x() < 1.0);
    let mut e = Ekf::new(&no_fix(), SITE).expect("valid");
    feed(&mut e, &[ahrs(0.0), gps(0.0, SITE.lat_rad), imu(0.01)]);
    let out = feed(&mut e, &[fix(0.02), imu(0.03)]);
    assert_eq!((e.stats().fix.used, e.stats().fix_ignored), (0, 1));
    assert!(out[0].aiding_mode & aiding::FIX == 0);
}

/// Run A to a stamp, snapshot it (it encodes into at most 2304 bytes and
/// goes through serde), restore it into B: both continue identically; and
/// two runs of the same inputs are identical.
#[test]
fn snapshot_fits_the_message_and_restores_bit_for_bit() {
    let scenario = ScenarioParams::default();
    let mut g = Generator::new(
        &scenario,
        Origin::lisbon(),
        scenario.sensors_preset(),
        7,
        400.0,
    )
    .expect("valid");
    let site = site(&g);
    let mut inputs = Vec::new();
    while let Some(s) = g.step() {
        harness::inputs(&s.expect("step"), None, &mut inputs);
    }
    let split = inputs.len() / 2;
    let mut a = Ekf::new(&no_fix(), site).expect("valid");
    let mut b = Ekf::new(&no_fix(), site).expect("valid");
    let mut out_a = Vec::new();
    for i in &inputs[..split] {
        a.on_input(i, &mut out_a).expect("valid");
    }
    let snap: EkfSnapshot = a.snapshot().expect("snapshot");
    let bytes = size::encoded_size(&snap);
    eprintln!("snapshot: {bytes} bytes");
    assert!(bytes <= 2304, "{bytes} bytes");
    let text = toml::to_string(&snap).expect("serialise");
    let back: EkfSnapshot = toml::from_str(&text).expect("deserialise");
    assert_eq!(back, snap);
    let stamp = inputs[split - 1].stamp_ns();
    b.restore(&back, stamp).expect("restore");
    let (mut ra, mut rb) = (Vec::new(), Vec::new());
    // Inputs up to the stamp (a repeat of the same stamp included) are skipped by B.
    for i in &inputs[split..] {
        a.on_input(i, &mut ra).expect("valid");
        b.on_input(i, &mut rb).expect("valid");
    }
    assert!(ra.len() > 10_000);
    let ra: Vec<_> = ra.into_iter().filter(|n| n.stamp_ns > stamp).collect();
    assert_eq!(ra, rb, "continues bit for bit");
    // Determinism: the same inputs again.
    let mut c = Ekf::new(&no_fix(), site).expect("valid");
    let mut rc = Vec::new();
    for i in &inputs {
        c.on_input(i, &mut rc).expect("valid");
    }
    assert_eq!(rc.last(), rb.last());
    // A broken snapshot is refused and the state kept.
    let mut bad = snap.clone();
    if let Some(f) = bad.filter.as_mut() {
        f.p_upper.pop();
    }
    let kept = c.snapshot();
    assert!(c.restore(&bad, stamp).is_err());
    assert_eq!(c.snapshot(), kept);
    let mut bad = snap;
    if let Some(f) = bad.filter.as_mut() {
        f.q_nb_wxyz[0] = f64::NAN;
    }
    assert!(c.restore(&bad, stamp).is_err());
}

/// The published attitude is the strapdown's: a unit quaternion.
#[test]
fn the_solution_carries_the_attitude() {
    let mut e = started();
    let out = feed(&mut e, &[imu(0.02)]);
    let q = out[0].attitude.expect("attitude");
    let _: Rotation<_, _> = q;
    assert!((q.as_nalgebra().norm() - 1.0).abs() < 1e-12);
}

/// `seconds` at rest from `t0`: IMU at 100 Hz, the AHRS at 10 Hz while
/// `ahrs_until` has not passed, the DVL at 5 Hz (locked or not), GPS at
/// `gps(t)` 1 Hz when Some.
fn rest(
    e: &mut Ekf,
    t0: f64,
    seconds: f64,
    ahrs_until: f64,
    lock: bool,
    gps_lat: impl Fn(f64) -> Option<f64>,
) -> Vec<Nav> {
    let mut inputs = Vec::new();
    for k in 1..=(seconds * 100.0).round() as u64 {
        let t = t0 + k as f64 * 0.01;
        if k % 10 == 0 && t <= ahrs_until {
            inputs.push(ahrs(t));
        }
        inputs.push(imu(t));
        if k % 20 == 0 {
            let AinsInput::Dvl(d) = dvl(t, [0.0; 3]) else {
                unreachable!()
            };
            inputs.push(AinsInput::Dvl(Dvl {
                bottom_lock: lock,
                beams_valid: if lock { 0b1111 } else { 0 },
                ..d
            }));
        }
        if k % 100 == 0
            && let Some(lat) = gps_lat(t)
        {
            inputs.push(gps(t, lat));
        }
    }
    feed(e, &inputs)
}

/// A GPS that never comes: `position_wait_s` (30 s) after the first IMU
/// sample with a heading the filter starts at the site, σ
/// `initial_position_std_m` (1 km), the `GPS` bit clear, and goes on
/// publishing; a warm restart keeps that state, and a late fix is an
/// ordinary update that brings the position and its σ in.
#[test]
fn without_a_gps_the_filter_starts_at_the_site_and_a_late_fix_takes_over() {
    let mut e = Ekf::new(&EkfParams::default(), SITE).expect("valid");
    assert!(feed(&mut e, &[ahrs(0.0)]).is_empty());
    assert!(rest(&mut e, 0.0, 29.99, 1e9, true, |_| None).is_empty());
    let out = rest(&mut e, 29.99, 60.0, 1e9, true, |_| None);
    assert_eq!(out.first().map(|n| n.stamp_ns), Some(ns(30.01)));
    let last = *out.last().expect("outputs");
    assert!(
        last.pos_std_ned_m.x() >= 1000.0 && last.pos_std_ned_m.y() >= 1000.0,
        "{last:?}"
    );
    assert_eq!(last.aiding_mode & aiding::GPS, 0);
    assert_ne!(last.aiding_mode & aiding::DVL, 0);
    let snap = e.snapshot().expect("snapshot");
    let mut restarted = Ekf::new(&EkfParams::default(), SITE).expect("valid");
    restarted.restore(&snap, last.stamp_ns).expect("restore");
    let north = SITE.lat_rad + 50.0 / 6_363_000.0;
    for est in [&mut e, &mut restarted] {
        let out = rest(est, 89.99, 5.0, 1e9, true, |_| Some(north));
        let n = *out.last().expect("outputs");
        assert!((n.lat_rad - north).abs() * 6.36e6 < 3.0, "{n:?}");
        assert!(n.pos_std_ned_m.x() < 3.0, "{n:?}");
        assert_ne!(n.aiding_mode & aiding::GPS, 0);
    }
}

/// The heading stops (here the AHRS, the only source): one solution per
/// IMU sample goes on, the `HEADING` bit clears after the aiding timeout,
/// and the yaw σ grows.
#[test]
fn when_the_heading_stops_the_solution_goes_on_and_says_so() {
    use nauta_estimation::ains::ekf::model::ATT;
    let yaw_var = |e: &Ekf| e.filter().expect("running").p[(ATT + 2, ATT + 2)];
    let mut e = started();
    let mut out = rest(&mut e, 0.01, 30.0, 30.0, true, |_| Some(SITE.lat_rad));
    let while_aided = yaw_var(&e);
    out.extend(rest(&mut e, 30.01, 30.0, 30.0, true, |_| {
        Some(SITE.lat_rad)
    }));
    assert_eq!(out.len(), 6000);
    let at = |t: f64| *out.iter().find(|n| n.stamp_ns >= ns(t)).expect("output");
    assert_ne!(at(29.0).aiding_mode & aiding::HEADING, 0);
    assert_eq!(at(40.0).aiding_mode & aiding::HEADING, 0);
    assert!(
        yaw_var(&e) > 1.2 * while_aided,
        "yaw σ {} rad then {} rad",
        while_aided.sqrt(),
        yaw_var(&e).sqrt()
    );
}

/// A DVL that never locks: free inertial, the `DVL` bit clear, the
/// velocity σ growing, one solution per IMU sample.
#[test]
fn a_dvl_that_never_locks_leaves_free_inertial_and_an_honest_sigma() {
    let mut e = Ekf::new(&EkfParams::default(), SITE).expect("valid");
    feed(&mut e, &[ahrs(0.0), gps(0.0, SITE.lat_rad)]);
    let out = rest(&mut e, 0.0, 60.0, 1e9, false, |_| None);
    assert_eq!(out.len(), 6000);
    assert!(out.iter().all(|n| n.aiding_mode & aiding::DVL == 0));
    assert!(e.stats().dvl_no_lock >= 299, "{:?}", e.stats());
    let sigma: Vec<f64> = out
        .iter()
        .step_by(1000)
        .map(|n| n.vel_std_ned_m_s.x())
        .collect();
    assert!(
        sigma.windows(2).all(|w| w[1] > w[0]),
        "the velocity σ grows: {sigma:?}"
    );
}
