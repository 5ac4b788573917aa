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
