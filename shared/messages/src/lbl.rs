//! The LBL role's messages from its estimator's values: `lbl/nav` (with the
//! uncertainty ellipse of `P_xy`, paper 003 §V-A), `lbl/interrogate`, and
//! the snapshot of its state.

use nauta_estimation::lbl::ellipse::Ellipse;
use nauta_estimation::lbl::{LblSaved, LblState, Ping};
use nauta_estimation::readings::LblNav;

use crate::domain::{decode, pack, unpack};
use crate::{Flags, Header, LblInterrogation, LblSnapshot, LblSolution, Role, codec, to_fixed_str};

/// Bytes an [`LblSnapshot`] holds of the state.
pub const LBL_STATE_BYTES: usize = 16 * 32 * 8;

impl From<&LblNav> for LblSolution {
    fn from(n: &LblNav) -> Self {
        let e = Ellipse::of([[n.p[0][0], n.p[0][1]], [n.p[1][0], n.p[1][1]]]);
        let mut header = Header::new(n.stamp_ns, 0, Role::Lbl, 0);
        if n.baseline_crossed {
            header.flags |= Flags::DEGRADED.0;
        }
        LblSolution {
            header,
            x_m: n.x_m,
            y_m: n.y_m,
            current_x_m_s: n.current_m_s[0],
            current_y_m_s: n.current_m_s[1],
            p: n.p,
            ellipse_major_m: e.major_m,
            ellipse_minor_m: e.minor_m,
            ellipse_orientation_rad: e.orientation_rad,
            last_innovation_m: n.last_innovation_m,
            transponder_id: n.transponder_id,
            accepted: u32::from(n.accepted),
        }
    }
}

impl From<&Ping> for LblInterrogation {
    fn from(p: &Ping) -> Self {
        LblInterrogation {
            header: Header::new(p.stamp_ns, 0, Role::Lbl, 0),
            transponder_id: p.transponder_id,
            pad: 0,
        }
    }
}

impl LblSnapshot {
    /// The snapshot message of a saved state, after the input stamped
    /// `stamp_ns`. A state that does not fit (the test below bounds it) or
    /// an unreadable one is sent empty, and refused on restore.
    pub fn of_saved(saved: &LblSaved, stamp_ns: u64) -> Self {
        let bytes = match saved {
            LblSaved::State(s) => bincode::serde::encode_to_vec(s.as_ref(), codec::config())
                .ok()
                .filter(|b| b.len() <= LBL_STATE_BYTES)
                .unwrap_or_default(),
            LblSaved::Unreadable(_) => Vec::new(),
        };
        let mut m = LblSnapshot {
            header: Header::new(stamp_ns, 0, Role::Lbl, 0),
            variant: to_fixed_str("ekf"),
            state_len: bytes.len() as u32,
            pad: 0,
            state: [[0; 32]; 16],
        };
        pack(&bytes, &mut m.state);
        m
    }

