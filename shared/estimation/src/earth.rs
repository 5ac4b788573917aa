//! The WGS84 Earth: constants, radii of curvature, normal gravity, Earth and
//! transport rates in NED, and geodetic ↔ ECEF conversion.
//!
//! Conventions (DESIGN §4): geodetic latitude `lat` and longitude `lon` in radians,
//! height `h` in metres above the WGS84 ellipsoid, positive up (a depth `d` below
//! a sea surface at the ellipsoid is `h = -d`). Vectors in the navigation frame are
//! NED; ECEF is x through (0°, 0°), z through the north pole.
//!
//! # Radii of curvature: which name is which
//!
//! nauta uses the naming of Groves (2013, §2.4), which is also the one of the
//! Titterton & Weston (2004) / Farrell (2008) formulas (Farrell spells the first one
//! `R_M`):
//!
//! - [`meridian_radius`] `R_N(L) = a (1 - e²) / (1 - e² sin² L)^{3/2}`: the radius of
//!   curvature of the meridian, the one that turns north motion into latitude rate,
//!   `L̇ = v_N / (R_N + h)`;
//! - [`transverse_radius`] `R_E(L) = a / (1 - e² sin² L)^{1/2}`: the transverse
//!   (prime-vertical) radius, the one that turns east motion into longitude rate,
//!   `λ̇ = v_E / ((R_E + h) cos L)`.
//!
//! Paper 002 eq. 3 gives the same two formulas, but its text (above eq. 3) and its
//! eq. 4 swap the names: they call the meridian radius "transverse" and pair `R_N`
//! with longitude. The formulas here follow the standard definitions above, not
//! paper 002's text.

use nalgebra::Vector3;
use thiserror::Error;

/// WGS84 defining and derived constants (NIMA TR8350.2, 3rd ed., tables 3.1-3.3).
pub mod wgs84 {
    /// Semi-major axis `a`, m.
    pub const A_M: f64 = 6_378_137.0;
    /// Flattening `f = 1 / 298.257223563`.
    pub const F: f64 = 1.0 / 298.257_223_563;
    /// Semi-minor axis `b = a (1 - f)`, m.
    pub const B_M: f64 = A_M * (1.0 - F);
    /// First eccentricity squared `e² = f (2 - f)` (≈ 6.69437999014e-3).
    pub const E2: f64 = F * (2.0 - F);
    /// Earth rotation rate `ω_ie`, rad/s.
    pub const OMEGA_IE_RAD_S: f64 = 7.292_115e-5;
    /// Earth gravitational constant `GM` (including the atmosphere), m³/s².
    pub const GM_M3_S2: f64 = 3.986_004_418e14;
    /// Normal gravity at the equator `γ_e`, m/s².
    pub const GAMMA_EQUATOR_M_S2: f64 = 9.780_325_335_9;
    /// Normal gravity at the poles `γ_p`, m/s².
    pub const GAMMA_POLE_M_S2: f64 = 9.832_184_937_8;
    /// Somigliana's constant `k = b γ_p / (a γ_e) - 1` (TR8350.2 eq. 4-1).
    pub const SOMIGLIANA_K: f64 = 0.001_931_852_652_41;
    /// `m = ω² a² b / GM` (TR8350.2 eq. 4-3).
    pub const M: f64 = 0.003_449_786_506_84;
}

/// Meridian radius of curvature `R_N(L) = a (1 - e²) / (1 - e² sin² L)^{3/2}`, m.
///
/// Groves (2013) §2.4; paper 002 eq. 3 (first formula). Pairs with latitude:
/// `L̇ = v_N / (R_N + h)`.
pub fn meridian_radius(lat_rad: f64) -> f64 {
    let s = lat_rad.sin();
    let d = 1.0 - wgs84::E2 * s * s;
    wgs84::A_M * (1.0 - wgs84::E2) / (d * d.sqrt())
}

