use super::*;
use crate::environment::{Current, MagneticField, Water};
use crate::mission::{
    AttitudeMotion, DrManoeuvre, Origin, SurveySpec, WaypointMission, attitude, dr, lbl, survey,
};
use nauta_estimation::attitude::wrap_pi;
use nauta_estimation::earth::transverse_radius;
use nauta_estimation::frames::Vector;
use nauta_estimation::strapdown::Strapdown;

fn env() -> Environment {
    let o = Origin::lisbon();
    Environment {
        magnetic: MagneticField::from_wmm(o.lat_rad, o.lon_rad, 0.0, 2026, 182).expect("wmm"),
        water: Water::default(),
        current: Current::none(),
    }
}

fn sim(mission: Mission, env: Environment, seed: u64) -> Simulator {
    Simulator::new(
        mission,
        env,
        SimConfig {
            seed,
            ..SimConfig::default()
        },
    )
    .expect("valid config")
}

/// Horizontal and vertical error of an INS state against the truth, m.
fn errors(est: &StrapdownState, t: &Truth) -> (f64, f64) {
    let dn = (est.lat_rad - t.lat_rad) * meridian_radius(t.lat_rad);
    let de = wrap_pi(est.lon_rad - t.lon_rad) * transverse_radius(t.lat_rad) * t.lat_rad.cos();
    (dn.hypot(de), (est.height_m - t.height_m()).abs())
}

/// The acceptance test (issue): the strapdown mechanization fed the noise-free
/// IMU of a 10-minute survey leg (with its turns and depth changes) stays within
/// 1 m of the truth, and within 0.01° in attitude.
#[test]
fn strapdown_follows_ten_minutes_of_survey() {
    let mut s = sim(survey(Origin::lisbon(), &SurveySpec::default()), env(), 7);
    let mut ins = Strapdown::new(s.truth().strapdown_state()).expect("valid start");
    let (mut max_h, mut max_v, mut max_att, mut max_vel) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let (mut min_yaw, mut max_yaw) = (f64::MAX, f64::MIN);
    let mut max_depth = 0.0f64;
    let mut last = *s.truth();
    for _ in 0..60_000 {
        let (truth, imu) = s.step();
        ins.update(
            &Vector::from_nalgebra(imu.gyro_rad_s),
            &Vector::from_nalgebra(imu.accel_m_s2),
            imu.dt_s,
        )
        .expect("sample accepted");
        let est = ins.state();
        let (h, v) = errors(&est, &truth);
        max_h = max_h.max(h);
        max_v = max_v.max(v);
        max_att = max_att.max(est.q_nb.as_nalgebra().angle_to(&truth.q_nb));
        max_vel = max_vel.max((est.v_ned_m_s.to_nalgebra() - truth.v_ned_m_s).norm());
        min_yaw = min_yaw.min(s.vehicle_state().yaw_rad);
        max_yaw = max_yaw.max(s.vehicle_state().yaw_rad);
        max_depth = max_depth.max(truth.depth_m);
        last = truth;
    }
    eprintln!(
        "survey 10 min: horizontal {max_h:.3e} m, vertical {max_v:.3e} m, attitude {:.3e}°, velocity {max_vel:.3e} m/s; distance {:.1} m, yaw span {:.1}°, max depth {max_depth:.2} m",
        max_att.to_degrees(),
        last.distance_m,
        (max_yaw - min_yaw).to_degrees()
    );
    // The leg is what it claims: a turn and a dive.
    assert!((max_yaw - min_yaw).to_degrees() > 90.0);
    assert!(max_depth > 14.0);
    assert!(last.distance_m > 800.0);
    assert!(max_h < 1.0 && max_v < 1.0, "{max_h} {max_v}");
    assert!(max_att.to_degrees() < 0.01, "{max_att}");
}

/// The same with a water current and a different start latitude: the IMU is
/// consistent whatever the vehicle does over ground.
#[test]
fn strapdown_follows_the_lbl_route_in_a_current() {
    let o = Origin::from_degrees(-23.8, -45.4);
    let mut e = env();
    e.current = Current::lbl_default();
    let mut s = sim(lbl(o, 1), e, 3);
    let mut ins = Strapdown::new(s.truth().strapdown_state()).expect("valid start");
    let (mut max_h, mut max_v, mut max_att) = (0.0f64, 0.0f64, 0.0f64);
    for _ in 0..30_000 {
        let (truth, imu) = s.step();
        ins.update(
            &Vector::from_nalgebra(imu.gyro_rad_s),
            &Vector::from_nalgebra(imu.accel_m_s2),
            imu.dt_s,
        )
        .expect("sample accepted");
        let (h, v) = errors(&ins.state(), &truth);
        max_h = max_h.max(h);
        max_v = max_v.max(v);
        max_att = max_att.max(ins.state().q_nb.as_nalgebra().angle_to(&truth.q_nb));
    }
    eprintln!(
        "lbl 5 min in current: horizontal {max_h:.3e} m, vertical {max_v:.3e} m, attitude {:.3e}°",
        max_att.to_degrees()
    );
    assert!(max_h < 0.1 && max_v < 0.1 && max_att.to_degrees() < 0.01);
}

