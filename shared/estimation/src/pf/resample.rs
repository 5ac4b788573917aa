//! Resampling (P6) and the statistics of the particle cloud.

use nalgebra::{Matrix6, Vector3, Vector6};

use super::cloud::{Cloud, LANES, total};
use super::isa::{Isa, dispatch};
use super::math::qmul;
use super::noise::Noise;

/// Smallest variance kept on the kernel's diagonal (rad², (rad/s)²): a cloud
/// that has collapsed on one axis still gets a positive definite kernel.
const VARIANCE_FLOOR: f64 = 1e-18;

/// The chart of (P6) for particle `i` from its error `E_i = q̂ ⊗ q_i⁻¹`:
/// `δθ_i = 2 s_i vec(q_i ⊗ q̂⁻¹) = −2 s_i vec(E_i)` (`s_i` the sign of
/// `E_i`'s `w`), then the bias deviation.
#[inline(always)]
fn chart(e: &[Vec<f64>; 4], cloud: &Cloud, b_hat: &Vector3<f64>, i: usize) -> [f64; 6] {
    let s = if e[0][i] < 0.0 { 2.0 } else { -2.0 };
    [
        s * e[1][i],
        s * e[2][i],
        s * e[3][i],
        cloud.b[0][i] - b_hat.x,
        cloud.b[1][i] - b_hat.y,
        cloud.b[2][i] - b_hat.z,
    ]
}

dispatch! {
    /// Weighted sample covariance of `[δθ_i; b_i − b̂]` (6×6, symmetric), the
    /// attitude error in the chart of (P6), from the errors `e` about `q̂`.
    pub(super) fn cloud_covariance(
        cloud: &Cloud,
        e: &[Vec<f64>; 4],
        weights: &[f64],
        b_hat: &Vector3<f64>,
    ) -> Matrix6<f64> = cloud_covariance_body;
}

/// [`cloud_covariance`]'s loop.
#[inline(always)]
fn cloud_covariance_body(
    cloud: &Cloud,
    e: &[Vec<f64>; 4],
    weights: &[f64],
    b_hat: &Vector3<f64>,
) -> Matrix6<f64> {
    let n = cloud.len();
    // Partial sums per lane: 6 means and the 21 products of the upper triangle.
    let mut mean = [[0.0; LANES]; 6];
    let mut m2 = [[0.0; LANES]; 21];
    for (i, &w) in weights.iter().enumerate().take(n) {
        let j = i % LANES;
        let x = chart(e, cloud, b_hat, i);
        let mut t = 0;
        for a in 0..6 {
            mean[a][j] += w * x[a];
            for bb in a..6 {
                m2[t][j] += w * x[a] * x[bb];
                t += 1;
            }
        }
    }
    let mean = Vector6::from_fn(|a, _| total(mean[a]));
    let mut c = Matrix6::zeros();
    let mut t = 0;
    for a in 0..6 {
        for bb in a..6 {
            let v = total(m2[t]) - mean[a] * mean[bb];
            c[(a, bb)] = v;
            c[(bb, a)] = v;
            t += 1;
        }
    }
    c
}

/// Lower Cholesky factor of `cov` with every variance floored at
/// [`VARIANCE_FLOOR`]; zeros if even that fails (no jitter).
pub(super) fn cholesky_floor(cov: &Matrix6<f64>) -> Matrix6<f64> {
    let mut c = (cov + cov.transpose()) * 0.5;
    for i in 0..6 {
        c[(i, i)] = c[(i, i)].max(VARIANCE_FLOOR);
    }
    for _ in 0..3 {
        if let Some(ch) = c.cholesky() {
            return ch.l();
        }
        let bump = c.diagonal().amax() * 1e-9;
        for i in 0..6 {
            c[(i, i)] += bump;
        }
    }
    Matrix6::zeros()
}

