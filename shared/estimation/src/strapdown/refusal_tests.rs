//! Tests of what the strapdown refuses (bad samples, bad states) and of the
//! longitude's wrap across the antimeridian: the mechanization's input
//! checks, apart from its accuracy (`tests.rs`).

use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};

use crate::attitude::from_euler;

use super::*;

fn sample_state() -> StrapdownState {
    StrapdownState::at_depth(
        Rotation::from_euler(0.1, -0.05, 1.0),
        Vector::new(1.0, 0.5, 0.1),
        0.67,
        -0.16,
        15.0,
    )
}

#[test]
fn refuses_bad_samples_and_keeps_the_state() {
    let mut nav = Strapdown::new(sample_state()).expect("valid");
    let before = nav.state();
    let g = Vector3::new(0.0, 0.0, 0.01);
    let a = Vector3::new(0.0, 0.0, -9.8);
    let nan = Vector3::new(f64::NAN, 0.0, 0.0);
    let inf = Vector3::new(0.0, f64::INFINITY, 0.0);
    assert_eq!(
        nav.update(&Vector::from_nalgebra(nan), &Vector::from_nalgebra(a), 0.01),
        Err(StrapdownError::NonFiniteSample)
    );
    assert_eq!(
        nav.update(&Vector::from_nalgebra(g), &Vector::from_nalgebra(inf), 0.01),
        Err(StrapdownError::NonFiniteSample)
    );
    for dt in [0.0, -0.01, f64::NAN, f64::INFINITY, 1.5] {
        match nav.update(&Vector::from_nalgebra(g), &Vector::from_nalgebra(a), dt) {
            Err(StrapdownError::BadInterval(x)) => {
                assert!(x.to_bits() == dt.to_bits(), "{x} vs {dt}")
            }
            other => panic!("dt {dt}: {other:?}"),
        }
    }
    assert!(matches!(
        nav.update(
            &Vector::from_nalgebra(Vector3::new(50.0, 0.0, 0.0)),
            &Vector::from_nalgebra(a),
            0.01
        ),
        Err(StrapdownError::SampleOutOfRange { .. })
    ));
    assert!(matches!(
        nav.update(
            &Vector::from_nalgebra(g),
            &Vector::from_nalgebra(Vector3::new(0.0, 0.0, -2000.0)),
            0.01
        ),
        Err(StrapdownError::SampleOutOfRange { .. })
    ));
    assert_eq!(nav.state(), before);
    assert_eq!(nav.rejected_count(), 9);
    assert_eq!(nav.step_count(), 0);
    // The largest interval is accepted.
    nav.update(
        &Vector::from_nalgebra(g),
        &Vector::from_nalgebra(a),
        MAX_INTERVAL_S,
    )
    .expect("1 s is allowed");
    assert_eq!(nav.step_count(), 1);
}

#[test]
fn refuses_bad_states() {
    let ok = sample_state();
    assert!(Strapdown::new(ok).is_ok());
    let cases = [
        (
            StrapdownState {
                lat_rad: 1.56,
                ..ok
            },
            StrapdownError::LatitudeOutOfRange(1.56),
        ),
        (
            StrapdownState {
                height_m: f64::NAN,
                ..ok
            },
            StrapdownError::NonFiniteState,
        ),
        (
            StrapdownState {
                v_ned_m_s: Vector::new(0.0, f64::INFINITY, 0.0),
                ..ok
            },
            StrapdownError::NonFiniteState,
        ),
    ];
    for (s, want) in cases {
        assert_eq!(Strapdown::new(s).err(), Some(want));
    }
    assert!(matches!(
        Strapdown::new(StrapdownState {
            lat_rad: f64::NAN,
            ..ok
        }),
        Err(StrapdownError::LatitudeOutOfRange(_))
    ));
    let not_unit = UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(1.1, 0.0, 0.0, 0.0));
    assert!(matches!(
        Strapdown::new(StrapdownState {
            q_nb: Rotation::from_nalgebra(not_unit),
            ..ok
        }),
        Err(StrapdownError::NotUnitQuaternion(_))
    ));
    // set_state validates too and keeps the old state on refusal.
    let mut nav = Strapdown::new(ok).expect("valid");
    assert!(
        nav.set_state(StrapdownState {
            lat_rad: -1.6,
            ..ok
        })
        .is_err()
    );
    assert_eq!(nav.state(), ok);
    // A step that would cross the latitude limit is refused.
    let edge = StrapdownState {
        lat_rad: MAX_ABS_LATITUDE_RAD - 1e-9,
        v_ned_m_s: Vector::new(100.0, 0.0, 0.0),
        q_nb: Rotation::identity(),
        ..ok
    };
    let mut nav = Strapdown::new(edge).expect("valid");
    let g_edge = normal_gravity(edge.lat_rad, edge.height_m);
    assert!(matches!(
        nav.update(
            &Vector::from_nalgebra(Vector3::zeros()),
            &Vector::from_nalgebra(Vector3::new(0.0, 0.0, -g_edge)),
            1.0
        ),
        Err(StrapdownError::LatitudeOutOfRange(_))
    ));
    assert_eq!(nav.state(), edge);
}

/// Eastward across the antimeridian: the longitude wraps and the track is
/// continuous.
#[test]
fn longitude_wraps_across_the_antimeridian() {
    let lat: f64 = 0.2;
    let q = from_euler(0.0, 0.0, 0.5 * PI);
    let v = Vector3::new(0.0, 2.0, 0.0);
    let start = StrapdownState::at_depth(
        Rotation::from_nalgebra(q),
        Vector::from_nalgebra(v),
        lat,
        PI - 1e-7,
        10.0,
    );
    let mut nav = Strapdown::new(start).expect("valid");
    // Hold the velocity: feed the specific force that cancels gravity, Coriolis
    // and the transport-rate terms, and the gyro that keeps the attitude in NED.
    for _ in 0..500 {
        let s = nav.state();
        let w_ie = earth_rate_ned(s.lat_rad);
        let w_en = transport_rate_ned(s.lat_rad, s.height_m, s.v_ned_m_s.as_nalgebra());
        let g = Vector3::new(0.0, 0.0, normal_gravity(s.lat_rad, s.height_m));
        let f_n = (2.0 * w_ie + w_en).cross(s.v_ned_m_s.as_nalgebra()) - g;
        let gyro = s
            .q_nb
            .as_nalgebra()
            .inverse_transform_vector(&(w_ie + w_en));
        let accel = s.q_nb.as_nalgebra().inverse_transform_vector(&f_n);
        nav.update(
            &Vector::from_nalgebra(gyro),
            &Vector::from_nalgebra(accel),
            0.01,
        )
        .expect("valid");
    }
    let s = nav.state();
    assert!(s.lon_rad < 0.0 && s.lon_rad >= -PI, "{s:?}");
    let travelled = crate::attitude::wrap_pi(s.lon_rad - start.lon_rad)
        * (transverse_radius(lat) - 10.0)
        * lat.cos();
    assert!((travelled - 10.0).abs() < 1e-3, "{travelled}");
    assert!(s.geodetic().is_ok());
    assert!((s.depth_m() - 10.0).abs() < 1e-3, "{s:?}");
}
