//! The particle cloud as a structure of arrays, and the loops over it that
//! run per sample: prediction (P1), the attitude errors and likelihoods
//! (P3), the weights and the moments of the estimate (eq. 47).
//!
//! Every loop runs over plain `f64` slices in particle order with no branch
//! that depends on the data, so that the compiler vectorises it; sums are
//! kept in [`LANES`] partial sums, added in a fixed order at the end, so the
//! result is the same bit for bit on every run (and every x86-64, the code
//! having no fused multiply-add).

use super::isa::{Isa, dispatch};
use super::math::{exp_nonpositive, exp_series, qmul};

/// Partial sums per reduction (two SSE2 registers of `f64`).
pub(super) const LANES: usize = 4;

/// The particles: attitude `[w, x, y, z]` (body → NED) in `q[0..4]`, gyro
/// bias (FRD, rad/s) in `b[0..3]`, log weight in `lw`, one entry per
/// particle in each.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Cloud {
    pub(super) q: [Vec<f64>; 4],
    pub(super) b: [Vec<f64>; 3],
    pub(super) lw: Vec<f64>,
}

/// Sums of the weighted moments (eq. 47 and the spread), with weights that
/// need not be normalised, about the reference `r` whose errors
/// `E_i = r ⊗ q_i⁻¹` they were taken from: `se = Σ w_i s_i E_i` (`s_i` the
/// sign of `E_i`'s `w`, i.e. of `q_i · r`: q and −q are one attitude),
/// `d2 = Σ w_i vec(E_i)²` per axis, `b = Σ w_i b_i`, `w = Σ w_i`,
/// `w2 = Σ w_i²`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Moments {
    pub(super) r: [f64; 4],
    pub(super) se: [f64; 4],
    pub(super) d2: [f64; 3],
    pub(super) b: [f64; 3],
    pub(super) w: f64,
    pub(super) w2: f64,
}

impl Moments {
    /// The sign-aligned weighted sum of the attitudes, `Σ w_i s_i q_i =
    /// conj(se) ⊗ r` (each `q_i = conj(E_i) ⊗ r`), not normalised.
    pub(super) fn attitude_sum(&self) -> [f64; 4] {
        let c = [self.se[0], -self.se[1], -self.se[2], -self.se[3]];
        qmul(&c, &self.r)
    }

    /// The weighted mean and standard deviation of the small-angle error
    /// `δθ_i = 2 s_i vec(q_i ⊗ r⁻¹) = −2 s_i vec(E_i)` per N, E, D axis
    /// (exact to third order: `log(q_i ⊗ r⁻¹)`).
    pub(super) fn spread(&self) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (k, o) in out.iter_mut().enumerate() {
            let mean = -2.0 * self.se[k + 1] / self.w;
            *o = (4.0 * self.d2[k] / self.w - mean * mean).max(0.0).sqrt();
        }
        out
    }
}

/// `Σ` of `LANES` partial sums, in lane order.
#[inline(always)]
pub(super) fn total(lanes: [f64; LANES]) -> f64 {
    lanes[1..].iter().fold(lanes[0], |a, b| a + b)
}

/// [`total`] of each of four sums' partial sums. Not inlined, on purpose:
/// the partial sums then leave the loop that made them as four stores of
/// [`LANES`] contiguous values, from which the compiler vectorises that loop
/// across the lanes (a register per sum). Inlined, it vectorised the loop
/// across the four sums instead, to take the four totals in one register,
/// with a shuffle per value loaded: three times the instructions (callgrind).
#[inline(never)]
fn totals(acc: &[[f64; LANES]; 4]) -> [f64; 4] {
    acc.map(total)
}

/// The largest of `LANES` partial maxima.
#[inline(always)]
fn largest(lanes: [f64; LANES]) -> f64 {
    lanes[1..].iter().fold(lanes[0], |a, b| a.max(*b))
}

impl Cloud {
    /// `n` particles at `q`, zero bias, log weight 0.
    pub(super) fn new(n: usize, q: [f64; 4]) -> Self {
        Self {
            q: q.map(|c| vec![c; n]),
            b: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            lw: vec![0.0; n],
        }
    }

