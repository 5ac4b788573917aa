//! The aided INS's `dr` variant: paper 002's dead reckoning (Pirajuba AUV)
//! with its DVL spike filter and its error predictor.
//!
//! - Eq. 1: `v_n = R_b^n(Θ) v_b`, the DVL's body velocity rotated by the
//!   AHRS's attitude, integrated with the trapezoid rule between the
//!   estimator's steps (each AHRS and DVL sample, and each GPS fix):
//!   `p_n += ½ (v_n,k−1 + v_n,k) Δt`. Between DVL samples the body velocity
//!   is held and the attitude follows the AHRS.
//! - The AHRS's heading is magnetic; the true heading is
//!   `ψ = ψ_mag + D`, `D` the site's declination (paper 002 §1.2; east
//!   positive, from the manifest or the WMM).
//! - Eq. 4: latitude and longitude from the north and east of the origin
//!   with the WGS84 radii at `L₀` ([`crate::local::flat`]). Paper 002's
//!   text swaps the radii's names; nauta uses the standard ones (Groves
//!   2013; Farrell 2008): `R_N` the meridian radius, with latitude, `R_E`
//!   the prime-vertical radius, with longitude ([`crate::earth`]). The
//!   origin is the last GPS fix, as in the paper (the start of the
//!   manoeuvre at the surface), so the flat form's error (0.07 m at 1 km,
//!   7 m at 10 km from the origin) restarts at every surfacing.
//! - GPS at the surface resets the horizontal position to the fix (and the
//!   predictor's horizontal error to the fix's σ), if it passes a
//!   normalised-innovation gate against the predicted covariance; after
//!   `gps_gate_max_rejections` gated fixes in a row the next one resets the
//!   position anyway (counted in [`DrStats`]).
//! - Depth from the gauge, its offset tared at the surface
//!   ([`crate::ains::tare`]): a reading is a surface reading when a GPS fix
//!   came within `surface_window_s` and the vertical velocity is below
//!   `tare_max_vertical_speed_m_s`.
//! - Eq. 7, the DVL spike filter ([`spike`]): each DVL sample is compared
//!   with the velocity integrated from the IMU since the last accepted
//!   one; a spike is replaced by that prediction, at most
//!   `spike_max_rejections` times in a row. A sample without bottom lock
//!   is bridged by the same prediction for at most `max_prediction_s`,
//!   then the last body velocity is held.
//! - The error predictor ([`crate::predictor`], paper 002 eqs. 14-17) runs
//!   along the track and gives `predicted_drift_m` and the position and
//!   velocity standard deviations; its `surfacing_advised` flag is
//!   [`DeadReckoning::surfacing_advised`].
//!
//! **Outputs.** One [`Nav`] per AHRS sample (10 Hz in the scenarios: the
//! attitude of eq. 1 is refreshed there), stamped with it; while the AHRS
//! is stale (no sample within `aiding_timeout_s`), one per DVL sample
//! instead, so that the output goes on when the attitude stream stops.
//! IMU, depth, GPS, attitude-estimate and fix inputs never publish: for
//! the shell, `sensor/ahrs` and `sensor/dvl` are the triggering inputs and
//! the others aiding ones. When neither the AHRS nor the DVL has come
//! within `aiding_timeout_s` the position still moves on with the held
//! velocity at every other input (at most once per timeout).
//!
//! **Aiding mode.** `DVL` while a DVL velocity was used as measured within
//! the timeout (a spike replaced by the prediction does not count),
//! `HEADING` while the AHRS is fresh, `DEPTH` while the gauge is, `GPS`
//! while a fix is; the predictor's unaided-velocity error grows whenever
//! the DVL or the AHRS is stale, so the published σ widens.
//!
//! **Bad input** ([`EstimatorError`], state kept): a stamp before the last
//! one, an IMU interval outside (0, 1] s or a specific force above
//! 200 m/s², a DVL velocity above `max_speed_m_s`, a depth outside
//! [−10, 11000] m, a GPS fix of quality 0 or with a latitude beyond ±90° or
//! a negative σ.

mod params;
mod snapshot;
pub mod spike;

