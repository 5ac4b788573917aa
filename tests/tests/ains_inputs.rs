//! Issue 13: bad input at each of the aided INS's seven inputs (IMU, DVL,
//! depth, GPS, AHRS, `attitude/estimate`, `positioning/fix`) is refused and
//! counted by the real `nauta-ains`, and changes nothing it publishes.
//!
//! The test is every publisher the ains listens to: the simulator's sensor
//! messages of paper 002's manoeuvre 1 (its first 90 s), an attitude estimate
//! per IMU sample and a position fix every 10 s, both from the truth. Each
//! test inserts three bad messages into one input (a non-finite value, a
//! value out of its physical range, a stamp earlier than that input's last)
//! and compares the run with a clean one: the same solutions bit for bit,
//! and three more refusals in the ains's health. Every run has its own
//! namespace and a watchdog.

use std::sync::OnceLock;
use std::time::Duration;

use nauta_messages::{
    AttitudeEstimate, Header, Health, NavSolution, PositionFix, Progress, Role, SensorMessage,
    event_kind, fixed_str, state,
};
use nauta_runtime::context::{Context, ContextSettings};
use nauta_runtime::{Namespace, services};
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
use nauta_tests::*;

const BOUND: Duration = Duration::from_secs(240);

/// Mission seconds fed to the ains.
const MISSION_S: f64 = 90.0;

/// Simulator steps (0.01 s each) published between two watermarks.
const BATCH_STEPS: usize = 25;

/// One message of one of the ains's inputs.
#[derive(Debug, Clone, Copy)]
enum Msg {
    Sensor(SensorMessage),
    Attitude(AttitudeEstimate),
    Fix(PositionFix),
}

impl Msg {
    fn stamp_ns(&self) -> u64 {
        match self {
            Msg::Sensor(m) => m.header().stamp_ns,
            Msg::Attitude(m) => m.header.stamp_ns,
            Msg::Fix(m) => m.header.stamp_ns,
        }
    }

    fn header_mut(&mut self) -> &mut Header {
        match self {
            Msg::Sensor(m) => m.header_mut(),
            Msg::Attitude(m) => &mut m.header,
            Msg::Fix(m) => &mut m.header,
        }
    }
}

/// The clean feed, one simulator step per inner list.
fn clean_feed() -> Vec<Vec<Msg>> {
    let scenario = ScenarioParams {
        scenario: ScenarioKind::Dr,
        dr_manoeuvre: 1,
        ..Default::default()
    };
    let mut g = Generator::new(
        &scenario,
        Origin::lisbon(),
        scenario.sensors_preset(),
        7,
        MISSION_S,
    )
    .expect("the dr scenario");
    let (mut steps, mut wire) = (Vec::new(), Vec::new());
    let mut next_fix_ns = 10_000_000_000;
    while let Some(step) = g.step() {
        let step = step.expect("a simulator step");
        wire.clear();
        nauta_sim::wire::to_wire(&step, &mut wire);
        let mut msgs = Vec::new();
        let mut truth = None;
        for m in &wire {
            match m {
                SensorMessage::Truth(t) => truth = Some(*t),
                SensorMessage::Imu(_)
                | SensorMessage::Dvl(_)
                | SensorMessage::Depth(_)
                | SensorMessage::Gps(_)
                | SensorMessage::Ahrs(_) => msgs.push(Msg::Sensor(*m)),
                _ => {}
            }
        }
        let imu_stamp = wire.iter().find_map(|m| match m {
            SensorMessage::Imu(i) => Some(i.header.stamp_ns),
            _ => None,
        });
        if let (Some(t), Some(stamp)) = (truth, imu_stamp) {
            msgs.push(Msg::Attitude(AttitudeEstimate {
                header: Header::new(stamp, 0, Role::Attitude, 0),
                quat_nb: t.quat_nb,
                std_rad: [0.002, 0.002, 0.01],
                ..Default::default()
            }));
            if stamp >= next_fix_ns {
                next_fix_ns += 10_000_000_000;
                msgs.push(Msg::Fix(PositionFix {
                    header: Header::new(stamp, 0, Role::Positioning, 0),
                    lat_rad: t.lat_rad,
                    lon_rad: t.lon_rad,
                    std_north_m: 2.0,
                    std_east_m: 2.0,
                    effective_particles: 100.0,
                    fix_source: 1,
                    ..Default::default()
                }));
            }
        }
        steps.push(msgs);
    }
    steps
}

/// What a run of the ains gave: its solutions and its last health.
struct Outcome {
    nav: Vec<NavSolution>,
    health: Health,
    /// The process's log (standard error).
    log: String,
}

/// What the test has seen of the ains so far.
#[derive(Default)]
struct Seen {
    nav: Vec<NavSolution>,
    health: Option<Health>,
    watermark: u64,
    ended: bool,
}

