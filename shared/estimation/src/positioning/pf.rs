//! `pf`: paper 000 §III-B-2's buoy time-of-flight particle filter
//! (eqs. 48-58), on offsets from the dead-reckoned centre
//! ([`super::frame`]).
//!
//! - Initialisation (eqs. 48-49): `N` particles uniform in a square around
//!   the last known position (a GPS fix before the dive), weights `1/N`.
//! - Prediction (eq. 50): the centre moves with the navigation's velocity,
//!   and the particles with it. Eq. 50 has no noise and trusts that
//!   velocity; a DVL-aided INS's velocity errs by a bias over minutes (its
//!   heading error times its speed), which a filter of the position alone
//!   follows only with a lag of the drift per message over its gain (2.6 m
//!   on the survey, seed 7, with a 0.007 m/s bias). So each particle also
//!   carries a correction `c_j` of the navigation's north and east
//!   velocity (our addition), a random walk, and its position a random
//!   walk of its own (the velocity's white error): the state
//!   `[n, e, c_n, c_e]` is moved once per message over the time since the
//!   last, with the exact discretisation of the integrated random walk
//!   ([`super::process`]), which costs nothing per navigation sample.
//! - Update (eqs. 51-54): each particle's slant range to the buoy,
//!   `w_j ← w_j N(d − d_j; 0, σ_d²)`, normalised (in logarithms, so that an
//!   unlikely range underflows nothing).
//! - Resampling (eqs. 46, 55): when `N_eff = 1/Σw²` falls below `N_th`,
//!   particle `j` is reproduced `⌊N w_j⌋` times (55, the text's `N w_j`
//!   rounded down: the prose says the reproduced set "will contain less
//!   than N particles") and the set completed with particles uniform in a
//!   square around the particle of largest weight; all weights `1/N`.
//! - Estimation (eqs. 56-58): the weighted mean (56) without resampling;
//!   after it, the mean of the `M` reproduced particles only (57-58: the
//!   completing ones have not met a range yet). With the equal weights of
//!   the reproduced set, 57's sum is `M/N` and 58 the plain mean of the
//!   `M`. The published covariance is the same set's.

use nalgebra::{Matrix4, Vector4};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::positioning::frame::RangeFrame;
use crate::positioning::process::Walk;
use crate::positioning::{Gaussian, PositioningPfParams};

/// The particle set.
#[derive(Debug, Clone)]
pub struct BuoyPf {
    /// Per particle: north, east offsets (m), north, east velocity
    /// corrections (m/s).
    state: Vec<[f64; 4]>,
    weight: Vec<f64>,
    /// The first `reproduced` particles make the estimate (eqs. 57-58);
    /// all of them when the last update did not resample.
    reproduced: usize,
    neff: f64,
    threshold: f64,
    fill_half_width_m: f64,
    fill_velocity_m_s: f64,
    seed: u64,
    rng: ChaCha8Rng,
    /// Per-particle log-likelihood, kept to save an allocation per update.
    scratch: Vec<f64>,
}

impl BuoyPf {
    /// A set of the parameters' size, all at the centre (call
    /// [`Self::reset`]).
    pub fn new(p: &PositioningPfParams) -> Self {
        let n = p.particles;
        Self {
            state: vec![[0.0; 4]; n],
            weight: vec![1.0 / n as f64; n],
            reproduced: n,
            neff: n as f64,
            threshold: p.resample_threshold * n as f64,
            fill_half_width_m: p.fill_half_width_m,
            fill_velocity_m_s: p.fill_velocity_m_s,
            seed: p.seed,
            rng: ChaCha8Rng::seed_from_u64(p.seed),
            scratch: vec![0.0; n],
        }
    }

    fn normal(&mut self) -> f64 {
        StandardNormal.sample(&mut self.rng)
    }

    /// Eqs. 48-49: positions uniform in the square of half-width
    /// `half_width_m` around the centre, velocity corrections normal of σ
    /// `velocity_sigma_m_s`, weights `1/N`.
    pub fn reset(&mut self, half_width_m: f64, velocity_sigma_m_s: f64) {
        let n = self.state.len();
        for j in 0..n {
            let a = self.rng.random_range(-half_width_m..=half_width_m);
            let b = self.rng.random_range(-half_width_m..=half_width_m);
            let (c, d) = (self.normal(), self.normal());
            self.state[j] = [a, b, velocity_sigma_m_s * c, velocity_sigma_m_s * d];
        }
        self.weight.fill(1.0 / n as f64);
        self.reproduced = n;
        self.neff = n as f64;
    }

    /// Redraws the set from a Gaussian about the centre (a warm restart:
    /// the particles do not fit a snapshot), the random numbers reseeded
    /// from the seed and `salt` (the snapshot's stamp) so that a restart
    /// is deterministic.
    pub fn redraw(&mut self, g: &Gaussian, salt: u64) {
        self.rng = ChaCha8Rng::seed_from_u64(self.seed ^ salt.rotate_left(17));
        let p = Matrix4::from_fn(|i, j| g.cov[i][j]);
        // A covariance that is only semi-definite (a collapsed axis) gets
        // a micrometre of spread.
        let l = p
            .cholesky()
            .or_else(|| (p + Matrix4::identity() * 1e-12).cholesky())
            .map_or(Matrix4::zeros(), |c| c.l());
        let m = Vector4::from(g.mean);
        let n = self.state.len();
        for j in 0..n {
            let u = Vector4::from_fn(|_, _| self.normal());
            let x = m + l * u;
            self.state[j] = [x[0], x[1], x[2], x[3]];
        }
        self.weight.fill(1.0 / n as f64);
        self.reproduced = n;
        self.neff = g.effective_particles.clamp(1.0, n as f64);
    }