/// Transverse (prime-vertical) radius of curvature `R_E(L) = a / (1 - e² sin² L)^{1/2}`, m.
///
/// Groves (2013) §2.4; paper 002 eq. 3 (second formula). Pairs with longitude:
/// `λ̇ = v_E / ((R_E + h) cos L)`.
pub fn transverse_radius(lat_rad: f64) -> f64 {
    let s = lat_rad.sin();
    wgs84::A_M / (1.0 - wgs84::E2 * s * s).sqrt()
}

/// Magnitude of WGS84 normal gravity at geodetic latitude `L` and height `h`, m/s².
///
/// Somigliana's formula on the ellipsoid (TR8350.2 eq. 4-1; Groves 2013 §2.4),
/// `γ_0(L) = γ_e (1 + k sin² L) / (1 - e² sin² L)^{1/2}`,
/// with the WGS84 second-order free-air correction for height (TR8350.2 eq. 4-3;
/// Titterton & Weston 2004 ch. 3),
/// `γ(L, h) = γ_0(L) [1 - 2/a (1 + f + m - 2 f sin² L) h + 3 h² / a²]`.
///
/// Below the ellipsoid (`h < 0`, an AUV at depth) the same expression is used: the
/// free-air gradient (≈ -3.1e-6 m/s² per m) ignores the attraction of the water
/// above the vehicle, an error of ~1e-6 relative at 20 m depth, far below what a
/// low-cost accelerometer resolves.
pub fn normal_gravity(lat_rad: f64, height_m: f64) -> f64 {
    use wgs84::{A_M, E2, F, GAMMA_EQUATOR_M_S2, M, SOMIGLIANA_K};
    let s2 = lat_rad.sin().powi(2);
    let gamma_0 = GAMMA_EQUATOR_M_S2 * (1.0 + SOMIGLIANA_K * s2) / (1.0 - E2 * s2).sqrt();
    let h = height_m;
    gamma_0 * (1.0 - 2.0 / A_M * (1.0 + F + M - 2.0 * F * s2) * h + 3.0 * h * h / (A_M * A_M))
}

/// Earth rotation rate expressed in NED, `ω_ie^n = ω_ie [cos L, 0, -sin L]`, rad/s.
///
/// Titterton & Weston (2004) ch. 3; Groves (2013) §5.4.
pub fn earth_rate_ned(lat_rad: f64) -> Vector3<f64> {
    let w = wgs84::OMEGA_IE_RAD_S;
    Vector3::new(w * lat_rad.cos(), 0.0, -w * lat_rad.sin())
}

/// Transport rate (rotation of NED with respect to the Earth) expressed in NED,
/// `ω_en^n = [v_E / (R_E + h), -v_N / (R_N + h), -v_E tan L / (R_E + h)]`, rad/s.
///
/// Titterton & Weston (2004) ch. 3; Groves (2013) §5.4. `R_N`, `R_E` as in
/// [`meridian_radius`] and [`transverse_radius`]. Singular at the poles (`tan L`).
pub fn transport_rate_ned(lat_rad: f64, height_m: f64, v_ned_m_s: &Vector3<f64>) -> Vector3<f64> {
    let r_n = meridian_radius(lat_rad) + height_m;
    let r_e = transverse_radius(lat_rad) + height_m;
    let (v_n, v_e) = (v_ned_m_s.x, v_ned_m_s.y);
    Vector3::new(v_e / r_e, -v_n / r_n, -v_e * lat_rad.tan() / r_e)
}

/// A validated geodetic position on WGS84.
/// Built only through [`Geodetic::new`] or [`ecef_to_geodetic`], so its latitude is
/// always within ±π/2 and every field is finite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geodetic {
    lat_rad: f64,
    lon_rad: f64,
    height_m: f64,
}

/// Why a [`Geodetic`] position could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum GeodeticNewError {
    /// Latitude outside [-π/2, π/2] (or NaN); it is not wrapped silently.
    #[error("latitude {0} rad is outside [-pi/2, pi/2]")]
    LatitudeOutOfRange(f64),
    /// Longitude or height is NaN or infinite.
    #[error("longitude or height is not finite")]
    NonFinite,
}

