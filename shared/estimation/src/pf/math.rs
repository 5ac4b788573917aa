//! Small arithmetic of the filter's loops: the Hamilton product, the
//! rotation increment of (P1) and an exponential for the weights, written
//! without branches or library calls so that loops over particles
//! vectorise.

/// `exp(θ)` to fourth order in `|θ|` (P1): `[1 − t/8 + t²/384, (½ − t/48) θ]`,
/// `t = |θ|²`.
#[inline(always)]
pub(super) fn exp_series(theta: [f64; 3]) -> [f64; 4] {
    let t = theta[0] * theta[0] + theta[1] * theta[1] + theta[2] * theta[2];
    let c = 1.0 - t * (1.0 / 8.0) + t * t * (1.0 / 384.0);
    let s = 0.5 - t * (1.0 / 48.0);
    [c, s * theta[0], s * theta[1], s * theta[2]]
}

/// Hamilton product `a ⊗ b` of `[w, x, y, z]` arrays.
#[inline(always)]
pub(super) fn qmul(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// `1.5 · 2⁵²`: adding it rounds a number below 2⁵¹ in magnitude to an
/// integer, which then sits in the low bits of the sum.
const ROUND_SHIFT: f64 = 6_755_399_441_055_744.0;
/// ln 2 in two parts (fdlibm's `ln2_hi`, `ln2_lo`): `k · LN2_HI` is exact.
const LN2_HI: f64 = 0.693_147_180_369_123_8;
const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
/// Below this `exp` is 0 here (`e^−708` is the smallest normal result).
const EXP_FLOOR: f64 = -708.0;

/// `e^x` for `x ≤ 0` (a weight relative to the largest): `x = k ln 2 + r`
/// with `|r| ≤ ln 2 / 2`, `e^r` by its Taylor polynomial of degree 8
/// (relative error below `0.347⁹/9! = 2e-10`, far below what a weight
/// needs), `2^k` written into the exponent bits; 0 below −708 (and for
/// NaN). About 20 operations without a branch, against a libm call (libm's
/// `exp` was a fifth of the filter's time, perf, before this change).
#[inline(always)]
pub(super) fn exp_nonpositive(x: f64) -> f64 {
    let xc = x.max(EXP_FLOOR);
    let shifted = xc * std::f64::consts::LOG2_E + ROUND_SHIFT;
    let k = shifted - ROUND_SHIFT;
    let r = (xc - k * LN2_HI) - k * LN2_LO;
    let p = 1.0
        + r * (1.0
            + r * (1.0 / 2.0
                + r * (1.0 / 6.0
                    + r * (1.0 / 24.0
                        + r * (1.0 / 120.0
                            + r * (1.0 / 720.0 + r * (1.0 / 5040.0 + r * (1.0 / 40320.0))))))));
    // `shifted`'s bits are ROUND_SHIFT's plus k (−1022 ≤ k ≤ 0): 2^k has the
    // biased exponent k + 1023 (1..=1023, a normal number).
    let k_bits = shifted.to_bits().wrapping_sub(ROUND_SHIFT.to_bits());
    let scale = f64::from_bits(k_bits.wrapping_add(1023) << 52);
    if x >= EXP_FLOOR { p * scale } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against libm over the range the weights use, and at its ends.
    #[test]
    fn exp_matches_libm() {
        let mut worst: f64 = 0.0;
        for i in 0..=200_000 {
            let x = -708.0 * f64::from(i) / 200_000.0;
            let rel = (exp_nonpositive(x) - x.exp()).abs() / x.exp();
            worst = worst.max(rel);
        }
        assert!(worst < 3e-10, "{worst}");
        assert_eq!(exp_nonpositive(0.0), 1.0);
        assert_eq!(exp_nonpositive(-709.0), 0.0);
        assert_eq!(exp_nonpositive(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp_nonpositive(f64::NAN), 0.0);
        assert!((exp_nonpositive(-1e-300) - 1.0).abs() < 1e-15);
    }
}
