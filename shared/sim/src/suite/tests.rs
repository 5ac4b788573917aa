//! Tests of the sensor suite.

use std::sync::OnceLock;

use super::*;
use crate::environment::{Environment, MagneticField};
use crate::mission::{self, Mission, Origin, SurveySpec};
use crate::noise::DepthSpec;
use crate::trajectory::{ImuSample, SimConfig, Simulator, Truth};

type Steps = Vec<(Truth, ImuSample)>;

fn env(origin: Origin) -> Environment {
    Environment::at(origin.lat_rad, origin.lon_rad, 2026, 182).expect("wmm")
}

fn record(mission: Mission, env: Environment, seconds: f64) -> Steps {
    let mut sim = Simulator::new(
        mission,
        env,
        SimConfig {
            seed: 7,
            ..SimConfig::default()
        },
    )
    .expect("simulator");
    let n = (seconds * 100.0).round() as usize;
    (0..n).map(|_| sim.step()).collect()
}

/// Ten minutes of the survey (dive from the surface, first transect).
fn survey_steps() -> &'static Steps {
    static S: OnceLock<Steps> = OnceLock::new();
    S.get_or_init(|| {
        let o = Origin::lisbon();
        record(mission::survey(o, &SurveySpec::default()), env(o), 600.0)
    })
}

/// Five minutes of the LBL mission.
fn lbl_steps() -> &'static Steps {
    static S: OnceLock<Steps> = OnceLock::new();
    S.get_or_init(|| {
        let o = Origin::lisbon();
        record(mission::lbl(o, 1), env(o), 300.0)
    })
}

fn run(config: SuiteConfig, seed: u64, steps: &[(Truth, ImuSample)]) -> Vec<Measurements> {
    let o = Origin::lisbon();
    let mut suite = SensorSuite::new(config, seed, o, &env(o)).expect("suite");
    steps
        .iter()
        .map(|(t, i)| suite.step(t, i).expect("step"))
        .collect()
}

fn count<T>(m: &[Measurements], f: impl Fn(&Measurements) -> Option<T>) -> usize {
    m.iter().filter_map(f).count()
}

#[test]
fn rates_over_ten_minutes() {
    let steps = survey_steps();
    let m = run(SuiteConfig::survey(), 1, steps);
    assert_eq!(count(&m, |x| x.imu), 60_000);
    assert_eq!(count(&m, |x| x.ahrs), 6_000);
    assert_eq!(count(&m, |x| x.depth), 6_000);
    assert_eq!(count(&m, |x| x.propeller), 6_000);
    assert_eq!(count(&m, |x| x.dvl), 3_000);
    // 20 broadcasts at 30 s intervals; ~10 % lost.
    let modem = count(&m, |x| x.modem);
    assert!((12..=20).contains(&modem), "{modem}");
    // Stamps fall on the configured grid.
    for x in &m {
        if x.ahrs.is_some() {
            assert_eq!(x.stamp_ns % 100_000_000, 0);
        }
        if x.dvl.is_some() {
            assert_eq!(x.stamp_ns % 200_000_000, 0);
        }
    }
    // GPS only at the surface, at 1 Hz while there.
    let gps: Vec<_> = m.iter().filter(|x| x.gps.is_some()).collect();
    assert!(!gps.is_empty());
    for x in &gps {
        assert!(x.truth.depth_m < 0.3);
        assert_eq!(x.stamp_ns % 1_000_000_000, 0);
    }
    let surfaced_seconds = m
        .iter()
        .filter(|x| x.stamp_ns % 1_000_000_000 == 0 && x.truth.depth_m < 0.3)
        .count();
    assert_eq!(gps.len(), surfaced_seconds);
    assert!(gps.len() < 60, "{}", gps.len());
    // The receiver's velocity (`GpsFix.v2`): the truth's, with the
    // configured noise.
    let sigma = SuiteConfig::survey().gps.velocity_sigma_m_s;
    let errors: Vec<f64> = gps
        .iter()
        .filter_map(|x| {
            let g = x.gps?;
            assert_eq!(g.vel_std_m_s, sigma);
            Some((0..3).map(move |i| g.vel_ned_m_s[i] - x.truth.vel_ned_m_s[i]))
        })
        .flatten()
        .collect();
    let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    assert!(
        (0.5 * sigma..2.0 * sigma).contains(&rms),
        "velocity error RMS {rms} against σ {sigma} over {} values",
        errors.len()
    );
    // Default seafloor: lock throughout except dropouts.
    for d in m.iter().filter_map(|x| x.dvl) {
        let locked = matches!(d.event, DvlEvent::Valid | DvlEvent::Spike { .. });
        assert_eq!(d.bottom_lock == 1, locked);
        assert_eq!(d.beams_valid == 0b1111, locked);
        assert_ne!(d.event, DvlEvent::OutOfRange);
    }
}