fn ctx(ns: &Namespace, role: Role, process: &str) -> Context {
    Context::new(
        ns,
        ContextSettings {
            process: process.into(),
            ..Context::settings(role)
        },
    )
    .expect("a context")
}

/// Runs `nauta-ains` (variant `variant` of `launch/dr.toml`) on `feed`.
fn run(wd: &Watchdog, variant: &str, feed: &[Vec<Msg>]) -> Outcome {
    let ns = Namespace::unique();
    let sensor = ctx(&ns, Role::Sensor, "sensor");
    let attitude = ctx(&ns, Role::Attitude, "attitude");
    let positioning = ctx(&ns, Role::Positioning, "positioning");
    let test = ctx(&ns, Role::Test, "test");
    let (mut events, _events_inbox) = test.subscriber(&services::run_events()).expect("events");
    let (mut nav_sub, _nav_inbox) = test.subscriber(&services::nav_solution()).expect("nav");
    let (mut health_sub, _health_inbox) = test
        .subscriber(&services::health(Role::Ains))
        .expect("health");
    let (mut progress_sub, _progress_inbox) = test
        .subscriber(&services::progress(Role::Ains))
        .expect("progress");
    let mut imu = sensor.publisher(&services::imu()).expect("imu");
    let mut dvl = sensor.publisher(&services::dvl()).expect("dvl");
    let mut depth = sensor.publisher(&services::depth()).expect("depth");
    let mut gps = sensor.publisher(&services::gps()).expect("gps");
    let mut ahrs = sensor.publisher(&services::ahrs()).expect("ahrs");
    let mut sensor_progress = sensor
        .publisher(&services::progress(Role::Sensor))
        .expect("sensor progress");
    let mut att = attitude
        .publisher(&services::attitude_estimate())
        .expect("attitude");
    let mut att_progress = attitude
        .publisher(&services::progress(Role::Attitude))
        .expect("attitude progress");
    let mut fix = positioning
        .publisher(&services::position_fix())
        .expect("fix");
    let mut fix_progress = positioning
        .publisher(&services::progress(Role::Positioning))
        .expect("fix progress");
    let manifest = workspace_root().join("launch").join("dr.toml");
    let manifest = manifest.to_str().expect("a UTF-8 path");
    let mut child = Running::spawn(
        wd,
        &bin("nauta-ains"),
        &[
            "--manifest",
            manifest,
            "--process",
            "ains",
            "--namespace",
            ns.as_str(),
            "--variant",
            variant,
        ],
        None,
    );
    // Ready once it has subscribed to all seven inputs.
    let ready = wait_until(wd, Duration::from_secs(60), || {
        let mut ready = false;
        events
            .drain(|e| ready |= e.kind == event_kind::READY && fixed_str(&e.process) == "ains")
            .expect("events");
        ready || !child.is_running()
    });
    assert!(ready && child.is_running(), "nauta-ains never got ready");
    let mut seen = Seen::default();
    let mut collect = |seen: &mut Seen| {
        nav_sub.drain(|n| seen.nav.push(n)).expect("nav");
        health_sub.drain(|h| seen.health = Some(h)).expect("health");
        progress_sub
            .drain(|p| {
                seen.ended |= p.header.is_end_of_stream();
                seen.watermark = seen.watermark.max(p.header.stamp_ns);
            })
            .expect("progress");
    };
    let batches: Vec<&[Vec<Msg>]> = feed.chunks(BATCH_STEPS).collect();
    let first_of = |b: &[Vec<Msg>]| b.iter().flatten().map(Msg::stamp_ns).min();
    for (k, batch) in batches.iter().enumerate() {
        wd.check();
        // Paced as the sensor is in `sim` clock: at most a second ahead of
        // what the ains has taken, so that neither side's queues fill.
        let first = first_of(batch).unwrap_or(0);
        loop {
            collect(&mut seen);
            if first < seen.watermark + 1_000_000_000 || !child.is_running() {
                break;
            }
            wd.check();
            std::thread::sleep(Duration::from_micros(200));
        }
        let mut last = 0;
        for m in batch.iter().flatten() {
            last = last.max(m.stamp_ns());
            match m {
                Msg::Sensor(SensorMessage::Imu(s)) => imu.publish(*s),
                Msg::Sensor(SensorMessage::Dvl(s)) => dvl.publish(*s),
                Msg::Sensor(SensorMessage::Depth(s)) => depth.publish(*s),
                Msg::Sensor(SensorMessage::Gps(s)) => gps.publish(*s),
                Msg::Sensor(SensorMessage::Ahrs(s)) => ahrs.publish(*s),
                Msg::Sensor(_) => Ok(()),
                Msg::Attitude(a) => att.publish(*a),
                Msg::Fix(f) => fix.publish(*f),
            }
            .expect("publish");
        }
        // A watermark per batch: nothing earlier than the next batch's
        // first stamp is still to come from any of the three publishers.
        let next = batches
            .get(k + 1)
            .and_then(|b| first_of(b))
            .unwrap_or(last + 1);
        imu.flush();
        dvl.flush();
        depth.flush();
        gps.flush();
        ahrs.flush();
        att.flush();
        fix.flush();
        sensor_progress
            .publish_now(Progress::at(next, Role::Sensor, 0))
            .expect("progress");
        att_progress
            .publish_now(Progress::at(next, Role::Attitude, 0))
            .expect("progress");
        fix_progress
            .publish_now(Progress::at(next, Role::Positioning, 0))
            .expect("progress");
    }
    let last = feed.iter().flatten().map(Msg::stamp_ns).max().unwrap_or(0);
    for (p, role) in [
        (&mut sensor_progress, Role::Sensor),
        (&mut att_progress, Role::Attitude),
        (&mut fix_progress, Role::Positioning),
    ] {
        p.publish_now(Progress::end_of_stream(last, role, 0))
            .expect("end of stream");
    }
    // Until the ains has ended its stream and said so in its last health.
    let done = wait_until(wd, Duration::from_secs(120), || {
        collect(&mut seen);
        seen.ended && seen.health.is_some_and(|h| h.state == state::STOPPED)
    });
    assert!(
        done,
        "nauta-ains did not end its stream (health {:?})",
        seen.health
    );
    let out = child.wait(wd);
    assert_eq!(out.code(), Some(0), "{out}");
    let log = out.stderr.clone();
    drop((imu, dvl, depth, gps, ahrs, sensor_progress));
    drop((att, att_progress, fix, fix_progress));
    drop((events, nav_sub, health_sub, progress_sub));
    for c in [sensor, attitude, positioning, test] {
        c.finish();
    }
    Outcome {
        nav: seen.nav,
        health: seen.health.expect("a health report"),
        log,
    }
}

