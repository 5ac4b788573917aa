//! Two-transponder side ambiguity (paper 003 §III): two ranges give two
//! positions, mirror images across the baseline (the line through the
//! transponders); the ambiguity is avoided if the vehicle does not cross the
//! baseline and its initial side is known. The filter takes the side from
//! its start (a GPS fix, or the configured start) and says when the
//! estimate crosses.

use crate::lbl::layout::Layout;

/// Transponders within this of the line through the two farthest apart are
/// on the baseline, m.
const ON_LINE_M: f64 = 1.0;

/// The line every transponder of a layout lies on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Baseline {
    a: [f64; 2],
    /// Unit vector from `a` along the line.
    u: [f64; 2],
}

impl Baseline {
    /// The baseline of `layout`, when every transponder lies on one line
    /// (any two-transponder layout); `None` otherwise (three or more not in
    /// line: no mirror ambiguity).
    pub fn of(layout: &Layout) -> Option<Self> {
        let t = layout.transponders();
        let mut far = (0, 0, 0.0);
        for i in 0..t.len() {
            for j in i + 1..t.len() {
                let d = (t[i].north_m - t[j].north_m).hypot(t[i].east_m - t[j].east_m);
                if d > far.2 {
                    far = (i, j, d);
                }
            }
        }
        let (i, j, d) = far;
        if !(d > 0.0) {
            return None;
        }
        let a = [t[i].north_m, t[i].east_m];
        let u = [(t[j].north_m - a[0]) / d, (t[j].east_m - a[1]) / d];
        let line = Self { a, u };
        t.iter()
            .all(|k| line.side_m(k.north_m, k.east_m).abs() <= ON_LINE_M)
            .then_some(line)
    }

    /// The signed distance of `(north, east)` from the line, m (positive to
    /// the right of the direction from the first transponder to the other).
    pub fn side_m(&self, north_m: f64, east_m: f64) -> f64 {
        let (dn, de) = (north_m - self.a[0], east_m - self.a[1]);
        // The cross product u × d (north, east axes: east is to the right).
        self.u[0] * de - self.u[1] * dn
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lbl::layout::preset;

    #[test]
    fn two_transponders_have_a_baseline_four_do_not() {
        let two = Layout::new(preset("Two").expect("two")).expect("layout");
        let b = Baseline::of(&two).expect("baseline");
        // The box lies east of the north-south baseline at east = -150.
        assert!((b.side_m(250.0, 200.0) - 350.0).abs() < 1e-9);
        assert!(b.side_m(250.0, -300.0) < 0.0);
        let four = Layout::new(preset("Four").expect("four")).expect("layout");
        assert!(Baseline::of(&four).is_none());
    }
}
