//! The truth generator: steps the vehicle (or a scripted attitude) and yields, at
//! the IMU rate, the true state and the exact noise-free IMU sample over the
//! interval that ended.
//!
//! # Internal integration
//!
//! Guidance and control run at the IMU rate (commands held over each interval);
//! the vehicle ([`crate::vehicle`]) is integrated with classical RK4 at
//! `imu_rate × substeps` (default 100 Hz × 10 = 1 kHz), latitude, longitude and
//! depth on the WGS84 ellipsoid.
//!
//! # The noise-free IMU sample (interval `(t₀, t₁]`, `Δt = t₁ - t₀`)
//!
//! The sample is built from the truth at the two ends of the interval so that
//! [`nauta_estimation::strapdown::propagate`] (read its module docs) started from
//! the truth at `t₀` returns the truth at `t₁`:
//!
//! 1. Mid-interval navigation quantities exactly as the mechanization's corrector
//!    pass forms them: `v_m = (v₀ + v₁)/2`, `v_h = (3v₀ + v₁)/4`,
//!    `h_m = h₀ - ½Δt v_h,D`, `L_m = L₀ + ½Δt v_h,N / (R_N(L₀) + h₀)`,
//!    `ω_in = ω_ie^n(L_m) + ω_en^n(L_m, h_m, v_m)`.
//! 2. Gyro (exact rule of [`nauta_estimation::attitude::kinematics`], (K2)):
//!    `ω_nb = body_rate_between(q₀, q₁, Δt)`, then
//!    `ω̄_ib = inertial_body_rate(q₀, ω_nb, ω_in, Δt)`; the mechanization's (K1)
//!    step with the same `ω_in` returns `q₁` to rounding.
//! 3. Accelerometer (inverse of the mechanization's midpoint velocity rule):
//!    `q_m = propagate_attitude(q₀, ω̄_ib, ω_in, Δt/2)`,
//!    `f̄ = C(q_m)ᵀ [(v₁ - v₀)/Δt - g(L_m, h_m) + (2ω_ie + ω_en) × v_m]`.
//! 4. Magnetometer: the instantaneous field at `t₁` in body axes,
//!    `m = C(q₁)ᵀ B^n` (tesla).
//!
//! What is left between mechanization and truth: the mechanization's first,
//! predictor pass uses `v₁ ≈ v₀` for its mid quantities, and its position step is
//! trapezoidal while the truth is integrated by RK4 (third-order local
//! differences, sub-millimetre over a survey leg, see the tests).
//!
//! Randomness: the seed draws the phase of the roll oscillation and a phase
//! offset of the current's slow variation; nothing else is random.

use nalgebra::{UnitQuaternion, Vector3};
use nauta_estimation::attitude::kinematics::{
    body_rate_between, inertial_body_rate, propagate_attitude,
};
use nauta_estimation::attitude::{from_euler, to_euler};
use nauta_estimation::earth::{
    earth_rate_ned, meridian_radius, normal_gravity, transport_rate_ned,
};
use nauta_estimation::frames::{Rotation, Vector};
use nauta_estimation::strapdown::StrapdownState;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::environment::Environment;
use crate::guidance::{Guidance, GuidanceParams, Phase};
use crate::mission::{AttitudeMission, Mission};
use crate::vehicle::{Commands, Vehicle, VehicleParams, VehicleState};

/// Simulator settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimConfig {
    /// IMU (output) rate, Hz (100 Hz, the MTi-30 class of DESIGN §10).
    pub imu_rate_hz: f64,
    /// RK4 steps per IMU interval (10: 1 kHz internal rate).
    pub substeps: usize,
    /// Seed of the run's random choices (roll and current phases).
    pub seed: u64,
    /// The vehicle.
    pub vehicle: VehicleParams,
    /// Guidance gains.
    pub guidance: GuidanceParams,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            imu_rate_hz: 100.0,
            substeps: 10,
            seed: 0,
            vehicle: VehicleParams::remus100(),
            guidance: GuidanceParams::default(),
        }
    }
}

