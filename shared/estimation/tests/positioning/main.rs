//! Issue 14: the positioning role's estimator in process on the simulator's
//! survey (seed 7, the development seed): the fixes bound the navigation's
//! drift, the gate refuses the modem's multipath, a lost message costs only
//! accuracy, bad inputs are refused and counted, the same seed gives the
//! same bytes, and a restart from a snapshot continues.

mod harness;
mod inputs;

use harness::*;
use nauta_estimation::Estimator;
use nauta_estimation::positioning::{
    Positioning, PositioningEkfParams, PositioningPfParams, Saved, source,
};

const SEED: u64 = 7;
/// The survey's length, s (its dive, six transects and the surfacing).
const FULL_S: f64 = 3000.0;

fn pf() -> Positioning {
    Positioning::pf(&PositioningPfParams::default()).expect("defaults")
}

fn ekf() -> Positioning {
    Positioning::ekf(&PositioningEkfParams::default()).expect("defaults")
}

fn report(name: &str, r: &Run) {
    let end = r.fixes.last().map_or(0.0, |s| s.fix.stamp_ns as f64 * 1e-9);
    let third = end / 3.0;
    eprintln!(
        "{name}: {} buoy fixes of {} messages, RMS N/E {:?} m (first third {:?}, last {:?}), inside 95 % {:.1} %, {:?}, outliers {} refused {}",
        r.of(source::BUOY, 0.0, f64::INFINITY).count(),
        r.messages,
        r.rms(0.0, f64::INFINITY),
        r.rms(0.0, third),
        r.rms(2.0 * third, f64::INFINITY),
        r.inside_95_pct(),
        r.stats,
        r.outliers,
        r.outliers_refused
    );
}

/// The survey at seed 7 with the sensors changed by `tweak`, through `est`.
fn survey_run(
    est: &mut Positioning,
    tweak: impl FnOnce(&mut nauta_sim::suite::SuiteConfig),
) -> Run {
    let mut g = survey(SEED, FULL_S, tweak);
    run(est, &mut g, NavErrors::default(), None)
}

fn horizontal(rms: [f64; 2]) -> f64 {
    rms[0].hypot(rms[1])
}

/// The harness's velocity bias alone moves a dead-reckoned position by
/// 0.0013 m/s × 2700 s ≈ 3.5 m over the dive; the fixes hold it to metres
/// all along (paper 000 Fig. 7: bounded, not drifting), the last third no
/// worse than 1.5× the first.
#[test]
fn the_fixes_bound_the_drift_of_a_biased_velocity() {
    for (name, mut est) in [("pf", pf()), ("ekf", ekf())] {
        let r = survey_run(&mut est, |_| {});
        report(name, &r);
        let used = r.of(source::BUOY, 0.0, f64::INFINITY).count() as u64;
        assert_eq!(used, r.stats.ranges_used, "{name}");
        assert!(
            used * 10 >= r.messages * 9,
            "{name}: {used} of {} used",
            r.messages
        );
        let end = r.fixes.last().expect("fixes").fix.stamp_ns as f64 * 1e-9;
        let (first, last) = (
            horizontal(r.rms(0.0, end / 3.0)),
            horizontal(r.rms(2.0 * end / 3.0, f64::INFINITY)),
        );
        let all = horizontal(r.rms(0.0, f64::INFINITY));
        assert!(all < 5.0, "{name}: horizontal RMS {all} m");
        assert!(
            last <= 1.5 * first,
            "{name}: last third {last} m, first {first} m"
        );
        // The surface: GPS fixes before the dive and after it.
        assert!(r.of(source::GPS, 0.0, 60.0).count() > 0, "{name}");
        assert!(
            r.of(source::GPS, end - 5.0, f64::INFINITY).count() > 0,
            "{name}"
        );
        // Published σ: finite and about the error (the 90-98 % coverage of
        // issue 14 is the benchmark's, over seeds).
        for s in &r.fixes {
            let f = &s.fix;
            assert!(
                f.std_north_m.is_finite() && f.std_east_m.is_finite() && f.corr_ne.abs() <= 1.0,
                "{f:?}"
            );
        }
        assert!(
            r.inside_95_pct() > 50.0,
            "{name}: {:.0} %",
            r.inside_95_pct()
        );
    }
}

/// Issue 14: multipath outliers (+20 to +200 m) are refused by the gate
/// (at least 95 % of them) and cost the fixes almost nothing; here one
/// message in ten comes by a longer path, for numbers.
#[test]
fn the_gate_refuses_multipath_outliers() {
    for (name, mut est, mut clean) in [("pf", pf(), pf()), ("ekf", ekf(), ekf())] {
        let r = survey_run(&mut est, |s| s.modem.noise.multipath_probability = 0.1);
        report(name, &r);
        assert!(r.outliers >= 5, "{name}: {} outliers", r.outliers);
        assert!(
            r.outliers_refused * 100 >= r.outliers * 95,
            "{name}: {} of {} outliers refused",
            r.outliers_refused,
            r.outliers
        );
        // Refused are the outliers, and few of the rest.
        assert!(
            r.stats.ranges_gated <= r.outliers + 2,
            "{name}: {:?}",
            r.stats
        );
        let base = survey_run(&mut clean, |_| {});
        let (h, h0) = (
            horizontal(r.rms(0.0, f64::INFINITY)),
            horizontal(base.rms(0.0, f64::INFINITY)),
        );
        assert!(
            h < 1.5 * h0 + 0.5,
            "{name}: {h} m with outliers, {h0} m without"
        );
    }
}