#[test]
fn dvl_lock_lost_above_the_altitude_limit() {
    let steps = survey_steps();
    let mut c = SuiteConfig::survey().noise_free();
    c.dvl.seafloor_depth_m = 100.0;
    c.dvl.max_altitude_m = 90.0;
    let m = run(c, 1, steps);
    let (mut locked, mut lost) = (0, 0);
    for x in &m {
        let Some(d) = x.dvl else { continue };
        let altitude = 100.0 - x.truth.depth_m;
        if altitude > 90.0 {
            lost += 1;
            assert_eq!(d.bottom_lock, 0);
            assert_eq!(d.beams_valid, 0);
            assert_eq!(d.event, DvlEvent::OutOfRange);
        } else {
            locked += 1;
            assert_eq!(d.bottom_lock, 1);
            assert_eq!(d.altitude_m, altitude);
            // Noise-free: the truth velocity in body axes.
            let (t, _) = steps
                .iter()
                .find(|(t, _)| stamp_ns(t.t_s) == x.stamp_ns)
                .expect("step");
            let v = t.q_nb.inverse_transform_vector(&t.v_ned_m_s);
            let got = Vector3::from(d.velocity_body_m_s);
            assert!((got - v).norm() < 1e-12);
        }
    }
    assert!(locked > 1000 && lost > 10, "{locked} {lost}");
}

fn sensor_view(m: &[Measurements]) -> Vec<(Option<AhrsReading>, Option<DepthReading>)> {
    m.iter().map(|x| (x.ahrs, x.depth)).collect()
}

#[test]
fn deterministic_and_sensors_independent() {
    let steps = &survey_steps()[..30_000];
    let a = run(SuiteConfig::survey(), 42, steps);
    let b = run(SuiteConfig::survey(), 42, steps);
    assert_eq!(a, b);
    let c = run(SuiteConfig::survey(), 43, steps);
    assert_ne!(sensor_view(&a), sensor_view(&c));

    // Disable the DVL and the modem, change the gyro and the GPS: AHRS, depth,
    // propeller, accelerometer and magnetometer draw the same numbers.
    let mut other = SuiteConfig::survey();
    other.dvl.enabled = false;
    other.modem.enabled = false;
    other.imu.gyro.noise_density *= 3.0;
    other.gps.horizontal_sigma_m = 10.0;
    let d = run(other, 42, steps);
    assert_eq!(sensor_view(&a), sensor_view(&d));
    for (x, y) in a.iter().zip(&d) {
        assert_eq!(x.propeller, y.propeller);
        assert!(y.dvl.is_none() && y.modem.is_none());
        let (xi, yi) = (x.imu.expect("imu"), y.imu.expect("imu"));
        assert_eq!(xi.accel_m_s2, yi.accel_m_s2);
        assert_eq!(xi.mag_ut, yi.mag_ut);
    }
    // Turning LBL on does not change the DVL or modem.
    let mut with_lbl = SuiteConfig::survey();
    with_lbl.lbl.enabled = true;
    let e = run(with_lbl, 42, steps);
    for (x, y) in a.iter().zip(&e) {
        assert_eq!(x.dvl, y.dvl);
        assert_eq!(x.modem, y.modem);
    }
}

