//! The attitude the velocity filter uses ([`super`] docs, "Attitude"):
//! carried by the gyro between corrections, and corrected towards the
//! attitude input by a small Kalman filter of the carried attitude's error
//! and the gyro's bias, which weighs the input by its published σ and by
//! what it errs by in a manoeuvre.
//!
//! Paper 000 §III-A resolves the specific force with the attitude PF's
//! estimate of §III-B as it comes. That estimate takes the accelerometer
//! for gravity, so in a turn it tilts by about the centripetal
//! acceleration over `g` (and its magnetic heading with it) while its
//! published σ does not change: on the survey, seed 7, 1.1° of roll and
//! 1.2° of yaw in the 10°/s turns, against 0.1-0.14° published, and each
//! 0.1° of tilt is 0.017 m/s² in the velocity filter's prediction. The
//! gyro carries the attitude through the turn; its bias is estimated here
//! (the attitude PF's own bias estimate was 3e-4 rad/s off on that survey,
//! a drift of 0.5° in 30 s).
//!
//! **Model** (Groves 2013 ch. 3, the Kalman filter, and ch. 14 for the
//! attitude error's propagation; equation numbers not checkable here).
//! State `x = [θ, δb]`: `θ` the carried attitude's error, NED
//! (`C = exp(θ) Ĉ`), `δb` the error of the gyro bias estimate `b̂`, FRD
//! (`ω = ω̃ − b̂ − δb`). `θ̇ = −Ĉ δb + w_g`, `δḃ = w_b`: over an interval
//! `T`, `Φ = [[I, −Σ Ĉ Δt], [0, I]]`, `Q = diag(q_g T I, q_b T I)` (`q_g`
//! the angle random walk squared, `q_b` the bias walk squared). An input
//! `q̃ = exp(δθ) q̂` (`δθ` the rotation vector from the carried attitude
//! to the input, NED) measures `θ` (`H = [I 0]`) with
//! `Rᵢ = max(σᵢ, floor)² + N k² m` (`σ` its published σ, `m` the
//! manoeuvre's squared tilt angle `|ω × v|² / g²`, held at its peak and
//! falling over `attitude_manoeuvre_time_s` ([`crate::ains::Manoeuvre`]),
//! `k` the manoeuvre factor, `N` the inputs used within that error's
//! correlation time, [`crate::ains::manoeuvre_var`]); the correction
//! `δx = K ν` is fed back (`q̂ ← exp(δθ̂) q̂`, `b̂ ← b̂ + δb̂`). At most one
//! input per `attitude_interval_s` is used: its error is correlated over
//! seconds.

use nalgebra::{Matrix3, SMatrix, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::frames::{Frd, Ned, Rotation, Vector};

use super::params::AinsPfConfig;

/// The error covariance of `[θ, δb]`.
type Cov6 = SMatrix<f64, 6, 6>;

/// The carried attitude's companions (the attitude itself is
/// [`super::ParticleAins`]'s `attitude`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct AttitudeTrack {
    /// The error covariance of `[θ (NED, rad), δb (FRD, rad/s)]`, upper
    /// triangle row by row.
    pub p_upper: [f64; 21],
    /// The gyro bias estimate, FRD, rad/s.
    pub gyro_bias_rad_s: [f64; 3],
    /// `Σ Ĉ Δt` since the last correction, row-major, s.
    pub c_dt: [f64; 9],
    /// `Σ Δt` since the last correction, s.
    pub t_s: f64,
    /// The manoeuvre measure of the input's error model.
    pub manoeuvre: crate::ains::Manoeuvre,
    /// Stamp of the last input that corrected the attitude, ns.
    pub last_update_ns: Option<u64>,
}

fn to_upper(p: &Cov6) -> [f64; 21] {
    let mut u = [0.0; 21];
    let mut k = 0;
    for i in 0..6 {
        for j in i..6 {
            u[k] = p[(i, j)];
            k += 1;
        }
    }
    u
}

