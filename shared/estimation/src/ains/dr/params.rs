//! The `dr` variant's parameters as a manifest writes them
//! (`[process.ains.variants.dr]`, every field defaulted, unknown keys
//! refused) and their check.

use serde::Deserialize;

use super::spike::SpikeConfig;
use crate::params::{OutOfRange, in_range, positive};
use crate::predictor::{PredictorConfig, PredictorParams, PredictorParamsError};

/// Parameters of paper 002's dead reckoning.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DrParams {
    /// Run the DVL spike filter of eq. 7. Default true.
    pub spike_filter: bool,
    /// Eq. 7's rejection threshold on `|ṽ_b − v̂_b|`, the distance between
    /// the DVL sample and the IMU-integrated prediction, m/s. Default 0.3
    /// (our choice: the prediction is good to a few cm/s over a second with
    /// an MTi-30 class IMU; the paper does not give its value).
    pub spike_threshold_m_s: f64,
    /// Largest number of consecutive rejections; the next sample over the
    /// threshold is trusted again (paper 002: "a limited number of times").
    /// Default 5 (our choice: 1 s at 5 Hz).
    pub spike_max_rejections: u32,
    /// Longest IMU integration (eq. 7's `t_k − t_{k−j}`) used to judge a
    /// sample or to bridge a DVL dropout, s; past it the last body velocity
    /// is held. Default 2 (our choice).
    pub max_prediction_s: f64,
    /// An aiding stream counts in `aiding_mode` (and the AHRS as the
    /// publishing input) while its last sample is at most this old, s.
    /// Default 1 (our choice).
    pub aiding_timeout_s: f64,
    /// A DVL velocity faster than this is refused as bad input, m/s.
    /// Default 10 (our choice; AUVs do not go at 20 knots).
    pub max_speed_m_s: f64,
    /// How long after its stamp a DVL sample's velocity holds, s: a DVL that
    /// stamps the start of its averaging interval, or a clock offset between
    /// the DVL and the attitude source. The sample is judged by the spike
    /// filter when it arrives and used from `stamp + dvl_delay_s` on (at
    /// most 8 samples waiting). Default 0. A-KIT's Snapir logs: 1.0
    /// (`docs/analysis/akit_dvl_timing.py`: fitted on trajectories 1-4).
    pub dvl_delay_s: f64,
    /// Horizontal position σ per axis before the first GPS fix (the
    /// position is then the site's), m. Default 1000 (our choice).
    pub initial_position_std_m: f64,
    /// A depth reading tares the gauge when a GPS fix came within this, s
    /// (the antenna is out of the water). Default 1.5 (our choice: the GPS
    /// gives 1 Hz at the surface).
    pub surface_window_s: f64,
    /// ... and the vertical velocity (eq. 1) is below this, m/s, so that
    /// the readings of a dive that has started are left out. Default 0.05
    /// (our choice).
    pub tare_max_vertical_speed_m_s: f64,
    /// Surface readings the tare averages (a session's average becomes the
    /// offset once it holds this many; later ones move it with weight
    /// 1/n). Default 20 (our choice: 2 s at 10 Hz).
    pub tare_samples: u64,
    /// Normalised-innovation gate of a GPS fix: the fix resets the position
    /// only if `νᵀ (P_h + σ² I)⁻¹ ν` is at most this, ν the fix's offset
    /// from the dead-reckoned position, `P_h` the predictor's horizontal
    /// covariance, σ the fix's. Default 13.8 (our choice: χ² with 2 degrees
    /// of freedom at 99.9 %); 0 turns the gate off.
    pub gps_gate_chi2: f64,
    /// After this many consecutive gated fixes the next one resets the
    /// position anyway (the gate cannot lock the GPS out). Default 5 (our
    /// choice: 5 s at 1 Hz).
    pub gps_gate_max_rejections: u32,
    /// The error predictor (paper 002 eqs. 14-17) and the sensors'
    /// specification it is fed from.
    pub predictor: PredictorParams,
    /// Accepted so that `ains.params.position_aiding` serves every variant;
    /// `dr` never uses position fixes (paper 002 has none), whatever it says.
    pub position_aiding: bool,
}

impl Default for DrParams {
    fn default() -> Self {
        Self {
            spike_filter: true,
            position_aiding: true,
            spike_threshold_m_s: 0.3,
            spike_max_rejections: 5,
            max_prediction_s: 2.0,
            aiding_timeout_s: 1.0,
            max_speed_m_s: 10.0,
            dvl_delay_s: 0.0,
            initial_position_std_m: 1000.0,
            surface_window_s: 1.5,
            tare_max_vertical_speed_m_s: 0.05,
            tare_samples: 20,
            gps_gate_chi2: 13.8,
            gps_gate_max_rejections: 5,
            predictor: PredictorParams::default(),
        }
    }
}

/// Why [`DrParams`] cannot be used.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum DrParamsError {
    /// A value is NaN, infinite or outside its range.
    #[error("dr parameter {name} = {value} is out of range ({range})")]
    OutOfRange {
        /// The field's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range, in words.
        range: &'static str,
    },
    /// The predictor's parameters are bad.
    #[error(transparent)]
    Predictor(#[from] PredictorParamsError),
}

impl From<OutOfRange> for DrParamsError {
    fn from(e: OutOfRange) -> Self {
        Self::OutOfRange {
            name: e.name,
            value: e.value,
            range: e.range,
        }
    }
}

