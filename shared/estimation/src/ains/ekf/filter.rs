//! The running filter: the total (nominal) navigation state on the WGS84
//! strapdown, the bias estimates, the error covariance, and the closed-loop
//! correction that feeds an error-state estimate back into them (Groves
//! 2013 ch. 14, closed-loop correction: the error state is zero after
//! every update, so it is not kept).

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use super::model::{
    ATT, BA, BG, BH, Block, Cov, DA, DC, ErrorState, HeadingBias, N, POS, VEL, propagate_covariance,
};
use super::params::EkfConfig;
use super::snapshot::{FilterState, from_upper, upper};
use crate::attitude::wrap_pi;
use crate::earth::{earth_rate_ned, meridian_radius, normal_gravity, transverse_radius};
use crate::frames::{Rotation, Vector};
use crate::readings::Imu;
use crate::strapdown::{MAX_ABS_LATITUDE_RAD, StrapdownError, StrapdownState, propagate};

/// Mean Earth radius for the vertical channel's `2γ/R`, m.
const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// The running filter.
#[derive(Debug, Clone, PartialEq)]
pub struct Filter {
    /// The nominal navigation state.
    pub nav: StrapdownState,
    /// Accelerometer bias estimate, FRD, m/s².
    pub ba: Vector3<f64>,
    /// Gyro bias estimate, FRD, rad/s.
    pub bg: Vector3<f64>,
    /// Heading source bias estimate, rad.
    pub bh: f64,
    /// Heading deviation estimate `[a_ψ, c_ψ]`, rad.
    pub dev: [f64; 2],
    /// Last bias-corrected angular rate, FRD, rad/s.
    pub omega_b: Vector3<f64>,
    /// The manoeuvre: what an accelerometer-levelled heading source errs by
    /// in a turn (`EkfParams::heading_manoeuvre_factor`).
    pub manoeuvre: crate::ains::Manoeuvre,
    /// Error covariance.
    pub p: Cov,
    /// Covariance block accumulated since the last propagation.
    pub block: Block,
}

/// Zeroes the rows and columns of `idx` in `p` and sets their block to `cov`
/// (a re-anchoring: that part of the state is now the measurement's).
pub fn reset_block<const M: usize>(
    p: &mut Cov,
    idx: [usize; M],
    cov: &nalgebra::SMatrix<f64, M, M>,
) {
    for &i in &idx {
        for j in 0..N {
            p[(i, j)] = 0.0;
            p[(j, i)] = 0.0;
        }
    }
    for (a, &i) in idx.iter().enumerate() {
        for (b, &j) in idx.iter().enumerate() {
            p[(i, j)] = cov[(a, b)];
        }
    }
}

impl Filter {
    /// `Ĉ_b^n`.
    pub fn c_nb(&self) -> Matrix3<f64> {
        self.nav
            .q_nb
            .as_nalgebra()
            .to_rotation_matrix()
            .into_inner()
    }

    /// `R_N + h`, `(R_E + h) cos L`: metres per radian of latitude and of
    /// longitude.
    pub fn metres_per_rad(&self) -> (f64, f64) {
        let (l, h) = (self.nav.lat_rad, self.nav.height_m);
        (meridian_radius(l) + h, (transverse_radius(l) + h) * l.cos())
    }

    /// One IMU sample: the strapdown with the bias-corrected sample
    /// (`f̃ − b̂_a`, `ω̃ − b̂_g`), its `f^n` into the covariance block, and the
    /// covariance step once the block holds `covariance_decimation` samples.
    pub fn on_imu(
        &mut self,
        m: &Imu,
        cfg: &EkfConfig,
        bh: HeadingBias,
    ) -> Result<(), StrapdownError> {
        let w = m.gyro_rad_s.to_nalgebra() - self.bg;
        let f = m.accel_m_s2.to_nalgebra() - self.ba;
        let c_before = self.c_nb();
        let step = propagate(
            &self.nav,
            &Vector::from_nalgebra(w),
            &Vector::from_nalgebra(f),
            m.interval_s,
        )?;
        self.nav = step.state;
        self.omega_b = w;
        // The manoeuvre (centripetal acceleration, body frame, the body's
        // velocity from the estimate) for the heading source's error model.
        let v_b = self.c_nb().transpose() * self.nav.v_ned_m_s.to_nalgebra();
        let g = normal_gravity(self.nav.lat_rad, self.nav.height_m);
        self.manoeuvre
            .update(&w, &v_b, g, m.interval_s, cfg.heading_manoeuvre_time_s);
        let c = 0.5 * (c_before + self.c_nb());
        let v = self.nav.v_ned_m_s.to_nalgebra();
        let w_in = earth_rate_ned(self.nav.lat_rad)
            + crate::earth::transport_rate_ned(self.nav.lat_rad, self.nav.height_m, &v);
        self.block.push(
            &step.specific_force_ned_m_s2.to_nalgebra(),
            &c,
            &w_in,
            m.interval_s,
        );
        if self.block.samples >= cfg.covariance_decimation {
            self.flush(cfg, bh);
        }
        Ok(())
    }

