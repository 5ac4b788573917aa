//! `nauta bench attitude`: the attitude variants (`gyro`, `mekf`, `pf`) run
//! in-process, one core, on recorded and simulated IMU data.
//!
//! - [`run_broad`]: the BROAD benchmark (Laidig et al. 2021,
//!   doi:10.3390/data6070072, data CC BY 4.0; `shared/data/broad/`): every
//!   `.csv`/`.csv.gz` trial of a directory, its total, heading and
//!   inclination RMSE over the moving samples with the BROAD metric, and the
//!   time per sample.
//! - [`run_sim`]: paper 000's three conditions (still, pitch and roll, yaw;
//!   Table I) on the simulator, RMS error per quaternion component and in
//!   roll, pitch and yaw against the truth, and the particle filter's
//!   throughput at 1,000 particles.
//!
//! Not wired to the CLI here (`bench/mod.rs` and `main.rs` are the CLI's).
//!
//! # BROAD: conventions and choices
//!
//! - **Frames.** The estimators are fed the IMU's samples as they are: the
//!   body frame is the IMU frame. Their NED estimate is turned into BROAD's
//!   ENU convention by (B1) of `nauta_datasets::broad`,
//!   `q_enu_imu = q_enu_ned ⊗ q_ned_imu`, `q_enu_ned = [0, 1/√2, 1/√2, 0]`
//!   (tested there, with the invariance of the metric).
//! - **Metric.** BROAD's `broad_utils.py`: `q_e = q_est ⊗ q_ref⁻¹`, total
//!   `2 acos|w|`, heading `2 atan|z/w|`, inclination `2 acos √(w² + z²)`, RMSE
//!   over the samples with `moving = 1`; samples whose reference is NaN
//!   (markers occluded) are left out (BROAD's `nanmean`). No constant heading
//!   offset is removed: BROAD's evaluation (`process_data.py`) compares the
//!   9-D estimates directly, because the reference's Earth frame has its y
//!   axis on magnetic north. Checked on the eight trials here: the field of
//!   the initial rest, seen through the reference, points within 4° of the
//!   reference's north (−0.7°, −1.8°, 0.3°, 0.4°, 0.5°, −3.9°, 2.8°, 3.1°).
//!   So the estimators run with declination 0 (their "north" is magnetic).
//! - **Site.** Berlin, latitude 52.51° N, for the Earth-rate compensation
//!   (the reference frame's north is magnetic, 4° from true there: the Earth
//!   rate is then mis-resolved by 5e-6 rad/s, far below the gyro's bias).
//! - **Start.** A trial has no still period guaranteed, so every variant
//!   starts from the first sample: the attitude is paper 000's aiding
//!   quaternion `q_am` of the first specific force and field (eqs. 30-41),
//!   the magnetic reference (norm, dip) that field; the gyro bias starts at
//!   zero. `gyro` then integrates (paper 000's baseline); `mekf` starts with
//!   5° tilt, 10° heading and 0.5 °/s bias 1σ (the `pf` defaults; the MEKF's
//!   own assume a still alignment) and `turn_speed_m_s = 0` (a hand-held IMU
//!   turns in place, without the AUV's centripetal acceleration); `pf` uses
//!   [`ParticleFilter::from_first_sample`] with its defaults. No parameter is
//!   set per trial.
//! - **Timing.** Wall time of the estimator's `predict`, `update` and
//!   `estimate` over the trial, divided by its samples (reading and error
//!   computation excluded).
//!
//! # JSON
//!
//! `run_broad(dir, true)` prints one object:
//!
//! ```text
//! {"variants": {"<variant>": {
//!     "mean_total_rmse_deg", "max_total_rmse_deg", "mean_heading_rmse_deg",
//!     "mean_inclination_rmse_deg", "us_per_sample",
//!     "trials": {"<file name up to its first dot>":
//!         {"total_rmse_deg", "heading_rmse_deg", "inclination_rmse_deg"}}}},
//!  "trials": <count>, "directory": "<dir>"}
//! ```
//!
//! for the variants `gyro`, `mekf` and `pf`; means are over trials,
//! `us_per_sample` over all samples of all trials.
//!
//! `run_sim(true)` prints one object:
//!
//! ```text
//! {"conditions": {"still" | "pitch_roll" | "yaw": {"<variant>": {
//!     "roll_rms_deg", "pitch_rms_deg", "yaw_rms_deg",
//!     "qw_rms", "qx_rms", "qy_rms", "qz_rms"}}},
//!  "pf_samples_per_s": <float>, "pf_particles": 1000,
//!  "duration_s": 600, "seed": 7}
//! ```
//!
//! # Simulator: conventions and choices
//!
//! - The scenarios `still`, `rocking` (paper 000's "pitch and roll") and
//!   `yaw` of `nauta_sim::scenario`, 600 s each, seed 7, the MTi-30-class
//!   IMU of the scenario's preset, Lisbon (`Origin::lisbon`), the WMM
//!   declination of the run.
//! - **Calibration first**, as paper 000 §IV-A: the magnetometer is
//!   calibrated from 2,000 samples of the preset's magnetometer (its hard and
//!   soft iron and noise, `MagnetometerNoise`) turned through random
//!   attitudes in the run's WMM field (seeded), with the default fit of
//!   `nauta_estimation::calibration`; the calibration is applied to every
//!   magnetometer sample that `mekf` and `pf` see.
//! - Every variant starts from the first sample, as on BROAD, with default
//!   parameters (`mekf`'s initial standard deviations as on BROAD).
//! - RMS over every sample after the first, against the simulator's truth;
//!   quaternion components with the estimate's sign chosen to agree with
//!   the truth's.
//! - `pf_samples_per_s`: samples divided by the wall time of the `pf`'s
//!   `predict` + `update` + `estimate` over the three conditions (1,000
//!   particles, the default).

