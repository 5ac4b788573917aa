//! Gyro and accelerometer axis error model, configured from datasheet specs.
//!
//! One axis measures the interval-average of the true value x over the
//! sample interval Δt (s) as
//!
//! ```text
//! x̃_k = (1 + s) x_k + b₀ + b_BI,k + b_RRW,k + w_k
//! ```
//!
//! - s ~ N(0, σ_s²): scale factor error, drawn once per instance (fraction);
//! - b₀ ~ N(0, σ_b0²): turn-on bias, drawn once per instance;
//! - w_k ~ N(0, N² / Δt): white noise of density N (unit/√Hz = unit·√s),
//!   the angle (gyro) or velocity (accelerometer) random walk; its Allan
//!   deviation is σ(τ) = N / √τ, so σ(1 s) = N;
//! - b_RRW,k = b_RRW,k−1 + K √Δt v_k: rate random walk of coefficient K
//!   (unit/√s); σ(τ) = K √(τ/3);
//! - b_BI,k = Σ_i g_i,k: bias instability as a sum of M = 9 first-order
//!   Gauss-Markov processes with correlation times T_i = 10^{i/2} s
//!   (i = 0 … 8, so 1 s … 10⁴ s, two per decade), each exactly discretised
//!   as g_i,k = φ_i g_i,k−1 + q √(1 − φ_i²) u_i,k with φ_i = e^{−Δt/T_i} and
//!   the same stationary standard deviation q, started from the stationary
//!   distribution (no transient). Equal variances at log-spaced corners sum
//!   to a 1/f (flicker) spectrum between the corners.
//!
//! The Allan variance of one Gauss-Markov process of variance q² and time
//! constant T is (e.g. El-Sheimy, Hou, Niu 2008, IEEE TIM 57(1))
//!
//! ```text
//! σ²_GM(τ) = q² (T/τ)² [2τ/T − 3 + 4 e^{−τ/T} − e^{−2τ/T}]
//! ```
//!
//! and q is set so that the geometric mean of Σ_i σ²_GM,i(τ) over τ in
//! [10 s, 1000 s] equals (0.664 B)², the flicker floor of a bias instability B
//! (IEEE Std 952-1997, Annex C). The sum is then flat within ±3 % over
//! 10 s – 1000 s (computed by [`InertialAxisSpec::model_adev`]), rolls off
//! as √τ below 1 s (where white noise dominates anyway) and as 1/√τ above
//! 10⁴ s.
//!
//! Units: a gyro spec is in rad/s (N in rad/√s, B and b₀ in rad/s, K in
//! rad/s/√s); an accelerometer spec in m/s² (N in m/s²/√Hz, B and b₀ in m/s²,
//! K in m/s²/√s). [`super::units`] converts from datasheet units.

use nalgebra::Vector3;
use rand::Rng;
use serde::{Deserialize, Serialize};

use super::allan::FLICKER_FLOOR_FACTOR;
use super::units::{
    deg_per_h_to_si, deg_per_s_per_rt_hz_to_si, deg_per_s_to_si, micro_g_per_rt_hz_to_si,
    micro_g_to_si, ppm_to_fraction,
};
use super::{NoiseError, check_non_negative, check_positive, std_normal};

/// Number of Gauss-Markov processes that make up the bias instability.
pub const BIAS_INSTABILITY_PROCESSES: usize = 9;

/// Correlation time of Gauss-Markov process i: T_i = 10^{i/2} s.
fn gm_time(i: usize) -> f64 {
    10f64.powf(i as f64 / 2.0)
}

/// Allan variance of a unit-variance first-order Gauss-Markov process at
/// x = τ/T: [2x − 3 + 4e^{−x} − e^{−2x}] / x².
fn gm_avar_shape(x: f64) -> f64 {
    if x < 1e-3 {
        // Series: (2/3) x − x²/2 (rate-random-walk asymptote).
        2.0 * x / 3.0 - x * x / 2.0
    } else {
        (2.0 * x - 3.0 + 4.0 * (-x).exp() - (-2.0 * x).exp()) / (x * x)
    }
}

/// Σ_i of the unit-variance shapes at τ.
fn gm_sum_shape(tau: f64) -> f64 {
    (0..BIAS_INSTABILITY_PROCESSES)
        .map(|i| gm_avar_shape(tau / gm_time(i)))
        .sum()
}

/// Geometric mean of [`gm_sum_shape`] over 41 log-spaced τ in [10 s, 1000 s].
fn gm_calibration() -> f64 {
    let count = 41;
    let mean_log = (0..count)
        .map(|j| {
            let tau = 10f64.powf(1.0 + 2.0 * j as f64 / (count - 1) as f64);
            gm_sum_shape(tau).ln()
        })
        .sum::<f64>()
        / count as f64;
    mean_log.exp()
}