pub use params::{DrConfig, DrParams, DrParamsError};
pub use snapshot::{DrSnapshot, DrSnapshotError, DrStats, MAX_PENDING_DVL, NavState};

use crate::ains::AinsInput;
use crate::ains::seed::NavSeed;
use crate::ains::tare::DepthTare;
use crate::ains::{advisory, aiding};
use crate::attitude::wrap_pi;
use crate::earth::normal_gravity;
use crate::frames::{Frd, Rotation, Vector};
use crate::local::flat;
use crate::predictor::{ErrorPredictor, Motion};
use crate::readings::{Ahrs, Depth, Dvl, Gps, Imu, Nav};
use crate::role::{Estimator, EstimatorError, Stamped};
use spike::{Decision, SpikeFilter};

/// Where the vehicle operates: the start position before any GPS fix and
/// the magnetic declination (the manifest's `[site]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Site {
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Magnetic declination `D`, rad, east positive (true = magnetic + D).
    pub declination_rad: f64,
}

/// Paper 002's dead reckoning (module docs).
#[derive(Debug, Clone)]
pub struct DeadReckoning {
    config: DrConfig,
    declination_rad: f64,
    nav: NavState,
    spike: SpikeFilter,
    tare: DepthTare,
    predictor: ErrorPredictor,
    /// After a restore: inputs up to this stamp are skipped.
    skip_until_ns: Option<u64>,
}

fn err(kind: &'static str, detail: impl std::fmt::Display) -> EstimatorError {
    EstimatorError::new(kind, detail)
}