use std::path::Path;
use std::time::Instant;

use anyhow::Context as _;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use nauta_datasets::broad::{self, BroadTrial};
use nauta_estimation::calibration::{self, MagCalibration, MagFitMethod, PsoParams};
use nauta_estimation::mekf::{MagneticReference, Mekf, MekfConfig, MekfParams};
use nauta_estimation::pf::{ParticleFilter, PfConfig, PfParams, aiding_quaternion};
use nauta_estimation::{AttitudeError, AttitudeEstimator, GyroIntegrator, HeadingInclinationError};
use nauta_sim::mission::Origin;
use nauta_sim::noise::{MagnetometerNoise, MagnetometerSpec};
use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Map, Value, json};

/// The variants, in the attitude service's order.
pub const VARIANTS: [&str; 3] = ["gyro", "mekf", "pf"];

/// Berlin (BROAD's lab), geodetic latitude, degrees.
const BROAD_LATITUDE_DEG: f64 = 52.51;

/// Simulator runs: length, s, and seed.
const SIM_DURATION_S: f64 = 600.0;
const SIM_SEED: u64 = 7;
/// Magnetometer calibration samples for the simulator runs.
const SIM_CALIBRATION_SAMPLES: usize = 2000;

/// Parameters of the variants under test (the defaults unless a study
/// changes them).
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// The MEKF's parameters.
    pub mekf: MekfParams,
    /// The particle filter's parameters.
    pub pf: PfParams,
}

impl Default for Settings {
    /// Defaults, except the MEKF's initial uncertainty (as the PF's: no still
    /// alignment) and `turn_speed_m_s = 0` (no AUV turning at speed).
    fn default() -> Self {
        let pf = PfParams::default();
        Self {
            mekf: MekfParams {
                turn_speed_m_s: 0.0,
                initial_tilt_std_deg: pf.initial_tilt_std_deg,
                initial_heading_std_deg: pf.initial_heading_std_deg,
                initial_bias_std_deg_s: pf.initial_bias_std_deg_s,
                ..MekfParams::default()
            },
            pf,
        }
    }
}

