//! The LBL role's estimator (paper 003 §V): the filter stepped on a fixed
//! grid of the run's clock, the inputs it holds, the replies it checks and
//! gates, the interrogations it schedules, and its snapshot.
//!
//! - **Steps.** Every `1 / rate_hz` (10 Hz) on the grid of the run's clock,
//!   triggered by the first input stamped at or after the grid point and
//!   before that input is taken in: the prediction over the step with the
//!   inputs held since the previous one (zero-order hold), then the ranges
//!   and the GPS fix that arrived during the step, then `lbl/nav` stamped
//!   at the grid point, then, if one is due, an interrogation stamped there
//!   too (the sensor's lock step, DESIGN §7: an interrogator pings at its
//!   "now", the watermark it was given).
//! - **Replies** are checked when they arrive: a transponder of the layout,
//!   an interrogation of ours not yet answered, a round trip that gives a
//!   range in (0, `max_range_m`] and fits between the ping and the reply;
//!   then gated (paper 003 §V-C, `‖r − r*‖²_{S⁻¹} ≤ γ`) against the last
//!   step's state moved to the middle of the round trip. A refusal is an
//!   [`EstimatorError`] of its kind, which the shell counts; an accepted
//!   range is applied at the next step (paper 004 §IV takes ranges at the
//!   steps' instants; the move back to the round trip's middle makes the
//!   ≤ 100 ms wait exact).
//! - **Re-acquisition.** After `reacquire_after` ranges refused in a row
//!   with none accepted for `reacquire_s`, or after `reacquire_agreeing`
//!   ranges of one transponder refused in a row whose innovations agree
//!   (the estimate is off, not the ranges: a multipath reply is late by a
//!   random amount), the range is accepted with the position's covariance
//!   widened by its innovation squared and the current's back to its
//!   starting σ: after a blackout the growth of `P` (eq. 4) usually lets
//!   the first range in anyway; these rules make sure no estimate, however
//!   wrong its `P` (a multipath reply taken while the start's `P` was still
//!   wide, then a current learnt from the conflict), is locked out.
//! - **GPS** at the surface (depth below `surface_depth_m`): the first fix
//!   after a dive resets the position; the next ones are weighed, and one
//!   beyond `gps_gate` resets again.
//! - **Two transponders** (every layout whose transponders lie on one
//!   line): the side of the baseline the filter starts on (at a GPS reset
//!   or the configured start) is kept; when the estimate crosses it, a
//!   warning says so once and `lbl/nav` carries the flag until it is back.

use nalgebra::{SMatrix, SVector};

use crate::attitude::from_euler;
use crate::lbl::baseline::Baseline;
use crate::lbl::forward::{ForwardStep, ForwardSteps};
use crate::lbl::history::History;
use crate::lbl::kalman::Kf;
use crate::lbl::layout::Layout;
use crate::lbl::model::{Basis, Dynamics, Model, propeller_basis};
use crate::lbl::params::{LblParams, VelocitySource};
use crate::lbl::range::{MidTrip, expected, range_of_round_trip};
use crate::lbl::selection;
use crate::lbl::state::{
    Held, LastRange, LblSaved, LblState, LblStats, MAX_PENDING, MAX_RECENT_PINGS, PendingGps,
    PendingRange, Pings, SentPing,
};
use crate::lbl::{LblInput, LblOutput, Ping};
use crate::readings::{Ahrs, Depth, Dvl, Gps, LblNav, LblReplyReading, Propeller};
use crate::role::{Estimator, EstimatorError, Stamped};

mod inputs;

/// An input older than this at a step is stale (counted), ns.
const STALE_NS: u64 = 1_000_000_000;
/// A gap in the inputs longer than this many steps is bridged by one step.
const MAX_STEPS_PER_INPUT: u64 = 6_000;
/// The smallest σ a GPS fix is weighed with, m.
const MIN_GPS_STD_M: f64 = 0.1;
/// A reply's round trip may exceed the time between the ping and the reply
/// by this much (the two stamps' own rounding), s.
const ROUND_TRIP_SLACK_S: f64 = 1e-3;

