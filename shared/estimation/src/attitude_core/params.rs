//! Parameters of the attitude role's variants, as the manifest gives them
//! (`[process.attitude.params]` and `variants.V`), and their checks.

use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;

use crate::calibration::MagCalibration;
use crate::mekf::MekfParams;
use crate::pf::PfParams;

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

/// Checks the alignment fields shared by `mekf` and `pf`.
pub(super) fn check_alignment_fields(
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
