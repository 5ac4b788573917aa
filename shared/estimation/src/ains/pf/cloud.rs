//! One component of a particle filter of paper 000 §III-A: `N` values of one
//! state component (north velocity, east position, ...) with their own
//! weights (eqs. 14 and 16: "an equal weight is assigned to every particle
//! component"). The velocity and position filters are three of these each;
//! the components share the prediction but are weighted (eqs. 23, 25),
//! resampled (eq. 11) and estimated (eqs. 26, 27) on their own.
//!
//! Structure of arrays, no allocation after construction: every loop runs
//! over plain `f64` slices of the same length, which the compiler
//! vectorises.

use super::noise::Noise;
use super::resampling::{self, Scratch};

/// One state component's particles (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Component {
    /// The particles' values `x_j`.
    pub(super) x: Vec<f64>,
    /// A companion value per particle moved with it by the resampling: the
    /// velocity filter's acceleration error, the position filter's velocity
    /// error `b_j` ([`super`] docs).
    pub(super) b: Vec<f64>,
    /// The normalised weights `w_j` (eq. 10).
    pub(super) w: Vec<f64>,
}

/// Weighted mean and variance of a component (eqs. 26-27 and the spread
/// the filter publishes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moments {
    /// `Σ w_j x_j`.
    pub mean: f64,
    /// `Σ w_j (x_j − mean)²`.
    pub var: f64,
}

/// Why a weight update could not be used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Degenerate;

impl Component {
    /// `n` particles at zero with equal weights (eqs. 14, 16), with a
    /// companion value when `with_b`.
    pub fn new(n: usize, with_b: bool) -> Self {
        Self {
            x: vec![0.0; n],
            b: if with_b { vec![0.0; n] } else { Vec::new() },
            w: vec![1.0 / n as f64; n],
        }
    }

    /// Particle count `N`.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Draws the particles from `N(mean, std²)` with equal weights (the
    /// initialisation, a re-anchoring and a restore); the companions from
    /// `N(b_mean, b_std²)`.
    pub fn spread(&mut self, mean: f64, std: f64, b: Moments, noise: &mut Noise) {
        noise.fill_normal(&mut self.x, std);
        for x in &mut self.x {
            *x += mean;
        }
        if !self.b.is_empty() {
            noise.fill_normal(&mut self.b, b.var.sqrt());
            for v in &mut self.b {
                *v += b.mean;
            }
        }
        let w = 1.0 / self.len() as f64;
        self.w.fill(w);
    }

    /// The prediction of one component (eqs. 19 and 21) with the process
    /// noise that keeps the cloud spread and the companion error `b_j`
    /// (first-order Gauss–Markov, `φ = e^{−Δt/τ}`, [`super`] docs):
    /// `x_j += δ + b_j Δt + σ z_j`, then `b_j ← φ b_j + σ_b √(1−φ²) z'_j`
    /// (`b_drive` is `σ_b √(1−φ²)`; `z` scratch).
    #[allow(clippy::too_many_arguments)]
    pub fn shift_with_bias(
        &mut self,
        delta: f64,
        dt: f64,
        sigma: f64,
        phi: f64,
        b_drive: f64,
        noise: &mut Noise,
        z: &mut [f64],
    ) {
        let n = self.x.len();
        let z = &mut z[..n];
        noise.fill_normal(z, sigma);
        for ((x, z), b) in self.x.iter_mut().zip(z.iter()).zip(&self.b) {
            *x += delta + b * dt + *z;
        }
        noise.fill_normal(z, b_drive);
        for (b, z) in self.b.iter_mut().zip(z.iter()) {
            *b = phi * *b + *z;
        }
    }

    /// Weighted mean and variance.
    pub fn moments(&self) -> Moments {
        moments(&self.x, &self.w)
    }

    /// Weighted mean and variance of the companions.
    pub fn b_moments(&self) -> Moments {
        moments(&self.b, &self.w)
    }

    /// Paper 000 eqs. 23 and 25 (and 9-10): `w_j ← w_j · exp(−(z − x_j)² /
    /// (2σ²))`, then normalised. The Gaussian's constant `1/(σ√2π)`
    /// cancels in the normalisation; the exponents are taken relative to
    /// their largest so that a measurement far from every particle does
    /// not underflow to all-zero weights. `Err` (weights unchanged) if the
    /// weights sum to nothing even so.
    pub fn weigh(&mut self, z: f64, sigma: f64, scratch: &mut [f64]) -> Result<(), Degenerate> {
        let k = -0.5 / (sigma * sigma);
        let lw = &mut scratch[..self.x.len()];
        let mut top = f64::NEG_INFINITY;
        for ((l, x), w) in lw.iter_mut().zip(&self.x).zip(&self.w) {
            let d = z - x;
            *l = if *w > 0.0 {
                k * d * d + w.ln()
            } else {
                f64::NEG_INFINITY
            };
            top = top.max(*l);
        }
        if !top.is_finite() {
            return Err(Degenerate);
        }
        let mut sum = 0.0;
        for l in lw.iter_mut() {
            *l = (*l - top).exp();
            sum += *l;
        }
        if !(sum > 0.0 && sum.is_finite()) {
            return Err(Degenerate);
        }
        let inv = 1.0 / sum;
        for (w, l) in self.w.iter_mut().zip(lw.iter()) {
            *w = l * inv;
        }
        Ok(())
    }