    /// Moves every particle over `dt` s of the random walk `w`.
    pub fn propagate(&mut self, w: &Walk, dt: f64) {
        if dt <= 0.0 {
            return;
        }
        let k = w.factors(dt);
        for j in 0..self.state.len() {
            let u: [f64; 6] = std::array::from_fn(|_| StandardNormal.sample(&mut self.rng));
            let s = &mut self.state[j];
            for axis in 0..2 {
                let (u1, u2, u3) = (u[3 * axis], u[3 * axis + 1], u[3 * axis + 2]);
                let dc = k.velocity * u1;
                s[axis] += s[2 + axis] * dt + k.coupling * u1 + k.integrated * u2 + k.position * u3;
                s[2 + axis] += dc;
            }
        }
    }

    /// Eqs. 51-55 for one range.
    pub fn update(&mut self, f: &RangeFrame) {
        let obs = *f.obs();
        let inv = -0.5 / obs.var_m2;
        self.weigh(|s| {
            let r = obs.range_m - f.predicted_m(s[0], s[1]);
            inv * r * r
        });
    }

    /// A position measurement `z` (north, east offsets, m) of variance
    /// `var_m2` per axis: a GPS fix at the surface, weighed as a range is
    /// (a Gaussian likelihood, our addition: the paper restarts at each).
    pub fn update_position(&mut self, z: [f64; 2], var_m2: f64) {
        let inv = -0.5 / var_m2;
        self.weigh(|s| inv * ((z[0] - s[0]).powi(2) + (z[1] - s[1]).powi(2)));
    }

    /// `w_j ← w_j exp(log_likelihood(x_j))`, normalised in logarithms (an
    /// unlikely measurement underflows nothing), then eq. 46 and, below
    /// the threshold, eq. 55.
    fn weigh(&mut self, log_likelihood: impl Fn(&[f64; 4]) -> f64) {
        let n = self.state.len();
        let mut best = f64::NEG_INFINITY;
        for j in 0..n {
            let l = self.weight[j].ln() + log_likelihood(&self.state[j]);
            self.scratch[j] = l;
            best = best.max(l);
        }
        let mut sum = 0.0;
        for j in 0..n {
            let w = (self.scratch[j] - best).exp();
            self.weight[j] = w;
            sum += w;
        }
        let mut sq = 0.0;
        for w in self.weight.iter_mut() {
            *w /= sum;
            sq += *w * *w;
        }
        // Eq. 46.
        self.neff = 1.0 / sq;
        self.reproduced = n;
        if self.neff < self.threshold {
            self.resample();
        }
    }

    /// Eq. 55 and the completion around the best particle.
    fn resample(&mut self) {
        let n = self.state.len();
        let nf = n as f64;
        let best = (0..n)
            .max_by(|&a, &b| self.weight[a].total_cmp(&self.weight[b]))
            .unwrap_or(0);
        let b = self.state[best];
        let mut next = Vec::with_capacity(n);
        for j in 0..n {
            let copies = (nf * self.weight[j]).floor() as usize;
            for _ in 0..copies.min(n - next.len()) {
                next.push(self.state[j]);
            }
        }
        // The largest weight is at least 1/N: one copy at least.
        if next.is_empty() {
            next.push(b);
        }
        let m = next.len();
        let (h, hv) = (self.fill_half_width_m, self.fill_velocity_m_s);
        while next.len() < n {
            next.push([
                b[0] + self.rng.random_range(-h..=h),
                b[1] + self.rng.random_range(-h..=h),
                b[2] + self.rng.random_range(-hv..=hv),
                b[3] + self.rng.random_range(-hv..=hv),
            ]);
        }
        self.state = next;
        self.weight.fill(1.0 / nf);
        self.reproduced = m;
    }

    /// Eqs. 56-58: the estimate and its covariance, about the centre.
    pub fn estimate(&self) -> Gaussian {
        let k = self.reproduced.clamp(1, self.state.len());
        let w = &self.weight[..k];
        let total: f64 = w.iter().sum();
        let mut mean = [0.0; 4];
        for (s, wj) in self.state[..k].iter().zip(w) {
            for i in 0..4 {
                mean[i] += wj * s[i];
            }
        }
        mean = mean.map(|m| m / total);
        let mut cov = [[0.0; 4]; 4];
        for (s, wj) in self.state[..k].iter().zip(w) {
            let d: [f64; 4] = std::array::from_fn(|i| s[i] - mean[i]);
            for i in 0..4 {
                for j in 0..4 {
                    cov[i][j] += wj * d[i] * d[j];
                }
            }
        }
        Gaussian {
            mean,
            cov: cov.map(|r| r.map(|v| v / total)),
            effective_particles: self.neff,
        }
    }

    /// Moves every particle by `-by` (the centre moved by `by`).
    pub fn recentre(&mut self, by: [f64; 2]) {
        for s in self.state.iter_mut() {
            s[0] -= by[0];
            s[1] -= by[1];
        }
    }
}
