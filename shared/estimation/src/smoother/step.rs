//! What the forward pass hands the smoother, and what the smoother returns.

use nalgebra::{SMatrix, SVector};

/// One step of a forward (Kalman) pass at the instant `t_i` (paper 004
/// §IV: the instants at which the dead-reckoning data were collected).
///
/// The prior is the forward pass's prediction to this instant from the
/// previous step's posterior (paper 004's `E⁻_i`, `P⁻_i`: eqs. 3-4
/// integrated over `[t_{i-1}, t_i]`, so it already holds `b_{i-1}` and
/// `Q_{i-1}`); the posterior is after this instant's range corrections, if
/// any (eqs. 5-6; without one it equals the prior). The first step's prior
/// is the filter's initial state and `phi` is ignored there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForwardStep<const N: usize> {
    /// The instant `t_i`, ns in the run's clock.
    pub stamp_ns: u64,
    /// `φ_{i-1} = φ(t_i, t_{i-1})`: the transition matrix of the linearised
    /// dynamics (`ż = ∂F/∂E z`) from the previous step's posterior to this
    /// step's prior (paper 004, after eq. 9).
    pub phi: SMatrix<f64, N, N>,
    /// `E⁻_i = φ_{i-1} E_{i-1} + b_{i-1}` (to first order; the forward pass
    /// may integrate the nonlinear dynamics instead).
    pub x_prior: SVector<f64, N>,
    /// `P⁻_i = φ_{i-1} P_{i-1} φ_{i-1}ᵀ + Q_{i-1}`.
    pub p_prior: SMatrix<f64, N, N>,
    /// `E_i`: the filtered state.
    pub x_post: SVector<f64, N>,
    /// `P_i`: the filtered covariance.
    pub p_post: SMatrix<f64, N, N>,
}

/// The smoothed estimate at one step: paper 004's `E_{i|N}` and `P_{i|N}`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothedStep<const N: usize> {
    /// The instant `t_i`, ns (the forward step's).
    pub stamp_ns: u64,
    /// `E_{i|N}`.
    pub x: SVector<f64, N>,
    /// `P_{i|N}`.
    pub p: SMatrix<f64, N, N>,
}
