//! The estimator shell, generically: a minimal role built on it (a 1-D
//! position tracker with a fast velocity input and a slow position input) in
//! real iceoryx2 processes-in-threads, each test in its own namespace and
//! under a watchdog. It shows stamp-ordered processing whatever the arrival
//! order, hot swap with every stamp exactly once, warm restart from the
//! snapshot within 3σ, bad input refused and counted, and a wiring cycle
//! (tracker ↔ relay) that stays deterministic without a round trip per
//! sample.
//!
//! The test role reuses nauta's message types as carriers: the tracker runs
//! as `ains` (`ains/nav`: `depth_m` is its 1-D position, `pos_std_ned_m[2]`
//! its σ; `ains/snapshot`), velocity arrives in `sensor/imu`'s
//! `accel_m_s2[0]`, position measurements in `sensor/depth`'s `depth_m`, and
//! the relay of the cycle runs as `lbl` (`lbl/nav`: `x_m`, `p[0][0]`).

mod harness;
mod roles;

use std::sync::Arc;
use std::time::Duration;

use nauta_messages::*;
use nauta_runtime::{Context, Namespace, services};

use harness::*;
use roles::*;

#[test]
fn inputs_are_processed_in_stamp_order_whatever_the_arrival_order() {
    let _wd = Watchdog::new("stamp order", Duration::from_secs(120));
    let data = samples(30, 1);
    let expected = reference(&data);
    for arrival in [Arrival::InOrder, Arrival::SlowFirst(5)] {
        let got = run_tracker(data.clone(), arrival);
        assert_same(
            &outputs(&got.nav),
            &expected,
            &format!("{arrival:?}: outputs differ from the in-process estimator"),
        );
        let h = got.health.expect("health");
        assert_eq!((h.rejected, h.dropped), (0, 0), "{arrival:?}");
    }
}

#[test]
fn bad_input_is_refused_and_counted() {
    let _wd = Watchdog::new("bad input", Duration::from_secs(120));
    let good = samples(10, 2);
    let mut bad = good.clone();
    // A NaN, an interval out of range, a repeated stamp, a stamp that goes
    // back, and a position the estimator itself refuses.
    let at = |k: usize| stamp_of(&good[k]);
    let nan = ImuSample {
        header: Header::new(at(100) + 1, 0, Role::Sensor, 0),
        accel_m_s2: [f64::NAN, 0.0, 0.0],
        interval_s: 0.01,
        ..Default::default()
    };
    bad.insert(101, Out::Imu(nan));
    let mut long = nan;
    long.header.stamp_ns = at(300) + 1;
    long.accel_m_s2[0] = 1.0;
    long.interval_s = 5.0;
    bad.insert(302, Out::Imu(long));
    let Out::Imu(mut repeated) = good[500] else {
        panic!("an IMU sample")
    };
    repeated.accel_m_s2[0] += 1.0;
    bad.insert(505, Out::Imu(repeated));
    let Out::Imu(mut back) = good[600] else {
        panic!("an IMU sample")
    };
    back.header.stamp_ns -= 5 * IMU_DT_NS;
    bad.insert(606, Out::Imu(back));
    let depth_at = bad
        .iter()
        .position(|o| matches!(o, Out::Depth(_)))
        .expect("a position sample");
    let Out::Depth(mut wild) = bad[depth_at] else {
        unreachable!()
    };
    wild.header.stamp_ns += 1;
    wild.depth_m = 5000.0;
    bad.insert(depth_at + 1, Out::Depth(wild));
    let got = run_tracker(bad, Arrival::InOrder);
    let h = got.health.expect("health");
    assert_eq!(h.rejected, 5, "every bad message counted once");
    assert_same(
        &outputs(&got.nav),
        &reference(&good),
        "bad input changed something",
    );
}

#[test]
fn hot_swap_publishes_every_stamp_exactly_once() {
    let _wd = Watchdog::new("hot swap", Duration::from_secs(180));
    let (got, boundary, expected) =
        run_handover(Handover::Swap, 12 * SNAPSHOT_NS + 345 * 1_000_000);
    assert_every_stamp_once(&got.nav, "swap");
    // Up to the boundary the outputs are instance 0's, bit for bit.
    let out = outputs(&got.nav);
    let before: Vec<_> = out
        .iter()
        .filter(|o| o.stamp_ns <= boundary)
        .copied()
        .collect();
    assert_eq!(before, expected[..before.len()].to_vec());
    // The successor continued the estimate (not a cold start).
    let after: Vec<_> = out.iter().filter(|o| o.stamp_ns > boundary).collect();
    let first = after.first().expect("outputs after the swap");
    let t = first.stamp_ns as f64 * 1e-9;
    assert!(
        (first.x - truth_x(t)).abs() <= 3.0 * first.std && first.std < COLD_STD_M / 10.0,
        "first output after the swap {first:?}: truth {}",
        truth_x(t)
    );
}

