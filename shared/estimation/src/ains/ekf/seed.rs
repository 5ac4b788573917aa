//! The `ekf` started from another variant's solution (a swap across
//! variants, [`crate::ains::seed`]).

use super::{Ekf, EkfStats, Pending, Stamps, err};
use crate::ains::ekf::model::POS;
use crate::ains::seed::NavSeed;
use crate::frames::{Frd, Ned, Rotation};
use crate::role::EstimatorError;

/// The smallest σ taken from a seed, m or m/s: a seed may say 0 (a `dr`
/// position just reset by a fix of σ 0), which a covariance cannot hold.
const SEED_STD_FLOOR: f64 = 0.01;

impl Ekf {
    /// Continues from another variant's solution after its input stamped
    /// `stamp_ns`: the filter starts there as it starts at a first fix
    /// (module docs), with the seed's position, depth, velocity and
    /// attitude and their σ (the attitude's σ are the AHRS's priors: a
    /// seed has none), its biases and the heading source's error at their
    /// priors. A seed without an attitude waits for the first heading.
    pub fn start_from(&mut self, seed: &NavSeed, stamp_ns: u64) -> Result<(), EstimatorError> {
        if !seed.is_valid() {
            return Err(err(
                "snapshot-refused",
                "the other variant's solution is not one",
            ));
        }
        let attitude = match seed.attitude_wxyz {
            Some(q) => {
                let (r, p, y) = Rotation::<Frd, Ned>::from_wxyz(q)
                    .map_err(|e| err("snapshot-refused", e))?
                    .euler();
                Some([r, p, y, 0.0, 0.0, 0.0, 0.0])
            }
            None => None,
        };
        let floor = |s: f64| s.max(SEED_STD_FLOOR);
        let [sn, se, sd] = seed.pos_std_ned_m.map(floor);
        let v_std = seed
            .vel_std_m_s
            .map_or(self.config.initial_velocity_std, |s| {
                floor(s.into_iter().fold(0.0, f64::max))
            });
        let v = seed.vel_ned_m_s;
        self.filter = None;
        self.pending = Pending {
            position: Some([seed.lat_rad, seed.lon_rad, sn, se, 0.0]),
            velocity: Some([v[0], v[1], v[2], v_std]),
            attitude,
            from_ahrs: true,
        };
        self.stamps = Stamps {
            last: Some(stamp_ns),
            ..Default::default()
        };
        self.heading_source = 0;
        self.tare.set_state(seed.tare);
        self.stats = EkfStats::default();
        if self.try_initialise()
            && let Some(f) = self.filter.as_mut()
        {
            f.nav.height_m = -seed.depth_m;
            f.p[(POS + 2, POS + 2)] = sd * sd;
        }
        self.skip_until_ns = Some(stamp_ns);
        Ok(())
    }
}
