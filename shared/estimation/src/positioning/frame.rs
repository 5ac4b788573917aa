//! The frame both positioning filters work in: offsets north and east (m)
//! of the vehicle from a centre, the dead-reckoned position that eq. 50
//! moves with the navigation's velocity. The filters hold only the
//! offsets' distribution; after each update the centre takes the mean and
//! the offsets are recentred, so they stay metres wide and the mapping of
//! an offset to latitude and longitude (paper 002 eq. 4's flat form about
//! the centre) is exact to micrometres.

use crate::earth::{meridian_radius, transverse_radius};
use crate::local::flat;
use crate::positioning::geometry::{haversine_m, radius_in_azimuth, slant_range_m};
use crate::positioning::process::{BE, BN, DIM, E, N, SOUND};

/// One buoy range, as the filters use it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeObs {
    /// Measured slant range, m.
    pub range_m: f64,
    /// Its variance (eq. 54's σ_d²), m².
    pub var_m2: f64,
    /// Latitude of the point the buoy's offsets are from, rad (its
    /// broadcast position when the buoy is not tracked).
    pub buoy_lat_rad: f64,
    /// Its longitude, rad.
    pub buoy_lon_rad: f64,
    /// Depth of the vehicle, m.
    pub depth_m: f64,
    /// Depth of the buoy's transducer, m.
    pub buoy_depth_m: f64,
}

/// The centre's mapping of offsets for one range: what eqs. 51-53 need
/// per particle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeFrame {
    lat_rad: f64,
    lon_rad: f64,
    r_north: f64,
    r_east: f64,
    /// The same at the buoy's reference.
    buoy_r_north: f64,
    buoy_r_east: f64,
    radius: f64,
    obs: RangeObs,
}

impl RangeFrame {
    /// The frame of a centre at `(lat, lon)` (rad) for `obs`.
    pub fn new(lat_rad: f64, lon_rad: f64, obs: RangeObs) -> Self {
        let (bn, be) = flat::to_local(lat_rad, lon_rad, obs.buoy_lat_rad, obs.buoy_lon_rad);
        // The sphere of the direction of the buoy (geometry.rs):
        // the cloud spans metres, so one azimuth serves every particle.
        let azimuth = be.atan2(bn);
        Self {
            lat_rad,
            lon_rad,
            r_north: meridian_radius(lat_rad),
            r_east: transverse_radius(lat_rad) * lat_rad.cos(),
            buoy_r_north: meridian_radius(obs.buoy_lat_rad),
            buoy_r_east: transverse_radius(obs.buoy_lat_rad) * obs.buoy_lat_rad.cos(),
            radius: radius_in_azimuth(lat_rad, azimuth),
            obs,
        }
    }

    /// The range this frame's observation measured.
    pub fn obs(&self) -> &RangeObs {
        &self.obs
    }

    /// Eqs. 51-53: the slant range from the buoy at offset `buoy` (north,
    /// east, m) from its reference to the vehicle at offset `(north,
    /// east)` from the centre, m.
    pub fn predicted_m(&self, north_m: f64, east_m: f64, buoy: [f64; 2]) -> f64 {
        let lat = self.lat_rad + north_m / self.r_north;
        let lon = self.lon_rad + east_m / self.r_east;
        let h = haversine_m(
            lat,
            lon,
            self.obs.buoy_lat_rad + buoy[0] / self.buoy_r_north,
            self.obs.buoy_lon_rad + buoy[1] / self.buoy_r_east,
            self.radius,
        );
        slant_range_m(h, self.obs.depth_m, self.obs.buoy_depth_m)
    }

    /// The gradient of [`Self::predicted_m`] with the vehicle's offset at
    /// `(north, east)`, per m (the EKF's `H`, and the gate's line of
    /// sight; the buoy's is its negative): by central differences of a
    /// centimetre, exact to 10⁻⁸ for ranges of metres and more (the unit
    /// vector from the buoy, scaled by horizontal over slant range).
    pub fn gradient(&self, north_m: f64, east_m: f64, buoy: [f64; 2]) -> [f64; 2] {
        const H: f64 = 0.01;
        let p = |n, e| self.predicted_m(n, e, buoy);
        [
            (p(north_m + H, east_m) - p(north_m - H, east_m)) / (2.0 * H),
            (p(north_m, east_m + H) - p(north_m, east_m - H)) / (2.0 * H),
        ]
    }
}

