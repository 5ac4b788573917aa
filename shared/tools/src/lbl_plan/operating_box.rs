//! Paper 003 Fig. 4: the desirable operating area of a two-transponder
//! baseline. "The minimum distance to the baseline is one fourth of the
//! distance between the transponders and the maximum distance is equal to
//! the distance between the transponders"; along the baseline the box spans
//! the transponders, since both sensitivities grow beyond its ends (Figs.
//! 2-3). Two ranges fix a position only up to its mirror image in the
//! baseline, so the vehicle stays on one side (§III): the box is on the side
//! of the vehicle's start.

use super::layout::Transponder;
use super::sensitivity::baseline_frame;

/// The near edge's distance from the baseline, in baselines.
pub const NEAR_FRACTION: f64 = 0.25;
/// The far edge's distance from the baseline, in baselines.
pub const FAR_FRACTION: f64 = 1.0;

/// The box of one baseline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OperatingBox {
    /// The baseline's transponders, `[t1, t2]`.
    pub pair: [u32; 2],
    /// `L`, the horizontal distance between them, m.
    pub baseline_m: f64,
    /// The near edge's distance from the baseline, m (`L/4`).
    pub near_m: f64,
    /// The far edge's distance from the baseline, m (`L`).
    pub far_m: f64,
    /// The corners `[north, east]`, m: off `t1` at `L/4`, off `t2` at
    /// `L/4`, off `t2` at `L`, off `t1` at `L`.
    pub corners: [[f64; 2]; 4],
}

/// Why there is no box.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum OperatingBoxError {
    /// The two transponders are at one place.
    #[error("transponders {0} and {1} are at the same place: no baseline")]
    NoBaseline(u32, u32),
    /// The start lies on the line through the transponders: no side.
    #[error(
        "the start ({north_m}, {east_m}) lies on the line through transponders {a} and {b}: give a start on the side the vehicle works on"
    )]
    StartOnBaseline {
        /// North of the start, m.
        north_m: f64,
        /// East of the start, m.
        east_m: f64,
        /// One transponder.
        a: u32,
        /// The other.
        b: u32,
    },
}

impl OperatingBox {
    /// The box of the baseline `t1`-`t2` on the side of `start` (`[north,
    /// east]`, m).
    pub fn new(
        t1: &Transponder,
        t2: &Transponder,
        start: [f64; 2],
    ) -> Result<Self, OperatingBoxError> {
        let Some((_, y, l)) = baseline_frame(t1.ne(), t2.ne(), start) else {
            return Err(OperatingBoxError::NoBaseline(t1.id, t2.id));
        };
        if !(y.abs() > 1e-9 * l) {
            return Err(OperatingBoxError::StartOnBaseline {
                north_m: start[0],
                east_m: start[1],
                a: t1.id,
                b: t2.id,
            });
        }
        // The unit normal towards the start: the baseline's direction turned
        // by +90° in (north, east), flipped to the start's side.
        let (en, ee) = ((t2.north_m - t1.north_m) / l, (t2.east_m - t1.east_m) / l);
        let side = y.signum();
        let (nn, ne) = (-ee * side, en * side);
        let (near_m, far_m) = (NEAR_FRACTION * l, FAR_FRACTION * l);
        let off = |t: &Transponder, d: f64| [t.north_m + nn * d, t.east_m + ne * d];
        Ok(Self {
            pair: [t1.id, t2.id],
            baseline_m: l,
            near_m,
            far_m,
            corners: [
                off(t1, near_m),
                off(t2, near_m),
                off(t2, far_m),
                off(t1, far_m),
            ],
        })
    }

    /// Whether `p` (`[north, east]`) is inside the box (edges included).
    pub fn contains(&self, p: [f64; 2]) -> bool {
        let [a, b, _, d] = self.corners;
        let (u, v) = ([b[0] - a[0], b[1] - a[1]], [d[0] - a[0], d[1] - a[1]]);
        let w = [p[0] - a[0], p[1] - a[1]];
        let s = (w[0] * u[0] + w[1] * u[1]) / (u[0] * u[0] + u[1] * u[1]);
        let t = (w[0] * v[0] + w[1] * v[1]) / (v[0] * v[0] + v[1] * v[1]);
        let eps = 1e-9;
        (-eps..=1.0 + eps).contains(&s) && (-eps..=1.0 + eps).contains(&t)
    }
}
