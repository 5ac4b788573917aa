//! What one instance of the LBL estimator hands another (warm restart, hot
//! swap): its whole state, plain and serialisable (the snapshot message
//! carries it bincode-encoded), and its counters.

use serde::{Deserialize, Serialize};

use crate::lbl::history::History;

/// Pings remembered for matching replies (older ones are forgotten).
pub const MAX_RECENT_PINGS: usize = 32;
/// Replies and GPS fixes waiting for the next step, at most.
pub const MAX_PENDING: usize = 16;
/// Transponders whose refused ranges are remembered (the most recent).
pub const MAX_REFUSALS: usize = 4;

/// What the role counted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct LblStats {
    /// Filter steps taken (10 Hz).
    pub steps: u64,
    /// Interrogations sent.
    pub pings: u64,
    /// Interrogations given up without a reply (the timeout).
    pub timeouts: u64,
    /// Replies matched to a ping.
    pub replies: u64,
    /// Ranges used by the filter (re-acquisitions included).
    pub ranges_used: u64,
    /// Ranges refused by the gate γ.
    pub gated: u64,
    /// Ranges accepted by the re-acquisition rule.
    pub reacquisitions: u64,
    /// Replies whose round trip gives no possible range.
    pub bad_round_trip: u64,
    /// Replies from a transponder the layout does not have.
    pub unknown_transponder: u64,
    /// Replies to no interrogation of ours.
    pub no_interrogation: u64,
    /// A second reply to one interrogation.
    pub duplicate_replies: u64,
    /// Replies before the filter had a position or a depth.
    pub no_position: u64,
    /// GPS fixes that reset the position.
    pub gps_resets: u64,
    /// GPS fixes weighed as measurements.
    pub gps_used: u64,
    /// GPS fixes refused below the surface depth or without a fix.
    pub gps_refused: u64,
    /// Times the estimate crossed a two-transponder baseline.
    pub baseline_crossings: u64,
    /// Steps predicted with an input older than a second.
    pub stale_steps: u64,
    /// Gaps in the inputs longer than the step limit, bridged by one step.
    pub jumps: u64,
}

/// The last of each input the filter holds (zero-order hold over a step).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Held {
    /// AHRS roll, pitch, true heading (rad) and its stamp.
    pub attitude: Option<([f64; 3], u64)>,
    /// Shaft speed, rad/s, and its stamp.
    pub shaft: Option<(f64, u64)>,
    /// Depth, m, and its stamp.
    pub depth: Option<(f64, u64)>,
    /// The DVL's velocity over the ground north and east, m/s, and its stamp.
    pub ground_velocity: Option<([f64; 2], u64)>,
}

/// A range that passed the gate, to be applied at the next step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PendingRange {
    /// Reception stamp, ns.
    pub stamp_ns: u64,
    /// The transponder.
    pub transponder_id: u32,
    /// `r`, m.
    pub range_m: f64,
    /// The middle of the round trip, ns.
    pub mid_ns: u64,
    /// Accepted by the re-acquisition rule: the position's covariance is
    /// widened to the innovation first.
    pub reacquire: bool,
    /// The first range after `reacquire_s` without one: the position's
    /// correlation with the other states is dropped first (the error a long
    /// silence left is the heading's more than the current's).
    pub after_gap: bool,
}

/// A GPS fix at the surface, to be applied at the next step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PendingGps {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// North and east of the origin, m.
    pub position_m: [f64; 2],
    /// Variance per axis, m².
    pub var_m2: f64,
    /// The first fix of a surfacing: it resets the position.
    pub reset: bool,
}

/// One interrogation sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SentPing {
    /// The transponder.
    pub transponder_id: u32,
    /// When, ns.
    pub stamp_ns: u64,
    /// A reply came.
    pub answered: bool,
}

/// The interrogation schedule (paper 003 §V-D).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Pings {
    /// The ping waiting for its reply.
    pub outstanding: Option<SentPing>,
    /// The last ping's stamp, ns.
    pub last_ns: Option<u64>,
    /// Round robin's next index in the layout.
    pub next_in_turn: usize,
    /// Recent pings, oldest first, for matching replies.
    pub recent: Vec<SentPing>,
}

/// The last range looked at, for `lbl/nav`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct LastRange {
    /// `r − r*`, m.
    pub innovation_m: f64,
    /// The transponder (0 before any).
    pub transponder_id: u32,
    /// The gate accepted it.
    pub accepted: bool,
}