struct Run {
    truths: Vec<Truth>,
    max_yaw_rate: f64,
    max_pitch: f64,
}

fn run_to_end(mut s: Simulator, limit_s: f64) -> Run {
    let mut truths = vec![*s.truth()];
    let (mut max_yaw_rate, mut max_pitch) = (0.0f64, 0.0f64);
    while !s.finished() && s.truth().t_s < limit_s {
        let (t, _) = s.step();
        max_yaw_rate = max_yaw_rate.max(s.vehicle_state().yaw_rate_rad_s.abs());
        max_pitch = max_pitch.max(s.vehicle_state().pitch_rad.abs());
        truths.push(t);
    }
    Run {
        truths,
        max_yaw_rate,
        max_pitch,
    }
}

fn check_visits(w: &WaypointMission, r: &Run, tol_m: f64) {
    let mut from = 0;
    for (i, wp) in w.waypoints.iter().enumerate() {
        // Waypoints are visited in order: the first pass within the tolerance
        // after the previous visit.
        let dist = |t: &Truth| (t.north_m - wp.north_m).hypot(t.east_m - wp.east_m);
        match r.truths[from..].iter().position(|t| dist(t) < tol_m) {
            Some(k) => from += k,
            None => {
                let closest = r.truths[from..].iter().map(dist).fold(f64::MAX, f64::min);
                panic!("{}: waypoint {i} missed by {closest:.1} m", w.name);
            }
        }
    }
}

#[test]
fn survey_visits_its_waypoints_and_surfaces() {
    let m = survey(Origin::lisbon(), &SurveySpec::default());
    let Mission::Waypoints(w) = m.clone() else {
        unreachable!("survey is a waypoint mission")
    };
    let s = sim(m, env(), 1);
    let r = run_to_end(s, 4.0 * 3600.0);
    let end = r.truths.last().expect("ran");
    let p = VehicleParams::remus100();
    eprintln!(
        "survey: {:.1} min, {:.0} m, ends at depth {} m, max yaw rate {:.3}°/s, max |pitch| {:.3}°",
        end.t_s / 60.0,
        end.distance_m,
        end.depth_m,
        r.max_yaw_rate.to_degrees(),
        r.max_pitch.to_degrees()
    );
    check_visits(&w, &r, 12.0);
    assert_eq!(end.depth_m, 0.0);
    assert!(end.speed_through_water_m_s < 0.01);
    assert!((40.0..50.0).contains(&(end.t_s / 60.0)), "{}", end.t_s);
    assert!(r.max_yaw_rate <= p.max_yaw_rate_rad_s + 1e-12);
    assert!(r.max_pitch <= p.max_pitch_rad + 1e-9);
    // Transects held at survey depth: mid-leg of the third transect.
    let mid = r
        .truths
        .iter()
        .find(|t| t.east_m > 95.0 && (t.north_m - 300.0).abs() < 5.0)
        .expect("third transect");
    assert!((mid.depth_m - 15.0).abs() < 0.5, "{}", mid.depth_m);
    assert!(mid.east_m < 105.0);
}

#[test]
fn lbl_route_holds_the_track_in_a_current() {
    let m = lbl(Origin::lisbon(), 1);
    let Mission::Waypoints(w) = m.clone() else {
        unreachable!("lbl is a waypoint mission")
    };
    let mut e = env();
    e.current = Current::lbl_default();
    let r = run_to_end(sim(m, e, 2), 3.0 * 3600.0);
    let end = r.truths.last().expect("ran");
    eprintln!(
        "lbl: {:.1} min, {:.0} m over ground",
        end.t_s / 60.0,
        end.distance_m
    );
    check_visits(&w, &r, 12.0);
    assert!(end.distance_m > 2000.0);
    // On the second side (north = 500, east 100..300) the cross-track error is small.
    for t in r
        .truths
        .iter()
        .filter(|t| t.east_m > 100.0 && t.east_m < 300.0 && t.north_m > 400.0)
    {
        assert!((t.north_m - 500.0).abs() < 3.0, "{t:?}");
    }
}