#[test]
fn noise_free_reproduces_truth() {
    let steps = &survey_steps()[..20_000];
    let m = run(SuiteConfig::survey().noise_free(), 5, steps);
    for (x, (t, imu)) in m.iter().zip(steps) {
        let r = x.imu.expect("imu");
        assert_eq!(r.gyro_rad_s, <[f64; 3]>::from(imu.gyro_rad_s));
        assert_eq!(r.accel_m_s2, <[f64; 3]>::from(imu.accel_m_s2));
        assert_eq!(r.mag_ut, <[f64; 3]>::from(imu.mag_t * 1e6));
        assert_eq!(r.interval_s, imu.dt_s);
        assert_eq!(r.stamp_ns, stamp_ns(t.t_s));
        if let Some(d) = x.depth {
            assert_eq!(d.depth_m, t.depth_m);
        }
        if let Some(p) = x.propeller {
            assert_eq!(p.shaft_speed_rad_s, t.propeller_rad_s);
        }
        if let Some(g) = x.gps {
            assert_eq!((g.lat_rad, g.lon_rad), (t.lat_rad, t.lon_rad));
            assert_eq!(g.vel_ned_m_s, <[f64; 3]>::from(t.v_ned_m_s));
            assert_eq!(g.vel_std_m_s, 0.0);
        }
        assert_eq!(x.truth, TruthReading::from_truth(t));
    }
}

#[test]
fn ahrs_heading_is_magnetic() {
    let o = Origin::lisbon();
    let mut e = env(o);
    let decl = 10f64.to_radians();
    e.magnetic = MagneticField::from_angles(45e-6, decl, 55f64.to_radians());
    let steps = record(mission::survey(o, &SurveySpec::default()), e, 120.0);
    let go = |c: SuiteConfig| -> Vec<Measurements> {
        let mut s = SensorSuite::new(c, 3, o, &e).expect("suite");
        steps
            .iter()
            .map(|(t, i)| s.step(t, i).expect("step"))
            .collect()
    };
    let wrap = nauta_estimation::attitude::wrap_pi;
    for x in go(SuiteConfig::survey().noise_free()) {
        let Some(a) = x.ahrs else { continue };
        let q = Rotation::<Frd, Ned>::from_wxyz(x.truth.quat_nb).expect("unit truth");
        let (r, p, y) = q.euler();
        assert!((0.0..TAU).contains(&a.heading_mag_rad));
        assert!(wrap(a.heading_mag_rad - (y - decl)).abs() < 1e-12);
        assert!((a.roll_rad - r).abs() < 1e-12 && (a.pitch_rad - p).abs() < 1e-12);
    }
    // With noise: heading error w.r.t. magnetic heading stays within the
    // bias + white noise envelope, far from the 10° declination.
    let mut errs = Vec::new();
    for x in go(SuiteConfig::survey()) {
        let Some(a) = x.ahrs else { continue };
        let q = Rotation::<Frd, Ned>::from_wxyz(x.truth.quat_nb).expect("unit truth");
        let (_, _, y) = q.euler();
        errs.push(wrap(a.heading_mag_rad - (y - decl)));
    }
    let (mean, std) = crate::noise::mean_std(&errs);
    assert!(mean.abs() < 8f64.to_radians(), "{mean}");
    assert!(
        (std - 1f64.to_radians()).abs() < 0.3f64.to_radians(),
        "{std}"
    );
}

/// Vehicle (north, east, depth) at `stamp` by linear interpolation of the steps.
fn vehicle_at(steps: &[(Truth, ImuSample)], stamp: u64) -> Vector3<f64> {
    let t = seconds(stamp);
    let k = steps
        .iter()
        .position(|(s, _)| s.t_s >= t)
        .expect("inside the run");
    if k == 0 {
        return position(&steps[0].0);
    }
    let (a, b) = (&steps[k - 1].0, &steps[k].0);
    let f = (t - a.t_s) / (b.t_s - a.t_s);
    position(a) + (position(b) - position(a)) * f
}

