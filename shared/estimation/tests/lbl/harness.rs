//! Drives the LBL role's estimator with the simulator's `lbl` scenario in
//! lock step with its transponders (`nauta_sim::lbl_inputs`), and scores
//! `lbl/nav` against the truth at each solution's stamp.
//!
//! The IMU and the truth run at 20 Hz (the LBL role takes none of the IMU,
//! and its sensors, AHRS, depth and propeller at 10 Hz, draw the same
//! numbers at any IMU rate: each has its own random stream); the acoustic
//! reception is solved between steps to well under a millimetre either way.

use nauta_estimation::lbl::layout::Transponder;
use nauta_estimation::lbl::{Layout, Lbl, LblOutput, LblParams, LblSite, LblStats};
use nauta_estimation::readings::LblNav;
use nauta_sim::lbl_inputs::LblLoop;
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
use nauta_sim::suite::{LblLayout, SuiteConfig, TruthReading};

/// The shipped manifest's sound speed (`launch/lbl.toml`'s `[site]`): the
/// simulator's water (Mackenzie at 10 m, 15 °C, 35.5 psu) to 0.1 m/s.
pub const SOUND_SPEED_M_S: f64 = 1507.5;
/// The shipped manifest's declination, degrees.
pub const DECLINATION_DEG: f64 = -0.98;
/// The simulator's vehicle: m of advance per radian of the shaft.
pub const K_M_PER_RAD: f64 = 0.0105;

/// The shipped manifest's parameters (`launch/lbl.toml`).
pub fn params() -> LblParams {
    LblParams {
        propeller_m_per_rad: Some(K_M_PER_RAD),
        ..LblParams::default()
    }
}

/// The site of the simulator's lbl scenario with `transponders`.
pub fn site(transponders: Vec<Transponder>) -> LblSite {
    let o = Origin::lisbon();
    LblSite {
        origin_lat_rad: o.lat_rad,
        origin_lon_rad: o.lon_rad,
        declination_rad: DECLINATION_DEG.to_radians(),
        sound_speed_m_s: SOUND_SPEED_M_S,
        layout: Layout::new(transponders).expect("a layout"),
    }
}

/// The estimator with `params` on `layout`.
pub fn estimator(layout: LblLayout, params: &LblParams) -> Lbl {
    Lbl::new(params, site(layout.transponders())).expect("valid parameters")
}

/// The lbl scenario's run at `seed`, its sensors changed by `tweak`.
pub fn scenario(
    layout: LblLayout,
    seed: u64,
    duration_s: f64,
    tweak: impl FnOnce(&mut ScenarioParams, &mut SuiteConfig),
) -> Generator {
    let mut p = ScenarioParams {
        scenario: ScenarioKind::Lbl,
        lbl_layout: layout,
        imu_rate_hz: 20.0,
        ..Default::default()
    };
    let mut s = p.sensors_preset();
    tweak(&mut p, &mut s);
    Generator::new(&p, Origin::lisbon(), s, seed, duration_s).expect("valid scenario")
}

/// One solution and the truth at its stamp.
#[derive(Debug, Clone, Copy)]
pub struct Scored {
    pub nav: LblNav,
    /// North, east error, m.
    pub error_m: [f64; 2],
    /// The true current north, east, m/s.
    pub current_m_s: [f64; 2],
    /// True depth, m.
    pub depth_m: f64,
}

impl Scored {
    pub fn t_s(&self) -> f64 {
        self.nav.stamp_ns as f64 * 1e-9
    }

    pub fn horizontal_m(&self) -> f64 {
        self.error_m[0].hypot(self.error_m[1])
    }

    /// `‖e‖²_{P_xy⁻¹}` (χ², 2 degrees of freedom).
    pub fn mahalanobis2(&self) -> f64 {
        let p = &self.nav.p;
        let (a, b, d) = (p[0][0], p[0][1], p[1][1]);
        let det = a * d - b * b;
        let (x, y) = (self.error_m[0], self.error_m[1]);
        (d * x * x - 2.0 * b * x * y + a * y * y) / det
    }

    /// The semi-major axis of the 1σ ellipse, m.
    pub fn major_m(&self) -> f64 {
        nauta_estimation::lbl::ellipse::Ellipse::of([
            [self.nav.p[0][0], self.nav.p[0][1]],
            [self.nav.p[1][0], self.nav.p[1][1]],
        ])
        .major_m
    }
}

/// A reply and what the estimator did with it.
#[derive(Debug, Clone, Copy)]
pub struct ReplySeen {
    pub stamp_ns: u64,
    pub multipath: bool,
    /// Refused, and of which kind.
    pub refused: Option<&'static str>,
}

/// What a run gave.
#[derive(Debug, Clone, Default)]
pub struct Run {
    pub navs: Vec<Scored>,
    pub replies: Vec<ReplySeen>,
    /// Interrogations sent, with their stamps.
    pub pings: Vec<(u32, u64)>,
    pub stats: LblStats,
    /// Other inputs refused, by kind.
    pub refused: Vec<&'static str>,
}

