//! The aided INS's `ekf` variant: an error-state (indirect, closed-loop)
//! Kalman filter on the WGS84 strapdown of [`crate::strapdown`].
//!
//! - **Navigation** ([`filter`]): every IMU sample runs
//!   [`crate::strapdown::propagate`] on the bias-corrected sample.
//! - **Error model** ([`model`]): 15 INS error states (attitude, velocity,
//!   position in NED metres, accelerometer and gyro biases; Groves 2013
//!   ch. 14, Farrell 2008 ch. 11), a 16th, the heading source's slowly
//!   varying error (a Gauss-Markov state), and a 17th and 18th, its
//!   one-cycle deviation with the heading (a residual hard iron). The
//!   covariance is propagated
//!   every `covariance_decimation` IMU samples (10: 10 Hz at a 100 Hz IMU)
//!   with the block's mean transition, and before every measurement.
//! - **Aiding** ([`measurements`], [`update`]): DVL body velocity (bottom
//!   lock only; lever arm and misalignment), depth (gauge tared at the
//!   surface, [`crate::ains::tare`]), GPS position (and velocity when the
//!   receiver gives one), `positioning/fix` when `position_aiding`, and
//!   heading: the attitude estimate's yaw while one came within
//!   `aiding_timeout_s`, else the AHRS's magnetic heading plus the site's
//!   declination, at most once per `heading_interval_s`, its σ the
//!   source's and what an accelerometer-levelled heading errs by in a
//!   turn (`heading_manoeuvre_factor`, [`crate::ains::Manoeuvre`]: the
//!   attitude PF's 1° in the survey's turns, against its published 0.14°,
//!   had pulled the yaw and its bias state off for the legs after). Each passes a
//!   normalised-innovation (χ²) gate; rejections are counted per kind
//!   ([`EkfStats`]); after `max_consecutive_rejections` in a row the next
//!   measurement of that kind re-anchors (that part of the state is set to
//!   the measurement, its covariance to the measurement's, its
//!   cross-covariances to zero).
//! - **Initialisation**: nothing is published until a position (GPS or a
//!   fix) and a heading (attitude estimate or AHRS) have come; the first
//!   IMU sample after that starts the filter there, at rest (or at the
//!   GPS velocity), with the attitude estimate's attitude (else the
//!   AHRS's roll, pitch and heading). Without a position
//!   `position_wait_s` after the first IMU sample with a heading (a GPS
//!   that never comes), the position is the site's with σ
//!   `initial_position_std_m` (as `dr` starts), and the first fix that
//!   comes later is an ordinary update. The initial yaw error covariance
//!   holds the heading source's bias and deviation priors, anti-correlated
//!   with those states (the yaw *is* the measured heading then).
//!
//! **Outputs.** One [`Nav`] per IMU sample once initialised, stamped with
//! it: position, velocity, attitude, σ from the covariance,
//! `predicted_drift_m = √(P_NN + P_EE)`, and `aiding_mode` (the kinds used
//! within `aiding_timeout_s`). Without bottom lock the velocity is free
//! inertial and its σ grows with the covariance.
//!
//! **Bad input** ([`EstimatorError`], state kept): a stamp before the last
//! one, an IMU sample the strapdown refuses, a locked DVL speed above
//! `max_speed_m_s`, a depth outside [−10, 11000] m, a GPS fix of quality 0,
//! a latitude beyond ±89° or a negative σ, a fix correlation outside
//! [−1, 1], an AHRS or attitude that is not finite.
//!
//! **Measured** (the simulator's survey, 3837 m submerged, no
//! `positioning/fix`, the calibrated magnetometer, 2026-12-02):
//! - seed 7, heading from the shipped attitude PF: end-of-dive drift N/E/D
//!   0.22/0.29/0.00 m/km, least-squares slope 0.09/−0.47/0.00 m/km,
//!   velocity RMS 0.0060/0.0069/0.0021 m/s, truth inside the 95 % region
//!   100 % of the time (without the manoeuvre term 0.0087/0.0156/0.0022
//!   m/s and 54 % in `nauta bench nav`); from the `mekf`: 0.17/0.22/0.00
//!   m/km, slope 0.14/−0.39/0.00, 0.0060/0.0069/0.0021 m/s, 100 %
//!   (`cargo test --release -p nauta-estimation --test ains_ekf -- --nocapture`);
//! - before the manoeuvre term (commit 614e753), `mekf` heading, seeds
//!   100-109 (not measured again since): drift ≤ 4.8 m/km on every axis and seed (east, the
//!   worst, 0.2-4.8), velocity RMS ≤ 0.010 m/s on 9 of 10 (seed 100: east
//!   0.0103), inside the 95 % region 90.3 % of the submerged time over the
//!   ten (per seed 100 % on eight, 69 % and 34 % on 100 and 103, whose
//!   `mekf` yaw error depends on the course by about ±0.2°);
//!   1.4-1.9 µs per IMU sample in the estimator alone on a shared 2-core
//!   machine, 5200-7000× real time at 100 Hz
//!   (`cargo run --release -p nauta-estimation --example ains_ekf_survey`).
//! - With the AHRS alone (its heading has a 2° Gauss-Markov error in the
//!   simulator) the heading is known to about 2° and seed 7 drifts
//!   7.7 m/km east (test `with_the_ahrs_only_the_yaw_sigma_is_honest`).

