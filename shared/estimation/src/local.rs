//! Local north/east/down coordinates about a declared origin (DESIGN §4: LBL
//! positions are north/east metres from the run's origin), in two forms:
//!
//! - [`LocalTangentPlane`]: exact. The tangent plane to the WGS84 ellipsoid at
//!   the origin, reached through ECEF (as geographiclib's `LocalCartesian`):
//!   `n_ned = C_e^n(L₀, λ₀) (r_e(L, λ, h) − r_e(L₀, λ₀, h₀))`. Every tool that
//!   places a local position on the globe (the simulator's missions, eval,
//!   export, report) uses this one. It is checked against pymap3d's
//!   `geodetic2ned` in `tests/tests/projection.rs` (1 mm within 10 km).
//! - [`flat`]: paper 002 eq. 4, `L = L₀ + n / R_N(L₀)`, `λ = λ₀ + e / (R_E(L₀) cos L₀)`,
//!   with the standard meridian (`R_N`) and prime-vertical (`R_E`) radii at the
//!   origin (the paper's text swaps their names, see [`crate::earth`]). It is
//!   what paper 002's dead reckoning integrates, and the `dr` estimator uses
//!   it as the paper does. Its horizontal error against the exact plane, at
//!   38.6° N and the surface, worst over 16 bearings (measured by
//!   `paper_002_flat_form_error_grows_as_the_square_of_the_distance` below,
//!   `cargo test -p nauta-estimation --lib local -- --nocapture`): 0.07 m at
//!   1 km, 0.63 m at 3 km, 7.0 m at 10 km from the origin (it grows as the
//!   square of the distance: the convergence of the meridians and the
//!   change of the radii with latitude).

use nalgebra::{Matrix3, Vector3};

use crate::earth::{
    EcefToGeodeticError, Geodetic, GeodeticNewError, ecef_to_geodetic, geodetic_to_ecef,
    meridian_radius, transverse_radius,
};

/// North, east and down of a point from the origin, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ned {
    /// North, m.
    pub north_m: f64,
    /// East, m.
    pub east_m: f64,
    /// Down, m.
    pub down_m: f64,
}

/// The exact local tangent plane at an origin on the WGS84 ellipsoid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalTangentPlane {
    origin: Geodetic,
    origin_ecef: Vector3<f64>,
    /// `C_e^n`: ECEF to NED at the origin.
    c_en: Matrix3<f64>,
}

impl LocalTangentPlane {
    /// The plane at latitude/longitude (rad) and ellipsoidal height (m); a
    /// latitude beyond ±90° or a non-finite value is an error.
    pub fn new(lat_rad: f64, lon_rad: f64, height_m: f64) -> Result<Self, GeodeticNewError> {
        let origin = Geodetic::new(lat_rad, lon_rad, height_m)?;
        let (sl, cl) = lat_rad.sin_cos();
        let (so, co) = lon_rad.sin_cos();
        // Rows: north, east, down unit vectors in ECEF (Groves 2013, eq. 2.150).
        let c_en = Matrix3::new(
            -sl * co,
            -sl * so,
            cl, //
            -so,
            co,
            0.0, //
            -cl * co,
            -cl * so,
            -sl,
        );
        Ok(Self {
            origin,
            origin_ecef: geodetic_to_ecef(&origin),
            c_en,
        })
    }

    /// The plane at the sea surface (height 0) under `lat_deg`, `lon_deg`.
    pub fn from_degrees(lat_deg: f64, lon_deg: f64) -> Result<Self, GeodeticNewError> {
        Self::new(lat_deg.to_radians(), lon_deg.to_radians(), 0.0)
    }

    /// The origin.
    pub fn origin(&self) -> Geodetic {
        self.origin
    }

    /// North/east/down of a geodetic point.
    pub fn to_local(&self, p: &Geodetic) -> Ned {
        let n = self.c_en * (geodetic_to_ecef(p) - self.origin_ecef);
        Ned {
            north_m: n.x,
            east_m: n.y,
            down_m: n.z,
        }
    }

