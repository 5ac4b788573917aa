//! Paper 002's evaluation by dives (§2 and Table 2): for each dive, from the
//! last surface GPS fix before it to the first after it, the horizontal
//! error of the estimate just before that first fix (the last one stamped
//! before it: the fix itself may already have reset the estimate), against
//! the distance travelled submerged; and paper 000's per-axis drift, the
//! least-squares slope of the north, east and down errors against the
//! distance travelled submerged (a final error can cancel on a survey that
//! ends near its start; a slope does not).
//!
//! A dive is a gap between consecutive fixes of more than [`DIVE_MIN_S`].
//! The distance is the truth's (`distance_m` of `sim/truth`), so dives are
//! evaluated against the truth only.

use nauta_messages::checked::Gps;
use serde::Serialize;

use super::compute::ErrorSample;

/// Shortest time without a GPS fix that counts as a dive, s (the simulator's
/// GPS gives 1 Hz at the surface; a wave over the antenna is not a dive).
pub const DIVE_MIN_S: f64 = 60.0;

/// Dives shorter than this distance are listed without a relative error, m.
const MIN_DISTANCE_M: f64 = 1.0;

/// One dive of a stream.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Dive {
    /// The last fix before the dive, ns.
    pub start_stamp_ns: u64,
    /// The first fix after it, ns.
    pub end_stamp_ns: u64,
    /// Distance travelled between the two, m.
    pub distance_m: f64,
    /// Horizontal error of the last estimate before the end fix, m.
    pub error_m: f64,
    /// `error_m` in % of `distance_m` (paper 002's relative error).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_pct: Option<f64>,
    /// The error the estimate itself predicted at that moment
    /// (`predicted_drift_m`), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub predicted_error_m: Option<f64>,
}

/// The dives of `errors` (sorted by stamp, against the truth) between the
/// fixes `gps` (sorted); `predicted(stamp)` gives the estimate's own
/// prediction at a stamp.
pub fn dives(
    errors: &[ErrorSample],
    gps: &[Gps],
    predicted: impl Fn(u64) -> Option<f64>,
) -> Vec<Dive> {
    let min_gap_ns = (DIVE_MIN_S * 1e9) as u64;
    let mut out = Vec::new();
    for w in gps.windows(2) {
        let (a, b) = (w[0].stamp_ns, w[1].stamp_ns);
        if b.saturating_sub(a) <= min_gap_ns {
            continue;
        }
        let inside = |e: &&ErrorSample| e.stamp_ns >= a && e.stamp_ns < b && e.ne_m.is_some();
        let (Some(first), Some(last)) =
            (errors.iter().find(inside), errors.iter().rev().find(inside))
        else {
            continue;
        };
        let error_m = last.ne_m.map_or(0.0, |e| e[0].hypot(e[1]));
        let distance_m = last.distance_m - first.distance_m;
        out.push(Dive {
            start_stamp_ns: a,
            end_stamp_ns: b,
            distance_m,
            error_m,
            error_pct: (distance_m > MIN_DISTANCE_M).then(|| 100.0 * error_m / distance_m),
            predicted_error_m: predicted(last.stamp_ns),
        });
    }
    out
}

/// Paper 000's per-axis drift, m/km: for north, east and down, the
/// least-squares slope through the origin of the error against the distance
/// travelled since the dive's start, pooled over every sample of every dive
/// (`Σ x·y / Σ x²`; through the origin because the surface fix resets the
/// error at the start of each dive). `None` without a dive.
pub fn drift_slope(errors: &[ErrorSample], dives: &[Dive]) -> Option<[f64; 3]> {
    let mut sxx = 0.0;
    let mut sxy = [0.0; 3];
    for d in dives {
        let inside: Vec<&ErrorSample> = errors
            .iter()
            .filter(|e| e.stamp_ns >= d.start_stamp_ns && e.stamp_ns < d.end_stamp_ns)
            .collect();
        let Some(start) = inside.first().map(|e| e.distance_m) else {
            continue;
        };
        for e in inside {
            let (Some(ne), Some(down)) = (e.ne_m, e.down_m) else {
                continue;
            };
            let x = (e.distance_m - start) / 1000.0;
            sxx += x * x;
            for (k, y) in [ne[0], ne[1], down].into_iter().enumerate() {
                sxy[k] += x * y;
            }
        }
    }
    (sxx > 0.0).then(|| sxy.map(|s| s / sxx))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fix(t_s: u64) -> Gps {
        Gps {
            stamp_ns: t_s * 1_000_000_000,
            lat_rad: 0.0,
            lon_rad: 0.0,
            height_m: 0.0,
            horizontal_std_m: 2.0,
            quality: 1,
            velocity: None,
        }
    }

    /// An error growing at 20 m/km north, -10 m/km east, 5 m/km down, at
    /// 1 m/s, over the dives between fixes.
    fn errors(from_s: u64, to_s: u64) -> Vec<ErrorSample> {
        (from_s..to_s)
            .map(|t| {
                let x_km = (t - from_s) as f64 / 1000.0;
                ErrorSample {
                    stamp_ns: t * 1_000_000_000,
                    ne_m: Some([20.0 * x_km, -10.0 * x_km]),
                    down_m: Some(5.0 * x_km),
                    vel_m_s: None,
                    attitude: None,
                    inside_95: None,
                    distance_m: t as f64,
                }
            })
            .collect()
    }

    #[test]
    fn a_dive_between_fixes_gives_its_error_distance_and_slope() {
        let gps = [fix(0), fix(1), fix(2), fix(1002), fix(1003)];
        let e = errors(2, 1002);
        let d = dives(&e, &gps, |t| Some(t as f64 * 1e-9 * 0.01));
        assert_eq!(d.len(), 1, "the 1 s gaps are not dives");
        let d0 = d[0];
        assert_eq!(
            (d0.start_stamp_ns, d0.end_stamp_ns),
            (2_000_000_000, 1_002_000_000_000)
        );
        assert!((d0.distance_m - 999.0).abs() < 1e-9);
        let expect = 999e-3 * 20.0f64.hypot(10.0);
        assert!((d0.error_m - expect).abs() < 1e-9, "{}", d0.error_m);
        assert!((d0.error_pct.expect("pct") - 100.0 * expect / 999.0).abs() < 1e-9);
        assert!((d0.predicted_error_m.expect("predicted") - 10.01).abs() < 1e-9);
        let s = drift_slope(&e, &d).expect("slope");
        for (got, want) in s.iter().zip([20.0, -10.0, 5.0]) {
            assert!((got - want).abs() < 1e-9, "{s:?}");
        }
    }

    #[test]
    fn no_fix_no_dive() {
        let e = errors(0, 100);
        assert!(dives(&e, &[], |_| None).is_empty());
        assert!(dives(&e, &[fix(0)], |_| None).is_empty());
        assert_eq!(drift_slope(&e, &[]), None);
    }
}