/// The clean run, once per test binary.
fn clean(wd: &Watchdog) -> &'static (Vec<Vec<Msg>>, Outcome) {
    static CLEAN: OnceLock<(Vec<Vec<Msg>>, Outcome)> = OnceLock::new();
    CLEAN.get_or_init(|| {
        let feed = clean_feed();
        let out = run(wd, "pf", &feed);
        (feed, out)
    })
}

/// The ways one message of an input is made bad.
type Spoil = fn(&mut Msg);

/// Inserts three bad copies of messages of the input `which` picks: one
/// spoiled by `non_finite`, one by `out_of_range` (each 1 ns after its
/// original, so its stamp is new), and one 1 ns earlier than its original,
/// inserted after it (the input's stamps then go backwards).
fn spoiled(
    feed: &[Vec<Msg>],
    which: fn(&Msg) -> bool,
    non_finite: Spoil,
    out_of_range: Spoil,
) -> Vec<Vec<Msg>> {
    let mut feed = feed.to_vec();
    let hits: Vec<(usize, usize)> = feed
        .iter()
        .enumerate()
        .flat_map(|(s, step)| {
            step.iter()
                .enumerate()
                .filter(|(_, m)| which(m))
                .map(move |(i, _)| (s, i))
        })
        .collect();
    assert!(
        hits.len() >= 6,
        "too few messages of the input: {}",
        hits.len()
    );
    // Spread over the run, in reverse so that insertions keep the indices.
    let picks = [
        hits[hits.len() * 3 / 4],
        hits[hits.len() / 2],
        hits[hits.len() / 4],
    ];
    let spoils: [fn(&mut Msg); 3] = [non_finite, out_of_range, |m| {
        m.header_mut().stamp_ns -= 2;
    }];
    for ((s, i), spoil) in picks.into_iter().zip(spoils) {
        let mut bad = feed[s][i];
        bad.header_mut().stamp_ns += 1;
        spoil(&mut bad);
        feed[s].insert(i + 1, bad);
    }
    feed
}