fn from_upper(u: &[f64; 21]) -> Cov6 {
    let mut p = Cov6::zeros();
    let mut k = 0;
    for i in 0..6 {
        for j in i..6 {
            p[(i, j)] = u[k];
            p[(j, i)] = u[k];
            k += 1;
        }
    }
    p
}

impl AttitudeTrack {
    /// The gyro bias to remove from a sample.
    pub fn gyro_bias(&self) -> Vector<Frd> {
        Vector::from_array(self.gyro_bias_rad_s)
    }

    /// Whether every number is finite and the covariance's diagonal not
    /// negative (a snapshot's check).
    pub fn is_valid(&self) -> bool {
        let p = from_upper(&self.p_upper);
        self.p_upper.iter().all(|x| x.is_finite())
            && (0..6).all(|i| p[(i, i)] >= 0.0)
            && self.gyro_bias_rad_s.iter().all(|x| x.is_finite())
            && self.c_dt.iter().all(|x| x.is_finite())
            && self.t_s.is_finite()
            && self.t_s >= 0.0
            && self.manoeuvre.is_valid()
    }

    /// Starts over at an input of variance `r` per axis (the attitude is
    /// set to it), the gyro bias at `bias` with σ `bias_std`.
    pub fn anchor(&mut self, r: [f64; 3], bias: [f64; 3], bias_std: f64, t: u64) {
        let mut p = Cov6::zeros();
        for i in 0..3 {
            p[(i, i)] = r[i];
            p[(3 + i, 3 + i)] = bias_std * bias_std;
        }
        self.p_upper = to_upper(&p);
        self.gyro_bias_rad_s = bias;
        self.c_dt = [0.0; 9];
        self.t_s = 0.0;
        self.last_update_ns = Some(t);
    }

    /// One IMU sample of `dt` s at body rate `w` (bias-corrected), NED
    /// velocity `v`, gravity `g`, with the attitude `q` after it.
    pub fn predict(
        &mut self,
        c: &AinsPfConfig,
        q: &Rotation<Frd, Ned>,
        w: &Vector<Frd>,
        v: [f64; 3],
        g: f64,
        dt: f64,
    ) {
        let cm = q.as_nalgebra().to_rotation_matrix().into_inner();
        for i in 0..3 {
            for j in 0..3 {
                self.c_dt[3 * i + j] += cm[(i, j)] * dt;
            }
        }
        self.t_s += dt;
        let v_b = q.as_nalgebra().inverse_transform_vector(&Vector3::from(v));
        self.manoeuvre
            .update(&w.to_nalgebra(), &v_b, g, dt, c.attitude_manoeuvre_time_s);
    }

