//! Resampling (P6) and the statistics of the particle cloud.

use nalgebra::{Matrix6, UnitQuaternion, Vector3, Vector6};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::{Particle, to_array, to_unit};
use crate::attitude::{quat_from_rotation_vector, rotation_vector};

/// Smallest variance kept on the kernel's diagonal (rad², (rad/s)²): a cloud
/// that has collapsed on one axis still gets a positive definite kernel.
const VARIANCE_FLOOR: f64 = 1e-18;

/// Navigation-frame attitude error of particle `p` about `q_hat`,
/// `δθ = log(q ⊗ q̂⁻¹)`.
fn attitude_error(p: &Particle, q_hat: &UnitQuaternion<f64>) -> Vector3<f64> {
    rotation_vector(&(to_unit(&p.q) * q_hat.inverse()))
}

/// Weighted sample covariance of `[δθ_i; b_i − b̂]` (6×6, symmetric).
pub(super) fn cloud_covariance(
    particles: &[Particle],
    weights: &[f64],
    q_hat: &UnitQuaternion<f64>,
    b_hat: &Vector3<f64>,
) -> Matrix6<f64> {
    let mut mean = Vector6::zeros();
    let mut m2 = Matrix6::zeros();
    for (p, &w) in particles.iter().zip(weights) {
        let d = attitude_error(p, q_hat);
        let x = Vector6::new(
            d.x,
            d.y,
            d.z,
            p.b[0] - b_hat.x,
            p.b[1] - b_hat.y,
            p.b[2] - b_hat.z,
        );
        mean += x * w;
        m2 += x * x.transpose() * w;
    }
    let c = m2 - mean * mean.transpose();
    (c + c.transpose()) * 0.5
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
/// on the residual weights `N w_i − ⌊N w_i⌋` (one uniform). `out` receives
/// the N new particles in the order of their parents.
pub(super) fn residual(
    particles: &[Particle],
    weights: &[f64],
    out: &mut Vec<Particle>,
    rng: &mut ChaCha8Rng,
) {
    let n = particles.len();
    out.clear();
    let nf = n as f64;
    let mut residual_sum = 0.0;
    for (p, &w) in particles.iter().zip(weights) {
        let copies = (nf * w).floor();
        for _ in 0..copies as usize {
            out.push(*p);
        }
        residual_sum += nf * w - copies;
    }
    let remaining = n.saturating_sub(out.len());
    if remaining > 0 && residual_sum > 0.0 {
        // Systematic draws on the residuals: pointers u, u + 1, ..., in units
        // of residual_sum / remaining.
        let step = residual_sum / remaining as f64;
        let mut pointer = rng.random::<f64>() * step;
        let mut cumulative = 0.0;
        let mut drawn = 0;
        for (p, &w) in particles.iter().zip(weights) {
            cumulative += nf * w - (nf * w).floor();
            while drawn < remaining && pointer < cumulative {
                out.push(*p);
                drawn += 1;
                pointer += step;
            }
        }
    }
    // Rounding can leave a place or two: the last particles fill them.
    while out.len() < n {
        let last = out.last().copied().unwrap_or(particles[n - 1]);
        out.push(last);
    }
    out.truncate(n);
    for p in out.iter_mut() {
        p.lw = 0.0;
    }
}

/// The shrinkage kernel (Liu & West 2001): `x ← x̄ + a (x − x̄) + h L ε` in
/// the space of `[δθ; b]`, `h` the Gaussian kernel's optimal bandwidth for
/// d = 6, `a = √(1 − h²)`; `L` the Cholesky factor of the cloud's covariance
/// before resampling.
pub(super) fn regularise(
    particles: &mut [Particle],
    q_hat: &UnitQuaternion<f64>,
    b_hat: &Vector3<f64>,
    l: &Matrix6<f64>,
    rng: &mut ChaCha8Rng,
) {
    let n = particles.len() as f64;
    let d = 6.0;
    let h = (4.0 / (n * (d + 2.0))).powf(1.0 / (d + 4.0));
    let a = (1.0 - h * h).sqrt();
    // The cloud's mean after selection, to shrink towards.
    let mut mean = Vector6::zeros();
    let errors: Vec<Vector6<f64>> = particles
        .iter()
        .map(|p| {
            let e = attitude_error(p, q_hat);
            Vector6::new(
                e.x,
                e.y,
                e.z,
                p.b[0] - b_hat.x,
                p.b[1] - b_hat.y,
                p.b[2] - b_hat.z,
            )
        })
        .collect();
    for e in &errors {
        mean += e / n;
    }
    for (p, e) in particles.iter_mut().zip(&errors) {
        let eps = Vector6::from_fn(|_, _| StandardNormal.sample(rng));
        let x = mean + (e - mean) * a + l * eps * h;
        let dq = quat_from_rotation_vector(&Vector3::new(x[0], x[1], x[2]));
        p.q = to_array(&(dq * q_hat));
        p.b = [b_hat.x + x[3], b_hat.y + x[4], b_hat.z + x[5]];
    }
}
