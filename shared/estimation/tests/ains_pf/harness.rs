//! Drives the `pf` aided INS with the simulator: the survey scenario's
//! readings as [`AinsInput`]s (IMU, attitude, DVL, depth, GPS, AHRS, the
//! order the service declares its inputs), the attitude input from the
//! real attitude estimator run in-process on the same IMU samples
//! ([`AttitudeCore`], [`attitude_core`]), and the scores against the
//! truth.

use std::time::{Duration, Instant};

use nauta_estimation::AttitudeError;
use nauta_estimation::Estimator;
use nauta_estimation::ains::AinsInput;
use nauta_estimation::ains::dr::Site;
use nauta_estimation::ains::pf::{AinsPfParams, AinsPfStats, ParticleAins};
use nauta_estimation::attitude_core::{
    AttitudeCore, MekfVariantParams, PfVariantParams, VariantParams,
};
use nauta_estimation::earth::{meridian_radius, transverse_radius};
use nauta_estimation::frames::{Frd, Ned, Rotation};
use nauta_estimation::readings::{Attitude, Nav};
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
use nauta_sim::suite::{Measurements, SuiteConfig, TruthReading};

/// The survey's sensors, the magnetometer without hard and soft iron (paper
/// 000 calibrates it before the run, §IV-A; nauta's calibration is tested
/// with the attitude role).
pub fn survey_sensors(p: &ScenarioParams) -> SuiteConfig {
    let mut s = p.sensors_preset();
    s.imu.mag.hard_iron = [0.0; 3];
    s.imu.mag.soft_iron = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    s
}

/// The survey generator for `seed`, ending after `duration_s`.
pub fn survey(seed: u64, duration_s: f64) -> Generator {
    let p = ScenarioParams {
        scenario: ScenarioKind::Survey,
        ..Default::default()
    };
    Generator::new(&p, Origin::lisbon(), survey_sensors(&p), seed, duration_s)
        .expect("valid scenario")
}

/// The scenario's origin as the site, with the simulator's declination.
pub fn site(g: &Generator) -> Site {
    let o = g.simulator().mission().origin();
    Site {
        lat_rad: o.lat_rad,
        lon_rad: o.lon_rad,
        declination_rad: g.suite().declination_rad(),
    }
}

/// Which of the attitude role's estimators feeds `attitude/estimate`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AttitudeInput {
    /// Paper 000's attitude PF, the shipped survey's (`launch/survey.toml`).
    Pf,
    /// The `mekf` variant.
    Mekf,
}

/// The attitude role's estimator of `input` at the site (400 alignment
/// samples, as the shipped manifests).
pub fn attitude_core(g: &Generator, input: AttitudeInput) -> AttitudeCore {
    let s = site(g);
    let p = match input {
        AttitudeInput::Pf => VariantParams::Pf(PfVariantParams {
            alignment_samples: 400,
            ..Default::default()
        }),
        AttitudeInput::Mekf => VariantParams::Mekf(MekfVariantParams {
            alignment_samples: 400,
            ..Default::default()
        }),
    };
    AttitudeCore::new(&p, s.lat_rad, s.declination_rad).expect("valid")
}

/// Mean and RMS of the attitude input's roll, pitch and yaw errors.
#[derive(Debug, Clone, Copy, Default)]
pub struct AttitudeScore {
    pub n: u64,
    pub sum: [f64; 3],
    pub sq: [f64; 3],
    /// Sum of the published σ about N, E, D, rad.
    pub std: [f64; 3],
}

impl AttitudeScore {
    fn push(&mut self, est: &Attitude, truth: &TruthReading) {
        let t = Rotation::<Frd, Ned>::from_wxyz(truth.quat_nb).expect("unit truth");
        let e = AttitudeError::between(est.attitude.as_nalgebra(), t.as_nalgebra());
        self.n += 1;
        for (s, v) in self.std.iter_mut().zip(est.std_rad.to_array()) {
            *s += v;
        }
        for (i, v) in [e.roll_rad, e.pitch_rad, e.yaw_rad].into_iter().enumerate() {
            self.sum[i] += v;
            self.sq[i] += v * v;
        }
    }

    /// Mean, RMS and mean published σ per axis, degrees.
    pub fn deg(&self) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let n = self.n.max(1) as f64;
        (
            self.sum.map(|s| (s / n).to_degrees()),
            self.sq.map(|s| (s / n).sqrt().to_degrees()),
            self.std.map(|s| (s / n).to_degrees()),
        )
    }
}

