//! Paper 002 §1.3, eq. 7: the DVL spike filter.
//!
//! Between DVL samples the velocity is integrated from the IMU's specific
//! force; a DVL sample farther than a threshold from that prediction is a
//! spike and is replaced by the prediction; after a bounded number of
//! consecutive rejections the prediction is taken to have diverged and the
//! DVL is trusted again.
//!
//! Eq. 7 as printed adds the body velocity of the last accepted sample,
//! `v_b(t_{k−j})`, to the rotated integral of the navigation-frame
//! acceleration; that is exact only if the attitude did not change. Here
//! the sum is made in the navigation frame, as eq. 6's first line says
//! (`v̂_b(t_k) = R_b^n(Θ(t_k))ᵀ v̂_n(t_k)`):
//!
//! ```text
//! v̂_n(t_k) = R_b^n(Θ(t_{k−j})) v_b(t_{k−j}) + Σ_IMU (R_b^n(Θ) f + g_l) Δt
//! v̂_b(t_k) = R_b^n(Θ(t_k))ᵀ v̂_n(t_k)
//! ```
//!
//! with `g_l = (0, 0, γ(L, h))` the normal gravity (plumb-bob gravity,
//! eq. 5's `g − Ω × (Ω × r)`) and the Coriolis term `−2 Ω × v_n` left out,
//! as the paper does (2·10⁻⁴ m/s² at 1.5 m/s). `Θ` is the attitude held
//! from the last AHRS sample. The integration lasts at most `max_span_s`
//! (an accelerometer bias of 0.03 m/s² is 0.06 m/s after 2 s); past it (a
//! long DVL dropout) the prediction is the last predicted body velocity,
//! held (our addition: without it the first sample after a long dropout
//! cannot be judged, and a spike there was taken as the new reference and
//! made the next good samples look like spikes). Only before the first
//! DVL sample is there no prediction.

use nalgebra::Vector3;

use crate::frames::{Frd, Ned, Rotation, Vector};

/// The filter's state, plain (for a snapshot).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct SpikeState {
    /// `v̂_n`: the velocity integrated since the last accepted sample, NED,
    /// m/s (`None`: no prediction, the next sample is accepted).
    pub v_ned_pred_m_s: Option<[f64; 3]>,
    /// Time integrated since the last accepted sample, s.
    pub span_s: f64,
    /// Past `max_span_s`: the body velocity held as the prediction, FRD,
    /// m/s (the integration has stopped).
    pub v_body_held_m_s: Option<[f64; 3]>,
    /// Consecutive rejections so far.
    pub rejections: u32,
}

/// What the filter made of one DVL sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Decision {
    /// Accepted (within the threshold, or no prediction to compare with).
    Accepted,
    /// A spike: the prediction `v̂_b` (FRD, m/s) replaces it.
    Rejected([f64; 3]),
    /// Over the threshold, but after the largest number of consecutive
    /// rejections: the DVL is trusted again and the prediction restarts
    /// from it.
    TrustedAgain,
}

/// The checked settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpikeConfig {
    /// Compare at all (off: every sample is accepted).
    pub enabled: bool,
    /// Rejection threshold on `|ṽ_b − v̂_b|`, m/s.
    pub threshold_m_s: f64,
    /// Largest number of consecutive rejections.
    pub max_rejections: u32,
    /// Longest prediction, s.
    pub max_span_s: f64,
}

/// The DVL spike filter (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SpikeFilter {
    config: SpikeConfig,
    state: SpikeState,
}

fn rotation(euler: [f64; 3]) -> Rotation<Frd, Ned> {
    Rotation::from_euler(euler[0], euler[1], euler[2])
}

impl SpikeFilter {
    /// A filter with no prediction yet.
    pub fn new(config: SpikeConfig) -> Self {
        Self {
            config,
            state: SpikeState::default(),
        }
    }