    /// Number of particles.
    pub(super) fn len(&self) -> usize {
        self.lw.len()
    }

    /// Sets particle `i`'s attitude.
    pub(super) fn set_q(&mut self, i: usize, q: [f64; 4]) {
        for (k, v) in q.into_iter().enumerate() {
            self.q[k][i] = v;
        }
    }

    /// (P1) in the body frame: `q_i ← q_i ⊗ exp(θ_i)`,
    /// `θ_i = (ω̃ − b_i) Δt + η_i`, with `η` the three axes' draws one after
    /// the other (`3n` values), or `η = 0` without them. Not renormalised:
    /// `exp_series` is unit to `|θ|⁶/4608`, and [`Cloud::rotate_nav`]
    /// renormalises every 16 samples.
    pub(super) fn propagate(&mut self, isa: Isa, omega: [f64; 3], dt: f64, eta: Option<&[f64]>) {
        match eta {
            Some(eta) => propagate_noisy(isa, self, omega, dt, eta),
            None => propagate_plain(isa, self, omega, dt, &[]),
        }
    }

    /// `q_i ← nav ⊗ q_i` (the Earth rate of (P1), common to all particles),
    /// then one Newton step towards unit norm, `q ← q (3 − |q|²)/2`.
    pub(super) fn rotate_nav(&mut self, isa: Isa, nav: [f64; 4]) {
        rotate_nav(isa, self, nav);
    }

    /// `b_i ← b_i + ζ_i` with `ζ` the three axes' draws one after the other.
    pub(super) fn add_bias(&mut self, isa: Isa, zeta: &[f64]) {
        add_bias(isa, self, zeta);
    }

    /// The attitude errors `E_i = r ⊗ q_i⁻¹` into `e` (navigation frame;
    /// `E_i`'s `w` is `q_i · r`).
    pub(super) fn errors(&self, isa: Isa, r: &[f64; 4], e: &mut [Vec<f64>; 4]) {
        let n = self.len();
        for v in e.iter_mut() {
            v.resize(n, 0.0);
        }
        errors(isa, self, r, e);
    }

    /// Copies of the particles `parents` (in that order) into `out`.
    pub(super) fn gather(&self, parents: &[u32], out: &mut Cloud) {
        let src = self.q.iter().chain(&self.b).chain([&self.lw]);
        let dst = out.q.iter_mut().chain(&mut out.b).chain([&mut out.lw]);
        for (s, d) in src.zip(dst) {
            d.clear();
            d.extend(parents.iter().map(|&i| s[i as usize]));
        }
    }
}

/// [`Cloud::propagate`]'s loop, with the draws `eta` if `NOISE`.
#[inline(always)]
fn propagate_body<const NOISE: bool>(cloud: &mut Cloud, omega: [f64; 3], dt: f64, eta: &[f64]) {
    let n = cloud.len();
    let zeros = [0.0; 0];
    let (ex, ey, ez) = if NOISE {
        let (ex, rest) = eta.split_at(n);
        let (ey, ez) = rest.split_at(n);
        (ex, ey, &ez[..n])
    } else {
        (&zeros[..], &zeros[..], &zeros[..])
    };
    let [qw, qx, qy, qz] = &mut cloud.q;
    let (qw, qx, qy, qz) = (&mut qw[..n], &mut qx[..n], &mut qy[..n], &mut qz[..n]);
    let [bx, by, bz] = &cloud.b;
    let (bx, by, bz) = (&bx[..n], &by[..n], &bz[..n]);
    for i in 0..n {
        let mut theta = [
            (omega[0] - bx[i]) * dt,
            (omega[1] - by[i]) * dt,
            (omega[2] - bz[i]) * dt,
        ];
        if NOISE {
            theta[0] += ex[i];
            theta[1] += ey[i];
            theta[2] += ez[i];
        }
        let q = qmul(&[qw[i], qx[i], qy[i], qz[i]], &exp_series(theta));
        qw[i] = q[0];
        qx[i] = q[1];
        qy[i] = q[2];
        qz[i] = q[3];
    }
}

