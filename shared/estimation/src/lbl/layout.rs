//! What the vehicle knows of its acoustic field (the manifest's `[site]`):
//! the transponders (id, position in the site's local frame, depth,
//! turnaround delay), checked, and the named layouts of the simulator's
//! `lbl` scenario.
//!
//! Paper 003 §III: the position follows from the ranges and the
//! transponders' positions, so a layout whose transponders cannot be told
//! apart (two at one place, two with one id) is refused, not guessed at.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A transponder's turnaround delay when none is given, s (a typical
/// transponder; our choice, the simulator's default since issue 3).
pub const DEFAULT_TURNAROUND_S: f64 = 12.5e-3;

/// Two transponders closer than this in the horizontal plane are refused,
/// m: their ranges would not tell a position apart (paper 003 Fig. 3's
/// sensitivity grows without bound as the baseline shrinks).
pub const MIN_SEPARATION_M: f64 = 1.0;

/// The deepest transponder accepted, m (the deepest ocean).
pub const MAX_DEPTH_M: f64 = 11_000.0;

/// The longest turnaround delay accepted, s.
pub const MAX_TURNAROUND_S: f64 = 10.0;

/// The farthest a transponder may be from the site's origin, m.
pub const MAX_OFFSET_M: f64 = 1.0e6;

/// One LBL transponder, fixed, in the site's local frame (north and east of
/// the origin, DESIGN §4).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Transponder {
    /// Id used by `lbl/interrogate` and `sensor/lbl`.
    pub id: u32,
    /// North of the origin, m.
    pub north_m: f64,
    /// East of the origin, m.
    pub east_m: f64,
    /// Depth, m (positive down).
    pub depth_m: f64,
    /// Turnaround delay `t_ta` between hearing the interrogation and
    /// replying, s (default [`DEFAULT_TURNAROUND_S`]).
    #[serde(default = "default_turnaround")]
    pub turnaround_s: f64,
}

fn default_turnaround() -> f64 {
    DEFAULT_TURNAROUND_S
}

/// Why a list of transponders is not a layout.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LayoutError {
    /// No transponder.
    #[error("no transponder: an LBL layout needs at least one (paper 003 uses two)")]
    Empty,
    /// Two transponders share an id.
    #[error("transponder id {0} is given twice")]
    DuplicateId(u32),
    /// A value is NaN, infinite or outside its range.
    #[error("transponder {id}: {field} = {value} is outside {range}")]
    OutOfRange {
        /// The transponder.
        id: u32,
        /// The field.
        field: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range, in words.
        range: &'static str,
    },
    /// Two transponders at (nearly) one place in the horizontal plane.
    #[error(
        "transponders {a} and {b} are {distance_m:.3} m apart in the horizontal plane (at least {MIN_SEPARATION_M} m): their ranges cannot tell a position apart"
    )]
    Coincident {
        /// One transponder.
        a: u32,
        /// The other.
        b: u32,
        /// Their horizontal distance, m.
        distance_m: f64,
    },
}

/// A checked layout: at least one transponder, unique ids, finite positions
/// within [`MAX_OFFSET_M`] of the origin, depths in [0, [`MAX_DEPTH_M`]],
/// turnarounds in [0, [`MAX_TURNAROUND_S`]], no two closer than
/// [`MIN_SEPARATION_M`] horizontally.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    transponders: Vec<Transponder>,
}

impl Layout {
    /// Checks `transponders` (see [`Layout`]).
    pub fn new(transponders: Vec<Transponder>) -> Result<Self, LayoutError> {
        if transponders.is_empty() {
            return Err(LayoutError::Empty);
        }
        for (i, t) in transponders.iter().enumerate() {
            let check = |field, value: f64, lo: f64, hi: f64, range| {
                // Written so that NaN fails.
                if value >= lo && value <= hi {
                    Ok(())
                } else {
                    Err(LayoutError::OutOfRange {
                        id: t.id,
                        field,
                        value,
                        range,
                    })
                }
            };
            check("north_m", t.north_m, -MAX_OFFSET_M, MAX_OFFSET_M, "±1e6")?;
            check("east_m", t.east_m, -MAX_OFFSET_M, MAX_OFFSET_M, "±1e6")?;
            check("depth_m", t.depth_m, 0.0, MAX_DEPTH_M, "[0, 11000]")?;
            check(
                "turnaround_s",
                t.turnaround_s,
                0.0,
                MAX_TURNAROUND_S,
                "[0, 10]",
            )?;
            for o in &transponders[..i] {
                if o.id == t.id {
                    return Err(LayoutError::DuplicateId(t.id));
                }
                let d = (t.north_m - o.north_m).hypot(t.east_m - o.east_m);
                if !(d >= MIN_SEPARATION_M) {
                    return Err(LayoutError::Coincident {
                        a: o.id,
                        b: t.id,
                        distance_m: d,
                    });
                }
            }
        }
        Ok(Self { transponders })
    }

