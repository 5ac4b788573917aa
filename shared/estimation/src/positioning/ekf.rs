//! `ekf`: a range-only extended Kalman filter on the same inputs as the
//! particle filter, for comparison. Its state is [`super::process`]'s `x`
//! (the vehicle's offset from the dead-reckoned centre, zero after every
//! update since the centre takes it; the velocity correction; the
//! sound-speed, scale and heading errors; the buoy's position and drift),
//! with covariance `P`.
//!
//! - Prediction over the time since the last message: `x ← F x`, `P ← F P
//!   Fᵀ + G Gᵀ` ([`super::process::Step`], the particle filter's motion).
//! - The buoy's broadcast position: the linear update of `(b_n, b_e)`.
//! - A range: `h(x) = (1 + s) ρ`, `ρ` eqs. 51-53's slant range between the
//!   vehicle and the buoy and `s` the sound-speed error, its row `H` from
//!   [`super::frame::range_row`]; `S = H P Hᵀ + σ_d²`, `K = P Hᵀ / S`, `x ←
//!   x + K (d − h(x))`, and `P` in Joseph form, `(I − K H) P (I − K H)ᵀ +
//!   K σ_d² Kᵀ` (Groves 2013 §3.2), which stays symmetric and positive
//!   over many updates.

use std::ops::Range;

use crate::positioning::Gaussian;
use crate::positioning::frame::{RangeFrame, range_row};
use crate::positioning::process::{BE, BN, DIM, E, N, Square, State, Step, Walk};

/// The filter's state about the centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeEkf {
    /// `x`.
    pub x: State,
    /// `P`.
    pub p: Square,
}

impl RangeEkf {
    /// A state of zero mean and independent values of σ `sigma` (a
    /// position uniform in a square of half-width `h` is `h/√3`).
    pub fn new(sigma: &[f64; DIM]) -> Self {
        Self {
            x: State::zeros(),
            p: Square::from_diagonal(&State::from(sigma.map(|s| s * s))),
        }
    }

    /// The values `values` restarted at zero mean with σ `sigma`,
    /// independent of the others (the rest kept).
    pub fn restart(&mut self, values: Range<usize>, sigma: &[f64; DIM]) {
        for i in values {
            self.x[i] = 0.0;
            for j in 0..DIM {
                self.p[(i, j)] = 0.0;
                self.p[(j, i)] = 0.0;
            }
            self.p[(i, i)] = sigma[i] * sigma[i];
        }
    }

    /// The state of a Gaussian.
    pub fn of(g: &Gaussian) -> Self {
        let p = Square::from_fn(|i, j| g.cov[i][j]);
        Self {
            x: State::from(g.mean),
            p: (p + p.transpose()) * 0.5,
        }
    }

    /// The prediction over `step`.
    pub fn propagate(&mut self, w: &Walk, step: &Step) {
        if step.dt_s <= 0.0 {
            return;
        }
        let f = step.transition();
        let g = step.noise_factor(w);
        self.x = f * self.x;
        let p = f * self.p * f.transpose() + g * g.transpose();
        self.p = (p + p.transpose()) * 0.5;
    }

    /// One range; the position correction the centre takes (the state's
    /// offset is then zero).
    pub fn update(&mut self, f: &RangeFrame) -> [f64; 2] {
        let obs = *f.obs();
        let x: [f64; DIM] = self.x.into();
        let (h, predicted) = range_row(f, &x);
        self.linear_update(&State::from(h), obs.range_m - predicted, obs.var_m2);
        self.take_offset()
    }

    /// A position measurement `z` (north, east offsets, m) of variance
    /// `var_m2` per axis (a GPS fix at the surface): the linear update with
    /// `H = [I 0]`; the position correction the centre takes.
    pub fn update_position(&mut self, z: [f64; 2], var_m2: f64) -> [f64; 2] {
        self.update_pair([N, E], z, var_m2);
        self.take_offset()
    }

    /// The buoy's broadcast position `z` (north, east of its reference, m)
    /// of variance `var_m2` per axis.
    pub fn update_buoy(&mut self, z: [f64; 2], var_m2: f64) {
        self.update_pair([BN, BE], z, var_m2);
    }

    fn update_pair(&mut self, at: [usize; 2], z: [f64; 2], var_m2: f64) {
        for (axis, z) in at.into_iter().zip(z) {
            let mut h = State::zeros();
            h[axis] = 1.0;
            self.linear_update(&h, z - self.x[axis], var_m2);
        }
    }

    /// A scalar update with the row `h`, innovation `nu` and variance `r`.
    fn linear_update(&mut self, h: &State, nu: f64, r: f64) {
        let ph = self.p * h;
        let s = h.dot(&ph) + r;
        let k = ph / s;
        self.x += k * nu;
        let a = Square::identity() - k * h.transpose();
        let p = a * self.p * a.transpose() + k * k.transpose() * r;
        self.p = (p + p.transpose()) * 0.5;
    }

    fn take_offset(&mut self) -> [f64; 2] {
        let by = [self.x[N], self.x[E]];
        self.x[N] = 0.0;
        self.x[E] = 0.0;
        by
    }

    /// The estimate about the centre.
    pub fn estimate(&self) -> Gaussian {
        Gaussian {
            mean: std::array::from_fn(|i| self.x[i]),
            cov: std::array::from_fn(|i| std::array::from_fn(|j| self.p[(i, j)])),
            effective_particles: 0.0,
        }
    }
}