/// The state of the estimator (everything but its configuration).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LblState {
    /// `E` (4 or 5 states), once started.
    pub x: Vec<f64>,
    /// `P`, row-major, once started.
    pub p: Vec<f64>,
    /// The next step's stamp, ns, once there was an input.
    pub next_step_ns: Option<u64>,
    /// The held inputs.
    pub held: Held,
    /// The last steps' inputs.
    pub history: History,
    /// Ranges waiting for the next step.
    pub pending: Vec<PendingRange>,
    /// A GPS fix waiting for the next step.
    pub pending_gps: Option<PendingGps>,
    /// The interrogations.
    pub pings: Pings,
    /// The side of a two-transponder baseline the vehicle started on (sign).
    pub start_side: Option<f64>,
    /// The estimate is on the other side now.
    pub crossed: bool,
    /// The vehicle dived since the last GPS fix (the next one resets).
    pub submerged: bool,
    /// The last range looked at.
    pub last: LastRange,
    /// Ranges refused in a row.
    pub refused_in_row: u32,
    /// Per transponder (the last [`MAX_REFUSALS`] refused), its ranges
    /// refused in a row whose innovations agree.
    pub refusals: Vec<Refusals>,
    /// The last range accepted (or the start), ns.
    pub last_accept_ns: Option<u64>,
    /// The counters.
    pub stats: LblStats,
}

impl LblState {
    /// Whether every value is finite and within its bounds (a snapshot's
    /// check; the filter's dimension is checked by the estimator).
    pub fn is_valid(&self) -> bool {
        let n = self.x.len();
        let sized = (n == 0 && self.p.is_empty()) || ((n == 4 || n == 5) && self.p.len() == n * n);
        let finite = self.x.iter().chain(&self.p).all(|v| v.is_finite());
        let held = {
            let h = &self.held;
            h.attitude
                .is_none_or(|(a, _)| a.iter().all(|v| v.is_finite()))
                && h.shaft.is_none_or(|(v, _)| v.is_finite())
                && h.depth.is_none_or(|(v, _)| v.is_finite())
                && h.ground_velocity
                    .is_none_or(|(v, _)| v.iter().all(|x| x.is_finite()))
        };
        let pending = self.pending.len() <= MAX_PENDING
            && self.pending.iter().all(|r| r.range_m.is_finite())
            && self.pending_gps.is_none_or(|g| {
                g.position_m.iter().all(|v| v.is_finite()) && g.var_m2 > 0.0 && g.var_m2.is_finite()
            });
        let pings = self.pings.recent.len() <= MAX_RECENT_PINGS
            && self.refusals.len() <= MAX_REFUSALS
            && self.refusals.iter().all(|r| r.innovation_m.is_finite());
        let last = self.last.innovation_m.is_finite() && self.start_side.is_none_or(f64::is_finite);
        sized && finite && held && self.history.is_valid() && pending && pings && last
    }
}

/// One transponder's ranges refused in a row, their innovations agreeing.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Refusals {
    /// The transponder.
    pub transponder_id: u32,
    /// The last one's innovation `r − r*`, m.
    pub innovation_m: f64,
    /// How many.
    pub count: u32,
}

impl LblState {
    /// Notes a range of `id` refused with innovation `nu`: one more in its
    /// run when `nu` is within `tolerance_m` of the run's last, else a new
    /// run; the run's length.
    pub fn note_refusal(&mut self, id: u32, nu: f64, tolerance_m: f64) -> u32 {
        if let Some(r) = self.refusals.iter_mut().find(|r| r.transponder_id == id) {
            r.count = if (nu - r.innovation_m).abs() <= tolerance_m {
                r.count + 1
            } else {
                1
            };
            r.innovation_m = nu;
            return r.count;
        }
        if self.refusals.len() >= MAX_REFUSALS {
            self.refusals.remove(0);
        }
        self.refusals.push(Refusals {
            transponder_id: id,
            innovation_m: nu,
            count: 1,
        });
        1
    }

    /// A range of `id` was accepted: its run of refusals ends.
    pub fn clear_refusals(&mut self, id: u32) {
        self.refusals.retain(|r| r.transponder_id != id);
    }
}

/// What an LBL snapshot message carries: a state, or why it could not be
/// read (refused on restore).
#[derive(Debug, Clone, PartialEq)]
pub enum LblSaved {
    /// The state.
    State(Box<LblState>),
    /// Why the message did not decode.
    Unreadable(String),
}