    /// North/east of a point at the origin's height (what a 2-D track needs).
    pub fn to_local_horizontal(&self, lat_rad: f64, lon_rad: f64) -> (f64, f64) {
        let p = Geodetic::new(lat_rad, lon_rad, self.origin.height_m()).unwrap_or(self.origin);
        let n = self.to_local(&p);
        (n.north_m, n.east_m)
    }

    /// The geodetic point at north/east/down from the origin.
    pub fn to_geodetic(&self, n: &Ned) -> Result<Geodetic, EcefToGeodeticError> {
        let r =
            self.origin_ecef + self.c_en.transpose() * Vector3::new(n.north_m, n.east_m, n.down_m);
        ecef_to_geodetic(&r)
    }

    /// Latitude and longitude (rad) of a point north/east of the origin on
    /// the local horizontal surface: at the origin's height, so that it
    /// round-trips with [`Self::to_local_horizontal`].
    pub fn to_geodetic_horizontal(&self, north_m: f64, east_m: f64) -> (f64, f64) {
        // The plane drops below the ellipsoid away from the origin; the point
        // of the horizontal surface is the one at the origin's height with
        // these north/east: two fixed-point steps on the down component reach
        // it to far below a millimetre within 100 km.
        let mut down = 0.0;
        let mut out = (self.origin.lat_rad(), self.origin.lon_rad());
        for _ in 0..3 {
            let Ok(g) = self.to_geodetic(&Ned {
                north_m,
                east_m,
                down_m: down,
            }) else {
                return out;
            };
            out = (g.lat_rad(), g.lon_rad());
            let on_surface = Geodetic::new(g.lat_rad(), g.lon_rad(), self.origin.height_m())
                .unwrap_or(self.origin);
            down = self.to_local(&on_surface).down_m;
        }
        out
    }
}

/// North and east (m) of `(lat, lon)` on the exact plane at the surface
/// origin `(lat0, lon0)` (rad): what every local origin of nauta
/// computes. NaN when the origin is not a position (a latitude beyond ±90°,
/// a non-finite value), which every input check then refuses.
pub fn north_east_of(lat0_rad: f64, lon0_rad: f64, lat_rad: f64, lon_rad: f64) -> (f64, f64) {
    LocalTangentPlane::new(lat0_rad, lon0_rad, 0.0).map_or((f64::NAN, f64::NAN), |p| {
        p.to_local_horizontal(lat_rad, lon_rad)
    })
}

/// Latitude and longitude (rad) of the point `north_m`, `east_m` from the
/// surface origin `(lat0, lon0)` on the exact plane; NaN as [`north_east_of`].
pub fn geodetic_of(lat0_rad: f64, lon0_rad: f64, north_m: f64, east_m: f64) -> (f64, f64) {
    LocalTangentPlane::new(lat0_rad, lon0_rad, 0.0).map_or((f64::NAN, f64::NAN), |p| {
        p.to_geodetic_horizontal(north_m, east_m)
    })
}

/// Paper 002 eq. 4: the flat-Earth approximation about an origin.
pub mod flat {
    use super::{meridian_radius, transverse_radius};

    /// Latitude and longitude (rad) of a point `north_m`, `east_m` from the
    /// origin (rad): `L = L₀ + n / R_N(L₀)`, `λ = λ₀ + e / (R_E(L₀) cos L₀)`.
    pub fn to_geodetic(lat0_rad: f64, lon0_rad: f64, north_m: f64, east_m: f64) -> (f64, f64) {
        (
            lat0_rad + north_m / meridian_radius(lat0_rad),
            lon0_rad + east_m / (transverse_radius(lat0_rad) * lat0_rad.cos()),
        )
    }

