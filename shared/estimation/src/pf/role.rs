//! The particle filter as an attitude estimator of the role
//! ([`AttitudeEstimator`]).

use super::*;

impl AttitudeEstimator for ParticleFilter {
    /// [`ParticleFilter::propagate`]; a refused sample is counted in
    /// [`PfStats::predict_rejected`].
    fn predict(&mut self, gyro_rad_s: &Vector<Frd>, dt_s: f64) {
        if self.propagate(gyro_rad_s.as_nalgebra(), dt_s).is_err() {
            self.stats.predict_rejected += 1;
        }
    }

    /// [`ParticleFilter::update_aiding`] (counted in [`PfStats`]).
    fn update(&mut self, accel_m_s2: &Vector<Frd>, mag_ut: &Vector<Frd>) {
        self.update_aiding(accel_m_s2.as_nalgebra(), mag_ut.as_nalgebra());
    }

    /// The weighted-mean attitude and bias; `std_rad` from the particles'
    /// weighted spread about the estimate (N, E, D).
    fn estimate(&self) -> AttitudeOutput {
        AttitudeOutput {
            q_nb: Rotation::from_nalgebra(self.q_hat),
            std_rad: Vector::from_nalgebra(self.spread),
            gyro_bias: Vector::from_nalgebra(self.bias_hat),
        }
    }

    /// Attitude, bias, the weighted sample covariance of the particles (6×6,
    /// row-major) and the calibration bits.
    fn snapshot(&self) -> AttitudeStateSnapshot {
        let p = self.covariance();
        let mut covariance = [[0.0; 6]; 6];
        for (i, row) in covariance.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = p[(i, j)];
            }
        }
        AttitudeStateSnapshot {
            q: to_array(&self.q_hat),
            gyro_bias: self.bias_hat.into(),
            covariance,
            calibration: self.calibration,
        }
    }

    /// Re-seeds the particles around the snapshot: drawn from N(mean,
    /// covariance) of the snapshot (the configured initial covariance when it
    /// is all zeros, e.g. from the `gyro` variant), with the generator
    /// re-seeded from the configured seed and the snapshot's bits, so the
    /// same snapshot always gives the same particles. Keeps the parameters,
    /// site and magnetic reference; the rest detector starts over.
    fn restore(&mut self, s: &AttitudeStateSnapshot) -> Result<(), AttitudeRestoreError> {
        let (q, b) = s.checked()?;
        let (q, b) = (q.to_nalgebra(), b.to_nalgebra());
        let cov = Matrix6::from_fn(|i, j| s.covariance[i][j]);
        let cov = if cov.iter().all(|v| *v == 0.0) {
            let t = self.config.initial_tilt_std_rad;
            let h = self.config.initial_heading_std_rad;
            let sb = self.config.initial_bias_std_rad_s;
            Matrix6::from_diagonal(&Vector6::new(
                t * t,
                t * t,
                h * h,
                sb * sb,
                sb * sb,
                sb * sb,
            ))
        } else {
            let scale = cov.diagonal().amax();
            if (cov - cov.transpose()).amax() > 1e-9 * scale
                || !cov.diagonal().iter().all(|d| *d > 0.0)
            {
                return Err(AttitudeRestoreError::NotCovariance);
            }
            cov
        };
        let words =
            s.q.iter()
                .chain(&s.gyro_bias)
                .chain(s.covariance.iter().flatten())
                .map(|v| v.to_bits())
                .chain([u64::from(s.calibration)]);
        self.rng = Noise::new(self.config.seed ^ fnv1a(words));
        self.draw_particles(&q, &b, &cov);
        // The snapshot's quaternion bit for bit when it is unit to rounding
        // (a restored instance continues from exactly the published state).
        self.q_hat = Rotation::<Frd, Ned>::from_wxyz_exact(s.q).map_or(q, Rotation::to_nalgebra);
        self.bias_hat = b;
        self.calibration = s.calibration;
        self.last_gyro = None;
        self.rest.started = false;
        self.rest.still_s = 0.0;
        self.accel_lp = None;
        self.bias_walk_steps = 0;
        self.bias_walk_s = 0.0;
        self.noise_steps = 0;
        self.noise_s = 0.0;
        self.nav_pending = Vector3::zeros();
        Ok(())
    }
}
