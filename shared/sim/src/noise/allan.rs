//! Overlapping Allan deviation of a rate series and the read-outs of its
//! curve (IEEE Std 952-1997, Annex C).
//!
//! For rate samples y₀ … y_{n-1} taken at fs (τ₀ = 1/fs), the angle is the
//! cumulative sum θ_k = τ₀ Σ_{i<k} y_i (k = 0 … n), and for a cluster time
//! τ = m τ₀ the overlapping Allan variance is
//!
//! ```text
//! σ²(τ) = 1 / (2 τ² (n + 1 − 2m)) · Σ_{k=0}^{n−2m} (θ_{k+2m} − 2 θ_{k+m} + θ_k)²
//! ```
//!
//! which costs O(n) per τ. The series mean is removed before summing (σ² is
//! blind to a constant), which keeps θ small and the differences exact.
//!
//! Slopes of σ(τ) on a log-log plot and what they read:
//! - white rate noise (angle random walk): σ(τ) = N / √τ, so N = σ(1 s);
//! - flicker rate noise (bias instability): flat floor σ_min = B · √(2 ln 2 / π)
//!   ≈ 0.664 B;
//! - rate random walk: σ(τ) = K √(τ / 3), so K = σ(τ) √(3 / τ).

use super::NoiseError;

/// σ_min / B for flicker (1/f) rate noise: √(2 ln 2 / π) ≈ 0.6643
/// (IEEE Std 952-1997, Annex C, Table C.1).
pub const FLICKER_FLOOR_FACTOR: f64 = 0.664_282_936_599_668_5;

/// One point of an Allan deviation curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AllanPoint {
    /// Cluster time τ = m / fs, s (the requested τ rounded to whole samples).
    pub tau: f64,
    /// Overlapping Allan deviation σ(τ), in the unit of the samples.
    pub adev: f64,
    /// Number of terms in the overlapping sum (n + 1 − 2m).
    pub terms: usize,
}

/// `count` cluster times spaced evenly in log between `tau_min` and `tau_max` (s).
pub fn log_spaced_taus(tau_min: f64, tau_max: f64, count: usize) -> Vec<f64> {
    match count {
        0 => Vec::new(),
        1 => vec![tau_min],
        _ => {
            let (a, b) = (tau_min.ln(), tau_max.ln());
            (0..count)
                .map(|i| (a + (b - a) * i as f64 / (count - 1) as f64).exp())
                .collect()
        }
    }
}

/// Overlapping Allan deviation of `rate` (sampled at `fs` Hz) at each τ of
/// `taus` (s). A τ is rounded to m = round(τ fs) samples; cluster sizes below
/// 1 or above (n − 1) / 2 are skipped, and duplicate m are reported once.
///
/// Errors: fs not positive and finite, any τ not positive and finite, or
/// fewer than 3 samples.
pub fn allan_deviation(rate: &[f64], fs: f64, taus: &[f64]) -> Result<Vec<AllanPoint>, NoiseError> {
    super::check_positive("fs", fs)?;
    for &t in taus {
        super::check_positive("tau", t)?;
    }
    let n = rate.len();
    if n < 3 {
        return Err(NoiseError::TooFewSamples {
            what: "Allan deviation",
            needed: 3,
            got: n,
        });
    }
    let tau0 = 1.0 / fs;
    let mean = rate.iter().sum::<f64>() / n as f64;
    let mut theta = Vec::with_capacity(n + 1);
    theta.push(0.0);
    let mut acc = 0.0;
    for &y in rate {
        acc += (y - mean) * tau0;
        theta.push(acc);
    }
    let mut out: Vec<AllanPoint> = Vec::with_capacity(taus.len());
    let mut last_m = 0usize;
    for &t in taus {
        let m = (t * fs).round();
        if !(m >= 1.0) || m > ((n - 1) / 2) as f64 {
            continue;
        }
        let m = m as usize;
        if m == last_m {
            continue;
        }
        last_m = m;
        let terms = n + 1 - 2 * m;
        let mut sum = 0.0;
        for k in 0..terms {
            let d = theta[k + 2 * m] - 2.0 * theta[k + m] + theta[k];
            sum += d * d;
        }
        let tau = m as f64 * tau0;
        let avar = sum / (2.0 * tau * tau * terms as f64);
        out.push(AllanPoint {
            tau,
            adev: avar.sqrt(),
            terms,
        });
    }
    Ok(out)
}

/// Means of consecutive blocks of `factor` samples (a trailing partial block
/// is dropped). Averaging down to fs/factor leaves σ(τ) unchanged for
/// τ ≥ factor/fs, so long Allan curves can be computed at a lower rate.
pub fn average_down(samples: &[f64], factor: usize) -> Vec<f64> {
    if factor <= 1 {
        return samples.to_vec();
    }
    samples
        .chunks_exact(factor)
        .map(|c| c.iter().sum::<f64>() / factor as f64)
        .collect()
}

/// The point of `curve` whose τ is closest (in log) to `tau`.
fn nearest(curve: &[AllanPoint], tau: f64) -> Option<AllanPoint> {
    curve.iter().copied().min_by(|a, b| {
        let da = (a.tau / tau).ln().abs();
        let db = (b.tau / tau).ln().abs();
        da.total_cmp(&db)
    })
}