    /// A measurement much narrower than the cloud (`s > 5σ`): eq. 23's
    /// weights would fall on a few particles, whose spread says nothing of
    /// the posterior's. The particles are selected with those weights (the
    /// companions that go with values near the measurement survive, as in
    /// an ordinary update), then their values drawn from the Gaussian
    /// posterior of the cloud's moments and the measurement,
    /// `x̄⁺ = x̄ + s²/(s² + σ²) (z − x̄)`, `s⁺² = s² σ² / (s² + σ²)` (our
    /// addition; it happens when the DVL returns after an outage). False
    /// (nothing done) when the cloud is not that wide.
    pub fn narrow_update(
        &mut self,
        z: f64,
        sigma: f64,
        noise: &mut Noise,
        scratch: &mut Scratch,
    ) -> Result<bool, Degenerate> {
        let m = self.moments();
        let r = sigma * sigma;
        if m.var <= 25.0 * r {
            return Ok(false);
        }
        self.weigh(z, sigma, &mut scratch.z)?;
        resampling::resample(self, 0.0, noise, scratch);
        let k = m.var / (m.var + r);
        let mean = m.mean + k * (z - m.mean);
        noise.fill_normal(&mut self.x, (k * r).sqrt());
        for x in &mut self.x {
            *x += mean;
        }
        Ok(true)
    }

    /// Paper 000 eq. 11: the effective particle number `1 / Σ w_j²`.
    pub fn effective(&self) -> f64 {
        1.0 / self.w.iter().map(|w| w * w).sum::<f64>()
    }

    /// Eq. 11's test and the selection-and-replacement resampling of this
    /// component (`resampling.rs`) when `N_eff < threshold · N`; true if it
    /// resampled.
    pub fn maybe_resample(
        &mut self,
        threshold: f64,
        kernel: f64,
        noise: &mut Noise,
        scratch: &mut Scratch,
    ) -> bool {
        if self.effective() >= threshold * self.len() as f64 {
            return false;
        }
        resampling::resample(self, kernel, noise, scratch);
        true
    }
}

/// Weighted mean and variance in one pass, about the first value (so that
/// positions a kilometre from the origin keep their centimetres):
/// `d_j = x_j − x_0`, `x̄ = x_0 + Σ w d`, `s² = Σ w d² − (Σ w d)²`.
fn moments(x: &[f64], w: &[f64]) -> Moments {
    let Some(&x0) = x.first() else {
        return Moments {
            mean: 0.0,
            var: 0.0,
        };
    };
    let (mut m1, mut m2) = (0.0, 0.0);
    for (x, w) in x.iter().zip(w) {
        let d = x - x0;
        m1 += w * d;
        m2 += w * d * d;
    }
    Moments {
        mean: x0 + m1,
        var: (m2 - m1 * m1).max(0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weighing_moves_the_mean_toward_the_measurement() {
        let mut noise = Noise::new(1);
        let mut c = Component::new(500, false);
        let zero = Moments {
            mean: 0.0,
            var: 0.0,
        };
        c.spread(0.0, 1.0, zero, &mut noise);
        let m0 = c.moments();
        assert!(m0.mean.abs() < 0.15 && (m0.var - 1.0).abs() < 0.2, "{m0:?}");
        let mut s = vec![0.0; 500];
        c.weigh(1.0, 1.0, &mut s).expect("weights");
        // Prior N(0, 1), likelihood N(1, 1): posterior N(0.5, 0.5).
        let m = c.moments();
        assert!(
            (m.mean - 0.5).abs() < 0.1 && (m.var - 0.5).abs() < 0.12,
            "{m:?}"
        );
        assert!(c.effective() < 500.0);
        // Far away: no underflow, the nearest particles take the weight.
        c.weigh(1e3, 1e-3, &mut s).expect("relative exponents");
        assert!((c.w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(c.weigh(f64::NAN, 1.0, &mut s).is_err());
    }

    /// A measurement 100 times narrower than the cloud: the Gaussian
    /// posterior, not the few particles that happened to be near it.
    #[test]
    fn a_narrow_measurement_gives_the_gaussian_posterior() {
        let mut noise = Noise::new(2);
        let mut c = Component::new(256, true);
        let b = Moments {
            mean: 0.0,
            var: 1.0,
        };
        c.spread(0.0, 1.0, b, &mut noise);
        let mut s = Scratch::new(256);
        assert_eq!(c.narrow_update(0.5, 0.01, &mut noise, &mut s), Ok(true));
        let m = c.moments();
        assert!((m.mean - 0.5).abs() < 0.003, "{m:?}");
        assert!((m.var.sqrt() - 0.01).abs() < 0.002, "{m:?}");
        // Not that narrow: left to eq. 23.
        assert_eq!(c.narrow_update(0.5, 0.01, &mut noise, &mut s), Ok(false));
    }
}