/// The true state at one IMU epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Time since the start, s.
    pub t_s: f64,
    /// Geodetic latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad, in [-π, π).
    pub lon_rad: f64,
    /// Depth, m (height above the ellipsoid is `-depth`).
    pub depth_m: f64,
    /// North of the mission origin, m (flat mapping of [`crate::mission::Origin`]).
    pub north_m: f64,
    /// East of the mission origin, m.
    pub east_m: f64,
    /// Velocity over ground, NED, m/s.
    pub v_ned_m_s: Vector3<f64>,
    /// Attitude, body (FRD) → NED.
    pub q_nb: UnitQuaternion<f64>,
    /// Mean body rate relative to NED over the interval that ended here, FRD,
    /// rad/s (zero at the start).
    pub body_rate_nb_rad_s: Vector3<f64>,
    /// Water current, NED, m/s.
    pub current_ned_m_s: Vector3<f64>,
    /// Speed through the water (surge), m/s.
    pub speed_through_water_m_s: f64,
    /// Propeller shaft speed, rad/s ([`crate::vehicle::PROPELLER_ADVANCE_M_PER_RAD`]).
    pub propeller_rad_s: f64,
    /// Horizontal distance travelled over ground, m.
    pub distance_m: f64,
}

impl Truth {
    /// Height above the ellipsoid, m.
    pub fn height_m(&self) -> f64 {
        -self.depth_m
    }

    /// (roll, pitch, yaw), rad.
    pub fn euler_rad(&self) -> (f64, f64, f64) {
        to_euler(&self.q_nb)
    }

    /// The truth as a strapdown navigation state (e.g. to start an INS).
    pub fn strapdown_state(&self) -> StrapdownState {
        StrapdownState::at_depth(
            Rotation::from_nalgebra(self.q_nb),
            Vector::from_nalgebra(self.v_ned_m_s),
            self.lat_rad,
            self.lon_rad,
            self.depth_m,
        )
    }
}

/// A noise-free IMU sample: interval averages over `(t - dt, t]` (DESIGN §4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuSample {
    /// End of the interval, s.
    pub t_s: f64,
    /// Interval, s.
    pub dt_s: f64,
    /// Angular rate relative to inertial space, FRD, rad/s (`θ_ib / Δt`).
    pub gyro_rad_s: Vector3<f64>,
    /// Specific force, FRD, m/s².
    pub accel_m_s2: Vector3<f64>,
    /// Magnetic field at `t`, FRD, tesla.
    pub mag_t: Vector3<f64>,
}

/// The exact noise-free gyro and accelerometer over an interval from the truth
/// at its two ends (module docs, steps 1-3): `(gyro, accel)`.
pub fn exact_imu(prev: &Truth, next: &Truth, dt_s: f64) -> (Vector3<f64>, Vector3<f64>) {
    let (v0, v1) = (prev.v_ned_m_s, next.v_ned_m_s);
    let (lat0, h0) = (prev.lat_rad, prev.height_m());
    let v_m = 0.5 * (v0 + v1);
    let v_half = 0.75 * v0 + 0.25 * v1;
    let h_m = h0 - 0.5 * dt_s * v_half.z;
    let lat_m = lat0 + 0.5 * dt_s * v_half.x / (meridian_radius(lat0) + h0);
    let w_ie = earth_rate_ned(lat_m);
    let w_en = transport_rate_ned(lat_m, h_m, &v_m);
    let w_in = w_ie + w_en;
    let w_nb = body_rate_between(&prev.q_nb, &next.q_nb, dt_s);
    let gyro = inertial_body_rate(&prev.q_nb, &w_nb, &w_in, dt_s);
    let q_m = propagate_attitude(&prev.q_nb, &gyro, &w_in, 0.5 * dt_s);
    let g = Vector3::new(0.0, 0.0, normal_gravity(lat_m, h_m));
    let f_n = (v1 - v0) / dt_s - g + (2.0 * w_ie + w_en).cross(&v_m);
    (gyro, q_m.inverse_transform_vector(&f_n))
}