#[test]
fn buoy_time_of_flight_matches_geometry() {
    let steps = survey_steps();
    let o = Origin::lisbon();
    let mut s = SensorSuite::new(SuiteConfig::survey().noise_free(), 9, o, &env(o)).expect("suite");
    let c = s.sound_speed_m_s();
    assert!((1500.0..1515.0).contains(&c), "{c}");
    let mut n = 0;
    for (t, i) in steps {
        let m = s.step(t, i).expect("step");
        let Some(b) = m.modem else { continue };
        n += 1;
        assert!(b.stamp_ns <= m.stamp_ns && m.stamp_ns - b.stamp_ns < 10_000_000);
        assert_eq!(b.send_stamp_ns % 30_000_000_000, 0);
        // Noise free: broadcast position = true buoy; reported c = true c.
        let (bn, be) = o.to_local(b.buoy_lat_rad, b.buoy_lon_rad);
        let buoy = Vector3::new(bn, be, b.buoy_depth_m);
        assert!((bn - b.true_buoy_north_east_m[0]).abs() < 1e-6);
        assert!((be - b.true_buoy_north_east_m[1]).abs() < 1e-6);
        assert_eq!(b.sound_speed_m_s, c);
        let expect_n = 300.0 + 0.02 * seconds(b.send_stamp_ns);
        assert!((bn - expect_n).abs() < 1e-6);
        // TOF × c = distance from the buoy at send to the vehicle at reception.
        let range = (vehicle_at(steps, b.stamp_ns) - buoy).norm();
        assert!((b.time_of_flight_s * c - range).abs() < 2e-3, "{range}");
        assert!((seconds(b.stamp_ns) - seconds(b.send_stamp_ns) - b.time_of_flight_s).abs() < 1e-6);
    }
    // 20 broadcasts; the one sent at the last step (600 s) is still in flight.
    assert_eq!(s.stats().modem_sent, 20);
    assert_eq!(n, 19);

    // With noise: TOF = range / c + jitter (1 ms), reported c off by 0.3 %.
    let m = run(SuiteConfig::survey(), 9, steps);
    for b in m.iter().filter_map(|x| x.modem) {
        assert!((b.time_of_flight_s - b.true_range_m / c).abs() < 5e-3);
        assert!((b.sound_speed_m_s / c - 1.003).abs() < 1e-12);
    }
}

/// Multipath on the modem (issue 14): a share of the messages comes with
/// the extra travel time in [δ_lo, δ_hi]; the others, and the losses, are
/// those of the run without (the outliers have their own random stream).
#[test]
fn modem_multipath_outliers_have_their_own_stream() {
    let steps = survey_steps();
    let clean = run(SuiteConfig::survey(), 9, steps);
    let mut config = SuiteConfig::survey();
    config.modem.noise.multipath_probability = 0.5;
    let mp = run(config.clone(), 9, steps);
    let o = Origin::lisbon();
    let mut s = SensorSuite::new(config, 9, o, &env(o)).expect("suite");
    for (t, i) in steps {
        s.step(t, i).expect("step");
    }
    let c = s.sound_speed_m_s();
    let a: Vec<_> = clean.iter().filter_map(|m| m.modem).collect();
    let b: Vec<_> = mp.iter().filter_map(|m| m.modem).collect();
    assert_eq!(a.len(), b.len(), "the same messages arrive");
    let mut late = 0;
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.send_stamp_ns, y.send_stamp_ns);
        let extra = y.time_of_flight_s - x.time_of_flight_s;
        if extra == 0.0 {
            continue;
        }
        late += 1;
        assert!(
            (0.0133..=0.133).contains(&extra),
            "extra travel time {extra} s ({} m)",
            extra * c
        );
    }
    assert_eq!(late as u64, s.stats().modem_multipath);
    assert!(late > 0 && late < a.len(), "{late} of {} late", a.len());
}

