//! `pf`: paper 000 §III-B-2's buoy time-of-flight particle filter
//! (eqs. 48-58), on offsets from the dead-reckoned centre
//! ([`super::frame`]).
//!
//! - Initialisation (eqs. 48-49): `N` particles uniform in a square around
//!   the last known position (a GPS fix before the dive), weights `1/N`.
//! - Prediction (eq. 50): the centre moves with the navigation's velocity,
//!   and the particles with it. Eq. 50 has no noise and trusts that
//!   velocity; a DVL-aided INS's velocity errs by a bias over minutes,
//!   which a filter of the position alone follows only with a lag of the
//!   drift per message over its gain (2.6 m on the survey, seed 7, with a
//!   0.007 m/s bias). So each particle also carries the errors of
//!   [`super::process`] (our addition): a correction of the navigation's
//!   velocity, its scale and heading errors and the sound speed's; the
//!   state is moved once per message over the time since the last (`x ←
//!   F x + G u`), which costs nothing per navigation sample.
//! - Update (eqs. 51-54): each particle's slant range to the buoy, times
//!   its `1 + s` (the sound-speed error), `w_j ← w_j N(d − (1 + s_j) d_j;
//!   0, σ_d²)`, normalised (in logarithms, so that an unlikely range
//!   underflows nothing).
//! - Resampling (eqs. 46, 55): when `N_eff = 1/Σw²` falls below `N_th`,
//!   particle `j` is reproduced `⌊N w_j⌋` times (55, the text's `N w_j`
//!   rounded down: the prose says the reproduced set "will contain less
//!   than N particles") and the set completed with particles uniform in a
//!   box around the particle of largest weight: `L u`, `L` the Cholesky
//!   factor of the reproduced set's covariance and `u` uniform in
//!   `±√3 fill_spread` per value (`fill_spread` times the set's spread, in
//!   its own axes; the paper gives no width or shape); all weights `1/N`.
//! - Estimation (eqs. 56-58): the weighted mean (56) without resampling;
//!   after it, the mean of the `M` reproduced particles only (57-58: the
//!   completing ones have not met a range yet). With the equal weights of
//!   the reproduced set, 57's sum is `M/N` and 58 the plain mean of the
//!   `M`. The published covariance is the same set's.