/// Residual resampling ("selection and replacement"): particle `i` is
/// selected `⌊N w_i⌋` times, the remaining `R` places go to systematic draws
/// on the residual weights `N w_i − ⌊N w_i⌋` (one uniform). `parents`
/// receives the N indices of the new particles' parents: the selected
/// copies in particle order, then the drawn ones in particle order.
pub(super) fn residual(weights: &[f64], parents: &mut Vec<u32>, rng: &mut Noise) {
    let n = weights.len();
    parents.clear();
    let nf = n as f64;
    let mut residual_sum = 0.0;
    for (i, &w) in weights.iter().enumerate() {
        let copies = (nf * w).floor();
        // i < n ≤ MAX_PARTICLES < 2³²: the index fits.
        parents.extend(std::iter::repeat_n(i as u32, copies as usize));
        residual_sum += nf * w - copies;
    }
    let remaining = n.saturating_sub(parents.len());
    if remaining > 0 && residual_sum > 0.0 {
        // Systematic draws on the residuals: pointers u, u + 1, ..., in units
        // of residual_sum / remaining.
        let step = residual_sum / remaining as f64;
        let mut pointer = rng.uniform() * step;
        let mut cumulative = 0.0;
        let mut drawn = 0;
        for (i, &w) in weights.iter().enumerate() {
            cumulative += nf * w - (nf * w).floor();
            while drawn < remaining && pointer < cumulative {
                parents.push(i as u32);
                drawn += 1;
                pointer += step;
            }
        }
    }
    // Rounding can leave a place or two: the last particles fill them.
    while parents.len() < n {
        let last = parents.last().copied().unwrap_or(n as u32 - 1);
        parents.push(last);
    }
    parents.truncate(n);
}

/// The shrinkage kernel (Liu & West 2001): `x ← x̄ + a (x − x̄) + h L ε` in
/// the space of `[δθ; b]` (the chart of (P6) about `q_hat`), `h` the
/// Gaussian kernel's optimal bandwidth for d = 6, `a = √(1 − h²)`; `L` the
/// Cholesky factor of the cloud's covariance before resampling. `errors` and
/// `normals` are scratch.
#[allow(clippy::too_many_arguments)]
pub(super) fn regularise(
    isa: Isa,
    cloud: &mut Cloud,
    q_hat: &[f64; 4],
    b_hat: &Vector3<f64>,
    l: &Matrix6<f64>,
    rng: &mut Noise,
    errors: &mut [Vec<f64>; 4],
    normals: &mut Vec<f64>,
) {
    let n = cloud.len();
    let nf = n as f64;
    let d = 6.0;
    let h = (4.0 / (nf * (d + 2.0))).powf(1.0 / (d + 4.0));
    let a = (1.0 - h * h).sqrt();
    cloud.errors(isa, q_hat, errors);
    normals.resize(6 * n, 0.0);
    rng.fill_normal(isa, normals, h);
    let kernel = Kernel { q_hat, b_hat, l, a };
    spread(isa, cloud, &kernel, errors, normals);
}

/// The kernel of [`regularise`]: about `q_hat` and `b_hat`, shrinkage `a`,
/// the covariance's Cholesky factor `l`.
#[derive(Debug)]
struct Kernel<'a> {
    q_hat: &'a [f64; 4],
    b_hat: &'a Vector3<f64>,
    l: &'a Matrix6<f64>,
    a: f64,
}

dispatch! {
    fn spread(cloud: &mut Cloud, k: &Kernel<'_>, errors: &[Vec<f64>; 4], normals: &[f64]) = spread_body;
}

/// [`regularise`]'s loops: the cloud's mean after selection, to shrink
/// towards, then each particle moved, with the kernel draws `normals` (`6n`,
/// `h` already in them).
#[inline(always)]
fn spread_body(cloud: &mut Cloud, k: &Kernel<'_>, errors: &[Vec<f64>; 4], normals: &[f64]) {
    let Kernel { q_hat, b_hat, l, a } = *k;
    let n = cloud.len();
    let nf = n as f64;
    let mut lanes = [[0.0; LANES]; 6];
    for i in 0..n {
        let x = chart(errors, cloud, b_hat, i);
        for (k, v) in x.iter().enumerate() {
            lanes[k][i % LANES] += v;
        }
    }
    let mean = lanes.map(|l| total(l) / nf);
    let l = l.as_slice();
    // Column-major: L[(r, c)] is l[r + 6 c].
    for i in 0..n {
        let x = chart(errors, cloud, b_hat, i);
        let mut y = [0.0; 6];
        for (r, y) in y.iter_mut().enumerate() {
            let mut v = mean[r] + a * (x[r] - mean[r]);
            for c in 0..=r {
                v += l[r + 6 * c] * normals[c * n + i];
            }
            *y = v;
        }
        // The chart's inverse: q_i ⊗ q̂⁻¹ = [√(1 − |δθ/2|²), δθ/2],
        // normalised (a kernel draw beyond 180° is clamped onto the sphere).
        let v = [0.5 * y[0], 0.5 * y[1], 0.5 * y[2]];
        let v2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        let w = (1.0 - v2).max(0.0).sqrt();
        let k = 1.0 / (w * w + v2).sqrt();
        let q = qmul(&[w * k, v[0] * k, v[1] * k, v[2] * k], q_hat);
        cloud.set_q(i, q);
        for k in 0..3 {
            cloud.b[k][i] = b_hat[k] + y[3 + k];
        }
    }
}