/// What the estimator knows of the site (the manifest's `[site]`).
#[derive(Debug, Clone, PartialEq)]
pub struct LblSite {
    /// The local frame's origin, latitude, rad.
    pub origin_lat_rad: f64,
    /// The local frame's origin, longitude, rad.
    pub origin_lon_rad: f64,
    /// Magnetic declination, rad, east positive (true = magnetic + it).
    pub declination_rad: f64,
    /// The sound speed the vehicle assumes, m/s.
    pub sound_speed_m_s: f64,
    /// The transponders.
    pub layout: Layout,
}

#[derive(Debug, Clone, PartialEq)]
enum Filter {
    Four(Kf<4>),
    Five(Kf<5>),
}

/// The LBL estimator (module docs).
#[derive(Debug, Clone)]
pub struct Lbl {
    params: LblParams,
    site: LblSite,
    model: Model,
    baseline: Option<Baseline>,
    period_ns: u64,
    filter: Option<Filter>,
    st: LblState,
    resume_after: Option<u64>,
    recorded: Option<ForwardSteps>,
    replay: bool,
}

fn refuse(kind: &'static str, detail: impl std::fmt::Display) -> EstimatorError {
    EstimatorError::new(kind, detail)
}

impl Lbl {
    /// The `ekf` variant with `params` at `site`.
    pub fn new(params: &LblParams, site: LblSite) -> anyhow::Result<Self> {
        params.validate()?;
        if !(site.sound_speed_m_s >= 1300.0 && site.sound_speed_m_s <= 1800.0) {
            anyhow::bail!(
                "the sound speed {} m/s is outside [1300, 1800]",
                site.sound_speed_m_s
            );
        }
        let dynamics = match (params.velocity_source, params.estimate_k) {
            (VelocitySource::Dvl, _) => Dynamics::OverGround,
            (VelocitySource::Propeller, true) => Dynamics::PropellerEstimatedK,
            (VelocitySource::Propeller, false) => Dynamics::Propeller {
                k: params.propeller_m_per_rad.unwrap_or_default(),
            },
        };
        let q_current = params.q_current_m2_s3;
        let model = Model {
            dynamics,
            q: [
                params.q_position_m2_s,
                params.q_position_m2_s,
                q_current,
                q_current,
                params.q_k,
            ],
        };
        Ok(Self {
            params: *params,
            baseline: Baseline::of(&site.layout),
            site,
            model,
            period_ns: params.period_ns(),
            filter: None,
            st: LblState {
                x: Vec::new(),
                p: Vec::new(),
                next_step_ns: None,
                held: Held::default(),
                history: History::default(),
                pending: Vec::new(),
                pending_gps: None,
                pings: Pings::default(),
                start_side: None,
                crossed: false,
                submerged: false,
                last: LastRange::default(),
                refused_in_row: 0,
                refusals: Vec::new(),
                last_accept_ns: None,
                stats: LblStats::default(),
            },
            resume_after: None,
            recorded: None,
            replay: false,
        })
    }

    /// Records every step for the smoother ([`Lbl::take_steps`]).
    pub fn record_steps(&mut self, on: bool) {
        self.recorded = on.then(|| {
            if self.dimension() == 5 {
                ForwardSteps::Five(Vec::new())
            } else {
                ForwardSteps::Four(Vec::new())
            }
        });
    }

    /// Takes the steps recorded so far.
    pub fn take_steps(&mut self) -> ForwardSteps {
        let empty = if self.dimension() == 5 {
            ForwardSteps::Five(Vec::new())
        } else {
            ForwardSteps::Four(Vec::new())
        };
        match self.recorded.as_mut() {
            Some(r) => std::mem::replace(r, empty),
            None => empty,
        }
    }

    /// Replaying a recording: a reply is taken once per transponder and
    /// interrogation stamp, without matching it to our own pings (which a
    /// recording's replies do not answer).
    pub fn replay_replies(&mut self, on: bool) {
        self.replay = on;
    }

    /// The filter's dimension (4, or 5 with `k`).
    pub fn dimension(&self) -> usize {
        if matches!(self.model.dynamics, Dynamics::PropellerEstimatedK) {
            5
        } else {
            4
        }
    }

    /// What the role counted.
    pub fn stats(&self) -> LblStats {
        self.st.stats
    }

