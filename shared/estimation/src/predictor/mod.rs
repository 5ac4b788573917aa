//! Paper 002's error predictor (§2, eqs. 8-17): how far the dead reckoning's
//! position has drifted since the last GPS fix, from the sensors'
//! specifications, as `√E|δp_h|²` (`Nav::predicted_drift_m`), and a
//! surfacing advisory when it passes a threshold ("foresee the moment to
//! emerge").
//!
//! Paper 002 integrates eq. 8, `δp_n = ∫ δv_n dτ`, with `δv_n` from eqs.
//! 14-17 ([`sensitivity`]) and constant sensor errors (5 % of `v_b`, 3°).
//! A constant error over-predicts a long dive and gets closed tracks wrong
//! (a constant heading error rotates the track about its start, so a
//! rectangle back to its start keeps no error from it). Here the errors are
//! random processes with the statistics of [`SensorErrorSpec`] (white
//! noise, Gauss-Markov biases, a DVL scale factor) and the predictor
//! propagates the covariance of the linear error state along the vehicle's
//! actual track (the paper's `v_b ≈ v̂_b`, `Θ ≈ Θ̂`):
//!
//! ```text
//! x = [δp_N, δp_E, δp_D | b_vx, b_vy, b_vz, b_φ, b_θ, b_ψ | s | u_N, u_E, u_D]
//! δṗ = J (b + [s v_b; 0] + w) + u         (eq. 8 with eq. 14-17's J)
//! ḃ_i = −b_i / τ_i + n_i                   (first-order Gauss-Markov)
//! ṡ = 0,  u̇ = q n while the velocity is not aided (else u = 0)
//! ```
//!
//! with `w` the white noise (PSD `σ²/f`), discretised per step Δt as
//! `Φ = [[I, Δt G], [0, D]]`, `D = diag(e^{−Δt/τ_i}, 1, 1)`,
//! `G = [J | J_v v_b | I]`, and `Q` = `J W Jᵀ Δt` on the position,
//! `σ_b² (1 − e^{−2Δt/τ})` on the biases, `q² Δt` on `u` while unaided.
//! `u` is the error of a velocity that is not measured (a DVL outage, held
//! or inertially predicted velocity), a random walk of density `q`; when
//! the DVL returns it is dropped. A GPS fix resets the horizontal position
//! error to the fix's σ (uncorrelated with the sensor errors), a depth
//! sample the vertical one; the bias and scale-factor variances stay (they
//! are not observed).
//!
//! Eq. 8 makes no use of the depth gauge; here the down position is the
//! gauge's, so `δp_D` is reset at each depth sample and the prediction
//! (`horizontal_rms_m`) is horizontal.

mod sensitivity;
mod spec;

use nalgebra::{SMatrix, SVector};
use serde::Deserialize;
use thiserror::Error;

pub use sensitivity::{Form, Sensitivity, sensitivity};
pub use spec::{AhrsErrorSpec, CheckedSpec, DepthErrorSpec, DvlErrorSpec, SensorErrorSpec};

use crate::params::{OutOfRange, nonneg, positive};

/// Size of the error state: position (3), biases (6), scale factor (1),
/// unaided velocity (3).
pub const STATES: usize = 13;
const P0: usize = 0;
const B0: usize = 3;
const S0: usize = 9;
const U0: usize = 10;
/// Error states besides the position.
const E: usize = STATES - 3;

/// The predictor's covariance, row-major.
pub type Covariance = [[f64; STATES]; STATES];

/// The predictor's parameters as a manifest writes them
/// (`variants.dr.predictor = { form = "eq17", surfacing_threshold_m = 50.0,
/// sensors = { ahrs = { heading_bias_sigma_deg = 2.0 } } }`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PredictorParams {
    /// Which of eqs. 14-17 gives the sensitivities. Default `eq17` (paper
    /// 002's recommendation for embedded use; on its manoeuvres all four
    /// agreed within 0.1 %).
    pub form: Form,
    /// The sensors' error specification (default: the shipped simulator's).
    pub sensors: SensorErrorSpec,
    /// Density q of the velocity error while the velocity is not measured
    /// (DVL outage or no attitude), m/s/√s. Default 0.05 (our choice: after a
    /// 10 s outage the held velocity is trusted to 0.16 m/s).
    pub unaided_velocity_walk_m_s_rt_s: f64,
    /// The surfacing advisory is raised while the predicted horizontal RMS
    /// error is above this, m. Default 50 (our choice).
    pub surfacing_threshold_m: f64,
}

impl Default for PredictorParams {
    fn default() -> Self {
        Self {
            form: Form::Eq17,
            sensors: SensorErrorSpec::default(),
            unaided_velocity_walk_m_s_rt_s: 0.05,
            surfacing_threshold_m: 50.0,
        }
    }
}

/// Why [`PredictorParams`] cannot be used.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum PredictorParamsError {
    /// A value is NaN, infinite or outside its range.
    #[error("predictor parameter {name} = {value} is out of range ({range})")]
    OutOfRange {
        /// The field's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range, in words.
        range: &'static str,
    },
}

