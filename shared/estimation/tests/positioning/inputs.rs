//! Bad inputs at the estimator: each refused with its kind and counted,
//! and the state unmoved by them.

use nauta_estimation::Estimator;
use nauta_estimation::frames::Vector;
use nauta_estimation::positioning::{
    Positioning, PositioningEkfParams, PositioningInput, PositioningPfParams, source,
};
use nauta_estimation::readings::{BuoyRangeReading, Depth, Fix, Gps, Nav};

const LAT: f64 = 0.675;
const LON: f64 = -0.159;

fn both() -> [(&'static str, Positioning); 2] {
    [
        (
            "pf",
            Positioning::pf(&PositioningPfParams::default()).expect("defaults"),
        ),
        (
            "ekf",
            Positioning::ekf(&PositioningEkfParams::default()).expect("defaults"),
        ),
    ]
}

fn nav(t_s: f64) -> PositioningInput {
    PositioningInput::Nav(Nav {
        stamp_ns: (t_s * 1e9) as u64,
        lat_rad: LAT,
        lon_rad: LON,
        depth_m: 15.0,
        vel_ned_m_s: Vector::from_array([0.0; 3]),
        attitude: None,
        pos_std_ned_m: Vector::from_array([1.0; 3]),
        vel_std_ned_m_s: Vector::from_array([0.01; 3]),
        predicted_drift_m: 0.0,
        aiding_mode: 0,
        advisory: 0,
    })
}

fn depth(t_s: f64, d: f64) -> PositioningInput {
    PositioningInput::Depth(Depth {
        stamp_ns: (t_s * 1e9) as u64,
        depth_m: d,
    })
}

fn gps(t_s: f64) -> PositioningInput {
    PositioningInput::Gps(Gps {
        stamp_ns: (t_s * 1e9) as u64,
        lat_rad: LAT,
        lon_rad: LON,
        height_m: 0.0,
        horizontal_std_m: 2.0,
        quality: 1,
        velocity: None,
    })
}

/// A buoy 200 m north of the vehicle; `tof_scale` stretches its flight.
fn range(t_s: f64, tof_scale: f64) -> PositioningInput {
    let north = 200.0 / nauta_estimation::earth::meridian_radius(LAT);
    let slant = 200f64.hypot(14.0);
    PositioningInput::Modem(BuoyRangeReading {
        stamp_ns: (t_s * 1e9) as u64,
        buoy_lat_rad: LAT + north,
        buoy_lon_rad: LON,
        buoy_depth_m: 1.0,
        time_of_flight_s: slant / 1500.0 * tof_scale,
        sound_speed_m_s: 1500.0,
    })
}

#[test]
fn bad_inputs_are_refused_by_kind_and_move_nothing() {
    for (name, mut est) in both() {
        let mut out: Vec<Fix> = Vec::new();
        // A range before any position or depth.
        let e = est
            .on_input(&range(1.0, 1.0), &mut out)
            .expect_err("early range");
        assert_eq!(e.kind, "no_position", "{name}");
        // At the surface: a GPS fix starts the filter and is published.
        est.on_input(&depth(2.0, 0.2), &mut out).expect("depth");
        est.on_input(&gps(2.0), &mut out).expect("gps");
        assert_eq!(out.last().map(|f| f.source), Some(source::GPS), "{name}");
        // Submerged: a GPS fix is impossible there.
        est.on_input(&depth(3.0, 15.0), &mut out).expect("depth");
        est.on_input(&nav(3.0), &mut out).expect("nav");
        let e = est.on_input(&gps(3.5), &mut out).expect_err("gps at 15 m");
        assert_eq!(e.kind, "gps_submerged", "{name}");
        // A good range is used; one twice as long (a clock jump) is gated
        // and leaves the estimate where it was.
        out.clear();
        est.on_input(&range(4.0, 1.0), &mut out)
            .expect("good range");
        assert_eq!(out.len(), 1, "{name}");
        let before = est.estimate().expect("estimate");
        let e = est
            .on_input(&range(5.0, 2.0), &mut out)
            .expect_err("long range");
        assert_eq!(e.kind, "gated", "{name}");
        let after = est.estimate().expect("estimate");
        // Only the second of random walk before the gate moves it (the
        // particles' draws), by millimetres.
        let moved = nauta_estimation::local::north_east_of(before.0, before.1, after.0, after.1);
        assert!(
            moved.0.hypot(moved.1) < 0.05,
            "{name}: moved {moved:?} m by a gated range"
        );
        // A range shorter than the depth difference allows (impossible).
        let e = est
            .on_input(&range(6.0, 0.01), &mut out)
            .expect_err("short range");
        assert_eq!(e.kind, "gated", "{name}");
        let s = est.stats();
        assert_eq!(
            (
                s.ranges_early,
                s.gps_submerged,
                s.ranges_gated,
                s.ranges_used,
                s.gps_fixes
            ),
            (1, 1, 2, 1, 1),
            "{name}: {s:?}"
        );
    }
}