/// One estimator started from the first sample.
fn start(
    variant: &str,
    settings: &Settings,
    accel: &Vector3<f64>,
    mag: &Vector3<f64>,
    latitude_rad: f64,
    declination_rad: f64,
) -> anyhow::Result<Box<dyn AttitudeEstimator>> {
    let q = aiding_quaternion(accel, mag, declination_rad)?;
    Ok(match variant {
        "gyro" => Box::new(GyroIntegrator::new(q, latitude_rad, 0)?),
        "mekf" => {
            let config = MekfConfig::try_from(&settings.mekf)?;
            let reference = MagneticReference::from_mean_field(&q, mag)?;
            Box::new(Mekf::new(
                &config,
                q,
                latitude_rad,
                declination_rad,
                reference,
            )?)
        }
        "pf" => {
            let config = PfConfig::try_from(&settings.pf)?;
            Box::new(ParticleFilter::from_first_sample(
                &config,
                accel,
                mag,
                latitude_rad,
                declination_rad,
            )?)
        }
        other => anyhow::bail!("unknown variant {other:?}"),
    })
}

/// RMSE of one BROAD trial, degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BroadScore {
    /// Total error RMSE.
    pub total_rmse_deg: f64,
    /// Heading error RMSE.
    pub heading_rmse_deg: f64,
    /// Inclination error RMSE.
    pub inclination_rmse_deg: f64,
    /// Samples processed.
    pub samples: usize,
    /// Wall time of the estimator over the trial, s.
    pub estimator_s: f64,
}

/// Runs `variant` over `trial` and scores it with the BROAD metric.
pub fn score_trial(
    trial: &BroadTrial,
    variant: &str,
    settings: &Settings,
) -> anyhow::Result<BroadScore> {
    let first = trial.samples.first().context("empty trial")?;
    let mut est = start(
        variant,
        settings,
        &first.accel_m_s2,
        &first.mag_ut,
        BROAD_LATITUDE_DEG.to_radians(),
        0.0,
    )?;
    let mut estimates = Vec::with_capacity(trial.samples.len());
    let t0 = Instant::now();
    estimates.push(est.estimate().q_nb);
    for pair in trial.samples.windows(2) {
        let (prev, s) = (&pair[0], &pair[1]);
        est.predict(&s.gyro_rad_s, s.t_s - prev.t_s);
        est.update(&s.accel_m_s2, &s.mag_ut);
        estimates.push(est.estimate().q_nb);
    }
    let estimator_s = t0.elapsed().as_secs_f64();
    let (mut n, mut total, mut heading, mut incl) = (0usize, 0.0, 0.0, 0.0);
    for (s, q) in trial.samples.iter().zip(&estimates) {
        let Some(reference) = s.reference_enu else {
            continue;
        };
        if !s.moving {
            continue;
        }
        let q_enu = broad::enu_from_ned(q);
        let e = HeadingInclinationError::between(&q_enu, &reference);
        let t = AttitudeError::between(&q_enu, &reference).total_rad;
        n += 1;
        total += t * t;
        heading += e.heading_rad * e.heading_rad;
        incl += e.inclination_rad * e.inclination_rad;
    }
    anyhow::ensure!(n > 0, "{}: no moving sample with a reference", trial.name);
    let rms = |s: f64| (s / n as f64).sqrt().to_degrees();
    Ok(BroadScore {
        total_rmse_deg: rms(total),
        heading_rmse_deg: rms(heading),
        inclination_rmse_deg: rms(incl),
        samples: trial.samples.len(),
        estimator_s,
    })
}

/// Every trial of `dir` through every variant: `(trial names, scores[variant][trial])`.
pub fn score_directory(
    dir: &Path,
    settings: &Settings,
    progress: bool,
) -> anyhow::Result<(Vec<String>, Vec<Vec<BroadScore>>)> {
    let files = broad::list_trials(dir)?;
    anyhow::ensure!(
        !files.is_empty(),
        "{}: no .csv or .csv.gz trial",
        dir.display()
    );
    let mut names = Vec::new();
    let mut scores = vec![Vec::new(); VARIANTS.len()];
    for file in &files {
        let trial = broad::read_trial(file)?;
        if progress {
            eprint!("\rnauta bench attitude: {}          ", trial.name);
        }
        for (v, variant) in VARIANTS.iter().enumerate() {
            scores[v].push(
                score_trial(&trial, variant, settings)
                    .with_context(|| format!("{}: variant {variant}", trial.name))?,
            );
        }
        names.push(trial.name);
    }
    if progress {
        eprintln!();
    }
    Ok((names, scores))
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (n, s) = v.fold((0usize, 0.0), |(n, s), x| (n + 1, s + x));
    s / n.max(1) as f64
}

