//! The attitude role's pure core: static alignment from the first still samples,
//! then one [`AttitudeEstimator`] variant. No IPC here; `main` wires it to ports.
//!
//! - `gyro`: [`GyroIntegrator`] from the aligned attitude with zero bias (paper
//!   000's unaided baseline).
//! - `mekf`: [`Mekf`] from the aligned attitude; during the alignment the core
//!   also averages the gyro, and if it was still (the spread of its samples
//!   about their mean below `still_gyro_rms_deg_s`) takes that mean, less the
//!   Earth rate seen at the aligned attitude, as the initial bias, with a 1σ of
//!   `√(N²/T + B²)` (white noise N averaged over the T seconds of alignment,
//!   plus the bias instability B). Otherwise the bias starts at zero with the
//!   configured `initial_bias_std_deg_s` and the attitude with the larger
//!   `moving_alignment_*_std_deg`. The expected field norm and dip come
//!   from the alignment's mean field ([`MagneticReference::from_mean_field`]).
//!   Then each IMU sample is one `predict` and one `update` (no decimation).
//! - `pf`: [`ParticleFilter`], paper 000's attitude particle filter, started
//!   as the `mekf` is: particles around the aligned attitude; if the
//!   alignment was still, biases around its mean gyro less the Earth rate
//!   (paper 000 §IV-A's static calibration) with a 1σ of `N/√T` (N the
//!   filter's process noise density, floored at 0.01 °/s), otherwise around
//!   zero with the attitude spread of `moving_alignment_*_std_deg`; the
//!   magnetic reference from the alignment's mean field. Parameters in
//!   `shared/estimation/src/pf/params.rs`
//!   (`variants.pf = { alignment_samples = 400, filter = { particles = 1000 } }`).
//!
//! Every variant first corrects each magnetometer sample with the configured
//! hard- and soft-iron calibration ([`MagnetometerParams`]; paper 000 §IV-A
//! calibrates the magnetometer before the filter), the alignment's mean field
//! included; without one the samples are used as they come.

use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;

use nauta_estimation::alignment::Alignment;
use nauta_estimation::calibration::MagCalibration;
use nauta_estimation::earth::earth_rate_ned;
use nauta_estimation::mekf::{MagneticReference, Mekf, MekfConfig, MekfParams};
use nauta_estimation::pf::{ParticleFilter, PfConfig, PfParams};
use nauta_estimation::{AttitudeEstimator, AttitudeOutput, AttitudeStateSnapshot, GyroIntegrator};
use nauta_messages::checked::Imu;

#[cfg(test)]
mod tests;

/// The variants this binary implements; the first is the default.
pub const VARIANTS: [&str; 3] = ["pf", "gyro", "mekf"];

/// The magnetometer's calibration, `m = W (m̃ − h)` (C1 of
/// `nauta_estimation::calibration::magnetometer`), in the parameters of every
/// variant (`params.magnetometer = { hard_iron_ut = [..], soft_iron_inv = [[..], [..], [..]] }`);
/// `nauta calibrate magnetometer` fits one. Default: none (h = 0, W = I).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MagnetometerParams {
    /// Hard iron `h`, µT, sensor frame.
    pub hard_iron_ut: [f64; 3],
    /// `W`, the inverse of the soft iron, by rows.
    pub soft_iron_inv: [[f64; 3]; 3],
}

impl Default for MagnetometerParams {
    fn default() -> Self {
        Self {
            hard_iron_ut: [0.0; 3],
            soft_iron_inv: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        }
    }
}

impl MagnetometerParams {
    /// The checked calibration (finite, `W` invertible).
    pub fn calibration(&self) -> anyhow::Result<MagCalibration> {
        let w = Matrix3::from_fn(|r, c| self.soft_iron_inv[r][c]);
        MagCalibration::new(Vector3::from(self.hard_iron_ut), w)
            .map_err(|e| anyhow::anyhow!("magnetometer: {e}"))
    }
}

/// Parameters of the `gyro` variant (`[process.attitude.variants.gyro]` over
/// `[process.attitude.params]`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GyroParams {
    /// Still samples averaged for the initial alignment (paper 000 averages 400 for
    /// its static calibration; 200 is 2 s at 100 Hz).
    pub alignment_samples: usize,
    /// The magnetometer's calibration (the alignment's heading uses the field).
    pub magnetometer: MagnetometerParams,
}

impl Default for GyroParams {
    fn default() -> Self {
        GyroParams {
            alignment_samples: 200,
            magnetometer: MagnetometerParams::default(),
        }
    }
}

