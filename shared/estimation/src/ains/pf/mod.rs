//! The aided INS's `pf` variant: paper 000 §III-A's velocity and position
//! particle filters on top of the strapdown mechanisation of §II-A.
//!
//! The extracted text of eqs. 11-27 is partly garbled; what follows is
//! derived from the prose around them and the standard particle filter the
//! paper describes in §II-B (eqs. 6-12).
//!
//! **Velocity filter** (eqs. 13-14, 17-19, 22-23). `N_v` particles of NED
//! velocity `v_j = [v_N, v_E, v_D]`, each component with its own weight.
//! Prediction at every IMU sample: the specific force resolved in NED with
//! the attitude (eq. 17, `a^n = C_b^n a^b`), minus Coriolis and plus gravity
//! (eq. 18), integrated over the sample (eq. 19). The increment is the
//! strapdown's ([`crate::strapdown::propagate`], mid-interval attitude,
//! WGS84 gravity, Coriolis and transport rate) computed once from the
//! filter's mean (the Coriolis term's dependence on each particle's own
//! velocity, ~1e-4 of its deviation per second, is left out), and added to
//! every particle with a velocity random walk `σ_v √Δt z` (the process noise
//! the paper does not write; without it the cloud would never spread).
//! Each velocity particle also carries an acceleration error `a_j` of its
//! own, added to the increment (`v_j += Δv + a_j Δt + σ_v √Δt z`), a
//! first-order Gauss–Markov process (σ `accel_bias_std_m_s2`, correlation
//! time `accel_bias_time_s`; our addition, as the position filter's drift
//! below): the accelerometer's bias in NED, which the paper's filter has no
//! state for. Resampled with its particle, it is estimated by the DVL's
//! weights; without it a turn-on bias of a few hundredths of a m/s² held
//! the velocity 0.015 m/s off the DVL between samples (the survey's down
//! velocity RMS, seed 7, fell from 0.0155 to 0.0062 m/s with it).
//! Update: eq. 22's innovation `δv = z − v_j` and eq. 23's Gaussian
//! likelihood per component, from the DVL's body velocity rotated to NED
//! (`C_b^n ṽ_b`, while it has bottom lock) or the GPS's velocity at the
//! surface (`readings::Gps::velocity`, when the receiver gives one).
//!
//! **Position filter** (eqs. 15-16, 20-21, 24-25, 27). `N_p` particles of
//! north and east of an origin (the first fix) and depth, m; eq. 20's
//! `L̇ = v_N / (R₀ + h)`, `λ̇ = v_E sec L / (R₀ + h)` is here its local form
//! `ṅ = v_N`, `ė = v_E`, `ḋ = v_D` with the velocity filter's estimate
//! (eq. 26; trapezoid over the sample), and latitude and longitude come
//! from north and east through the WGS84 radii at the origin
//! ([`crate::local::flat`]: 0.07 m off at 1 km from the origin, 7 m at
//! 10 km). Each particle also carries a velocity error `b_j` of its own, a
//! first-order Gauss–Markov process (σ `drift_speed_std_m_s`, correlation
//! time `drift_time_s`; our addition): the velocity estimate's errors that
//! matter for position (DVL scale factor, heading) are slow, so the
//! position cloud spreads in proportion to the distance as the true error
//! does, not with its square root, and the published σ stays honest.
//! Update (eqs. 24-25): GPS position at the surface, `positioning/fix`
//! when `position_aiding` is set (north and east separately: the
//! components are separate filters, so the fix's correlation is not used),
//! and the depth gauge, tared at the surface ([`crate::ains::tare`]).
//!
//! **Resampling** (eq. 11), per component: when the effective particle
//! number falls below `resample_threshold · N`, selection with replacement
//! and a shrinkage kernel (`resampling.rs`). **Estimate**: weighted means
//! (eqs. 26-27); the published σ are the weighted standard deviations, and
//! `predicted_drift_m` the horizontal RMS `√(s²_N + s²_E)` of the position
//! particles.
//!
//! **Gate** (`gate.rs`): every measurement passes a normalised-innovation
//! gate against the particles' spread; after `gate_max_rejections` gated
//! ones in a row the next one re-anchors its filter around itself
//! (counted in [`AinsPfStats`]).
//!
//! **Attitude** ([`attitude`]; our addition: the paper uses its attitude
//! PF's estimate as it comes): the attitude of eqs. 17-19 and of the DVL's
//! rotation is carried by the gyro, less a gyro bias estimated with it,
//! and corrected towards the attitude input (`attitude/estimate`, the
//! attitude PF's estimate, paper 000 §III-B) at most once a second by a
//! six-state Kalman filter of the carried attitude's error and the bias.
//! The input is weighed by its published σ and by what an
//! accelerometer-levelled attitude errs by in a manoeuvre (the turn's
//! centripetal acceleration read as tilt), which its published σ does not
//! say: taken as it came, the attitude PF's 1° errors in the survey's
//! turns were 0.08 m/s of velocity error there (seed 7). While the input
//! is stale (`aiding_timeout_s`) the AHRS with the site's declination
//! added sets the attitude. Without bottom lock or
//! during a DVL dropout the velocity comes from the IMU alone: the `DVL`
//! bit of `aiding_mode` drops after the timeout and the velocity particles
//! spread with their random walk, so the published σ grow.
//!
//! **Initialisation**: nothing is published until an attitude and a first
//! position (a GPS fix, or a `positioning/fix` with `position_aiding`) have
//! come; the clouds are drawn then, position around the fix, depth around
//! the gauge's last tared reading, velocity around the last DVL velocity
//! (or zero). Without a position `position_wait_s` after the first IMU
//! sample with an attitude (a GPS that never comes, a launch submerged),
//! the position cloud is drawn around the site with σ
//! `initial_position_std_m` (as `dr` starts), the `GPS` bit clear; the
//! first position then redraws the horizontal cloud around itself.
//! **Outputs**: one [`Nav`] per IMU sample from then on, stamped with it.
//!
//! **Measured** (survey scenario, 43 minutes, one 3.8 km dive, GPS only at
//! the surface, no position aiding, seed 7, the attitude input from paper
//! 000's attitude PF run in-process, magnetometer without hard and soft
//! iron; `cargo test --release -p nauta-estimation --test ains_pf survey --
//! --nocapture`, 2026-12-02): drift while submerged 0.35 / 0.64 / 0.00 m/km
//! N/E/D (final error over distance; least-squares slopes 0.00 / 0.76 /
//! 0.00 m/km; paper 000's DVL-aided INS: 23.8 / 29 / 32.8 m/km), velocity
//! RMS 0.0074 / 0.0074 / 0.0067 m/s (paper: 0.014 / 0.016 / 0.016; 0.022 /
//! 0.020 / 0.007 with the attitude input used as it came, before the
//! carried attitude), truth inside the published 95 % horizontal region
//! 99.9 % of the time (the target's 90-98 %: one dive's error, mostly
//! inside or mostly outside), about 4-7 µs per IMU sample with 128
//! particles per filter on a shared, loaded two-core machine. With the
//! attitude role's `mekf` as the input: 0.24 / 0.76 / 0.00 m/km, 0.0070 /
//! 0.0074 / 0.0070 m/s, 100 %.
//!
//! **Bad input** ([`EstimatorError`], state kept): a stamp before the last
//! one, an IMU sample the strapdown refuses (interval outside (0, 1] s,
//! non-finite, out of range) or with a specific force above 200 m/s², a
//! DVL velocity above `max_speed_m_s`, a depth outside [−10, 11000] m, a
//! GPS fix of quality 0, a latitude beyond ±90°, a negative or non-finite σ.

