//! Drives the `ekf` estimator with the simulator's survey: the readings of
//! each step as [`AinsInput`]s (IMU, attitude estimate, DVL, depth, GPS,
//! AHRS), the attitude estimate from the attitude role's core run
//! in-process, and the figures of the issue against the truth.

use std::time::{Duration, Instant};

use nauta_estimation::Estimator;
use nauta_estimation::ains::AinsInput;
use nauta_estimation::ains::dr::Site;
use nauta_estimation::ains::ekf::{Ekf, EkfParams, EkfStats};
use nauta_estimation::attitude_core::{
    AttitudeCore, MagnetometerParams, MekfVariantParams, PfVariantParams, VariantParams,
};
use nauta_estimation::readings::{Attitude, Nav};
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioParams};
use nauta_sim::suite::{Measurements, SuiteConfig};

/// The magnetometer calibration that inverts the simulator's survey
/// hard and soft iron (`W = S⁻¹`, `h` in µT), as `nauta calibrate
/// magnetometer` would fit it and the manifest give it.
pub fn calibrated_magnetometer() -> MagnetometerParams {
    let spec = SuiteConfig::survey().imu.mag;
    let s_inv = spec.soft_iron_matrix().try_inverse().expect("invertible");
    MagnetometerParams {
        hard_iron_ut: spec.hard_iron.map(|h| h * 1e6),
        soft_iron_inv: [0, 1, 2].map(|r| [0, 1, 2].map(|c| s_inv[(r, c)])),
    }
}

/// The attitude role's `pf` (default, `alignment_samples = 400` as the
/// shipped manifests) with the calibrated magnetometer.
pub fn attitude_pf() -> Heading {
    Heading::Attitude(Box::new(VariantParams::Pf(PfVariantParams {
        alignment_samples: 400,
        magnetometer: calibrated_magnetometer(),
        ..Default::default()
    })))
}

/// The same with the `mekf`.
pub fn attitude_mekf() -> Heading {
    Heading::Attitude(Box::new(VariantParams::Mekf(MekfVariantParams {
        alignment_samples: 400,
        magnetometer: calibrated_magnetometer(),
        ..Default::default()
    })))
}

/// Where the heading aiding comes from.
#[derive(Debug, Clone)]
pub enum Heading {
    /// The AHRS only (no attitude estimate).
    Ahrs,
    /// The attitude role's core of these parameters, run in-process on
    /// the same IMU samples (and the AHRS, which the EKF then ignores).
    Attitude(Box<VariantParams>),
}

/// One step's readings as inputs, appended to `out` (the attitude
/// estimate, if any, right after the IMU sample it came from).
pub fn inputs(m: &Measurements, attitude: Option<&mut AttitudeCore>, out: &mut Vec<AinsInput>) {
    if let Some(r) = &m.imu {
        let imu = nauta_sim::ains_inputs::imu(r);
        out.push(AinsInput::Imu(imu));
        if let Some(core) = attitude
            && let Some(o) = core.step(&imu).expect("attitude step")
        {
            out.push(AinsInput::Attitude(Attitude {
                stamp_ns: imu.stamp_ns,
                attitude: o.q_nb,
                std_rad: o.std_rad,
                gyro_bias_rad_s: o.gyro_bias,
            }));
        }
    }
    nauta_sim::ains_inputs::aiding(m, false, out);
}

/// The end of one dive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiveEnd {
    /// Distance travelled since the last GPS fix before the dive, m.
    pub distance_m: f64,
    /// North, east, down error of the last solution before the first fix
    /// after the dive, m.
    pub error_ned_m: [f64; 3],
    /// The published horizontal σ then (`predicted_drift_m`), m.
    pub predicted_drift_m: f64,
}