/// Parameters of the `mekf` variant (`variants.mekf = { alignment_samples = 400,
/// filter = { mag_norm_gate = 0.2 } }`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MekfVariantParams {
    /// Samples averaged for the initial alignment (as the `gyro` variant).
    pub alignment_samples: usize,
    /// The alignment counts as still, and its mean gyro as the initial bias, when
    /// the RMS of the gyro samples about their mean (norm over the three axes) is
    /// below this, °/s. Default 1 (our choice: the MTi-30's white noise gives
    /// 0.52 °/s at 100 Hz; a hand-rocked or wave-rocked IMU gives tens).
    pub still_gyro_rms_deg_s: f64,
    /// Initial roll and pitch 1σ, degrees, when the alignment was not still (its
    /// means then average a moving attitude). Default 20 (our choice: the
    /// amplitude of paper 000's rocking motion).
    pub moving_alignment_tilt_std_deg: f64,
    /// Initial heading 1σ, degrees, when the alignment was not still. Default 30
    /// (our choice).
    pub moving_alignment_heading_std_deg: f64,
    /// The magnetometer's calibration.
    pub magnetometer: MagnetometerParams,
    /// The filter's parameters.
    pub filter: MekfParams,
}

impl Default for MekfVariantParams {
    fn default() -> Self {
        Self {
            alignment_samples: 200,
            still_gyro_rms_deg_s: 1.0,
            moving_alignment_tilt_std_deg: 20.0,
            moving_alignment_heading_std_deg: 30.0,
            magnetometer: MagnetometerParams::default(),
            filter: MekfParams::default(),
        }
    }
}

/// Parameters of the `pf` variant (`variants.pf = { alignment_samples = 400,
/// filter = { particles = 1000 } }`); the alignment fields as the `mekf`'s.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PfVariantParams {
    /// Samples averaged for the initial alignment.
    pub alignment_samples: usize,
    /// The alignment counts as still, and its mean gyro as the initial bias
    /// (paper 000's static calibration), when the RMS of the gyro samples
    /// about their mean is below this, °/s. Default 1 (as the `mekf`).
    pub still_gyro_rms_deg_s: f64,
    /// Initial roll and pitch 1σ of the particles, degrees, when the alignment
    /// was not still. Default 20 (as the `mekf`).
    pub moving_alignment_tilt_std_deg: f64,
    /// Initial heading 1σ, degrees, when the alignment was not still.
    /// Default 30 (as the `mekf`).
    pub moving_alignment_heading_std_deg: f64,
    /// The magnetometer's calibration.
    pub magnetometer: MagnetometerParams,
    /// The filter's parameters.
    pub filter: PfParams,
}

impl Default for PfVariantParams {
    fn default() -> Self {
        Self {
            alignment_samples: 200,
            still_gyro_rms_deg_s: 1.0,
            moving_alignment_tilt_std_deg: 20.0,
            moving_alignment_heading_std_deg: 30.0,
            magnetometer: MagnetometerParams::default(),
            filter: PfParams::default(),
        }
    }
}

/// A variant's parameters.
#[derive(Debug, Clone)]
pub enum VariantParams {
    /// `gyro`.
    Gyro(GyroParams),
    /// `mekf`.
    Mekf(MekfVariantParams),
    /// `pf`.
    Pf(PfVariantParams),
}

impl VariantParams {
    /// The magnetometer's calibration parameters.
    pub fn magnetometer(&self) -> &MagnetometerParams {
        match self {
            VariantParams::Gyro(p) => &p.magnetometer,
            VariantParams::Mekf(p) => &p.magnetometer,
            VariantParams::Pf(p) => &p.magnetometer,
        }
    }
}

/// The checked form of [`VariantParams`].
#[derive(Debug, Clone, Copy)]
enum Variant {
    Gyro,
    Mekf {
        config: MekfConfig,
        still_gyro_rms_rad_s: f64,
        moving_tilt_std_rad: f64,
        moving_heading_std_rad: f64,
    },
    Pf {
        config: PfConfig,
        still_gyro_rms_rad_s: f64,
        moving_tilt_std_rad: f64,
        moving_heading_std_rad: f64,
    },
}

/// Checks the alignment fields shared by `mekf` and `pf`.
fn check_alignment_fields(
    still_gyro_rms_deg_s: f64,
    tilt_std_deg: f64,
    heading_std_deg: f64,
) -> anyhow::Result<()> {
    anyhow::ensure!(
        still_gyro_rms_deg_s >= 0.0 && still_gyro_rms_deg_s.is_finite(),
        "still_gyro_rms_deg_s = {still_gyro_rms_deg_s} is not a non-negative number"
    );
    for (name, v) in [
        ("moving_alignment_tilt_std_deg", tilt_std_deg),
        ("moving_alignment_heading_std_deg", heading_std_deg),
    ] {
        anyhow::ensure!(v > 0.0 && v <= 180.0, "{name} = {v} is not in (0, 180]");
    }
    Ok(())
}