/// BROAD: every trial of `dir` (`.csv` or `.csv.gz`) through `gyro`, `mekf`
/// and `pf`; a table, or the JSON of the module documentation.
pub fn run_broad(dir: &Path, json: bool) -> anyhow::Result<()> {
    let (names, scores) = score_directory(dir, &Settings::default(), !json)?;
    let mut variants = Map::new();
    for (v, variant) in VARIANTS.iter().enumerate() {
        let s = &scores[v];
        let samples: usize = s.iter().map(|x| x.samples).sum();
        let seconds: f64 = s.iter().map(|x| x.estimator_s).sum();
        let trials: Map<String, Value> = names
            .iter()
            .zip(s)
            .map(|(name, x)| {
                (
                    name.clone(),
                    json!({
                        "total_rmse_deg": x.total_rmse_deg,
                        "heading_rmse_deg": x.heading_rmse_deg,
                        "inclination_rmse_deg": x.inclination_rmse_deg,
                    }),
                )
            })
            .collect();
        variants.insert(
            variant.to_string(),
            json!({
                "mean_total_rmse_deg": mean(s.iter().map(|x| x.total_rmse_deg)),
                "max_total_rmse_deg": s.iter().map(|x| x.total_rmse_deg).fold(0.0, f64::max),
                "mean_heading_rmse_deg": mean(s.iter().map(|x| x.heading_rmse_deg)),
                "mean_inclination_rmse_deg": mean(s.iter().map(|x| x.inclination_rmse_deg)),
                "us_per_sample": 1e6 * seconds / samples.max(1) as f64,
                "trials": trials,
            }),
        );
    }
    if json {
        println!(
            "{}",
            json!({
                "variants": variants,
                "trials": names.len(),
                "directory": dir.display().to_string(),
            })
        );
        return Ok(());
    }
    println!(
        "BROAD RMSE over moving samples, degrees: total / heading / inclination ({} trials, {})",
        names.len(),
        dir.display()
    );
    print!("{:<36}", "trial");
    for variant in VARIANTS {
        print!(" {variant:>21}");
    }
    println!();
    for (t, name) in names.iter().enumerate() {
        print!("{name:<36}");
        for s in &scores {
            let x = s[t];
            print!(
                " {:>6.2} {:>6.2} {:>6.2}",
                x.total_rmse_deg, x.heading_rmse_deg, x.inclination_rmse_deg
            );
        }
        println!();
    }
    print!("{:<36}", "mean");
    for s in &scores {
        print!(
            " {:>6.2} {:>6.2} {:>6.2}",
            mean(s.iter().map(|x| x.total_rmse_deg)),
            mean(s.iter().map(|x| x.heading_rmse_deg)),
            mean(s.iter().map(|x| x.inclination_rmse_deg))
        );
    }
    println!();
    print!("{:<36}", "µs per sample");
    for s in &scores {
        let samples: usize = s.iter().map(|x| x.samples).sum();
        let seconds: f64 = s.iter().map(|x| x.estimator_s).sum();
        print!(" {:>20.2}", 1e6 * seconds / samples.max(1) as f64);
    }
    println!();
    Ok(())
}

/// RMS errors of one variant in one simulated condition.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SimScore {
    /// Roll, pitch, yaw RMS, degrees.
    pub euler_rms_deg: [f64; 3],
    /// RMS of the quaternion components w, x, y, z.
    pub quat_rms: [f64; 4],
    /// Samples scored.
    pub samples: usize,
    /// Wall time of the estimator, s.
    pub estimator_s: f64,
}

/// Paper 000's conditions: JSON name and scenario.
pub const SIM_CONDITIONS: [(&str, ScenarioKind); 3] = [
    ("still", ScenarioKind::Still),
    ("pitch_roll", ScenarioKind::Rocking),
    ("yaw", ScenarioKind::Yaw),
];

