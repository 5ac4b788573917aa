//! The `pf` started without a first fix (at the site, after waiting) or
//! from another variant's solution (a swap across variants,
//! [`crate::ains::seed`]).

use super::{AttitudeTrack, Moments, ParticleAins, err};
use crate::ains::pf::AinsPfStats;
use crate::ains::seed::NavSeed;
use crate::frames::Rotation;
use crate::role::EstimatorError;

impl ParticleAins {
    /// Continues from another variant's solution after its input stamped
    /// `stamp_ns`: both clouds drawn around it, Gaussian (as a warm
    /// restart draws them from a snapshot's moments), the position's
    /// origin at the seed's position, σ the seed's (the velocity's, when
    /// the seed has none, `initial_velocity_std_m_s`; every σ at least
    /// the filter's own floor); the particles' acceleration and drift
    /// errors at their priors; the attitude the seed's until the attitude
    /// input anchors the carried one. A seed without an attitude waits
    /// for the first attitude or AHRS sample.
    pub fn start_from(&mut self, seed: &NavSeed, stamp_ns: u64) -> Result<(), EstimatorError> {
        if !seed.is_valid() {
            return Err(err(
                "snapshot-refused",
                "the other variant's solution is not one",
            ));
        }
        let attitude = seed
            .attitude_wxyz
            .map(Rotation::from_wxyz)
            .transpose()
            .map_err(|e| err("snapshot-refused", e))?;
        let c = self.config;
        let bias = Moments {
            mean: 0.0,
            var: c.accel_bias_std * c.accel_bias_std,
        };
        let v_std = seed.vel_std_m_s.unwrap_or([c.initial_velocity_std; 3]);
        for ((comp, v), s) in self.vel.c.iter_mut().zip(seed.vel_ned_m_s).zip(v_std) {
            comp.spread(v, s.max(1e-3), bias, &mut self.noise);
        }
        let drift = Moments {
            mean: 0.0,
            var: c.drift_std * c.drift_std,
        };
        let [sn, se, sd] = seed.pos_std_ned_m;
        for (i, (m, s)) in [
            (0.0, sn.max(c.min_position_std)),
            (0.0, se.max(c.min_position_std)),
            (seed.depth_m, sd.max(c.depth_std)),
        ]
        .into_iter()
        .enumerate()
        {
            self.pos.c[i].spread(m, s, drift, &mut self.noise);
        }
        self.vel.refresh();
        self.pos.refresh();
        self.origin_rad = Some([seed.lat_rad, seed.lon_rad]);
        self.position_from_site = false;
        self.waiting_since_ns = None;
        self.attitude = attitude;
        self.attitude_from_estimate = false;
        self.track = AttitudeTrack::default();
        self.last_ns = [None; 5];
        self.last_stamp_ns = Some(stamp_ns);
        self.last_dvl_ned = None;
        self.last_depth_m = Some(seed.depth_m);
        self.tare.set_state(seed.tare);
        self.stats = AinsPfStats::default();
        self.skip_until_ns = Some(stamp_ns);
        Ok(())
    }

    /// Without a position `position_wait_s` after the first IMU sample with
    /// an attitude: the filters start at the site, σ
    /// `initial_position_std_m` north and east.
    pub(super) fn start_at_site_after_waiting(&mut self, t: u64) {
        let since = *self.waiting_since_ns.get_or_insert(t);
        if t.saturating_sub(since) < self.config.position_wait_ns {
            return;
        }
        let [lat, lon] = self.site_rad;
        let s = self.config.initial_position_std;
        self.initialise(lat, lon, [s, s], t);
        self.position_from_site = true;
        tracing::info!(
            waited_s = t.saturating_sub(since) as f64 * 1e-9,
            sigma_m = s,
            "no position came: the pf aided INS starts at the site"
        );
    }

    /// The first position after a start at the site: the horizontal
    /// particles are drawn around it (the origin moves there), the velocity
    /// and depth kept.
    pub(super) fn redraw_horizontal(&mut self, lat: f64, lon: f64, sigma: [f64; 2]) {
        let c = self.config;
        let drift = Moments {
            mean: 0.0,
            var: c.drift_std * c.drift_std,
        };
        for (comp, s) in self.pos.c.iter_mut().zip(sigma) {
            comp.spread(0.0, s, drift, &mut self.noise);
        }
        self.pos.refresh();
        self.origin_rad = Some([lat, lon]);
        self.position_from_site = false;
    }
}