/// [`Cloud::rotate_nav`]'s loop.
#[inline(always)]
fn rotate_nav_body(cloud: &mut Cloud, nav: [f64; 4]) {
    let n = cloud.len();
    let [qw, qx, qy, qz] = &mut cloud.q;
    let (qw, qx, qy, qz) = (&mut qw[..n], &mut qx[..n], &mut qy[..n], &mut qz[..n]);
    for i in 0..n {
        let q = qmul(&nav, &[qw[i], qx[i], qy[i], qz[i]]);
        let n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
        let k = 1.5 - 0.5 * n2;
        qw[i] = q[0] * k;
        qx[i] = q[1] * k;
        qy[i] = q[2] * k;
        qz[i] = q[3] * k;
    }
}

/// [`Cloud::add_bias`]'s loop.
#[inline(always)]
fn add_bias_body(cloud: &mut Cloud, zeta: &[f64]) {
    let n = cloud.len();
    for (b, z) in cloud.b.iter_mut().zip(zeta.chunks_exact(n)) {
        for (b, z) in b.iter_mut().zip(z) {
            *b += z;
        }
    }
}

/// [`Cloud::errors`]'s loop (`e` already of the cloud's length).
#[inline(always)]
fn errors_body(cloud: &Cloud, r: &[f64; 4], e: &mut [Vec<f64>; 4]) {
    let n = cloud.len();
    let [e0, e1, e2, e3] = e;
    let (e0, e1, e2, e3) = (&mut e0[..n], &mut e1[..n], &mut e2[..n], &mut e3[..n]);
    let [qw, qx, qy, qz] = &cloud.q;
    let (qw, qx, qy, qz) = (&qw[..n], &qx[..n], &qy[..n], &qz[..n]);
    for i in 0..n {
        let (w, x, y, z) = (qw[i], qx[i], qy[i], qz[i]);
        e0[i] = r[0] * w + r[1] * x + r[2] * y + r[3] * z;
        e1[i] = -r[0] * x + r[1] * w - r[2] * z + r[3] * y;
        e2[i] = -r[0] * y + r[1] * z + r[2] * w - r[3] * x;
        e3[i] = -r[0] * z - r[1] * y + r[2] * x + r[3] * w;
    }
}

dispatch! {
    fn propagate_noisy(cloud: &mut Cloud, omega: [f64; 3], dt: f64, eta: &[f64]) = propagate_body::<true>;
}
dispatch! {
    fn propagate_plain(cloud: &mut Cloud, omega: [f64; 3], dt: f64, eta: &[f64]) = propagate_body::<false>;
}
dispatch! {
    fn rotate_nav(cloud: &mut Cloud, nav: [f64; 4]) = rotate_nav_body;
}
dispatch! {
    fn add_bias(cloud: &mut Cloud, zeta: &[f64]) = add_bias_body;
}
dispatch! {
    fn errors(cloud: &Cloud, r: &[f64; 4], e: &mut [Vec<f64>; 4]) = errors_body;
}

/// The aiding pair of (P3) about a reference `r`: `a = q_acc ⊗ r⁻¹`,
/// `m = q_mag ⊗ r⁻¹`, and the factors' precisions `k = 1/(2 s²)` (0 for a
/// factor left out).
#[derive(Debug, Clone, Copy)]
pub(super) struct AidAbout {
    pub(super) r: [f64; 4],
    pub(super) k_t: f64,
    pub(super) a: [f64; 4],
    pub(super) k_h: f64,
    pub(super) m: [f64; 4],
}

/// Where one likelihood pass writes: the errors, the log-likelihoods, the
/// weights and the signed weights.
#[derive(Debug)]
pub(super) struct PassOut<'a> {
    pub(super) e: &'a mut [Vec<f64>; 4],
    pub(super) delta: &'a mut Vec<f64>,
    pub(super) weights: &'a mut Vec<f64>,
    pub(super) signed: &'a mut Vec<f64>,
}