/// What a run measured (submerged: more than 2 s since the last GPS fix).
#[derive(Debug, Clone)]
pub struct Figures {
    /// Each completed dive.
    pub dives: Vec<DiveEnd>,
    /// Least-squares slope of the N, E, D error against the distance
    /// travelled submerged, over every submerged solution, m/km.
    pub slope_m_per_km: [f64; 3],
    /// RMS of the N, E, D velocity error over the submerged solutions, m/s.
    pub vel_rms_m_s: [f64; 3],
    /// Fraction of submerged solutions whose horizontal error is inside
    /// the published 95 % ellipse (`(e_N/σ_N)² + (e_E/σ_E)² ≤ 5.991`).
    pub inside_95: f64,
    /// Fraction of submerged solutions with the velocity error inside
    /// 1.96 σ on every axis.
    pub vel_inside_95: f64,
    /// Largest horizontal error submerged, m.
    pub max_horizontal_m: f64,
    /// Submerged solutions.
    pub submerged: usize,
    /// Solutions.
    pub outputs: usize,
    /// The estimator's counters.
    pub stats: EkfStats,
    /// Time spent in the estimator (not the simulator nor the attitude
    /// core).
    pub ekf_time: Duration,
    /// IMU samples fed.
    pub imu_samples: u64,
    /// The last solution.
    pub last: Option<Nav>,
    /// RMS yaw error submerged, and RMS of the filter's yaw σ, rad.
    pub yaw_rms_rad: [f64; 2],
    /// Σ squared yaw error, Σ published yaw variance, count, of the
    /// attitude estimate fed in.
    pub source_yaw: [f64; 3],
    /// One solution a second.
    pub trace: Vec<TracePoint>,
    /// Heading north, south, other: Σ source yaw error, n, Σ EKF yaw error, n.
    pub legs: [[f64; 4]; 3],
}

impl Figures {
    /// Time in the estimator per IMU sample, µs.
    pub fn us_per_imu(&self) -> f64 {
        self.ekf_time.as_secs_f64() * 1e6 / self.imu_samples.max(1) as f64
    }

    /// The end-of-dive drift per axis, m/km (worst dive).
    pub fn dive_drift_m_per_km(&self) -> [f64; 3] {
        let mut d = [0.0f64; 3];
        for e in &self.dives {
            for (k, x) in d.iter_mut().enumerate() {
                *x = x.max(e.error_ned_m[k].abs() / (e.distance_m * 1e-3));
            }
        }
        d
    }
}

/// A least-squares line `y = a + b x`: its slope `b`.
fn slope(sx: f64, sy: f64, sxx: f64, sxy: f64, n: f64) -> f64 {
    let d = n * sxx - sx * sx;
    if d > 0.0 {
        (n * sxy - sx * sy) / d
    } else {
        0.0
    }
}

/// The simulator's declination at the scenario's origin and the origin as
/// the site.
pub fn site(g: &Generator) -> Site {
    let o = g.simulator().mission().origin();
    Site {
        lat_rad: o.lat_rad,
        lon_rad: o.lon_rad,
        declination_rad: g.suite().declination_rad(),
    }
}

/// The survey (`ScenarioParams::default()`, 100 Hz IMU) of `seed` for
/// `duration_s` through an `ekf` of `params`, heading from `heading`;
/// `each` sees every input and the estimator after it (for snapshot tests).
pub fn run(seed: u64, duration_s: f64, params: &EkfParams, heading: Heading) -> Figures {
    run_with(
        seed,
        duration_s,
        params,
        heading,
        SuiteConfig::survey(),
        None,
    )
}

/// One solution a second.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TracePoint {
    /// Time, s.
    pub t_s: f64,
    /// `aiding_mode`.
    pub aiding_mode: u32,
    /// `predicted_drift_m`.
    pub predicted_drift_m: f64,
    /// Velocity σ north, m/s.
    pub vel_std_n_m_s: f64,
    /// Horizontal error, m.
    pub horizontal_error_m: f64,
}

