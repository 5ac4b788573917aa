//! Ranges (paper 003 §IV-§V-C): the range of a round trip, and the expected
//! range `r*` with its Jacobian `H`, evaluated where the vehicle was at the
//! middle of the round trip.
//!
//! A reply heard at `t_r` to a ping sent at `t_s` measures
//! `(d_out + d_back) / 2`, the mean of the vehicle's distances to the
//! transponder at `t_s` and `t_r`: to well under a millimetre the distance
//! at the middle, `t_m = (t_s + t_r) / 2` (the vehicle moves ~0.5 m in a
//! round trip; the difference is of order `δ² / 8 r`). The filter's state is
//! at another instant `t` (the step the range is applied at, or the last
//! one); the position at `t_m` is that state moved back along the
//! dead-reckoned velocity of eq. 3:
//!
//! ```text
//! p(t_m) = p(t) − s ∫_{t_m}^{t} a dτ − w (t − t_m)      (s = k, or 1 over ground; no w over ground)
//! r*     = √((x_m − x̄)² + (y_m − ȳ)² + (z − z̄)²)       (paper 003 §V-C, 3-D)
//! H      = ∂r*/∂E = [g_x, g_y, −(t − t_m) g_x, −(t − t_m) g_y, −g · ∫a dτ],   g = (p(t_m) − (x̄, ȳ)) / r*
//! ```
//!
//! (paper 003's `H = [(x⁻ − x̄)/r*, (y⁻ − ȳ)/r*, 0, 0]` is the case `t = t_m`;
//! the current's and `k`'s entries are the chain rule through the move back).

use nalgebra::{SMatrix, SVector};

use crate::lbl::layout::Transponder;
use crate::lbl::model::Model;

/// Paper 003 §IV: the range of a round trip `t_rt` to a transponder of
/// turnaround `t_ta` at sound speed `c`, with `half_tick_s` added back for
/// a clock that stamps each event on the tick before it:
/// `r = c (t_rt + Δ/2 − t_ta) / 2`, m.
pub fn range_of_round_trip(
    round_trip_s: f64,
    turnaround_s: f64,
    sound_speed_m_s: f64,
    half_tick_s: f64,
) -> f64 {
    0.5 * sound_speed_m_s * (round_trip_s + half_tick_s - turnaround_s)
}

/// How the state's instant relates to the middle of the round trip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MidTrip {
    /// `t − t_m`, s (negative when the middle is after the state's instant).
    pub lag_s: f64,
    /// `∫_{t_m}^{t} a dτ` (the held inputs of eq. 3; negative when `t < t_m`).
    pub basis_integral: [f64; 2],
}

/// `r*` and `H` for a range to `t` from the state `x` (module docs), with
/// the vehicle at depth `depth_m`; `None` when the vehicle is on the
/// transponder (`r*` = 0: no direction).
pub fn expected<const N: usize>(
    model: &Model,
    x: &SVector<f64, N>,
    mid: &MidTrip,
    depth_m: f64,
    t: &Transponder,
) -> Option<(f64, SMatrix<f64, 1, N>)> {
    let s = model.scale(x);
    let current = model.current_moves_position();
    let (wx, wy) = if current { (x[2], x[3]) } else { (0.0, 0.0) };
    let xm = x[0] - s * mid.basis_integral[0] - wx * mid.lag_s;
    let ym = x[1] - s * mid.basis_integral[1] - wy * mid.lag_s;
    let (dx, dy, dz) = (xm - t.north_m, ym - t.east_m, depth_m - t.depth_m);
    let r = (dx * dx + dy * dy + dz * dz).sqrt();
    if !(r > 1e-6) {
        return None;
    }
    let (gx, gy) = (dx / r, dy / r);
    let mut h = SMatrix::<f64, 1, N>::zeros();
    h[0] = gx;
    h[1] = gy;
    if current {
        h[2] = -mid.lag_s * gx;
        h[3] = -mid.lag_s * gy;
    }
    if N > 4
        && matches!(
            model.dynamics,
            crate::lbl::model::Dynamics::PropellerEstimatedK
        )
    {
        h[4] = -(gx * mid.basis_integral[0] + gy * mid.basis_integral[1]);
    }
    Some((r, h))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lbl::model::Dynamics;

    fn tx() -> Transponder {
        Transponder {
            id: 1,
            north_m: 100.0,
            east_m: -50.0,
            depth_m: 20.0,
            turnaround_s: 0.0125,
        }
    }

    #[test]
    fn a_round_trip_gives_the_range() {
        // 2 × 300 m at 1500 m/s plus the turnaround.
        let rt = 600.0 / 1500.0 + 0.0125;
        assert!((range_of_round_trip(rt, 0.0125, 1500.0, 0.0) - 300.0).abs() < 1e-9);
        assert!((range_of_round_trip(rt, 0.0125, 1500.0, 1e-4) - 300.075).abs() < 1e-9);
    }

    /// `H` is the derivative of `r*` in every state, against central
    /// differences.
    #[test]
    fn h_is_the_jacobian_of_r_star() {
        for dynamics in [
            Dynamics::Propeller { k: 0.01 },
            Dynamics::PropellerEstimatedK,
            Dynamics::OverGround,
        ] {
            let model = Model {
                dynamics,
                q: [0.0; 5],
            };
            let mid = MidTrip {
                lag_s: 0.43,
                basis_integral: [40.0, 25.0],
            };
            let x = SVector::<f64, 5>::from([300.0, 200.0, 0.15, -0.1, 0.011]);
            let (r0, h) = expected(&model, &x, &mid, 10.0, &tx()).expect("range");
            assert!(r0 > 0.0);
            for i in 0..5 {
                let e = 1e-6;
                let mut xp = x;
                xp[i] += e;
                let mut xm = x;
                xm[i] -= e;
                let d = (expected(&model, &xp, &mid, 10.0, &tx()).expect("r").0
                    - expected(&model, &xm, &mid, 10.0, &tx()).expect("r").0)
                    / (2.0 * e);
                let want = if i == 4 && !matches!(dynamics, Dynamics::PropellerEstimatedK) {
                    0.0
                } else {
                    d
                };
                assert!(
                    (h[i] - want).abs() < 1e-6,
                    "{dynamics:?} state {i}: {} vs {d}",
                    h[i]
                );
            }
        }
    }

    #[test]
    fn on_the_transponder_there_is_no_direction() {
        let model = Model {
            dynamics: Dynamics::OverGround,
            q: [0.0; 5],
        };
        let x = SVector::<f64, 4>::from([100.0, -50.0, 0.0, 0.0]);
        let mid = MidTrip {
            lag_s: 0.0,
            basis_integral: [0.0; 2],
        };
        let mut t = tx();
        t.depth_m = 10.0;
        assert!(expected(&model, &x, &mid, 10.0, &t).is_none());
    }
}