    /// The saved state this message carries (checked again by the instance
    /// that restores it).
    pub fn saved(&self) -> LblSaved {
        let len = self.state_len as usize;
        if len == 0 || len > LBL_STATE_BYTES {
            return LblSaved::Unreadable(format!("it holds {len} bytes of state"));
        }
        match decode::<LblState>(&unpack(&self.state, len)) {
            Ok(s) => LblSaved::State(Box::new(s)),
            Err(e) => LblSaved::Unreadable(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use nauta_estimation::Estimator;
    use nauta_estimation::lbl::layout::preset;
    use nauta_estimation::lbl::{Layout, Lbl, LblInput, LblOutput, LblParams, LblSite};
    use nauta_estimation::readings::{Ahrs, Depth, LblReplyReading, Propeller};

    use super::*;
    use crate::LblReply;

    fn running() -> Lbl {
        let p = LblParams {
            propeller_m_per_rad: Some(0.0105),
            initial_position_m: Some([100.0, 50.0]),
            ..Default::default()
        };
        let site = LblSite {
            origin_lat_rad: 0.67,
            origin_lon_rad: -0.16,
            declination_rad: 0.0,
            sound_speed_m_s: 1500.0,
            layout: Layout::new(preset("Four").expect("four")).expect("layout"),
        };
        let mut e = Lbl::new(&p, site).expect("valid");
        let mut out: Vec<LblOutput> = Vec::new();
        for k in 1..=30u64 {
            let t = k * 100_000_000;
            for i in [
                LblInput::Ahrs(Ahrs {
                    stamp_ns: t,
                    roll_rad: 0.0,
                    pitch_rad: 0.05,
                    heading_mag_rad: 1.0,
                }),
                LblInput::Depth(Depth {
                    stamp_ns: t,
                    depth_m: 10.0,
                }),
                LblInput::Propeller(Propeller {
                    stamp_ns: t,
                    shaft_speed_rad_s: 110.0,
                }),
            ] {
                e.on_input(&i, &mut out).expect("input");
            }
        }
        e
    }

    /// The biggest state (every history step, pending range and ping, a
    /// five-state filter) fits the message, and a snapshot round-trips.
    #[test]
    fn the_state_fits_and_round_trips() {
        let e = running();
        let mut s = e.state();
        s.history = {
            let mut h = nauta_estimation::lbl::history::History::default();
            for _ in 0..nauta_estimation::lbl::history::CAPACITY {
                h.push([1e300, -1e300]);
            }
            h
        };
        s.x.push(0.0105);
        s.p = vec![1e300; 25];
        for _ in 0..nauta_estimation::lbl::state::MAX_PENDING {
            s.pending.push(nauta_estimation::lbl::state::PendingRange {
                stamp_ns: u64::MAX,
                transponder_id: u32::MAX,
                range_m: 1e300,
                mid_ns: u64::MAX,
                reacquire: true,
                after_gap: true,
            });
        }
        for _ in 0..nauta_estimation::lbl::state::MAX_RECENT_PINGS {
            s.pings.recent.push(nauta_estimation::lbl::state::SentPing {
                transponder_id: u32::MAX,
                stamp_ns: u64::MAX,
                answered: true,
            });
        }
        let bytes = bincode::serde::encode_to_vec(&s, codec::config()).expect("encode");
        assert!(bytes.len() <= LBL_STATE_BYTES, "{} bytes", bytes.len());
        let m = LblSnapshot::of_saved(&LblSaved::State(Box::new(s.clone())), 7);
        match m.saved() {
            LblSaved::State(back) => assert_eq!(*back, s),
            LblSaved::Unreadable(e) => panic!("{e}"),
        }
        let mut empty = m;
        empty.state_len = 0;
        assert!(matches!(empty.saved(), LblSaved::Unreadable(_)));
    }

    #[test]
    fn a_solution_carries_its_ellipse_and_flag() {
        let e = running();
        let (x, p) = e.estimate().expect("started");
        let nav = LblNav {
            stamp_ns: 5,
            x_m: x[0],
            y_m: x[1],
            current_m_s: [x[2], x[3]],
            p: std::array::from_fn(|i| std::array::from_fn(|j| p[i * 4 + j])),
            last_innovation_m: 0.5,
            transponder_id: 2,
            accepted: true,
            baseline_crossed: true,
        };
        let m = LblSolution::from(&nav);
        assert!(m.ellipse_major_m >= m.ellipse_minor_m && m.ellipse_minor_m > 0.0);
        assert!((m.ellipse_major_m.powi(2) - nav.p[0][0].max(nav.p[1][1])).abs() < 1e-9);
        let back = LblNav::try_from(&m).expect("checked");
        assert_eq!(back, nav);
    }

    /// Non-finite, negative and absurd round trips never reach the filter.
    #[test]
    fn bad_replies_are_refused_at_the_port() {
        let ok = LblReply {
            header: Header::new(2_000_000_000, 0, Role::Sensor, 0),
            transponder_id: 1,
            pad: 0,
            interrogation_stamp_ns: 1_000_000_000,
            reply_stamp_ns: 2_000_000_000,
            round_trip_s: 0.5,
        };
        assert!(LblReplyReading::try_from(&ok).is_ok());
        for rt in [f64::NAN, f64::INFINITY, -0.1, 1e3] {
            let bad = LblReply {
                round_trip_s: rt,
                ..ok
            };
            assert!(LblReplyReading::try_from(&bad).is_err(), "{rt}");
        }
        let backwards = LblReply {
            interrogation_stamp_ns: 3_000_000_000,
            ..ok
        };
        assert!(LblReplyReading::try_from(&backwards).is_err());
    }
}