/// (ask log (id, stamp), replies with their delivery stamp, the steps).
type ClosedLoop = (Vec<(u32, u64)>, Vec<(LblReplyReading, u64)>, &'static Steps);

/// A navigator loop: pings the transponders round robin, the next one right
/// after each reply or after a 3 s timeout. Returns (ask log, replies, steps).
fn lbl_closed_loop(config: SuiteConfig, seed: u64) -> ClosedLoop {
    let steps = lbl_steps();
    let o = Origin::lisbon();
    let ids: Vec<u32> = config.lbl.transponders.iter().map(|t| t.id).collect();
    let mut s = SensorSuite::new(config, seed, o, &env(o)).expect("suite");
    let mut asked = Vec::new();
    let mut replies = Vec::new();
    let mut next = 0;
    let mut last_ping: Option<u64> = None;
    for (t, i) in steps {
        let m = s.step(t, i).expect("step");
        let got_reply = !m.lbl.is_empty();
        for r in m.lbl {
            replies.push((r, m.stamp_ns));
        }
        let timeout = last_ping.is_none_or(|p| m.stamp_ns - p >= 3_000_000_000);
        if got_reply || timeout {
            let id = ids[next % ids.len()];
            next += 1;
            s.interrogate(id, m.stamp_ns).expect("interrogate");
            asked.push((id, m.stamp_ns));
            last_ping = Some(m.stamp_ns);
        }
    }
    (asked, replies, steps)
}

/// With the detection jitter, a reply is delivered at the step that holds
/// its stamp: never stamped before the previous step (which the sensor may
/// already have covered with a watermark), never after its own.
#[test]
fn jittered_replies_are_delivered_at_their_stamp() {
    let config = SuiteConfig::lbl(LblLayout::Two);
    assert!(config.lbl.noise.timing_jitter_sigma > 0.0);
    let (_, replies, _) = lbl_closed_loop(config, 6);
    assert!(replies.len() > 100);
    for (r, delivered) in &replies {
        assert!(r.stamp_ns <= *delivered, "{r:?} at {delivered}");
        assert!(
            r.stamp_ns + 10_000_000 >= *delivered,
            "{r:?} at {delivered}"
        );
    }
}

/// A blackout window loses exactly the replies heard in it: the same
/// pings outside it give the same replies, bit for bit.
#[test]
fn an_lbl_blackout_loses_only_its_replies() {
    let config = SuiteConfig::lbl(LblLayout::Two);
    let (_, all, _) = lbl_closed_loop(config.clone(), 5);
    let mut dark = config;
    dark.lbl.blackout_s = Some([60.0, 120.0]);
    let steps = lbl_steps();
    let o = Origin::lisbon();
    // Ping as the run without blackout did, so that both ask the same.
    let (asked, _, _) = lbl_closed_loop(SuiteConfig::lbl(LblLayout::Two), 5);
    let mut s = SensorSuite::new(dark, 5, o, &env(o)).expect("suite");
    let mut got = Vec::new();
    let mut k = 0;
    for (t, i) in steps {
        let m = s.step(t, i).expect("step");
        got.extend(m.lbl.iter().map(|r| (*r, m.stamp_ns)));
        while k < asked.len() && asked[k].1 == m.stamp_ns {
            s.interrogate(asked[k].0, asked[k].1).expect("interrogate");
            k += 1;
        }
    }
    let inside = |r: &LblReplyReading| (60e9..=120e9).contains(&(r.stamp_ns as f64));
    let outside: Vec<_> = all.iter().filter(|(r, _)| !inside(r)).collect();
    assert!(got.iter().all(|(r, _)| !inside(r)));
    assert_eq!(got.len(), outside.len());
    for ((a, _), (b, _)) in got.iter().zip(outside) {
        assert_eq!(a, b);
    }
    assert!(s.stats().lbl_blackout > 20, "{:?}", s.stats());
}

#[test]
fn lbl_closed_loop_round_trips() {
    let mut config = SuiteConfig::lbl(LblLayout::Four);
    config.lbl.noise.multipath_probability = 0.0;
    // The physics and the clock alone (the detection jitter has its own test).
    config.lbl.noise.timing_jitter_sigma = 0.0;
    let tx = config.lbl.transponders.clone();
    let spec = config.lbl.noise;
    let (asked, replies, steps) = lbl_closed_loop(config, 11);
    assert!(replies.len() > 100, "{}", replies.len());
    let c = {
        let o = Origin::lisbon();
        SensorSuite::new(SuiteConfig::lbl(LblLayout::Four), 0, o, &env(o))
            .expect("suite")
            .sound_speed_m_s()
    };
    let v_max = 2.0; // m/s, over ground, bounds the vehicle's motion
    for (r, delivered) in &replies {
        // Only the asked transponder replies, once per interrogation.
        let (id, _) = asked
            .iter()
            .find(|(_, s)| *s == r.interrogation_stamp_ns)
            .expect("asked");
        assert_eq!(*id, r.transponder_id);
        assert!(!r.multipath);
        assert_eq!(r.stamp_ns, r.reply_stamp_ns);
        // Delivered at the step where the wavefront arrives: within one step
        // (plus one clock tick, the quantisation) after the reply stamp.
        assert!(
            *delivered >= r.reply_stamp_ns && *delivered - r.reply_stamp_ns < 10_100_000,
            "{delivered} {}",
            r.reply_stamp_ns
        );
        let ticks = (r.round_trip_s / spec.clock_resolution).round();
        assert!((r.round_trip_s - ticks * spec.clock_resolution).abs() < 1e-12);
        assert_eq!(
            r.reply_stamp_ns - r.interrogation_stamp_ns,
            (ticks as u64) * 100_000
        );
        // Quantised down by less than one tick.
        let q = r.true_round_trip_s - r.round_trip_s;
        assert!((-1e-9..1e-4 + 1e-9).contains(&q), "{q}");
        // 2 r(send)/c + t_ta within 100 µs plus the motion during the round trip.
        let t = tx
            .iter()
            .find(|t| t.id == r.transponder_id)
            .expect("transponder");
        let p = vehicle_at(steps, r.interrogation_stamp_ns);
        let range = (Vector3::new(t.north_m, t.east_m, t.depth_m) - p).norm();
        let predicted = 2.0 * range / c + t.turnaround_s;
        let bound = 1e-4 + v_max * r.round_trip_s / c + 1e-9;
        assert!(
            (r.round_trip_s - predicted).abs() <= bound,
            "{} vs {predicted}",
            r.round_trip_s
        );
    }
    // Every transponder was asked and answered.
    for t in &tx {
        assert!(replies.iter().any(|(r, _)| r.transponder_id == t.id));
    }
}

#[test]
fn lbl_multipath_replies_are_later() {
    let mut config = SuiteConfig::lbl(LblLayout::Two);
    config.lbl.noise.multipath_probability = 0.5;
    // The delays alone, without the detection jitter.
    config.lbl.noise.timing_jitter_sigma = 0.0;
    let spec = config.lbl.noise;
    let (_, replies, _) = lbl_closed_loop(config, 12);
    let multipath: Vec<_> = replies.iter().filter(|(r, _)| r.multipath).collect();
    let direct: Vec<_> = replies.iter().filter(|(r, _)| !r.multipath).collect();
    assert!(multipath.len() > 20 && direct.len() > 20);
    for (r, _) in &multipath {
        let late = r.round_trip_s - r.true_round_trip_s;
        assert!(
            late >= spec.multipath_delay[0] - spec.clock_resolution,
            "{late}"
        );
        assert!(late <= spec.multipath_delay[1] + 1e-9, "{late}");
    }
    for (r, _) in &direct {
        assert!(r.true_round_trip_s - r.round_trip_s < spec.clock_resolution + 1e-9);
    }
}

#[test]
fn lbl_only_asked_transponder_and_errors() {
    let steps = lbl_steps();
    let o = Origin::lisbon();
    let mut s = SensorSuite::new(
        SuiteConfig::lbl(LblLayout::Four).noise_free(),
        1,
        o,
        &env(o),
    )
    .expect("suite");
    assert_eq!(s.interrogate(9, 0), Err(SuiteError::UnknownTransponder(9)));
    s.interrogate(3, 1_000_000_000).expect("ping");
    let mut got = Vec::new();
    for (t, i) in &steps[..1_000] {
        got.extend(s.step(t, i).expect("step").lbl);
    }
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].transponder_id, 3);
    assert_eq!(got[0].interrogation_stamp_ns, 1_000_000_000);
    assert_eq!(s.pending_interrogations(), 0);

    let mut off = SensorSuite::new(SuiteConfig::survey(), 1, o, &env(o)).expect("suite");
    assert_eq!(off.interrogate(1, 0), Err(SuiteError::LblDisabled));
}

