//! The positioning role's estimator (both variants): the dead-reckoned
//! centre moved by eq. 50, the depth gauge and its tare, paper 000's
//! surface rule, the gate, and one of the two filters on the offsets.
//!
//! - Before a position: the cloud starts around the first GPS fix (eq. 48;
//!   the simulator gives them above 0.3 m), or, without one, around the
//!   first `ains/nav` position in a square of twice its σ.
//! - At the surface (the tared depth below `surface_depth_m`, paper 000's
//!   4 m): each GPS fix is weighed as a position measurement (the filter
//!   restarts around it only without a position or beyond the gate), and
//!   the estimate after it published as a fix of source [`source::GPS`];
//!   the dive starts from what the surface fixes gave.
//! - Each buoy message: the random walk since the last one, then the gate
//!   (innovation against the filter's own spread and σ_d), then the
//!   update; a fix of source [`source::BUOY`]. A refused range changes
//!   nothing but the walk, and is counted by kind (`gated`).
//! - Submerged with no range used for `silence_s`: a fix of source
//!   [`source::NONE`] with the next depth reading, the centre carried by
//!   the velocity alone.

use crate::ains::tare::{DepthTare, TareState};
use crate::local::flat;
use crate::positioning::ekf::RangeEkf;
use crate::positioning::frame::{RangeFrame, RangeObs, advance, moved, range_row};
use crate::positioning::geometry::range_of_flight_m;
use crate::positioning::pf::BuoyPf;
use crate::positioning::process::{BE, BN, BUOY, DIM, Step, VEHICLE};
use crate::positioning::{
    Gaussian, PositioningEkfParams, PositioningInput, PositioningPfParams, RangeModel, source,
};
use crate::readings::{BuoyRangeReading, Depth, Fix, Gps, Nav};
use crate::role::{Estimator, EstimatorError};

/// Readings the depth tare averages at the surface (2 s of a 10 Hz gauge),
/// the aided INS's default `tare_samples`.
const TARE_SAMPLES: u64 = 20;
/// A depth reading within this of a GPS fix is taken at the surface, ns.
const SURFACE_GPS_WINDOW_NS: u64 = 1_000_000_000;
/// The smallest σ a GPS fix is weighed with, m.
const MIN_GPS_STD_M: f64 = 0.1;
/// The buoy's track moves its reference to itself when it is farther than
/// this from it, m (the flat mapping about the reference is then exact to
/// millimetres).
const BUOY_RECENTRE_M: f64 = 100.0;

/// The dead-reckoned centre, rad, at `stamp_ns`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Centre {
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Time of validity, ns.
    pub stamp_ns: u64,
}

/// What the role counted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct PositioningStats {
    /// Buoy ranges used.
    pub ranges_used: u64,
    /// Buoy ranges refused by the gate.
    pub ranges_gated: u64,
    /// Buoy ranges before any position or depth.
    pub ranges_early: u64,
    /// GPS fixes used at the surface.
    pub gps_fixes: u64,
    /// GPS fixes refused below the surface depth.
    pub gps_submerged: u64,
    /// Fixes of source [`source::NONE`] published.
    pub silent_fixes: u64,
    /// Buoy broadcasts beyond the gate from its track, which restarted it.
    pub buoy_restarts: u64,
}

/// The state one instance hands another (warm restart, hot swap): every
/// value of the estimator but the particles, which a restarted `pf`
/// redraws from the Gaussian.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PositioningState {
    /// The centre, once there is a position.
    pub centre: Option<Centre>,
    /// The filter's distribution about the centre.
    pub offsets: Gaussian,
    /// The point the buoy's tracked offsets are from, rad, once a buoy
    /// broadcast came.
    pub buoy_ref_rad: Option<[f64; 2]>,
    /// The navigation's last north and east velocity, m/s.
    pub velocity_m_s: Option<[f64; 2]>,
    /// The last tared depth, m.
    pub depth_m: Option<f64>,
    /// The depth gauge's tare.
    pub tare: TareState,
    /// The last GPS fix, ns.
    pub last_gps_ns: Option<u64>,
    /// The time since the filter's state was last moved, and how far the
    /// centre moved in it.
    pub pending: Step,
    /// The next silence fix is due at or after this, ns.
    pub next_silence_ns: u64,
    /// The counters.
    pub stats: PositioningStats,
}

