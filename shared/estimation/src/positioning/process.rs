//! The motion the positioning filters add to eq. 50 between two buoy
//! messages, per horizontal axis: the navigation's velocity errs by a
//! correction `c` that is a random walk of density `q_v²` (m²/s³), and the
//! position by a random walk of density `q_p²` (m²/s) besides. Over `Δt`:
//!
//! `p ← p + c Δt + w_p`, `c ← c + w_c`, with `(w_p, w_c)` zero-mean normal
//! of covariance `q_v² [[Δt³/3, Δt²/2], [Δt²/2, Δt]] + [[q_p² Δt, 0], [0,
//! 0]]` (the exact discretisation of the integrated random walk; Groves
//! 2013 §3.2.2, Bar-Shalom et al. 2001 §6.2 for the white-noise
//! acceleration model it is). One step over the time since the last message
//! is the same distribution as many small ones.

/// The random walk's densities.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Walk {
    /// `q_p`, m/√s.
    pub position_m_rt_s: f64,
    /// `q_v`, m/s/√s.
    pub velocity_m_s_rt_s: f64,
}

/// The factors that draw `(w_p, w_c)` from three standard normals `u₁, u₂,
/// u₃`: `w_c = velocity u₁`, `w_p = coupling u₁ + integrated u₂ +
/// position u₃` (a Cholesky factor of the covariance above).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Factors {
    /// `q_v √Δt`.
    pub velocity: f64,
    /// `q_v √Δt · Δt/2`.
    pub coupling: f64,
    /// `q_v √(Δt³/12)`.
    pub integrated: f64,
    /// `q_p √Δt`.
    pub position: f64,
}

impl Walk {
    /// The factors over `dt` s.
    pub fn factors(&self, dt: f64) -> Factors {
        let v = self.velocity_m_s_rt_s * dt.sqrt();
        Factors {
            velocity: v,
            coupling: v * dt / 2.0,
            integrated: self.velocity_m_s_rt_s * (dt * dt * dt / 12.0).sqrt(),
            position: self.position_m_rt_s * dt.sqrt(),
        }
    }

    /// The covariance over `dt` s for one axis, `[[pp, pc], [pc, cc]]`.
    pub fn covariance(&self, dt: f64) -> [[f64; 2]; 2] {
        let qv = self.velocity_m_s_rt_s.powi(2);
        let qp = self.position_m_rt_s.powi(2);
        [
            [qv * dt.powi(3) / 3.0 + qp * dt, qv * dt * dt / 2.0],
            [qv * dt * dt / 2.0, qv * dt],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_factors_give_the_covariance() {
        let w = Walk {
            position_m_rt_s: 0.03,
            velocity_m_s_rt_s: 2e-4,
        };
        let dt = 30.0;
        let k = w.factors(dt);
        let c = w.covariance(dt);
        let pp = k.coupling.powi(2) + k.integrated.powi(2) + k.position.powi(2);
        assert!((pp - c[0][0]).abs() < 1e-15, "{pp} {c:?}");
        assert!((k.coupling * k.velocity - c[0][1]).abs() < 1e-15);
        assert!((k.velocity.powi(2) - c[1][1]).abs() < 1e-15);
    }
}
