//! The attitude role's pure core: static alignment from the first still samples,
//! then one [`AttitudeEstimator`] variant. No IPC here; `main` wires it to ports.

use serde::Deserialize;

use nauta_estimation::alignment::Alignment;
use nauta_estimation::{AttitudeEstimator, AttitudeOutput, GyroIntegrator};
use nauta_messages::checked::Imu;

/// The variants this binary implements; the first is the default.
pub const VARIANTS: [&str; 1] = ["gyro"];

/// Parameters of the `gyro` variant (`[process.attitude.variants.gyro]` over
/// `[process.attitude.params]`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GyroParams {
    /// Still samples averaged for the initial alignment (paper 000 averages 400 for
    /// its static calibration; 200 is 2 s at 100 Hz).
    pub alignment_samples: usize,
}

impl Default for GyroParams {
    fn default() -> Self {
        GyroParams {
            alignment_samples: 200,
        }
    }
}

/// Where the estimator is in its life.
#[derive(Debug)]
enum Phase {
    Aligning(Alignment),
    Running(Box<GyroIntegrator>),
}

/// Alignment then gyro integration.
#[derive(Debug)]
pub struct AttitudeCore {
    phase: Phase,
    latitude_rad: f64,
    alignment_samples: usize,
}

impl AttitudeCore {
    /// A core for the `gyro` variant at the site's latitude and declination.
    pub fn new(
        params: &GyroParams,
        latitude_rad: f64,
        declination_rad: f64,
    ) -> anyhow::Result<Self> {
        let alignment_samples = params.alignment_samples.max(1);
        let alignment = Alignment::new(declination_rad, alignment_samples)?;
        anyhow::ensure!(
            latitude_rad.abs() <= std::f64::consts::FRAC_PI_2,
            "latitude out of range"
        );
        Ok(AttitudeCore {
            phase: Phase::Aligning(alignment),
            latitude_rad,
            alignment_samples,
        })
    }

    /// Processes one checked IMU sample; returns the estimate once aligned.
    pub fn step(&mut self, imu: &Imu) -> anyhow::Result<Option<AttitudeOutput>> {
        match &mut self.phase {
            Phase::Aligning(a) => {
                a.push(&imu.accel_m_s2, &imu.mag_ut)?;
                if a.count() >= self.alignment_samples {
                    let q = a.finish()?;
                    let g = GyroIntegrator::new(q, self.latitude_rad, imu.stamp_ns)?;
                    let out = g.estimate();
                    self.phase = Phase::Running(Box::new(g));
                    return Ok(Some(out));
                }
                Ok(None)
            }
            Phase::Running(g) => {
                g.predict(&imu.gyro_rad_s, imu.interval_s);
                g.update(&imu.accel_m_s2, &imu.mag_ut);
                Ok(Some(g.estimate()))
            }
        }
    }

    /// The estimator's snapshot, once aligned.
    pub fn snapshot(&self) -> Option<nauta_estimation::AttitudeStateSnapshot> {
        match &self.phase {
            Phase::Running(g) => Some(g.snapshot()),
            Phase::Aligning(_) => None,
        }
    }

    /// True once aligned.
    pub fn is_aligned(&self) -> bool {
        matches!(self.phase, Phase::Running(_))
    }
}
