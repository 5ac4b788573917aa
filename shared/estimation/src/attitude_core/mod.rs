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

use nalgebra::Vector3;

use crate::alignment::Alignment;
use crate::calibration::MagCalibration;
use crate::earth::earth_rate_ned;
use crate::frames::Vector;
use crate::mekf::{MagneticReference, Mekf, MekfConfig};
use crate::pf::{ParticleFilter, PfConfig};
use crate::readings::Imu;
use crate::role::{Estimator, EstimatorError, Stamped};
use crate::{AttitudeEstimator, AttitudeOutput, AttitudeStateSnapshot, GyroIntegrator};

mod params;

use params::check_alignment_fields;
pub use params::{
    GyroParams, MagnetometerParams, MekfVariantParams, PfVariantParams, VariantParams,
};

/// The variants of the attitude role; the first is the default.
pub const VARIANTS: [&str; 3] = ["pf", "gyro", "mekf"];

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

/// One running filter.
#[derive(Debug)]
enum Filter {
    Gyro(GyroIntegrator),
    Mekf(Box<Mekf>),
    Pf(Box<ParticleFilter>),
}

impl Filter {
    fn get(&self) -> &dyn AttitudeEstimator {
        match self {
            Filter::Gyro(g) => g,
            Filter::Mekf(m) => m.as_ref(),
            Filter::Pf(p) => p.as_ref(),
        }
    }

    fn get_mut(&mut self) -> &mut dyn AttitudeEstimator {
        match self {
            Filter::Gyro(g) => g,
            Filter::Mekf(m) => m.as_mut(),
            Filter::Pf(p) => p.as_mut(),
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
    Running(Filter),
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
                check_alignment_fields(
                    p.still_gyro_rms_deg_s,
                    p.moving_alignment_tilt_std_deg,
                    p.moving_alignment_heading_std_deg,
                )?;
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
            mag_ut: Vector::from_nalgebra(self.magnetometer.apply(imu.mag_ut.as_nalgebra())),
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
                a.push(imu.accel_m_s2.as_nalgebra(), imu.mag_ut.as_nalgebra())?;
                gyro.push(imu.gyro_rad_s.as_nalgebra(), imu.interval_s);
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
) -> anyhow::Result<Filter> {
    let (q, _) = snapshot
        .checked()
        .map_err(|e| anyhow::anyhow!("snapshot refused: {e}"))?;
    let q = q.to_nalgebra();
    let mut est = match variant {
        Variant::Gyro => Filter::Gyro(GyroIntegrator::new(q, latitude_rad, stamp_ns)?),
        Variant::Mekf { config, .. } => {
            let reference = MagneticReference::from_mean_field(&q, first.mag_ut.as_nalgebra())?;
            Filter::Mekf(Box::new(Mekf::new(
                &config,
                q,
                latitude_rad,
                declination_rad,
                reference,
            )?))
        }
        Variant::Pf { config, .. } => {
            let reference = MagneticReference::from_mean_field(&q, first.mag_ut.as_nalgebra())?;
            Filter::Pf(Box::new(ParticleFilter::new(
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
) -> anyhow::Result<Filter> {
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
        Variant::Gyro => Ok(Filter::Gyro(GyroIntegrator::new(
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
            Ok(Filter::Mekf(Box::new(mekf)))
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
            Ok(Filter::Pf(Box::new(pf)))
        }
    }
}

/// Smallest initial bias 1σ of the `pf` after a still alignment, rad/s
/// (0.01 °/s): the particles keep some spread in bias.
const PF_MIN_INITIAL_BIAS_STD_RAD_S: f64 = 1.745e-4;

/// What the attitude role publishes for one IMU sample (`attitude/estimate`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AttitudeReport {
    /// The IMU sample's stamp, ns.
    pub stamp_ns: u64,
    /// The estimate.
    pub estimate: AttitudeOutput,
    /// The initial alignment is done (always, once there is an estimate).
    pub aligned: bool,
    /// A magnetometer calibration other than none is applied.
    pub magnetometer_calibrated: bool,
}

impl Stamped for AttitudeReport {
    fn stamp_ns(&self) -> u64 {
        self.stamp_ns
    }
}

impl Estimator for AttitudeCore {
    type Input = Imu;
    type Output = AttitudeReport;
    type Snapshot = AttitudeStateSnapshot;

    fn on_input(&mut self, imu: &Imu, out: &mut Vec<AttitudeReport>) -> Result<(), EstimatorError> {
        let estimate = self
            .step(imu)
            .map_err(|e| EstimatorError::new("attitude-step", format!("{e:#}")))?;
        if let Some(estimate) = estimate {
            out.push(AttitudeReport {
                stamp_ns: imu.stamp_ns,
                estimate,
                aligned: self.is_aligned(),
                magnetometer_calibrated: self.magnetometer_calibrated(),
            });
        }
        Ok(())
    }

    fn snapshot(&self) -> Option<AttitudeStateSnapshot> {
        AttitudeCore::snapshot(self)
    }

    fn restore(
        &mut self,
        snapshot: &AttitudeStateSnapshot,
        stamp_ns: u64,
    ) -> Result<(), EstimatorError> {
        self.warm_start(*snapshot, stamp_ns)
            .map_err(|e| EstimatorError::new("snapshot-refused", format!("{e:#}")))
    }
}