/// A lost message costs only accuracy: with 30 % lost, as many fixes as
/// messages arrive and the error stays bounded.
#[test]
fn lost_messages_cost_only_accuracy() {
    for (name, mut est) in [("pf", pf()), ("ekf", ekf())] {
        let r = survey_run(&mut est, |s| s.modem.noise.loss_probability = 0.3);
        report(name, &r);
        assert_eq!(
            r.stats.ranges_used + r.stats.ranges_gated,
            r.messages,
            "{name}"
        );
        assert!(r.messages < 70, "{name}: {} messages", r.messages);
        let h = horizontal(r.rms(0.0, f64::INFINITY));
        assert!(h < 6.0, "{name}: horizontal RMS {h} m");
    }
}

/// No buoy message for the whole dive: the fixes of the dive say so
/// (source NONE, every `silence_s`), their σ grows, and nothing is refused.
#[test]
fn without_a_buoy_the_fix_source_says_so() {
    for (name, mut est) in [("pf", pf()), ("ekf", ekf())] {
        let r = survey_run(&mut est, |s| s.modem.enabled = false);
        assert_eq!(r.messages, 0);
        assert_eq!(r.of(source::BUOY, 0.0, f64::INFINITY).count(), 0, "{name}");
        let silent: Vec<_> = r.of(source::NONE, 0.0, f64::INFINITY).collect();
        // 90 s apart over a dive of about 2700 s.
        assert!(silent.len() >= 25, "{name}: {} silent fixes", silent.len());
        let (a, b) = (silent[0].fix, silent[silent.len() - 1].fix);
        assert!(
            b.std_north_m > a.std_north_m && b.std_east_m > a.std_east_m,
            "{name}: {a:?} {b:?}"
        );
        assert_eq!(
            r.stats.ranges_gated + r.stats.gps_submerged,
            0,
            "{name}: {:?}",
            r.stats
        );
    }
}

/// The same seed gives the same fixes, bit for bit.
#[test]
fn the_same_seed_gives_the_same_fixes() {
    let a = survey_run(&mut pf(), |_| {});
    let b = survey_run(&mut pf(), |_| {});
    assert_eq!(a.fixes.len(), b.fixes.len());
    for (x, y) in a.fixes.iter().zip(&b.fixes) {
        assert_eq!(x.fix, y.fix);
    }
}

/// A restart from the snapshot at 1500 s: the `ekf` continues bit for bit,
/// the `pf` (its set redrawn from the snapshot's Gaussian) as accurately.
#[test]
fn a_restart_from_a_snapshot_continues() {
    for (name, make) in [("pf", pf as fn() -> Positioning), ("ekf", ekf)] {
        let mut g = survey(SEED, FULL_S, |_| {});
        let whole = run(&mut make(), &mut g, NavErrors::default(), Some(1500.0));
        let (state, stamp) = whole.snapshot.clone().expect("a snapshot at 1500 s");
        let mut restarted = make();
        restarted.restore(&state, stamp).expect("restore");
        let mut g = survey(SEED, FULL_S, |_| {});
        let after = run(&mut restarted, &mut g, NavErrors::default(), None);
        let later = |r: &Run| -> Vec<_> {
            r.fixes
                .iter()
                .filter(|s| s.fix.stamp_ns > stamp)
                .map(|s| s.fix)
                .collect()
        };
        let (a, b) = (later(&whole), later(&after));
        assert_eq!(a.len(), b.len(), "{name}");
        assert!(
            after.fixes.iter().all(|s| s.fix.stamp_ns > stamp),
            "{name}: nothing before the snapshot"
        );
        if name == "ekf" {
            assert_eq!(a, b, "ekf: not bit for bit");
        }
        let (h_a, h_b) = (
            horizontal(whole.rms(stamp as f64 * 1e-9, f64::INFINITY)),
            horizontal(after.rms(stamp as f64 * 1e-9, f64::INFINITY)),
        );
        assert!(
            h_b < h_a + 2.0,
            "{name}: {h_b} m after the restart, {h_a} m without"
        );
        // A damaged snapshot is refused, as an unreadable one.
        let Saved::State(good, variant) = &state else {
            panic!("{state:?}")
        };
        let mut bad = good.as_ref().clone();
        bad.offsets.cov[0][0] = f64::NAN;
        let bad = Saved::State(Box::new(bad), variant.clone());
        assert!(make().restore(&bad, stamp).is_err(), "{name}");
        let unreadable = Saved::Unreadable("cut".into());
        assert!(make().restore(&unreadable, stamp).is_err(), "{name}");
    }
}