/// (P3) for every particle in one pass: its error `E_i = r ⊗ q_i⁻¹` (as
/// [`Cloud::errors`]); `q_acc ⊗ q_i⁻¹ = a ⊗ E_i`, whose x and y are the tilt
/// differences, and `q_mag ⊗ q_i⁻¹ = m ⊗ E_i`, whose z is the heading
/// difference; `δ_i = −k_t (x² + y²) − k_h z²`; `lw_i ← lw_i + α δ_i`; and
/// the weight `w_i = exp(lw_i)` with its signed copy `s_i w_i` (`s_i` the
/// sign of `E_i`'s `w`). Returns the largest `lw_i`: the weights are right
/// (not overflowed, not all underflowed) only if it is in `[−300, 0]`, which
/// holds when every `lw_i ≤ 0` on entry (the largest is 0 after each update
/// and after a resampling) and the likelihood is not far narrower than the
/// cloud; otherwise the caller weighs again about the largest.
#[inline(always)]
fn likelihood_pass_body(cloud: &mut Cloud, aid: &AidAbout, alpha: f64, out: PassOut<'_>) -> f64 {
    let n = cloud.len();
    for v in out.e.iter_mut() {
        v.resize(n, 0.0);
    }
    for v in [&mut *out.delta, &mut *out.weights, &mut *out.signed] {
        v.resize(n, 0.0);
    }
    let delta = &mut out.delta[..n];
    let weights = &mut out.weights[..n];
    let signed = &mut out.signed[..n];
    let [e0, e1, e2, e3] = out.e;
    let (e0, e1, e2, e3) = (&mut e0[..n], &mut e1[..n], &mut e2[..n], &mut e3[..n]);
    let [qw, qx, qy, qz] = &cloud.q;
    let (qw, qx, qy, qz) = (&qw[..n], &qx[..n], &qy[..n], &qz[..n]);
    let lw = &mut cloud.lw[..n];
    let AidAbout { r, k_t, a, k_h, m } = *aid;
    for i in 0..n {
        let (w, x, y, z) = (qw[i], qx[i], qy[i], qz[i]);
        let f0 = r[0] * w + r[1] * x + r[2] * y + r[3] * z;
        let f1 = -r[0] * x + r[1] * w - r[2] * z + r[3] * y;
        let f2 = -r[0] * y + r[1] * z + r[2] * w - r[3] * x;
        let f3 = -r[0] * z - r[1] * y + r[2] * x + r[3] * w;
        e0[i] = f0;
        e1[i] = f1;
        e2[i] = f2;
        e3[i] = f3;
        let dx = a[0] * f1 + a[1] * f0 + a[2] * f3 - a[3] * f2;
        let dy = a[0] * f2 - a[1] * f3 + a[2] * f0 + a[3] * f1;
        let dz = m[0] * f3 + m[1] * f2 - m[2] * f1 + m[3] * f0;
        let d = -(k_t * (dx * dx + dy * dy) + k_h * (dz * dz));
        delta[i] = d;
        let l = lw[i] + alpha * d;
        lw[i] = l;
        let wt = exp_nonpositive(l);
        weights[i] = wt;
        signed[i] = if f0 < 0.0 { -wt } else { wt };
    }
    let mut max = [f64::NEG_INFINITY; LANES];
    let (chunks, rest) = lw.as_chunks::<LANES>();
    for c in chunks {
        for j in 0..LANES {
            max[j] = max[j].max(c[j]);
        }
    }
    for v in rest {
        max[0] = max[0].max(*v);
    }
    largest(max)
}

/// `lw_i ← lw_i + α δ_i`; returns the largest `lw_i`.
#[inline(always)]
fn add_log_likelihoods_body(lw: &mut [f64], delta: &[f64], alpha: f64) -> f64 {
    let n = lw.len();
    let delta = &delta[..n];
    let mut max = [f64::NEG_INFINITY; LANES];
    let mut chunks = lw.chunks_exact_mut(LANES);
    let mut d_chunks = delta.chunks_exact(LANES);
    for (l, d) in (&mut chunks).zip(&mut d_chunks) {
        for j in 0..LANES {
            l[j] += alpha * d[j];
            max[j] = max[j].max(l[j]);
        }
    }
    for (l, d) in chunks.into_remainder().iter_mut().zip(d_chunks.remainder()) {
        *l += alpha * d;
        max[0] = max[0].max(*l);
    }
    largest(max)
}