    /// The transponders, in the order given.
    pub fn transponders(&self) -> &[Transponder] {
        &self.transponders
    }

    /// Transponder `id`, if the layout has it.
    pub fn get(&self, id: u32) -> Option<&Transponder> {
        self.transponders.iter().find(|t| t.id == id)
    }

    /// The index of transponder `id` in [`Layout::transponders`].
    pub fn index_of(&self, id: u32) -> Option<usize> {
        self.transponders.iter().position(|t| t.id == id)
    }

    /// How many transponders.
    pub fn len(&self) -> usize {
        self.transponders.len()
    }

    /// Never true (a layout has at least one transponder); for clippy's sake.
    pub fn is_empty(&self) -> bool {
        self.transponders.is_empty()
    }
}

/// The names of the simulator's `lbl` scenario layouts ([`preset`]).
pub const PRESETS: [&str; 2] = ["Two", "Four"];

/// A named layout of the simulator's `lbl` scenario (a 500 m north × 400 m
/// east box from the origin; the depths, 20 m, and turnarounds,
/// [`DEFAULT_TURNAROUND_S`], are our choice):
///
/// - `"Two"`: ids 1, 2 at (−50, −150) and (550, −150): a 600 m north-south
///   baseline 150 m (a quarter of it) west of the box, which lies 150-550 m
///   from it: paper 003's rule (Fig. 4: from L/4 to L from the baseline,
///   never crossing it; Isurus had a 600 m baseline).
/// - `"Four"`: the two above plus ids 3, 4 at (−50, 550) and (550, 550),
///   east of the box.
pub fn preset(name: &str) -> Option<Vec<Transponder>> {
    let t = |id, north_m, east_m| Transponder {
        id,
        north_m,
        east_m,
        depth_m: 20.0,
        turnaround_s: DEFAULT_TURNAROUND_S,
    };
    let two = vec![t(1, -50.0, -150.0), t(2, 550.0, -150.0)];
    match name {
        "Two" => Some(two),
        "Four" => {
            let mut v = two;
            v.push(t(3, -50.0, 550.0));
            v.push(t(4, 550.0, 550.0));
            Some(v)
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(id: u32, n: f64, e: f64) -> Transponder {
        Transponder {
            id,
            north_m: n,
            east_m: e,
            depth_m: 20.0,
            turnaround_s: DEFAULT_TURNAROUND_S,
        }
    }

    #[test]
    fn presets_are_layouts() {
        for name in PRESETS {
            let l = Layout::new(preset(name).expect("preset")).expect("valid");
            assert!(l.len() >= 2);
        }
        assert!(preset("Three").is_none());
        assert_eq!(preset("Four").map(|v| v.len()), Some(4));
    }

    #[test]
    fn bad_layouts_are_refused_with_a_reason() {
        assert_eq!(Layout::new(vec![]), Err(LayoutError::Empty));
        assert_eq!(
            Layout::new(vec![t(1, 0.0, 0.0), t(1, 100.0, 0.0)]),
            Err(LayoutError::DuplicateId(1))
        );
        let e = Layout::new(vec![t(1, 0.0, 0.0), t(2, 0.3, 0.4)]).expect_err("coincident");
        assert!(
            matches!(e, LayoutError::Coincident { a: 1, b: 2, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("0.500 m apart"), "{e}");
        let mut nan = t(3, f64::NAN, 0.0);
        let e = Layout::new(vec![nan]).expect_err("NaN");
        assert!(e.to_string().contains("north_m = NaN"), "{e}");
        nan.north_m = 0.0;
        nan.depth_m = -1.0;
        assert!(Layout::new(vec![nan]).is_err());
        nan.depth_m = 1.0;
        nan.turnaround_s = f64::INFINITY;
        assert!(Layout::new(vec![nan]).is_err());
    }

    #[test]
    fn a_missing_turnaround_is_the_default() {
        let t: Transponder =
            toml::from_str("id = 1\nnorth_m = 0.0\neast_m = 1.0\ndepth_m = 5.0").expect("toml");
        assert_eq!(t.turnaround_s, DEFAULT_TURNAROUND_S);
        assert!(toml::from_str::<Transponder>("id = 1\nnorth = 0.0").is_err());
    }
}