mod checks;
pub mod filter;
pub mod measurements;
pub mod model;
mod params;
mod seed;
mod snapshot;
pub mod update;

pub use params::{EkfConfig, EkfParams, EkfParamsError};
pub use snapshot::{
    EkfSnapshot, EkfSnapshotError, EkfStats, FilterState, GateStats, Pending, Stamps,
};

use nalgebra::{Matrix2, SMatrix, UnitQuaternion, Vector3};

use crate::ains::AinsInput;
use crate::ains::dr::Site;
use crate::ains::tare::DepthTare;
use crate::ains::{advisory, aiding};
use crate::attitude::wrap_pi;
use crate::frames::{Frd, Ned, Rotation, Vector};
use crate::readings::{Ahrs, Attitude, Depth, Dvl, Fix, Gps, Imu, Nav};
use crate::role::{Estimator, EstimatorError, Stamped};
use crate::strapdown::StrapdownState;
use filter::{Filter, reset_block};
use measurements::Measurement;
use model::{ATT, BA, BG, BH, Cov, DA, DC, HeadingBias, POS, VEL};
use update::Gated;

/// The aiding kinds, for the gate's counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Dvl,
    Depth,
    Gps,
    GpsVelocity,
    Fix,
    Heading,
}

/// The error-state Kalman filter (module docs).
#[derive(Debug, Clone)]
pub struct Ekf {
    config: EkfConfig,
    declination_rad: f64,
    /// The site's latitude and longitude, rad (the start without a fix).
    site_rad: [f64; 2],
    filter: Option<Filter>,
    pending: Pending,
    stamps: Stamps,
    heading_source: u8,
    tare: DepthTare,
    stats: EkfStats,
    /// After a restore: inputs up to this stamp are skipped.
    skip_until_ns: Option<u64>,
}

fn err(kind: &'static str, detail: impl std::fmt::Display) -> EstimatorError {
    EstimatorError::new(kind, detail)
}

const HEADING_ATTITUDE: u8 = 1;
const HEADING_AHRS: u8 = 2;

impl Ekf {
    /// The estimator of `params` at `site` (the site gives the declination;
    /// the position comes from the first GPS fix or fix); bad parameters or
    /// a site that is not a position are refused.
    pub fn new(params: &EkfParams, site: Site) -> anyhow::Result<Self> {
        let config = params.validate()?;
        anyhow::ensure!(
            site.lat_rad.abs() <= std::f64::consts::FRAC_PI_2 && site.lon_rad.is_finite(),
            "site latitude {} / longitude {} is not a position",
            site.lat_rad,
            site.lon_rad
        );
        anyhow::ensure!(
            site.declination_rad.abs() <= std::f64::consts::PI,
            "site declination {} rad is not in [-π, π]",
            site.declination_rad
        );
        Ok(Self {
            config,
            declination_rad: site.declination_rad,
            site_rad: [site.lat_rad, site.lon_rad],
            filter: None,
            pending: Pending::default(),
            stamps: Stamps::default(),
            heading_source: 0,
            tare: DepthTare::new(config.tare_samples),
            stats: EkfStats::default(),
            skip_until_ns: None,
        })
    }