/// A range's row of `H` at the state `x` and the range `h(x)` it
/// predicts: `h(x) = (1 + s) ρ(n, e, b_n, b_e)` ([`super::process`]'s
/// values), `∂h/∂(n, e) = (1 + s) ∂ρ/∂(n, e)`, `∂h/∂(b_n, b_e)` its
/// negative, `∂h/∂s = ρ`.
pub fn range_row(f: &RangeFrame, x: &[f64; DIM]) -> ([f64; DIM], f64) {
    let buoy = [x[BN], x[BE]];
    let rho = f.predicted_m(x[N], x[E], buoy);
    let g = f.gradient(x[N], x[E], buoy);
    let scale = 1.0 + x[SOUND];
    let mut h = [0.0; DIM];
    h[N] = scale * g[0];
    h[E] = scale * g[1];
    h[BN] = -scale * g[0];
    h[BE] = -scale * g[1];
    h[SOUND] = rho;
    (h, scale * rho)
}

/// Paper 000 eq. 50 for the centre: `dt` s at north and east velocity
/// `v` (m/s) at depth `depth_m`. Eq. 50's radius reads "R + z" with R =
/// 6 378 137 m; we take the WGS84 meridian and transverse radii at the
/// latitude (paper 002 eq. 4's names) less the depth, the radii at the
/// vehicle (the difference is 10⁻⁵ of the distance).
pub fn advance(lat_rad: f64, lon_rad: f64, v: [f64; 2], depth_m: f64, dt: f64) -> (f64, f64) {
    let lat = lat_rad + dt * v[0] / (meridian_radius(lat_rad) - depth_m);
    let lon = lon_rad + dt * v[1] / ((transverse_radius(lat_rad) - depth_m) * lat_rad.cos());
    (lat, lon)
}

/// The centre moved by an offset `(north, east)`, m.
pub fn moved(lat_rad: f64, lon_rad: f64, north_m: f64, east_m: f64) -> (f64, f64) {
    flat::to_geodetic(lat_rad, lon_rad, north_m, east_m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gradient_is_the_predicted_ranges_slope() {
        let (lat, lon) = (38.7f64.to_radians(), (-9.1f64).to_radians());
        let (blat, blon) = moved(lat, lon, 120.0, -250.0);
        let f = RangeFrame::new(
            lat,
            lon,
            RangeObs {
                range_m: 0.0,
                var_m2: 1.0,
                buoy_lat_rad: blat,
                buoy_lon_rad: blon,
                depth_m: 30.0,
                buoy_depth_m: 1.0,
            },
        );
        let at = [0.0; 2];
        let g = f.gradient(2.0, 3.0, at);
        let h = 1e-3;
        let dn = (f.predicted_m(2.0 + h, 3.0, at) - f.predicted_m(2.0 - h, 3.0, at)) / (2.0 * h);
        let de = (f.predicted_m(2.0, 3.0 + h, at) - f.predicted_m(2.0, 3.0 - h, at)) / (2.0 * h);
        assert!(
            (g[0] - dn).abs() < 1e-4 && (g[1] - de).abs() < 1e-4,
            "{g:?} {dn} {de}"
        );
        // The unit vector from the buoy, scaled by horizontal over slant,
        // to the sphere's isotropy: one radius for the line's azimuth
        // turns the gradient by ~(R_N − R_M)/R (0.4 %), which moves a
        // particle's range by centimetres across a cloud of metres.
        let (hn, he) = (2.0 - 120.0, 3.0 + 250.0);
        let slant = (hn * hn + he * he + 29.0f64 * 29.0).sqrt();
        assert!(
            (g[0] - hn / slant).abs() < 1e-2 && (g[1] - he / slant).abs() < 1e-2,
            "{g:?}"
        );
        let d = f.predicted_m(0.0, 0.0, at);
        assert!((d - (120f64.hypot(250.0)).hypot(29.0)).abs() < 0.01, "{d}");
        // The buoy moved by an offset is the vehicle moved by its opposite.
        let moved_buoy = f.predicted_m(0.0, 0.0, [3.0, -4.0]);
        let moved_vehicle = f.predicted_m(-3.0, 4.0, at);
        assert!(
            (moved_buoy - moved_vehicle).abs() < 1e-3,
            "{moved_buoy} {moved_vehicle}"
        );
    }
}