#[test]
fn presets_and_serde() {
    for c in [
        SuiteConfig::survey(),
        SuiteConfig::lbl(LblLayout::Two),
        SuiteConfig::lbl(LblLayout::Four),
        SuiteConfig::dr(),
        SuiteConfig::survey().noise_free(),
    ] {
        c.validate().expect("valid preset");
    }
    assert!(SuiteConfig::survey().modem.enabled && !SuiteConfig::survey().lbl.enabled);
    let l = SuiteConfig::lbl(LblLayout::Four);
    assert!(l.lbl.enabled && !l.dvl.enabled && l.lbl.transponders.len() == 4);
    assert!(!SuiteConfig::dr().modem.enabled && SuiteConfig::dr().dvl.enabled);
    // Paper 003: a 600 m baseline.
    let t = LblLayout::Two.transponders();
    assert!(((t[0].north_m - t[1].north_m).hypot(t[0].east_m - t[1].east_m) - 600.0).abs() < 1e-9);

    let mut bad = SuiteConfig::survey();
    bad.ahrs.rate_hz = 0.0;
    assert!(bad.validate().is_err());
    let mut dup = SuiteConfig::lbl(LblLayout::Two);
    dup.lbl.transponders[1].id = 1;
    assert_eq!(
        dup.validate(),
        Err(SuiteError::Layout(
            nauta_estimation::lbl::LayoutError::DuplicateId(1)
        ))
    );
    let mut on_top = SuiteConfig::lbl(LblLayout::Two);
    on_top.lbl.transponders[1].north_m = on_top.lbl.transponders[0].north_m;
    on_top.lbl.transponders[1].east_m = on_top.lbl.transponders[0].east_m + 0.5;
    let e = on_top.validate().expect_err("coincident");
    assert!(
        e.to_string().contains("cannot tell a position apart"),
        "{e}"
    );
    let mut bad_window = SuiteConfig::lbl(LblLayout::Two);
    bad_window.lbl.blackout_s = Some([100.0, 50.0]);
    assert!(bad_window.validate().is_err());

    use serde::Deserialize;
    use serde::de::value::{Error, MapDeserializer};
    let empty = MapDeserializer::<_, Error>::new(std::iter::empty::<(&str, f64)>());
    assert_eq!(
        SuiteConfig::deserialize(empty).expect("defaults"),
        SuiteConfig::default()
    );
    let unknown = MapDeserializer::<_, Error>::new([("bogus", 1.0)].into_iter());
    assert!(SuiteConfig::deserialize(unknown).is_err());
    let ahrs = MapDeserializer::<_, Error>::new([("rate_hz", 20.0)].into_iter());
    let a = AhrsConfig::deserialize(ahrs).expect("partial");
    assert_eq!(a.rate_hz, 20.0);
    assert_eq!(a.heading_bias_time_s, 600.0);
    let typo = MapDeserializer::<_, Error>::new([("rate", 20.0)].into_iter());
    assert!(AhrsConfig::deserialize(typo).is_err());
    // Inside a nested noise table too (the specs refuse unknown keys themselves).
    let depth = DepthSpec::default();
    let ok = MapDeserializer::<_, Error>::new(
        [("noise_sigma", depth.noise_sigma), ("offset", depth.offset)].into_iter(),
    );
    assert_eq!(DepthSpec::deserialize(ok).expect("complete"), depth);
    let nested_typo = MapDeserializer::<_, Error>::new(
        [("noise_sigma", 0.02), ("offset", 0.0), ("ofset", 0.1)].into_iter(),
    );
    assert!(DepthSpec::deserialize(nested_typo).is_err());
}
