//! Drives the positioning role's estimator with the simulator's survey: the
//! depth gauge, the GPS and the buoy's messages as the sensor publishes them,
//! and in place of `ains/nav` the true velocity with a DVL-aided INS's
//! errors (a constant bias and white noise per axis, from their own seeded
//! stream), so that the fixes are scored against the truth without the
//! aided INS in the loop.

use nauta_estimation::Estimator;
use nauta_estimation::ains::AinsInput;
use nauta_estimation::earth::{meridian_radius, transverse_radius};
use nauta_estimation::frames::Vector;
use nauta_estimation::positioning::{Positioning, PositioningInput, PositioningStats, source};
use nauta_estimation::readings::{BuoyRangeReading, Fix, Nav};
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
use nauta_sim::suite::{Measurements, SuiteConfig, TruthReading};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// The navigation's velocity errors standing in for the aided INS's.
#[derive(Debug, Clone, Copy)]
pub struct NavErrors {
    /// Constant bias north, east, m/s.
    pub bias_m_s: [f64; 2],
    /// White noise per axis and solution, m/s.
    pub white_m_s: f64,
    /// Solutions per second.
    pub rate_hz: f64,
}

/// The aided INS `pf`'s own errors on the survey, seed 7, measured in the
/// complete system in process (`nauta-bench`'s `complete` runner): a mean
/// of 0.0002 / −0.0013 m/s north / east over the dive and 0.007 m/s RMS
/// (BENCHMARKS.md, "Acoustic positioning").
impl Default for NavErrors {
    fn default() -> Self {
        Self {
            bias_m_s: [0.0002, -0.0013],
            white_m_s: 0.007,
            rate_hz: 10.0,
        }
    }
}

/// A run's sensors: the survey's, changed by `tweak`.
pub fn survey(seed: u64, duration_s: f64, tweak: impl FnOnce(&mut SuiteConfig)) -> Generator {
    let p = ScenarioParams {
        scenario: ScenarioKind::Survey,
        ..Default::default()
    };
    let mut s = p.sensors_preset();
    tweak(&mut s);
    Generator::new(&p, Origin::lisbon(), s, seed, duration_s).expect("valid scenario")
}

/// One fix and the truth at its step.
#[derive(Debug, Clone, Copy)]
pub struct Scored {
    pub fix: Fix,
    /// North, east error, m.
    pub error_m: [f64; 2],
}

/// What a run gave.
#[derive(Debug, Clone, Default)]
pub struct Run {
    pub fixes: Vec<Scored>,
    pub stats: PositioningStats,
    /// Buoy messages whose measured range was more than 15 m longer than
    /// the truth (the simulator's multipath), and how many of them the
    /// estimator refused.
    pub outliers: u64,
    pub outliers_refused: u64,
    /// Every message received.
    pub messages: u64,
    /// The state at `snapshot_at_s`, if asked.
    pub snapshot: Option<(nauta_estimation::positioning::Saved, u64)>,
}

impl Run {
    /// Fixes of `src` stamped in `[from_s, to_s)`.
    pub fn of(&self, src: u32, from_s: f64, to_s: f64) -> impl Iterator<Item = &Scored> {
        self.fixes.iter().filter(move |s| {
            let t = s.fix.stamp_ns as f64 * 1e-9;
            s.fix.source == src && t >= from_s && t < to_s
        })
    }

    /// North and east RMS of the buoy fixes in `[from_s, to_s)`, m.
    pub fn rms(&self, from_s: f64, to_s: f64) -> [f64; 2] {
        let (mut sq, mut n) = ([0.0; 2], 0.0);
        for s in self.of(source::BUOY, from_s, to_s) {
            sq[0] += s.error_m[0].powi(2);
            sq[1] += s.error_m[1].powi(2);
            n += 1.0;
        }
        sq.map(|v| (v / n).sqrt())
    }

    /// Share of the buoy fixes with the truth inside the published 95 %
    /// region (χ², 2 degrees of freedom, with the correlation), %.
    pub fn inside_95_pct(&self) -> f64 {
        let (mut inside, mut n) = (0.0, 0.0);
        for s in self.of(source::BUOY, 0.0, f64::INFINITY) {
            let f = &s.fix;
            let (a, b, r) = (f.std_north_m, f.std_east_m, f.corr_ne);
            let (x, y) = (s.error_m[0] / a, s.error_m[1] / b);
            let m = (x * x - 2.0 * r * x * y + y * y) / (1.0 - r * r);
            n += 1.0;
            if m <= 5.991 {
                inside += 1.0;
            }
        }
        100.0 * inside / n
    }
}