#[derive(Debug, Clone, PartialEq)]
enum Driver {
    Vehicle(Box<Guidance>),
    Attitude(AttitudeMission),
}

/// Why a simulator could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// IMU rate not positive and finite, or zero substeps.
    #[error("bad rate: imu_rate_hz {0}, substeps {1}")]
    BadRate(f64, usize),
    /// The environment's current is invalid.
    #[error(transparent)]
    Environment(#[from] crate::environment::EnvironmentError),
}

/// The truth generator (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Simulator {
    env: Environment,
    mission: Mission,
    vehicle: Vehicle,
    driver: Driver,
    state: VehicleState,
    config: SimConfig,
    k: u64,
    dt_s: f64,
    roll_phase_rad: f64,
    truth: Truth,
}

impl Simulator {
    /// A run of `mission` in `env`. Pure: the same arguments give the same run, bit
    /// for bit.
    pub fn new(mission: Mission, env: Environment, config: SimConfig) -> Result<Self, SimError> {
        if !(config.imu_rate_hz.is_finite() && config.imu_rate_hz > 0.0) || config.substeps == 0 {
            return Err(SimError::BadRate(config.imu_rate_hz, config.substeps));
        }
        env.current.validate()?;
        let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
        let roll_phase_rad = rng.random_range(0.0..std::f64::consts::TAU);
        let mut env = env;
        env.current.phase_rad += rng.random_range(0.0..std::f64::consts::TAU);
        let origin = mission.origin();
        let (driver, state) = match &mission {
            Mission::Waypoints(w) => (
                Driver::Vehicle(Box::new(Guidance::new(w.clone(), config.guidance))),
                VehicleState::at_rest(origin.lat_rad, origin.lon_rad, 0.0, w.start_yaw_rad),
            ),
            Mission::Attitude(a) => (
                Driver::Attitude(a.clone()),
                VehicleState::at_rest(origin.lat_rad, origin.lon_rad, a.depth_m, a.heading_rad),
            ),
        };
        let mut sim = Self {
            env,
            mission,
            vehicle: Vehicle::new(config.vehicle),
            driver,
            state,
            config,
            k: 0,
            dt_s: 1.0 / config.imu_rate_hz,
            roll_phase_rad,
            truth: Truth {
                t_s: 0.0,
                lat_rad: 0.0,
                lon_rad: 0.0,
                depth_m: 0.0,
                north_m: 0.0,
                east_m: 0.0,
                v_ned_m_s: Vector3::zeros(),
                q_nb: UnitQuaternion::identity(),
                body_rate_nb_rad_s: Vector3::zeros(),
                current_ned_m_s: Vector3::zeros(),
                speed_through_water_m_s: 0.0,
                propeller_rad_s: 0.0,
                distance_m: 0.0,
            },
        };
        sim.truth = sim.make_truth(0.0, Vector3::zeros());
        Ok(sim)
    }

    fn make_truth(&self, t_s: f64, body_rate: Vector3<f64>) -> Truth {
        let s = &self.state;
        let origin = self.mission.origin();
        let (north_m, east_m) = origin.to_local(s.lat_rad, s.lon_rad);
        let (q_nb, v, current) = match &self.driver {
            Driver::Vehicle(_) => {
                let current = self.env.current.at(t_s);
                let roll = self.roll_rad(t_s);
                (
                    s.attitude(roll),
                    self.vehicle.velocity_ned(s, &current),
                    current,
                )
            }
            Driver::Attitude(a) => {
                let (r, p, y) = a.motion.euler_at(t_s);
                (
                    from_euler(r, p, a.heading_rad + y),
                    Vector3::zeros(),
                    Vector3::zeros(),
                )
            }
        };
        Truth {
            t_s,
            lat_rad: s.lat_rad,
            lon_rad: nauta_estimation::attitude::wrap_pi(s.lon_rad),
            depth_m: s.depth_m,
            north_m,
            east_m,
            v_ned_m_s: v,
            q_nb,
            body_rate_nb_rad_s: body_rate,
            current_ned_m_s: current,
            speed_through_water_m_s: s.speed_m_s,
            propeller_rad_s: s.propeller_rad_s(),
            distance_m: s.distance_m,
        }
    }