/// One simulated IMU sample with its truth.
#[derive(Debug, Clone, Copy)]
struct SimSample {
    dt_s: f64,
    gyro: Vector3<f64>,
    accel: Vector3<f64>,
    mag: Vector3<f64>,
    truth: UnitQuaternion<f64>,
}

/// A uniformly distributed attitude (Shoemake 1992, from three uniforms).
fn random_attitude(rng: &mut ChaCha8Rng) -> UnitQuaternion<f64> {
    let (u1, u2, u3): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    UnitQuaternion::new_normalize(Quaternion::new(
        a * (tau * u2).sin(),
        a * (tau * u2).cos(),
        b * (tau * u3).sin(),
        b * (tau * u3).cos(),
    ))
}

/// Paper 000 §IV-A's magnetometer calibration for a simulated run: the
/// preset magnetometer `spec` turned through random attitudes in the field
/// `field_ned_t` (T), fitted with the default method.
fn calibrate_magnetometer(
    spec: MagnetometerSpec,
    field_ned_t: &Vector3<f64>,
    seed: u64,
) -> anyhow::Result<MagCalibration> {
    let mut noise = MagnetometerNoise::new(spec)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let samples: Vec<Vector3<f64>> = (0..SIM_CALIBRATION_SAMPLES)
        .map(|_| {
            let q = random_attitude(&mut rng);
            noise.next(&mut rng, q.inverse_transform_vector(field_ned_t)) * 1e6
        })
        .collect();
    Ok(calibration::fit(
        &samples,
        field_ned_t.norm() * 1e6,
        MagFitMethod::default(),
        &PsoParams::default(),
        seed,
    )?)
}

/// The samples of one condition, the site latitude and declination, and the
/// magnetometer calibration.
fn simulate(
    kind: ScenarioKind,
) -> anyhow::Result<(Vec<SimSample>, f64, f64, MagCalibration)> {
    let params = ScenarioParams {
        scenario: kind,
        attitude_duration_s: SIM_DURATION_S,
        ..Default::default()
    };
    let origin = Origin::lisbon();
    let sensors = params.sensors_preset();
    let mag_spec = sensors.imu.mag;
    let mut generator = Generator::new(&params, origin, sensors, SIM_SEED, SIM_DURATION_S)?;
    let field = generator.simulator().environment().magnetic;
    let cal = calibrate_magnetometer(mag_spec, &field.ned_t, SIM_SEED)?;
    let mut samples = Vec::new();
    while let Some(m) = generator.step() {
        let m = m?;
        let Some(r) = m.imu else { continue };
        let [w, x, y, z] = m.truth.quat_nb;
        samples.push(SimSample {
            dt_s: r.interval_s,
            gyro: Vector3::from(r.gyro_rad_s),
            accel: Vector3::from(r.accel_m_s2),
            mag: cal.apply(&Vector3::from(r.mag_ut)),
            truth: UnitQuaternion::new_normalize(Quaternion::new(w, x, y, z)),
        });
    }
    Ok((samples, origin.lat_rad, field.declination_rad, cal))
}

/// Runs `variant` over simulated `samples` and scores it against the truth.
fn score_sim(
    samples: &[SimSample],
    variant: &str,
    settings: &Settings,
    latitude_rad: f64,
    declination_rad: f64,
) -> anyhow::Result<SimScore> {
    let first = samples.first().context("no samples")?;
    let mut est = start(
        variant,
        settings,
        &first.accel,
        &first.mag,
        latitude_rad,
        declination_rad,
    )?;
    let mut out = Vec::with_capacity(samples.len());
    let t0 = Instant::now();
    for s in &samples[1..] {
        est.predict(&s.gyro, s.dt_s);
        est.update(&s.accel, &s.mag);
        out.push(est.estimate().q_nb);
    }
    let estimator_s = t0.elapsed().as_secs_f64();
    let mut euler = [0.0; 3];
    let mut comp = [0.0; 4];
    for (s, q) in samples[1..].iter().zip(&out) {
        let e = AttitudeError::between(q, &s.truth);
        for (acc, v) in euler.iter_mut().zip([e.roll_rad, e.pitch_rad, e.yaw_rad]) {
            *acc += v * v;
        }
        let sign = if q.coords.dot(&s.truth.coords) < 0.0 {
            -1.0
        } else {
            1.0
        };
        let d = [
            sign * q.w - s.truth.w,
            sign * q.i - s.truth.i,
            sign * q.j - s.truth.j,
            sign * q.k - s.truth.k,
        ];
        for (acc, v) in comp.iter_mut().zip(d) {
            *acc += v * v;
        }
    }
    let n = out.len().max(1) as f64;
    Ok(SimScore {
        euler_rms_deg: euler.map(|s| (s / n).sqrt().to_degrees()),
        quat_rms: comp.map(|s| (s / n).sqrt()),
        samples: out.len(),
        estimator_s,
    })
}

