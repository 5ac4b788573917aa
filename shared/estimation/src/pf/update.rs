//! The filter's update with one aiding pair (P2)-(P6): the likelihood of
//! each particle, tempering when the weights would collapse, the rest-time
//! bias update, and selection-and-replacement resampling.

use super::isa::dispatch;
use super::*;

/// What one aiding pair says (P3): the factors' precisions `1/(2 s²)` (0:
/// factor left out) and their references.
#[derive(Debug, Clone, Copy)]
pub(super) struct Aid {
    k_t: f64,
    q_acc: [f64; 4],
    k_h: f64,
    q_mag: [f64; 4],
}

/// `a ⊗ b⁻¹` of `[w, x, y, z]` arrays (`b` unit).
fn qmul_inv(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    math::qmul(a, &[b[0], -b[1], -b[2], -b[3]])
}

impl ParticleFilter {
    /// Updates (P2)-(P6) with one specific force (m/s², FRD) and one
    /// calibrated field (µT, FRD); returns what each sensor did.
    pub fn update_aiding(
        &mut self,
        accel_m_s2: &Vector3<f64>,
        mag_ut: &Vector3<f64>,
    ) -> (AidingUse, AidingUse) {
        let dt = self.last_gyro.map_or(0.01, |(_, dt)| dt);
        let accel_ok = finite3(accel_m_s2) && accel_m_s2.norm() > 0.0;
        let rest = accel_ok && self.update_rest(accel_m_s2);

        // (P2)/(P4), tilt.
        let g = self.gravity_m_s2;
        let mut tilt = AidingUse::Invalid;
        let mut k_t = 0.0;
        let mut q_acc = [0.0; 4];
        if accel_ok {
            // The specific force in the navigation frame, with the estimate
            // half a gyro interval back (an interval average), low-passed
            // there (P2'): accelerations that come and go average out.
            let half_back = match self.last_gyro {
                Some((w, dt)) => quat_from_rotation_vector(&((self.bias_hat - w) * (0.5 * dt))),
                None => UnitQuaternion::identity(),
            };
            let f_n = (self.q_hat * half_back) * accel_m_s2;
            // At rest there is nothing to average: the low-pass restarts
            // from the current sample, without its lag.
            let tau = self.config.accel_lowpass_s;
            self.accel_lp = match self.accel_lp {
                Some(lp) if tau > 0.0 && !rest => Some(lp + (f_n - lp) * (dt / (tau + dt))),
                _ => Some(f_n),
            };
            let lp = self.accel_lp.unwrap_or(f_n);
            let norm = lp.norm();
            let deviation = norm - g;
            if !(deviation.abs() <= self.config.accel_gate_m_s2 && norm > 0.0) {
                tilt = AidingUse::Gated;
            } else {
                let v = lp / norm;
                let r = Vector3::new(0.0, 0.0, -1.0);
                let axis = v.cross(&r);
                let s = axis.norm();
                let theta = if s > 0.0 {
                    axis * (s.atan2(v.dot(&r)) / s)
                } else {
                    Vector3::zeros()
                };
                let var = self.config.accel_noise_m_s2_rt_hz.powi(2) / (dt * g * g)
                    + self.config.tilt_noise_rad_rt_s.powi(2) / dt
                    + (deviation / g).powi(2);
                let s_t = (0.5 * var.sqrt()).sin();
                k_t = 0.5 / (s_t * s_t);
                q_acc = to_array(&(quat_from_rotation_vector(&theta) * self.q_hat));
                tilt = AidingUse::Used;
            }
        }

        // (P2)/(P4), heading.
        let mut heading = AidingUse::Invalid;
        let mut k_h = 0.0;
        let mut q_mag = [0.0; 4];
        let m_norm = mag_ut.norm();
        let repeated = self.last_mag == Some(*mag_ut);
        self.last_mag = Some(*mag_ut);
        if repeated {
            heading = AidingUse::Repeated;
        } else if finite3(mag_ut) && m_norm > 0.0 {
            let ratio = m_norm / self.magnetic.field_ut();
            let m_n = self.q_hat * mag_ut;
            let horizontal = m_n.x.hypot(m_n.y);
            let dip = m_n.z.atan2(horizontal);
            let dip_diff = dip - self.magnetic.dip_rad();
            if !(horizontal > 0.0) {
                heading = AidingUse::Invalid;
            } else if !((ratio - 1.0).abs() <= self.config.mag_norm_gate
                && dip_diff.abs() <= self.config.mag_dip_gate_rad)
            {
                heading = AidingUse::Gated;
            } else {
                let psi = wrap_pi(self.declination_rad - m_n.y.atan2(m_n.x));
                let var = self.config.heading_noise_rad_rt_s.powi(2) / dt
                    + (self.config.mag_noise_ut
                        / (self.magnetic.field_ut() * self.magnetic.dip_rad().cos()))
                    .powi(2)
                    + (ratio - 1.0).powi(2)
                    + dip_diff * dip_diff;
                let s_h = (0.5 * var.sqrt()).sin();
                k_h = 0.5 / (s_h * s_h);
                q_mag = to_array(&(quat_from_rotation_vector(&(Vector3::z() * psi)) * self.q_hat));
                heading = AidingUse::Used;
            }
        }

        // (P5): the gyro as a bias measurement at rest.
        if let (true, Some((w, _))) = (rest, self.last_gyro) {
            let earth_b = self.q_hat.inverse_transform_vector(&self.omega_ie_n);
            self.rest_bias_update(&(w - earth_b));
            self.stats.rest_samples += 1;
        }

        match tilt {
            AidingUse::Used => self.stats.tilt_used += 1,
            AidingUse::Gated => self.stats.tilt_gated += 1,
            AidingUse::Invalid | AidingUse::Repeated => self.stats.tilt_invalid += 1,
        }
        match heading {
            AidingUse::Used => self.stats.heading_used += 1,
            AidingUse::Gated => self.stats.heading_gated += 1,
            AidingUse::Invalid => self.stats.heading_invalid += 1,
            AidingUse::Repeated => self.stats.heading_repeated += 1,
        }
        if k_t == 0.0 && k_h == 0.0 {
            return (tilt, heading);
        }

        // (P3), with progressive correction (P7).
        let prior = self.q_hat;
        let aid = Aid {
            k_t,
            q_acc,
            k_h,
            q_mag,
        };
        let n = self.particles.len() as f64;
        let n_th = self.config.resample_threshold * n;
        let mut delta = std::mem::take(&mut self.delta);
        let mut remaining = 1.0;
        for stage in 0..=MAX_TEMPER_STAGES {
            // (P3) about the current estimate r: E_i = r ⊗ q_i⁻¹ once, the
            // aiding references as a ⊗ r⁻¹.
            let r = to_array(&self.q_hat);
            let about = cloud::AidAbout {
                r,
                k_t: aid.k_t,
                a: qmul_inv(&aid.q_acc, &r),
                k_h: aid.k_h,
                m: qmul_inv(&aid.q_mag, &r),
            };
            let max = cloud::likelihood_pass(
                self.isa,
                &mut self.particles,
                &about,
                remaining,
                cloud::PassOut {
                    e: &mut self.errors,
                    delta: &mut delta,
                    weights: &mut self.weights,
                    signed: &mut self.signed,
                },
            );
            let sum_sq = self.finish_pass(max, &delta, &r);
            if stage == MAX_TEMPER_STAGES || n_th < 1.0 || 1.0 / sum_sq >= n_th {
                // (P6): eq. 46 and resampling.
                if 1.0 / sum_sq < n_th {
                    self.resample();
                }
                break;
            }
            // (P7): too few effective particles for the whole likelihood.
            // Undo it, apply the largest fraction that keeps N_eff at N_th
            // (bisection; N_eff falls as the fraction grows), resample, go on.
            for (l, d) in self.particles.lw.iter_mut().zip(&delta) {
                *l -= remaining * d;
            }
            let (mut lo, mut hi) = (0.0, remaining);
            for _ in 0..BISECTION_STEPS {
                let mid = 0.5 * (lo + hi);
                if cloud::ess_with(
                    self.isa,
                    &self.particles.lw,
                    &delta,
                    mid,
                    &mut self.exponents,
                ) >= n_th
                {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let alpha = lo.max(remaining / f64::from(1u32 << BISECTION_STEPS));
            self.apply_log_likelihoods(&delta, alpha, &r);
            remaining -= alpha;
            self.stats.tempering_stages += 1;
            self.resample();
        }
        self.delta = delta;
        // The low-passed specific force follows the correction (P2').
        if let Some(lp) = self.accel_lp {
            self.accel_lp = Some((self.q_hat * prior.inverse()) * lp);
        }
        (tilt, heading)
    }

    /// (P5): the Kalman update of the biases with the measurement `z` (rad/s)
    /// of variance σ_r² per axis, applied to the cloud as a shift and a
    /// contraction (per axis: `K = P/(P + σ_r²)`, mean `b̂ + K (z − b̂)`,
    /// deviations scaled by `√(1 − K)`). The measurement is linear and
    /// Gaussian in the bias alone, so this is the exact update of a Gaussian
    /// cloud; unlike a reweighting it cannot run out of particles near `z`.
    pub(super) fn rest_bias_update(&mut self, z: &Vector3<f64>) {
        let r = self.rest.gyro_var.max(REST_VARIANCE_FLOOR);
        let b_hat: [f64; 3] = self.bias_hat.into();
        let var = bias_variance(self.isa, &self.particles.b, &self.weights, b_hat);
        let mut shift = [0.0; 3];
        let mut scale = [1.0; 3];
        for (k, (sh, sc)) in shift.iter_mut().zip(scale.iter_mut()).enumerate() {
            let gain = var[k] / (var[k] + r);
            *sh = gain * (z[k] - b_hat[k]);
            *sc = (1.0 - gain).sqrt();
        }
        if !(shift.iter().chain(&scale).all(|v| v.is_finite())) {
            return;
        }
        shift_biases(self.isa, &mut self.particles.b, b_hat, shift, scale);
        self.bias_hat += Vector3::from(shift);
    }

    /// Normalises the weights of [`cloud::likelihood_pass`] (whose largest
    /// log weight is `max`) and takes the estimate, with the errors in
    /// `self.errors` taken about `r`; returns `Σ w_i²`. Weighs again about
    /// `max` when the pass's weights could not be used.
    fn finish_pass(&mut self, max: f64, delta: &[f64], r: &[f64; 4]) -> f64 {
        if !max.is_finite() {
            // Cannot happen with finite inputs; the weights restart equal.
            let n = self.particles.len() as f64;
            self.particles.lw.iter_mut().for_each(|l| *l = 0.0);
            self.weights.iter_mut().for_each(|w| *w = 1.0 / n);
            self.refresh_estimate();
            return 1.0 / n;
        }
        if !(-300.0..=0.0).contains(&max) {
            // The log weights already hold the likelihood: weigh about the
            // largest.
            return self.apply_log_likelihoods(delta, 0.0, r);
        }
        let m = cloud::signed_moments(
            self.isa,
            &self.errors,
            &self.particles.b,
            &self.weights,
            &self.signed,
            r,
        );
        self.normalise(&m, max)
    }

    /// Divides the weights by their sum and shifts the log weights by
    /// `-shift` (their largest then 0), takes the estimate from `m`; returns
    /// `Σ w_i²` of the normalised weights.
    fn normalise(&mut self, m: &Moments, shift: f64) -> f64 {
        let inv = 1.0 / m.w;
        normalise_weights(
            self.isa,
            &mut self.particles.lw,
            &mut self.weights,
            shift,
            inv,
        );
        self.finish_moments(m);
        m.w2 * inv * inv
    }

    /// Adds `alpha` times the log-likelihoods to the log weights, normalises
    /// the weights and takes the estimate in the same pass, with the errors
    /// in `self.errors` taken about `r`; returns `Σ w_i²`.
    pub(super) fn apply_log_likelihoods(&mut self, delta: &[f64], alpha: f64, r: &[f64; 4]) -> f64 {
        let max_lw = cloud::add_log_likelihoods(self.isa, &mut self.particles.lw, delta, alpha);
        if !max_lw.is_finite() {
            // Cannot happen with finite inputs; keep the previous weights.
            for (l, w) in self.particles.lw.iter_mut().zip(&self.weights) {
                *l = w.ln();
            }
            return self.weights.iter().map(|w| w * w).sum();
        }
        let m = cloud::weigh(
            self.isa,
            &mut self.particles,
            max_lw,
            &self.errors,
            r,
            &mut self.weights,
            &mut self.signed,
        );
        self.normalise(&m, 0.0)
    }

    /// (P6): residual resampling, then the shrinkage kernel; equal weights.
    pub(super) fn resample(&mut self) {
        let r = to_array(&self.q_hat);
        self.particles.errors(self.isa, &r, &mut self.errors);
        let cov = resample::cloud_covariance(
            self.isa,
            &self.particles,
            &self.errors,
            &self.weights,
            &self.bias_hat,
        );
        let l = resample::cholesky_floor(&cov);
        resample::residual(&self.weights, &mut self.parents, &mut self.rng);
        self.particles.gather(&self.parents, &mut self.scratch);
        std::mem::swap(&mut self.particles, &mut self.scratch);
        self.particles.lw.iter_mut().for_each(|l| *l = 0.0);
        resample::regularise(
            self.isa,
            &mut self.particles,
            &r,
            &self.bias_hat,
            &l,
            &mut self.rng,
            &mut self.errors,
            &mut self.normals,
        );
        let n = self.particles.len() as f64;
        self.weights.iter_mut().for_each(|w| *w = 1.0 / n);
        self.refresh_estimate();
        self.stats.resamples += 1;
    }
}

dispatch! {
    /// `Σ w_i (b_i − b̂)²` per axis (P5).
    fn bias_variance(b: &[Vec<f64>; 3], weights: &[f64], b_hat: [f64; 3]) -> [f64; 3]
        = bias_variance_body;
}

/// [`bias_variance`]'s loops.
#[inline(always)]
fn bias_variance_body(b: &[Vec<f64>; 3], weights: &[f64], b_hat: [f64; 3]) -> [f64; 3] {
    let mut var = [0.0; 3];
    for (k, v) in var.iter_mut().enumerate() {
        let mut lanes = [0.0; cloud::LANES];
        let mut chunks = b[k].chunks_exact(cloud::LANES);
        let mut w_chunks = weights.chunks_exact(cloud::LANES);
        for (b, w) in (&mut chunks).zip(&mut w_chunks) {
            for j in 0..cloud::LANES {
                let d = b[j] - b_hat[k];
                lanes[j] += w[j] * d * d;
            }
        }
        for (b, w) in chunks.remainder().iter().zip(w_chunks.remainder()) {
            let d = b - b_hat[k];
            lanes[0] += w * d * d;
        }
        *v = cloud::total(lanes);
    }
    var
}

dispatch! {
    /// (P5) on the cloud: `b_i ← b̂ + shift + scale (b_i − b̂)` per axis.
    fn shift_biases(b: &mut [Vec<f64>; 3], b_hat: [f64; 3], shift: [f64; 3], scale: [f64; 3])
        = shift_biases_body;
}

/// [`shift_biases`]'s loop.
#[inline(always)]
fn shift_biases_body(b: &mut [Vec<f64>; 3], b_hat: [f64; 3], shift: [f64; 3], scale: [f64; 3]) {
    for (k, b) in b.iter_mut().enumerate() {
        let (c, sc) = (b_hat[k], scale[k]);
        let sh = c + shift[k];
        for b in b.iter_mut() {
            *b = sh + sc * (*b - c);
        }
    }
}

dispatch! {
    /// `lw_i ← lw_i − shift`, `w_i ← w_i · inv`.
    fn normalise_weights(lw: &mut [f64], weights: &mut [f64], shift: f64, inv: f64)
        = normalise_weights_body;
}

/// [`normalise_weights`]'s loop.
#[inline(always)]
fn normalise_weights_body(lw: &mut [f64], weights: &mut [f64], shift: f64, inv: f64) {
    for (l, w) in lw.iter_mut().zip(weights.iter_mut()) {
        *l -= shift;
        *w *= inv;
    }
}