    /// `E` and `P`, once started.
    pub fn estimate(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        self.filter.as_ref().map(|f| match f {
            Filter::Four(k) => (k.x.iter().copied().collect(), k.p.iter().copied().collect()),
            Filter::Five(k) => (k.x.iter().copied().collect(), k.p.iter().copied().collect()),
        })
    }

    fn period_s(&self) -> f64 {
        self.period_ns as f64 * 1e-9
    }

    /// `a` of eq. 3 from the held inputs (counted stale when one is older
    /// than a second at `t`).
    fn basis(&mut self, t: u64) -> Option<Basis> {
        let h = &self.st.held;
        let (a, oldest) = match self.params.velocity_source {
            VelocitySource::Propeller => {
                let (att, ta) = h.attitude?;
                let (w, tw) = h.shaft?;
                (propeller_basis(w, att[1], att[2]), ta.min(tw))
            }
            VelocitySource::Dvl => {
                let (v, tv) = h.ground_velocity?;
                (v, tv)
            }
        };
        if t.saturating_sub(oldest) > STALE_NS {
            self.st.stats.stale_steps += 1;
        }
        Some(a)
    }

    /// The held `a` without counting (for gating between steps).
    fn held_basis(&self) -> Basis {
        let h = &self.st.held;
        match self.params.velocity_source {
            VelocitySource::Propeller => match (h.attitude, h.shaft) {
                (Some((att, _)), Some((w, _))) => propeller_basis(w, att[1], att[2]),
                _ => [0.0; 2],
            },
            VelocitySource::Dvl => h.ground_velocity.map_or([0.0; 2], |(v, _)| v),
        }
    }

    /// Every step due at or before `stamp` (module docs).
    fn advance(&mut self, stamp: u64, out: &mut Vec<LblOutput>) {
        let p = self.period_ns;
        let mut next = *self
            .st
            .next_step_ns
            .get_or_insert(stamp.div_ceil(p).saturating_mul(p));
        if next <= stamp && (stamp - next) / p > MAX_STEPS_PER_INPUT {
            // A gap: one step over it to the last grid point.
            let last = stamp - stamp % p;
            let dt = (last - (next.saturating_sub(p))) as f64 * 1e-9;
            self.st.stats.jumps += 1;
            self.st.history.clear();
            self.step(last, dt, out);
            next = last + p;
        }
        while next <= stamp {
            self.step(next, self.period_s(), out);
            next += p;
        }
        self.st.next_step_ns = Some(next);
    }

    fn step(&mut self, t: u64, dt_s: f64, out: &mut Vec<LblOutput>) {
        self.st.stats.steps += 1;
        let drive = self.basis(t);
        match self.filter.take() {
            None => {
                let Some(a) = drive else {
                    return;
                };
                if !self.start(t, a) {
                    return;
                }
            }
            Some(Filter::Four(mut kf)) => {
                let a = drive.unwrap_or_default();
                let s = self.advance_kf(&mut kf, t, dt_s, a);
                if let Some(ForwardSteps::Four(v)) = &mut self.recorded {
                    v.push(s);
                }
                self.filter = Some(Filter::Four(kf));
            }
            Some(Filter::Five(mut kf)) => {
                let a = drive.unwrap_or_default();
                let s = self.advance_kf(&mut kf, t, dt_s, a);
                if let Some(ForwardSteps::Five(v)) = &mut self.recorded {
                    v.push(s);
                }
                self.filter = Some(Filter::Five(kf));
            }
        }
        self.publish(t, out);
    }