    /// The covariance propagated over the samples since the last
    /// correction (module docs).
    fn propagated(&self, c: &AinsPfConfig) -> Cov6 {
        let p = from_upper(&self.p_upper);
        let mut phi = Cov6::identity();
        let c_dt = Matrix3::from_row_slice(&self.c_dt);
        phi.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-c_dt));
        let mut next = phi * p * phi.transpose();
        for i in 0..3 {
            next[(i, i)] += c.attitude_gyro_noise * c.attitude_gyro_noise * self.t_s;
            next[(3 + i, 3 + i)] += c.attitude_bias_walk * c.attitude_bias_walk * self.t_s;
        }
        0.5 * (next + next.transpose())
    }

    /// The variance per axis of an input at `t` of published σ `std`.
    pub fn input_var(&self, c: &AinsPfConfig, std: [f64; 3], t: u64) -> [f64; 3] {
        let spacing = self
            .last_update_ns
            .map(|l| t.saturating_sub(l) as f64 * 1e-9);
        let m = crate::ains::manoeuvre_var(
            c.attitude_manoeuvre_factor,
            self.manoeuvre.tilt_sq_rad2,
            c.attitude_manoeuvre_time_s,
            spacing,
        );
        std.map(|s| {
            let s = s.max(c.attitude_std_floor);
            s * s + m
        })
    }

    /// `δθ`, the rotation vector (NED) from `q` to the input `z`.
    pub fn innovation(q: &Rotation<Frd, Ned>, z: &Rotation<Frd, Ned>) -> [f64; 3] {
        let d: UnitQuaternion<f64> = z.as_nalgebra() * q.as_nalgebra().inverse();
        d.scaled_axis().into()
    }

    /// The innovation's variance per axis (`P_θθ + R` on the diagonal,
    /// for the gate), with the covariance propagated to now.
    pub fn innovation_var(&self, c: &AinsPfConfig, r: [f64; 3]) -> [f64; 3] {
        let p = self.propagated(c);
        [0, 1, 2].map(|i| p[(i, i)] + r[i])
    }

    /// The Kalman correction of `q` by the innovation `nu` of variance `r`
    /// at `t` (module docs); the corrected attitude, or `None` when the
    /// innovation covariance is singular (state kept).
    pub fn correct(
        &mut self,
        c: &AinsPfConfig,
        q: &Rotation<Frd, Ned>,
        nu: [f64; 3],
        r: [f64; 3],
        t: u64,
    ) -> Option<Rotation<Frd, Ned>> {
        let p = self.propagated(c);
        let s = p.fixed_view::<3, 3>(0, 0) + Matrix3::from_diagonal(&Vector3::from(r));
        let s_inv = s.try_inverse()?;
        let k: SMatrix<f64, 6, 3> = p.fixed_view::<6, 3>(0, 0) * s_inv;
        let dx = k * Vector3::from(nu);
        let mut next = p - k * p.fixed_view::<3, 6>(0, 0);
        next = 0.5 * (next + next.transpose());
        self.p_upper = to_upper(&next);
        for i in 0..3 {
            self.gyro_bias_rad_s[i] += dx[3 + i];
        }
        self.c_dt = [0.0; 9];
        self.t_s = 0.0;
        self.last_update_ns = Some(t);
        let dq = UnitQuaternion::from_scaled_axis(Vector3::new(dx[0], dx[1], dx[2]));
        Some(Rotation::from_nalgebra(dq * q.as_nalgebra()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A constant gyro bias error is learnt from the attitude inputs: the
    /// carried attitude drifts with it between inputs, each input pulls it
    /// back, and the bias estimate converges to the true one.
    #[test]
    fn a_gyro_bias_error_is_learnt_from_the_inputs() {
        let c = super::super::AinsPfParams::default()
            .validate()
            .expect("valid");
        let true_bias = Vector3::new(3e-4, -2e-4, 1e-4);
        let mut track = AttitudeTrack::default();
        track.anchor([1e-6; 3], [0.0; 3], 1e-3, 0);
        let mut q = Rotation::<Frd, Ned>::identity();
        let dt = 0.01;
        for k in 1..=60_000u64 {
            // At rest: the gyro measures the bias alone; the carried
            // attitude integrates `ω̃ − b̂`.
            let w = true_bias - Vector3::from(track.gyro_bias_rad_s);
            let dq = UnitQuaternion::from_scaled_axis(w * dt);
            q = Rotation::from_nalgebra(q.as_nalgebra() * dq);
            track.predict(&c, &q, &Vector::from_nalgebra(w), [0.0; 3], 9.8, dt);
            if k % 100 == 0 {
                let nu = AttitudeTrack::innovation(&q, &Rotation::identity());
                q = track
                    .correct(&c, &q, nu, [3e-6; 3], k * 10_000_000)
                    .expect("regular");
            }
        }
        let b = Vector3::from(track.gyro_bias_rad_s);
        assert!((b - true_bias).norm() < 2e-5, "{b} vs {true_bias}");
        let e = AttitudeTrack::innovation(&q, &Rotation::identity());
        assert!(Vector3::from(e).norm() < 1e-4, "{e:?}");
    }
}