impl Geodetic {
    /// Builds a position from latitude and longitude in radians and height above
    /// the ellipsoid in metres. Longitude is wrapped to [-π, π); latitude is not.
    pub fn new(lat_rad: f64, lon_rad: f64, height_m: f64) -> Result<Self, GeodeticNewError> {
        if lat_rad.is_nan() || lat_rad.abs() > std::f64::consts::FRAC_PI_2 {
            return Err(GeodeticNewError::LatitudeOutOfRange(lat_rad));
        }
        if !lon_rad.is_finite() || !height_m.is_finite() {
            return Err(GeodeticNewError::NonFinite);
        }
        Ok(Self {
            lat_rad,
            lon_rad: crate::attitude::wrap_pi(lon_rad),
            height_m,
        })
    }

    /// Geodetic latitude, rad.
    pub fn lat_rad(&self) -> f64 {
        self.lat_rad
    }

    /// Longitude, rad, in [-π, π).
    pub fn lon_rad(&self) -> f64 {
        self.lon_rad
    }

    /// Height above the ellipsoid, m (positive up).
    pub fn height_m(&self) -> f64 {
        self.height_m
    }
}

/// Why an ECEF position has no geodetic equivalent here.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum EcefToGeodeticError {
    /// A coordinate is NaN or infinite.
    #[error("ECEF position is not finite")]
    NonFinite,
    /// The point lies within ~43 km of the Earth's centre (inside the evolute of the
    /// ellipse), where the geodetic latitude is not unique.
    #[error("ECEF position is too close to the Earth's centre")]
    NearCentre,
}

/// Geodetic → ECEF, m.
///
/// Groves (2013) §2.4; Farrell (2008) ch. 2:
/// `x = (R_E + h) cos L cos λ`, `y = (R_E + h) cos L sin λ`,
/// `z = (R_E (1 - e²) + h) sin L`, with `R_E` the transverse radius.
pub fn geodetic_to_ecef(p: &Geodetic) -> Vector3<f64> {
    let (sl, cl) = p.lat_rad.sin_cos();
    let (so, co) = p.lon_rad.sin_cos();
    let r_e = transverse_radius(p.lat_rad);
    Vector3::new(
        (r_e + p.height_m) * cl * co,
        (r_e + p.height_m) * cl * so,
        (r_e * (1.0 - wgs84::E2) + p.height_m) * sl,
    )
}