impl Run {
    /// Solutions stamped in `[from_s, to_s)` while submerged.
    pub fn between(&self, from_s: f64, to_s: f64) -> impl Iterator<Item = &Scored> {
        self.navs
            .iter()
            .filter(move |s| s.t_s() >= from_s && s.t_s() < to_s && s.depth_m > 1.0)
    }

    /// Horizontal RMS in `[from_s, to_s)`, m.
    pub fn rms(&self, from_s: f64, to_s: f64) -> f64 {
        let (mut sq, mut n) = (0.0, 0.0);
        for s in self.between(from_s, to_s) {
            sq += s.horizontal_m().powi(2);
            n += 1.0;
        }
        (sq / n).sqrt()
    }

    /// Share of solutions with the truth inside the 95 % ellipse, %.
    pub fn inside_95_pct(&self, from_s: f64, to_s: f64) -> f64 {
        let (mut inside, mut n) = (0.0, 0.0);
        for s in self.between(from_s, to_s) {
            n += 1.0;
            if s.mahalanobis2() <= 5.991 {
                inside += 1.0;
            }
        }
        100.0 * inside / n
    }

    /// Median of `f` over the solutions in `[from_s, to_s)`.
    pub fn median(&self, from_s: f64, to_s: f64, f: impl Fn(&Scored) -> f64) -> f64 {
        let mut v: Vec<f64> = self.between(from_s, to_s).map(f).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    }

    /// RMS error of the current after `from_s`, m/s.
    pub fn current_rms(&self, from_s: f64) -> f64 {
        let (mut sq, mut n) = (0.0, 0.0);
        for s in self.between(from_s, f64::INFINITY) {
            sq += (s.nav.current_m_s[0] - s.current_m_s[0]).powi(2)
                + (s.nav.current_m_s[1] - s.current_m_s[1]).powi(2);
            n += 1.0;
        }
        (sq / n).sqrt()
    }

    /// (multipath replies, of them refused, direct replies, of them refused).
    pub fn multipath(&self) -> (usize, usize, usize, usize) {
        let refused = |r: &&&ReplySeen| r.refused == Some("gated");
        let mp: Vec<_> = self.replies.iter().filter(|r| r.multipath).collect();
        let direct: Vec<_> = self.replies.iter().filter(|r| !r.multipath).collect();
        (
            mp.len(),
            mp.iter().filter(refused).count(),
            direct.len(),
            direct.iter().filter(refused).count(),
        )
    }

    pub fn summary(&self) -> String {
        let end = self.navs.last().map_or(0.0, |s| s.t_s());
        let (mp, mp_refused, direct, direct_refused) = self.multipath();
        format!(
            "{} solutions, RMS {:.2} m, inside 95 % {:.1} %, major p50 {:.2} m, current RMS after 300 s {:.3} m/s, \
             multipath {mp_refused}/{mp} refused, direct {direct_refused}/{direct} refused, {:?}",
            self.navs.len(),
            self.rms(0.0, end + 1.0),
            self.inside_95_pct(0.0, end + 1.0),
            self.median(0.0, end + 1.0, Scored::major_m),
            self.current_rms(300.0),
            self.stats
        )
    }
}

fn local(t: &TruthReading) -> [f64; 2] {
    let (n, e) = Origin::lisbon().to_local(t.lat_rad, t.lon_rad);
    [n, e]
}

/// Runs `est` over `g` in lock step; `before` may replace the estimator
/// before each simulator step (given the step's stamp and whether it holds
/// a reply), for snapshots and restarts.
pub fn run_with(
    est: &mut Lbl,
    g: &mut Generator,
    mut before: impl FnMut(&mut Lbl, u64, bool),
) -> Run {
    let mut r = Run::default();
    let mut lp = LblLoop::new(10.0);
    while let Some((m, step)) = lp.step_with(g, est, &mut before) {
        for o in &step.outputs {
            match o {
                LblOutput::Nav(n) => {
                    // A solution is stamped with the step that made it.
                    if n.stamp_ns != m.stamp_ns {
                        continue;
                    }
                    let p = local(&m.truth);
                    r.navs.push(Scored {
                        nav: *n,
                        error_m: [n.x_m - p[0], n.y_m - p[1]],
                        current_m_s: [m.truth.current_ned_m_s[0], m.truth.current_ned_m_s[1]],
                        depth_m: m.truth.depth_m,
                    });
                }
                LblOutput::Ping(p) => r.pings.push((p.transponder_id, p.stamp_ns)),
            }
        }
        for (reply, res) in &step.replies {
            r.replies.push(ReplySeen {
                stamp_ns: reply.stamp_ns,
                multipath: reply.multipath,
                refused: res.as_ref().err().map(|e| e.kind),
            });
        }
        r.refused.extend(step.refused.iter().map(|e| e.kind));
    }
    r.stats = est.stats();
    r
}

/// Runs `est` over `g` in lock step.
pub fn run(est: &mut Lbl, g: &mut Generator) -> Run {
    run_with(est, g, |_, _, _| {})
}