/// One step's readings as inputs, appended to `out`; the attitude core
/// runs on the IMU sample and its estimate follows it.
pub fn inputs(m: &Measurements, att: &mut AttitudeCore, out: &mut Vec<AinsInput>) {
    if let Some(r) = &m.imu {
        let imu = nauta_sim::ains_inputs::imu(r);
        out.push(AinsInput::Imu(imu));
        if let Some(o) = att.step(&imu).expect("attitude step") {
            out.push(AinsInput::Attitude(Attitude {
                stamp_ns: r.stamp_ns,
                attitude: o.q_nb,
                std_rad: o.std_rad,
                gyro_bias_rad_s: o.gyro_bias,
            }));
        }
    }
    nauta_sim::ains_inputs::aiding(m, false, out);
}

/// North, east, down error of a solution against the truth, m.
pub fn position_error(n: &Nav, t: &TruthReading) -> [f64; 3] {
    let dlon = (n.lon_rad - t.lon_rad + std::f64::consts::PI)
        .rem_euclid(2.0 * std::f64::consts::PI)
        - std::f64::consts::PI;
    [
        (n.lat_rad - t.lat_rad) * meridian_radius(t.lat_rad),
        dlon * transverse_radius(t.lat_rad) * t.lat_rad.cos(),
        n.depth_m - t.depth_m,
    ]
}

/// A submerged stretch: from the last GPS fix before a gap of more than
/// 30 s to the first one after.
#[derive(Debug, Clone, Default)]
pub struct Dive {
    /// Distance travelled submerged, m.
    pub distance_m: f64,
    /// Error N, E, D of the last solution before the surfacing fix, m.
    pub final_error_m: [f64; 3],
    /// `(distance submerged, error N/E/D)` at every solution, m.
    pub samples: Vec<(f64, [f64; 3])>,
}

impl Dive {
    /// Final error over distance, per axis, m/km.
    pub fn final_m_per_km(&self) -> [f64; 3] {
        self.final_error_m.map(|e| e.abs() / self.distance_m * 1e3)
    }

    /// Least-squares slope of the error against the distance submerged, per
    /// axis, m/km (with an intercept).
    pub fn slope_m_per_km(&self) -> [f64; 3] {
        let n = self.samples.len() as f64;
        let md = self.samples.iter().map(|s| s.0).sum::<f64>() / n;
        std::array::from_fn(|i| {
            let me = self.samples.iter().map(|s| s.1[i]).sum::<f64>() / n;
            let (sxy, sxx) = self.samples.iter().fold((0.0, 0.0), |(a, b), s| {
                (a + (s.0 - md) * (s.1[i] - me), b + (s.0 - md).powi(2))
            });
            (sxy / sxx * 1e3).abs()
        })
    }
}

/// What a run of the estimator scored.
#[derive(Debug, Clone, Default)]
pub struct Score {
    /// Solutions published.
    pub outputs: u64,
    /// Sum of squared velocity errors per axis.
    pub vel_sq: [f64; 3],
    /// Solutions with the horizontal truth inside the published 95 % region
    /// (`(e_N/σ_N)² + (e_E/σ_E)² ≤ 5.991`, χ² with 2 degrees of freedom).
    pub inside_95: u64,
    /// Solutions with each velocity component inside its published ±1.96σ.
    pub vel_inside_95: u64,
    /// The dives.
    pub dives: Vec<Dive>,
    /// Wall-clock time spent in the estimator, and IMU samples it took.
    pub busy: Duration,
    pub imu_samples: u64,
    /// The estimator's counters at the end.
    pub stats: AinsPfStats,
    /// The last solution.
    pub last: Option<Nav>,
    /// The attitude input's errors.
    pub attitude: AttitudeScore,
}

impl Score {
    /// Velocity RMS per axis, m/s.
    pub fn vel_rms(&self) -> [f64; 3] {
        self.vel_sq.map(|s| (s / self.outputs.max(1) as f64).sqrt())
    }

    /// Fraction of solutions with the truth inside the 95 % region.
    pub fn coverage(&self) -> f64 {
        self.inside_95 as f64 / self.outputs.max(1) as f64
    }

    /// Fraction of solutions with every velocity component inside ±1.96σ.
    pub fn vel_coverage(&self) -> f64 {
        self.vel_inside_95 as f64 / self.outputs.max(1) as f64
    }

    /// Estimator time per IMU sample, µs (measured, printed, not asserted).
    pub fn us_per_imu(&self) -> f64 {
        self.busy.as_secs_f64() * 1e6 / self.imu_samples.max(1) as f64
    }
}