impl From<OutOfRange> for PredictorParamsError {
    fn from(e: OutOfRange) -> Self {
        Self::OutOfRange {
            name: e.name,
            value: e.value,
            range: e.range,
        }
    }
}

/// Checked predictor parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PredictorConfig {
    form: Form,
    spec: CheckedSpec,
    unaided_q: f64,
    threshold_m: f64,
}

impl PredictorParams {
    /// The checked configuration.
    pub fn check(&self) -> Result<PredictorConfig, PredictorParamsError> {
        Ok(PredictorConfig {
            form: self.form,
            spec: self.sensors.check()?,
            unaided_q: nonneg(
                "unaided_velocity_walk_m_s_rt_s",
                self.unaided_velocity_walk_m_s_rt_s,
            )?,
            threshold_m: positive("surfacing_threshold_m", self.surfacing_threshold_m)?,
        })
    }
}

impl PredictorConfig {
    /// The form of eqs. 14-17 in use.
    pub fn form(&self) -> Form {
        self.form
    }

    /// The checked sensor specification.
    pub fn spec(&self) -> &CheckedSpec {
        &self.spec
    }

    /// The surfacing threshold, m.
    pub fn surfacing_threshold_m(&self) -> f64 {
        self.threshold_m
    }
}

/// Where the vehicle is and how it moves during one step, the inputs of
/// eqs. 14-17.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    /// Body velocity in use, FRD, m/s.
    pub v_b: [f64; 3],
    /// Roll, pitch, yaw (true), rad.
    pub euler: [f64; 3],
    /// The velocity is measured (the DVL aids it); otherwise the unaided
    /// velocity error grows.
    pub aided: bool,
}

/// Why a covariance cannot be restored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
#[error("the predictor's covariance is not symmetric with a non-negative, finite diagonal")]
pub struct NotCovariance;

/// The error predictor: the covariance of the error state (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorPredictor {
    config: PredictorConfig,
    p: SMatrix<f64, STATES, STATES>,
}

impl ErrorPredictor {
    /// A predictor with horizontal position error σ `initial_std_m` per axis,
    /// the depth gauge's σ down, and every sensor error at its stationary
    /// variance.
    pub fn new(config: PredictorConfig, initial_std_m: f64) -> Self {
        let mut p = SMatrix::<f64, STATES, STATES>::zeros();
        p[(P0, P0)] = initial_std_m * initial_std_m;
        p[(P0 + 1, P0 + 1)] = initial_std_m * initial_std_m;
        p[(P0 + 2, P0 + 2)] = config.spec.depth_sigma_m.powi(2);
        for (i, c) in config.spec.channels.iter().enumerate() {
            p[(B0 + i, B0 + i)] = c.bias_sigma * c.bias_sigma;
        }
        p[(S0, S0)] = config.spec.scale_factor_sigma.powi(2);
        Self { config, p }
    }

    /// The configuration.
    pub fn config(&self) -> &PredictorConfig {
        &self.config
    }

    /// `G = [J | J_v v_b | I]` (position rows), and `J`.
    fn coupling(&self, m: &Motion) -> (SMatrix<f64, 3, E>, Sensitivity) {
        let [roll, pitch, yaw] = m.euler;
        let j = sensitivity(self.config.form, m.v_b, roll, pitch, yaw);
        let mut g = SMatrix::<f64, 3, E>::zeros();
        for r in 0..3 {
            for c in 0..6 {
                g[(r, c)] = j[r][c];
            }
            g[(r, S0 - B0)] = j[r][0] * m.v_b[0] + j[r][1] * m.v_b[1] + j[r][2] * m.v_b[2];
            g[(r, U0 - B0 + r)] = 1.0;
        }
        (g, j)
    }

    /// `J diag(x) Jᵀ`.
    fn jxj(j: &Sensitivity, x: impl Fn(usize) -> f64) -> SMatrix<f64, 3, 3> {
        SMatrix::<f64, 3, 3>::from_fn(|r, c| (0..6).map(|k| j[r][k] * x(k) * j[c][k]).sum())
    }