/// What a positioning snapshot message carries: a state, or why it could
/// not be read (refused on restore).
#[derive(Debug, Clone, PartialEq)]
pub enum Saved {
    /// The state, and the variant that wrote it.
    State(Box<PositioningState>, String),
    /// Why the message did not decode.
    Unreadable(String),
}

#[derive(Debug, Clone)]
enum Filter {
    Pf(Box<BuoyPf>),
    Ekf(Box<RangeEkf>),
}

/// The positioning estimator (module docs).
#[derive(Debug, Clone)]
pub struct Positioning {
    model: RangeModel,
    filter: Filter,
    centre: Option<Centre>,
    buoy_ref: Option<[f64; 2]>,
    velocity: Option<[f64; 2]>,
    depth: Option<f64>,
    tare: DepthTare,
    last_gps_ns: Option<u64>,
    pending: Step,
    next_silence_ns: u64,
    stats: PositioningStats,
    resume_after: Option<u64>,
}

impl Positioning {
    /// The `pf` variant.
    pub fn pf(p: &PositioningPfParams) -> anyhow::Result<Self> {
        p.validate()?;
        let mut model = p.model;
        model.track_buoy.get_or_insert(false);
        Ok(Self::with(model, Filter::Pf(Box::new(BuoyPf::new(p)))))
    }

    /// The `ekf` variant.
    pub fn ekf(p: &PositioningEkfParams) -> anyhow::Result<Self> {
        p.validate()?;
        Ok(Self::with(
            p.model,
            Filter::Ekf(Box::new(RangeEkf::new(
                &p.model.prior_sigma(p.model.init_half_width_m),
            ))),
        ))
    }

    fn with(model: RangeModel, filter: Filter) -> Self {
        Self {
            model,
            filter,
            centre: None,
            buoy_ref: None,
            velocity: None,
            depth: None,
            tare: DepthTare::new(TARE_SAMPLES),
            last_gps_ns: None,
            pending: Step::default(),
            next_silence_ns: 0,
            stats: PositioningStats::default(),
            resume_after: None,
        }
    }