/// Feeds a run into one estimator and scores it.
pub struct Tracker {
    pub est: ParticleAins,
    pub score: Score,
    last_gps_ns: Option<u64>,
    gps_distance_m: f64,
    dive: Option<Dive>,
    out: Vec<Nav>,
}

impl Tracker {
    pub fn new(est: ParticleAins) -> Self {
        Self {
            est,
            score: Score::default(),
            last_gps_ns: None,
            gps_distance_m: 0.0,
            dive: None,
            out: Vec::new(),
        }
    }

    /// Feeds one input of the step whose truth is `t`.
    pub fn feed(&mut self, input: &AinsInput, t: &TruthReading) {
        if let AinsInput::Gps(g) = input {
            if let Some(prev) = self.last_gps_ns
                && g.stamp_ns - prev > 30_000_000_000
                && let Some(mut d) = self.dive.take()
                && let Some((dist, e)) = d.samples.last().copied()
            {
                d.distance_m = dist;
                d.final_error_m = e;
                self.score.dives.push(d);
            }
            self.dive = None;
            self.last_gps_ns = Some(g.stamp_ns);
            self.gps_distance_m = t.distance_m;
        }
        self.out.clear();
        let start = Instant::now();
        self.est
            .on_input(input, &mut self.out)
            .expect("valid input");
        self.score.busy += start.elapsed();
        if matches!(input, AinsInput::Imu(_)) {
            self.score.imu_samples += 1;
        }
        let out = std::mem::take(&mut self.out);
        for n in &out {
            self.score_one(n, t);
        }
        self.out = out;
    }

    fn score_one(&mut self, n: &Nav, t: &TruthReading) {
        let s = &mut self.score;
        s.outputs += 1;
        let e = position_error(n, t);
        let v = n.vel_ned_m_s.to_array();
        let sv = n.vel_std_ned_m_s.to_array();
        let mut v_in = true;
        for (i, sq) in s.vel_sq.iter_mut().enumerate() {
            let ev = v[i] - t.vel_ned_m_s[i];
            *sq += ev * ev;
            v_in &= ev.abs() <= 1.96 * sv[i];
        }
        s.vel_inside_95 += u64::from(v_in);
        let sd = n.pos_std_ned_m.to_array();
        if (e[0] / sd[0]).powi(2) + (e[1] / sd[1]).powi(2) <= 5.991 {
            s.inside_95 += 1;
        }
        if self
            .last_gps_ns
            .is_some_and(|g| n.stamp_ns.saturating_sub(g) > 2_000_000_000)
        {
            self.dive
                .get_or_insert_with(Dive::default)
                .samples
                .push((t.distance_m - self.gps_distance_m, e));
        }
        s.last = Some(*n);
    }
}

/// Every input of the survey for `duration_s` with `seed`, the attitude
/// from `input`, with its step's truth.
pub fn drive(
    seed: u64,
    duration_s: f64,
    input: AttitudeInput,
    mut f: impl FnMut(&AinsInput, &TruthReading),
) -> Site {
    let mut g = survey(seed, duration_s);
    let mut att = attitude_core(&g, input);
    let s = site(&g);
    let mut buf = Vec::new();
    while let Some(m) = g.step() {
        let m = m.expect("valid step");
        buf.clear();
        inputs(&m, &mut att, &mut buf);
        for i in &buf {
            f(i, &m.truth);
        }
    }
    s
}

/// Runs the survey for `duration_s` with `seed`, the attitude from `input`,
/// through one estimator per entry of `params`.
pub fn run_survey(
    seed: u64,
    duration_s: f64,
    input: AttitudeInput,
    params: &[AinsPfParams],
) -> Vec<Score> {
    let g = survey(seed, 1.0);
    let mut runs: Vec<Tracker> = params
        .iter()
        .map(|p| Tracker::new(ParticleAins::new(p, site(&g)).expect("valid")))
        .collect();
    drive(seed, duration_s, input, |i, t| {
        for r in &mut runs {
            if let AinsInput::Attitude(a) = i {
                r.score.attitude.push(a, t);
            }
            r.feed(i, t);
        }
    });
    runs.into_iter()
        .map(|mut r| {
            // A dive still under way when the run ends counts to its end.
            if let Some(mut d) = r.dive.take()
                && let Some((dist, e)) = d.samples.last().copied()
            {
                d.distance_m = dist;
                d.final_error_m = e;
                r.score.dives.push(d);
            }
            Score {
                stats: r.est.stats(),
                ..r.score
            }
        })
        .collect()
}