    /// Counters of the gates, re-anchorings and dropouts.
    pub fn stats(&self) -> EkfStats {
        self.stats
    }

    /// The running filter (`None` before initialisation).
    pub fn filter(&self) -> Option<&Filter> {
        self.filter.as_ref()
    }

    /// The depth gauge's offset in use, m.
    pub fn depth_offset_m(&self) -> f64 {
        self.tare.offset_m()
    }

    fn fresh(&self, last: Option<u64>, t: u64) -> bool {
        last.is_some_and(|l| t.saturating_sub(l) <= self.config.aiding_timeout_ns)
    }

    fn gate_stats(&mut self, k: Kind) -> &mut GateStats {
        let s = &mut self.stats;
        match k {
            Kind::Dvl => &mut s.dvl,
            Kind::Depth => &mut s.depth,
            Kind::Gps => &mut s.gps,
            Kind::GpsVelocity => &mut s.gps_velocity,
            Kind::Fix => &mut s.fix,
            Kind::Heading => &mut s.heading,
        }
    }

    /// Without a position `position_wait_s` after the first IMU sample with
    /// a heading: the site's position, σ `initial_position_std_m`.
    fn site_after_waiting(&mut self, t: u64) {
        if self.pending.position.is_some() || self.pending.attitude.is_none() {
            return;
        }
        let since = *self.stamps.waiting_since.get_or_insert(t);
        if t.saturating_sub(since) >= self.config.position_wait_ns {
            let s = self.config.initial_position_std;
            self.pending.position = Some([self.site_rad[0], self.site_rad[1], s, s, 0.0]);
            tracing::info!(
                waited_s = t.saturating_sub(since) as f64 * 1e-9,
                sigma_m = s,
                "no position came: the ekf aided INS starts at the site"
            );
        }
    }

    /// Initialises at `imu`'s stamp if a position and a heading are in.
    fn try_initialise(&mut self) -> bool {
        let (Some(pos), Some(att)) = (self.pending.position, self.pending.attitude) else {
            return false;
        };
        let c = &self.config;
        let (q, std_att) = if self.pending.from_ahrs {
            (
                crate::attitude::from_euler(att[0], att[1], att[2]),
                [c.initial_tilt_std, c.initial_tilt_std, c.ahrs_heading_std],
            )
        } else {
            (
                UnitQuaternion::new_normalize(Rotation::<Frd, Ned>::quaternion_from_wxyz([
                    att[0], att[1], att[2], att[3],
                ])),
                [
                    att[4].max(c.attitude_heading_std_floor),
                    att[5].max(c.attitude_heading_std_floor),
                    att[6].max(c.attitude_heading_std_floor),
                ],
            )
        };
        let (v, v_std) = match self.pending.velocity {
            Some(v) => ([v[0], v[1], v[2]], v[3]),
            None => ([0.0; 3], c.initial_velocity_std),
        };
        // At the surface (a position fix); the gauge corrects it.
        let depth = 0.0;
        let nav = StrapdownState::at_depth(
            Rotation::from_nalgebra(q),
            Vector::from_array(v),
            pos[0],
            pos[1],
            depth,
        );
        if nav.validate().is_err() {
            return false;
        }
        let mut p = Cov::zeros();
        for i in 0..3 {
            p[(ATT + i, ATT + i)] = std_att[i] * std_att[i];
            p[(VEL + i, VEL + i)] = v_std * v_std;
            p[(BA + i, BA + i)] = c.initial_accel_bias_std * c.initial_accel_bias_std;
            p[(BG + i, BG + i)] = c.initial_gyro_bias_std * c.initial_gyro_bias_std;
        }
        p[(POS, POS)] = pos[2] * pos[2];
        p[(POS + 1, POS + 1)] = pos[3] * pos[3];
        p[(POS, POS + 1)] = pos[4] * pos[2] * pos[3];
        p[(POS + 1, POS)] = p[(POS, POS + 1)];
        p[(POS + 2, POS + 2)] = 1.0;
        let source = if self.pending.from_ahrs {
            HEADING_AHRS
        } else {
            HEADING_ATTITUDE
        };
        // The initial yaw is the measured heading `ψ̃ = ψ + b_ψ + d(ψ) + w`,
        // so its error `δψ = −(b_ψ + d + w)`: its variance holds the source's
        // bias and deviation priors too, anti-correlated with them.
        let (bh, dev) = (self.bh_std(source).powi(2), c.heading_deviation_std.powi(2));
        let (sin, cos) = crate::attitude::to_euler(&q).2.sin_cos();
        p[(BH, BH)] = bh;
        p[(DA, DA)] = dev;
        p[(DC, DC)] = dev;
        p[(ATT + 2, ATT + 2)] += bh + dev;
        for (k, g) in [(BH, 1.0), (DA, sin), (DC, cos)] {
            let v = if k == BH { bh } else { dev };
            p[(ATT + 2, k)] = -g * v;
            p[(k, ATT + 2)] = -g * v;
        }
        self.heading_source = source;
        self.filter = Some(Filter {
            nav,
            ba: Vector3::zeros(),
            bg: Vector3::zeros(),
            bh: 0.0,
            dev: [0.0; 2],
            omega_b: Vector3::zeros(),
            manoeuvre: Default::default(),
            p,
            block: Default::default(),
        });
        true
    }