    /// Starts the filter at `t` from a GPS fix at the surface or the
    /// configured start; false while there is neither.
    fn start(&mut self, t: u64, a: Basis) -> bool {
        let (xy, var) = match (self.st.pending_gps.take(), self.params.initial_position_m) {
            (Some(g), _) => (g.position_m, g.var_m2),
            (None, Some(p)) => (p, self.params.initial_sigma_m.powi(2)),
            (None, None) => return false,
        };
        let vw = self.params.initial_current_sigma_m_s.powi(2);
        self.st.history.push(a);
        self.st.submerged = false;
        self.st.last_accept_ns = Some(t);
        self.st.start_side = self.baseline.map(|b| b.side_m(xy[0], xy[1]).signum());
        macro_rules! started {
            ($n:literal, $variant:ident) => {{
                let mut x = SVector::<f64, $n>::zeros();
                x[0] = xy[0];
                x[1] = xy[1];
                let mut p = SMatrix::<f64, $n, $n>::zeros();
                p[(0, 0)] = var;
                p[(1, 1)] = var;
                p[(2, 2)] = vw;
                p[(3, 3)] = vw;
                if $n > 4 {
                    let k = self.params.propeller_m_per_rad.unwrap_or_default();
                    x[$n - 1] = k;
                    p[($n - 1, $n - 1)] = (self.params.k_sigma_rel * k).powi(2);
                }
                let kf = Kf { x, p };
                if let Some(ForwardSteps::$variant(v)) = &mut self.recorded {
                    v.push(ForwardStep {
                        stamp_ns: t,
                        phi: SMatrix::identity(),
                        x_prior: x,
                        p_prior: p,
                        x_post: x,
                        p_post: p,
                    });
                }
                Filter::$variant(kf)
            }};
        }
        self.filter = Some(if self.dimension() == 5 {
            started!(5, Five)
        } else {
            started!(4, Four)
        });
        tracing::info!(
            north_m = xy[0],
            east_m = xy[1],
            sigma_m = var.sqrt(),
            "LBL filter started"
        );
        true
    }

    /// One step of a running filter (module docs): the prediction, the
    /// pending ranges and GPS fix, the side of the baseline.
    fn advance_kf<const N: usize>(
        &mut self,
        kf: &mut Kf<N>,
        t: u64,
        dt_s: f64,
        a: Basis,
    ) -> ForwardStep<N> {
        let d = self.model.discrete::<N>(a, dt_s);
        kf.predict(&d);
        self.st.history.push(a);
        let prior = *kf;
        for r in std::mem::take(&mut self.st.pending) {
            self.apply_range(kf, t, &r, a);
        }
        if let Some(g) = self.st.pending_gps.take() {
            self.apply_gps(kf, &g);
        }
        self.check_side(kf.x[0], kf.x[1]);
        ForwardStep {
            stamp_ns: t,
            phi: d.phi,
            x_prior: prior.x,
            p_prior: prior.p,
            x_post: kf.x,
            p_post: kf.p,
        }
    }

    /// `r*` and `H` of a range whose round trip's middle is `mid_ns`, from
    /// the state `x` at `t` (paper 003 §V-C at the middle of the round trip).
    fn range_model<const N: usize>(
        &self,
        x: &SVector<f64, N>,
        t: u64,
        mid_ns: u64,
        transponder_id: u32,
        a_now: Basis,
    ) -> Option<(f64, SMatrix<f64, 1, N>)> {
        let tx = self.site.layout.get(transponder_id)?;
        let depth = self.st.held.depth?.0;
        let lag_s = (t as f64 - mid_ns as f64) * 1e-9;
        let basis_integral = if lag_s >= 0.0 {
            self.st.history.integral(lag_s, self.period_s(), a_now)
        } else {
            [a_now[0] * lag_s, a_now[1] * lag_s]
        };
        expected(
            &self.model,
            x,
            &MidTrip {
                lag_s,
                basis_integral,
            },
            depth,
            tx,
        )
    }

    fn apply_range<const N: usize>(&mut self, kf: &mut Kf<N>, t: u64, r: &PendingRange, a: Basis) {
        let Some((r_star, h)) = self.range_model(&kf.x, t, r.mid_ns, r.transponder_id, a) else {
            return;
        };
        let nu = r.range_m - r_star;
        if r.after_gap {
            kf.decorrelate_position();
        }
        if r.reacquire {
            kf.p[(0, 0)] += nu * nu;
            kf.p[(1, 1)] += nu * nu;
            // Ranges refused long enough to re-acquire mean the dead
            // reckoning went wrong, and the current is what moves the
            // estimate away between ranges: it is as unknown as at the
            // start again (kept, a wrong current drifted the estimate off
            // after each re-acquisition).
            let vw = self.params.initial_current_sigma_m_s.powi(2);
            for i in [2, 3] {
                kf.p[(i, i)] = kf.p[(i, i)].max(vw);
            }
        }
        // Paper 003 §V-C: E⁺ = E⁻ + K (r − r*), P⁺ (Joseph form).
        if kf.update(&h, nu, self.params.range_sigma_m.powi(2)) {
            self.st.stats.ranges_used += 1;
        }
    }

