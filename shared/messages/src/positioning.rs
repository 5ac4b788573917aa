//! The positioning role's messages from its estimator's values: a fix
//! (`positioning/fix`) and the snapshot of its state.

use nauta_estimation::positioning::{PositioningState, Saved};
use nauta_estimation::readings::Fix;

use crate::domain::{decode, pack, unpack};
use crate::{Header, PositionFix, PositioningSnapshot, Role, codec, fixed_str, to_fixed_str};

/// Bytes a [`PositioningSnapshot`] holds of the state.
pub const POSITIONING_STATE_BYTES: usize = 6 * 32 * 8;

impl From<&Fix> for PositionFix {
    fn from(f: &Fix) -> Self {
        PositionFix {
            header: Header::new(f.stamp_ns, 0, Role::Positioning, 0),
            lat_rad: f.lat_rad,
            lon_rad: f.lon_rad,
            std_north_m: f.std_north_m,
            std_east_m: f.std_east_m,
            corr_ne: f.corr_ne,
            effective_particles: f.effective_particles,
            fix_source: f.source,
            pad: 0,
        }
    }
}

impl PositioningSnapshot {
    /// The snapshot message of a saved state, after the input stamped
    /// `stamp_ns`. A state that does not fit (it cannot: the test below
    /// bounds it) or an unreadable one is sent empty, and refused on
    /// restore.
    pub fn of_saved(saved: &Saved, stamp_ns: u64) -> Self {
        let (bytes, variant) = match saved {
            Saved::State(s, v) => (
                bincode::serde::encode_to_vec(s.as_ref(), codec::config())
                    .ok()
                    .filter(|b| b.len() <= POSITIONING_STATE_BYTES)
                    .unwrap_or_default(),
                v.as_str(),
            ),
            Saved::Unreadable(_) => (Vec::new(), ""),
        };
        let mut m = PositioningSnapshot {
            header: Header::new(stamp_ns, 0, Role::Positioning, 0),
            variant: to_fixed_str(variant),
            state_len: bytes.len() as u32,
            pad: 0,
            state: [[0; 32]; 6],
        };
        pack(&bytes, &mut m.state);
        m
    }

    /// The saved state this message carries (checked again by the
    /// instance that restores it).
    pub fn saved(&self) -> Saved {
        let len = self.state_len as usize;
        if len == 0 || len > POSITIONING_STATE_BYTES {
            return Saved::Unreadable(format!("it holds {len} bytes of state"));
        }
        match decode::<PositioningState>(&unpack(&self.state, len)) {
            Ok(s) => Saved::State(Box::new(s), fixed_str(&self.variant)),
            Err(e) => Saved::Unreadable(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use nauta_estimation::Estimator;
    use nauta_estimation::frames::Vector;
    use nauta_estimation::positioning::{
        Positioning, PositioningEkfParams, PositioningInput, PositioningPfParams,
    };
    use nauta_estimation::readings::{Depth, Gps, Nav};

    use super::*;

    /// An estimator started at the surface and carried a while submerged.
    fn running(mut p: Positioning) -> Positioning {
        let mut out = Vec::new();
        let s = |t: f64| (t * 1e9) as u64;
        let inputs = [
            PositioningInput::Depth(Depth {
                stamp_ns: s(1.0),
                depth_m: 0.1,
            }),
            PositioningInput::Gps(Gps {
                stamp_ns: s(1.0),
                lat_rad: 0.67,
                lon_rad: -0.16,
                height_m: 0.0,
                horizontal_std_m: 2.0,
                quality: 1,
                velocity: None,
            }),
            PositioningInput::Depth(Depth {
                stamp_ns: s(200.0),
                depth_m: 15.0,
            }),
            PositioningInput::Nav(Nav {
                stamp_ns: s(201.0),
                lat_rad: 0.67,
                lon_rad: -0.16,
                depth_m: 15.0,
                vel_ned_m_s: Vector::from_array([1.5, 0.1, 0.0]),
                attitude: None,
                pos_std_ned_m: Vector::from_array([2.0; 3]),
                vel_std_ned_m_s: Vector::from_array([0.01; 3]),
                predicted_drift_m: 0.0,
                aiding_mode: 0,
                advisory: 0,
            }),
            PositioningInput::Depth(Depth {
                stamp_ns: s(300.0),
                depth_m: 15.0,
            }),
        ];
        for i in &inputs {
            p.on_input(i, &mut out).expect("input");
        }
        p
    }

    #[test]
    fn a_state_fits_and_round_trips() {
        for p in [
            Positioning::pf(&PositioningPfParams::default()).expect("pf"),
            Positioning::ekf(&PositioningEkfParams::default()).expect("ekf"),
        ] {
            let saved = running(p).snapshot().expect("a state");
            let Saved::State(state, _) = &saved else {
                panic!("{saved:?}")
            };
            let bytes =
                bincode::serde::encode_to_vec(state.as_ref(), codec::config()).expect("encode");
            assert!(
                bytes.len() <= POSITIONING_STATE_BYTES,
                "{} bytes",
                bytes.len()
            );
            let m = PositioningSnapshot::of_saved(&saved, 300);
            assert_eq!(m.saved(), saved);
            let mut cut = m;
            cut.state_len = 3;
            assert!(matches!(cut.saved(), Saved::Unreadable(_)));
            cut.state_len = 10_000;
            assert!(matches!(cut.saved(), Saved::Unreadable(_)));
        }
    }
}
