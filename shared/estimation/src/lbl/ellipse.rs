//! The uncertainty ellipse of the position (paper 003 §V-A; paper 004 §V):
//! `P_xy` defines it by the lengths of its two principal axes and the
//! orientation of its major axis.

/// The 1σ ellipse of a 2×2 position covariance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipse {
    /// Semi-major axis, m: the square root of `P_xy`'s larger eigenvalue.
    pub major_m: f64,
    /// Semi-minor axis, m.
    pub minor_m: f64,
    /// Orientation of the major axis from north towards east, rad, in
    /// (−π/2, π/2].
    pub orientation_rad: f64,
}

impl Ellipse {
    /// The ellipse of `P_xy = [[σ_xx, σ_xy], [σ_yx, σ_yy]]` (x north, y east;
    /// the off-diagonal taken as the mean of the two, so a matrix that is
    /// symmetric only to rounding gives the same axes).
    pub fn of(p_xy: [[f64; 2]; 2]) -> Self {
        let (a, b, d) = (p_xy[0][0], 0.5 * (p_xy[0][1] + p_xy[1][0]), p_xy[1][1]);
        let mean = 0.5 * (a + d);
        let r = (0.25 * (a - d) * (a - d) + b * b).sqrt();
        Self {
            major_m: (mean + r).max(0.0).sqrt(),
            minor_m: (mean - r).max(0.0).sqrt(),
            orientation_rad: 0.5 * (2.0 * b).atan2(a - d),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_and_orientation() {
        let e = Ellipse::of([[4.0, 0.0], [0.0, 1.0]]);
        assert_eq!((e.major_m, e.minor_m, e.orientation_rad), (2.0, 1.0, 0.0));
        let e = Ellipse::of([[1.0, 0.0], [0.0, 9.0]]);
        assert!((e.orientation_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // A 45° ellipse: eigenvalues 3 and 1 along (1, 1) and (1, −1).
        let e = Ellipse::of([[2.0, 1.0], [1.0, 2.0]]);
        assert!((e.major_m - 3f64.sqrt()).abs() < 1e-12 && (e.minor_m - 1.0).abs() < 1e-12);
        assert!((e.orientation_rad - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
    }
}
