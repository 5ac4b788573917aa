use nalgebra::{Matrix2, UnitQuaternion, Vector3};
use nauta_estimation::attitude::{from_euler, to_euler};
use nauta_estimation::earth::{meridian_radius, transverse_radius};
use nauta_messages::checked::Gps;
use nauta_messages::{Header, NavSolution, Role, codec};
use nauta_sim::mission::Origin;

use super::compute::*;
use super::data::empty as sample;
use super::data::*;
use super::*;

const LAT0: f64 = 0.673_697_6; // 38.6°
const LON0: f64 = -0.162_315_6;

fn truth_sample(stamp_ns: u64, lat: f64, lon: f64, yaw: f64, distance_m: f64) -> TruthSample {
    TruthSample {
        stamp_ns,
        lat_rad: lat,
        lon_rad: lon,
        depth_m: 10.0,
        vel_ned_m_s: Vector3::new(1.5, 0.0, 0.0),
        attitude: from_euler(0.0, 0.0, yaw),
        distance_m,
    }
}

/// 10 s northwards at 1.5 m/s on a 10 ms grid, turning at 0.1 rad/s.
fn straight_truth() -> Vec<TruthSample> {
    (0..1000u64)
        .map(|i| {
            let t = i as f64 * 0.01;
            let north = 1.5 * t;
            let lat = LAT0 + north / (meridian_radius(LAT0) - 10.0);
            truth_sample(i * 10_000_000, lat, LON0, 0.1 * t, north)
        })
        .collect()
}

fn stream(kind: StreamKind, samples: Vec<EstimateSample>) -> Stream {
    Stream {
        topic: "x".into(),
        kind,
        samples,
        rejected: 0,
    }
}

#[test]
fn the_truth_is_interpolated_at_stamps_between_its_samples() {
    let truth = straight_truth();
    // Estimates 5 ms off the grid, (1, 2) m off the true track, yaw +0.01 rad.
    let samples: Vec<EstimateSample> = (0..99u64)
        .map(|k| {
            let stamp = k * 100_000_000 + 5_000_000;
            let t = stamp as f64 * 1e-9;
            let h = -10.0;
            let lat = LAT0 + 1.5 * t / (meridian_radius(LAT0) + h);
            let lat_e = lat + 1.0 / (meridian_radius(lat) + h);
            let lon_e = LON0 + 2.0 / ((transverse_radius(lat) + h) * lat.cos());
            EstimateSample {
                pos: Some(Horizontal::Geodetic {
                    lat_rad: lat_e,
                    lon_rad: lon_e,
                }),
                depth_m: Some(10.5),
                vel_ned_m_s: Some(Vector3::new(1.6, 0.0, 0.0)),
                attitude: Some(from_euler(0.0, 0.0, 0.1 * t + 0.01)),
                ..sample(stamp)
            }
        })
        .collect();
    let (errors, unmatched) = errors_against_truth(&stream(StreamKind::Nav, samples), &truth, None);
    assert_eq!((errors.len(), unmatched), (99, 0));
    for e in &errors {
        let [n, east] = e.ne_m.expect("ne");
        assert!((n - 1.0).abs() < 1e-6 && (east - 2.0).abs() < 1e-6, "{e:?}");
        assert!((e.down_m.expect("down") - 0.5).abs() < 1e-12);
        assert!((e.vel_m_s.expect("vel")[0] - 0.1).abs() < 1e-12);
        let a = e.attitude.expect("attitude");
        // Euler angles of the slerped truth: rounding of atan2 near 1 rad, ~1e-12.
        assert!((a.yaw_rad - 0.01).abs() < 1e-10, "{a:?}");
        assert!((a.total_rad - 0.01).abs() < 1e-12, "{a:?}");
        assert!(a.roll_rad.abs() < 1e-12 && a.pitch_rad.abs() < 1e-12);
        let want_distance = 1.5 * e.stamp_ns as f64 * 1e-9;
        assert!((e.distance_m - want_distance).abs() < 1e-9);
    }
    let m = metrics(&errors, unmatched, 0);
    assert!((m.horizontal_rms_m.expect("h") - 5f64.sqrt()).abs() < 1e-6);
    assert!((m.yaw_rms_deg.expect("yaw") - 0.01f64.to_degrees()).abs() < 1e-8);
    let d = m.distance_m.expect("distance");
    assert!((d - 1.5 * 9.8).abs() < 1e-9, "{d}");
    assert!((m.final_error_pct.expect("pct") - 100.0 * 5f64.sqrt() / d).abs() < 1e-6);
    assert!((m.drift_m_per_km.expect("drift") - 1000.0 * 5f64.sqrt() / d).abs() < 1e-6);
}

