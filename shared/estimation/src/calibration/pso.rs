//! Magnetometer calibration by particle swarm optimisation (paper 000 §IV-A:
//! "through the PSO the equivalent spheroid parameters are estimated to
//! correct the uncalibrated measurements"; the paper cites its PSO as [29]
//! without further detail).
//!
//! # Cost (C3)
//!
//! A particle is the nine numbers of a calibration (C1): the hard iron `h`
//! and the six of the symmetric `W`. Its cost is the mean squared distance
//! of the calibrated samples from the sphere of the reference norm `R`,
//!
//! ```text
//! J(h, W) = (1/n) Σ_k ( |W (m̃_k − h)| − R )²                              (C3)
//! ```
//!
//! the geometric counterpart of the algebraic fit (C2), and directly the
//! figure of merit (the spread of the calibrated norm about `R`).
//!
//! # Swarm (C4)
//!
//! Global-best PSO with Clerc and Kennedy's constriction (Clerc & Kennedy,
//! "The particle swarm - explosion, stability, and convergence in a
//! multidimensional complex space", IEEE TEC 6(1), 2002): for particle `i`,
//! dimension `d`, with uniform `r₁, r₂ ∈ [0, 1)` drawn per dimension,
//!
//! ```text
//! v ← χ (v + c₁ r₁ (p_i − x) + c₂ r₂ (g − x)),   x ← x + v               (C4)
//! ```
//!
//! `χ = 0.7298`, `c₁ = c₂ = 2.05`, `p_i` the particle's best position and `g`
//! the swarm's. Velocities are clamped to the initial box's width; positions
//! may leave the box. The box: `h` within half the samples' mean radius of
//! their centroid; `W` within ±50 % (diagonal) and ±30 % (off-diagonal) of
//! `R / radius`. One particle starts at the centroid with `W = (R/radius) I`
//! (the uncalibrated guess), the rest uniformly in the box. The generator is
//! ChaCha8 seeded by the caller: a seed gives the same fit bit for bit.

use nalgebra::{Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

use super::magnetometer::{MagCalibration, MagCalibrationError, centre_and_scale, check_inputs};

/// Swarm settings (`deny_unknown_fields`; every field defaulted).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PsoParams {
    /// Particles in the swarm. Default 40 (our choice; 9 dimensions).
    pub swarm: usize,
    /// Iterations (the swarm always runs them all, so a seed repeats). Default
    /// 400 (our choice: the cost stops improving after ~250 on the tests' data).
    pub iterations: usize,
}

impl Default for PsoParams {
    fn default() -> Self {
        Self {
            swarm: 40,
            iterations: 400,
        }
    }
}

/// Constriction factor χ and acceleration coefficients c₁ = c₂ (C4).
const CHI: f64 = 0.7298;
const C: f64 = 2.05;

type Position = [f64; 9];

fn calibration_of(x: &Position) -> MagCalibration {
    MagCalibration {
        hard_iron_ut: Vector3::new(x[0], x[1], x[2]),
        soft_iron_inv: Matrix3::new(x[3], x[6], x[7], x[6], x[4], x[8], x[7], x[8], x[5]),
    }
}

/// (C3).
fn cost(x: &Position, samples: &[Vector3<f64>], r: f64) -> f64 {
    let cal = calibration_of(x);
    let sum: f64 = samples
        .iter()
        .map(|m| (cal.apply(m).norm() - r).powi(2))
        .sum();
    let j = sum / samples.len() as f64;
    if j.is_finite() { j } else { f64::INFINITY }
}

/// Fits a calibration by (C3)-(C4) with the swarm settings `params` and the
/// generator seeded by `seed`.
pub fn fit_pso(
    samples: &[Vector3<f64>],
    reference_norm_ut: f64,
    params: &PsoParams,
    seed: u64,
) -> Result<MagCalibration, MagCalibrationError> {
    check_inputs(samples, reference_norm_ut)?;
    if params.swarm < 2 || params.iterations == 0 {
        return Err(MagCalibrationError::NonFinite);
    }
    let (mu, radius) = centre_and_scale(samples);
    if !(radius > 0.0) {
        return Err(MagCalibrationError::NotEllipsoid);
    }
    let k = reference_norm_ut / radius;
    let mut centre: Position = [mu.x, mu.y, mu.z, k, k, k, 0.0, 0.0, 0.0];
    let mut half: Position = [0.0; 9];
    for d in 0..3 {
        half[d] = 0.5 * radius;
        half[d + 3] = 0.5 * k;
        half[d + 6] = 0.3 * k;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut x: Vec<Position> = (0..params.swarm)
        .map(|i| {
            let mut p = centre;
            if i > 0 {
                for d in 0..9 {
                    p[d] += half[d] * (2.0 * rng.random::<f64>() - 1.0);
                }
            }
            p
        })
        .collect();
    let mut v: Vec<Position> = (0..params.swarm)
        .map(|_| {
            let mut q = [0.0; 9];
            for d in 0..9 {
                q[d] = half[d] * (2.0 * rng.random::<f64>() - 1.0);
            }
            q
        })
        .collect();
    let mut best = x.clone();
    let mut best_cost: Vec<f64> = x
        .iter()
        .map(|p| cost(p, samples, reference_norm_ut))
        .collect();
    let mut g = 0usize;
    for i in 1..params.swarm {
        if best_cost[i] < best_cost[g] {
            g = i;
        }
    }
    let vmax = half.map(|h| 2.0 * h);
    for _ in 0..params.iterations {
        let global = best[g];
        for i in 0..params.swarm {
            for d in 0..9 {
                let r1: f64 = rng.random();
                let r2: f64 = rng.random();
                let vel = CHI
                    * (v[i][d] + C * r1 * (best[i][d] - x[i][d]) + C * r2 * (global[d] - x[i][d]));
                v[i][d] = vel.clamp(-vmax[d], vmax[d]);
                x[i][d] += v[i][d];
            }
            let c = cost(&x[i], samples, reference_norm_ut);
            if c < best_cost[i] {
                best_cost[i] = c;
                best[i] = x[i];
                if c < best_cost[g] {
                    g = i;
                }
            }
        }
    }
    centre = best[g];
    let cal = calibration_of(&centre);
    MagCalibration::new(cal.hard_iron_ut, cal.soft_iron_inv)
}
