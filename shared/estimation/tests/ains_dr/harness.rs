//! Drives the `dr` estimator with the simulator: the readings of each step
//! as [`AinsInput`]s (in the order the service declares its inputs: IMU,
//! DVL, depth, GPS, AHRS), optional injected DVL spikes, and the dive's
//! final error against the truth.

use nauta_estimation::Estimator;
use nauta_estimation::ains::AinsInput;
use nauta_estimation::ains::dr::{DeadReckoning, DrParams, DrStats, Site};
use nauta_estimation::frames::Vector;
use nauta_estimation::readings::{Dvl, Nav};
use nauta_sim::mission::Origin;
use nauta_sim::noise::DvlSpec;
use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
use nauta_sim::suite::{Measurements, SuiteConfig};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The `dr` scenario of paper 002's manoeuvre `m`, as shipped (100 Hz IMU
/// and truth).
pub fn dr_scenario(m: u8) -> ScenarioParams {
    ScenarioParams {
        scenario: ScenarioKind::Dr,
        dr_manoeuvre: m,
        ..Default::default()
    }
}

/// The IMU and truth rate of the statistical tests: `NAUTA_DR_IMU_RATE_HZ`,
/// else 20 Hz (with 10 substeps: a 5 ms integration step). The `dr`'s own
/// sensors (AHRS 10 Hz, DVL 5 Hz, GPS 1 Hz) draw the same numbers at any
/// rate (each sensor has its own random stream, drawn per sample), so the
/// realised errors are those of the shipped 100 Hz scenario up to the
/// truth's integration, at a fifth of the simulator's time.
pub fn test_rate_hz() -> f64 {
    std::env::var("NAUTA_DR_IMU_RATE_HZ")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20.0)
}

/// The simulator's declination at the scenario's origin (what a manifest
/// takes from the WMM) and the origin as the site.
pub fn site(g: &Generator) -> Site {
    let o = g.simulator().mission().origin();
    Site {
        lat_rad: o.lat_rad,
        lon_rad: o.lon_rad,
        declination_rad: g.suite().declination_rad(),
    }
}

/// One step's readings as inputs, appended to `out`.
pub fn inputs(m: &Measurements, out: &mut Vec<AinsInput>) {
    if let Some(r) = &m.imu {
        out.push(AinsInput::Imu(nauta_sim::ains_inputs::imu(r)));
    }
    nauta_sim::ains_inputs::aiding(m, false, out);
}

/// Adds paper 002 Fig. 5's spikes to locked DVL samples, drawn as the
/// simulator's DVL model draws them ([`DvlSpec`]: probability, magnitude,
/// surge fraction) but from a stream of their own, so that a run with
/// spikes differs from the one without only by its spikes.
pub struct Spiker {
    rng: ChaCha8Rng,
    spec: DvlSpec,
    /// Spikes added.
    pub count: u64,
}

impl Spiker {
    /// Spikes of the default [`DvlSpec`] for `seed`.
    pub fn new(seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(1000);
        Self {
            rng,
            spec: DvlSpec::default(),
            count: 0,
        }
    }

    /// The input with a spike, or as it is.
    pub fn apply(&mut self, input: &AinsInput) -> AinsInput {
        let AinsInput::Dvl(d) = input else {
            return *input;
        };
        if !d.bottom_lock || !(self.rng.random::<f64>() < self.spec.spike_probability) {
            return *input;
        }
        let axis = if self.rng.random::<f64>() < self.spec.spike_surge_fraction {
            0
        } else if self.rng.random::<f64>() < 0.5 {
            1
        } else {
            2
        };
        let [lo, hi] = self.spec.spike_magnitude;
        let a = lo + (hi - lo) * self.rng.random::<f64>();
        let sign = if self.rng.random::<f64>() < 0.5 {
            1.0
        } else {
            -1.0
        };
        let mut v = d.velocity_body_m_s.to_array();
        v[axis] += sign * a;
        self.count += 1;
        AinsInput::Dvl(Dvl {
            velocity_body_m_s: Vector::from_array(v),
            ..*d
        })
    }
}

/// A dive's end, seen by one estimator: its last solution before the first
/// GPS fix after the dive, and the truth then.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiveEnd {
    /// The solution.
    pub nav: Nav,
    /// Its north and east from the scenario's origin, m (exact plane).
    pub nav_ne_m: (f64, f64),
    /// The truth's, m.
    pub truth_ne_m: (f64, f64),
    /// Distance travelled since the last fix before the dive, m.
    pub distance_m: f64,
    /// The estimator's counters at the end of the run.
    pub stats: DrStats,
}

impl DiveEnd {
    /// The horizontal error, m.
    pub fn error_m(&self) -> f64 {
        (self.nav_ne_m.0 - self.truth_ne_m.0).hypot(self.nav_ne_m.1 - self.truth_ne_m.1)
    }
}

