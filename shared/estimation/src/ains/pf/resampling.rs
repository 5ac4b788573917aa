//! Paper 000 eq. 11's resampling, per component: selection with replacement
//! (the paper's "selection and replacement", its refs. 24-25): `N` particles
//! drawn independently with probability `w_j` (multinomial), equal weights
//! after. The draws are made in order with the exponential-spacings method
//! (`u_(k) = S_k / S_{N+1}`, `S_k` the sum of `k` unit exponentials: the
//! order statistics of `N` uniforms, Devroye 1986 §V.2), so one pass over
//! the cumulative weights selects them all, O(N).
//!
//! Copies of one particle are then told apart by a kernel (our addition;
//! the paper says nothing of it, and with per-component filters aided
//! several times a second the copies would otherwise collapse the cloud to
//! a few values): the shrinkage kernel of Liu & West (2001),
//! `x'_j = a x_j + (1 − a) x̄ + h s z_j`, `a = √(1 − h²)`, `x̄` and `s²` the
//! weighted mean and variance before resampling, which keeps both.

use super::cloud::{Component, Moments};
use super::noise::Noise;

/// Buffers of one resampling, allocated once per filter.
#[derive(Debug, Clone, PartialEq)]
pub struct Scratch {
    u: Vec<f64>,
    x: Vec<f64>,
    b: Vec<f64>,
    /// Normal draws for the kernel and the predictions, length `N`.
    pub(super) z: Vec<f64>,
}

impl Scratch {
    /// Buffers for `n` particles.
    pub fn new(n: usize) -> Self {
        Self {
            u: vec![0.0; n + 1],
            x: vec![0.0; n],
            b: vec![0.0; n],
            z: vec![0.0; n],
        }
    }
}

/// Selection with replacement and the kernel of width `h` (module docs).
pub fn resample(c: &mut Component, h: f64, noise: &mut Noise, s: &mut Scratch) {
    let n = c.len();
    let before = c.moments();
    let before_b = c.b_moments();
    // Ordered uniforms by exponential spacings.
    noise.fill_uniform(&mut s.u);
    let mut sum = 0.0;
    for u in s.u.iter_mut() {
        // 1 − u in (0, 1]: the logarithm is finite.
        sum -= (1.0 - *u).ln();
        *u = sum;
    }
    let inv = 1.0 / sum;
    let with_b = !c.b.is_empty();
    let mut j = 0;
    let mut cum = c.w[0];
    for k in 0..n {
        let u = s.u[k] * inv;
        while u > cum && j + 1 < n {
            j += 1;
            cum += c.w[j];
        }
        s.x[k] = c.x[j];
        if with_b {
            s.b[k] = c.b[j];
        }
    }
    c.x.copy_from_slice(&s.x[..n]);
    if with_b {
        c.b.copy_from_slice(&s.b[..n]);
    }
    c.w.fill(1.0 / n as f64);
    kernel(&mut c.x, before, h, noise, &mut s.z);
    if with_b {
        kernel(&mut c.b, before_b, h, noise, &mut s.z);
    }
}

/// Liu & West's shrinkage kernel on `x` (module docs).
fn kernel(x: &mut [f64], m: Moments, h: f64, noise: &mut Noise, z: &mut [f64]) {
    if !(h > 0.0) {
        return;
    }
    let a = (1.0 - h * h).sqrt();
    let z = &mut z[..x.len()];
    noise.fill_normal(z, h * m.var.sqrt());
    let c = (1.0 - a) * m.mean;
    for (x, z) in x.iter_mut().zip(z.iter()) {
        *x = a * *x + c + *z;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Selection follows the weights and the kernel keeps mean and variance.
    #[test]
    fn resampling_keeps_the_distribution() {
        let n = 2000;
        let mut noise = Noise::new(3);
        let mut c = Component::new(n, true);
        for j in 0..n {
            c.x[j] = if j < n / 2 { 0.0 } else { 1.0 };
            c.b[j] = c.x[j];
            c.w[j] = if j < n / 2 { 0.2 } else { 0.8 } / (n / 2) as f64;
        }
        let before = c.moments();
        let mut s = Scratch::new(n);
        resample(&mut c, 0.0, &mut noise, &mut s);
        let ones = c.x.iter().filter(|&&x| x == 1.0).count() as f64 / n as f64;
        assert!((ones - 0.8).abs() < 0.03, "{ones}");
        assert_eq!(c.x, c.b, "companions move with their particles");
        assert!(c.w.iter().all(|&w| w == 1.0 / n as f64));
        let mut c2 = c.clone();
        resample(&mut c2, 0.3, &mut noise, &mut s);
        let after = c2.moments();
        assert!((after.mean - before.mean).abs() < 0.03, "{after:?}");
        assert!(
            (after.var - before.var).abs() < 0.03,
            "{after:?} {before:?}"
        );
        assert!(
            c2.x.iter().filter(|&&x| x == 1.0).count() < 5,
            "spread apart"
        );
    }
}
