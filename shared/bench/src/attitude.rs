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
//!   throughput at its default particle count (700 since 2026-12-02).
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
//!   [`ParticleFilter::from_first_sample`].
//! - **Parameters.** Every variant runs with its defaults ([`Settings::bench`]:
//!   only the MEKF's start and turn speed differ, as above), the same on
//!   BROAD as on the simulator; no parameter is set per trial. The defaults'
//!   sensor noise is an MTi-30's; BROAD's IMU is noisier (measured on the
//!   first 2,000 samples, at rest, of each trial: accelerometer 320-346
//!   µg/√Hz, magnetometer 0.63-0.76 µT, gyro 0.005-0.006 °/s/√Hz), but
//!   giving the PF those figures changes its mean by 0.01° (2.414° instead
//!   of 2.402°), so they are not used.
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
//!         {"total_rmse_deg", "heading_rmse_deg", "inclination_rmse_deg"}}}}}
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
//!  "pf_samples_per_s": <float>}
//! ```
//!
//! (600 s per condition, seed 7, the default particle count.)
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
//!   `predict` + `update` + `estimate` over the three conditions (the
//!   default particle count).
//!
//! # Measured (2026-11-22, this machine: 2 cores shared with other work)
//!
//! Until the CLI wires these functions, they were run through a small
//! harness crate outside the workspace that includes this file
//! (`#[path]`) and calls `run_broad(Path::new("../shared/data/broad"),
//! json)` and `run_sim(json)`, built with `cargo build --release`.
//!
//! BROAD, eight trials, total / heading / inclination RMSE, degrees:
//!
//! ```text
//! trial                                 gyro                  mekf                  pf
//! 01_undisturbed_slow_rotation_A    29.59 24.03 17.41     2.23  2.07  0.81     2.38  2.28  0.67
//! 06_undisturbed_fast_rotation_A    42.47 42.36  3.10     5.71  5.52  1.44     4.14  4.06  0.81
//! 10_undisturbed_slow_translation_A 18.14 14.12 11.42     3.74  3.48  1.38     2.13  2.11  0.33
//! 15_undisturbed_fast_translation_A 50.42 49.42 10.49    31.16  8.37 30.05     2.71  2.62  0.67
//! 24_disturbed_tapping_A            53.26 13.75 51.56     1.33  1.00  0.88     1.61  1.49  0.62
//! 26_disturbed_phone_vibration_A    42.54 10.76 41.20     6.41  5.55  3.21     1.96  1.88  0.57
//! 28_disturbed_stationary_magnet_A  14.54  6.71 12.90    12.53 10.40  7.02     1.72  1.07  1.35
//! 33_disturbed_attached_magnet_2cm  13.16 12.81  3.03    60.28 60.26  1.19     2.56  2.51  0.53
//! mean                              33.01 21.74 18.89    15.42 12.08  5.75     2.40  2.25  0.70
//! µs per sample                      0.06                 0.75                41.5
//! ```
//!
//! `pf` with seeds 1, 2, 3 instead of 0: mean 2.42°, 2.45°, 2.43°, largest
//! trial 4.16°, 4.14°, 4.12° (measured with the BROAD noise figures above,
//! which change the mean by 0.01°). The `pf`'s heading error on trial 06 is
//! the magnetometer's: seen through the reference, the field's azimuth
//! during its moving phase is −4.3° on average (−1.8° at rest). `mekf` with
//! these start values diverges on trials 15 and 33 (not studied here).
//!
//! Sensitivity of the `pf`'s BROAD mean (largest trial) to its noise
//! densities around the defaults (process 0.1 °/s/√Hz, tilt 0.1 °·√s,
//! heading 0.2 °·√s): tilt 0.03 / 0.1 / 0.3 with heading 0.1: 2.19 (4.19),
//! 2.36 (4.15), 2.61 (4.02); with heading 0.2: 2.15 (4.16), 2.41 (4.12),
//! 2.51 (4.12); with heading 0.6: 2.24 (4.72), 2.10 (4.07), 2.40 (4.05);
//! process 0.03 and 0.3: 2.74 (5.42), 3.17 (4.82); no low-pass of the
//! specific force: 6.06 (15.55); 300 particles: 2.22 (4.12).
//!
//! Simulator, 600 s per condition, seed 7, RMS roll / pitch / yaw (°) and
//! quaternion components:
//!
//! ```text
//! still       gyro   118.8434  22.2562  46.1489   5.33e-1 5.24e-1 5.76e-1 1.44e-1
//! still       mekf     0.0775   0.0725   0.0844   1.90e-4 6.30e-4 6.78e-4 7.11e-4
//! still       pf       0.0558   0.0432   0.0521   1.17e-4 4.02e-4 4.66e-4 4.39e-4
//! pitch_roll  gyro   118.8155  26.2663  46.0889   5.37e-1 5.26e-1 5.67e-1 1.66e-1
//! pitch_roll  mekf     0.0788   0.0732   0.0815   2.09e-4 6.36e-4 6.75e-4 6.76e-4
//! pitch_roll  pf       0.0793   0.0890   0.0968   2.30e-4 6.34e-4 8.21e-4 8.04e-4
//! yaw         gyro    69.5692  38.3370  44.8052   1.89e-1 3.65e-1 3.94e-1 1.32e-1
//! yaw         mekf     0.0639   0.0659   0.0787   3.91e-4 5.38e-4 5.93e-4 5.65e-4
//! yaw         pf       0.1276   0.1200   0.1654   7.36e-4 1.01e-3 1.14e-3 1.24e-3
//! ```
//!
//! Every `pf` error is at least 106 times below `gyro`'s. `pf_samples_per_s`
//! 25,761 to 27,106 over three runs (1,000 particles then, one core; see
//! BENCHMARKS.md for today's figures at 700).
use std::path::Path;
use std::time::Instant;