    /// Propagates over `dt_s` seconds of motion `m` (module docs). A step
    /// that is not positive and finite does nothing.
    pub fn propagate(&mut self, dt_s: f64, m: &Motion) {
        if !(dt_s > 0.0 && dt_s.is_finite()) {
            return;
        }
        let (g, j) = self.coupling(m);
        let mut d = SVector::<f64, E>::from_element(1.0);
        let mut q = SVector::<f64, E>::zeros();
        for (i, c) in self.config.spec.channels.iter().enumerate() {
            let phi = (-dt_s / c.bias_time_s).exp();
            d[i] = phi;
            q[i] = c.bias_sigma * c.bias_sigma * (1.0 - phi * phi);
        }
        if m.aided {
            // The velocity is measured: no unaided velocity error.
            self.drop_unaided();
        } else {
            for k in 0..3 {
                q[U0 - B0 + k] = self.config.unaided_q.powi(2) * dt_s;
            }
        }
        let a = self.p.fixed_view::<3, 3>(P0, P0).into_owned();
        let b = self.p.fixed_view::<3, E>(P0, B0).into_owned();
        let c = self.p.fixed_view::<E, E>(B0, B0).into_owned();
        let gc = g * c;
        let gbt = g * b.transpose();
        let mut pp = a + (gbt + gbt.transpose()) * dt_s + gc * g.transpose() * (dt_s * dt_s);
        let white = &self.config.spec.channels;
        pp += Self::jxj(&j, |k| white[k].white_psd) * dt_s;
        // Exactly symmetric (the products above are so only to rounding).
        let pp = (pp + pp.transpose()) * 0.5;
        let mut pe = b + gc * dt_s;
        for col in 0..E {
            for r in 0..3 {
                pe[(r, col)] *= d[col];
            }
        }
        let mut ee = c;
        for r in 0..E {
            for col in 0..E {
                ee[(r, col)] *= d[r] * d[col];
            }
            ee[(r, r)] += q[r];
        }
        self.p.fixed_view_mut::<3, 3>(P0, P0).copy_from(&pp);
        self.p.fixed_view_mut::<3, E>(P0, B0).copy_from(&pe);
        self.p
            .fixed_view_mut::<E, 3>(B0, P0)
            .copy_from(&pe.transpose());
        self.p.fixed_view_mut::<E, E>(B0, B0).copy_from(&ee);
    }

    /// Zeroes the rows and columns of the states in `range`.
    fn clear(&mut self, range: std::ops::Range<usize>) {
        for i in range {
            self.p.row_mut(i).fill(0.0);
            self.p.column_mut(i).fill(0.0);
        }
    }

    fn drop_unaided(&mut self) {
        self.clear(U0..STATES);
    }

    /// A GPS fix of σ `std_m` per horizontal axis: the horizontal position
    /// error becomes the fix's, uncorrelated with the sensor errors.
    pub fn reset_horizontal(&mut self, std_m: f64) {
        self.clear(P0..P0 + 2);
        self.p[(P0, P0)] = std_m * std_m;
        self.p[(P0 + 1, P0 + 1)] = std_m * std_m;
    }

    /// A depth sample: the down position error becomes the gauge's σ.
    pub fn reset_down(&mut self) {
        self.clear(P0 + 2..P0 + 3);
        self.p[(P0 + 2, P0 + 2)] = self.config.spec.depth_sigma_m.powi(2);
    }

    /// The predicted horizontal RMS error `√E|δp_h|²`, m.
    pub fn horizontal_rms_m(&self) -> f64 {
        (self.p[(P0, P0)] + self.p[(P0 + 1, P0 + 1)])
            .max(0.0)
            .sqrt()
    }

    /// The horizontal position error covariance (N, E), m².
    pub fn horizontal_covariance(&self) -> [[f64; 2]; 2] {
        [
            [self.p[(P0, P0)], self.p[(P0, P0 + 1)]],
            [self.p[(P0 + 1, P0)], self.p[(P0 + 1, P0 + 1)]],
        ]
    }

    /// The surfacing advisory: the prediction is above the threshold.
    pub fn surfacing_advised(&self) -> bool {
        self.horizontal_rms_m() > self.config.threshold_m
    }

    /// Position standard deviation N, E, D, m.
    pub fn position_std_m(&self) -> [f64; 3] {
        [0, 1, 2].map(|i| self.p[(P0 + i, P0 + i)].max(0.0).sqrt())
    }

    /// Velocity standard deviation N, E, D at motion `m`, m/s: `G P_e Gᵀ`
    /// plus the white noise of one sample, `J diag(σ²) Jᵀ`.
    pub fn velocity_std_m_s(&self, m: &Motion) -> [f64; 3] {
        let (g, j) = self.coupling(m);
        let c = self.p.fixed_view::<E, E>(B0, B0);
        let white = &self.config.spec.channels;
        let v = g * c * g.transpose() + Self::jxj(&j, |k| white[k].white_var);
        [0, 1, 2].map(|i| v[(i, i)].max(0.0).sqrt())
    }

    /// The covariance, row-major (for a snapshot).
    pub fn covariance(&self) -> Covariance {
        let mut out = [[0.0; STATES]; STATES];
        for (r, row) in out.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v = self.p[(r, c)];
            }
        }
        out
    }

    /// Replaces the covariance (a snapshot's): finite, symmetric (exactly,
    /// as [`Self::covariance`] writes it) with a non-negative diagonal, else
    /// refused and the state kept.
    pub fn set_covariance(&mut self, p: &Covariance) -> Result<(), NotCovariance> {
        let ok = (0..STATES).all(|r| {
            p[r][r] >= 0.0 && (0..STATES).all(|c| p[r][c].is_finite() && p[r][c] == p[c][r])
        });
        if !ok {
            return Err(NotCovariance);
        }
        self.p = SMatrix::from_fn(|r, c| p[r][c]);
        Ok(())
    }
}

#[cfg(test)]
mod tests;