impl DeadReckoning {
    /// The estimator of `params` at `site`; bad parameters or a site that is
    /// not a position are refused.
    pub fn new(params: &DrParams, site: Site) -> anyhow::Result<Self> {
        let config = params.check()?;
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
            nav: NavState::at([site.lat_rad, site.lon_rad]),
            spike: SpikeFilter::new(config.spike),
            tare: DepthTare::new(config.tare_samples),
            predictor: ErrorPredictor::new(config.predictor, config.initial_position_std_m),
            skip_until_ns: None,
        })
    }

    /// Continues from another variant's solution (a swap across variants,
    /// [`crate::ains::seed`]) after its input stamped `stamp_ns`: eq. 1's
    /// origin at the seed's position, its velocity (in the body frame
    /// through its attitude) until the next DVL sample, the predictor's
    /// position variance the seed's, its sensor error states at their
    /// priors (paper 002 eqs. 14-17's δv_b and δΘ, as at the start).
    pub fn start_from(&mut self, seed: &NavSeed, stamp_ns: u64) -> Result<(), EstimatorError> {
        let refused = |what: &str| err("snapshot-refused", what);
        if !seed.is_valid() {
            return Err(refused("the other variant's solution is not one"));
        }
        let euler = match seed.attitude_wxyz {
            Some(q) => Some(
                Rotation::<crate::frames::Frd, crate::frames::Ned>::from_wxyz(q)
                    .map_err(|e| refused(&e.to_string()))?
                    .euler(),
            ),
            None => None,
        };
        let v_body = euler.map_or([0.0; 3], |(r, p, y)| {
            let q = crate::attitude::from_euler(r, p, y);
            let v = q.inverse_transform_vector(&nalgebra::Vector3::from(seed.vel_ned_m_s));
            [v.x, v.y, v.z]
        });
        // The sensors' error states at their priors (a fresh predictor's),
        // the position's variance the seed's.
        let mut cov = ErrorPredictor::new(self.config.predictor, 0.0).covariance();
        for (i, s) in seed.pos_std_ned_m.iter().enumerate() {
            cov[i][i] = s * s;
        }
        let mut predictor = self.predictor.clone();
        predictor
            .set_covariance(&cov)
            .map_err(|e| refused(&e.to_string()))?;
        self.predictor = predictor;
        self.nav = NavState {
            last_stamp_ns: Some(stamp_ns),
            p_ned_m: [0.0, 0.0, seed.depth_m],
            v_body_m_s: v_body,
            v_ned_m_s: seed.vel_ned_m_s,
            euler_rad: euler.map(|(r, p, y)| [r, p, y]),
            ..NavState::at([seed.lat_rad, seed.lon_rad])
        };
        self.tare.set_state(seed.tare);
        self.skip_until_ns = Some(stamp_ns);
        Ok(())
    }

    /// The surfacing advisory (paper 002: "foresee the moment to emerge"):
    /// the predicted horizontal RMS error is above the threshold.
    pub fn surfacing_advised(&self) -> bool {
        self.predictor.surfacing_advised()
    }

    /// Counters of spikes, outages and fixes.
    pub fn stats(&self) -> DrStats {
        self.nav.stats
    }

    /// The error predictor.
    pub fn predictor(&self) -> &ErrorPredictor {
        &self.predictor
    }

    /// The depth gauge's offset in use, m.
    pub fn depth_offset_m(&self) -> f64 {
        self.tare.offset_m()
    }

    fn fresh(&self, last: Option<u64>, t: u64) -> bool {
        last.is_some_and(|l| t.saturating_sub(l) <= self.config.aiding_timeout_ns)
    }

    /// `R_b^n(Θ) v_b` (zero before the first attitude).
    fn v_ned_now(&self) -> [f64; 3] {
        self.nav.euler_rad.map_or([0.0; 3], |e| {
            (Rotation::from_euler(e[0], e[1], e[2])
                * Vector::<Frd>::from_array(self.nav.v_body_m_s))
            .to_array()
        })
    }

    fn motion(&self, t: u64) -> Motion {
        Motion {
            v_b: self.nav.v_body_m_s,
            euler: self.nav.euler_rad.unwrap_or([0.0; 3]),
            aided: self.fresh(self.nav.last_dvl_aid_ns, t) && self.fresh(self.nav.last_ahrs_ns, t),
        }
    }

    /// Eq. 1 from the last step to `t` (trapezoid), and the predictor.
    /// Eq. 1 integrated up to `t`, a delayed DVL sample (`dvl_delay_s`)
    /// taking effect at its time on the way.
    fn step(&mut self, t: u64) {
        while let Some((from, v)) = self.nav.pending_dvl[0].filter(|(from, _)| *from <= t) {
            self.integrate_to(from);
            self.nav.v_body_m_s = v;
            self.nav.pending_dvl.rotate_left(1);
            self.nav.pending_dvl[MAX_PENDING_DVL - 1] = None;
        }
        self.integrate_to(t);
    }

    /// A DVL body velocity in use from `t + dvl_delay_s` on.
    fn use_dvl(&mut self, v: [f64; 3], t: u64) {
        if self.config.dvl_delay_ns == 0 {
            self.nav.v_body_m_s = v;
            return;
        }
        let q = &mut self.nav.pending_dvl;
        if q[MAX_PENDING_DVL - 1].is_some() {
            // Full: the oldest takes effect now.
            if let Some((_, oldest)) = q[0] {
                self.nav.v_body_m_s = oldest;
            }
            q.rotate_left(1);
            q[MAX_PENDING_DVL - 1] = None;
        }
        if let Some(slot) = q.iter_mut().find(|s| s.is_none()) {
            *slot = Some((t.saturating_add(self.config.dvl_delay_ns), v));
        }
    }

    fn integrate_to(&mut self, t: u64) {
        let v_new = self.v_ned_now();
        if let Some(t0) = self.nav.last_step_ns {
            let dt = t.saturating_sub(t0) as f64 * 1e-9;
            for (p, (a, b)) in self
                .nav
                .p_ned_m
                .iter_mut()
                .zip(self.nav.v_ned_m_s.iter().zip(&v_new))
            {
                *p += 0.5 * (a + b) * dt;
            }
            let m = self.motion(t);
            self.predictor.propagate(dt, &m);
        }
        self.nav.v_ned_m_s = v_new;
        self.nav.last_step_ns = Some(t);
    }

    /// A step when the last one is older than the aiding timeout (the
    /// AHRS and the DVL have stopped).
    fn step_if_stale(&mut self, t: u64) {
        if !self.fresh(self.nav.last_step_ns, t) {
            self.step(t);
        }
    }

    fn validate(&self, input: &AinsInput) -> Result<(), EstimatorError> {
        match input {
            AinsInput::Imu(m) => {
                if !(m.interval_s > 0.0 && m.interval_s <= 1.0) {
                    return Err(err(
                        "imu-interval",
                        format!("IMU interval {} s is not in (0, 1]", m.interval_s),
                    ));
                }
                if !(m.accel_m_s2.norm() <= 200.0) {
                    return Err(err(
                        "imu-out-of-range",
                        format!("specific force {} m/s² above 200", m.accel_m_s2.norm()),
                    ));
                }
            }
            AinsInput::Dvl(d) => {
                let speed = d.velocity_body_m_s.norm();
                if d.bottom_lock && !(speed <= self.config.max_speed_m_s) {
                    return Err(err(
                        "dvl-out-of-range",
                        format!(
                            "DVL speed {speed} m/s above max_speed_m_s = {}",
                            self.config.max_speed_m_s
                        ),
                    ));
                }
            }
            AinsInput::Depth(d) => {
                if !(-10.0..=11_000.0).contains(&d.depth_m) {
                    return Err(err(
                        "depth-out-of-range",
                        format!("depth {} m is not in [-10, 11000]", d.depth_m),
                    ));
                }
            }
            AinsInput::Gps(g) => {
                if g.quality == 0 {
                    return Err(err("gps-no-fix", "GPS fix of quality 0 (no fix)"));
                }
                if !(g.lat_rad.abs() <= std::f64::consts::FRAC_PI_2 && g.lon_rad.is_finite()) {
                    return Err(err(
                        "gps-out-of-range",
                        format!("GPS latitude {} rad is not a latitude", g.lat_rad),
                    ));
                }
                if !(g.horizontal_std_m >= 0.0 && g.horizontal_std_m.is_finite()) {
                    return Err(err(
                        "gps-bad-std",
                        format!("GPS horizontal σ {} m", g.horizontal_std_m),
                    ));
                }
            }
            AinsInput::Ahrs(a) => {
                if ![a.roll_rad, a.pitch_rad, a.heading_mag_rad]
                    .iter()
                    .all(|v| v.is_finite())
                    || a.pitch_rad.abs() > std::f64::consts::FRAC_PI_2
                {
                    return Err(err("ahrs-out-of-range", format!("{a:?}")));
                }
            }
            AinsInput::Attitude(_) | AinsInput::Fix(_) => {}
        }
        Ok(())
    }

    fn on_imu(&mut self, m: &Imu) {
        if let Some(e) = self.nav.euler_rad {
            let g = normal_gravity(self.nav.origin_rad[0], -self.nav.p_ned_m[2]);
            self.spike
                .on_imu(m.accel_m_s2.to_array(), m.interval_s, e, g);
        }
    }

    fn on_ahrs(&mut self, a: &Ahrs, t: u64) {
        self.nav.euler_rad = Some([
            a.roll_rad,
            a.pitch_rad,
            wrap_pi(a.heading_mag_rad + self.declination_rad),
        ]);
        self.nav.last_ahrs_ns = Some(t);
    }

    /// Takes a DVL sample; `Err` when the spike filter rejected it (the
    /// state moved on with the IMU-predicted velocity).
    fn on_dvl(&mut self, d: &Dvl, t: u64) -> Result<(), EstimatorError> {
        let v = d.velocity_body_m_s.to_array();
        let euler = self.nav.euler_rad;
        if !d.bottom_lock {
            self.nav.stats.dvl_no_lock += 1;
            if let Some(p) = euler.and_then(|e| self.spike.predicted_body(e)) {
                self.nav.v_body_m_s = p;
            }
            return Ok(());
        }
        let Some(e) = euler else {
            // No attitude to predict with: taken as it is.
            self.spike.forget();
            self.use_dvl(v, t);
            self.nav.last_dvl_aid_ns = Some(t);
            return Ok(());
        };
        match self.spike.on_dvl(v, e) {
            Decision::Accepted => {
                self.use_dvl(v, t);
                self.nav.last_dvl_aid_ns = Some(t);
            }
            Decision::TrustedAgain => {
                self.nav.stats.spikes_trusted_again += 1;
                self.use_dvl(v, t);
                self.nav.last_dvl_aid_ns = Some(t);
            }
            Decision::Rejected(p) => {
                self.nav.stats.spikes_rejected += 1;
                self.nav.v_body_m_s = p;
                return Err(err(
                    "dvl-spike",
                    format!(
                        "DVL velocity {v:?} m/s rejected by the spike filter (eq. 7): the IMU predicts {p:?} m/s"
                    ),
                ));
            }
        }
        Ok(())
    }

    fn on_depth(&mut self, d: &Depth, t: u64) {
        let at_surface = self
            .nav
            .last_gps_ns
            .is_some_and(|g| t.saturating_sub(g) <= self.config.surface_window_ns)
            && self.nav.v_ned_m_s[2].abs() <= self.config.tare_max_vertical_speed_m_s;
        if at_surface {
            self.tare.push_surface(d.depth_m);
        } else {
            self.tare.end_session();
        }
        self.nav.p_ned_m[2] = self.tare.depth_m(d.depth_m);
        self.predictor.reset_down();
        self.nav.last_depth_ns = Some(t);
    }

    /// The fix's normalised innovation `νᵀ (P_h + σ² I)⁻¹ ν`.
    fn gps_innovation(&self, g: &Gps) -> f64 {
        let n = &self.nav;
        let (fn_, fe) = flat::to_local(n.origin_rad[0], n.origin_rad[1], g.lat_rad, g.lon_rad);
        let (vn, ve) = (fn_ - n.p_ned_m[0], fe - n.p_ned_m[1]);
        let p = self.predictor.horizontal_covariance();
        let r = g.horizontal_std_m * g.horizontal_std_m;
        let (a, b, d) = (p[0][0] + r, p[0][1], p[1][1] + r);
        let det = a * d - b * b;
        if !(det > 0.0) {
            return 0.0;
        }
        (d * vn * vn - 2.0 * b * vn * ve + a * ve * ve) / det
    }

    /// Takes a fix; `Err` when the gate refused it.
    fn on_gps(&mut self, g: &Gps, t: u64) -> Result<(), EstimatorError> {
        let gate = self.config.gps_gate_chi2;
        let innovation = self.gps_innovation(g);
        if gate > 0.0 && innovation > gate {
            let s = &mut self.nav.stats;
            if s.gps_gated_in_a_row < self.config.gps_gate_max_rejections {
                s.gps_gated += 1;
                s.gps_gated_in_a_row += 1;
                return Err(err(
                    "gps-gated",
                    format!(
                        "GPS fix refused by the gate: normalised innovation {innovation:.1} above {gate} ({} in a row; the next {} re-anchor)",
                        s.gps_gated_in_a_row, self.config.gps_gate_max_rejections
                    ),
                ));
            }
            s.gps_reanchored += 1;
        }
        self.nav.stats.gps_gated_in_a_row = 0;
        self.nav.origin_rad = [g.lat_rad, g.lon_rad];
        self.nav.p_ned_m[0] = 0.0;
        self.nav.p_ned_m[1] = 0.0;
        self.predictor.reset_horizontal(g.horizontal_std_m);
        self.nav.last_gps_ns = Some(t);
        self.nav.stats.gps_fixes += 1;
        Ok(())
    }

    /// The solution at `t` (after the step to `t`).
    fn output(&self, t: u64) -> Nav {
        let n = &self.nav;
        let (lat, lon) =
            flat::to_geodetic(n.origin_rad[0], n.origin_rad[1], n.p_ned_m[0], n.p_ned_m[1]);
        let mut mode = 0;
        for (bit, last) in [
            (aiding::DVL, n.last_dvl_aid_ns),
            (aiding::HEADING, n.last_ahrs_ns),
            (aiding::DEPTH, n.last_depth_ns),
            (aiding::GPS, n.last_gps_ns),
        ] {
            if self.fresh(last, t) {
                mode |= bit;
            }
        }
        let m = self.motion(t);
        Nav {
            stamp_ns: t,
            lat_rad: lat,
            lon_rad: wrap_pi(lon),
            depth_m: n.p_ned_m[2],
            vel_ned_m_s: Vector::from_array(n.v_ned_m_s),
            attitude: n.euler_rad.map(|e| Rotation::from_euler(e[0], e[1], e[2])),
            pos_std_ned_m: Vector::from_array(self.predictor.position_std_m()),
            vel_std_ned_m_s: Vector::from_array(self.predictor.velocity_std_m_s(&m)),
            predicted_drift_m: self.predictor.horizontal_rms_m(),
            aiding_mode: mode,
            advisory: if self.predictor.surfacing_advised() {
                advisory::SURFACE
            } else {
                0
            },
        }
    }
}