/// [`run`] with these sensors, and without the DVL samples in
/// `dvl_gap_s` (from, to), s.
pub fn run_with(
    seed: u64,
    duration_s: f64,
    params: &EkfParams,
    heading: Heading,
    sensors: SuiteConfig,
    dvl_gap_s: Option<(f64, f64)>,
) -> Figures {
    let scenario = ScenarioParams::default();
    let mut g = Generator::new(&scenario, Origin::lisbon(), sensors, seed, duration_s)
        .expect("valid scenario");
    let origin = g.simulator().mission().origin();
    let mut ekf = Ekf::new(params, site(&g)).expect("valid");
    let mut core = match heading {
        Heading::Ahrs => None,
        Heading::Attitude(ref p) => {
            Some(AttitudeCore::new(p, origin.lat_rad, g.suite().declination_rad()).expect("valid"))
        }
    };
    let mut buf = Vec::new();
    let mut out = Vec::new();
    let mut f = Figures {
        dives: Vec::new(),
        slope_m_per_km: [0.0; 3],
        vel_rms_m_s: [0.0; 3],
        inside_95: 0.0,
        vel_inside_95: 0.0,
        max_horizontal_m: 0.0,
        submerged: 0,
        outputs: 0,
        stats: EkfStats::default(),
        ekf_time: Duration::ZERO,
        imu_samples: 0,
        last: None,
        yaw_rms_rad: [0.0; 2],
        source_yaw: [0.0; 3],
        trace: Vec::new(),
        legs: [[0.0; 4]; 3],
    };
    let mut syaw = [0.0; 2];
    let mut last_gps_ns: Option<u64> = None;
    let mut dive_start_distance = 0.0;
    let mut in_dive = false;
    let mut last_submerged: Option<DiveEnd> = None;
    let (mut sx, mut sxx) = (0.0, 0.0);
    let (mut sy, mut sxy) = ([0.0; 3], [0.0; 3]);
    let mut sv = [0.0; 3];
    let (mut inside, mut vel_inside) = (0usize, 0usize);
    while let Some(s) = g.step() {
        let s = s.expect("valid step");
        buf.clear();
        inputs(&s, core.as_mut(), &mut buf);
        if let Some((a, b)) = dvl_gap_s {
            let t = s.stamp_ns as f64 * 1e-9;
            if t >= a && t < b {
                buf.retain(|i| !matches!(i, AinsInput::Dvl(_)));
            }
        }
        out.clear();
        for i in &buf {
            if let AinsInput::Attitude(a) = i {
                let tq = nauta_estimation::frames::Rotation::<
                    nauta_estimation::frames::Frd,
                    nauta_estimation::frames::Ned,
                >::from_wxyz(s.truth.quat_nb)
                .expect("unit");
                let ey = nauta_estimation::attitude::wrap_pi(a.attitude.euler().2 - tq.euler().2);
                f.source_yaw[0] += ey * ey;
                f.source_yaw[1] += a.std_rad.z() * a.std_rad.z();
                f.source_yaw[2] += 1.0;
                let c = tq.euler().2.cos();
                let k = if c > 0.9 {
                    0
                } else if c < -0.9 {
                    1
                } else {
                    2
                };
                f.legs[k][0] += ey;
                f.legs[k][1] += 1.0;
            }
        }
        let t0 = Instant::now();
        for i in &buf {
            ekf.on_input(i, &mut out).expect("valid input");
        }
        f.ekf_time += t0.elapsed();
        if s.imu.is_some() {
            f.imu_samples += 1;
        }
        if let Some(gps) = &s.gps {
            if in_dive && let Some(end) = last_submerged.take() {
                f.dives.push(end);
            }
            in_dive = false;
            last_gps_ns = Some(gps.stamp_ns);
            dive_start_distance = s.truth.distance_m;
        }
        let Some(nav) = out.last() else {
            continue;
        };
        f.outputs += 1;
        f.last = Some(*nav);
        if s.stamp_ns % 1_000_000_000 == 0 {
            let (nn, ne) = origin.to_local(nav.lat_rad, nav.lon_rad);
            let (tn, te) = origin.to_local(s.truth.lat_rad, s.truth.lon_rad);
            f.trace.push(TracePoint {
                t_s: s.stamp_ns as f64 * 1e-9,
                aiding_mode: nav.aiding_mode,
                predicted_drift_m: nav.predicted_drift_m,
                vel_std_n_m_s: nav.vel_std_ned_m_s.x(),
                horizontal_error_m: (nn - tn).hypot(ne - te),
            });
        }
        let submerged = last_gps_ns.is_some_and(|l| s.stamp_ns.saturating_sub(l) > 2_000_000_000);
        if !submerged {
            continue;
        }
        in_dive = true;
        let t = &s.truth;
        let (nn, ne) = origin.to_local(nav.lat_rad, nav.lon_rad);
        let (tn, te) = origin.to_local(t.lat_rad, t.lon_rad);
        let e = [nn - tn, ne - te, nav.depth_m - t.depth_m];
        let d_km = (t.distance_m - dive_start_distance) * 1e-3;
        last_submerged = Some(DiveEnd {
            distance_m: d_km * 1e3,
            error_ned_m: e,
            predicted_drift_m: nav.predicted_drift_m,
        });
        f.submerged += 1;
        sx += d_km;
        sxx += d_km * d_km;
        let v = nav.vel_ned_m_s.to_array();
        let vs = nav.vel_std_ned_m_s.to_array();
        let mut v_in = true;
        for k in 0..3 {
            sy[k] += e[k];
            sxy[k] += d_km * e[k];
            let ev = v[k] - t.vel_ned_m_s[k];
            sv[k] += ev * ev;
            v_in &= ev.abs() <= 1.96 * vs[k];
        }
        vel_inside += v_in as usize;
        let ps = nav.pos_std_ned_m.to_array();
        let m2 = (e[0] / ps[0]).powi(2) + (e[1] / ps[1]).powi(2);
        inside += (m2 <= 5.991) as usize;
        f.max_horizontal_m = f.max_horizontal_m.max(e[0].hypot(e[1]));
        if let (Some(q), Some(fl)) = (nav.attitude, ekf.filter()) {
            let tq = nauta_estimation::frames::Rotation::<
                nauta_estimation::frames::Frd,
                nauta_estimation::frames::Ned,
            >::from_wxyz(t.quat_nb)
            .expect("unit");
            let ey = nauta_estimation::attitude::wrap_pi(q.euler().2 - tq.euler().2);
            syaw[0] += ey * ey;
            let c = tq.euler().2.cos();
            let k = if c > 0.9 {
                0
            } else if c < -0.9 {
                1
            } else {
                2
            };
            f.legs[k][2] += ey;
            f.legs[k][3] += 1.0;
            syaw[1] += fl.p[(2, 2)];
        }
    }
    let n = f.submerged.max(1) as f64;
    for k in 0..3 {
        f.slope_m_per_km[k] = slope(sx, sy[k], sxx, sxy[k], n);
        f.vel_rms_m_s[k] = (sv[k] / n).sqrt();
    }
    f.inside_95 = inside as f64 / n;
    f.vel_inside_95 = vel_inside as f64 / n;
    f.stats = ekf.stats();
    f.yaw_rms_rad = [(syaw[0] / n).sqrt(), (syaw[1] / n).sqrt()];
    f
}

