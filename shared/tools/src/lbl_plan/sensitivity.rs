//! Paper 003 §III, Figs. 2-3: how much a horizontal position fixed by
//! ranges to transponders moves per metre of error, from place to place.
//!
//! - [`range_sensitivity`] (Fig. 2): the position's RMS error per metre of
//!   independent, equal range errors. With `G` the matrix whose rows are the
//!   horizontal unit vectors from each transponder to the position, the
//!   least-squares fix moves by `(GᵀG)⁻¹Gᵀ δr`, so the figure is
//!   `√trace((GᵀG)⁻¹)` (the horizontal dilution of precision). With two
//!   transponders `G` is square and it is `√2 / |sin α|`, `α` the angle
//!   the baseline subtends at the vehicle: it grows near the baseline
//!   (`α → π`), outside the region between the transponders and far from
//!   them (`α → 0`), as the paper says.
//! - [`baseline_sensitivity`] (Fig. 3): the position's error per metre of
//!   error in the distance `L` between two transponders, the ranges held.
//!   The paper does not say where the error goes; we lengthen the baseline
//!   about its midpoint (each transponder moves `δL/2` along it). In the
//!   baseline's frame (`x` along it from the midpoint, `y` across), the
//!   two-range fix is `x = (r₁² − r₂²) / 2L`, `y = √(r₁² − (x + L/2)²)`,
//!   so `∂x/∂L = −x/L` and `∂y/∂L = −(L²/4 − x²) / (L y)` (derived here):
//!   large near the baseline (`y → 0`) and beyond its ends (`|x| > L/2`),
//!   small far away across it, as Fig. 3 shows.
//!
//! Both are horizontal, as the paper's analysis is; `None` where the fix is
//! undefined (at a transponder, on the line through two).

/// Relative size under which a matrix or a distance is taken as singular.
const SINGULAR: f64 = 1e-12;

/// Fig. 2: `√trace((GᵀG)⁻¹)`, m of position per m of range error, at `p`
/// (`[north, east]`) for ranges to every transponder in `transponders`.
pub fn range_sensitivity(transponders: &[[f64; 2]], p: [f64; 2]) -> Option<f64> {
    // GᵀG = Σ u uᵀ (2×2, symmetric).
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for t in transponders {
        let (dn, de) = (p[0] - t[0], p[1] - t[1]);
        let r = dn.hypot(de);
        if !(r > SINGULAR) {
            return None;
        }
        let (un, ue) = (dn / r, de / r);
        a += un * un;
        b += un * ue;
        c += ue * ue;
    }
    let det = a * c - b * b;
    if !(det > SINGULAR) {
        return None;
    }
    // trace of the inverse of [[a, b], [b, c]] = (a + c) / det.
    let s = ((a + c) / det).sqrt();
    s.is_finite().then_some(s)
}

/// Fig. 3: `‖∂p/∂L‖`, m of position per m of baseline error, at `p` for the
/// baseline from `t1` to `t2` (all `[north, east]`).
pub fn baseline_sensitivity(t1: [f64; 2], t2: [f64; 2], p: [f64; 2]) -> Option<f64> {
    let (x, y, l) = baseline_frame(t1, t2, p)?;
    if !(y.abs() > SINGULAR * l) {
        return None;
    }
    let dx = -x / l;
    let dy = -(l * l / 4.0 - x * x) / (l * y);
    let s = dx.hypot(dy);
    s.is_finite().then_some(s)
}

/// `p` in the baseline's frame: `x` along `t1 → t2` from the midpoint, `y`
/// across (positive to the right of `t1 → t2` on a map, north up and east
/// right: a baseline pointing north has +y to the east), and the length
/// `L`.
pub fn baseline_frame(t1: [f64; 2], t2: [f64; 2], p: [f64; 2]) -> Option<(f64, f64, f64)> {
    let (en, ee) = (t2[0] - t1[0], t2[1] - t1[1]);
    let l = en.hypot(ee);
    if !(l > 0.0) || !l.is_finite() {
        return None;
    }
    let (en, ee) = (en / l, ee / l);
    let (dn, de) = (p[0] - 0.5 * (t1[0] + t2[0]), p[1] - 0.5 * (t1[1] + t2[1]));
    // The normal: the baseline's direction turned by +90° in (north, east),
    // (en, ee) → (−ee, en).
    Some((dn * en + de * ee, -dn * ee + de * en, l))
}