    /// The inverse of [`to_geodetic`]: north and east of a point from the
    /// origin, m (longitude difference wrapped to ±π).
    pub fn to_local(lat0_rad: f64, lon0_rad: f64, lat_rad: f64, lon_rad: f64) -> (f64, f64) {
        let dlon = (lon_rad - lon0_rad + std::f64::consts::PI)
            .rem_euclid(2.0 * std::f64::consts::PI)
            - std::f64::consts::PI;
        (
            (lat_rad - lat0_rad) * meridian_radius(lat0_rad),
            dlon * transverse_radius(lat0_rad) * lat0_rad.cos(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAT0: f64 = 38.6;
    const LON0: f64 = -9.3;

    fn plane() -> LocalTangentPlane {
        LocalTangentPlane::from_degrees(LAT0, LON0).expect("valid origin")
    }

    #[test]
    fn the_origin_is_zero_and_axes_point_north_east_down() {
        let p = plane();
        let o = p.to_local(&p.origin());
        assert!(o.north_m.abs() < 1e-9 && o.east_m.abs() < 1e-9 && o.down_m.abs() < 1e-9);
        let north =
            Geodetic::new((LAT0 + 0.001).to_radians(), LON0.to_radians(), 0.0).expect("valid");
        let n = p.to_local(&north);
        assert!(n.north_m > 100.0 && n.east_m.abs() < 1e-6, "{n:?}");
        let up = Geodetic::new(LAT0.to_radians(), LON0.to_radians(), 10.0).expect("valid");
        assert!((p.to_local(&up).down_m + 10.0).abs() < 1e-9);
    }

    #[test]
    fn local_and_geodetic_round_trip_to_the_micrometre() {
        let p = plane();
        for (n, e, d) in [
            (0.0, 0.0, 0.0),
            (9_000.0, -4_000.0, 15.0),
            (-7_000.0, 7_000.0, -3.0),
        ] {
            let g = p
                .to_geodetic(&Ned {
                    north_m: n,
                    east_m: e,
                    down_m: d,
                })
                .expect("geodetic");
            let back = p.to_local(&g);
            assert!(
                (back.north_m - n).abs() < 1e-6
                    && (back.east_m - e).abs() < 1e-6
                    && (back.down_m - d).abs() < 1e-6,
                "{back:?} against ({n}, {e}, {d})"
            );
            let (lat, lon) = p.to_geodetic_horizontal(n, e);
            let (n2, e2) = p.to_local_horizontal(lat, lon);
            assert!(
                (n2 - n).abs() < 1e-6 && (e2 - e).abs() < 1e-6,
                "({n2}, {e2}) against ({n}, {e})"
            );
        }
    }

    /// The flat form's error against the exact plane, as documented above.
    #[test]
    fn paper_002_flat_form_error_grows_as_the_square_of_the_distance() {
        let p = plane();
        let (lat0, lon0) = (LAT0.to_radians(), LON0.to_radians());
        let mut worst = Vec::new();
        for d in [1_000.0, 3_000.0, 10_000.0] {
            let mut w: f64 = 0.0;
            for k in 0..16 {
                let a = k as f64 * std::f64::consts::PI / 8.0;
                let (n, e) = (d * a.cos(), d * a.sin());
                let (lat, lon) = flat::to_geodetic(lat0, lon0, n, e);
                let (ne, ee) = p.to_local_horizontal(lat, lon);
                w = w.max(((ne - n).powi(2) + (ee - e).powi(2)).sqrt());
            }
            worst.push(w);
        }
        eprintln!("flat form error at 1, 3, 10 km: {worst:?} m");
        assert!(
            worst[0] < 0.1 && worst[1] < 1.0 && worst[2] < 10.0,
            "{worst:?}"
        );
        assert!(
            worst[2] > 10.0 * worst[0],
            "grows faster than the distance: {worst:?}"
        );
        let (n, e) = flat::to_local(lat0, lon0, lat0 + 1e-4, lon0 - 1e-4);
        let (lat, lon) = flat::to_geodetic(lat0, lon0, n, e);
        assert!((lat - lat0 - 1e-4).abs() < 1e-15 && (lon - lon0 + 1e-4).abs() < 1e-15);
    }
}