    /// Propagates the covariance over the samples accumulated so far (before
    /// a measurement, so that it sees the covariance of its stamp).
    pub fn flush(&mut self, cfg: &EkfConfig, bh: HeadingBias) {
        let g = normal_gravity(self.nav.lat_rad, self.nav.height_m);
        let w_ie = earth_rate_ned(self.nav.lat_rad);
        propagate_covariance(
            &mut self.p,
            &mut self.block,
            cfg,
            bh,
            g / EARTH_RADIUS_M,
            &w_ie,
        );
    }

    /// Feeds the error-state estimate `dx` back (closed loop): attitude
    /// `C ← (I + [φ×]) Ĉ` (as the rotation `exp(φ)` on the nav side),
    /// velocity, position (NED metres into latitude, longitude, height) and
    /// biases. A correction that would leave the mechanization's domain is
    /// refused (state kept): `false`.
    pub fn correct(&mut self, dx: &ErrorState) -> bool {
        let phi = Vector3::new(dx[ATT], dx[ATT + 1], dx[ATT + 2]);
        let (m_lat, m_lon) = self.metres_per_rad();
        let mut nav = self.nav;
        let q = UnitQuaternion::from_scaled_axis(phi) * nav.q_nb.as_nalgebra();
        nav.q_nb = Rotation::from_nalgebra(UnitQuaternion::new_normalize(q.into_inner()));
        nav.v_ned_m_s = Vector::from_nalgebra(
            nav.v_ned_m_s.to_nalgebra() + Vector3::new(dx[VEL], dx[VEL + 1], dx[VEL + 2]),
        );
        nav.lat_rad += dx[POS] / m_lat;
        nav.lon_rad = wrap_pi(nav.lon_rad + dx[POS + 1] / m_lon);
        nav.height_m -= dx[POS + 2];
        if nav.validate().is_err() || nav.lat_rad.abs() > MAX_ABS_LATITUDE_RAD {
            return false;
        }
        self.nav = nav;
        self.ba += Vector3::new(dx[BA], dx[BA + 1], dx[BA + 2]);
        self.bg += Vector3::new(dx[BG], dx[BG + 1], dx[BG + 2]);
        self.bh += dx[BH];
        self.dev[0] += dx[DA];
        self.dev[1] += dx[DC];
        true
    }

    /// The plain state.
    pub fn state(&self) -> FilterState {
        FilterState {
            q_nb_wxyz: self.nav.q_nb.to_wxyz(),
            v_ned_m_s: self.nav.v_ned_m_s.to_array(),
            lat_lon_height: [self.nav.lat_rad, self.nav.lon_rad, self.nav.height_m],
            accel_bias_m_s2: self.ba.into(),
            gyro_bias_rad_s: self.bg.into(),
            heading_bias_rad: self.bh,
            heading_deviation_rad: self.dev,
            omega_b_rad_s: self.omega_b.into(),
            manoeuvre: self.manoeuvre,
            p_upper: upper(&self.p),
            block: self.block,
        }
    }

    /// The filter of a checked plain state (`None` if it is not one).
    pub fn from_state(s: &FilterState) -> Option<Self> {
        let p = from_upper(&s.p_upper)?;
        // Kept bit for bit (the snapshot's check bounds the norm to 1e-6).
        let q = Rotation::from_nalgebra(UnitQuaternion::new_unchecked(Rotation::<
            crate::frames::Frd,
            crate::frames::Ned,
        >::quaternion_from_wxyz(
            s.q_nb_wxyz
        )));
        let [lat, lon, h] = s.lat_lon_height;
        let nav = StrapdownState {
            q_nb: q,
            v_ned_m_s: Vector::from_array(s.v_ned_m_s),
            lat_rad: lat,
            lon_rad: lon,
            height_m: h,
        };
        nav.validate().ok()?;
        Some(Self {
            nav,
            ba: s.accel_bias_m_s2.into(),
            bg: s.gyro_bias_rad_s.into(),
            bh: s.heading_bias_rad,
            dev: s.heading_deviation_rad,
            omega_b: s.omega_b_rad_s.into(),
            manoeuvre: s.manoeuvre,
            p,
            block: s.block,
        })
    }
}
