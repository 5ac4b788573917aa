//! The gated Kalman measurement update of the error state (Groves 2013
//! ch. 3: `K = P Hᵀ S⁻¹`, `δx̂ = K ν`, and the covariance in the
//! symmetric form `P⁺ = P − K S Kᵀ`, symmetrised; the Joseph form costs
//! three 18×18 products per update, this one an outer product), with the
//! normalised-innovation gate of Groves ch. 17 (innovation-based fault
//! detection:
//! `νᵀ S⁻¹ ν`, `S = H P Hᵀ + R`, against a χ² quantile).

use nalgebra::{SMatrix, SVector};

use super::model::{Cov, ErrorState, N};

/// What the gate made of a measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Gated {
    /// Used: the error-state estimate `δx̂ = K ν` (to feed back into the
    /// navigation state) and the normalised innovation.
    Used(ErrorState, f64),
    /// Refused by the gate, with its normalised innovation.
    Rejected(f64),
    /// `S` is not positive definite (not used).
    Singular,
}

/// The update of `p` by the residual `nu = z − ẑ` of a measurement with
/// Jacobian `h` and noise covariance `r`, if `νᵀ S⁻¹ ν ≤ gate` (no gate:
/// `None`). `p` is changed only when the measurement is used.
pub fn update<const M: usize>(
    p: &mut Cov,
    nu: &SVector<f64, M>,
    h: &SMatrix<f64, M, N>,
    r: &SMatrix<f64, M, M>,
    gate: Option<f64>,
) -> Gated {
    let pht = *p * h.transpose();
    let s = h * pht + r;
    let Some(chol) = s.cholesky() else {
        return Gated::Singular;
    };
    let s_inv_nu = chol.solve(nu);
    let nis = nu.dot(&s_inv_nu);
    if !nis.is_finite() {
        return Gated::Singular;
    }
    if gate.is_some_and(|g| nis > g) {
        return Gated::Rejected(nis);
    }
    // K = P Hᵀ S⁻¹, from Kᵀ = S⁻¹ H P.
    let k: SMatrix<f64, N, M> = chol.solve(&pht.transpose()).transpose();
    let dx = k * nu;
    let next = *p - k * pht.transpose();
    *p = 0.5 * (next + next.transpose());
    Gated::Used(dx, nis)
}
