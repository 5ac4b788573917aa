//! `ekf`: a range-only extended Kalman filter on the same inputs as the
//! particle filter, for comparison. Its state is `x = [n, e, c_n, c_e]`:
//! the offset of the vehicle from the dead-reckoned centre
//! ([`super::frame`]; zero after every update, the centre takes it) and
//! the correction of the navigation's velocity, with covariance `P` (4×4).
//!
//! - Prediction over the time since the last message: `x ← F x`, `P ← F P
//!   Fᵀ + Q` with `F = [[I, Δt I], [0, I]]` and `Q` the integrated random
//!   walk of [`super::process`] (the particle filter's motion).
//! - Update: `h(x)` is eqs. 51-53's slant range, `H = [∂h/∂n, ∂h/∂e, 0,
//!   0]` (the unit vector from the buoy scaled by horizontal over slant
//!   range); `S = H P Hᵀ + σ_d²`, `K = P Hᵀ / S`, `x ← x + K (d − h(x))`,
//!   and `P` in Joseph form, `(I − K H) P (I − K H)ᵀ + K σ_d² Kᵀ` (Groves
//!   2013 §3.2), which stays symmetric and positive over many updates.

use nalgebra::{Matrix4, RowVector4, Vector4};

use crate::positioning::Gaussian;
use crate::positioning::frame::RangeFrame;
use crate::positioning::process::Walk;

/// The filter's state about the centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeEkf {
    /// `x`.
    pub x: Vector4<f64>,
    /// `P`.
    pub p: Matrix4<f64>,
}

impl RangeEkf {
    /// A position uniform in the square of half-width `half_width_m`
    /// (eq. 48's set, as a Gaussian: variance `h²/3`) and a velocity
    /// correction of σ `velocity_sigma_m_s`.
    pub fn new(half_width_m: f64, velocity_sigma_m_s: f64) -> Self {
        let v = half_width_m * half_width_m / 3.0;
        let c = velocity_sigma_m_s * velocity_sigma_m_s;
        Self {
            x: Vector4::zeros(),
            p: Matrix4::from_diagonal(&Vector4::new(v, v, c, c)),
        }
    }

    /// The state of a Gaussian.
    pub fn of(g: &Gaussian) -> Self {
        let p = Matrix4::from_fn(|i, j| g.cov[i][j]);
        Self {
            x: Vector4::from(g.mean),
            p: (p + p.transpose()) * 0.5,
        }
    }

    /// The prediction over `dt` s.
    pub fn propagate(&mut self, w: &Walk, dt: f64) {
        if dt <= 0.0 {
            return;
        }
        let mut f = Matrix4::identity();
        f[(0, 2)] = dt;
        f[(1, 3)] = dt;
        let c = w.covariance(dt);
        let mut q = Matrix4::zeros();
        for axis in 0..2 {
            q[(axis, axis)] = c[0][0];
            q[(axis, 2 + axis)] = c[0][1];
            q[(2 + axis, axis)] = c[1][0];
            q[(2 + axis, 2 + axis)] = c[1][1];
        }
        self.x = f * self.x;
        self.p = f * self.p * f.transpose() + q;
    }

    /// One range; the position correction the centre takes (the state's
    /// offset is then zero).
    pub fn update(&mut self, f: &RangeFrame) -> [f64; 2] {
        let obs = *f.obs();
        let g = f.gradient(self.x[0], self.x[1]);
        let h = RowVector4::new(g[0], g[1], 0.0, 0.0);
        let ph = self.p * h.transpose();
        let s = (h * ph)[(0, 0)] + obs.var_m2;
        let k = ph / s;
        let nu = obs.range_m - f.predicted_m(self.x[0], self.x[1]);
        self.x += k * nu;
        let a = Matrix4::identity() - k * h;
        let p = a * self.p * a.transpose() + k * k.transpose() * obs.var_m2;
        self.p = (p + p.transpose()) * 0.5;
        let by = [self.x[0], self.x[1]];
        self.x[0] = 0.0;
        self.x[1] = 0.0;
        by
    }

    /// A position measurement `z` (north, east offsets, m) of variance
    /// `var_m2` per axis (a GPS fix at the surface): the linear update with
    /// `H = [I 0]`; the position correction the centre takes.
    pub fn update_position(&mut self, z: [f64; 2], var_m2: f64) -> [f64; 2] {
        for axis in 0..2 {
            let mut h = RowVector4::zeros();
            h[axis] = 1.0;
            let ph = self.p * h.transpose();
            let s = ph[axis] + var_m2;
            let k = ph / s;
            self.x += k * (z[axis] - self.x[axis]);
            let a = Matrix4::identity() - k * h;
            let p = a * self.p * a.transpose() + k * k.transpose() * var_m2;
            self.p = (p + p.transpose()) * 0.5;
        }
        let by = [self.x[0], self.x[1]];
        self.x[0] = 0.0;
        self.x[1] = 0.0;
        by
    }

    /// The estimate about the centre.
    pub fn estimate(&self) -> Gaussian {
        Gaussian {
            mean: [self.x[0], self.x[1], self.x[2], self.x[3]],
            cov: std::array::from_fn(|i| std::array::from_fn(|j| self.p[(i, j)])),
            effective_particles: 0.0,
        }
    }
}