/// Prints a run's figures.
pub fn report(name: &str, f: &Figures) {
    let d = f.dive_drift_m_per_km();
    eprintln!(
        "{name}: dives {} (distance {:.0?} m, end error NED {:.2?} m, σ_h {:.2?} m) | \
         end drift N/E/D {:.2}/{:.2}/{:.2} m/km | slope N/E/D {:.2}/{:.2}/{:.2} m/km | \
         vel RMS N/E/D {:.4}/{:.4}/{:.4} m/s | inside 95 % pos {:.1} % vel {:.1} % | \
         max horiz {:.2} m | yaw RMS {:.3}° σ {:.3}° (source {:.3}° σ {:.3}°) | \
         mean yaw error heading N/S/other: source {:.3?}°, ekf {:.3?}° | {} submerged of {} outputs | {:.3} µs per IMU sample | {:?}",
        f.dives.len(),
        f.dives.iter().map(|e| e.distance_m).collect::<Vec<_>>(),
        f.dives.iter().map(|e| e.error_ned_m).collect::<Vec<_>>(),
        f.dives
            .iter()
            .map(|e| e.predicted_drift_m)
            .collect::<Vec<_>>(),
        d[0],
        d[1],
        d[2],
        f.slope_m_per_km[0],
        f.slope_m_per_km[1],
        f.slope_m_per_km[2],
        f.vel_rms_m_s[0],
        f.vel_rms_m_s[1],
        f.vel_rms_m_s[2],
        100.0 * f.inside_95,
        100.0 * f.vel_inside_95,
        f.max_horizontal_m,
        f.yaw_rms_rad[0].to_degrees(),
        f.yaw_rms_rad[1].to_degrees(),
        (f.source_yaw[0] / f.source_yaw[2].max(1.0))
            .sqrt()
            .to_degrees(),
        (f.source_yaw[1] / f.source_yaw[2].max(1.0))
            .sqrt()
            .to_degrees(),
        f.legs.map(|l| (l[0] / l[1].max(1.0)).to_degrees()),
        f.legs.map(|l| (l[2] / l[3].max(1.0)).to_degrees()),
        f.submerged,
        f.outputs,
        f.us_per_imu(),
        f.stats,
    );
}
