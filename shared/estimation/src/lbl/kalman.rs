//! The filter's state and covariance and its two operations: the prediction
//! over one step (paper 004 eqs. 3-4, discretised in [`crate::lbl::model`])
//! and a scalar measurement update (paper 003 §V-C, eqs. 5-6 of paper 004),
//! in Joseph form so that `P` stays symmetric and positive semi-definite.

use nalgebra::{SMatrix, SVector};

use crate::lbl::model::Discrete;

/// `E` and `P` of `N` states (`[x, y, w_x, w_y]`, and `k` with 5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kf<const N: usize> {
    /// `E`.
    pub x: SVector<f64, N>,
    /// `P`.
    pub p: SMatrix<f64, N, N>,
}

impl<const N: usize> Kf<N> {
    /// `E⁻ = φ E + b`, `P⁻ = φ P φᵀ + Q_i` (paper 004 eqs. 3-4 over one
    /// step, exact: [`crate::lbl::model`]).
    pub fn predict(&mut self, d: &Discrete<N>) {
        self.x = d.phi * self.x + d.b;
        self.p = d.phi * self.p * d.phi.transpose() + d.q;
        self.symmetrise();
    }

    /// `S = H P Hᵀ + q` (paper 003 §V-C).
    pub fn innovation_variance(&self, h: &SMatrix<f64, 1, N>, q: f64) -> f64 {
        (h * self.p * h.transpose())[(0, 0)] + q
    }

    /// The update with innovation `ν = r − r*` (paper 003 §V-C: `K = P⁻ Hᵀ
    /// S⁻¹`, `E⁺ = E⁻ + K ν`; `P⁺ = P⁻ − K H P⁻` written in Joseph form,
    /// `P⁺ = (I − K H) P⁻ (I − K H)ᵀ + K q Kᵀ`, equal in exact arithmetic and
    /// safe in floating point). False, and nothing changed, when `S` is not
    /// positive and finite.
    pub fn update(&mut self, h: &SMatrix<f64, 1, N>, nu: f64, q: f64) -> bool {
        let s = self.innovation_variance(h, q);
        if !(s > 0.0 && s.is_finite() && nu.is_finite()) {
            return false;
        }
        let k = self.p * h.transpose() / s;
        self.x += k * nu;
        let ikh = SMatrix::<f64, N, N>::identity() - k * h;
        self.p = ikh * self.p * ikh.transpose() + k * k.transpose() * q;
        self.symmetrise();
        true
    }

    /// Sets the position to `(x, y)` with variance `var` per axis and no
    /// correlation with the other states (a GPS reset at the surface).
    pub fn reset_position(&mut self, xy: [f64; 2], var: f64) {
        self.x[0] = xy[0];
        self.x[1] = xy[1];
        for i in 0..2 {
            for j in 0..N {
                self.p[(i, j)] = 0.0;
                self.p[(j, i)] = 0.0;
            }
            self.p[(i, i)] = var;
        }
    }

    /// Drops the correlation of the position with the other states (their
    /// variances kept).
    pub fn decorrelate_position(&mut self) {
        for i in 0..2 {
            for j in 2..N {
                self.p[(i, j)] = 0.0;
                self.p[(j, i)] = 0.0;
            }
        }
    }

    /// `P_xy`.
    pub fn p_xy(&self) -> [[f64; 2]; 2] {
        [
            [self.p[(0, 0)], self.p[(0, 1)]],
            [self.p[(1, 0)], self.p[(1, 1)]],
        ]
    }

    fn symmetrise(&mut self) {
        self.p = (self.p + self.p.transpose()) * 0.5;
    }

    /// Whether every number is finite, `P` symmetric (to rounding) with a
    /// non-negative diagonal and correlations within ±1.
    pub fn is_valid(&self) -> bool {
        let finite = self.x.iter().chain(self.p.iter()).all(|v| v.is_finite());
        finite
            && (0..N).all(|i| {
                self.p[(i, i)] >= 0.0
                    && (0..N).all(|j| {
                        let (a, b) = (self.p[(i, j)], self.p[(j, i)]);
                        (a - b).abs() <= 1e-9 * (1.0 + a.abs())
                            && a * a <= self.p[(i, i)] * self.p[(j, j)] * (1.0 + 1e-9) + 1e-300
                    })
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Joseph form equals the textbook `P⁻ − K H P⁻` and keeps `P`
    /// symmetric.
    #[test]
    fn the_joseph_update_is_the_kalman_update() {
        let mut kf = Kf::<4> {
            x: SVector::from([10.0, 20.0, 0.1, 0.2]),
            p: SMatrix::from_fn(|i, j| if i == j { 4.0 + i as f64 } else { 0.5 }),
        };
        let h = SMatrix::<f64, 1, 4>::from_row_slice(&[0.6, 0.8, -0.3, -0.4]);
        let q = 0.16;
        let s = kf.innovation_variance(&h, q);
        let k = kf.p * h.transpose() / s;
        let plain = kf.p - k * h * kf.p;
        let x = kf.x + k * 1.5;
        assert!(kf.update(&h, 1.5, q));
        assert!((kf.p - plain).norm() < 1e-12);
        assert!((kf.x - x).norm() < 1e-12);
        assert_eq!(kf.p, kf.p.transpose());
        assert!(kf.is_valid());
        assert!(!kf.update(&h, f64::NAN, q));
        assert!(!kf.update(&h, 1.0, f64::NEG_INFINITY));
    }
}