/// Datasheet-style error specification of one inertial axis, SI units (see
/// the module documentation for the model and units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InertialAxisSpec {
    /// White noise density N: rad/s/√Hz (gyro) or m/s²/√Hz (accelerometer).
    pub noise_density: f64,
    /// Bias instability B (flicker floor σ_min = 0.664 B): rad/s or m/s².
    pub bias_instability: f64,
    /// Rate random walk K: rad/s/√s or m/s²/√s (0 to leave out).
    pub rate_random_walk: f64,
    /// Turn-on bias, 1σ, drawn once per instance: rad/s or m/s².
    pub turn_on_bias_sigma: f64,
    /// Scale factor error, 1σ, as a fraction (1e-6 = 1 ppm), drawn once.
    pub scale_factor_sigma: f64,
}

impl InertialAxisSpec {
    /// Gyro of the Xsens MTi-30 class (MTi 10-series datasheet, as remembered;
    /// check against the PDF): rate noise density 0.03 °/s/√Hz (= 1.8 °/√h),
    /// in-run bias stability 18 °/h, bias repeatability 0.2 °/s (used as the
    /// turn-on bias 1σ). Rate random walk is not given (0). The scale factor
    /// error, 500 ppm 1σ, is our choice (the datasheet gives non-linearity).
    pub fn mti30_gyro() -> Self {
        Self {
            noise_density: deg_per_s_per_rt_hz_to_si(0.03),
            bias_instability: deg_per_h_to_si(18.0),
            rate_random_walk: 0.0,
            turn_on_bias_sigma: deg_per_s_to_si(0.2),
            scale_factor_sigma: ppm_to_fraction(500.0),
        }
    }

    /// Accelerometer of the Xsens MTi-30 class. We use the 10-series figures
    /// (the MTi-30 is a 10-series device), as remembered from the vendor
    /// datasheets and to be checked against the PDF: noise density
    /// 80 µg/√Hz and in-run bias stability 40 µg (the 100-series quotes
    /// 60 µg/√Hz and 15 µg). Turn-on bias 1σ 0.03 m/s² (bias repeatability,
    /// as remembered); scale factor error 500 ppm 1σ (our choice).
    pub fn mti30_accel() -> Self {
        Self {
            noise_density: micro_g_per_rt_hz_to_si(80.0),
            bias_instability: micro_g_to_si(40.0),
            rate_random_walk: 0.0,
            turn_on_bias_sigma: 0.03,
            scale_factor_sigma: ppm_to_fraction(500.0),
        }
    }

    /// Check every field is finite and non-negative.
    pub fn validate(&self) -> Result<(), NoiseError> {
        check_non_negative("noise_density", self.noise_density)?;
        check_non_negative("bias_instability", self.bias_instability)?;
        check_non_negative("rate_random_walk", self.rate_random_walk)?;
        check_non_negative("turn_on_bias_sigma", self.turn_on_bias_sigma)?;
        check_non_negative("scale_factor_sigma", self.scale_factor_sigma)?;
        Ok(())
    }

    /// Stationary standard deviation q of each bias-instability Gauss-Markov
    /// process (same unit as B).
    pub fn gauss_markov_sigma(&self) -> f64 {
        FLICKER_FLOOR_FACTOR * self.bias_instability / gm_calibration().sqrt()
    }

    /// Allan deviation of the configured model at τ (s), for a series sampled
    /// fast enough that τ is many samples:
    /// σ²(τ) = N²/τ + q² Σ_i shape(τ/T_i) + K² τ/3.
    pub fn model_adev(&self, tau: f64) -> f64 {
        let q = self.gauss_markov_sigma();
        (self.noise_density.powi(2) / tau
            + q * q * gm_sum_shape(tau)
            + self.rate_random_walk.powi(2) * tau / 3.0)
            .sqrt()
    }
}

/// Error state of one inertial axis; see the module documentation.
#[derive(Debug, Clone)]
pub struct InertialAxisNoise {
    spec: InertialAxisSpec,
    scale_factor: f64,
    turn_on_bias: f64,
    gm_sigma: f64,
    gm: [f64; BIAS_INSTABILITY_PROCESSES],
    rrw: f64,
    // Discretisation cached for the last Δt.
    dt: f64,
    phi: [f64; BIAS_INSTABILITY_PROCESSES],
    drive: [f64; BIAS_INSTABILITY_PROCESSES],
    white_sigma: f64,
    rrw_step: f64,
}