/// The weights `w_i = exp(lw_i − max)` into `weights` (with `lw_i ← lw_i −
/// max`), and their moments about `r` from the errors `e` (taken about `r`);
/// `signed` is scratch.
#[inline(always)]
fn weigh_body(
    cloud: &mut Cloud,
    max: f64,
    e: &[Vec<f64>; 4],
    r: &[f64; 4],
    weights: &mut [f64],
    signed: &mut Vec<f64>,
) -> Moments {
    let n = cloud.len();
    let lw = &mut cloud.lw[..n];
    let weights = &mut weights[..n];
    for (l, w) in lw.iter_mut().zip(weights.iter_mut()) {
        *l -= max;
        *w = exp_nonpositive(*l);
    }
    moments_body(e, &cloud.b, weights, r, signed)
}

/// `v[..n]` as whole chunks of [`LANES`].
#[inline(always)]
fn chunks(v: &[f64], n: usize) -> &[[f64; LANES]] {
    v[..n].as_chunks::<LANES>().0
}

/// `acc[j] += x[j] · y[j]` over one chunk (vectorised).
#[inline(always)]
fn mul_add(acc: &mut [f64; LANES], x: &[f64; LANES], y: &[f64; LANES]) {
    for j in 0..LANES {
        acc[j] += x[j] * y[j];
    }
}

/// `acc[j] += w[j] · y[j]²` over one chunk (vectorised).
#[inline(always)]
fn mul_add_sq(acc: &mut [f64; LANES], w: &[f64; LANES], y: &[f64; LANES]) {
    for j in 0..LANES {
        acc[j] += w[j] * (y[j] * y[j]);
    }
}

/// The moments of the cloud with `weights` about `r`, from its errors `e`
/// taken about `r`; `signed` is scratch (`s_i w_i`).
#[inline(always)]
fn moments_body(
    e: &[Vec<f64>; 4],
    b: &[Vec<f64>; 3],
    weights: &[f64],
    r: &[f64; 4],
    signed: &mut Vec<f64>,
) -> Moments {
    let n = weights.len();
    signed.clear();
    signed.extend(
        weights
            .iter()
            .zip(&e[0][..n])
            .map(|(&w, &e0)| if e0 < 0.0 { -w } else { w }),
    );
    signed_moments_body(e, b, weights, signed, r)
}

/// [`moments`] with the signed weights `s_i w_i` already in `signed`.
#[inline(always)]
fn signed_moments_body(
    e: &[Vec<f64>; 4],
    b: &[Vec<f64>; 3],
    weights: &[f64],
    signed: &[f64],
    r: &[f64; 4],
) -> Moments {
    let n = weights.len();
    // Three passes of four sums each over whole chunks (particle i in
    // partial sum i mod LANES), then the rest.
    let full = n - n % LANES;
    let (sw, w) = (chunks(signed, full), chunks(weights, full));
    let (e0, e1, e2, e3) = (
        chunks(&e[0], full),
        chunks(&e[1], full),
        chunks(&e[2], full),
        chunks(&e[3], full),
    );
    let (bx, by, bz) = (
        chunks(&b[0], full),
        chunks(&b[1], full),
        chunks(&b[2], full),
    );
    let mut acc = [[0.0; LANES]; 4];
    for k in 0..full / LANES {
        mul_add(&mut acc[0], &sw[k], &e0[k]);
        mul_add(&mut acc[1], &sw[k], &e1[k]);
        mul_add(&mut acc[2], &sw[k], &e2[k]);
        mul_add(&mut acc[3], &sw[k], &e3[k]);
    }
    let se = totals(&acc);
    let mut acc = [[0.0; LANES]; 4];
    for k in 0..full / LANES {
        mul_add_sq(&mut acc[0], &w[k], &e1[k]);
        mul_add_sq(&mut acc[1], &w[k], &e2[k]);
        mul_add_sq(&mut acc[2], &w[k], &e3[k]);
        for j in 0..LANES {
            acc[3][j] += w[k][j];
        }
    }
    let d2w = totals(&acc);
    let mut acc = [[0.0; LANES]; 4];
    for k in 0..full / LANES {
        mul_add(&mut acc[0], &w[k], &bx[k]);
        mul_add(&mut acc[1], &w[k], &by[k]);
        mul_add(&mut acc[2], &w[k], &bz[k]);
        mul_add(&mut acc[3], &w[k], &w[k]);
    }
    let bw = totals(&acc);
    let mut m = Moments {
        r: *r,
        se,
        d2: [d2w[0], d2w[1], d2w[2]],
        b: [bw[0], bw[1], bw[2]],
        w: d2w[3],
        w2: bw[3],
    };
    for i in full..n {
        let w = weights[i];
        for (se, e) in m.se.iter_mut().zip(e) {
            *se += signed[i] * e[i];
        }
        for k in 0..3 {
            m.d2[k] += w * (e[k + 1][i] * e[k + 1][i]);
            m.b[k] += w * b[k][i];
        }
        m.w += w;
        m.w2 += w * w;
    }
    m
}