    /// A measurement through the gate, fed back if used; after
    /// `max_consecutive_rejections` rejections in a row, `reanchor` instead.
    /// True when the measurement was used (or re-anchored).
    fn aid<const M: usize>(
        &mut self,
        kind: Kind,
        m: Option<Measurement<M>>,
        reanchor: impl FnOnce(&mut Filter, &Measurement<M>) -> bool,
    ) -> bool {
        let Some(m) = m else {
            self.stats.singular += 1;
            return false;
        };
        let gate = self.config.gate_chi2[M - 1];
        let max = self.config.max_consecutive_rejections;
        let in_a_row = self.gate_stats(kind).rejected_in_a_row;
        let Some(f) = self.filter.as_mut() else {
            return false;
        };
        if in_a_row >= max && in_a_row > 0 {
            // The gate has refused this kind `max` times in a row: the
            // filter, not the sensor, is taken to be lost.
            let ok = reanchor(f, &m);
            let s = self.gate_stats(kind);
            if ok {
                s.reanchored += 1;
                s.rejected_in_a_row = 0;
            }
            return ok;
        }
        let mut trial = f.p;
        match update::update(&mut trial, &m.nu, &m.h, &m.r, Some(gate)) {
            Gated::Used(dx, _) => {
                let before = f.p;
                f.p = trial;
                if !f.correct(&dx) {
                    f.p = before;
                    self.stats.singular += 1;
                    return false;
                }
                let s = self.gate_stats(kind);
                s.used += 1;
                s.rejected_in_a_row = 0;
                true
            }
            Gated::Rejected(_) => {
                let s = self.gate_stats(kind);
                s.rejected += 1;
                s.rejected_in_a_row += 1;
                false
            }
            Gated::Singular => {
                self.stats.singular += 1;
                false
            }
        }
    }

    fn on_imu(&mut self, m: &Imu, out: &mut Vec<Nav>) -> Result<(), EstimatorError> {
        if self.filter.is_none() {
            // The strapdown's checks, so that bad input is refused alike.
            crate::strapdown::propagate(
                &StrapdownState::at_depth(Rotation::identity(), Vector::zeros(), 0.0, 0.0, 0.0),
                &m.gyro_rad_s,
                &m.accel_m_s2,
                m.interval_s,
            )
            .map_err(|e| err("imu-refused", e))?;
            self.site_after_waiting(m.stamp_ns);
            if !self.try_initialise() {
                return Ok(());
            }
        } else {
            let bh = self.bias_model(self.heading_source);
            let cfg = self.config;
            let Some(f) = self.filter.as_mut() else {
                return Ok(());
            };
            f.on_imu(m, &cfg, bh).map_err(|e| err("imu-refused", e))?;
        }
        self.stats.imu_samples += 1;
        if let Some(f) = &self.filter {
            out.push(self.output(f, m.stamp_ns));
        }
        Ok(())
    }