/// Angle random walk coefficient N (unit·√s, i.e. unit/√Hz) read at the
/// point nearest τ = 1 s, assuming white rate noise there: N = σ(τ) √τ.
pub fn angle_random_walk(curve: &[AllanPoint]) -> Option<f64> {
    nearest(curve, 1.0).map(|p| p.adev * p.tau.sqrt())
}

/// Bias instability B from the minimum of the curve over τ in
/// [`tau_min`, `tau_max`]: B = σ_min / 0.664 ([`FLICKER_FLOOR_FACTOR`]).
/// Returns (B, τ at the minimum).
pub fn bias_instability(curve: &[AllanPoint], tau_min: f64, tau_max: f64) -> Option<(f64, f64)> {
    curve
        .iter()
        .filter(|p| p.tau >= tau_min && p.tau <= tau_max)
        .min_by(|a, b| a.adev.total_cmp(&b.adev))
        .map(|p| (p.adev / FLICKER_FLOOR_FACTOR, p.tau))
}

/// Rate random walk K (unit/√s) read at the point nearest `tau`, assuming
/// the curve follows the +½ slope there: K = σ(τ) √(3 / τ).
pub fn rate_random_walk(curve: &[AllanPoint], tau: f64) -> Option<f64> {
    nearest(curve, tau).map(|p| p.adev * (3.0 / p.tau).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn white_noise_gives_n_over_root_tau() {
        // White rate noise of density N at fs: sample σ = N √fs.
        let fs: f64 = 100.0;
        let n_density = 0.01;
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let y: Vec<f64> = (0..200_000)
            .map(|_| n_density * fs.sqrt() * super::super::std_normal(&mut rng))
            .collect();
        let curve = allan_deviation(&y, fs, &log_spaced_taus(0.01, 10.0, 13)).expect("curve");
        for p in &curve {
            let expected = n_density / p.tau.sqrt();
            // Relative standard error of the overlapping estimate ~ sqrt(m/n).
            let tol = 0.03 + 3.0 * (p.tau * fs / y.len() as f64).sqrt();
            assert!(
                (p.adev / expected - 1.0).abs() < tol,
                "tau {} adev {} expected {}",
                p.tau,
                p.adev,
                expected
            );
        }
        let n = angle_random_walk(&curve).expect("N");
        assert!((n / n_density - 1.0).abs() < 0.02, "N {n}");
    }

    #[test]
    fn random_walk_gives_k_root_tau_over_3() {
        // Rate random walk: y_k = y_{k-1} + K √τ₀ w.
        let fs: f64 = 10.0;
        let k = 1e-3;
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut b = 0.0;
        let y: Vec<f64> = (0..400_000)
            .map(|_| {
                b += k * (1.0 / fs).sqrt() * super::super::std_normal(&mut rng);
                b
            })
            .collect();
        let curve = allan_deviation(&y, fs, &[10.0, 100.0]).expect("curve");
        let est = rate_random_walk(&curve, 10.0).expect("K");
        assert!((est / k - 1.0).abs() < 0.1, "K {est}");
    }

    #[test]
    fn constant_and_linear_inputs() {
        // A constant has zero Allan deviation; too short a series is an error.
        let y = vec![3.0; 100];
        let c = allan_deviation(&y, 1.0, &[1.0, 10.0]).expect("curve");
        assert!(c.iter().all(|p| p.adev.abs() < 1e-12));
        assert!(matches!(
            allan_deviation(&[1.0, 2.0], 1.0, &[1.0]),
            Err(NoiseError::TooFewSamples { .. })
        ));
        assert!(allan_deviation(&y, f64::NAN, &[1.0]).is_err());
        assert!(allan_deviation(&y, 1.0, &[-1.0]).is_err());
        // Clusters longer than half the series are skipped.
        assert!(allan_deviation(&y, 1.0, &[60.0]).expect("curve").is_empty());
        assert_eq!(average_down(&[1.0, 3.0, 5.0, 7.0, 9.0], 2), vec![2.0, 6.0]);
    }

    proptest::proptest! {
        #[test]
        fn adev_is_blind_to_offset_and_linear_in_scale(
            y in proptest::collection::vec(-1.0f64..1.0, 20..200),
            c in -1e3f64..1e3,
            k in -10.0f64..10.0,
        ) {
            let taus = [1.0, 2.0, 5.0];
            let a = allan_deviation(&y, 1.0, &taus).expect("curve");
            let z: Vec<f64> = y.iter().map(|v| k * v + c).collect();
            let b = allan_deviation(&z, 1.0, &taus).expect("curve");
            proptest::prop_assert_eq!(a.len(), b.len());
            for (p, q) in a.iter().zip(&b) {
                proptest::prop_assert!((q.adev - k.abs() * p.adev).abs() <= 1e-9 * (1.0 + q.adev));
            }
        }

        #[test]
        fn probabilities_outside_unit_interval_are_rejected(p in proptest::num::f64::ANY) {
            let ok = super::super::check_probability("p", p).is_ok();
            proptest::prop_assert_eq!(ok, (0.0..=1.0).contains(&p));
        }
    }
}