    /// Rest at the surface before the route starts, s (waypoint missions).
    pub fn still_s(&self) -> f64 {
        match &self.mission {
            Mission::Waypoints(w) => w.still_s,
            Mission::Attitude(_) => 0.0,
        }
    }

    /// The vehicle's roll oscillation at `t_s`: zero while still, then
    /// [`VehicleParams::roll_rad`] of the time since the start, its amplitude
    /// ramped up over one period so that the attitude stays continuous.
    fn roll_rad(&self, t_s: f64) -> f64 {
        let p = &self.config.vehicle;
        let t = t_s - self.still_s();
        if t <= 0.0 {
            return 0.0;
        }
        (t / p.roll_period_s).min(1.0) * p.roll_rad(t, self.roll_phase_rad)
    }

    /// The truth now (at the last IMU epoch).
    pub fn truth(&self) -> &Truth {
        &self.truth
    }

    /// The vehicle's integrated state now.
    pub fn vehicle_state(&self) -> &VehicleState {
        &self.state
    }

    /// The environment (with the seeded current phase).
    pub fn environment(&self) -> &Environment {
        &self.env
    }

    /// The mission.
    pub fn mission(&self) -> &Mission {
        &self.mission
    }

    /// IMU interval, s.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// The guidance phase (`None` for an attitude mission).
    pub fn phase(&self) -> Option<Phase> {
        match &self.driver {
            Driver::Vehicle(g) => Some(g.phase()),
            Driver::Attitude(_) => None,
        }
    }

    /// Whether the mission is over: surfaced with the propeller stopped (speed
    /// below 1 cm/s), or an attitude script past its duration.
    pub fn finished(&self) -> bool {
        match &self.driver {
            Driver::Vehicle(g) => g.phase() == Phase::Done && self.state.speed_m_s < 0.01,
            Driver::Attitude(a) => self.truth.t_s >= a.duration_s,
        }
    }

    /// Advances one IMU interval: the truth at its end and the noise-free IMU
    /// sample over it.
    pub fn step(&mut self) -> (Truth, ImuSample) {
        let t0 = self.k as f64 * self.dt_s;
        let t1 = (self.k + 1) as f64 * self.dt_s;
        let still_s = self.still_s();
        if let Driver::Vehicle(g) = &mut self.driver {
            let tr = &self.truth;
            // Floating still (propeller stopped) until the route starts.
            let cmd = if t0 < still_s {
                Commands::default()
            } else {
                g.command(&self.state, tr.north_m, tr.east_m, &tr.current_ned_m_s)
            };
            let h = self.dt_s / self.config.substeps as f64;
            let current = self.env.current;
            for i in 0..self.config.substeps {
                let t = t0 + i as f64 * h;
                self.state = self
                    .vehicle
                    .rk4_step(&self.state, &cmd, t, h, |t| current.at(t));
            }
        }
        self.k += 1;
        let prev = self.truth;
        let mut next = self.make_truth(t1, Vector3::zeros());
        next.body_rate_nb_rad_s = body_rate_between(&prev.q_nb, &next.q_nb, self.dt_s);
        let (gyro, accel) = exact_imu(&prev, &next, self.dt_s);
        self.truth = next;
        let imu = ImuSample {
            t_s: t1,
            dt_s: self.dt_s,
            gyro_rad_s: gyro,
            accel_m_s2: accel,
            mag_t: next.q_nb.inverse_transform_vector(&self.env.magnetic.ned_t),
        };
        (next, imu)
    }
}

#[cfg(test)]
mod tests;