    /// The heading bias state's model for `source`.
    fn bias_model(&self, source: u8) -> HeadingBias {
        let c = &self.config;
        if source == HEADING_ATTITUDE {
            HeadingBias {
                std_rad: c.attitude_heading_bias_std,
                time_s: c.attitude_heading_bias_time_s,
                deviation_std_rad: c.heading_deviation_std,
            }
        } else {
            HeadingBias {
                std_rad: c.heading_bias_std,
                time_s: c.heading_bias_time_s,
                deviation_std_rad: c.heading_deviation_std,
            }
        }
    }

    fn bh_std(&self, source: u8) -> f64 {
        self.bias_model(source).std_rad
    }

    fn flush(&mut self) {
        let cfg = self.config;
        let bh = self.bias_model(self.heading_source);
        if let Some(f) = self.filter.as_mut() {
            f.flush(&cfg, bh);
        }
    }

    fn on_dvl(&mut self, d: &Dvl, t: u64) {
        if !d.bottom_lock {
            self.stats.dvl_no_lock += 1;
            return;
        }
        let Some(f) = self.filter.as_ref() else {
            return;
        };
        let z = d.velocity_body_m_s.to_nalgebra();
        let m = measurements::dvl(f, &self.config, &z);
        let cfg = self.config;
        self.flush();
        if self.aid(Kind::Dvl, Some(m), |f, m| {
            let v = measurements::dvl_velocity_ned(f, &cfg, &z);
            f.nav.v_ned_m_s = Vector::from_nalgebra(v);
            reset_block(&mut f.p, [VEL, VEL + 1, VEL + 2], &m.r);
            true
        }) {
            self.stamps.dvl = Some(t);
        }
    }

    fn on_depth(&mut self, d: &Depth, t: u64) {
        let v_down = self.filter.as_ref().map_or(0.0, |f| f.nav.v_ned_m_s.z());
        let at_surface = self
            .stamps
            .gps_seen
            .is_some_and(|g| t.saturating_sub(g) <= self.config.surface_window_ns)
            && v_down.abs() <= self.config.tare_max_vertical_speed_m_s;
        if at_surface {
            self.tare.push_surface(d.depth_m);
        } else {
            self.tare.end_session();
        }
        let z = self.tare.depth_m(d.depth_m);
        let Some(f) = self.filter.as_ref() else {
            return;
        };
        let m = measurements::depth(f, &self.config, z);
        self.flush();
        if self.aid(Kind::Depth, Some(m), |f, m| {
            f.nav.height_m = -z;
            reset_block(&mut f.p, [POS + 2], &m.r);
            true
        }) {
            self.stamps.depth = Some(t);
        }
    }

    fn position(&mut self, kind: Kind, lat: f64, lon: f64, r: Matrix2<f64>) -> bool {
        let Some(f) = self.filter.as_ref() else {
            return false;
        };
        let m = measurements::horizontal(f, lat, lon, r);
        self.flush();
        self.aid(kind, Some(m), |f, m| {
            let mut nav = f.nav;
            nav.lat_rad = lat;
            nav.lon_rad = lon;
            if nav.validate().is_err() {
                return false;
            }
            f.nav = nav;
            reset_block(&mut f.p, [POS, POS + 1], &m.r);
            true
        })
    }

    fn on_gps(&mut self, g: &Gps, t: u64) {
        self.stamps.gps_seen = Some(t);
        let s = g.horizontal_std_m.max(self.config.gps_std_floor);
        if self.filter.is_none() {
            self.stamps.gps = Some(t);
            self.pending.position = Some([g.lat_rad, g.lon_rad, s, s, 0.0]);
            self.pending.velocity = g.velocity.map(|(v, s)| [v.x(), v.y(), v.z(), s]);
            return;
        }
        if self.position(
            Kind::Gps,
            g.lat_rad,
            g.lon_rad,
            Matrix2::identity() * (s * s),
        ) {
            self.stamps.gps = Some(t);
        }
        if let Some((v, sv)) = g.velocity {
            let z = v.to_nalgebra();
            let m = self
                .filter
                .as_ref()
                .map(|f| measurements::velocity(f, &z, sv));
            self.aid(Kind::GpsVelocity, m, |f, m| {
                f.nav.v_ned_m_s = Vector::from_nalgebra(z);
                reset_block(&mut f.p, [VEL, VEL + 1, VEL + 2], &m.r);
                true
            });
        }
    }

