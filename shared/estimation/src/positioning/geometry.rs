//! The geometry of a buoy range (paper 000 §III-B-2, eqs. 51-53): the
//! horizontal distance between two positions by the haversine formula, the
//! slant range with the buoy transducer's depth, and the range a time of
//! flight gives.
//!
//! Eqs. 51-52 of the text are garbled; from the prose and the standard
//! haversine formula (Sinnott 1984), `a = sin²(ΔL/2) + cos L₁ cos L₂
//! sin²(Δλ/2)` (52) and `d = 2 R atan2(√a, √(1 − a))` (51). The paper takes
//! `R` = 6 378 137 m, the equatorial radius: at 38° N that makes a north
//! distance 0.3 % long (0.8 m at 300 m, most of the error budget of a fix),
//! so [`haversine_m`] takes the radius of the sphere on which a line in the
//! direction of the buoy is as long as on the WGS84 ellipsoid
//! ([`radius_in_azimuth`]: from the ellipsoid's local metric, north `R_M
//! dL`, east `R_N cos L dλ`, a line of azimuth α and length d spans `dL =
//! d cos α / R_M` and `cos L dλ = d sin α / R_N`, which the sphere makes
//! `R d √(cos²α/R_M² + sin²α/R_N²)`), exact to the ellipsoid's curvature
//! over the ranges of a buoy (millimetres at 800 m).

use crate::earth::{meridian_radius, transverse_radius};

/// The radius of the sphere on which a short line of azimuth
/// `azimuth_rad` (from north) at latitude `lat_rad` is as long as on the
/// WGS84 ellipsoid, m: `1/R² = cos²α/R_M² + sin²α/R_N²` (module docs).
pub fn radius_in_azimuth(lat_rad: f64, azimuth_rad: f64) -> f64 {
    let (s, c) = azimuth_rad.sin_cos();
    let (m, n) = (meridian_radius(lat_rad), transverse_radius(lat_rad));
    1.0 / (c * c / (m * m) + s * s / (n * n)).sqrt()
}

/// Paper 000 eqs. 51-52: the distance on a sphere of radius `radius_m`
/// between `(lat1, lon1)` and `(lat2, lon2)` (rad), m.
pub fn haversine_m(lat1: f64, lon1: f64, lat2: f64, lon2: f64, radius_m: f64) -> f64 {
    let a = haversine_a(lat1, lon1, lat2, lon2);
    2.0 * radius_m * a.sqrt().atan2((1.0 - a).max(0.0).sqrt())
}

/// Eq. 52's `a`, in [0, 1].
fn haversine_a(lat1: f64, lon1: f64, lat2: f64, lon2: f64) -> f64 {
    let s_lat = ((lat2 - lat1) / 2.0).sin();
    let s_lon = ((lon2 - lon1) / 2.0).sin();
    (s_lat * s_lat + lat1.cos() * lat2.cos() * s_lon * s_lon).clamp(0.0, 1.0)
}

/// Paper 000 eq. 53: the slant range from the buoy's transducer at depth
/// `buoy_depth_m` to the vehicle at depth `depth_m`, `horizontal_m` apart, m.
pub fn slant_range_m(horizontal_m: f64, depth_m: f64, buoy_depth_m: f64) -> f64 {
    horizontal_m.hypot(depth_m - buoy_depth_m)
}

/// The range a one-way time of flight measures at the given sound speed, m
/// (paper 000 §III-B-2: "with the TOF measurement and sound speed").
pub fn range_of_flight_m(time_of_flight_s: f64, sound_speed_m_s: f64) -> f64 {
    time_of_flight_s * sound_speed_m_s
}

/// The horizontal distance a slant range leaves at a vertical separation
/// `dz_m`, m: `None` when the range is shorter than the separation (an
/// impossible time of flight).
pub fn horizontal_of_slant_m(slant_m: f64, dz_m: f64) -> Option<f64> {
    let h2 = slant_m * slant_m - dz_m * dz_m;
    (h2 >= 0.0).then(|| h2.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::local::north_east_of;

    #[test]
    fn haversine_in_the_azimuths_radius_matches_the_exact_plane() {
        // Over a buoy's ranges the ellipsoid's own distance (the exact
        // tangent plane nauta's tools use) and eqs. 51-52 on the azimuth's
        // sphere agree to millimetres in every direction.
        let (lat0, lon0) = (38.7f64.to_radians(), (-9.1f64).to_radians());
        for k in 0..16 {
            let az = k as f64 * std::f64::consts::TAU / 16.0;
            let d = 800.0;
            let (lat, lon) = crate::local::geodetic_of(lat0, lon0, d * az.cos(), d * az.sin());
            let (n, e) = north_east_of(lat0, lon0, lat, lon);
            let plane = n.hypot(e);
            let h = haversine_m(lat0, lon0, lat, lon, radius_in_azimuth(lat0, az));
            assert!((h - plane).abs() < 5e-3, "azimuth {az}: {h} vs {plane}");
            // The paper's equatorial sphere errs by up to a few metres here.
            let paper = haversine_m(lat0, lon0, lat, lon, 6_378_137.0);
            if k == 0 {
                assert!((paper - plane).abs() > 1.0, "{paper} vs {plane}");
            }
        }
    }

    #[test]
    fn slant_and_horizontal_invert_each_other() {
        let s = slant_range_m(300.0, 41.0, 1.0);
        assert!((s - 300f64.hypot(40.0)).abs() < 1e-12);
        let h = horizontal_of_slant_m(s, 40.0).expect("possible");
        assert!((h - 300.0).abs() < 1e-9);
        assert_eq!(horizontal_of_slant_m(30.0, 40.0), None);
        assert_eq!(range_of_flight_m(0.2, 1500.0), 300.0);
    }
}