impl Estimator for DeadReckoning {
    type Input = AinsInput;
    type Output = Nav;
    type Snapshot = DrSnapshot;

    fn on_input(&mut self, input: &AinsInput, out: &mut Vec<Nav>) -> Result<(), EstimatorError> {
        let t = input.stamp_ns();
        if let Some(skip) = self.skip_until_ns {
            if t <= skip {
                return Ok(());
            }
            self.skip_until_ns = None;
        }
        if let Some(last) = self.nav.last_stamp_ns
            && t < last
        {
            return Err(err(
                "stamp-backwards",
                format!("input stamped {t} ns after one stamped {last} ns"),
            ));
        }
        self.validate(input)?;
        self.nav.last_stamp_ns = Some(t);
        match input {
            AinsInput::Imu(m) => {
                self.on_imu(m);
                self.step_if_stale(t);
            }
            AinsInput::Ahrs(a) => {
                self.on_ahrs(a, t);
                self.step(t);
                out.push(self.output(t));
            }
            AinsInput::Dvl(d) => {
                // Up to this sample on the velocity held since the last one
                // (a zero-order hold: a 1 Hz DVL's new velocity applied to
                // the second before it made A-KIT's errors 0.87 % instead of
                // 0.56 % on trajectory 1), then the new velocity.
                self.step(t);
                let taken = self.on_dvl(d, t);
                // Between AHRS samples (a stale or stopped AHRS), once there
                // was one: before any attitude there is nothing to dead-reckon
                // with, and the AHRS of this same instant publishes next.
                if self.nav.euler_rad.is_some() && !self.fresh(self.nav.last_ahrs_ns, t) {
                    out.push(self.output(t));
                }
                // A spike is refused and counted (the shell's health); the
                // solution of this instant is published all the same.
                taken?;
            }
            AinsInput::Depth(d) => {
                self.step_if_stale(t);
                self.on_depth(d, t);
            }
            AinsInput::Gps(g) => {
                self.step(t);
                self.on_gps(g, t)?;
            }
            AinsInput::Attitude(_) | AinsInput::Fix(_) => self.step_if_stale(t),
        }
        Ok(())
    }

    fn snapshot(&self) -> Option<DrSnapshot> {
        self.nav.last_stamp_ns?;
        Some(DrSnapshot {
            nav: self.nav,
            spike: self.spike.state(),
            tare: self.tare.state(),
            covariance: self.predictor.covariance(),
        })
    }

    fn restore(&mut self, s: &DrSnapshot, stamp_ns: u64) -> Result<(), EstimatorError> {
        let refused = |e: &dyn std::fmt::Display| err("snapshot-refused", e);
        s.check().map_err(|e| refused(&e))?;
        if s.nav.last_stamp_ns.is_some_and(|l| l > stamp_ns) {
            return Err(refused(&format!(
                "snapshot's last input at {:?} ns is after its stamp {stamp_ns} ns",
                s.nav.last_stamp_ns
            )));
        }
        let mut predictor = self.predictor.clone();
        predictor
            .set_covariance(&s.covariance)
            .map_err(|e| refused(&e))?;
        self.predictor = predictor;
        self.nav = s.nav;
        self.spike.set_state(s.spike);
        self.tare.set_state(s.tare);
        self.skip_until_ns = Some(stamp_ns);
        Ok(())
    }
}