mod attitude;
mod check;
mod cloud;
mod gate;
mod noise;
mod params;
mod resampling;
mod seed;
mod snapshot;

pub use attitude::AttitudeTrack;
pub use cloud::Moments;
pub use params::{AinsPfConfig, AinsPfParams, AinsPfParamsError, MAX_PARTICLES};
pub use snapshot::{AinsPfSnapshot, AinsPfSnapshotError, AinsPfStats, ComponentMoments, GateStats};

use crate::ains::AinsInput;
use crate::ains::dr::Site;
use crate::ains::tare::DepthTare;
use crate::ains::{advisory, aiding};
use crate::attitude::wrap_pi;
use crate::frames::{Frd, Ned, Rotation, Vector};
use crate::local::flat;
use crate::readings::{Ahrs, Attitude, Depth, Dvl, Fix, Gps, Imu, Nav};
use crate::role::{Estimator, EstimatorError, Stamped};
use crate::strapdown::{StrapdownState, propagate};
use check::check_input;
use cloud::Component;
use gate::{Decision, decide, normalised_innovation};
use noise::Noise;
use resampling::Scratch;

fn err(kind: &'static str, detail: impl std::fmt::Display) -> EstimatorError {
    EstimatorError::new(kind, detail)
}

const ZERO: Moments = Moments {
    mean: 0.0,
    var: 0.0,
};