/// The checked parameters, SI units, ns for time windows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrConfig {
    pub(super) spike: SpikeConfig,
    pub(super) aiding_timeout_ns: u64,
    pub(super) max_speed_m_s: f64,
    pub(super) dvl_delay_ns: u64,
    pub(super) initial_position_std_m: f64,
    pub(super) surface_window_ns: u64,
    pub(super) tare_max_vertical_speed_m_s: f64,
    pub(super) tare_samples: u64,
    pub(super) gps_gate_chi2: f64,
    pub(super) gps_gate_max_rejections: u32,
    pub(super) predictor: PredictorConfig,
}

fn ns(s: f64) -> u64 {
    (s * 1e9).round() as u64
}

impl DrParams {
    /// The checked configuration; a bad value is refused by name.
    pub fn check(&self) -> Result<DrConfig, DrParamsError> {
        let threshold = positive("spike_threshold_m_s", self.spike_threshold_m_s)?;
        if self.spike_max_rejections > 1000 {
            return Err(DrParamsError::OutOfRange {
                name: "spike_max_rejections",
                value: self.spike_max_rejections as f64,
                range: "[0, 1000]",
            });
        }
        let day = 86_400.0;
        let max_span = in_range(
            "max_prediction_s",
            self.max_prediction_s,
            0.0,
            60.0,
            false,
            "[0, 60]",
        )?;
        let timeout = in_range(
            "aiding_timeout_s",
            self.aiding_timeout_s,
            0.0,
            day,
            true,
            "(0, 86400]",
        )?;
        let max_speed = in_range(
            "max_speed_m_s",
            self.max_speed_m_s,
            0.0,
            100.0,
            true,
            "(0, 100]",
        )?;
        let delay = in_range("dvl_delay_s", self.dvl_delay_s, 0.0, 10.0, false, "[0, 10]")?;
        let initial = positive("initial_position_std_m", self.initial_position_std_m)?;
        let window = in_range(
            "surface_window_s",
            self.surface_window_s,
            0.0,
            day,
            false,
            "[0, 86400]",
        )?;
        let vz = in_range(
            "tare_max_vertical_speed_m_s",
            self.tare_max_vertical_speed_m_s,
            0.0,
            10.0,
            false,
            "[0, 10]",
        )?;
        if !(1..=1_000_000).contains(&self.tare_samples) {
            return Err(DrParamsError::OutOfRange {
                name: "tare_samples",
                value: self.tare_samples as f64,
                range: "[1, 1000000]",
            });
        }
        let gate = in_range(
            "gps_gate_chi2",
            self.gps_gate_chi2,
            0.0,
            1e6,
            false,
            "[0, 1e6]",
        )?;
        if self.gps_gate_max_rejections > 1_000_000 {
            return Err(DrParamsError::OutOfRange {
                name: "gps_gate_max_rejections",
                value: self.gps_gate_max_rejections as f64,
                range: "[0, 1000000]",
            });
        }
        Ok(DrConfig {
            spike: SpikeConfig {
                enabled: self.spike_filter,
                threshold_m_s: threshold,
                max_rejections: self.spike_max_rejections,
                max_span_s: max_span,
            },
            aiding_timeout_ns: ns(timeout),
            max_speed_m_s: max_speed,
            dvl_delay_ns: ns(delay),
            initial_position_std_m: initial,
            surface_window_ns: ns(window),
            tare_max_vertical_speed_m_s: vz,
            tare_samples: self.tare_samples,
            gps_gate_chi2: gate,
            gps_gate_max_rejections: self.gps_gate_max_rejections,
            predictor: self.predictor.check()?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_parse_and_bad_values_are_refused_by_name() {
        let p: DrParams = toml::from_str("").expect("defaults");
        assert_eq!(p, DrParams::default());
        assert!(p.check().is_ok());
        let p: DrParams = toml::from_str(
            "spike_threshold_m_s = 0.5\npredictor = { form = \"eq14\", sensors = { ahrs = { heading_bias_time_s = inf } } }",
        )
        .expect("valid");
        assert_eq!(p.spike_threshold_m_s, 0.5);
        assert!(p.predictor.sensors.ahrs.heading_bias_time_s.is_infinite());
        assert!(toml::from_str::<DrParams>("nope = 1").is_err());
        assert!(toml::from_str::<DrParams>("predictor = { nope = 1 }").is_err());
        for (p, name) in [
            (
                DrParams {
                    spike_threshold_m_s: f64::NAN,
                    ..Default::default()
                },
                "spike_threshold_m_s",
            ),
            (
                DrParams {
                    aiding_timeout_s: 0.0,
                    ..Default::default()
                },
                "aiding_timeout_s",
            ),
            (
                DrParams {
                    tare_samples: 0,
                    ..Default::default()
                },
                "tare_samples",
            ),
            (
                DrParams {
                    max_prediction_s: -1.0,
                    ..Default::default()
                },
                "max_prediction_s",
            ),
        ] {
            match p.check() {
                Err(DrParamsError::OutOfRange { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{name}: {other:?}"),
            }
        }
        let mut p = DrParams::default();
        p.predictor.sensors.ahrs.rate_hz = 0.0;
        let e = p.check().unwrap_err();
        assert!(e.to_string().contains("ahrs.rate_hz"), "{e}");
    }
}
