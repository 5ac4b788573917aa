//! The golden fixture of the smoother test (`tests/tests/smoother.rs`): a
//! linear version of the LBL filter's problem (paper 004 eqs. 1-4, state
//! `[x, y, w_x, w_y]`, 10 Hz), generated from a seed, that both nauta's
//! smoother and an independent one (pykalman, `tests/py/rts_smoother.py`)
//! smooth.
//!
//! The vehicle runs a lawnmower at 1.2 m/s in a 0.2 m/s current: the
//! transitions are paper 004's `φ_i`, `b_i` (the dead-reckoned velocity,
//! which turns) and `Q_i` (larger in the turns, Q "possibly time varying");
//! every 2 s a range to one of two transponders, linearised about the truth
//! (`z = u·p + v`, `u` the unit vector from the transponder), and none in a
//! 60 s blackout, so both dense and scarce corrections are smoothed.

use nalgebra::{Matrix4, SMatrix, Vector4};
use nauta_estimation::smoother::Discretised;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde_json::{Value, json};

/// One transition into step `i` and step `i`'s measurement, if any.
#[derive(Debug, Clone)]
pub struct FixtureStep {
    /// `φ_{i-1}`, `b_{i-1}`, `Q_{i-1}` (unused at step 0).
    pub model: Discretised<4>,
    /// `(H, z, R)`: one linearised range.
    pub measurement: Option<(SMatrix<f64, 1, 4>, f64, f64)>,
}

/// The fixture: the initial state and covariance, and the steps.
#[derive(Debug, Clone)]
pub struct Fixture {
    /// Step length, s.
    pub dt_s: f64,
    /// `E₀`.
    pub x0: Vector4<f64>,
    /// `P₀`.
    pub p0: Matrix4<f64>,
    /// Steps 0..n.
    pub steps: Vec<FixtureStep>,
}

fn matrix_json<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> Value {
    json!(
        m.row_iter()
            .map(|r| r.iter().copied().collect::<Vec<_>>())
            .collect::<Vec<_>>()
    )
}

impl Fixture {
    /// `steps` steps after the first, from `seed`.
    pub fn generate(seed: u64, steps: usize) -> Self {
        let dt_s = 0.1;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let unit = Normal::new(0.0, 1.0).expect("unit normal");
        let mut a = Matrix4::zeros();
        a[(0, 2)] = 1.0;
        a[(1, 3)] = 1.0;
        let transponders = [[0.0, 0.0], [0.0, 600.0]];
        let range_sigma = 0.3;
        let current = [0.15, -0.13];
        let mut truth = [200.0, 100.0];
        let mut heading = 0.0f64;
        let x0 = Vector4::new(truth[0] + 3.0, truth[1] - 2.0, 0.0, 0.0);
        let p0 = Matrix4::from_diagonal(&Vector4::new(25.0, 25.0, 0.09, 0.09));
        let mut out = vec![FixtureStep {
            model: Discretised {
                phi: Matrix4::identity(),
                q: Matrix4::zeros(),
                b: Vector4::zeros(),
            },
            measurement: None,
        }];
        for i in 1..=steps {
            let t = i as f64 * dt_s;
            // 90 s legs joined by 15 s turns of 180°.
            let phase = t % 105.0;
            let turning = phase >= 90.0;
            if turning {
                heading += std::f64::consts::PI / 15.0 * dt_s;
            }
            let (s, c) = heading.sin_cos();
            let speed = 1.2;
            // Dead-reckoned velocity over the water, from the last instant.
            let (u, v) = (speed * c, speed * s);
            let growth = if turning { 4.0 } else { 1.0 };
            let qc =
                Matrix4::from_diagonal(&Vector4::new(0.02 * growth, 0.02 * growth, 1e-6, 1e-6));
            let model = Discretised::of(&a, &qc, &Vector4::new(u, v, 0.0, 0.0), dt_s)
                .expect("finite dynamics");
            truth[0] += (u + current[0]) * dt_s + 0.02 * unit.sample(&mut rng);
            truth[1] += (v + current[1]) * dt_s + 0.02 * unit.sample(&mut rng);
            let blackout = (300.0..360.0).contains(&t);
            let measurement = (i % 20 == 0 && !blackout).then(|| {
                let tp = transponders[(i / 20) % 2];
                let (dn, de) = (truth[0] - tp[0], truth[1] - tp[1]);
                let r = dn.hypot(de);
                let h = SMatrix::<f64, 1, 4>::new(dn / r, de / r, 0.0, 0.0);
                let z = (h * Vector4::new(truth[0], truth[1], 0.0, 0.0))[0]
                    + range_sigma * unit.sample(&mut rng);
                (h, z, range_sigma * range_sigma)
            });
            out.push(FixtureStep { model, measurement });
        }
        Self {
            dt_s,
            x0,
            p0,
            steps: out,
        }
    }

    /// The fixture as `tests/py/rts_smoother.py` reads it: `{"x0", "p0",
    /// "transitions": [{"phi", "b", "q"}] (into steps 1..n), "measurements":
    /// [{"h", "z", "r"} or null] (steps 0..n)}`.
    pub fn to_json(&self) -> Value {
        let transitions: Vec<Value> = self.steps[1..]
            .iter()
            .map(|s| {
                json!({"phi": matrix_json(&s.model.phi), "b": s.model.b.as_slice(),
                       "q": matrix_json(&s.model.q)})
            })
            .collect();
        let measurements: Vec<Value> = self
            .steps
            .iter()
            .map(|s| match &s.measurement {
                Some((h, z, r)) => json!({"h": matrix_json(h), "z": z, "r": r}),
                None => Value::Null,
            })
            .collect();
        json!({"dt_s": self.dt_s, "x0": self.x0.as_slice(), "p0": matrix_json(&self.p0),
               "transitions": transitions, "measurements": measurements})
    }
}