/// Indices into the stamps of the last used aiding.
const ATT: usize = 0;
const DVL: usize = 1;
const GPS: usize = 2;
const FIX: usize = 3;
const DEPTH: usize = 4;

/// One filter of three components (velocity or position).
#[derive(Debug, Clone, PartialEq)]
struct Filter {
    c: [Component; 3],
    hat: [Moments; 3],
    scratch: Scratch,
}

impl Filter {
    fn new(n: usize, with_b: bool) -> Self {
        Self {
            c: std::array::from_fn(|_| Component::new(n, with_b)),
            hat: [ZERO; 3],
            scratch: Scratch::new(n),
        }
    }

    fn refresh(&mut self) {
        for (h, c) in self.hat.iter_mut().zip(&self.c) {
            *h = c.moments();
        }
    }

    fn var(&self) -> [f64; 3] {
        self.hat.map(|m| m.var)
    }

    fn mean(&self) -> [f64; 3] {
        self.hat.map(|m| m.mean)
    }
}

/// Paper 000 §III-A's particle-filter aided INS (module docs).
#[derive(Debug, Clone)]
pub struct ParticleAins {
    config: AinsPfConfig,
    declination_rad: f64,
    /// The site's latitude and longitude, rad (the start without a fix).
    site_rad: [f64; 2],
    /// Origin of the local north/east; `Some` once initialised.
    origin_rad: Option<[f64; 2]>,
    /// The filters started at the site, no position has come yet.
    position_from_site: bool,
    /// First IMU sample with an attitude while no position has come, ns.
    waiting_since_ns: Option<u64>,
    vel: Filter,
    pos: Filter,
    noise: Noise,
    /// The attitude in use: carried by the gyro, corrected towards the
    /// attitude input ([`attitude`]).
    attitude: Option<Rotation<Frd, Ned>>,
    attitude_from_estimate: bool,
    track: AttitudeTrack,
    /// Stamps of the last attitude, DVL aiding, GPS, fix and depth used.
    last_ns: [Option<u64>; 5],
    last_stamp_ns: Option<u64>,
    /// Last GPS fix received (for the tare's surface window).
    last_gps_seen_ns: Option<u64>,
    /// Last DVL velocity in NED, for the initialisation.
    last_dvl_ned: Option<(u64, [f64; 3])>,
    /// Last tared depth, for the initialisation.
    last_depth_m: Option<f64>,
    tare: DepthTare,
    stats: AinsPfStats,
    skip_until_ns: Option<u64>,
}

