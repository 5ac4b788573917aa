//! Paper 004's smoother on the LBL filter's forward pass over the
//! simulator's `lbl` scenario, in process (development seeds 7-9, 2 and 4
//! transponders): the smoothed track against the truth and the filter's,
//! and `P_smoothed ≤ P_filtered` at every step of a mission.

use std::collections::HashMap;

use nalgebra::Matrix4;
use nauta_estimation::lbl::{Lbl, LblInput, forward_pass};
use nauta_estimation::readings::LblNav;
use nauta_messages::checked::LblNav as CheckedNav;
use nauta_runtime::Manifest;
use nauta_sim::lbl_inputs::{LblLoop, inputs};
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
use nauta_sim::suite::LblLayout;
use nauta_tools::smooth::filter::{lbl_filter, lbl_process};
use nauta_tools::smooth::track::{navs, smoothed_track};

/// The filter of the shipped `launch/lbl.toml` on `layout`, as `nauta
/// smooth` builds it from a recording's manifest.
fn estimator(layout: LblLayout) -> Lbl {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch/lbl.toml");
    let m = Manifest::load_with(&path, &[format!("sensor.params.lbl_layout={layout:?}")])
        .expect("launch/lbl.toml");
    lbl_filter(&m, &lbl_process(&m, None).expect("an lbl process")).expect("its filter")
}

struct Mission {
    inputs: Vec<LblInput>,
    /// True north, east by stamp.
    truth: HashMap<u64, ([f64; 2], f64)>,
}

fn mission(layout: LblLayout, seed: u64) -> Mission {
    mission_with(layout, seed, None)
}

/// [`mission`] with the transponders silent during `blackout_s`.
fn mission_with(layout: LblLayout, seed: u64, blackout_s: Option<[f64; 2]>) -> Mission {
    let p = ScenarioParams {
        scenario: ScenarioKind::Lbl,
        lbl_layout: layout,
        imu_rate_hz: 20.0,
        ..Default::default()
    };
    let mut sensors = p.sensors_preset();
    sensors.lbl.blackout_s = blackout_s;
    let mut g = Generator::new(&p, Origin::lisbon(), sensors, seed, 2100.0).expect("scenario");
    let mut est = estimator(layout);
    let mut lp = LblLoop::new(10.0);
    let mut all = Vec::new();
    let mut buf = Vec::new();
    let mut truth = HashMap::new();
    while let Some((m, _)) = lp.step(&mut g, &mut est) {
        buf.clear();
        inputs(&m, &mut buf);
        all.extend(buf.iter().map(|(i, _)| *i));
        let (n, e) = Origin::lisbon().to_local(m.truth.lat_rad, m.truth.lon_rad);
        truth.insert(m.stamp_ns, ([n, e], m.truth.depth_m));
    }
    Mission { inputs: all, truth }
}

struct Score {
    rms_m: f64,
    inside_95_pct: f64,
    major_p50_m: f64,
}

fn score(navs: &[LblNav], truth: &HashMap<u64, ([f64; 2], f64)>) -> Score {
    let (mut sq, mut inside, mut n) = (0.0, 0.0, 0.0);
    let mut majors = Vec::new();
    for nav in navs {
        let Some((t, depth)) = truth.get(&nav.stamp_ns) else {
            continue;
        };
        if *depth < 1.0 {
            continue;
        }
        let (x, y) = (nav.x_m - t[0], nav.y_m - t[1]);
        let p = &nav.p;
        let (a, b, d) = (p[0][0], p[0][1], p[1][1]);
        let det = a * d - b * b;
        if (d * x * x - 2.0 * b * x * y + a * y * y) / det <= 5.991 {
            inside += 1.0;
        }
        sq += x * x + y * y;
        n += 1.0;
        let mean = 0.5 * (a + d);
        majors.push((mean + (0.25 * (a - d).powi(2) + b * b).sqrt()).sqrt());
    }
    majors.sort_by(f64::total_cmp);
    Score {
        rms_m: (sq / n).sqrt(),
        inside_95_pct: 100.0 * inside / n,
        major_p50_m: majors[majors.len() / 2],
    }
}