    fn on_fix(&mut self, x: &Fix, t: u64) {
        // Only a buoy range's fix is news: the positioning's GPS fixes are
        // this filter's own GPS, its silent ones its own velocity.
        if !self.config.position_aiding || x.source != crate::positioning::source::BUOY {
            self.stats.fix_ignored += 1;
            return;
        }
        let c = x.corr_ne * x.std_north_m * x.std_east_m;
        let r = Matrix2::new(
            x.std_north_m * x.std_north_m,
            c,
            c,
            x.std_east_m * x.std_east_m,
        );
        if self.filter.is_none() {
            self.stamps.fix = Some(t);
            self.pending.position =
                Some([x.lat_rad, x.lon_rad, x.std_north_m, x.std_east_m, x.corr_ne]);
            return;
        }
        if self.position(Kind::Fix, x.lat_rad, x.lon_rad, r) {
            self.stamps.fix = Some(t);
        }
    }

    /// A heading `z` (true, rad) of white σ `std` from `source`.
    fn on_heading(&mut self, z: f64, std: f64, source: u8, t: u64) {
        if self.filter.is_none() {
            return;
        }
        if self
            .stamps
            .heading_tried
            .is_some_and(|l| t.saturating_sub(l) < self.config.heading_interval_ns)
            && self.heading_source == source
        {
            return;
        }
        let previous = self.stamps.heading_tried;
        self.stamps.heading_tried = Some(t);
        let bh_var = self.bh_std(source).powi(2);
        let dev_var = self.config.heading_deviation_std.powi(2);
        let source_prior =
            SMatrix::<f64, 3, 3>::from_diagonal(&nalgebra::Vector3::new(bh_var, dev_var, dev_var));
        if self.heading_source != source {
            // Another source, another error: its bias starts afresh.
            if let Some(f) = self.filter.as_mut() {
                f.bh = 0.0;
                f.dev = [0.0; 2];
                reset_block(&mut f.p, [BH, DA, DC], &source_prior);
            }
            self.heading_source = source;
        }
        // The source's white σ and its error in a manoeuvre
        // (`heading_manoeuvre_factor`, [`crate::ains::manoeuvre_var`]), in
        // quadrature.
        let (k, time_s) = (
            self.config.heading_manoeuvre_factor,
            self.config.heading_manoeuvre_time_s,
        );
        let spacing = previous.map(|l| t.saturating_sub(l) as f64 * 1e-9);
        let m = self.filter.as_ref().and_then(|f| {
            let r = std * std
                + crate::ains::manoeuvre_var(k, f.manoeuvre.tilt_sq_rad2, time_s, spacing);
            measurements::heading(f, z, r.sqrt())
        });
        self.flush();
        if self.aid(Kind::Heading, m, |f, m| {
            let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), m.nu[0])
                * f.nav.q_nb.as_nalgebra();
            f.nav.q_nb = Rotation::from_nalgebra(q);
            f.bh = 0.0;
            f.dev = [0.0; 2];
            reset_block(&mut f.p, [ATT + 2], &m.r);
            reset_block(&mut f.p, [BH, DA, DC], &source_prior);
            true
        }) {
            self.stamps.heading = Some(t);
        }
    }

    fn on_attitude(&mut self, a: &Attitude, t: u64) {
        self.stamps.attitude_seen = Some(t);
        let s = a.std_rad.to_array();
        if self.filter.is_none() {
            let q = a.attitude.to_wxyz();
            self.stamps.heading = Some(t);
            self.pending.attitude = Some([q[0], q[1], q[2], q[3], s[0], s[1], s[2]]);
            self.pending.from_ahrs = false;
            return;
        }
        let (_, _, yaw) = a.attitude.euler();
        let std = s[2].max(self.config.attitude_heading_std_floor);
        self.on_heading(yaw, std, HEADING_ATTITUDE, t);
    }

    fn on_ahrs(&mut self, a: &Ahrs, t: u64) {
        let yaw = wrap_pi(a.heading_mag_rad + self.declination_rad);
        if self.fresh(self.stamps.attitude_seen, t) {
            return; // the attitude estimate is the heading source
        }
        if self.filter.is_none() {
            self.stamps.heading = Some(t);
            self.pending.attitude = Some([a.roll_rad, a.pitch_rad, yaw, 0.0, 0.0, 0.0, 0.0]);
            self.pending.from_ahrs = true;
            return;
        }
        self.on_heading(yaw, self.config.ahrs_heading_std, HEADING_AHRS, t);
    }

    /// The solution at `t`.
    fn output(&self, f: &Filter, t: u64) -> Nav {
        let mut mode = 0;
        for (bit, last) in [
            (aiding::DVL, self.stamps.dvl),
            (aiding::GPS, self.stamps.gps),
            (aiding::FIX, self.stamps.fix),
            (aiding::HEADING, self.stamps.heading),
            (aiding::DEPTH, self.stamps.depth),
        ] {
            if self.fresh(last, t) {
                mode |= bit;
            }
        }
        let sd = |i: usize| f.p[(i, i)].max(0.0).sqrt();
        let drift = (f.p[(POS, POS)] + f.p[(POS + 1, POS + 1)]).max(0.0).sqrt();
        Nav {
            stamp_ns: t,
            lat_rad: f.nav.lat_rad,
            lon_rad: f.nav.lon_rad,
            depth_m: f.nav.depth_m(),
            vel_ned_m_s: f.nav.v_ned_m_s,
            attitude: Some(f.nav.q_nb),
            pos_std_ned_m: Vector::new(sd(POS), sd(POS + 1), sd(POS + 2)),
            vel_std_ned_m_s: Vector::new(sd(VEL), sd(VEL + 1), sd(VEL + 2)),
            predicted_drift_m: drift,
            aiding_mode: mode,
            advisory: advisory::surface(drift, self.config.surfacing_threshold),
        }
    }
}

