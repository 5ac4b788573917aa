//! A linear(ised) Kalman filter's forward pass that records its
//! [`ForwardStep`]s: predictions with paper 004's `φ_i`, `b_i`, `Q_i`
//! ([`Discretised`]) and linear measurement updates. The smoother's tests,
//! its golden fixture and its benchmark run it; a nonlinear filter records
//! its own steps the same way (prior after the prediction, posterior after
//! the step's corrections).

use nalgebra::{SMatrix, SVector};

use crate::smoother::discretise::Discretised;
use crate::smoother::step::ForwardStep;

/// A measurement the filter refused, its state unchanged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum LinearUpdateError {
    /// `z`, `H` or `R` is NaN or infinite.
    #[error("the measurement, its matrix or its covariance is not finite")]
    NonFinite,
    /// The innovation covariance `S = H P Hᵀ + R` is not positive definite.
    #[error("the innovation covariance is not positive definite")]
    InnovationNotPositive,
}

/// The forward pass: the state `x`, its covariance `P`, and every step so
/// far (the last one is the current instant).
#[derive(Debug, Clone)]
pub struct LinearForward<const N: usize> {
    steps: Vec<ForwardStep<N>>,
}

impl<const N: usize> LinearForward<N> {
    /// Starts at `stamp_ns` from `x0`, `P0` (the first step's prior and
    /// posterior).
    pub fn new(stamp_ns: u64, x0: SVector<f64, N>, p0: SMatrix<f64, N, N>) -> Self {
        Self::with_capacity(stamp_ns, x0, p0, 1)
    }

    /// [`Self::new`] with room for `steps` steps.
    pub fn with_capacity(
        stamp_ns: u64,
        x0: SVector<f64, N>,
        p0: SMatrix<f64, N, N>,
        steps: usize,
    ) -> Self {
        let mut v = Vec::with_capacity(steps.max(1));
        v.push(ForwardStep {
            stamp_ns,
            phi: SMatrix::identity(),
            x_prior: x0,
            p_prior: p0,
            x_post: x0,
            p_post: p0,
        });
        Self { steps: v }
    }

    /// The current step.
    pub fn current(&self) -> &ForwardStep<N> {
        // `new` pushes one step and nothing removes any.
        &self.steps[self.steps.len() - 1]
    }

    /// Every step so far.
    pub fn steps(&self) -> &[ForwardStep<N>] {
        &self.steps
    }

    /// The steps, the filter consumed.
    pub fn into_steps(self) -> Vec<ForwardStep<N>> {
        self.steps
    }

    /// A new step at `stamp_ns`: `E⁻ = φ E + b`, `P⁻ = φ P φᵀ + Q`.
    pub fn predict(&mut self, stamp_ns: u64, d: &Discretised<N>) {
        let last = self.current();
        let x = d.phi * last.x_post + d.b;
        let p = d.phi * last.p_post * d.phi.transpose() + d.q;
        let p = (p + p.transpose()) * 0.5;
        self.steps.push(ForwardStep {
            stamp_ns,
            phi: d.phi,
            x_prior: x,
            p_prior: p,
            x_post: x,
            p_post: p,
        });
    }

    /// Replaces the current step's posterior (a reset that discards the
    /// prior, such as a GPS fix at the surface; the smoother restarts there).
    pub fn reset(&mut self, x: SVector<f64, N>, p: SMatrix<f64, N, N>) {
        let n = self.steps.len() - 1;
        self.steps[n].x_post = x;
        self.steps[n].p_post = p;
    }

    /// Corrects the current step with `z = H x + v`, `v ~ N(0, R)`:
    /// `K = P Hᵀ S⁻¹`, `x += K (z − H x)`, `P` in Joseph form `(I − K H) P
    /// (I − K H)ᵀ + K R Kᵀ`.
    pub fn update<const M: usize>(
        &mut self,
        z: &SVector<f64, M>,
        h: &SMatrix<f64, M, N>,
        r: &SMatrix<f64, M, M>,
    ) -> Result<(), LinearUpdateError> {
        let finite = z
            .iter()
            .chain(h.iter())
            .chain(r.iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(LinearUpdateError::NonFinite);
        }
        let n = self.steps.len() - 1;
        let step = &mut self.steps[n];
        let ph = step.p_post * h.transpose();
        let s = h * ph + r;
        let Some(chol) = s.cholesky() else {
            return Err(LinearUpdateError::InnovationNotPositive);
        };
        let k = chol.solve(&ph.transpose()).transpose();
        let i_kh = SMatrix::<f64, N, N>::identity() - k * h;
        step.x_post += k * (z - h * step.x_post);
        let p = i_kh * step.p_post * i_kh.transpose() + k * r * k.transpose();
        step.p_post = (p + p.transpose()) * 0.5;
        Ok(())
    }
}
