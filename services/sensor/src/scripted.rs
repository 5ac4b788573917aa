//! A small scripted mission, pure and seeded: the first data source of the slice
//! (the full simulator replaces it). The vehicle floats still at the surface for
//! an alignment period, accelerates to its cruise speed, dives to the survey
//! depth and runs parallel transects joined by constant-rate turns, with a small
//! roll oscillation.
//!
//! The truth is generated on the WGS84 ellipsoid at the IMU rate. The IMU is
//! consistent with it: the gyro is the exact body rotation between consecutive
//! truth attitudes plus Earth and transport rate; the specific force is the
//! velocity change minus gravity plus the Coriolis terms (Titterton & Weston
//! 2004, eq. 3.71, written for specific force), both as interval averages.

use nalgebra::{UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::Deserialize;

use nauta_estimation::{attitude, earth};

/// Parameters of the scripted mission and its sensors (`[process.sensor.params]`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScriptParams {
    /// IMU and truth rate, Hz.
    pub imu_rate_hz: f64,
    /// Depth sensor rate, Hz (a divisor of the IMU rate).
    pub depth_rate_hz: f64,
    /// Still period at the start, for the attitude alignment, s.
    pub still_s: f64,
    /// Cruise speed through the water, m/s.
    pub speed_m_s: f64,
    /// Survey depth, m.
    pub depth_m: f64,
    /// Length of one transect, s.
    pub leg_s: f64,
    /// Turn rate between transects, deg/s.
    pub turn_rate_deg_s: f64,
    /// Initial heading, deg from true north.
    pub heading_deg: f64,
    /// Roll oscillation amplitude, deg.
    pub roll_amplitude_deg: f64,
    /// Roll oscillation period, s.
    pub roll_period_s: f64,
    /// Add sensor errors (false: the IMU and depth are exact).
    pub noise: bool,
    /// Gyro angle random walk, deg/s/√Hz (Xsens MTi-30 datasheet: 0.03).
    pub gyro_noise_deg_s_rthz: f64,
    /// Gyro turn-on bias, 1σ per axis, deg/h (MTi-30 in-run bias stability: 18).
    pub gyro_bias_deg_h: f64,
    /// Accelerometer noise density, µg/√Hz (MTi-30: 60).
    pub accel_noise_ug_rthz: f64,
    /// Magnetometer noise, µT 1σ (MTi-30: 0.5 mG = 0.05 µT).
    pub mag_noise_ut: f64,
    /// Depth noise, m 1σ (a 0.01 % FS 200 m pressure sensor: 0.02).
    pub depth_noise_m: f64,
    /// Earth field at the site, NED, µT (survey default: roughly Lisbon, 2026).
    pub mag_field_ned_ut: [f64; 3],
}

impl Default for ScriptParams {
    fn default() -> Self {
        ScriptParams {
            imu_rate_hz: 100.0,
            depth_rate_hz: 10.0,
            still_s: 5.0,
            speed_m_s: 1.5,
            depth_m: 15.0,
            leg_s: 120.0,
            turn_rate_deg_s: 3.0,
            heading_deg: 30.0,
            roll_amplitude_deg: 2.0,
            roll_period_s: 8.0,
            noise: true,
            gyro_noise_deg_s_rthz: 0.03,
            gyro_bias_deg_h: 18.0,
            accel_noise_ug_rthz: 60.0,
            mag_noise_ut: 0.05,
            depth_noise_m: 0.02,
            mag_field_ned_ut: [27.2, -0.9, 33.6],
        }
    }
}

impl ScriptParams {
    /// Checks the values (NaN fails every check).
    pub fn check(&self) -> anyhow::Result<()> {
        let positive = [
            ("imu_rate_hz", self.imu_rate_hz),
            ("depth_rate_hz", self.depth_rate_hz),
            ("leg_s", self.leg_s),
            ("turn_rate_deg_s", self.turn_rate_deg_s),
            ("roll_period_s", self.roll_period_s),
        ];
        for (k, v) in positive {
            anyhow::ensure!(
                v > 0.0 && v.is_finite(),
                "sensor params: {k} must be positive, got {v}"
            );
        }
        let non_negative = [
            ("still_s", self.still_s),
            ("speed_m_s", self.speed_m_s),
            ("depth_m", self.depth_m),
            ("roll_amplitude_deg", self.roll_amplitude_deg),
            ("gyro_noise_deg_s_rthz", self.gyro_noise_deg_s_rthz),
            ("gyro_bias_deg_h", self.gyro_bias_deg_h),
            ("accel_noise_ug_rthz", self.accel_noise_ug_rthz),
            ("mag_noise_ut", self.mag_noise_ut),
            ("depth_noise_m", self.depth_noise_m),
        ];
        for (k, v) in non_negative {
            anyhow::ensure!(
                v >= 0.0 && v.is_finite(),
                "sensor params: {k} must be >= 0, got {v}"
            );
        }
        anyhow::ensure!(
            self.heading_deg.is_finite(),
            "sensor params: heading_deg must be finite"
        );
        let ratio = self.imu_rate_hz / self.depth_rate_hz;
        anyhow::ensure!(
            (ratio - ratio.round()).abs() < 1e-9 && ratio >= 1.0,
            "sensor params: imu_rate_hz must be a multiple of depth_rate_hz"
        );
        Ok(())
    }
}

