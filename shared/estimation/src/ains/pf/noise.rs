//! The filter's random numbers: [`LANES`] xoshiro128++ streams run side by
//! side (a loop the compiler turns into SIMD) and standard normal draws made
//! from them in batches, as the attitude PF does (`crate::pf`'s generator,
//! private to that module; this is the same algorithm with fewer lanes, so
//! that its state fits the aided INS's snapshot).
//!
//! - xoshiro128++ (Blackman & Vigna, ACM TOMS 47(4), 2021), the streams
//!   seeded by SplitMix64 from the filter's seed: the same seed gives the
//!   same numbers on every machine (32-bit integer operations only).
//! - Normal draws (Irwin–Hall of four bytes, mean 0, variance 1 exactly):
//!   `z = (S − 510) · √(3 / 65535)`, `S` the sum of a word's four bytes.
//!   What the filter draws them for (process noise at the IMU rate, the
//!   kernel after a resampling) adds up over many draws, so the bounded
//!   support (±3.46) does not show.
//! - Uniform draws in [0, 1) with 32 random bits for the resampling.

/// Streams run side by side.
pub const LANES: usize = 32;

/// `√(3 / 65535)`: the Irwin–Hall draw's scale for unit variance.
const IRWIN_HALL_SCALE: f64 = 0.006_765_875_086_793_227;

/// The generator (module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Noise {
    /// State word `k` of stream `l` is `s[k][l]`.
    s: [[u32; LANES]; 4],
}

/// SplitMix64 (Steele, Lea & Flood 2014): the seeder of the streams.
fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Noise {
    /// The streams seeded from `seed`.
    pub fn new(seed: u64) -> Self {
        let mut sm = seed;
        let mut s = [[0u32; LANES]; 4];
        for l in 0..LANES {
            let (a, b) = (splitmix64(&mut sm), splitmix64(&mut sm));
            // Truncations keep the low and high halves of each word.
            s[0][l] = a as u32;
            s[1][l] = (a >> 32) as u32;
            s[2][l] = b as u32;
            s[3][l] = (b >> 32) as u32;
            if s.iter().all(|w| w[l] == 0) {
                s[0][l] = 1;
            }
        }
        Self { s }
    }

    /// The state as `4 × LANES` words (for a snapshot).
    pub fn state(&self) -> Vec<u32> {
        self.s.iter().flatten().copied().collect()
    }

    /// The generator of a [`Noise::state`]; `None` if it has the wrong length
    /// or a stream is all zeros (a state xoshiro cannot leave).
    pub fn from_state(words: &[u32]) -> Option<Self> {
        if words.len() != 4 * LANES {
            return None;
        }
        let mut s = [[0u32; LANES]; 4];
        for (k, row) in s.iter_mut().enumerate() {
            row.copy_from_slice(&words[k * LANES..(k + 1) * LANES]);
        }
        if (0..LANES).any(|l| s.iter().all(|w| w[l] == 0)) {
            return None;
        }
        Some(Self { s })
    }

    /// One output of every stream (xoshiro128++).
    #[inline(always)]
    fn next(&mut self) -> [u32; LANES] {
        let [s0, s1, s2, s3] = &mut self.s;
        let mut out = [0u32; LANES];
        for l in 0..LANES {
            out[l] = s0[l].wrapping_add(s3[l]).rotate_left(7).wrapping_add(s0[l]);
            let t = s1[l] << 9;
            s2[l] ^= s0[l];
            s3[l] ^= s1[l];
            s1[l] ^= s2[l];
            s0[l] ^= s3[l];
            s2[l] ^= t;
            s3[l] = s3[l].rotate_left(11);
        }
        out
    }

    /// Fills `out` with `scale · z`, `z` unit-variance normal draws.
    pub fn fill_normal(&mut self, out: &mut [f64], scale: f64) {
        let k = scale * IRWIN_HALL_SCALE;
        let (chunks, rest) = out.as_chunks_mut::<LANES>();
        for chunk in chunks {
            let r = self.next();
            for l in 0..LANES {
                chunk[l] = f64::from(byte_sum(r[l]) - 510) * k;
            }
        }
        if !rest.is_empty() {
            let r = self.next();
            for (o, x) in rest.iter_mut().zip(r) {
                *o = f64::from(byte_sum(x) - 510) * k;
            }
        }
    }

    /// Fills `out` with uniform draws in [0, 1) (32 random bits each).
    pub fn fill_uniform(&mut self, out: &mut [f64]) {
        const SCALE: f64 = 1.0 / 4_294_967_296.0;
        for chunk in out.chunks_mut(LANES) {
            let r = self.next();
            for (o, x) in chunk.iter_mut().zip(r) {
                *o = f64::from(x) * SCALE;
            }
        }
    }
}

/// The sum of the four bytes of `x` (0..=1020), as an `i32`.
#[inline(always)]
fn byte_sum(x: u32) -> i32 {
    let pairs = (x & 0x00ff_00ff) + ((x >> 8) & 0x00ff_00ff);
    // At most 1020 < 2³¹: the conversion is exact.
    ((pairs & 0xffff) + (pairs >> 16)) as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// xoshiro128++ from state {1, 2, 3, 4}: the published algorithm's first
    /// outputs (the same reference values as the attitude PF's test).
    #[test]
    fn xoshiro128pp_matches_the_reference() {
        let mut words = vec![0u32; 4 * LANES];
        for k in 0..4 {
            for l in 0..LANES {
                words[k * LANES + l] = k as u32 + 1;
            }
        }
        let mut n = Noise::from_state(&words).expect("valid state");
        for e in [641, 1_573_767, 3_222_811_527, 3_517_856_514] {
            assert_eq!(n.next()[LANES - 1], e);
        }
    }

    #[test]
    fn draws_have_their_moments_and_the_state_round_trips() {
        let mut n = Noise::new(42);
        let mut z = vec![0.0; 200_001];
        n.fill_normal(&mut z, 2.0);
        let m = z.iter().sum::<f64>() / z.len() as f64;
        let v = z.iter().map(|x| (x - m).powi(2)).sum::<f64>() / z.len() as f64;
        assert!(m.abs() < 0.02, "{m}");
        assert!((v - 4.0).abs() < 0.04, "{v}");
        let mut u = vec![0.0; 10_001];
        n.fill_uniform(&mut u);
        assert!(u.iter().all(|x| (0.0..1.0).contains(x)));
        assert!((u.iter().sum::<f64>() / u.len() as f64 - 0.5).abs() < 0.01);
        let copy = Noise::from_state(&n.state()).expect("round trip");
        assert_eq!(copy, n);
        assert!(Noise::from_state(&[0; 4 * LANES]).is_none());
        assert!(Noise::from_state(&[1; 3]).is_none());
    }
}