    /// Integrates one IMU sample: specific force `f_b` (FRD, m/s²) over
    /// `dt_s`, at the attitude `euler` (roll, pitch, true yaw, rad), with
    /// normal gravity `gravity_m_s2`.
    pub fn on_imu(&mut self, f_b: [f64; 3], dt_s: f64, euler: [f64; 3], gravity_m_s2: f64) {
        if self.state.v_body_held_m_s.is_some() {
            return;
        }
        let Some(v) = &mut self.state.v_ned_pred_m_s else {
            return;
        };
        let a = (rotation(euler) * Vector::<Frd>::from_array(f_b)).to_nalgebra()
            + Vector3::new(0.0, 0.0, gravity_m_s2);
        for (vi, ai) in v.iter_mut().zip(a.iter()) {
            *vi += ai * dt_s;
        }
        self.state.span_s += dt_s;
        if self.state.span_s > self.config.max_span_s {
            self.state.v_body_held_m_s = self.predicted_body(euler);
        }
    }

    /// The prediction in the body frame at `euler`, `v̂_b`, if there is one.
    pub fn predicted_body(&self, euler: [f64; 3]) -> Option<[f64; 3]> {
        if let Some(v) = self.state.v_body_held_m_s {
            return Some(v);
        }
        self.state
            .v_ned_pred_m_s
            .map(|v| (rotation(euler).inverse() * Vector::<Ned>::from_array(v)).to_array())
    }

    /// Judges a DVL sample `v_b` (FRD, m/s) taken at `euler`.
    pub fn on_dvl(&mut self, v_b: [f64; 3], euler: [f64; 3]) -> Decision {
        // Judged only against a prediction the IMU carried forward: with no
        // IMU sample since the last accepted DVL sample (a log without an
        // IMU, such as A-KIT's 1 Hz DVL), the "prediction" would be that
        // last velocity, and every manoeuvre a spike.
        let predicted = self
            .predicted_body(euler)
            .filter(|_| self.state.span_s > 0.0 || self.state.v_body_held_m_s.is_some());
        let decision = match predicted {
            Some(p) if self.config.enabled => {
                let d = Vector3::from(v_b) - Vector3::from(p);
                if d.norm() <= self.config.threshold_m_s {
                    Decision::Accepted
                } else if self.state.rejections >= self.config.max_rejections {
                    Decision::TrustedAgain
                } else {
                    Decision::Rejected(p)
                }
            }
            _ => Decision::Accepted,
        };
        match decision {
            Decision::Accepted | Decision::TrustedAgain => {
                self.state = SpikeState {
                    v_ned_pred_m_s: Some(
                        (rotation(euler) * Vector::<Frd>::from_array(v_b)).to_array(),
                    ),
                    span_s: 0.0,
                    v_body_held_m_s: None,
                    rejections: 0,
                };
            }
            Decision::Rejected(_) => self.state.rejections += 1,
        }
        decision
    }

    /// Drops the prediction (the next DVL sample is accepted as it is).
    pub fn forget(&mut self) {
        self.state = SpikeState::default();
    }

    /// The state.
    pub fn state(&self) -> SpikeState {
        self.state
    }