/// Running mean and spread of the gyro during the alignment (Welford).
#[derive(Debug, Clone, Default)]
struct GyroMean {
    count: u64,
    mean: Vector3<f64>,
    /// Sum of squared deviations from the mean, all axes.
    m2: f64,
    duration_s: f64,
}

impl GyroMean {
    fn push(&mut self, gyro: &Vector3<f64>, interval_s: f64) {
        self.count += 1;
        let delta = gyro - self.mean;
        self.mean += delta / self.count as f64;
        self.m2 += delta.dot(&(gyro - self.mean));
        self.duration_s += interval_s;
    }

    /// RMS norm of the deviations from the mean.
    fn rms(&self) -> f64 {
        (self.m2 / self.count.max(1) as f64).sqrt()
    }
}

/// One running estimator.
#[derive(Debug)]
enum Estimator {
    Gyro(GyroIntegrator),
    Mekf(Box<Mekf>),
    Pf(Box<ParticleFilter>),
}

impl Estimator {
    fn get(&self) -> &dyn AttitudeEstimator {
        match self {
            Estimator::Gyro(g) => g,
            Estimator::Mekf(m) => m.as_ref(),
            Estimator::Pf(p) => p.as_ref(),
        }
    }

    fn get_mut(&mut self) -> &mut dyn AttitudeEstimator {
        match self {
            Estimator::Gyro(g) => g,
            Estimator::Mekf(m) => m.as_mut(),
            Estimator::Pf(p) => p.as_mut(),
        }
    }
}

/// Where the estimator is in its life.
#[derive(Debug)]
enum Phase {
    Aligning(Alignment, GyroMean),
    /// Warm start: the estimator is built from this snapshot, valid after the
    /// sample stamped `.1`, at the first sample after it.
    Restoring(Box<AttitudeStateSnapshot>, u64),
    Running(Estimator),
}

/// Alignment then one estimator variant.
#[derive(Debug)]
pub struct AttitudeCore {
    phase: Phase,
    variant: Variant,
    latitude_rad: f64,
    declination_rad: f64,
    alignment_samples: usize,
    magnetometer: MagCalibration,
}

impl AttitudeCore {
    /// A core for the variant of `params` at the site's latitude and declination.
    pub fn new(
        params: &VariantParams,
        latitude_rad: f64,
        declination_rad: f64,
    ) -> anyhow::Result<Self> {
        let (alignment_samples, variant) = match params {
            VariantParams::Gyro(p) => (p.alignment_samples, Variant::Gyro),
            VariantParams::Mekf(p) => {
                anyhow::ensure!(
                    p.still_gyro_rms_deg_s >= 0.0 && p.still_gyro_rms_deg_s.is_finite(),
                    "still_gyro_rms_deg_s = {} is not a non-negative number",
                    p.still_gyro_rms_deg_s
                );
                for (name, v) in [
                    (
                        "moving_alignment_tilt_std_deg",
                        p.moving_alignment_tilt_std_deg,
                    ),
                    (
                        "moving_alignment_heading_std_deg",
                        p.moving_alignment_heading_std_deg,
                    ),
                ] {
                    anyhow::ensure!(v > 0.0 && v <= 180.0, "{name} = {v} is not in (0, 180]");
                }
                (
                    p.alignment_samples,
                    Variant::Mekf {
                        config: MekfConfig::try_from(&p.filter)?,
                        still_gyro_rms_rad_s: p.still_gyro_rms_deg_s.to_radians(),
                        moving_tilt_std_rad: p.moving_alignment_tilt_std_deg.to_radians(),
                        moving_heading_std_rad: p.moving_alignment_heading_std_deg.to_radians(),
                    },
                )
            }
            VariantParams::Pf(p) => {
                check_alignment_fields(
                    p.still_gyro_rms_deg_s,
                    p.moving_alignment_tilt_std_deg,
                    p.moving_alignment_heading_std_deg,
                )?;
                (
                    p.alignment_samples,
                    Variant::Pf {
                        config: PfConfig::try_from(&p.filter)?,
                        still_gyro_rms_rad_s: p.still_gyro_rms_deg_s.to_radians(),
                        moving_tilt_std_rad: p.moving_alignment_tilt_std_deg.to_radians(),
                        moving_heading_std_rad: p.moving_alignment_heading_std_deg.to_radians(),
                    },
                )
            }
        };
        let magnetometer = params.magnetometer().calibration()?;
        let alignment_samples = alignment_samples.max(1);
        let alignment = Alignment::new(declination_rad, alignment_samples)?;
        anyhow::ensure!(
            latitude_rad.abs() <= std::f64::consts::FRAC_PI_2,
            "latitude out of range"
        );
        Ok(AttitudeCore {
            phase: Phase::Aligning(alignment, GyroMean::default()),
            variant,
            latitude_rad,
            declination_rad,
            alignment_samples,
            magnetometer,
        })
    }