#[test]
fn dr_manoeuvres_match_paper_002() {
    // (manoeuvre, paper distance m, paper time min)
    for (which, dist, minutes) in [
        (DrManoeuvre::One, 650.0, 11.0),
        (DrManoeuvre::Two, 3543.0, 49.0),
        (DrManoeuvre::Three, 10752.0, 142.0),
    ] {
        let m = dr(Origin::lisbon(), which);
        let r = run_to_end(sim(m, env(), 0), 4.0 * 3600.0);
        let end = r.truths.last().expect("ran");
        eprintln!(
            "{which:?}: {:.1} min, {:.0} m (paper: {minutes} min, {dist} m)",
            end.t_s / 60.0,
            end.distance_m
        );
        assert!((end.distance_m / dist - 1.0).abs() < 0.1);
        assert!((end.t_s / 60.0 / minutes - 1.0).abs() < 0.15);
        assert_eq!(end.depth_m, 0.0);
    }
}

#[test]
fn same_seed_same_truth_bit_for_bit() {
    let make = |seed| {
        let mut e = env();
        e.current = Current::lbl_default();
        let mut s = sim(survey(Origin::lisbon(), &SurveySpec::default()), e, seed);
        (0..3000).map(|_| s.step()).collect::<Vec<_>>()
    };
    let (a, b, c) = (make(11), make(11), make(12));
    assert!(a.iter().zip(&b).all(|(x, y)| {
        x.0.q_nb
            .coords
            .iter()
            .zip(y.0.q_nb.coords.iter())
            .all(|(p, q)| p.to_bits() == q.to_bits())
            && x.0.lat_rad.to_bits() == y.0.lat_rad.to_bits()
            && x.1
                .accel_m_s2
                .iter()
                .zip(y.1.accel_m_s2.iter())
                .all(|(p, q)| p.to_bits() == q.to_bits())
    }));
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn still_imu_sees_gravity_earth_rate_and_the_field() {
    let o = Origin::lisbon();
    let e = env();
    let mut s = sim(attitude(o, AttitudeMotion::Still, 10.0), e, 0);
    let (t, imu) = s.step();
    let q = t.q_nb;
    let g = q.inverse_transform_vector(&Vector3::new(0.0, 0.0, -normal_gravity(o.lat_rad, 0.0)));
    let w = q.inverse_transform_vector(&earth_rate_ned(o.lat_rad));
    assert!((imu.accel_m_s2 - g).norm() < 1e-9, "{:?}", imu.accel_m_s2);
    assert!((imu.gyro_rad_s - w).norm() < 1e-15);
    assert!((imu.mag_t - q.inverse_transform_vector(&e.magnetic.ned_t)).norm() < 1e-18);
    let (_, _, yaw) = t.euler_rad();
    assert!((yaw - 30f64.to_radians()).abs() < 1e-12);
}

#[test]
fn attitude_motions_are_reproduced_by_the_mechanization() {
    let o = Origin::lisbon();
    for motion in [
        AttitudeMotion::Still,
        AttitudeMotion::rocking(),
        AttitudeMotion::yaw_turns(),
    ] {
        let mut s = sim(attitude(o, motion, 60.0), env(), 0);
        let mut ins = Strapdown::new(s.truth().strapdown_state()).expect("valid");
        let mut max_att = 0.0f64;
        let mut max_pos = 0.0f64;
        while !s.finished() {
            let (t, imu) = s.step();
            ins.update(
                &Vector::from_nalgebra(imu.gyro_rad_s),
                &Vector::from_nalgebra(imu.accel_m_s2),
                imu.dt_s,
            )
            .expect("accepted");
            max_att = max_att.max(ins.state().q_nb.as_nalgebra().angle_to(&t.q_nb));
            let (h, v) = errors(&ins.state(), &t);
            max_pos = max_pos.max(h.max(v));
        }
        eprintln!(
            "{motion:?}: attitude {:.2e}°, position {max_pos:.2e} m",
            max_att.to_degrees()
        );
        assert!(max_att.to_degrees() < 1e-6 && max_pos < 1e-3);
    }
}

#[test]
fn propeller_and_current_in_the_truth() {
    let mut e = env();
    e.current = Current::lbl_default();
    let mut s = sim(lbl(Origin::lisbon(), 1), e, 5);
    for _ in 0..12_000 {
        s.step();
    }
    let t = *s.truth();
    assert!(
        (t.propeller_rad_s * crate::vehicle::PROPELLER_ADVANCE_M_PER_RAD
            - t.speed_through_water_m_s)
            .abs()
            < 1e-12
    );
    assert!((t.current_ned_m_s - s.environment().current.at(t.t_s)).norm() < 1e-15);
    // Over ground = through the water along the body x axis + current.
    let water = t.q_nb * Vector3::new(t.speed_through_water_m_s, 0.0, 0.0);
    assert!((t.v_ned_m_s - water - t.current_ned_m_s).norm() < 1e-12);
}

#[test]
fn refuses_bad_config() {
    let m = survey(Origin::lisbon(), &SurveySpec::default());
    let bad = SimConfig {
        substeps: 0,
        ..SimConfig::default()
    };
    assert!(Simulator::new(m, env(), bad).is_err());
}