fn error_m(f: &Fix, t: &TruthReading) -> [f64; 2] {
    [
        (f.lat_rad - t.lat_rad) * meridian_radius(t.lat_rad),
        (f.lon_rad - t.lon_rad) * transverse_radius(t.lat_rad) * t.lat_rad.cos(),
    ]
}

fn buoy(m: &Measurements) -> Option<BuoyRangeReading> {
    m.modem.as_ref().map(|r| BuoyRangeReading {
        stamp_ns: r.stamp_ns,
        buoy_lat_rad: r.buoy_lat_rad,
        buoy_lon_rad: r.buoy_lon_rad,
        buoy_depth_m: r.buoy_depth_m,
        time_of_flight_s: r.time_of_flight_s,
        sound_speed_m_s: r.sound_speed_m_s,
    })
}

/// The step's inputs in the service's order: navigation, depth, GPS, modem.
pub fn inputs(m: &Measurements, nav: Option<Nav>, out: &mut Vec<PositioningInput>) {
    out.extend(nav.map(PositioningInput::Nav));
    let mut aiding = Vec::new();
    nauta_sim::ains_inputs::aiding(m, false, &mut aiding);
    for a in aiding {
        match a {
            AinsInput::Depth(d) => out.push(PositioningInput::Depth(d)),
            AinsInput::Gps(g) => out.push(PositioningInput::Gps(g)),
            _ => {}
        }
    }
    out.extend(buoy(m).map(PositioningInput::Modem));
}

/// Runs `est` over `g` with navigation errors `e`; the state after the
/// step at `snapshot_at_s` is kept.
pub fn run(
    est: &mut Positioning,
    g: &mut Generator,
    e: NavErrors,
    snapshot_at_s: Option<f64>,
) -> Run {
    let mut rng = ChaCha8Rng::seed_from_u64(0x6e61_7675);
    let every = (100.0 / e.rate_hz).round().max(1.0) as u64;
    let mut r = Run::default();
    let mut inputs_buf = Vec::new();
    let mut out = Vec::new();
    let mut step = 0u64;
    while let Some(m) = g.step() {
        let m = m.expect("simulator step");
        let t = &m.truth;
        let nav = step.is_multiple_of(every).then(|| {
            let mut noise = || -> f64 { StandardNormal.sample(&mut rng) };
            let v = [
                t.vel_ned_m_s[0] + e.bias_m_s[0] + e.white_m_s * noise(),
                t.vel_ned_m_s[1] + e.bias_m_s[1] + e.white_m_s * noise(),
                t.vel_ned_m_s[2],
            ];
            Nav {
                stamp_ns: m.stamp_ns,
                lat_rad: t.lat_rad,
                lon_rad: t.lon_rad,
                depth_m: t.depth_m,
                vel_ned_m_s: Vector::from_array(v),
                attitude: None,
                pos_std_ned_m: Vector::from_array([3.0, 3.0, 0.1]),
                vel_std_ned_m_s: Vector::from_array([0.01; 3]),
                predicted_drift_m: 0.0,
                aiding_mode: 0,
                advisory: 0,
            }
        });
        step += 1;
        if let Some(b) = &m.modem {
            r.messages += 1;
            if b.time_of_flight_s * b.sound_speed_m_s > b.true_range_m + 15.0 {
                r.outliers += 1;
            }
        }
        inputs_buf.clear();
        inputs(&m, nav, &mut inputs_buf);
        for i in &inputs_buf {
            let refused = est.on_input(i, &mut out).is_err();
            if let (PositioningInput::Modem(b), true) = (i, refused) {
                let sim = m.modem.as_ref().expect("the step's message");
                if b.time_of_flight_s * b.sound_speed_m_s > sim.true_range_m + 15.0 {
                    r.outliers_refused += 1;
                }
            }
        }
        for f in out.drain(..) {
            r.fixes.push(Scored {
                fix: f,
                error_m: error_m(&f, t),
            });
        }
        if snapshot_at_s.is_some_and(|s| (m.stamp_ns as f64 * 1e-9 - s).abs() < 0.005) {
            r.snapshot = est.snapshot().map(|s| (s, m.stamp_ns));
        }
    }
    r.stats = est.stats();
    r
}