    fn apply_gps<const N: usize>(&mut self, kf: &mut Kf<N>, g: &PendingGps) {
        let (dn, de) = (g.position_m[0] - kf.x[0], g.position_m[1] - kf.x[1]);
        let (a, b, d) = (
            kf.p[(0, 0)] + g.var_m2,
            kf.p[(0, 1)],
            kf.p[(1, 1)] + g.var_m2,
        );
        let det = a * d - b * b;
        let d2 = (d * dn * dn - 2.0 * b * dn * de + a * de * de) / det;
        if g.reset || !(det > 0.0 && d2 <= self.params.gps_gate) {
            kf.reset_position(g.position_m, g.var_m2);
            self.st.stats.gps_resets += 1;
            self.st.start_side = self
                .baseline
                .map(|b| b.side_m(g.position_m[0], g.position_m[1]).signum());
            self.st.crossed = false;
        } else {
            for axis in 0..2 {
                let mut h = SMatrix::<f64, 1, N>::zeros();
                h[axis] = 1.0;
                let nu = g.position_m[axis] - kf.x[axis];
                kf.update(&h, nu, g.var_m2);
            }
            self.st.stats.gps_used += 1;
        }
        self.st.submerged = false;
        self.st.last_accept_ns = Some(g.stamp_ns);
    }

    /// Paper 003 §III: says when the estimate crosses the baseline of a
    /// two-transponder layout.
    fn check_side(&mut self, x: f64, y: f64) {
        let (Some(b), Some(s0)) = (self.baseline, self.st.start_side) else {
            return;
        };
        let s = b.side_m(x, y);
        let crossed = s * s0 < 0.0;
        if crossed && !self.st.crossed {
            self.st.stats.baseline_crossings += 1;
            tracing::warn!(
                north_m = x,
                east_m = y,
                distance_m = s.abs(),
                "the estimate crossed the two-transponder baseline: the fix is ambiguous there \
                 (paper 003 §III); lbl/nav is flagged degraded until it is back on the start side"
            );
        }
        self.st.crossed = crossed;
    }

    /// `lbl/nav` at `t`, and the next interrogation if one is due.
    fn publish(&mut self, t: u64, out: &mut Vec<LblOutput>) {
        let Some(f) = &self.filter else {
            return;
        };
        let (xy, p_xy, nav) = match f {
            Filter::Four(k) => (
                [k.x[0], k.x[1]],
                k.p_xy(),
                self.nav(t, k.x.as_slice(), &|i, j| k.p[(i, j)]),
            ),
            Filter::Five(k) => (
                [k.x[0], k.x[1]],
                k.p_xy(),
                self.nav(t, k.x.as_slice(), &|i, j| k.p[(i, j)]),
            ),
        };
        out.push(LblOutput::Nav(nav));
        // Paper 003 §V-D: right after the previous reply, or after the timeout.
        let timeout_ns = (self.params.timeout_s * 1e9) as u64;
        let interval_ns = (self.params.interval_s * 1e9) as u64;
        let pings = &mut self.st.pings;
        if let Some(o) = pings.outstanding
            && t.saturating_sub(o.stamp_ns) >= timeout_ns
        {
            pings.outstanding = None;
            self.st.stats.timeouts += 1;
        }
        let due = pings.outstanding.is_none()
            && pings
                .last_ns
                .is_none_or(|l| t >= l.saturating_add(interval_ns));
        if !due {
            return;
        }
        let i = selection::next(
            self.params.selection,
            &self.site.layout,
            xy,
            p_xy,
            &mut pings.next_in_turn,
        );
        let id = self.site.layout.transponders()[i].id;
        let ping = SentPing {
            transponder_id: id,
            stamp_ns: t,
            answered: false,
        };
        pings.outstanding = Some(ping);
        pings.last_ns = Some(t);
        pings.recent.push(ping);
        self.forget_old_pings(t);
        self.st.stats.pings += 1;
        out.push(LblOutput::Ping(Ping {
            stamp_ns: t,
            transponder_id: id,
        }));
    }