/// Runs the spoiled feed and compares it with the clean run.
fn refused_and_counted(
    name: &str,
    service: &str,
    which: fn(&Msg) -> bool,
    non_finite: Spoil,
    out_of_range: Spoil,
) {
    bin_dir();
    let wd = Watchdog::new(name, BOUND);
    let (feed, good) = clean(&wd);
    let bad = spoiled(feed, which, non_finite, out_of_range);
    let got = run(&wd, "pf", &bad);
    assert!(good.nav.len() > 1000, "{} solutions", good.nav.len());
    assert_eq!(
        got.health.rejected,
        good.health.rejected + 3,
        "{name}: every bad message refused and counted once"
    );
    assert_eq!(got.nav.len(), good.nav.len(), "{name}: solutions");
    // The last log line counts the refusals per input and kind.
    let done = got
        .log
        .lines()
        .rev()
        .find(|l| l.contains("rejected_by_kind"))
        .unwrap_or_else(|| panic!("{name}: no final counts in the log:\n{}", got.log));
    assert!(
        done.contains(service),
        "{name}: {service} not among the counts: {done}"
    );
    for (a, b) in got.nav.iter().zip(&good.nav) {
        let same = a.header.stamp_ns == b.header.stamp_ns
            && a.lat_rad.to_bits() == b.lat_rad.to_bits()
            && a.lon_rad.to_bits() == b.lon_rad.to_bits()
            && a.vel_ned_m_s.map(f64::to_bits) == b.vel_ned_m_s.map(f64::to_bits);
        assert!(
            same,
            "{name}: the bad input changed the solution at {} ns",
            a.header.stamp_ns
        );
    }
}

fn sensor(m: &mut Msg) -> &mut SensorMessage {
    match m {
        Msg::Sensor(s) => s,
        _ => unreachable!("a sensor message"),
    }
}

#[test]
fn bad_imu_samples_are_refused_and_counted() {
    refused_and_counted(
        "bad_imu",
        "sensor/imu",
        |m| matches!(m, Msg::Sensor(SensorMessage::Imu(_))),
        |m| {
            if let SensorMessage::Imu(s) = sensor(m) {
                s.gyro_rad_s[1] = f64::NAN;
            }
        },
        |m| {
            if let SensorMessage::Imu(s) = sensor(m) {
                s.accel_m_s2[2] = 1e4;
            }
        },
    );
}

#[test]
fn bad_dvl_samples_are_refused_and_counted() {
    refused_and_counted(
        "bad_dvl",
        "sensor/dvl",
        |m| matches!(m, Msg::Sensor(SensorMessage::Dvl(_))),
        |m| {
            if let SensorMessage::Dvl(s) = sensor(m) {
                s.velocity_body_m_s[0] = f64::INFINITY;
            }
        },
        |m| {
            if let SensorMessage::Dvl(s) = sensor(m) {
                s.altitude_m = -3.0;
            }
        },
    );
}

#[test]
fn bad_depth_samples_are_refused_and_counted() {
    refused_and_counted(
        "bad_depth",
        "sensor/depth",
        |m| matches!(m, Msg::Sensor(SensorMessage::Depth(_))),
        |m| {
            if let SensorMessage::Depth(s) = sensor(m) {
                s.depth_m = f64::NAN;
            }
        },
        |m| {
            if let SensorMessage::Depth(s) = sensor(m) {
                s.depth_m = 20_000.0;
            }
        },
    );
}

#[test]
fn bad_gps_fixes_are_refused_and_counted() {
    refused_and_counted(
        "bad_gps",
        "sensor/gps",
        |m| matches!(m, Msg::Sensor(SensorMessage::Gps(_))),
        |m| {
            if let SensorMessage::Gps(s) = sensor(m) {
                s.lon_rad = f64::NAN;
            }
        },
        |m| {
            if let SensorMessage::Gps(s) = sensor(m) {
                s.lat_rad = 2.0;
            }
        },
    );
}

#[test]
fn bad_ahrs_samples_are_refused_and_counted() {
    refused_and_counted(
        "bad_ahrs",
        "sensor/ahrs",
        |m| matches!(m, Msg::Sensor(SensorMessage::Ahrs(_))),
        |m| {
            if let SensorMessage::Ahrs(s) = sensor(m) {
                s.heading_mag_rad = f64::NEG_INFINITY;
            }
        },
        |m| {
            if let SensorMessage::Ahrs(s) = sensor(m) {
                s.pitch_rad = 3.0;
            }
        },
    );
}

#[test]
fn bad_attitude_estimates_are_refused_and_counted() {
    refused_and_counted(
        "bad_attitude",
        "attitude/estimate",
        |m| matches!(m, Msg::Attitude(_)),
        |m| {
            if let Msg::Attitude(a) = m {
                a.quat_nb[0] = f64::NAN;
            }
        },
        |m| {
            if let Msg::Attitude(a) = m {
                a.quat_nb = a.quat_nb.map(|x| 2.0 * x);
            }
        },
    );
}

#[test]
fn bad_position_fixes_are_refused_and_counted() {
    refused_and_counted(
        "bad_fix",
        "positioning/fix",
        |m| matches!(m, Msg::Fix(_)),
        |m| {
            if let Msg::Fix(f) = m {
                f.std_north_m = f64::NAN;
            }
        },
        |m| {
            if let Msg::Fix(f) = m {
                f.corr_ne = 1.5;
            }
        },
    );
}