    /// The variant's name.
    pub fn variant(&self) -> &'static str {
        match self.filter {
            Filter::Pf(_) => "pf",
            Filter::Ekf(_) => "ekf",
        }
    }

    /// What the role counted.
    pub fn stats(&self) -> PositioningStats {
        self.stats
    }

    /// The current estimate, once there is a position: the centre moved
    /// by the filter's mean, and the covariance.
    pub fn estimate(&self) -> Option<(f64, f64, Gaussian)> {
        let c = self.centre?;
        let g = self.offsets();
        let (lat, lon) = moved(c.lat_rad, c.lon_rad, g.mean[0], g.mean[1]);
        Some((lat, lon, g))
    }

    fn offsets(&self) -> Gaussian {
        match &self.filter {
            Filter::Pf(p) => p.estimate(),
            Filter::Ekf(e) => e.estimate(),
        }
    }

    fn submerged(&self) -> bool {
        self.depth.is_some_and(|d| d >= self.model.surface_depth_m)
    }

    /// Restarts the filter around `(lat, lon)` at `stamp_ns`.
    fn start(&mut self, lat_rad: f64, lon_rad: f64, stamp_ns: u64, half_width_m: f64) {
        self.centre = Some(Centre {
            lat_rad,
            lon_rad,
            stamp_ns,
        });
        let sigma = self.model.prior_sigma(half_width_m);
        match &mut self.filter {
            Filter::Pf(p) => p.reset(VEHICLE, &sigma),
            Filter::Ekf(e) => e.restart(VEHICLE, &sigma),
        }
        self.pending = Step::default();
        self.next_silence_ns = stamp_ns.saturating_add(self.silence_ns());
    }

    fn silence_ns(&self) -> u64 {
        (self.model.silence_s * 1e9) as u64
    }

    /// Eq. 50: the centre to `stamp_ns` with the last velocity; the
    /// filter's own motion over the time is applied when it is next used.
    fn advance_to(&mut self, stamp_ns: u64) {
        let Some(c) = &mut self.centre else {
            return;
        };
        if stamp_ns <= c.stamp_ns {
            return;
        }
        let dt = (stamp_ns - c.stamp_ns) as f64 * 1e-9;
        if let Some(v) = self.velocity {
            let (lat, lon) = advance(c.lat_rad, c.lon_rad, v, self.depth.unwrap_or(0.0), dt);
            c.lat_rad = lat;
            c.lon_rad = lon;
            self.pending.displacement_m[0] += v[0] * dt;
            self.pending.displacement_m[1] += v[1] * dt;
        }
        c.stamp_ns = stamp_ns;
        self.pending.dt_s += dt;
    }

    fn fix(&self, stamp_ns: u64, source: u32) -> Option<Fix> {
        let (lat, lon, g) = self.estimate()?;
        let (sn, se) = (g.cov[0][0].max(0.0).sqrt(), g.cov[1][1].max(0.0).sqrt());
        let corr = if sn > 0.0 && se > 0.0 {
            (g.cov[0][1] / (sn * se)).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        Some(Fix {
            stamp_ns,
            lat_rad: lat,
            lon_rad: lon,
            std_north_m: sn,
            std_east_m: se,
            corr_ne: corr,
            effective_particles: g.effective_particles,
            source,
        })
    }

    fn on_nav(&mut self, n: &Nav) {
        if self.centre.is_none() {
            let s = n.pos_std_ned_m.to_array();
            let hw = self.model.init_half_width_m.max(2.0 * s[0].max(s[1]));
            self.start(n.lat_rad, n.lon_rad, n.stamp_ns, hw);
        }
        self.advance_to(n.stamp_ns);
        let v = n.vel_ned_m_s.to_array();
        self.velocity = Some([v[0], v[1]]);
    }

    /// The filter's motion since it was last moved ([`super::process`]).
    fn apply_walk(&mut self) {
        let step = std::mem::take(&mut self.pending);
        let w = self.model.walk();
        match &mut self.filter {
            Filter::Pf(p) => p.propagate(&w, &step),
            Filter::Ekf(e) => e.propagate(&w, &step),
        }
    }

    fn on_depth(&mut self, d: &Depth, out: &mut Vec<Fix>) {
        let near_gps = self
            .last_gps_ns
            .is_some_and(|g| d.stamp_ns.saturating_sub(g) <= SURFACE_GPS_WINDOW_NS);
        if near_gps && self.tare.depth_m(d.depth_m) < self.model.surface_depth_m {
            self.tare.push_surface(d.depth_m);
        } else {
            self.tare.end_session();
        }
        self.depth = Some(self.tare.depth_m(d.depth_m));
        // The silence fix comes with a sensor's sample, not the ains's, so
        // that the role's watermark moves with the sensor's (`ains/nav` is
        // an aiding input: the cycle ains ↔ positioning waits on neither).
        if self.submerged() && self.centre.is_some() && d.stamp_ns >= self.next_silence_ns {
            self.next_silence_ns = d.stamp_ns.saturating_add(self.silence_ns());
            self.advance_to(d.stamp_ns);
            self.apply_walk();
            if let Some(f) = self.fix(d.stamp_ns, source::NONE) {
                self.stats.silent_fixes += 1;
                out.push(f);
            }
        }
    }

    fn on_gps(&mut self, g: &Gps, out: &mut Vec<Fix>) -> Result<(), EstimatorError> {
        if self.submerged() {
            self.stats.gps_submerged += 1;
            return Err(EstimatorError::new(
                "gps_submerged",
                format!(
                    "a GPS fix at {:.1} m of depth (the surface rule is {} m)",
                    self.depth.unwrap_or(0.0),
                    self.model.surface_depth_m
                ),
            ));
        }
        self.last_gps_ns = Some(g.stamp_ns);
        self.stats.gps_fixes += 1;
        if !self.fuse_gps(g) {
            self.start(
                g.lat_rad,
                g.lon_rad,
                g.stamp_ns,
                self.model.init_half_width_m,
            );
        }
        out.extend(self.fix(g.stamp_ns, source::GPS));
        Ok(())
    }

    /// A GPS fix at the surface as a position measurement of the filter
    /// (our addition: the paper restarts around each fix, so that the dive
    /// starts from the last one alone, 2.5 m off with the simulator's
    /// receiver; weighed, a minute at the surface averages them). False,
    /// and nothing changed, when there is no position yet or the fix lies
    /// beyond the gate from it (a restart).
    fn fuse_gps(&mut self, g: &Gps) -> bool {
        let Some(c) = self.centre else {
            return false;
        };
        if g.stamp_ns < c.stamp_ns {
            return false;
        }
        self.advance_to(g.stamp_ns);
        let c = self.centre.expect("checked above");
        let (zn, ze) = flat::to_local(c.lat_rad, c.lon_rad, g.lat_rad, g.lon_rad);
        // A receiver's σ of zero would weigh with an infinite precision.
        let var = g.horizontal_std_m.max(MIN_GPS_STD_M).powi(2);
        let e = self.offsets();
        // d² of the 2-D innovation with the filter's covariance.
        let (a, b, d) = (e.cov[0][0] + var, e.cov[0][1], e.cov[1][1] + var);
        let (nn, ne) = (zn - e.mean[0], ze - e.mean[1]);
        let det = a * d - b * b;
        let d2 = (d * nn * nn - 2.0 * b * nn * ne + a * ne * ne) / det;
        if !(det > 0.0 && d2 <= self.model.gate_sigmas.powi(2)) {
            return false;
        }
        self.apply_walk();
        let by = match &mut self.filter {
            Filter::Pf(p) => {
                p.update_position([zn, ze], var);
                let m = p.estimate().mean;
                p.recentre([m[0], m[1]]);
                [m[0], m[1]]
            }
            Filter::Ekf(e) => e.update_position([zn, ze], var),
        };
        let c = self.centre.as_mut().expect("checked above");
        (c.lat_rad, c.lon_rad) = moved(c.lat_rad, c.lon_rad, by[0], by[1]);
        true
    }

    fn on_range(&mut self, b: &BuoyRangeReading, out: &mut Vec<Fix>) -> Result<(), EstimatorError> {
        let (Some(_), Some(depth)) = (self.centre, self.depth) else {
            self.stats.ranges_early += 1;
            return Err(EstimatorError::new(
                "no_position",
                "a buoy range before the first position and depth",
            ));
        };
        self.advance_to(b.stamp_ns);
        self.apply_walk();
        let buoy = if self.model.tracks_buoy() {
            self.track_buoy(b)
        } else {
            [b.buoy_lat_rad, b.buoy_lon_rad]
        };
        let range_m = range_of_flight_m(b.time_of_flight_s, b.sound_speed_m_s);
        let obs = RangeObs {
            range_m,
            var_m2: self.model.range_var_m2(),
            buoy_lat_rad: buoy[0],
            buoy_lon_rad: buoy[1],
            depth_m: depth,
            buoy_depth_m: b.buoy_depth_m,
        };
        let c = self.centre.expect("checked above");
        let frame = RangeFrame::new(c.lat_rad, c.lon_rad, obs);
        // The gate: the innovation at the estimate against σ_d and the
        // filter's spread along the line of sight, in the sound speed and
        // in the buoy's position.
        let g = self.offsets();
        let (h, predicted) = range_row(&frame, &g.mean);
        let spread: f64 = (0..DIM)
            .map(|i| (0..DIM).map(|j| h[i] * g.cov[i][j] * h[j]).sum::<f64>())
            .sum();
        let s = obs.var_m2 + spread.max(0.0);
        let nu = range_m - predicted;
        if !(nu * nu <= self.model.gate_sigmas.powi(2) * s) {
            self.stats.ranges_gated += 1;
            return Err(EstimatorError::new(
                "gated",
                format!(
                    "a buoy range {nu:+.1} m from the estimate, beyond {} σ ({:.1} m)",
                    self.model.gate_sigmas,
                    self.model.gate_sigmas * s.sqrt()
                ),
            ));
        }
        let by = match &mut self.filter {
            Filter::Pf(p) => {
                p.update(&frame);
                let m = p.estimate().mean;
                let by = [m[0], m[1]];
                p.recentre(by);
                by
            }
            Filter::Ekf(e) => e.update(&frame),
        };
        let c = self.centre.as_mut().expect("checked above");
        (c.lat_rad, c.lon_rad) = moved(c.lat_rad, c.lon_rad, by[0], by[1]);
        self.stats.ranges_used += 1;
        self.next_silence_ns = b.stamp_ns.saturating_add(self.silence_ns());
        out.extend(self.fix(b.stamp_ns, source::BUOY));
        Ok(())
    }

    /// The buoy's broadcast position as a measurement of its tracked
    /// position ([`super::process`]); the reference its offsets are from.
    /// The first broadcast starts the track at itself; one beyond the gate
    /// from the track (a buoy moved, a track gone wrong) starts it again
    /// there, counted in `buoy_restarts`; a track more than
    /// [`BUOY_RECENTRE_M`] from its reference moves the reference.
    fn track_buoy(&mut self, b: &BuoyRangeReading) -> [f64; 2] {
        let reported = [b.buoy_lat_rad, b.buoy_lon_rad];
        let var = self.model.buoy_var_m2();
        let Some(r) = self.buoy_ref else {
            self.restart_buoy(reported);
            return reported;
        };
        let (zn, ze) = flat::to_local(r[0], r[1], reported[0], reported[1]);
        let g = self.offsets();
        let (a, c, d) = (g.cov[BN][BN] + var, g.cov[BN][BE], g.cov[BE][BE] + var);
        let (nn, ne) = (zn - g.mean[BN], ze - g.mean[BE]);
        let det = a * d - c * c;
        let d2 = (d * nn * nn - 2.0 * c * nn * ne + a * ne * ne) / det;
        if !(det > 0.0 && d2 <= self.model.gate_sigmas.powi(2)) {
            self.stats.buoy_restarts += 1;
            self.restart_buoy(reported);
            return reported;
        }
        match &mut self.filter {
            Filter::Pf(p) => p.update_buoy([zn, ze], var),
            Filter::Ekf(e) => e.update_buoy([zn, ze], var),
        }
        let m = self.offsets().mean;
        if m[BN].hypot(m[BE]) <= BUOY_RECENTRE_M {
            return r;
        }
        let moved = flat::to_geodetic(r[0], r[1], m[BN], m[BE]);
        match &mut self.filter {
            Filter::Pf(p) => p.recentre_buoy([m[BN], m[BE]]),
            Filter::Ekf(e) => {
                e.x[BN] -= m[BN];
                e.x[BE] -= m[BE];
            }
        }
        self.buoy_ref = Some([moved.0, moved.1]);
        [moved.0, moved.1]
    }

    /// The buoy's track started at `at` (its reference).
    fn restart_buoy(&mut self, at: [f64; 2]) {
        self.buoy_ref = Some(at);
        let sigma = self.model.prior_sigma(self.model.init_half_width_m);
        match &mut self.filter {
            Filter::Pf(p) => p.reset(BUOY, &sigma),
            Filter::Ekf(e) => e.restart(BUOY, &sigma),
        }
    }

    /// The state for a snapshot, once there is a position.
    pub fn state(&self) -> Option<PositioningState> {
        self.centre?;
        Some(PositioningState {
            centre: self.centre,
            offsets: self.offsets(),
            buoy_ref_rad: self.buoy_ref,
            velocity_m_s: self.velocity,
            depth_m: self.depth,
            tare: self.tare.state(),
            last_gps_ns: self.last_gps_ns,
            pending: self.pending,
            next_silence_ns: self.next_silence_ns,
            stats: self.stats,
        })
    }
}