impl ParticleAins {
    /// The estimator of `params` at `site` (the site's declination corrects
    /// the AHRS's magnetic heading); bad parameters or a site that is not a
    /// position are refused.
    pub fn new(params: &AinsPfParams, site: Site) -> anyhow::Result<Self> {
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
            origin_rad: None,
            position_from_site: false,
            waiting_since_ns: None,
            vel: Filter::new(config.n_v, true),
            pos: Filter::new(config.n_p, true),
            noise: Noise::new(config.seed),
            attitude: None,
            attitude_from_estimate: false,
            track: AttitudeTrack::default(),
            last_ns: [None; 5],
            last_stamp_ns: None,
            last_gps_seen_ns: None,
            last_dvl_ned: None,
            last_depth_m: None,
            tare: DepthTare::new(config.tare_samples),
            stats: AinsPfStats::default(),
            skip_until_ns: None,
        })
    }

    /// Counters of the aiding, gates and resamplings.
    pub fn stats(&self) -> AinsPfStats {
        self.stats
    }

    /// The depth gauge's offset in use, m.
    pub fn depth_offset_m(&self) -> f64 {
        self.tare.offset_m()
    }

    /// True once the filters are running (outputs are published).
    pub fn is_initialised(&self) -> bool {
        self.origin_rad.is_some()
    }

    fn fresh(&self, last: Option<u64>, t: u64) -> bool {
        last.is_some_and(|l| t.saturating_sub(l) <= self.config.aiding_timeout_ns)
    }

    /// Eqs. 17-21 for one IMU sample, then the output.
    fn on_imu(&mut self, m: &Imu, t: u64, out: &mut Vec<Nav>) -> Result<(), EstimatorError> {
        if self.origin_rad.is_none() && self.attitude.is_some() {
            self.start_at_site_after_waiting(t);
        }
        let (Some(origin), Some(q)) = (self.origin_rad, self.attitude) else {
            return Ok(());
        };
        let dt = m.interval_s;
        let v0 = self.vel.mean();
        let p0 = self.pos.mean();
        let (lat, lon) = flat::to_geodetic(origin[0], origin[1], p0[0], p0[1]);
        let state = StrapdownState::at_depth(q, Vector::from_array(v0), lat, wrap_pi(lon), p0[2]);
        // Eqs. 17-19 on the mean (module docs), the attitude carried by the
        // gyro less the attitude input's gyro bias ([`attitude`]).
        let w = Vector::from_nalgebra(
            m.gyro_rad_s.to_nalgebra() - self.track.gyro_bias().to_nalgebra(),
        );
        let prop = propagate(&state, &w, &m.accel_m_s2, dt).map_err(|e| err("imu-refused", e))?;
        let v1 = prop.state.v_ned_m_s.to_array();
        let c = self.config;
        self.attitude = Some(prop.state.q_nb);
        let g = crate::earth::normal_gravity(lat, -p0[2]);
        self.track.predict(&c, &prop.state.q_nb, &w, v1, g, dt);
        let sv = c.q_v * dt.sqrt();
        let phi_a = (-dt / c.accel_bias_time_s).exp();
        let drive_a = c.accel_bias_std * (1.0 - phi_a * phi_a).sqrt();
        for i in 0..3 {
            self.vel.c[i].shift_with_bias(
                v1[i] - v0[i],
                dt,
                sv,
                phi_a,
                drive_a,
                &mut self.noise,
                &mut self.vel.scratch.z,
            );
        }
        self.vel.refresh();
        // Eqs. 20-21 with the velocity filter's estimate (trapezoid).
        let v1 = self.vel.mean();
        let sp = c.q_p * dt.sqrt();
        let phi = (-dt / c.drift_time_s).exp();
        let drive = c.drift_std * (1.0 - phi * phi).sqrt();
        for i in 0..3 {
            let delta = 0.5 * (v0[i] + v1[i]) * dt;
            self.pos.c[i].shift_with_bias(
                delta,
                dt,
                sp,
                phi,
                drive,
                &mut self.noise,
                &mut self.pos.scratch.z,
            );
        }
        self.pos.refresh();
        out.push(self.output(t, origin));
        Ok(())
    }

    fn on_attitude(&mut self, q: Rotation<Frd, Ned>, from_estimate: bool, t: u64) {
        self.attitude = Some(q);
        self.attitude_from_estimate = from_estimate;
        self.last_ns[ATT] = Some(t);
    }

    /// The attitude input ([`attitude`]): the carried attitude corrected
    /// towards it (at most once per `attitude_interval_s`, through the
    /// gate), or set to it before the filters run, after the AHRS, or when
    /// the gate re-anchors.
    fn on_estimate(&mut self, a: &Attitude, t: u64) {
        let c = self.config;
        let r = self.track.input_var(&c, a.std_rad.to_array(), t);
        let anchor = |me: &mut Self| {
            me.track.anchor(
                r,
                a.gyro_bias_rad_s.to_array(),
                c.attitude_initial_bias_std,
                t,
            );
            me.on_attitude(a.attitude, true, t);
        };
        let carried = match self.attitude {
            Some(q) if self.origin_rad.is_some() && self.attitude_from_estimate => q,
            _ => return anchor(self),
        };
        if self
            .track
            .last_update_ns
            .is_some_and(|l| t.saturating_sub(l) < c.attitude_interval_ns)
        {
            self.last_ns[ATT] = Some(t);
            return;
        }
        let nu = AttitudeTrack::innovation(&carried, &a.attitude);
        let s = self.track.innovation_var(&c, r);
        let d2 = normalised_innovation(&nu, &s, &[0.0; 3]);
        match decide(
            &mut self.stats.attitude,
            d2,
            c.attitude_gate,
            c.gate_max_rejections,
        ) {
            Decision::Gated => {}
            Decision::Use => match self.track.correct(&c, &carried, nu, r, t) {
                Some(q) => self.on_attitude(q, true, t),
                None => anchor(self),
            },
            Decision::Reanchor => anchor(self),
        }
    }

    fn on_ahrs(&mut self, a: &Ahrs, t: u64) {
        // The attitude input is preferred while it is fresh.
        if self.attitude_from_estimate && self.fresh(self.last_ns[ATT], t) {
            return;
        }
        let yaw = wrap_pi(a.heading_mag_rad + self.declination_rad);
        self.on_attitude(Rotation::from_euler(a.roll_rad, a.pitch_rad, yaw), false, t);
    }

    /// Eqs. 22-23 with a velocity measurement `z` (NED) of σ `sigma`.
    fn velocity_update(&mut self, z: [f64; 3], sigma: f64, gps: bool) -> bool {
        let c = self.config;
        let var = self.vel.var();
        let mean = self.vel.mean();
        let nu = [z[0] - mean[0], z[1] - mean[1], z[2] - mean[2]];
        let d2 = normalised_innovation(&nu, &var, &[sigma * sigma; 3]);
        let stats = if gps {
            &mut self.stats.gps_velocity
        } else {
            &mut self.stats.dvl
        };
        let decision = decide(stats, d2, c.velocity_gate, c.gate_max_rejections);
        let used = self.apply(true, &[0, 1, 2], &z, &[sigma; 3], decision);
        if used {
            self.vel.refresh();
        }
        used
    }

    /// Eqs. 24-25 on the position components `axes` (0 N, 1 E, 2 D).
    fn position_update(&mut self, axes: &[usize], z: &[f64], sigma: &[f64], kind: usize) -> bool {
        let c = self.config;
        let (var, mean) = (self.pos.var(), self.pos.mean());
        // On the stack: at most three axes (no allocation per sample).
        let n = axes.len().min(3);
        let (mut nu, mut pv, mut mv) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        for k in 0..n {
            nu[k] = z[k] - mean[axes[k]];
            pv[k] = var[axes[k]];
            mv[k] = sigma[k] * sigma[k];
        }
        let d2 = normalised_innovation(&nu[..n], &pv[..n], &mv[..n]);
        let (stats, limit) = match kind {
            GPS => (&mut self.stats.gps, c.position_gate),
            FIX => (&mut self.stats.fix, c.position_gate),
            _ => (&mut self.stats.depth, c.depth_gate),
        };
        let decision = match decide(stats, d2, limit, c.gate_max_rejections) {
            Decision::Use if kind == FIX && c.fix_reset => Decision::Reanchor,
            d => d,
        };
        let used = self.apply(false, axes, z, sigma, decision);
        if used {
            self.pos.refresh();
        }
        used
    }

    /// Applies a gate's decision to the components `axes` of the velocity
    /// (`velocity`) or position filter; true if the measurement was used.
    fn apply(
        &mut self,
        velocity: bool,
        axes: &[usize],
        z: &[f64],
        sigma: &[f64],
        decision: Decision,
    ) -> bool {
        let c = self.config;
        let (f, resamples) = if velocity {
            (&mut self.vel, &mut self.stats.velocity_resamples)
        } else {
            (&mut self.pos, &mut self.stats.position_resamples)
        };
        match decision {
            Decision::Gated => false,
            Decision::Use => {
                for ((&i, &z), &s) in axes.iter().zip(z).zip(sigma) {
                    let comp = &mut f.c[i];
                    match comp.narrow_update(z, s, &mut self.noise, &mut f.scratch) {
                        Ok(true) => {
                            *resamples += 1;
                            continue;
                        }
                        Ok(false) => {}
                        Err(_) => {
                            let b = comp.b_moments();
                            comp.spread(z, s, b, &mut self.noise);
                            continue;
                        }
                    }
                    if comp.weigh(z, s, &mut f.scratch.z).is_err() {
                        // No particle left near it (the gate's limit was
                        // far beyond the cloud): re-anchored on it.
                        let b = comp.b_moments();
                        comp.spread(z, s, b, &mut self.noise);
                        continue;
                    }
                    if comp.maybe_resample(
                        c.resample_threshold,
                        c.kernel_width,
                        &mut self.noise,
                        &mut f.scratch,
                    ) {
                        *resamples += 1;
                    }
                }
                true
            }
            Decision::Reanchor => {
                for ((&i, &z), &s) in axes.iter().zip(z).zip(sigma) {
                    let comp = &mut f.c[i];
                    let b = comp.b_moments();
                    comp.spread(z, s, b, &mut self.noise);
                }
                true
            }
        }
    }

    fn on_dvl(&mut self, d: &Dvl, t: u64) {
        if !d.bottom_lock {
            self.stats.dvl_no_lock += 1;
            return;
        }
        let Some(q) = self.attitude else { return };
        let z = (q * d.velocity_body_m_s).to_array();
        self.last_dvl_ned = Some((t, z));
        if self.origin_rad.is_none() {
            return;
        }
        if self.velocity_update(z, self.config.dvl_std, false) {
            self.last_ns[DVL] = Some(t);
        }
    }

    fn on_depth(&mut self, d: &Depth, t: u64) {
        let at_surface = self
            .last_gps_seen_ns
            .is_some_and(|g| t.saturating_sub(g) <= self.config.surface_window_ns)
            && self.vel.hat[2].mean.abs() <= self.config.tare_max_vz;
        if at_surface {
            self.tare.push_surface(d.depth_m);
        } else {
            self.tare.end_session();
        }
        let z = self.tare.depth_m(d.depth_m);
        self.last_depth_m = Some(z);
        if self.origin_rad.is_some()
            && self.position_update(&[2], &[z], &[self.config.depth_std], DEPTH)
        {
            self.last_ns[DEPTH] = Some(t);
        }
    }

    /// Draws both clouds (module docs) at a first fix `(lat, lon)` of σ
    /// `sigma` (north, east).
    fn initialise(&mut self, lat: f64, lon: f64, sigma: [f64; 2], t: u64) {
        let c = self.config;
        let v0 = self
            .last_dvl_ned
            .filter(|(s, _)| t.saturating_sub(*s) <= c.aiding_timeout_ns)
            .map_or([0.0; 3], |(_, v)| v);
        let bias = Moments {
            mean: 0.0,
            var: c.accel_bias_std * c.accel_bias_std,
        };
        for (comp, v) in self.vel.c.iter_mut().zip(v0) {
            comp.spread(v, c.initial_velocity_std, bias, &mut self.noise);
        }
        let drift = Moments {
            mean: 0.0,
            var: c.drift_std * c.drift_std,
        };
        let depth = self.last_depth_m.unwrap_or(0.0);
        for (i, (m, s)) in [
            (0.0, sigma[0]),
            (0.0, sigma[1]),
            (depth, c.initial_depth_std),
        ]
        .into_iter()
        .enumerate()
        {
            self.pos.c[i].spread(m, s, drift, &mut self.noise);
        }
        self.vel.refresh();
        self.pos.refresh();
        self.origin_rad = Some([lat, lon]);
        tracing::debug!(lat_rad = lat, lon_rad = lon, "pf aided INS initialised");
    }

    /// A horizontal fix: initialises, or eqs. 24-25 on north and east.
    fn on_position(&mut self, lat: f64, lon: f64, sigma: [f64; 2], kind: usize, t: u64) {
        let sigma = sigma.map(|s| s.max(self.config.min_position_std));
        let Some(origin) = self.origin_rad else {
            if self.attitude.is_some() {
                self.initialise(lat, lon, sigma, t);
                self.last_ns[kind] = Some(t);
            }
            return;
        };
        if self.position_from_site {
            self.redraw_horizontal(lat, lon, sigma);
            self.last_ns[kind] = Some(t);
            return;
        }
        let (n, e) = flat::to_local(origin[0], origin[1], lat, lon);
        if self.position_update(&[0, 1], &[n, e], &sigma, kind) {
            self.last_ns[kind] = Some(t);
        }
    }

    fn on_gps(&mut self, g: &Gps, t: u64) {
        self.last_gps_seen_ns = Some(t);
        self.on_position(g.lat_rad, g.lon_rad, [g.horizontal_std_m; 2], GPS, t);
        if let (Some((v, s)), true) = (g.velocity, self.origin_rad.is_some()) {
            self.velocity_update(v.to_array(), s.max(1e-3), true);
        }
    }

    fn on_fix(&mut self, f: &Fix, t: u64) {
        // Only a buoy range's fix is news: the positioning's GPS fixes are
        // this filter's own GPS, its silent ones its own velocity.
        if self.config.position_aiding && f.source == crate::positioning::source::BUOY {
            self.on_position(f.lat_rad, f.lon_rad, [f.std_north_m, f.std_east_m], FIX, t);
        }
    }

    fn output(&self, t: u64, origin: [f64; 2]) -> Nav {
        let p = self.pos.mean();
        let (lat, lon) = flat::to_geodetic(origin[0], origin[1], p[0], p[1]);
        let mut mode = 0;
        for (bit, k) in [
            (aiding::HEADING, ATT),
            (aiding::DVL, DVL),
            (aiding::GPS, GPS),
            (aiding::FIX, FIX),
            (aiding::DEPTH, DEPTH),
        ] {
            if self.fresh(self.last_ns[k], t) {
                mode |= bit;
            }
        }
        let pv = self.pos.var();
        Nav {
            stamp_ns: t,
            lat_rad: lat,
            lon_rad: wrap_pi(lon),
            depth_m: p[2],
            vel_ned_m_s: Vector::from_array(self.vel.mean()),
            attitude: self.attitude,
            pos_std_ned_m: Vector::from_array(pv.map(f64::sqrt)),
            vel_std_ned_m_s: Vector::from_array(self.vel.var().map(f64::sqrt)),
            predicted_drift_m: (pv[0] + pv[1]).sqrt(),
            aiding_mode: mode,
            advisory: advisory::surface((pv[0] + pv[1]).sqrt(), self.config.surfacing_threshold),
        }
    }

    fn moments(f: &Filter) -> ComponentMoments {
        ComponentMoments {
            mean: f.mean(),
            std: f.var().map(f64::sqrt),
        }
    }
}