#[test]
fn estimates_outside_the_truth_or_across_a_hole_are_unmatched() {
    let mut truth = straight_truth();
    // A 2 s hole in the truth.
    truth.retain(|t| !(300_000_000..2_300_000_000).contains(&t.stamp_ns));
    let samples = [0, 1_000_000_000, 2_500_000_005, 20_000_000_000]
        .map(|s| EstimateSample {
            attitude: Some(UnitQuaternion::identity()),
            ..sample(s)
        })
        .to_vec();
    let (errors, unmatched) =
        errors_against_truth(&stream(StreamKind::Attitude, samples), &truth, None);
    assert_eq!(errors.len(), 2);
    assert_eq!(unmatched, 2);
}

#[test]
fn chi_square_regions_and_ellipse_axes() {
    // 3²/25 + 4²/25 = 1: inside; 3² + 4² = 25: outside.
    assert_eq!(
        inside_95_2d([3.0, 4.0], &Matrix2::new(25.0, 0.0, 0.0, 25.0)),
        Some(true)
    );
    assert_eq!(inside_95_2d([3.0, 4.0], &Matrix2::identity()), Some(false));
    // Exactly on the boundary along one axis.
    let r = CHI2_2DOF_95.sqrt();
    assert_eq!(
        inside_95_2d([r * 0.999, 0.0], &Matrix2::identity()),
        Some(true)
    );
    assert_eq!(
        inside_95_2d([r * 1.001, 0.0], &Matrix2::identity()),
        Some(false)
    );
    assert_eq!(inside_95_2d([1.0, 0.0], &Matrix2::zeros()), None);

    let (a, b) = ellipse_axes(&Matrix2::new(9.0, 0.0, 0.0, 4.0));
    assert!((a - 3.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
    // diag(9, 4) rotated by 30° from north towards east.
    let (s, c) = 30f64.to_radians().sin_cos();
    let rot = Matrix2::new(c, -s, s, c);
    let cov = rot * Matrix2::new(9.0, 0.0, 0.0, 4.0) * rot.transpose();
    let (a, b) = ellipse_axes(&cov);
    assert!((a - 3.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
    assert!((ellipse_orientation(&cov) - 30f64.to_radians()).abs() < 1e-12);
    // The quantiles themselves: P(χ²₂ ≤ x) = 1 - exp(-x/2).
    assert!((1.0 - (-CHI2_2DOF_95 / 2.0).exp() - 0.95).abs() < 1e-12);
}

#[test]
fn attitude_inside_95_uses_the_nav_frame_error_and_std() {
    let truth: Vec<TruthSample> = (0..3u64)
        .map(|i| truth_sample(i * 10_000_000, LAT0, LON0, 1.0, 0.0))
        .collect();
    // 0.02 rad about down (a yaw error): inside with σ = 0.01 rad (χ² = 4), outside with 0.005 (16).
    let est = from_euler(0.0, 0.0, 1.02);
    let samples = [0.01, 0.005]
        .iter()
        .enumerate()
        .map(|(i, s)| EstimateSample {
            attitude: Some(est),
            att_std_rad: Some(Vector3::new(1e-9, 1e-9, *s)),
            ..sample(i as u64 * 10_000_000)
        })
        .collect();
    let (errors, _) = errors_against_truth(&stream(StreamKind::Attitude, samples), &truth, None);
    let inside: Vec<Option<bool>> = errors.iter().map(|e| e.inside_95).collect();
    assert_eq!(inside, [Some(true), Some(false)]);
    let m = metrics(&errors, 0, 0);
    assert_eq!(m.inside_95_pct, Some(50.0));
    assert_eq!(m.covariance_samples, Some(2));
    assert!(m.north_rms_m.is_none() && m.final_error_m.is_none());
}

#[test]
fn slerp_takes_the_short_way_whatever_the_signs() {
    let a = from_euler(0.1, 0.2, 3.1);
    let b = from_euler(0.1, 0.2, -3.1);
    let flipped = UnitQuaternion::new_unchecked(-b.into_inner());
    for q in [b, flipped] {
        let mid = interpolate_attitude(&a, &q, 0.5);
        let (_, _, yaw) = to_euler(&mid);
        assert!((yaw.abs() - std::f64::consts::PI).abs() < 1e-9, "{yaw}");
    }
}

#[test]
fn against_gps_the_estimate_is_interpolated_and_its_track_measured() {
    // An estimate moving east 1 m per 100 ms, 2 m north of the fixes.
    let lat_e = LAT0 + 2.0 / meridian_radius(LAT0);
    let east = |k: u64| LON0 + k as f64 / (transverse_radius(lat_e) * lat_e.cos());
    let samples: Vec<EstimateSample> = (0..101u64)
        .map(|k| EstimateSample {
            pos: Some(Horizontal::Geodetic {
                lat_rad: lat_e,
                lon_rad: east(k),
            }),
            cov_ne_m2: Some(Matrix2::identity()),
            ..sample(k * 100_000_000)
        })
        .collect();
    // Fixes every 1.05 s (between estimates), each on the true track.
    let gps: Vec<Gps> = (0..10u64)
        .map(|k| Gps {
            stamp_ns: k * 1_050_000_000,
            lat_rad: LAT0,
            lon_rad: east(0) + (east(1) - east(0)) * k as f64 * 10.5,
            height_m: 0.0,
            horizontal_std_m: 1.0,
            quality: 1,
            velocity: None,
        })
        .collect();
    let (errors, unmatched) = errors_against_gps(&stream(StreamKind::Fix, samples), &gps, None);
    assert_eq!((errors.len(), unmatched), (10, 0));
    for e in &errors {
        let [n, east] = e.ne_m.expect("ne");
        assert!((n - 2.0).abs() < 1e-6 && east.abs() < 1e-6, "{e:?}");
        // χ² = 4 / (1 + 1) = 2: inside.
        assert_eq!(e.inside_95, Some(true));
    }
    let m = metrics(&errors, unmatched, 0);
    let d = m.distance_m.expect("distance");
    assert!((d - 9.0 * 10.5).abs() < 1e-6, "{d}");
    assert!(m.down_rms_m.is_none() && m.vel_north_rms_m_s.is_none());
}

#[test]
fn metrics_without_travel_have_no_relative_error() {
    let e = ErrorSample {
        stamp_ns: 0,
        ne_m: Some([3.0, -4.0]),
        down_m: None,
        vel_m_s: None,
        attitude: None,
        inside_95: None,
        distance_m: 7.0,
    };
    let m = metrics(&[e, e], 0, 0);
    assert_eq!(m.final_error_m, Some(5.0));
    assert_eq!(m.distance_m, Some(0.0));
    assert!(m.final_error_pct.is_none() && m.drift_m_per_km.is_none());
    assert!(m.inside_95_pct.is_none());
    assert_eq!(metrics(&[], 3, 1).samples, 0);
}

fn nav_bytes(lat: f64) -> Vec<u8> {
    codec::encode(&NavSolution {
        header: Header::new(1, 0, Role::Ains, 0),
        lat_rad: lat,
        lon_rad: LON0,
        quat_nb: [1.0, 0.0, 0.0, 0.0],
        ..Default::default()
    })
    .expect("encode")
}

#[test]
fn bad_messages_are_counted_never_trusted() {
    let mut d = Data::default();
    let t = <NavSolution as nauta_messages::Message>::TYPE_NAME;
    d.take("ains/nav", t, &nav_bytes(LAT0));
    d.take("ains/nav", t, &nav_bytes(f64::NAN));
    d.take("ains/nav", t, &nav_bytes(4.0));
    d.take("ains/nav", t, &nav_bytes(LAT0)[..50]);
    d.take("ains/nav", t, &[]);
    d.take("sim/truth", "nauta.TruthState.v1", &[1, 2, 3]);
    d.take("sensor/gps", "nauta.GpsFix.v1", &[0; 8]);
    d.take("sensor/gps", "nauta.GpsFix.v2", &[0; 8]);
    d.take("some/other", "nauta.Unknown.v1", &[0; 3]);
    let s = &d.streams["ains/nav"];
    assert_eq!((s.samples.len(), s.rejected), (1, 4));
    assert_eq!(d.rejected["sim/truth"], 1);
    assert_eq!(
        d.rejected["sensor/gps"], 2,
        "v1 (older recordings) and v2 fixes"
    );
    assert!(!d.rejected.contains_key("some/other"));
    // A zero quaternion: a position-only solution, no attitude.
    let mut m = NavSolution {
        lat_rad: LAT0,
        ..Default::default()
    };
    d.take("ains/nav", t, &codec::encode(&m).expect("encode"));
    assert!(d.streams["ains/nav"].samples[1].attitude.is_none());
    m.quat_nb = [0.5, 0.0, 0.0, 0.0];
    d.take("ains/nav", t, &codec::encode(&m).expect("encode"));
    assert_eq!(d.streams["ains/nav"].rejected, 5);
}

#[test]
fn evaluate_needs_estimates_and_a_reference_and_a_frame_for_local_streams() {
    let file = Path::new("x.mcap");
    let e = evaluate(file, &Data::default()).expect_err("no streams");
    assert!(e.to_string().contains("no estimate stream"), "{e}");

    let mut d = Data::default();
    let lbl = EstimateSample {
        pos: Some(Horizontal::Local {
            north_m: 1.0,
            east_m: 2.0,
        }),
        ..sample(10_000_000)
    };
    d.streams.insert(
        "lbl/nav".into(),
        Stream {
            topic: "lbl/nav".into(),
            ..stream(StreamKind::Lbl, vec![lbl])
        },
    );
    let e = evaluate(file, &d).expect_err("no reference");
    assert!(e.to_string().contains("no reference"), "{e}");

    // A truth that starts under way: no origin, the local stream is skipped.
    d.truth = straight_truth()[10..].to_vec();
    let ev = evaluate(file, &d).expect("evaluate");
    assert!(ev.streams.is_empty());
    assert!(
        ev.skipped["lbl/nav"].contains("no origin"),
        "{:?}",
        ev.skipped
    );

    // From the start, the truth's first point is the origin.
    d.truth = straight_truth();
    let ev = evaluate(file, &d).expect("evaluate");
    let m = &ev.streams["lbl/nav"];
    assert_eq!(m.samples, 1);
    let (n, e) = Origin::to_local(
        &Origin {
            lat_rad: LAT0,
            lon_rad: LON0,
        },
        d.truth[1].lat_rad,
        d.truth[1].lon_rad,
    );
    assert!((m.north_rms_m.expect("n") - (1.0 - n).abs()).abs() < 1e-9);
    assert!((m.east_rms_m.expect("e") - (2.0 - e).abs()).abs() < 1e-9);
}