use nalgebra::{Cholesky, SVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use std::ops::Range;

use crate::positioning::frame::RangeFrame;
use crate::positioning::process::{BE, BN, DIM, DRAWS, E, N, SOUND, Square, State, Step, Walk};
use crate::positioning::{Gaussian, PositioningPfParams};

/// A particle: [`super::process`]'s state.
type Particle = [f64; DIM];

/// The particle set.
#[derive(Debug, Clone)]
pub struct BuoyPf {
    state: Vec<Particle>,
    weight: Vec<f64>,
    /// The first `reproduced` particles make the estimate (eqs. 57-58);
    /// all of them when the last update did not resample.
    reproduced: usize,
    neff: f64,
    threshold: f64,
    fill_spread: f64,
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
            state: vec![[0.0; DIM]; n],
            weight: vec![1.0 / n as f64; n],
            reproduced: n,
            neff: n as f64,
            threshold: p.resample_threshold * n as f64,
            fill_spread: p.fill_spread,
            seed: p.seed,
            rng: ChaCha8Rng::seed_from_u64(p.seed),
            scratch: vec![0.0; n],
        }
    }

    fn normal(&mut self) -> f64 {
        StandardNormal.sample(&mut self.rng)
    }

    /// Eqs. 48-49 for the values `values`: the vehicle's position uniform
    /// in the square of half-width `√3 σ` around the centre, the other
    /// values normal of their σ (`sigma`,
    /// [`crate::positioning::RangeModel::prior_sigma`]) about zero; the
    /// rest of each particle kept; weights `1/N` when the whole state is
    /// drawn (a restart of a part keeps the weights, which say nothing of
    /// the part).
    pub fn reset(&mut self, values: Range<usize>, sigma: &[f64; DIM]) {
        let n = self.state.len();
        let whole = values == (0..DIM);
        for j in 0..n {
            for i in values.clone() {
                let s = sigma[i];
                self.state[j][i] = if i == N || i == E {
                    let h = s * 3f64.sqrt();
                    if h > 0.0 {
                        self.rng.random_range(-h..=h)
                    } else {
                        0.0
                    }
                } else {
                    s * self.normal()
                };
            }
        }
        if whole {
            self.weight.fill(1.0 / n as f64);
            self.reproduced = n;
            self.neff = n as f64;
        }
    }

    /// Redraws the set from a Gaussian about the centre (a warm restart:
    /// the particles do not fit a snapshot), the random numbers reseeded
    /// from the seed and `salt` (the snapshot's stamp) so that a restart
    /// is deterministic.
    pub fn redraw(&mut self, g: &Gaussian, salt: u64) {
        self.rng = ChaCha8Rng::seed_from_u64(self.seed ^ salt.rotate_left(17));
        let p = Square::from_fn(|i, j| g.cov[i][j]);
        // A covariance that is only semi-definite (a value not estimated,
        // a collapsed axis) gets a micrometre of spread.
        let l = Cholesky::new(p)
            .or_else(|| Cholesky::new(p + Square::identity() * 1e-12))
            .map_or(Square::zeros(), |c| c.l());
        let m = State::from(g.mean);
        let n = self.state.len();
        for j in 0..n {
            let u = State::from_fn(|_, _| self.normal());
            let x = m + l * u;
            self.state[j] = std::array::from_fn(|i| x[i]);
        }
        self.weight.fill(1.0 / n as f64);
        self.reproduced = n;
        self.neff = g.effective_particles.clamp(1.0, n as f64);
    }

    /// Moves every particle over `step` (`x ← F x + G u`,
    /// [`super::process`]).
    pub fn propagate(&mut self, w: &Walk, step: &Step) {
        if step.dt_s <= 0.0 {
            return;
        }
        let g = step.noise_factor(w);
        for j in 0..self.state.len() {
            let u = SVector::<f64, DRAWS>::from_fn(|_, _| StandardNormal.sample(&mut self.rng));
            let gu = g * u;
            let s = &mut self.state[j];
            step.apply(s);
            for (x, d) in s.iter_mut().zip(gu.iter()) {
                *x += d;
            }
        }
    }

    /// Eqs. 51-55 for one range.
    pub fn update(&mut self, f: &RangeFrame) {
        let obs = *f.obs();
        let inv = -0.5 / obs.var_m2;
        self.weigh(|s| {
            let r = obs.range_m - (1.0 + s[SOUND]) * f.predicted_m(s[N], s[E], [s[BN], s[BE]]);
            inv * r * r
        });
    }

    /// The buoy's broadcast position `z` (north, east of its reference, m)
    /// of variance `var_m2` per axis, weighed as a range is.
    pub fn update_buoy(&mut self, z: [f64; 2], var_m2: f64) {
        let inv = -0.5 / var_m2;
        self.weigh(|s| inv * ((z[0] - s[BN]).powi(2) + (z[1] - s[BE]).powi(2)));
    }

    /// A position measurement `z` (north, east offsets, m) of variance
    /// `var_m2` per axis: a GPS fix at the surface, weighed as a range is
    /// (a Gaussian likelihood, our addition: the paper restarts at each).
    pub fn update_position(&mut self, z: [f64; 2], var_m2: f64) {
        let inv = -0.5 / var_m2;
        self.weigh(|s| inv * ((z[0] - s[N]).powi(2) + (z[1] - s[E]).powi(2)));
    }

    /// `w_j ← w_j exp(log_likelihood(x_j))`, normalised in logarithms (an
    /// unlikely measurement underflows nothing), then eq. 46 and, below
    /// the threshold, eq. 55.
    fn weigh(&mut self, log_likelihood: impl Fn(&Particle) -> f64) {
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
        // The reproduced set's spread in the position (equal weights).
        let mean = |i: usize| next.iter().map(|x| x[i]).sum::<f64>() / m as f64;
        let (mn, me) = (mean(N), mean(E));
        let (mut snn, mut sne, mut see) = (0.0, 0.0, 0.0);
        for x in &next {
            let (dn, de) = (x[N] - mn, x[E] - me);
            snn += dn * dn;
            sne += dn * de;
            see += de * de;
        }
        let (snn, sne, see) = (snn / m as f64, sne / m as f64, see / m as f64);
        // Its Cholesky factor [[l11, 0], [l21, l22]].
        let l11 = snn.max(0.0).sqrt();
        let l21 = if l11 > 0.0 { sne / l11 } else { 0.0 };
        let l22 = (see - l21 * l21).max(0.0).sqrt();
        // The completion: the position uniform in a box of `fill_spread`
        // σ of the reproduced set (half-width `√3 fill_spread` in its own
        // axes) around the best particle; the other values (velocity
        // correction, sound speed, buoy, ...) those of a reproduced
        // particle drawn at random, so that the completion spreads the
        // position as the paper's does and leaves the distribution of the
        // slowly varying values as the ranges made it (a spread added to
        // them at each resampling would be a random walk far beyond their
        // model's). The width and the shape are our choice: the paper,
        // whose state is the position alone, gives neither.
        let hw = self.fill_spread * 3f64.sqrt();
        while next.len() < n {
            let (u1, u2) = (
                self.rng.random_range(-hw..=hw),
                self.rng.random_range(-hw..=hw),
            );
            let mut x = next[self.rng.random_range(0..m)];
            x[N] = b[N] + l11 * u1;
            x[E] = b[E] + l21 * u1 + l22 * u2;
            next.push(x);
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
        let mut mean = [0.0; DIM];
        for (s, wj) in self.state[..k].iter().zip(w) {
            for i in 0..DIM {
                mean[i] += wj * s[i];
            }
        }
        mean = mean.map(|m| m / total);
        let mut cov = [[0.0; DIM]; DIM];
        for (s, wj) in self.state[..k].iter().zip(w) {
            let d: Particle = std::array::from_fn(|i| s[i] - mean[i]);
            for i in 0..DIM {
                for j in 0..DIM {
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

    /// Moves every particle's buoy by `-by` (its reference moved by `by`).
    pub fn recentre_buoy(&mut self, by: [f64; 2]) {
        for s in self.state.iter_mut() {
            s[BN] -= by[0];
            s[BE] -= by[1];
        }
    }

    /// Moves every particle by `-by` (the centre moved by `by`).
    pub fn recentre(&mut self, by: [f64; 2]) {
        for s in self.state.iter_mut() {
            s[N] -= by[0];
            s[E] -= by[1];
        }
    }
}