/// ECEF → geodetic, closed form (Vermeille 2002, "Direct transformation from
/// geocentric coordinates to geodetic coordinates", J. Geodesy 76:451-454).
///
/// Exact (no iteration) everywhere outside a small region around the Earth's
/// centre; accurate to well below a micrometre and 1e-14 rad for any point from
/// the deepest ocean to geostationary orbit (see the round-trip tests).
pub fn ecef_to_geodetic(r_e_m: &Vector3<f64>) -> Result<Geodetic, EcefToGeodeticError> {
    use wgs84::{A_M, E2};
    let (x, y, z) = (r_e_m.x, r_e_m.y, r_e_m.z);
    if !(x.is_finite() && y.is_finite() && z.is_finite()) {
        return Err(EcefToGeodeticError::NonFinite);
    }
    let e4 = E2 * E2;
    let rho = x.hypot(y);
    let p = (rho / A_M).powi(2);
    let q = (1.0 - E2) / (A_M * A_M) * z * z;
    let r = (p + q - e4) / 6.0;
    // r is positive outside the evolute.
    if r.is_nan() || r <= 0.0 {
        return Err(EcefToGeodeticError::NearCentre);
    }
    let s = e4 * p * q / (4.0 * r * r * r);
    let t = (1.0 + s + (s * (2.0 + s)).sqrt()).cbrt();
    let u = r * (1.0 + t + 1.0 / t);
    let v = (u * u + e4 * q).sqrt();
    let w = E2 * (u + v - q) / (2.0 * v);
    let k = (u + v + w * w).sqrt() - w;
    let d = k * rho / (k + E2);
    let dz = d.hypot(z);
    let lat = 2.0 * z.atan2(d + dz);
    let h = (k + E2 - 1.0) / k * dz;
    let lon = y.atan2(x);
    Ok(Geodetic {
        lat_rad: lat,
        lon_rad: crate::attitude::wrap_pi(lon),
        height_m: h,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::f64::consts::FRAC_PI_2;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn constants_match_the_published_values() {
        assert!(close(wgs84::E2, 6.694_379_990_14e-3, 1e-14));
        assert!(close(wgs84::B_M, 6_356_752.314_245_179, 1e-6));
        // k and m follow from the defining constants.
        let k =
            wgs84::B_M * wgs84::GAMMA_POLE_M_S2 / (wgs84::A_M * wgs84::GAMMA_EQUATOR_M_S2) - 1.0;
        assert!(close(k, wgs84::SOMIGLIANA_K, 1e-11));
        let m = wgs84::OMEGA_IE_RAD_S.powi(2) * wgs84::A_M.powi(2) * wgs84::B_M / wgs84::GM_M3_S2;
        assert!(close(m, wgs84::M, 1e-14));
    }

    #[test]
    fn radii_at_equator_45_and_pole() {
        let a = wgs84::A_M;
        let e2 = wgs84::E2;
        assert!(close(meridian_radius(0.0), a * (1.0 - e2), 1e-6));
        assert!(close(transverse_radius(0.0), a, 1e-6));
        let polar = a / (1.0 - e2).sqrt();
        assert!(close(meridian_radius(FRAC_PI_2), polar, 1e-6));
        assert!(close(transverse_radius(FRAC_PI_2), polar, 1e-6));
        // 40-digit reference values (mpmath).
        let l45 = 45f64.to_radians();
        assert!(close(meridian_radius(l45), 6_367_381.815_619_549, 1e-6));
        assert!(close(transverse_radius(l45), 6_388_838.290_121_148, 1e-6));
        // The meridian radius is the smaller one everywhere but at the poles.
        for deg in [-80.0f64, -30.0, 0.0, 10.0, 60.0] {
            let l = deg.to_radians();
            assert!(meridian_radius(l) < transverse_radius(l));
        }
    }

    #[test]
    fn normal_gravity_golden() {
        // On the ellipsoid the formula must give the defining values γ_e, γ_p.
        assert!(close(normal_gravity(0.0, 0.0), 9.780_325_335_9, 1e-10));
        assert!(close(normal_gravity(FRAC_PI_2, 0.0), 9.832_184_937_8, 1e-9));
        assert!(close(
            normal_gravity(FRAC_PI_2, 0.0),
            normal_gravity(-FRAC_PI_2, 0.0),
            1e-15
        ));
        // 30-digit reference evaluations of TR8350.2 eqs. 4-1 and 4-3.
        assert!(close(
            normal_gravity(45f64.to_radians(), 0.0),
            9.806_197_769_37,
            1e-9
        ));
        assert!(close(
            normal_gravity((-23.8f64).to_radians(), -20.0),
            9.788_801_124_205,
            1e-9
        ));
        assert!(close(
            normal_gravity(60f64.to_radians(), 1000.0),
            9.816_093_205_939,
            1e-9
        ));
        // Free-air gradient ≈ -3.086e-6 m/s² per metre.
        let grad = (normal_gravity(0.7, 100.0) - normal_gravity(0.7, 0.0)) / 100.0;
        assert!(close(grad, -3.086e-6, 0.01e-6));
    }

    #[test]
    fn earth_rate_components() {
        let l = 0.6;
        let w = earth_rate_ned(l);
        assert!(close(w.norm(), 7.292_115e-5, 1e-18));
        assert!(close(w.x, 7.292_115e-5 * l.cos(), 1e-18));
        assert!(close(w.y, 0.0, 0.0));
        assert!(close(w.z, -7.292_115e-5 * l.sin(), 1e-18));
        // Northern hemisphere: the Earth's axis points up out of the ground (negative down).
        assert!(w.z < 0.0);
    }

    #[test]
    fn transport_rate_components_and_magnitude() {
        let l = 0.7;
        let h = -20.0;
        let v = Vector3::new(1.0, 1.5, 0.1);
        let w = transport_rate_ned(l, h, &v);
        let rn = meridian_radius(l) + h;
        let re = transverse_radius(l) + h;
        assert!(close(w.x, 1.5 / re, 1e-20));
        assert!(close(w.y, -1.0 / rn, 1e-20));
        assert!(close(w.z, -1.5 * l.tan() / re, 1e-20));
        // AUV speed: of order 1.5 m/s / 6.4e6 m ≈ 2.3e-7 rad/s.
        let east = transport_rate_ned(0.0, 0.0, &Vector3::new(0.0, 1.5, 0.0));
        assert!(close(east.norm(), 1.5 / wgs84::A_M, 1e-20));
        // Latitude rate from the north component matches the meridian radius.
        assert!(close(-w.y, v.x / rn, 1e-20));
    }

    #[test]
    fn geodetic_new_validates() {
        assert!(Geodetic::new(FRAC_PI_2, 0.0, 0.0).is_ok());
        assert_eq!(
            Geodetic::new(1.6, 0.0, 0.0),
            Err(GeodeticNewError::LatitudeOutOfRange(1.6))
        );
        assert!(matches!(
            Geodetic::new(f64::NAN, 0.0, 0.0),
            Err(GeodeticNewError::LatitudeOutOfRange(_))
        ));
        assert_eq!(
            Geodetic::new(0.0, f64::INFINITY, 0.0),
            Err(GeodeticNewError::NonFinite)
        );
        assert_eq!(
            Geodetic::new(0.0, 0.0, f64::NAN),
            Err(GeodeticNewError::NonFinite)
        );
        let p = Geodetic::new(0.1, 3.0 * std::f64::consts::PI, 5.0).expect("valid");
        assert!(close(p.lon_rad(), -std::f64::consts::PI, 1e-12));
    }

    /// Reference values from an independent 40-digit implementation (mpmath,
    /// fixed-point iteration to convergence), not from these formulas in f64.
    #[test]
    fn geodetic_ecef_golden() {
        let cases = [
            (
                (-0.415_388_361_974_650_44, -0.792_379_480_405_425_6, -20.0),
                (
                    4_099_803.843_947_795,
                    -4_157_451.296_255_987_5,
                    -2_558_023.397_047_492_7,
                ),
            ),
            (
                (0.722_217_244_475_253_6, 0.037_873_644_768_276_95, 120.0),
                (
                    4_789_451.634_303_348,
                    181_480.770_921_869_66,
                    4_194_260.643_437_028,
                ),
            ),
            (
                (1.569_050_997_542_902_3, 2.617_993_877_991_494_4, 5000.0),
                (
                    -9_680.534_858_090_215,
                    5_589.059_406_217_942,
                    6_361_742.559_493_88,
                ),
            ),
            (
                (-1.047_197_551_196_597_7, -2.967_059_728_390_360_3, -3000.0),
                (
                    -3_147_056.172_764_078,
                    -554_910.913_063_427_2,
                    -5_497_879.057_727_286,
                ),
            ),
        ];
        for ((lat, lon, h), (x, y, z)) in cases {
            let g = Geodetic::new(lat, lon, h).expect("valid");
            let r = geodetic_to_ecef(&g);
            assert!(
                (r - Vector3::new(x, y, z)).norm() < 1e-6,
                "{r:?} vs {x} {y} {z}"
            );
            let back = ecef_to_geodetic(&Vector3::new(x, y, z)).expect("outside the evolute");
            assert!(close(back.lat_rad(), lat, 1e-14), "{back:?}");
            assert!(close(back.lon_rad(), lon, 1e-14), "{back:?}");
            assert!(close(back.height_m(), h, 1e-6), "{back:?}");
        }
        // ECEF points not generated from geodetic ones.
        let g = ecef_to_geodetic(&Vector3::new(4.0e6, 3.0e6, 3.5e6)).expect("valid");
        assert!(close(g.lat_rad(), 0.614_024_108_427_259_1, 1e-14));
        assert!(close(g.lon_rad(), 0.643_501_108_793_284_4, 1e-14));
        assert!(close(g.height_m(), -267_801.449_618_955_1, 1e-6));
        let g = ecef_to_geodetic(&Vector3::new(-1000.0, 2000.0, 6.4e6)).expect("valid");
        assert!(close(g.lat_rad(), 1.570_449_264_407_278, 1e-14));
        assert!(close(g.lon_rad(), 2.034_443_935_795_702_7, 1e-14));
        assert!(close(g.height_m(), 43_248.073_782_369_89, 1e-6));
    }

    #[test]
    fn ecef_special_points() {
        let a = wgs84::A_M;
        let b = wgs84::B_M;
        let origin = Geodetic::new(0.0, 0.0, 0.0).expect("valid");
        assert!((geodetic_to_ecef(&origin) - Vector3::new(a, 0.0, 0.0)).norm() < 1e-9);
        let north = ecef_to_geodetic(&Vector3::new(0.0, 0.0, b + 10.0)).expect("valid");
        assert!(close(north.lat_rad(), FRAC_PI_2, 1e-15));
        assert!(close(north.height_m(), 10.0, 1e-8));
        let south = ecef_to_geodetic(&Vector3::new(0.0, 0.0, -b)).expect("valid");
        assert!(close(south.lat_rad(), -FRAC_PI_2, 1e-15));
        assert!(close(south.height_m(), 0.0, 1e-8));
        let eq = ecef_to_geodetic(&Vector3::new(0.0, -a - 5.0, 0.0)).expect("valid");
        assert!(close(eq.lat_rad(), 0.0, 1e-15));
        assert!(close(eq.lon_rad(), -FRAC_PI_2, 1e-15));
        assert!(close(eq.height_m(), 5.0, 1e-8));
        assert_eq!(
            ecef_to_geodetic(&Vector3::new(0.0, 0.0, 0.0)),
            Err(EcefToGeodeticError::NearCentre)
        );
        assert_eq!(
            ecef_to_geodetic(&Vector3::new(f64::NAN, 0.0, 0.0)),
            Err(EcefToGeodeticError::NonFinite)
        );
    }

    proptest! {
        #[test]
        fn geodetic_ecef_round_trip(
            lat in -FRAC_PI_2..=FRAC_PI_2,
            lon in -std::f64::consts::PI..std::f64::consts::PI,
            h in -11_000.0f64..40_000_000.0,
        ) {
            let g = Geodetic::new(lat, lon, h).expect("valid");
            let r = geodetic_to_ecef(&g);
            let back = ecef_to_geodetic(&r).expect("outside the evolute");
            prop_assert!(close(back.lat_rad(), lat, 1e-14), "lat {} vs {}", back.lat_rad(), lat);
            // Longitude is undefined at the poles; compare positions there instead.
            if lat.abs() < FRAC_PI_2 - 1e-9 {
                let dlon = crate::attitude::wrap_pi(back.lon_rad() - lon);
                prop_assert!(dlon.abs() <= 1e-14, "lon {} vs {}", back.lon_rad(), lon);
            }
            // Relative to the distance from the centre: f64 resolves ~1e-16 of it.
            let tol_h = 1e-6 + 1e-15 * r.norm();
            prop_assert!(close(back.height_m(), h, tol_h), "h {} vs {}", back.height_m(), h);
            prop_assert!((geodetic_to_ecef(&back) - r).norm() <= tol_h);
        }
    }
}
