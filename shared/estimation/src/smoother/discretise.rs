//! Paper 004's `φ_i`, `Q_i` and `b_i`: the linearised dynamics over one
//! step, for a forward pass that records [`super::ForwardStep`]s.
//!
//! About the state `E*` at `t_i`, with the inputs held over the step,
//! `Ė = F(E) ≈ A E + c` with `A = ∂F/∂E` and `c = F(E*) − A E*`; then
//! (paper 004, after eq. 9)
//!
//! - `φ_i = φ(t_{i+1}, t_i) = e^{A h}` (`ż = A z`),
//! - `b_i = ∫₀ʰ e^{A s} ds c` (`ḃ = A b + F − A E`, `b(t_i) = 0`),
//! - `Q_i = ∫₀ʰ e^{A s} Q e^{Aᵀ s} ds`,
//!
//! so that `E⁻_{i+1} = φ_i E_i + b_i` and `P⁻_{i+1} = φ_i P_i φ_iᵀ + Q_i`.
//!
//! All three are power series in `A h`: `e^{A s} = Σ (A s)ᵏ/k!`, `b_i = Σ
//! Aᵏ h^{k+1}/(k+1)! c` and, since `d/ds (e^{As} Q e^{Aᵀs}) = L(·)` with
//! `L(X) = A X + X Aᵀ`, `Q_i = Σ h^{m+1}/(m+1)! Lᵐ(Q)` (the series form of
//! Van Loan 1978's block exponential). The series are summed over a step
//! short enough that `‖A‖₁ h ≤ ½` and the whole step is built by doubling
//! (scaling and squaring): over `[0, 2h]`, `φ = φ_h φ_h`, `b = φ_h b_h +
//! b_h`, `Q = φ_h Q_h φ_hᵀ + Q_h`. For LBL's 4-state model `A² = 0` and
//! the series end after their second term, exactly.

use nalgebra::{SMatrix, SVector};

/// `φ_i`, `Q_i`, `b_i` of one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Discretised<const N: usize> {
    /// `φ_i`.
    pub phi: SMatrix<f64, N, N>,
    /// `Q_i`.
    pub q: SMatrix<f64, N, N>,
    /// `b_i`.
    pub b: SVector<f64, N>,
}

/// Dynamics that cannot be discretised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DiscretiseError {
    /// `A`, `Q`, `c` or the interval is NaN or infinite.
    #[error("the linearised dynamics or the interval are not finite")]
    NonFinite,
    /// The interval is negative.
    #[error("the interval is negative")]
    NegativeInterval,
    /// The result overflowed (`‖A‖ h` far beyond any navigation step).
    #[error("the transition over the interval overflows")]
    Overflow,
}

/// Terms of the power series at most (at `‖A h‖₁ ≤ ½` the 20th term is
/// below 2⁻²⁰/20! ≈ 4·10⁻²⁵ of the first).
const MAX_TERMS: usize = 20;

/// Halvings of the interval at most (`‖A‖₁ h` up to 2⁶³).
const MAX_HALVINGS: i32 = 64;

impl<const N: usize> Discretised<N> {
    /// The step of length `h` s of `Ė ≈ A E + c` with process noise of
    /// spectral density `q` (paper 004 eq. 4's `Q`).
    pub fn of(
        a: &SMatrix<f64, N, N>,
        q: &SMatrix<f64, N, N>,
        c: &SVector<f64, N>,
        h: f64,
    ) -> Result<Self, DiscretiseError> {
        let all_finite = a
            .iter()
            .chain(q.iter())
            .chain(c.iter())
            .all(|v| v.is_finite());
        if !all_finite || !h.is_finite() {
            return Err(DiscretiseError::NonFinite);
        }
        if h < 0.0 {
            return Err(DiscretiseError::NegativeInterval);
        }
        let norm = a
            .column_iter()
            .map(|col| col.lp_norm(1))
            .fold(0.0, f64::max)
            * h;
        let halvings = if norm > 0.5 {
            // The smallest s with norm / 2^s ≤ ½.
            ((norm / 0.5).log2().ceil() as i32).clamp(0, MAX_HALVINGS)
        } else {
            0
        };
        let short = h / 2f64.powi(halvings);
        let mut d = Self::series(a, q, c, short);
        for _ in 0..halvings {
            d = Self {
                phi: d.phi * d.phi,
                q: d.phi * d.q * d.phi.transpose() + d.q,
                b: d.phi * d.b + d.b,
            };
        }
        let finite = d
            .phi
            .iter()
            .chain(d.q.iter())
            .chain(d.b.iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(DiscretiseError::Overflow);
        }
        d.q = (d.q + d.q.transpose()) * 0.5;
        Ok(d)
    }

    /// The three series over `h` with `‖A‖₁ h ≤ ½`.
    fn series(a: &SMatrix<f64, N, N>, q: &SMatrix<f64, N, N>, c: &SVector<f64, N>, h: f64) -> Self {
        let ah = a * h;
        let mut phi = SMatrix::<f64, N, N>::identity();
        // (A h)ᵏ / k!
        let mut phi_term = SMatrix::<f64, N, N>::identity();
        // Aᵏ h^{k+1} / (k+1)! c
        let mut b_term = c * h;
        let mut b = b_term;
        // h^{m+1} / (m+1)! Lᵐ(Q)
        let mut q_term = q * h;
        let mut q_sum = q_term;
        for k in 1..MAX_TERMS {
            let kf = k as f64;
            phi_term = ah * phi_term / kf;
            b_term = ah * b_term / (kf + 1.0);
            q_term = (ah * q_term + q_term * ah.transpose()) / (kf + 1.0);
            phi += phi_term;
            b += b_term;
            q_sum += q_term;
            let small = |term: f64, sum: f64| term <= f64::EPSILON * sum;
            if small(phi_term.amax(), phi.amax())
                && small(b_term.amax(), b.amax())
                && small(q_term.amax(), q_sum.amax())
            {
                break;
            }
        }
        Self { phi, q: q_sum, b }
    }
}