/// N_eff (eq. 46) of the weights `∝ exp(lw_i + α δ_i)`.
#[inline(always)]
fn ess_with_body(lw: &[f64], delta: &[f64], alpha: f64, scratch: &mut Vec<f64>) -> f64 {
    scratch.clear();
    scratch.extend(lw.iter().zip(delta).map(|(l, d)| l + alpha * d));
    let mut max = [f64::NEG_INFINITY; LANES];
    let mut chunks = scratch.chunks_exact(LANES);
    for c in &mut chunks {
        for j in 0..LANES {
            max[j] = max[j].max(c[j]);
        }
    }
    for v in chunks.remainder() {
        max[0] = max[0].max(*v);
    }
    let max = largest(max);
    if !max.is_finite() {
        return 0.0;
    }
    let (mut sum, mut sum_sq) = ([0.0; LANES], [0.0; LANES]);
    let mut chunks = scratch.chunks_exact(LANES);
    for c in &mut chunks {
        for j in 0..LANES {
            let w = exp_nonpositive(c[j] - max);
            sum[j] += w;
            sum_sq[j] += w * w;
        }
    }
    for v in chunks.remainder() {
        let w = exp_nonpositive(v - max);
        sum[0] += w;
        sum_sq[0] += w * w;
    }
    let (sum, sum_sq) = (total(sum), total(sum_sq));
    sum * sum / sum_sq
}

dispatch! {
    /// (P3) for every particle in one pass; see [`likelihood_pass_body`].
    pub(super) fn likelihood_pass(cloud: &mut Cloud, aid: &AidAbout, alpha: f64, out: PassOut<'_>) -> f64
        = likelihood_pass_body;
}
dispatch! {
    /// `lw_i ← lw_i + α δ_i`; returns the largest `lw_i`.
    pub(super) fn add_log_likelihoods(lw: &mut [f64], delta: &[f64], alpha: f64) -> f64
        = add_log_likelihoods_body;
}
dispatch! {
    /// The weights and their moments; see [`weigh_body`].
    pub(super) fn weigh(
        cloud: &mut Cloud,
        max: f64,
        e: &[Vec<f64>; 4],
        r: &[f64; 4],
        weights: &mut [f64],
        signed: &mut Vec<f64>,
    ) -> Moments = weigh_body;
}
dispatch! {
    /// The moments of the cloud; see [`moments_body`].
    pub(super) fn moments(
        e: &[Vec<f64>; 4],
        b: &[Vec<f64>; 3],
        weights: &[f64],
        r: &[f64; 4],
        signed: &mut Vec<f64>,
    ) -> Moments = moments_body;
}
dispatch! {
    /// [`moments`] with the signed weights given; see [`signed_moments_body`].
    pub(super) fn signed_moments(
        e: &[Vec<f64>; 4],
        b: &[Vec<f64>; 3],
        weights: &[f64],
        signed: &[f64],
        r: &[f64; 4],
    ) -> Moments = signed_moments_body;
}
dispatch! {
    /// N_eff (eq. 46) of the weights `∝ exp(lw_i + α δ_i)`.
    pub(super) fn ess_with(lw: &[f64], delta: &[f64], alpha: f64, scratch: &mut Vec<f64>) -> f64
        = ess_with_body;
}