impl InertialAxisNoise {
    /// Validate `spec` and draw the per-instance errors (scale factor,
    /// turn-on bias, stationary Gauss-Markov states) from `rng`.
    pub fn new<R: Rng + ?Sized>(spec: InertialAxisSpec, rng: &mut R) -> Result<Self, NoiseError> {
        spec.validate()?;
        let scale_factor = spec.scale_factor_sigma * std_normal(rng);
        let turn_on_bias = spec.turn_on_bias_sigma * std_normal(rng);
        let gm_sigma = spec.gauss_markov_sigma();
        let mut gm = [0.0; BIAS_INSTABILITY_PROCESSES];
        if gm_sigma > 0.0 {
            for g in &mut gm {
                *g = gm_sigma * std_normal(rng);
            }
        }
        Ok(Self {
            spec,
            scale_factor,
            turn_on_bias,
            gm_sigma,
            gm,
            rrw: 0.0,
            dt: f64::NAN,
            phi: [0.0; BIAS_INSTABILITY_PROCESSES],
            drive: [0.0; BIAS_INSTABILITY_PROCESSES],
            white_sigma: 0.0,
            rrw_step: 0.0,
        })
    }

    /// The spec this axis was built from.
    pub fn spec(&self) -> &InertialAxisSpec {
        &self.spec
    }

    /// Scale factor error s drawn for this instance (fraction).
    pub fn scale_factor_error(&self) -> f64 {
        self.scale_factor
    }

    /// Turn-on bias b₀ drawn for this instance.
    pub fn turn_on_bias(&self) -> f64 {
        self.turn_on_bias
    }

    /// Current total bias b₀ + b_BI + b_RRW (what a perfect estimator would track).
    pub fn bias(&self) -> f64 {
        self.turn_on_bias + self.gm.iter().sum::<f64>() + self.rrw
    }

    fn discretise(&mut self, dt: f64) {
        self.dt = dt;
        for i in 0..BIAS_INSTABILITY_PROCESSES {
            let phi = (-dt / gm_time(i)).exp();
            self.phi[i] = phi;
            self.drive[i] = self.gm_sigma * (1.0 - phi * phi).sqrt();
        }
        self.white_sigma = self.spec.noise_density / dt.sqrt();
        self.rrw_step = self.spec.rate_random_walk * dt.sqrt();
    }

    /// Measure `true_value` (the interval average over the last `dt` seconds):
    /// returns (1 + s) x + b₀ + b_BI + b_RRW + w, then advances the bias
    /// processes by `dt`. Errors if `dt` is not positive and finite.
    pub fn next<R: Rng + ?Sized>(
        &mut self,
        rng: &mut R,
        true_value: f64,
        dt: f64,
    ) -> Result<f64, NoiseError> {
        check_positive("dt", dt)?;
        if dt != self.dt {
            self.discretise(dt);
        }
        let white = if self.white_sigma > 0.0 {
            self.white_sigma * std_normal(rng)
        } else {
            0.0
        };
        let measured = (1.0 + self.scale_factor) * true_value + self.bias() + white;
        if self.gm_sigma > 0.0 {
            for i in 0..BIAS_INSTABILITY_PROCESSES {
                self.gm[i] = self.phi[i] * self.gm[i] + self.drive[i] * std_normal(rng);
            }
        }
        if self.rrw_step > 0.0 {
            self.rrw += self.rrw_step * std_normal(rng);
        }
        Ok(measured)
    }
}

/// Three independent axes with the same spec (a gyro or accelerometer
/// triad; axis misalignment is not modelled).
#[derive(Debug, Clone)]
pub struct InertialTriadNoise {
    /// The x, y, z axes.
    pub axes: [InertialAxisNoise; 3],
}

impl InertialTriadNoise {
    /// Three axes drawn in order x, y, z from `rng`.
    pub fn new<R: Rng + ?Sized>(spec: InertialAxisSpec, rng: &mut R) -> Result<Self, NoiseError> {
        Ok(Self {
            axes: [
                InertialAxisNoise::new(spec, rng)?,
                InertialAxisNoise::new(spec, rng)?,
                InertialAxisNoise::new(spec, rng)?,
            ],
        })
    }

    /// Measure a true vector (interval average over `dt`), axis by axis.
    pub fn next<R: Rng + ?Sized>(
        &mut self,
        rng: &mut R,
        true_value: Vector3<f64>,
        dt: f64,
    ) -> Result<Vector3<f64>, NoiseError> {
        Ok(Vector3::new(
            self.axes[0].next(rng, true_value.x, dt)?,
            self.axes[1].next(rng, true_value.y, dt)?,
            self.axes[2].next(rng, true_value.z, dt)?,
        ))
    }

    /// Current bias of each axis.
    pub fn bias(&self) -> Vector3<f64> {
        Vector3::new(
            self.axes[0].bias(),
            self.axes[1].bias(),
            self.axes[2].bias(),
        )
    }
}

#[cfg(test)]
mod tests;