/// One step of the mission: the truth at the end of the interval and the IMU
/// sample over it.
#[derive(Debug, Clone, Copy)]
pub struct Step {
    /// End of the interval, ns since mission start.
    pub stamp_ns: u64,
    /// Interval length, s.
    pub dt_s: f64,
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Depth, m.
    pub depth_m: f64,
    /// Velocity NED, m/s.
    pub vel_ned: Vector3<f64>,
    /// Attitude body → NED.
    pub q_nb: UnitQuaternion<f64>,
    /// Angular rate of body w.r.t. NED over the interval, FRD, rad/s.
    pub rate_nb_body: Vector3<f64>,
    /// Distance travelled, m.
    pub distance_m: f64,
    /// Measured angular rate (with errors when enabled), FRD, rad/s.
    pub gyro: Vector3<f64>,
    /// Measured specific force, FRD, m/s².
    pub accel: Vector3<f64>,
    /// Measured magnetic field, FRD, µT.
    pub mag: Vector3<f64>,
    /// Measured depth, m (sampled only every depth interval by the caller).
    pub depth_measured_m: f64,
}

/// The scripted mission generator.
#[derive(Debug)]
pub struct Script {
    p: ScriptParams,
    k: u64,
    dt: f64,
    // Vehicle state.
    lat: f64,
    lon: f64,
    depth: f64,
    vel_ned: Vector3<f64>,
    q_nb: UnitQuaternion<f64>,
    yaw: f64,
    pitch: f64,
    speed: f64,
    distance: f64,
    // Sensor errors.
    rng: ChaCha8Rng,
    gyro_bias: Vector3<f64>,
    unit: Normal<f64>,
}

fn euler(roll: f64, pitch: f64, yaw: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(roll, pitch, yaw)
}

impl Script {
    /// A mission starting at the site's position at the surface.
    pub fn new(p: ScriptParams, lat_rad: f64, lon_rad: f64, seed: u64) -> anyhow::Result<Self> {
        p.check()?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let unit = Normal::new(0.0, 1.0)?;
        let bias_sigma = (p.gyro_bias_deg_h / 3600.0).to_radians();
        let gyro_bias = if p.noise {
            Vector3::from_fn(|_, _| bias_sigma * unit.sample(&mut rng))
        } else {
            Vector3::zeros()
        };
        let yaw = p.heading_deg.to_radians();
        Ok(Script {
            dt: 1.0 / p.imu_rate_hz,
            k: 0,
            lat: lat_rad,
            lon: lon_rad,
            depth: 0.0,
            vel_ned: Vector3::zeros(),
            q_nb: euler(0.0, 0.0, yaw),
            yaw,
            pitch: 0.0,
            speed: 0.0,
            distance: 0.0,
            rng,
            gyro_bias,
            unit,
            p,
        })
    }

    /// The IMU interval, s.
    pub fn dt_s(&self) -> f64 {
        self.dt
    }

    /// Every how many IMU samples a depth sample is due.
    pub fn depth_every(&self) -> u64 {
        (self.p.imu_rate_hz / self.p.depth_rate_hz).round() as u64
    }

    fn noise(&mut self, sigma: f64) -> f64 {
        if self.p.noise {
            sigma * self.unit.sample(&mut self.rng)
        } else {
            0.0
        }
    }

