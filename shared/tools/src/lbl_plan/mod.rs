//! `nauta lbl plan LAYOUT -o MAP.png [--json]`: paper 003 §III for a
//! transponder layout: the sensitivity of the LBL position to range errors
//! (Fig. 2) and to the baseline's length (Fig. 3) as level contours over the
//! area, and the desirable operating box (Fig. 4), drawn and printed.
//!
//! - [`layout`]: the transponders, checked; the CSV list form.
//! - [`sensitivity`]: Figs. 2-3's two sensitivities at a point.
//! - [`operating_box`]: Fig. 4's box.
//! - [`contour`]: a sampled field and its level contours.
//! - [`map`]: the PNG.
//! - [`command`]: the command line.

pub mod command;
pub mod contour;
pub mod layout;
pub mod map;
pub mod operating_box;
pub mod sensitivity;

#[cfg(test)]
mod tests;

use serde_json::{Value, json};

use layout::{Layout, Transponder};
use operating_box::{OperatingBox, OperatingBoxError};
use sensitivity::{baseline_sensitivity, range_sensitivity};

/// Why there is no plan for a layout.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// A baseline names a transponder the layout does not have.
    #[error("--pair: the layout has no transponder {id} (it has {ids})")]
    UnknownId {
        /// The id asked for.
        id: u32,
        /// The layout's ids.
        ids: String,
    },
    /// A baseline from a transponder to itself.
    #[error("--pair: transponder {0} twice; a baseline joins two transponders")]
    SamePair(u32),
    /// More than two transponders and no baseline chosen.
    #[error(
        "the layout has {count} transponders ({ids}): choose the baseline whose operating box to plan with --pair ID,ID"
    )]
    NoPair {
        /// How many.
        count: usize,
        /// Their ids.
        ids: String,
    },
    /// No box on that baseline.
    #[error(transparent)]
    Box(#[from] OperatingBoxError),
}

/// What to plan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanOptions {
    /// The baseline whose box to plan; `None`: the layout's only two.
    pub pair: Option<[u32; 2]>,
    /// Where the vehicle starts, `[north, east]`, m: it stays on this side
    /// of the baseline (paper 003 §III).
    pub start: [f64; 2],
}

impl Default for PlanOptions {
    fn default() -> Self {
        Self {
            pair: None,
            // The shipped missions start at the site's origin.
            start: [0.0, 0.0],
        }
    }
}

/// Levels of the range sensitivity's contours, m per m (Fig. 2; two
/// transponders give at least √2).
pub const RANGE_LEVELS: [f64; 6] = [1.25, 1.5, 2.0, 3.0, 5.0, 10.0];
/// Levels of the baseline sensitivity's contours, m per m (Fig. 3).
pub const BASELINE_LEVELS: [f64; 5] = [0.25, 0.5, 1.0, 2.0, 5.0];

/// The plan of one layout.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The layout.
    pub layout: Layout,
    /// The baseline's two transponders.
    pub pair: [Transponder; 2],
    /// Fig. 4's box on the start's side.
    pub operating_box: OperatingBox,
    /// The start, `[north, east]`, m.
    pub start: [f64; 2],
    /// Fig. 2's sensitivity over the box (with every transponder of the
    /// layout): smallest and largest on its edges and inside, m per m.
    pub range_in_box: (f64, f64),
    /// Fig. 3's sensitivity over the box (its baseline), m per m.
    pub baseline_in_box: (f64, f64),
}

impl Plan {
    /// Plans `layout`.
    pub fn new(layout: &Layout, options: &PlanOptions) -> Result<Self, PlanError> {
        let ids = || {
            layout
                .transponders()
                .iter()
                .map(|t| t.id.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let [a, b] = match (options.pair, layout.transponders()) {
            (Some([a, b]), _) => {
                if a == b {
                    return Err(PlanError::SamePair(a));
                }
                let get = |id| {
                    layout
                        .get(id)
                        .copied()
                        .ok_or_else(|| PlanError::UnknownId { id, ids: ids() })
                };
                [get(a)?, get(b)?]
            }
            (None, [a, b]) => [*a, *b],
            (None, all) => {
                return Err(PlanError::NoPair {
                    count: all.len(),
                    ids: ids(),
                });
            }
        };
        let operating_box = OperatingBox::new(&a, &b, options.start)?;
        let all: Vec<[f64; 2]> = layout.transponders().iter().map(Transponder::ne).collect();
        let over_box = |f: &dyn Fn([f64; 2]) -> Option<f64>| {
            let [c0, c1, _, c3] = operating_box.corners;
            let mut lo = f64::INFINITY;
            let mut hi = f64::NEG_INFINITY;
            let n = 40;
            for i in 0..=n {
                for j in 0..=n {
                    let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                    let p = [
                        c0[0] + s * (c1[0] - c0[0]) + t * (c3[0] - c0[0]),
                        c0[1] + s * (c1[1] - c0[1]) + t * (c3[1] - c0[1]),
                    ];
                    let v = f(p).unwrap_or(f64::INFINITY);
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
            (lo, hi)
        };
        let range_in_box = over_box(&|p| range_sensitivity(&all, p));
        let baseline_in_box = over_box(&|p| baseline_sensitivity(a.ne(), b.ne(), p));
        Ok(Self {
            layout: layout.clone(),
            pair: [a, b],
            operating_box,
            start: options.start,
            range_in_box,
            baseline_in_box,
        })
    }

    /// The JSON `nauta lbl plan --json` prints: `{"baseline_m", "box":
    /// [[north_m, east_m], ...], "pair", "near_m", "far_m", "start",
    /// "transponders", "range_sensitivity_in_box", "baseline_sensitivity_in_box"}`.
    pub fn to_json(&self) -> Value {
        let b = &self.operating_box;
        json!({
            "baseline_m": b.baseline_m,
            "box": b.corners,
            "pair": b.pair,
            "near_m": b.near_m,
            "far_m": b.far_m,
            "start": self.start,
            "transponders": self.layout.transponders().iter().map(|t| json!({
                "id": t.id, "north_m": t.north_m, "east_m": t.east_m, "depth_m": t.depth_m,
            })).collect::<Vec<_>>(),
            "range_sensitivity_in_box": {"min": finite(self.range_in_box.0), "max": finite(self.range_in_box.1)},
            "baseline_sensitivity_in_box": {"min": finite(self.baseline_in_box.0), "max": finite(self.baseline_in_box.1)},
        })
    }

    /// The plan for people.
    pub fn text(&self) -> String {
        use std::fmt::Write as _;
        let b = &self.operating_box;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "baseline T{}-T{}: {:.1} m",
            b.pair[0], b.pair[1], b.baseline_m
        );
        let _ = writeln!(
            s,
            "operating box (paper 003 Fig. 4: {:.1} m to {:.1} m from the baseline, between the transponders, on the side of the start ({:.1}, {:.1})):",
            b.near_m, b.far_m, self.start[0], self.start[1]
        );
        let _ = writeln!(s, "  {:>10} {:>10}", "north_m", "east_m");
        for c in &b.corners {
            let _ = writeln!(s, "  {:>10.1} {:>10.1}", c[0], c[1]);
        }
        let range = |(lo, hi): (f64, f64)| format!("{lo:.2} to {hi:.2}");
        let _ = writeln!(
            s,
            "in the box: position error per range error {} m/m (Fig. 2, {} transponders), per baseline error {} m/m (Fig. 3)",
            range(self.range_in_box),
            self.layout.transponders().len(),
            range(self.baseline_in_box)
        );
        s
    }
}

fn finite(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}