impl PositioningState {
    /// Whether every value is finite and in range (a snapshot's check).
    pub fn is_valid(&self) -> bool {
        let g = &self.offsets;
        let c = &g.cov;
        let finite = g
            .mean
            .iter()
            .chain(c.iter().flatten())
            .all(|x| x.is_finite())
            && g.effective_particles.is_finite()
            && self.pending.dt_s.is_finite()
            && self.pending.dt_s >= 0.0
            && self.pending.displacement_m.iter().all(|d| d.is_finite());
        // Variances not negative, correlations within ±1 (to rounding).
        let positive = (0..DIM).all(|i| {
            c[i][i] >= 0.0
                && (0..DIM).all(|j| c[i][j] * c[i][j] <= c[i][i] * c[j][j] * (1.0 + 1e-9) + 1e-300)
        });
        let centre = self.centre.is_none_or(|c| {
            c.lat_rad.is_finite()
                && c.lon_rad.is_finite()
                && c.lat_rad.abs() <= std::f64::consts::FRAC_PI_2
        });
        let v = self
            .velocity_m_s
            .is_none_or(|v| v.iter().all(|x| x.is_finite()));
        let buoy = self
            .buoy_ref_rad
            .is_none_or(|b| b[0].abs() <= std::f64::consts::FRAC_PI_2 && b[1].is_finite());
        let d = self.depth_m.is_none_or(f64::is_finite);
        finite && positive && centre && v && d && buoy
    }
}