    /// Starts warm instead of aligning: the estimator continues from
    /// `snapshot`, the state after the sample stamped `stamp_ns` (a previous
    /// instance's, handed over by the launcher). Samples up to that stamp are
    /// skipped; the next one builds the estimator and is processed. A snapshot
    /// that fails its checks is refused and the core keeps aligning.
    pub fn warm_start(
        &mut self,
        snapshot: AttitudeStateSnapshot,
        stamp_ns: u64,
    ) -> anyhow::Result<()> {
        snapshot
            .checked()
            .map_err(|e| anyhow::anyhow!("snapshot refused: {e}"))?;
        self.phase = Phase::Restoring(Box::new(snapshot), stamp_ns);
        Ok(())
    }

    /// Processes one checked IMU sample; returns the estimate once aligned.
    pub fn step(&mut self, imu: &Imu) -> anyhow::Result<Option<AttitudeOutput>> {
        let imu = &Imu {
            mag_ut: self.magnetometer.apply(&imu.mag_ut),
            ..*imu
        };
        if let Phase::Restoring(snapshot, after) = &self.phase {
            if imu.stamp_ns <= *after {
                return Ok(None);
            }
            let expected = *after + (imu.interval_s * 1e9).round() as u64;
            if imu.stamp_ns > expected {
                tracing::warn!(
                    snapshot_ns = *after,
                    first_sample_ns = imu.stamp_ns,
                    "the inputs' history does not reach back to the snapshot: the samples between are missing"
                );
            }
            let est = restore(
                self.variant,
                self.latitude_rad,
                self.declination_rad,
                snapshot,
                *after,
                imu,
            )?;
            self.phase = Phase::Running(est);
        }
        match &mut self.phase {
            Phase::Restoring(..) => Ok(None),
            Phase::Aligning(a, gyro) => {
                a.push(&imu.accel_m_s2, &imu.mag_ut)?;
                gyro.push(&imu.gyro_rad_s, imu.interval_s);
                if a.count() >= self.alignment_samples {
                    let est = start(
                        self.variant,
                        self.latitude_rad,
                        self.declination_rad,
                        a,
                        gyro,
                        imu.stamp_ns,
                    )?;
                    let out = est.get().estimate();
                    self.phase = Phase::Running(est);
                    return Ok(Some(out));
                }
                Ok(None)
            }
            Phase::Running(est) => {
                let e = est.get_mut();
                e.predict(&imu.gyro_rad_s, imu.interval_s);
                e.update(&imu.accel_m_s2, &imu.mag_ut);
                Ok(Some(e.estimate()))
            }
        }
    }

    /// The estimator's snapshot, once aligned.
    pub fn snapshot(&self) -> Option<AttitudeStateSnapshot> {
        match &self.phase {
            Phase::Running(est) => Some(est.get().snapshot()),
            Phase::Aligning(..) | Phase::Restoring(..) => None,
        }
    }

    /// True when a magnetometer calibration other than none is applied.
    pub fn magnetometer_calibrated(&self) -> bool {
        self.magnetometer != MagCalibration::identity()
    }

    /// True once aligned.
    pub fn is_aligned(&self) -> bool {
        matches!(self.phase, Phase::Running(_))
    }
}

/// The estimator of a warm start: the variant's estimator at the snapshot's
/// attitude with the snapshot's state. The `mekf` takes its magnetic
/// reference (field norm and dip) from the first sample's field seen at the
/// snapshot's attitude, since the snapshot does not carry it; so does the
/// `pf`, whose particles are re-seeded around the snapshot.
fn restore(
    variant: Variant,
    latitude_rad: f64,
    declination_rad: f64,
    snapshot: &AttitudeStateSnapshot,
    stamp_ns: u64,
    first: &Imu,
) -> anyhow::Result<Estimator> {
    let (q, _) = snapshot
        .checked()
        .map_err(|e| anyhow::anyhow!("snapshot refused: {e}"))?;
    let mut est = match variant {
        Variant::Gyro => Estimator::Gyro(GyroIntegrator::new(q, latitude_rad, stamp_ns)?),
        Variant::Mekf { config, .. } => {
            let reference = MagneticReference::from_mean_field(&q, &first.mag_ut)?;
            Estimator::Mekf(Box::new(Mekf::new(
                &config,
                q,
                latitude_rad,
                declination_rad,
                reference,
            )?))
        }
        Variant::Pf { config, .. } => {
            let reference = MagneticReference::from_mean_field(&q, &first.mag_ut)?;
            Estimator::Pf(Box::new(ParticleFilter::new(
                &config,
                q,
                latitude_rad,
                declination_rad,
                reference,
            )?))
        }
    };
    est.get_mut()
        .restore(snapshot)
        .map_err(|e| anyhow::anyhow!("snapshot refused: {e}"))?;
    tracing::info!(stamp_ns, "warm start from the snapshot");
    Ok(est)
}