/// Every condition through every variant: `scores[condition][variant]`.
pub fn score_conditions(settings: &Settings, progress: bool) -> anyhow::Result<Vec<Vec<SimScore>>> {
    let mut all = Vec::new();
    for (name, kind) in SIM_CONDITIONS {
        if progress {
            eprint!("\rnauta bench attitude: simulating {name}          ");
        }
        let (samples, lat, decl, _) = simulate(kind)?;
        let mut row = Vec::new();
        for variant in VARIANTS {
            row.push(score_sim(&samples, variant, settings, lat, decl)?);
        }
        all.push(row);
    }
    if progress {
        eprintln!();
    }
    Ok(all)
}

/// Paper 000's three conditions on the simulator; a table, or the JSON of the
/// module documentation.
pub fn run_sim(json: bool) -> anyhow::Result<()> {
    let settings = Settings::default();
    let scores = score_conditions(&settings, !json)?;
    let pf = VARIANTS.iter().position(|v| *v == "pf").context("pf")?;
    let (samples, seconds) = scores.iter().fold((0usize, 0.0), |(n, s), row| {
        (n + row[pf].samples, s + row[pf].estimator_s)
    });
    let pf_rate = samples as f64 / seconds.max(1e-12);
    if json {
        let mut conditions = Map::new();
        for ((name, _), row) in SIM_CONDITIONS.iter().zip(&scores) {
            let per: Map<String, Value> = VARIANTS
                .iter()
                .zip(row)
                .map(|(v, s)| {
                    (
                        v.to_string(),
                        json!({
                            "roll_rms_deg": s.euler_rms_deg[0],
                            "pitch_rms_deg": s.euler_rms_deg[1],
                            "yaw_rms_deg": s.euler_rms_deg[2],
                            "qw_rms": s.quat_rms[0],
                            "qx_rms": s.quat_rms[1],
                            "qy_rms": s.quat_rms[2],
                            "qz_rms": s.quat_rms[3],
                        }),
                    )
                })
                .collect();
            conditions.insert(name.to_string(), Value::Object(per));
        }
        println!(
            "{}",
            json!({
                "conditions": conditions,
                "pf_samples_per_s": pf_rate,
                "pf_particles": settings.pf.particles,
                "duration_s": SIM_DURATION_S,
                "seed": SIM_SEED,
            })
        );
        return Ok(());
    }
    println!(
        "simulator, {SIM_DURATION_S} s per condition, seed {SIM_SEED}: RMS roll / pitch / yaw (°) and quaternion components w x y z"
    );
    for ((name, _), row) in SIM_CONDITIONS.iter().zip(&scores) {
        for (v, s) in VARIANTS.iter().zip(row) {
            println!(
                "{name:<11} {v:<5} {:>9.4} {:>9.4} {:>9.4}   {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e}",
                s.euler_rms_deg[0],
                s.euler_rms_deg[1],
                s.euler_rms_deg[2],
                s.quat_rms[0],
                s.quat_rms[1],
                s.quat_rms[2],
                s.quat_rms[3]
            );
        }
    }
    println!(
        "pf: {:.0} samples/s with {} particles (one core)",
        pf_rate, settings.pf.particles
    );
    Ok(())
}