/// One estimator fed along a run, and what it saw of the dive.
pub struct Tracked {
    pub dr: DeadReckoning,
    last: Option<(Nav, (f64, f64))>,
    last_gps_ns: Option<u64>,
    gps_distance_m: f64,
    /// The first dive's end (a gap of more than 30 s between GPS fixes).
    pub dive_end: Option<DiveEnd>,
    out: Vec<Nav>,
}

impl Tracked {
    pub fn new(dr: DeadReckoning) -> Self {
        Self {
            dr,
            last: None,
            last_gps_ns: None,
            gps_distance_m: 0.0,
            dive_end: None,
            out: Vec::new(),
        }
    }

    /// Feeds one input of the step whose truth is `m`.
    pub fn feed(&mut self, input: &AinsInput, m: &Measurements, origin: &Origin) {
        if let AinsInput::Gps(g) = input {
            if let (Some(prev), Some((nav, truth_ne)), None) =
                (self.last_gps_ns, self.last, self.dive_end)
                && g.stamp_ns - prev > 30_000_000_000
            {
                self.dive_end = Some(DiveEnd {
                    nav,
                    nav_ne_m: origin.to_local(nav.lat_rad, nav.lon_rad),
                    truth_ne_m: truth_ne,
                    distance_m: m.truth.distance_m - self.gps_distance_m,
                    stats: DrStats::default(),
                });
            }
            self.last_gps_ns = Some(g.stamp_ns);
            self.gps_distance_m = m.truth.distance_m;
        }
        self.out.clear();
        // A spike or a gated fix is refused (counted by the service); any
        // other refusal of the simulator's input is a defect.
        if let Err(e) = self.dr.on_input(input, &mut self.out) {
            assert!(matches!(e.kind, "dvl-spike" | "gps-gated"), "{e}");
        }
        if let Some(n) = self.out.last() {
            let t = &m.truth;
            self.last = Some((*n, origin.to_local(t.lat_rad, t.lon_rad)));
        }
    }
}

/// Runs manoeuvre `m` with seed `seed` through one `dr` per entry of
/// `params` with the scenario's sensors; each one's dive end.
pub fn dive(m: u8, seed: u64, params: &[DrParams]) -> Vec<DiveEnd> {
    let scenario = ScenarioParams {
        imu_rate_hz: test_rate_hz(),
        ..dr_scenario(m)
    };
    let mut g = Generator::new(
        &scenario,
        Origin::lisbon(),
        scenario.sensors_preset(),
        seed,
        1e6,
    )
    .expect("valid scenario");
    let mut runs: Vec<Tracked> = params
        .iter()
        .map(|p| Tracked::new(DeadReckoning::new(p, site(&g)).expect("valid")))
        .collect();
    let origin = g.simulator().mission().origin();
    let mut buf = Vec::new();
    while let Some(s) = g.step() {
        let s = s.expect("valid step");
        buf.clear();
        inputs(&s, &mut buf);
        for i in &buf {
            for t in &mut runs {
                t.feed(i, &s, &origin);
            }
        }
    }
    runs.iter()
        .map(|t| DiveEnd {
            stats: t.dr.stats(),
            ..t.dive_end.expect("the run has a dive")
        })
        .collect()
}

/// The spike comparison on one seed of manoeuvre `m`: the same run without
/// spikes (the simulator's spike probability set to 0) and with injected
/// ones, each through a `dr` with and without the spike filter. Returns the
/// dive-end shifts `|p̂_spiky − p̂_clean|`, m, with and without the filter,
/// and the number of spikes.
pub fn spike_shift(m: u8, seed: u64) -> (f64, f64, u64) {
    let scenario = ScenarioParams {
        imu_rate_hz: test_rate_hz(),
        ..dr_scenario(m)
    };
    let mut sensors: SuiteConfig = scenario.sensors_preset();
    sensors.dvl.noise.spike_probability = 0.0;
    let mut g = Generator::new(&scenario, Origin::lisbon(), sensors, seed, 1e6).expect("valid");
    let origin = g.simulator().mission().origin();
    let filtered = DrParams::default();
    let unfiltered = DrParams {
        spike_filter: false,
        ..DrParams::default()
    };
    let make = |p: &DrParams| Tracked::new(DeadReckoning::new(p, site(&g)).expect("valid"));
    let mut runs = [
        make(&filtered),
        make(&filtered),
        make(&unfiltered),
        make(&unfiltered),
    ];
    let mut spiker = Spiker::new(seed);
    let mut buf = Vec::new();
    while let Some(s) = g.step() {
        let s = s.expect("valid step");
        buf.clear();
        inputs(&s, &mut buf);
        for i in &buf {
            let spiky = spiker.apply(i);
            runs[0].feed(i, &s, &origin);
            runs[1].feed(&spiky, &s, &origin);
            runs[2].feed(i, &s, &origin);
            runs[3].feed(&spiky, &s, &origin);
        }
    }
    let end = |k: usize| runs[k].dive_end.expect("a dive").nav_ne_m;
    let shift = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).hypot(a.1 - b.1);
    (shift(end(1), end(0)), shift(end(3), end(2)), spiker.count)
}