impl Estimator for ParticleAins {
    type Input = AinsInput;
    type Output = Nav;
    type Snapshot = AinsPfSnapshot;

    fn on_input(&mut self, input: &AinsInput, out: &mut Vec<Nav>) -> Result<(), EstimatorError> {
        let t = input.stamp_ns();
        if let Some(skip) = self.skip_until_ns {
            if t <= skip {
                return Ok(());
            }
            self.skip_until_ns = None;
        }
        if let Some(last) = self.last_stamp_ns
            && t < last
        {
            return Err(err(
                "stamp-backwards",
                format!("input stamped {t} ns after one stamped {last} ns"),
            ));
        }
        check_input(&self.config, input)?;
        match input {
            AinsInput::Imu(m) => self.on_imu(m, t, out)?,
            AinsInput::Attitude(a) => self.on_estimate(a, t),
            AinsInput::Ahrs(a) => self.on_ahrs(a, t),
            AinsInput::Dvl(d) => self.on_dvl(d, t),
            AinsInput::Depth(d) => self.on_depth(d, t),
            AinsInput::Gps(g) => self.on_gps(g, t),
            AinsInput::Fix(f) => self.on_fix(f, t),
        }
        self.last_stamp_ns = Some(t);
        Ok(())
    }

    fn snapshot(&self) -> Option<AinsPfSnapshot> {
        let origin = self.origin_rad?;
        let attitude = self.attitude?;
        let drift: [Moments; 3] = std::array::from_fn(|i| self.pos.c[i].b_moments());
        let bias: [Moments; 3] = std::array::from_fn(|i| self.vel.c[i].b_moments());
        Some(AinsPfSnapshot {
            last_stamp_ns: self.last_stamp_ns?,
            origin_rad: origin,
            position_from_site: self.position_from_site,
            velocity: Self::moments(&self.vel),
            accel_bias: ComponentMoments {
                mean: bias.map(|m| m.mean),
                std: bias.map(|m| m.var.sqrt()),
            },
            position: Self::moments(&self.pos),
            drift: ComponentMoments {
                mean: drift.map(|m| m.mean),
                std: drift.map(|m| m.var.sqrt()),
            },
            attitude_wxyz: attitude.to_wxyz(),
            attitude_from_estimate: self.attitude_from_estimate,
            attitude_track: self.track,
            last_ns: self.last_ns,
            tare: self.tare.state(),
            stats: self.stats,
            rng: self.noise.state(),
        })
    }