    /// Pings older than the longest round trip are forgotten, and at most
    /// [`MAX_RECENT_PINGS`] kept.
    fn forget_old_pings(&mut self, now: u64) {
        let max_ta = self
            .site
            .layout
            .transponders()
            .iter()
            .map(|t| t.turnaround_s)
            .fold(0.0, f64::max);
        let keep_s = 2.0 * self.params.max_range_m / self.site.sound_speed_m_s + max_ta + 1.0;
        let keep_ns = (keep_s * 1e9) as u64;
        let recent = &mut self.st.pings.recent;
        recent.retain(|p| now.saturating_sub(p.stamp_ns) <= keep_ns);
        let excess = recent.len().saturating_sub(MAX_RECENT_PINGS);
        recent.drain(..excess);
    }

    fn nav(&self, t: u64, x: &[f64], p: &dyn Fn(usize, usize) -> f64) -> LblNav {
        LblNav {
            stamp_ns: t,
            x_m: x[0],
            y_m: x[1],
            current_m_s: [x[2], x[3]],
            p: std::array::from_fn(|i| std::array::from_fn(|j| p(i, j))),
            last_innovation_m: self.st.last.innovation_m,
            transponder_id: self.st.last.transponder_id,
            accepted: self.st.last.accepted,
            baseline_crossed: self.st.crossed,
        }
    }

    /// The state for a snapshot.
    pub fn state(&self) -> LblState {
        let mut s = self.st.clone();
        if let Some((x, p)) = self.estimate() {
            s.x = x;
            s.p = p;
        }
        s
    }
}

impl Estimator for Lbl {
    type Input = LblInput;
    type Output = LblOutput;
    type Snapshot = LblSaved;

    fn on_input(
        &mut self,
        input: &LblInput,
        out: &mut Vec<LblOutput>,
    ) -> Result<(), EstimatorError> {
        let stamp = input.stamp_ns();
        if self.resume_after.is_some_and(|r| stamp <= r) {
            return Ok(());
        }
        self.advance(stamp, out);
        match input {
            LblInput::Ahrs(a) => self.on_ahrs(a),
            LblInput::Depth(d) => self.on_depth(d),
            LblInput::Propeller(p) => self.on_propeller(p),
            LblInput::Dvl(d) => self.on_dvl(d),
            LblInput::Reply(r) => return self.on_reply(r),
            LblInput::Gps(g) => return self.on_gps(g),
        }
        Ok(())
    }

    fn snapshot(&self) -> Option<LblSaved> {
        self.st
            .next_step_ns
            .map(|_| LblSaved::State(Box::new(self.state())))
    }

    fn restore(&mut self, saved: &LblSaved, stamp_ns: u64) -> Result<(), EstimatorError> {
        let s = match saved {
            LblSaved::State(s) => s,
            LblSaved::Unreadable(why) => {
                return Err(refuse(
                    "snapshot",
                    format!("an unreadable LBL snapshot: {why}"),
                ));
            }
        };
        if !s.is_valid() {
            return Err(refuse(
                "snapshot",
                "an LBL snapshot with a non-finite or impossible value",
            ));
        }
        let n = s.x.len();
        if n != 0 && n != self.dimension() {
            return Err(refuse(
                "snapshot",
                format!(
                    "an LBL snapshot of {n} states for a filter of {}",
                    self.dimension()
                ),
            ));
        }
        let filter = match n {
            0 => None,
            4 => Some(Filter::Four(Kf {
                x: SVector::from_column_slice(&s.x),
                p: SMatrix::from_row_slice(&s.p),
            })),
            _ => Some(Filter::Five(Kf {
                x: SVector::from_column_slice(&s.x),
                p: SMatrix::from_row_slice(&s.p),
            })),
        };
        let valid = match &filter {
            Some(Filter::Four(k)) => k.is_valid(),
            Some(Filter::Five(k)) => k.is_valid(),
            None => true,
        };
        if !valid {
            return Err(refuse(
                "snapshot",
                "an LBL snapshot whose covariance is not one",
            ));
        }
        self.filter = filter;
        self.st = (**s).clone();
        self.st.x.clear();
        self.st.p.clear();
        self.resume_after = Some(stamp_ns);
        Ok(())
    }
}