    /// Advances one IMU interval.
    pub fn step(&mut self) -> Step {
        let p = &self.p;
        let dt = self.dt;
        self.k += 1;
        let t = self.k as f64 * dt;
        let moving = t > p.still_s;
        let tm = (t - p.still_s).max(0.0);

        // Guidance: speed ramp, depth-keeping by pitch, transects and turns.
        let speed_cmd = if moving { p.speed_m_s } else { 0.0 };
        self.speed += (speed_cmd - self.speed).clamp(-0.2 * dt, 0.2 * dt);
        let pitch_cmd = if moving {
            // Nose down (negative pitch in FRD/NED) to go deeper.
            (-(p.depth_m - self.depth) * 0.02).clamp(-0.26, 0.26)
        } else {
            0.0
        };
        self.pitch += (pitch_cmd - self.pitch).clamp(-0.05 * dt, 0.05 * dt);
        let turn_s = std::f64::consts::PI / p.turn_rate_deg_s.to_radians();
        let cycle = p.leg_s + turn_s;
        let phase = tm % cycle;
        let turning = moving && phase > p.leg_s;
        if turning {
            let n = (tm / cycle).floor() as i64;
            let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
            self.yaw += sign * p.turn_rate_deg_s.to_radians() * dt;
        }
        let roll = if moving {
            p.roll_amplitude_deg.to_radians()
                * (2.0 * std::f64::consts::PI * tm / p.roll_period_s).sin()
        } else {
            0.0
        };

        let q_prev = self.q_nb;
        let q_next = euler(roll, self.pitch, self.yaw);
        // Exact body rotation over the interval: q_next = q_prev ⊗ exp(ω_nb dt).
        let rate_nb_body = attitude::kinematics::body_rate_between(&q_prev, &q_next, dt);

        // Kinematics on the ellipsoid (trapezoidal position update).
        let v_prev = self.vel_ned;
        let v_next = q_next * Vector3::new(self.speed, 0.0, 0.0);
        let v_mid = 0.5 * (v_prev + v_next);
        let h = -self.depth;
        let lat_mid = self.lat;
        let rn = earth::meridian_radius(lat_mid) + h;
        let re = earth::transverse_radius(lat_mid) + h;
        self.lat += v_mid.x / rn * dt;
        self.lon += v_mid.y / (re * lat_mid.cos()) * dt;
        self.depth = (self.depth + v_mid.z * dt).max(0.0);
        self.distance += v_mid.xy().norm() * dt;
        self.vel_ned = v_next;
        self.q_nb = q_next;

        // IMU consistent with the truth: the gyro sample that turns q_prev into q_next
        // while NED turns at ω_ie + ω_en (estimation::attitude::kinematics, (K2);
        // to first order ω_nb + C_bn (ω_ie + ω_en)); the specific force
        // f = C_bn (dv/dt - g + (2ω_ie + ω_en) × v) at mid-interval.
        let w_ie = earth::earth_rate_ned(lat_mid);
        let w_en = earth::transport_rate_ned(lat_mid, h, &v_mid);
        let gyro_true =
            attitude::kinematics::inertial_body_rate(&q_prev, &rate_nb_body, &(w_ie + w_en), dt);
        let q_mid = q_prev.slerp(&q_next, 0.5);
        let g = Vector3::new(0.0, 0.0, earth::normal_gravity(lat_mid, h));
        let f_ned = (v_next - v_prev) / dt - g + (2.0 * w_ie + w_en).cross(&v_mid);
        let accel_true = q_mid.inverse() * f_ned;
        let mag_true = q_next.inverse() * Vector3::from(p.mag_field_ned_ut);

        let gyro_sigma = p.gyro_noise_deg_s_rthz.to_radians() / dt.sqrt();
        let accel_sigma = p.accel_noise_ug_rthz * 1e-6 * 9.80665 / dt.sqrt();
        let (mag_sigma, depth_sigma) = (p.mag_noise_ut, p.depth_noise_m);
        let gyro = gyro_true
            + self.gyro_bias
            + Vector3::new(
                self.noise(gyro_sigma),
                self.noise(gyro_sigma),
                self.noise(gyro_sigma),
            );
        let accel = accel_true
            + Vector3::new(
                self.noise(accel_sigma),
                self.noise(accel_sigma),
                self.noise(accel_sigma),
            );
        let mag = mag_true
            + Vector3::new(
                self.noise(mag_sigma),
                self.noise(mag_sigma),
                self.noise(mag_sigma),
            );
        let depth_measured_m = self.depth + self.noise(depth_sigma);

        Step {
            stamp_ns: (self.k as u128 * 1_000_000_000u128 / self.p.imu_rate_hz.round() as u128)
                as u64,
            dt_s: dt,
            lat_rad: self.lat,
            lon_rad: self.lon,
            depth_m: self.depth,
            vel_ned: v_next,
            q_nb: q_next,
            rate_nb_body,
            distance_m: self.distance,
            gyro,
            accel,
            mag,
            depth_measured_m,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_for_a_seed() {
        let run = |seed| {
            let mut s = Script::new(ScriptParams::default(), 0.675, -0.159, seed).expect("params");
            (0..2000)
                .map(|_| s.step().gyro.x.to_bits())
                .collect::<Vec<_>>()
        };
        assert_eq!(run(7), run(7));
        assert_ne!(run(7), run(8));
    }

    #[test]
    fn still_then_dives_and_moves() {
        let mut s = Script::new(ScriptParams::default(), 0.675, -0.159, 1).expect("params");
        let first = s.step();
        assert!(
            (first.accel.z + 9.80).abs() < 0.05,
            "level and still: f ≈ -g, got {}",
            first.accel.z
        );
        let mut last = first;
        for _ in 0..(200 * 100) {
            last = s.step();
        }
        assert!(last.depth_m > 10.0, "dived to {}", last.depth_m);
        assert!(last.distance_m > 200.0, "moved {}", last.distance_m);
        assert!(
            ScriptParams {
                imu_rate_hz: f64::NAN,
                ..Default::default()
            }
            .check()
            .is_err()
        );
        assert!(
            ScriptParams {
                depth_rate_hz: 30.0,
                ..Default::default()
            }
            .check()
            .is_err()
        );
    }
}