    fn restore(&mut self, s: &AinsPfSnapshot, stamp_ns: u64) -> Result<(), EstimatorError> {
        let refused = |e: &dyn std::fmt::Display| err("snapshot-refused", e);
        s.check().map_err(|e| refused(&e))?;
        if s.last_stamp_ns > stamp_ns {
            return Err(refused(&format!(
                "snapshot's last input at {} ns is after its stamp {stamp_ns} ns",
                s.last_stamp_ns
            )));
        }
        let mut noise = Noise::from_state(&s.rng)
            .ok_or_else(|| refused(&"the generator's state is not one"))?;
        let attitude = Rotation::from_wxyz(s.attitude_wxyz).map_err(|e| refused(&e))?;
        // The clouds drawn again from the moments (module docs of snapshot).
        let mut vel = self.vel.clone();
        let mut pos = self.pos.clone();
        for i in 0..3 {
            let bias = Moments {
                mean: s.accel_bias.mean[i],
                var: s.accel_bias.std[i] * s.accel_bias.std[i],
            };
            vel.c[i].spread(s.velocity.mean[i], s.velocity.std[i], bias, &mut noise);
            let drift = Moments {
                mean: s.drift.mean[i],
                var: s.drift.std[i] * s.drift.std[i],
            };
            pos.c[i].spread(s.position.mean[i], s.position.std[i], drift, &mut noise);
        }
        vel.refresh();
        pos.refresh();
        self.vel = vel;
        self.pos = pos;
        self.noise = noise;
        self.origin_rad = Some(s.origin_rad);
        self.position_from_site = s.position_from_site;
        self.attitude = Some(attitude);
        self.attitude_from_estimate = s.attitude_from_estimate;
        self.track = s.attitude_track;
        self.last_ns = s.last_ns;
        self.last_stamp_ns = Some(s.last_stamp_ns);
        self.tare.set_state(s.tare);
        self.stats = s.stats;
        self.skip_until_ns = Some(stamp_ns);
        Ok(())
    }
}