impl Estimator for Positioning {
    type Input = PositioningInput;
    type Output = Fix;
    type Snapshot = Saved;

    fn on_input(
        &mut self,
        input: &PositioningInput,
        out: &mut Vec<Fix>,
    ) -> Result<(), EstimatorError> {
        let stamp = crate::role::Stamped::stamp_ns(input);
        if self.resume_after.is_some_and(|r| stamp <= r) {
            return Ok(());
        }
        match input {
            PositioningInput::Nav(n) => {
                self.on_nav(n);
                Ok(())
            }
            PositioningInput::Depth(d) => {
                self.on_depth(d, out);
                Ok(())
            }
            PositioningInput::Gps(g) => self.on_gps(g, out),
            PositioningInput::Modem(b) => self.on_range(b, out),
        }
    }

    fn snapshot(&self) -> Option<Saved> {
        self.state()
            .map(|s| Saved::State(Box::new(s), self.variant().to_string()))
    }

    fn restore(&mut self, saved: &Saved, stamp_ns: u64) -> Result<(), EstimatorError> {
        let s = match saved {
            Saved::State(s, _) => s,
            Saved::Unreadable(why) => {
                return Err(EstimatorError::new(
                    "snapshot",
                    format!("an unreadable positioning snapshot: {why}"),
                ));
            }
        };
        if !s.is_valid() {
            return Err(EstimatorError::new(
                "snapshot",
                "a positioning snapshot with a non-finite or impossible value",
            ));
        }
        match &mut self.filter {
            Filter::Pf(p) => p.redraw(&s.offsets, stamp_ns),
            Filter::Ekf(e) => **e = RangeEkf::of(&s.offsets),
        }
        self.centre = s.centre;
        self.buoy_ref = s.buoy_ref_rad;
        self.velocity = s.velocity_m_s;
        self.depth = s.depth_m;
        self.tare.set_state(s.tare);
        self.last_gps_ns = s.last_gps_ns;
        self.pending = s.pending;
        self.next_silence_ns = s.next_silence_ns;
        self.stats = s.stats;
        self.resume_after = Some(stamp_ns);
        Ok(())
    }
}