    /// Replaces the state (a snapshot's; the caller checks it is finite).
    pub fn set_state(&mut self, state: SpikeState) {
        self.state = state;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f64 = 9.8;

    fn filter(max_rejections: u32) -> SpikeFilter {
        SpikeFilter::new(SpikeConfig {
            enabled: true,
            threshold_m_s: 0.3,
            max_rejections,
            max_span_s: 2.0,
        })
    }

    /// `n` IMU samples of 10 ms, level, accelerating forward at `a` m/s².
    fn imu(f: &mut SpikeFilter, n: usize, a: f64, euler: [f64; 3]) {
        // Level: the specific force is (a, 0, −g) in the body frame.
        for _ in 0..n {
            f.on_imu([a, 0.0, -G], 0.01, euler, G);
        }
    }

    #[test]
    fn the_prediction_follows_the_imu_and_a_spike_is_replaced() {
        let e = [0.0, 0.0, 1.0];
        let mut f = filter(3);
        assert_eq!(f.on_dvl([1.0, 0.0, 0.0], e), Decision::Accepted);
        imu(&mut f, 20, 0.5, e);
        let p = f.predicted_body(e).expect("prediction");
        assert!((p[0] - 1.1).abs() < 1e-12 && p[1].abs() < 1e-12 && p[2].abs() < 1e-12);
        assert_eq!(f.on_dvl([1.1, 0.01, 0.0], e), Decision::Accepted);
        imu(&mut f, 20, 0.0, e);
        match f.on_dvl([2.6, 0.0, 0.0], e) {
            Decision::Rejected(v) => assert!((v[0] - 1.1).abs() < 1e-12),
            d => panic!("{d:?}"),
        }
        assert_eq!(f.state().rejections, 1);
        imu(&mut f, 20, 0.0, e);
        assert_eq!(f.on_dvl([1.1, 0.0, 0.0], e), Decision::Accepted);
        assert_eq!(f.state().rejections, 0);
    }

    #[test]
    fn a_turn_keeps_the_prediction_in_the_body_frame() {
        // At 1 m/s, a 90° turn right between two samples: the body velocity
        // stays forward (the NED velocity was integrated through the turn
        // with the centripetal force).
        let mut f = filter(3);
        assert_eq!(f.on_dvl([1.0, 0.0, 0.0], [0.0; 3]), Decision::Accepted);
        let (n, w) = (100, std::f64::consts::FRAC_PI_2);
        for k in 0..n {
            let yaw = (k as f64 + 0.5) * 0.01 * w;
            // Centripetal force to starboard: v ω.
            f.on_imu([0.0, w, -G], 0.01, [0.0, 0.0, yaw], G);
        }
        let p = f
            .predicted_body([0.0, 0.0, std::f64::consts::FRAC_PI_2])
            .expect("prediction");
        assert!((p[0] - 1.0).abs() < 1e-3 && p[1].abs() < 1e-3, "{p:?}");
    }

    #[test]
    fn after_the_largest_number_of_rejections_the_dvl_is_trusted_again() {
        let e = [0.0; 3];
        let mut f = filter(2);
        f.on_dvl([1.0, 0.0, 0.0], e);
        for _ in 0..2 {
            imu(&mut f, 20, 0.0, e);
            assert!(matches!(
                f.on_dvl([2.0, 0.0, 0.0], e),
                Decision::Rejected(_)
            ));
        }
        imu(&mut f, 20, 0.0, e);
        assert_eq!(f.on_dvl([2.0, 0.0, 0.0], e), Decision::TrustedAgain);
        imu(&mut f, 20, 0.0, e);
        assert_eq!(f.on_dvl([2.0, 0.0, 0.0], e), Decision::Accepted);
    }

    #[test]
    fn past_the_longest_integration_the_body_velocity_is_held_and_off_accepts_everything() {
        let mut f = filter(5);
        assert_eq!(f.predicted_body([0.0; 3]), None);
        f.on_dvl([1.0, 0.0, 0.0], [0.0; 3]);
        // Accelerating at 0.1 m/s² for 3 s: the integration stops at 2 s.
        imu(&mut f, 300, 0.1, [0.0; 3]);
        let held = f.predicted_body([0.0, 0.0, 2.0]).expect("held");
        assert!(
            (held[0] - 1.2).abs() < 0.002 && held[1].abs() < 1e-12,
            "{held:?}"
        );
        // A spike after the long gap is still caught.
        assert!(matches!(
            f.on_dvl([3.0, 0.0, 0.0], [0.0, 0.0, 2.0]),
            Decision::Rejected(_)
        ));
        let e = [0.0; 3];
        assert_eq!(f.on_dvl([1.25, 0.0, 0.0], e), Decision::Accepted);
        let mut off = SpikeFilter::new(SpikeConfig {
            enabled: false,
            ..f.config
        });
        off.on_dvl([1.0, 0.0, 0.0], e);
        imu(&mut off, 20, 0.0, e);
        assert_eq!(off.on_dvl([3.0, 0.0, 0.0], e), Decision::Accepted);
    }
}