#[test]
fn the_smoothed_track_beats_the_filter_on_the_development_seeds() {
    for layout in [LblLayout::Two, LblLayout::Four] {
        let mut inside = Vec::new();
        for seed in 7..=9 {
            let m = mission(layout, seed);
            let pass = forward_pass(estimator(layout), &m.inputs);
            let filtered = navs(&pass);
            let track = smoothed_track(&pass).expect("smooth");
            let smoothed: Vec<LblNav> = track
                .solutions
                .iter()
                .map(|s| CheckedNav::try_from(s).expect("a valid message"))
                .collect();
            assert_eq!(smoothed.len(), filtered.len());
            let f = score(&filtered, &m.truth);
            let s = score(&smoothed, &m.truth);
            eprintln!(
                "{layout:?} seed {seed}: filter RMS {:.3} m, 95% {:.1} %, major p50 {:.3} m; smoothed RMS {:.3} m ({:.2}x), 95% {:.1} %, major p50 {:.3} m; {} steps, backward {:.3} s",
                f.rms_m,
                f.inside_95_pct,
                f.major_p50_m,
                s.rms_m,
                s.rms_m / f.rms_m,
                s.inside_95_pct,
                s.major_p50_m,
                track.steps,
                track.backward_s
            );
            // P_smoothed ≤ P_filtered at every published step: the
            // difference of the published `[x, y, w_x, w_y]` blocks is
            // positive semi-definite (to rounding; a principal block of the
            // 5-state difference is, too).
            let mut worst = f64::INFINITY;
            for (f, s) in filtered.iter().zip(&smoothed) {
                assert_eq!(f.stamp_ns, s.stamp_ns);
                let (pf, ps) = (
                    Matrix4::from(f.p).transpose(),
                    Matrix4::from(s.p).transpose(),
                );
                let min = (pf - ps).symmetric_eigen().eigenvalues.min() / pf.amax();
                worst = worst.min(min);
                assert!(
                    min >= -1e-9,
                    "{layout:?} seed {seed} at {} ns: P_filtered − P_smoothed has eigenvalue {min} × |P|",
                    f.stamp_ns
                );
            }
            eprintln!("  smallest eigenvalue of P_filtered − P_smoothed over |P|: {worst:e}");
            // Issue 15's figures (BENCHMARKS.md measures them over seeds
            // 100-199): the smoothed RMS at most 0.7 of the filter's, the
            // smoothed ellipse's semi-major axis p50 at most 0.6 m.
            assert!(s.rms_m <= 0.7 * f.rms_m, "{layout:?} seed {seed}");
            assert!(s.major_p50_m <= 0.6, "{layout:?} seed {seed}");
            assert!(s.major_p50_m < f.major_p50_m, "{layout:?} seed {seed}");
            inside.push(s.inside_95_pct);
        }
        // The smoothed covariance is not overconfident: over the seeds the
        // truth is inside its 95 % ellipse at least 90 % of the time. (The
        // issue also asks at most 98 %: with the filter's default `Q` the
        // smoothed ellipse is a little wide, 98-99 % on these seeds;
        // docs/design-notes.md, "LBL smoother".)
        let mean = inside.iter().sum::<f64>() / inside.len() as f64;
        assert!(
            mean >= 90.0,
            "{layout:?}: {mean} % inside the smoothed 95 % ellipse"
        );
    }
}

/// Ten minutes without replies (issue 15's blackout): the filter widens its
/// covariance to re-acquire, a restart the backward pass carries back as a
/// fix of the position; `P_smoothed ≤ P_filtered` everywhere, the smoothed
/// track better than the filter's outside the blackout and inside it.
#[test]
fn a_blackout_is_bridged_by_the_reacquisition() {
    const BLACKOUT: [f64; 2] = [600.0, 1200.0];
    let m = mission_with(LblLayout::Two, 7, Some(BLACKOUT));
    let pass = forward_pass(estimator(LblLayout::Two), &m.inputs);
    let filtered = navs(&pass);
    let track = smoothed_track(&pass).expect("smooth");
    let smoothed: Vec<LblNav> = track
        .solutions
        .iter()
        .map(|s| CheckedNav::try_from(s).expect("a valid message"))
        .collect();
    assert_eq!(smoothed.len(), filtered.len());
    for (f, s) in filtered.iter().zip(&smoothed) {
        let (pf, ps) = (Matrix4::from(f.p), Matrix4::from(s.p));
        let min = (pf - ps).symmetric_eigen().eigenvalues.min() / pf.amax();
        assert!(min >= -1e-9, "at {} ns: {min}", f.stamp_ns);
    }
    let outside = |navs: &[LblNav]| -> Vec<LblNav> {
        navs.iter()
            .filter(|n| {
                let t = n.stamp_ns as f64 * 1e-9;
                !(BLACKOUT[0]..=BLACKOUT[1] + 120.0).contains(&t)
            })
            .copied()
            .collect()
    };
    let (f, s) = (
        score(&outside(&filtered), &m.truth),
        score(&outside(&smoothed), &m.truth),
    );
    eprintln!(
        "outside the blackout: filter RMS {:.3} m, smoothed {:.3} m; inside 95 %: filter {:.1} %, smoothed {:.1} %",
        f.rms_m, s.rms_m, f.inside_95_pct, s.inside_95_pct
    );
    let during = |navs: &[LblNav]| -> Vec<LblNav> {
        navs.iter()
            .filter(|n| (BLACKOUT[0]..BLACKOUT[1]).contains(&(n.stamp_ns as f64 * 1e-9)))
            .copied()
            .collect()
    };
    let (fd, sd) = (
        score(&during(&filtered), &m.truth),
        score(&during(&smoothed), &m.truth),
    );
    // The re-acquisition is carried back as a fix of the position
    // (`smooth_bridged`): the blackout's drift is taken out, mostly (the
    // heading bias turns with the vehicle, a current does not).
    eprintln!(
        "in the blackout: filter RMS {:.3} m, smoothed {:.3} m; inside 95 %: filter {:.1} %, smoothed {:.1} %",
        fd.rms_m, sd.rms_m, fd.inside_95_pct, sd.inside_95_pct
    );
    assert!(fd.rms_m > 2.0, "the blackout did not show: {} m", fd.rms_m);
    assert!(sd.rms_m <= 0.5 * fd.rms_m);
    assert!(s.rms_m <= 0.7 * f.rms_m);
    assert!(s.inside_95_pct >= 90.0);
}