use anyhow::Context as _;
use nalgebra::{UnitQuaternion, Vector3};
use nauta_datasets::broad::{self, BroadTrial};
use nauta_estimation::calibration::{self, MagCalibration, MagFitMethod, PsoParams};
use nauta_estimation::frames::{Frd, Ned, Rotation, Vector};
use nauta_estimation::mekf::{MagneticReference, Mekf, MekfConfig, MekfParams};
use nauta_estimation::pf::{ParticleFilter, PfConfig, PfParams, aiding_quaternion};
use nauta_estimation::{AttitudeError, AttitudeEstimator, GyroIntegrator, HeadingInclinationError};
use nauta_sim::manoeuvre::magnetometer_manoeuvre;
use nauta_sim::mission::Origin;
use nauta_sim::noise::MagnetometerSpec;
use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
use serde_json::{Map, Value, json};

/// The variants, in the attitude service's order.
pub const VARIANTS: [&str; 3] = ["gyro", "mekf", "pf"];

/// Berlin (BROAD's lab), geodetic latitude, degrees.
const BROAD_LATITUDE_DEG: f64 = 52.51;

/// Simulator runs: length, s, and seed.
const SIM_DURATION_S: f64 = 600.0;
const SIM_SEED: u64 = 7;

/// Parameters of the variants under test.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// The MEKF's parameters.
    pub mekf: MekfParams,
    /// The particle filter's parameters.
    pub pf: PfParams,
}

impl Settings {
    /// The defaults, except the MEKF's initial uncertainty (the PF's: no
    /// still alignment) and its `turn_speed_m_s = 0` (the IMU turns in place:
    /// hand-held on BROAD, the simulator's attitude scenarios). The same for
    /// BROAD and the simulator.
    pub fn bench() -> Self {
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
    estimates.push(est.estimate().q_nb.to_nalgebra());
    for pair in trial.samples.windows(2) {
        let (prev, s) = (&pair[0], &pair[1]);
        est.predict(&Vector::from_nalgebra(s.gyro_rad_s), s.t_s - prev.t_s);
        est.update(
            &Vector::from_nalgebra(s.accel_m_s2),
            &Vector::from_nalgebra(s.mag_ut),
        );
        estimates.push(est.estimate().q_nb.to_nalgebra());
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
    let (names, scores) = score_directory(dir, &Settings::bench(), !json)?;
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
        println!("{}", json!({ "variants": variants }));
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
    gyro: Vector<Frd>,
    accel: Vector<Frd>,
    mag: Vector<Frd>,
    truth: UnitQuaternion<f64>,
}

/// Paper 000 §IV-A's magnetometer calibration for a simulated run: the
/// manoeuvre of [`magnetometer_manoeuvre`], fitted with the default method.
fn calibrate_magnetometer(
    spec: MagnetometerSpec,
    field_ned_t: &Vector3<f64>,
    seed: u64,
) -> anyhow::Result<MagCalibration> {
    let samples = magnetometer_manoeuvre(spec, field_ned_t, seed)?;
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
fn simulate(kind: ScenarioKind) -> anyhow::Result<(Vec<SimSample>, f64, f64, MagCalibration)> {
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
        samples.push(SimSample {
            dt_s: r.interval_s,
            gyro: Vector::from_array(r.gyro_rad_s),
            accel: Vector::from_array(r.accel_m_s2),
            mag: Vector::from_nalgebra(cal.apply(&Vector3::from(r.mag_ut))),
            truth: Rotation::<Frd, Ned>::from_wxyz(m.truth.quat_nb)
                .context("simulated truth attitude")?
                .to_nalgebra(),
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
        first.accel.as_nalgebra(),
        first.mag.as_nalgebra(),
        latitude_rad,
        declination_rad,
    )?;
    let mut out = Vec::with_capacity(samples.len());
    let t0 = Instant::now();
    for s in &samples[1..] {
        est.predict(&s.gyro, s.dt_s);
        est.update(&s.accel, &s.mag);
        out.push(est.estimate().q_nb.to_nalgebra());
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
    let settings = Settings::bench();
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
            json!({ "conditions": conditions, "pf_samples_per_s": pf_rate })
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