#[test]
fn a_warm_restart_continues_from_the_snapshot_within_3_sigma() {
    let _wd = Watchdog::new("warm restart", Duration::from_secs(180));
    let (got, _, _) = run_handover(
        Handover::Restart { lag_ns: 0 },
        17 * SNAPSHOT_NS + 505 * 1_000_000,
    );
    assert_every_stamp_once(&got.nav, "restart");
    let restarted: Vec<_> = got
        .nav
        .iter()
        .filter(|m| m.header.instance == 1)
        .take(100)
        .collect();
    assert_eq!(restarted.len(), 100, "instance 1 published");
    for m in restarted {
        let t = m.header.stamp_ns as f64 * 1e-9;
        let (x, std) = (m.depth_m, m.pos_std_ned_m[2]);
        assert!(
            (x - truth_x(t)).abs() <= 3.0 * std && std < COLD_STD_M / 10.0,
            "at {t} s: {x} ± {std} against the truth {} (a cold start begins at 0 ± {COLD_STD_M})",
            truth_x(t)
        );
    }
}

/// Regression (the ains/nav stamps lost in `chaos_short_version`, 2026-12-03):
/// a killed instance lagged behind its inputs and its successor took time
/// to start, so it subscribed seconds of the run's clock after the snapshot
/// it starts from; what its inputs' history no longer held was never
/// published. At `--rate 10` 10 s of mission is 1 s of wall time: the
/// history must reach back that far (4.8 s did not).
#[test]
fn a_restart_ten_seconds_behind_replays_from_the_snapshot() {
    let _wd = Watchdog::new("late restart", Duration::from_secs(180));
    let (got, _, _) = run_handover(
        Handover::Restart {
            lag_ns: 10 * SNAPSHOT_NS,
        },
        12 * SNAPSHOT_NS + 505 * 1_000_000,
    );
    assert_every_stamp_once(&got.nav, "late restart");
    let h = got.health.expect("health");
    assert_eq!((h.rejected, h.dropped), (0, 0), "refused or lost input");
}

#[test]
fn a_wiring_cycle_runs_deterministically_without_a_round_trip_per_sample() {
    let _wd = Watchdog::new("cycle", Duration::from_secs(180));
    let data = samples(40, 4);
    let mut digests = Vec::new();
    for arrival in [Arrival::InOrder, Arrival::SlowFirst(9)] {
        let ns = Namespace::unique();
        let (col, col_ready) = collector(&ns, 0, &Arc::default());
        col_ready.recv().expect("collector started");
        let relay_progress = {
            let ctx = Context::new(&ns, settings(Role::Test, "counter", 0)).expect("node");
            let (sub, inbox) = ctx.subscriber(&services::progress(Role::Lbl)).expect("tap");
            (ctx, sub, inbox)
        };
        let src = source(
            ns.clone(),
            data.clone(),
            arrival,
            vec!["tracker", "relay", "collector"],
            None,
        );
        let trk = role(
            &ns,
            cyclic_tracker_shell,
            Tracker::cold(),
            Role::Ains,
            "tracker",
            0,
            |_| {},
        );
        let rel = role(
            &ns,
            relay_shell,
            Relay::default(),
            Role::Lbl,
            "relay",
            0,
            |_| {},
        );
        join(src, "source");
        join(trk, "tracker");
        join(rel, "relay");
        let got = join(col, "collector");
        let (ctx, mut sub, inbox) = relay_progress;
        let mut watermarks = 0;
        sub.drain(|_| watermarks += 1).expect("relay watermarks");
        drop((sub, inbox));
        ctx.finish();
        let out = outputs(&got.nav);
        let h = got.health.expect("tracker health");
        assert_eq!(
            (h.rejected, h.dropped),
            (0, 0),
            "{arrival:?}: tracker refused or lost input"
        );
        assert_eq!(
            out.len(),
            4000,
            "{arrival:?}: one output per velocity sample"
        );
        // Far fewer watermarks from the relay than samples: the tracker did
        // not wait on it sample by sample.
        assert!(
            watermarks < 4000 / 4,
            "{arrival:?}: {watermarks} relay watermarks"
        );
        digests.push(out);
    }
    assert_same(
        &digests[0],
        &digests[1],
        "the cycle's outputs depend on timing",
    );
    assert_same(
        &digests[0],
        &cycle_reference(&data),
        "the cycle's outputs differ from the in-process order",
    );
}

#[test]
fn an_absent_optional_input_is_neither_subscribed_nor_waited_for() {
    let _wd = Watchdog::new("optional input", Duration::from_secs(120));
    let d = optionally_relayed_tracker_shell().describe();
    let optional: Vec<(&str, bool)> = d
        .inputs
        .iter()
        .map(|p| (p.service.as_str(), p.optional))
        .collect();
    assert_eq!(
        optional,
        vec![
            ("sensor/imu", false),
            ("sensor/depth", false),
            ("lbl/nav", true),
            ("sensor/progress", false),
            ("lbl/progress", true),
        ],
        "--describe marks the optional input and its publisher's watermarks"
    );
    // No relay runs: told so, the tracker runs as if it had no such input
    // (without `--absent` it would wait for the relay's publisher).
    let data = samples(20, 5);
    let ns = Namespace::unique();
    let (col, col_ready) = collector(&ns, 0, &Arc::default());
    col_ready.recv().expect("collector started");
    let src = source(
        ns.clone(),
        data.clone(),
        Arrival::InOrder,
        vec!["tracker", "collector"],
        None,
    );
    let trk = role(
        &ns,
        optionally_relayed_tracker_shell,
        Tracker::cold(),
        Role::Ains,
        "tracker",
        0,
        |ctx| ctx.absent = vec!["lbl/nav".into()],
    );
    join(src, "source");
    join(trk, "tracker");
    let got = join(col, "collector");
    assert_same(
        &outputs(&got.nav),
        &reference(&data),
        "outputs differ from the tracker without the optional input",
    );
}