impl Estimator for Ekf {
    type Input = AinsInput;
    type Output = Nav;
    type Snapshot = EkfSnapshot;

    fn on_input(&mut self, input: &AinsInput, out: &mut Vec<Nav>) -> Result<(), EstimatorError> {
        let t = input.stamp_ns();
        if let Some(skip) = self.skip_until_ns {
            if t <= skip {
                return Ok(());
            }
            self.skip_until_ns = None;
        }
        if let Some(last) = self.stamps.last
            && t < last
        {
            return Err(err(
                "stamp-backwards",
                format!("input stamped {t} ns after one stamped {last} ns"),
            ));
        }
        self.validate(input)?;
        match input {
            AinsInput::Imu(m) => self.on_imu(m, out)?,
            AinsInput::Dvl(d) => self.on_dvl(d, t),
            AinsInput::Depth(d) => self.on_depth(d, t),
            AinsInput::Gps(g) => self.on_gps(g, t),
            AinsInput::Fix(x) => self.on_fix(x, t),
            AinsInput::Attitude(a) => self.on_attitude(a, t),
            AinsInput::Ahrs(a) => self.on_ahrs(a, t),
        }
        self.stamps.last = Some(t);
        Ok(())
    }

    fn snapshot(&self) -> Option<EkfSnapshot> {
        self.stamps.last?;
        Some(EkfSnapshot {
            filter: self.filter.as_ref().map(Filter::state),
            pending: self.pending,
            stamps: self.stamps,
            heading_source: self.heading_source,
            tare: self.tare.state(),
            stats: self.stats,
        })
    }

    fn restore(&mut self, s: &EkfSnapshot, stamp_ns: u64) -> Result<(), EstimatorError> {
        let refused = |e: &dyn std::fmt::Display| err("snapshot-refused", e);
        s.check().map_err(|e| refused(&e))?;
        if s.stamps.last.is_some_and(|l| l > stamp_ns) {
            return Err(refused(&format!(
                "snapshot's last input at {:?} ns is after its stamp {stamp_ns} ns",
                s.stamps.last
            )));
        }
        let filter = match &s.filter {
            Some(fs) => {
                Some(Filter::from_state(fs).ok_or_else(|| refused(&"navigation state refused"))?)
            }
            None => None,
        };
        self.filter = filter;
        self.pending = s.pending;
        self.stamps = s.stamps;
        self.heading_source = s.heading_source;
        self.tare.set_state(s.tare);
        self.stats = s.stats;
        self.skip_until_ns = Some(stamp_ns);
        Ok(())
    }
}