/// The estimator that follows the alignment.
fn start(
    variant: Variant,
    latitude_rad: f64,
    declination_rad: f64,
    a: &Alignment,
    gyro: &GyroMean,
    stamp_ns: u64,
) -> anyhow::Result<Estimator> {
    let q = a.finish()?;
    // The expected field (the `gyro` variant does not need one).
    let reference = || -> anyhow::Result<MagneticReference> {
        let mean_mag = a
            .mean_magnetic_field()
            .ok_or_else(|| anyhow::anyhow!("alignment finished without samples"))?;
        Ok(MagneticReference::from_mean_field(&q, &mean_mag)?)
    };
    let earth_b = q.inverse_transform_vector(&earth_rate_ned(latitude_rad));
    match variant {
        Variant::Gyro => Ok(Estimator::Gyro(GyroIntegrator::new(
            q,
            latitude_rad,
            stamp_ns,
        )?)),
        Variant::Mekf {
            config,
            still_gyro_rms_rad_s,
            moving_tilt_std_rad,
            moving_heading_std_rad,
        } => {
            let reference = reference()?;
            let mut mekf = Mekf::new(&config, q, latitude_rad, declination_rad, reference)?;
            let still = gyro.rms() <= still_gyro_rms_rad_s && gyro.duration_s > 0.0;
            if still {
                let bias = gyro.mean - earth_b;
                let std = (config.gyro_noise_rad_rt_s().powi(2) / gyro.duration_s
                    + config.gyro_bias_instability_rad_s().powi(2))
                .sqrt();
                mekf = mekf.with_initial_bias(bias, std)?;
            } else {
                mekf =
                    mekf.with_initial_attitude_std(moving_tilt_std_rad, moving_heading_std_rad)?;
            }
            tracing::info!(
                still,
                gyro_rms_deg_s = gyro.rms().to_degrees(),
                bias_deg_h = ?mekf.gyro_bias().map(|b| b.to_degrees() * 3600.0),
                field_ut = reference.field_ut(),
                dip_deg = reference.dip_rad().to_degrees(),
                "aligned; mekf starts"
            );
            Ok(Estimator::Mekf(Box::new(mekf)))
        }
        Variant::Pf {
            config,
            still_gyro_rms_rad_s,
            moving_tilt_std_rad,
            moving_heading_std_rad,
        } => {
            let reference = reference()?;
            let mut pf = ParticleFilter::new(&config, q, latitude_rad, declination_rad, reference)?;
            let still = gyro.rms() <= still_gyro_rms_rad_s && gyro.duration_s > 0.0;
            if still {
                // Paper 000's static calibration: the still mean less the
                // Earth rate, known to N/√T.
                let bias = gyro.mean - earth_b;
                let std = (config.gyro_noise_rad_rt_s() / gyro.duration_s.sqrt())
                    .max(PF_MIN_INITIAL_BIAS_STD_RAD_S);
                pf = pf.with_initial_bias(bias, std)?;
            } else {
                pf = pf.with_initial_attitude_std(moving_tilt_std_rad, moving_heading_std_rad)?;
            }
            tracing::info!(
                still,
                particles = config.particles(),
                gyro_rms_deg_s = gyro.rms().to_degrees(),
                bias_deg_h = ?pf.gyro_bias().map(|b| b.to_degrees() * 3600.0),
                field_ut = reference.field_ut(),
                dip_deg = reference.dip_rad().to_degrees(),
                "aligned; pf starts"
            );
            Ok(Estimator::Pf(Box::new(pf)))
        }
    }
}

/// Smallest initial bias 1σ of the `pf` after a still alignment, rad/s
/// (0.01 °/s): the particles keep some spread in bias.
const PF_MIN_INITIAL_BIAS_STD_RAD_S: f64 = 1.745e-4;
