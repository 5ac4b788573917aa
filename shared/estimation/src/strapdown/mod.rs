//! Strapdown inertial navigation in the local navigation frame (NED) on the WGS84
//! ellipsoid: attitude, NED velocity, latitude, longitude and height from gyro and
//! accelerometer samples alone (no aiding; the aided INS puts its filters on top).
//!
//! Paper 000 §II-A (eqs. 1-4) does this on a sphere of radius `R_0`: specific force
//! into NED through the DCM, velocity from specific force minus gravity, Coriolis and
//! centripetal terms, position from `L̇ = v_N / (R_0 + h)`, `λ̇ = v_E sec L / (R_0 + h)`,
//! `ḣ = -v_D`. Its eq. 3 is unreadable in the extracted text; the form below is the
//! standard one of Titterton & Weston (2004) ch. 3 (§3.5.3, the local geographic
//! navigation frame mechanisation) and Groves (2013) §5.4 (local-navigation-frame
//! navigation equations: §5.4.1 attitude, §5.4.2 specific-force transformation,
//! §5.4.3 velocity, §5.4.4 position), on the ellipsoid instead of the sphere, with
//! the precision refinements of Groves §5.5 that matter at 100 Hz.
//!
//! # Continuous equations
//!
//! ```text
//! Ċ_b^n = C_b^n [ω_ib^b ×] - [ω_in^n ×] C_b^n,        ω_in^n = ω_ie^n + ω_en^n
//! v̇^n   = C_b^n f^b + g^n(L, h) - (2 ω_ie^n + ω_en^n) × v^n
//! L̇ = v_N / (R_N(L) + h),   λ̇ = v_E / ((R_E(L) + h) cos L),   ḣ = -v_D
//! ```
//!
//! with `R_N` the meridian and `R_E` the transverse radius of curvature
//! ([`crate::earth`] states which name is which), `ω_ie^n` the Earth rate and
//! `ω_en^n` the transport rate ([`crate::earth::earth_rate_ned`],
//! [`crate::earth::transport_rate_ned`]), and `g^n = [0, 0, γ(L, h)]` the WGS84
//! normal gravity ([`crate::earth::normal_gravity`]): gravitation plus the
//! centripetal acceleration of the Earth's rotation, so the centripetal term of
//! paper 000 eq. 3 is inside `g`, not added again.
//!
//! # The IMU sample
//!
//! A sample (DESIGN §4, `ImuSample`) reports over `(t - Δt, t]`
//! - `ω̄ = θ_ib / Δt`, the rotation vector of the body's rotation relative to
//!   inertial space over the interval, divided by `Δt` (the convention of
//!   [`crate::attitude::kinematics`]);
//! - `f̄ = (1/Δt) ∫ f^b dt`, the interval average of the specific force in body
//!   axes (what an integrating accelerometer reports; no sculling compensation).
//!
//! # Discrete update (one call of [`propagate`])
//!
//! Mid-interval quantities (subscript `m`) are predicted, then corrected once:
//! pass 1 takes the velocity as constant over the interval, pass 2 uses the
//! velocity from pass 1 (`v_m = (v₀ + v₁)/2`; the mid position moves by the mean
//! velocity of the first half, `(3v₀ + v₁)/4`, exact for a linear velocity).
//!
//! 1. Attitude (exact closed form, [`propagate_attitude`], (K1)):
//!    `q₁ = exp(-ω_in^n(m) Δt) ⊗ q₀ ⊗ exp(ω̄ Δt)`, and the mid-interval attitude
//!    `q_m` the same with `Δt/2`.
//! 2. Velocity (midpoint rule): `v₁ = v₀ + [C(q_m) f̄ + g(L_m, h_m) - (2ω_ie^n + ω_en^n)(m) × v_m] Δt`.
//!    Resolving `f̄` at the mid-interval attitude is the second-order form of
//!    Groves §5.5.2's specific-force frame transformation (it contains the half
//!    nav-frame rotation `-½ Ω_in^n C_b^n Δt` and the half body rotation). Left out:
//!    the second-order rotation terms (sculling, `(ω × ḟ) Δt²/12`, and the
//!    curvature of `C_b^n` over the interval, both of order `|ω|² |f| Δt²/12`).
//!    They rectify under an oscillating rotation: a ±2° roll with a 7 s period
//!    makes about 4e-8 m/s² along the vertical at 100 Hz, which is most of the
//!    4 mm height error measured over the 10-minute survey test.
//! 3. Position (trapezoidal): `h₁ = h₀ - ½(v_D₀ + v_D₁) Δt`, then
//!    `L₁ = L₀ + ½(v_N₀ + v_N₁) Δt / (R_N(L_m) + h_m)`,
//!    `λ₁ = λ₀ + ½(v_E₀ + v_E₁) Δt / ((R_E(L_m) + h_m) cos L_m)`, with `h_m`, `L_m`
//!    the means of old and new values (Groves §5.4.4, with the radii of curvature
//!    taken at mid-interval instead of at the start).
//!
//! The local truncation errors are third order in `Δt`; the test
//! `survey_leg_follows_the_truth` measures what they add up to over a 10-minute
//! survey leg against a truth built independently in ECEF.
//!
//! # Limits
//!
//! - Normal gravity only: no gravity anomaly or deflection of the vertical (real
//!   deflections, ~10″, are a 5e-4 m/s² horizontal error for any INS using a
//!   normal-gravity model), and the small north component that normal gravity has
//!   off the ellipsoid (≈ 8e-9 h sin 2L m/s², 2e-7 m/s² at 20 m depth) is neglected.
//! - The vertical channel is unstable, as in any free inertial navigator: a height
//!   error `δh` makes a gravity error `2γ/R δh` that increases it, with a time
//!   constant `√(R / 2γ)` ≈ 570 s. Over hours it must be aided (depth sensor); the
//!   aided INS does that.
//! - NED is singular at the poles (`tan L`, `sec L`): states beyond
//!   [`MAX_ABS_LATITUDE_RAD`] are refused.

use nalgebra::Vector3;

use crate::frames::{Frd, Ned, Rotation, Vector};
use thiserror::Error;

use crate::attitude::kinematics::propagate_attitude;
use crate::attitude::wrap_pi;
use crate::earth::{
    Geodetic, GeodeticNewError, earth_rate_ned, meridian_radius, normal_gravity,
    transport_rate_ned, transverse_radius,
};

#[cfg(test)]
mod refusal_tests;
#[cfg(test)]
mod tests;

/// Largest |latitude| the mechanization accepts, rad (89°): the NED frame and the
/// longitude rate are singular at the poles.
pub const MAX_ABS_LATITUDE_RAD: f64 = 89.0 * std::f64::consts::PI / 180.0;

/// Longest IMU interval accepted, s. The update is second order; beyond a second
/// a gap means lost samples, and the navigator should be told, not fed a guess.
pub const MAX_INTERVAL_S: f64 = 1.0;

/// Largest angular-rate magnitude accepted, rad/s (2000°/s, above the full scale
/// of any IMU an AUV carries; Xsens MTi-30: 450°/s).
pub const MAX_RATE_RAD_S: f64 = 2000.0 * std::f64::consts::PI / 180.0;

/// Largest specific-force magnitude accepted, m/s² (about 100 g; MTi-30: 20 g).
pub const MAX_SPECIFIC_FORCE_M_S2: f64 = 1000.0;

/// How far from 1 the norm of a state's quaternion may be.
pub const MAX_QUATERNION_NORM_ERROR: f64 = 1e-6;

/// The navigation state of a strapdown INS.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrapdownState {
    /// Attitude, body (FRD) → NED.
    pub q_nb: Rotation<Frd, Ned>,
    /// Velocity relative to the Earth, NED, m/s.
    pub v_ned_m_s: Vector<Ned>,
    /// Geodetic latitude (WGS84), rad.
    pub lat_rad: f64,
    /// Longitude, rad, kept in [-π, π).
    pub lon_rad: f64,
    /// Height above the WGS84 ellipsoid, m, positive up (`depth = -height`).
    pub height_m: f64,
}

impl StrapdownState {
    /// A state at `depth_m` below the ellipsoid (`height = -depth`).
    pub fn at_depth(
        q_nb: Rotation<Frd, Ned>,
        v_ned_m_s: Vector<Ned>,
        lat_rad: f64,
        lon_rad: f64,
        depth_m: f64,
    ) -> Self {
        Self {
            q_nb,
            v_ned_m_s,
            lat_rad,
            lon_rad,
            height_m: -depth_m,
        }
    }

    /// Depth below the ellipsoid, m (`-height`).
    pub fn depth_m(&self) -> f64 {
        -self.height_m
    }

    /// The position as a validated [`Geodetic`].
    pub fn geodetic(&self) -> Result<Geodetic, GeodeticNewError> {
        Geodetic::new(self.lat_rad, self.lon_rad, self.height_m)
    }

    /// Checks what the mechanization needs: every number finite, `q_nb` unit to
    /// [`MAX_QUATERNION_NORM_ERROR`], |latitude| ≤ [`MAX_ABS_LATITUDE_RAD`].
    pub fn validate(&self) -> Result<(), StrapdownError> {
        let finite = self.q_nb.as_nalgebra().coords.iter().all(|v| v.is_finite())
            && self.v_ned_m_s.iter().all(|v| v.is_finite())
            && self.lon_rad.is_finite()
            && self.height_m.is_finite();
        if !finite {
            return Err(StrapdownError::NonFiniteState);
        }
        let norm = self.q_nb.as_nalgebra().coords.norm();
        if !((norm - 1.0).abs() <= MAX_QUATERNION_NORM_ERROR) {
            return Err(StrapdownError::NotUnitQuaternion(norm));
        }
        if !(self.lat_rad.abs() <= MAX_ABS_LATITUDE_RAD) {
            return Err(StrapdownError::LatitudeOutOfRange(self.lat_rad));
        }
        Ok(())
    }
}

/// Why a state or an IMU sample was refused; the navigator's state is unchanged.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum StrapdownError {
    /// A number of the state is NaN or infinite.
    #[error("navigation state holds a non-finite number")]
    NonFiniteState,
    /// The attitude quaternion is not unit.
    #[error("attitude quaternion has norm {0}, not 1")]
    NotUnitQuaternion(f64),
    /// The latitude (given, or that the update would reach) is beyond
    /// ±[`MAX_ABS_LATITUDE_RAD`] or NaN.
    #[error("latitude {0} rad is beyond the mechanization's limit of ±89°")]
    LatitudeOutOfRange(f64),
    /// A gyro or accelerometer component is NaN or infinite.
    #[error("IMU sample is not finite")]
    NonFiniteSample,
    /// The angular rate exceeds [`MAX_RATE_RAD_S`] or the specific force
    /// [`MAX_SPECIFIC_FORCE_M_S2`].
    #[error("IMU sample out of range: |gyro| {rate_rad_s} rad/s, |accel| {accel_m_s2} m/s²")]
    SampleOutOfRange {
        /// Magnitude of the angular rate, rad/s.
        rate_rad_s: f64,
        /// Magnitude of the specific force, m/s².
        accel_m_s2: f64,
    },
    /// The interval is not a finite number of seconds in (0, [`MAX_INTERVAL_S`]].
    #[error("interval {0} s is not in (0, 1] s")]
    BadInterval(f64),
}

/// The outcome of one mechanization step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Propagated {
    /// The state at the end of the interval.
    pub state: StrapdownState,
    /// The interval's specific force resolved in NED at mid-interval,
    /// `C_b^n(q_m) f̄`, m/s² (what an error-state filter's transition matrix needs).
    pub specific_force_ned_m_s2: Vector<Ned>,
}

fn validate_sample(
    gyro_rad_s: &Vector3<f64>,
    accel_m_s2: &Vector3<f64>,
    dt_s: f64,
) -> Result<(), StrapdownError> {
    if !(gyro_rad_s.iter().all(|v| v.is_finite()) && accel_m_s2.iter().all(|v| v.is_finite())) {
        return Err(StrapdownError::NonFiniteSample);
    }
    if !(dt_s > 0.0 && dt_s <= MAX_INTERVAL_S) {
        return Err(StrapdownError::BadInterval(dt_s));
    }
    let (rate, accel) = (gyro_rad_s.norm(), accel_m_s2.norm());
    if !(rate <= MAX_RATE_RAD_S && accel <= MAX_SPECIFIC_FORCE_M_S2) {
        return Err(StrapdownError::SampleOutOfRange {
            rate_rad_s: rate,
            accel_m_s2: accel,
        });
    }
    Ok(())
}

/// One mechanization step (see the module documentation): the state at the end of
/// an interval of `dt_s` from the state `prev` at its start and the interval
/// averages `gyro_rad_s` (`ω_ib^b`, FRD) and `accel_m_s2` (specific force, FRD).
///
/// Pure; the inputs and the state are validated first, and a step that would
/// carry the latitude beyond [`MAX_ABS_LATITUDE_RAD`] is refused.
pub fn propagate(
    prev: &StrapdownState,
    gyro_rad_s: &Vector<Frd>,
    accel_m_s2: &Vector<Frd>,
    dt_s: f64,
) -> Result<Propagated, StrapdownError> {
    // The arithmetic is nalgebra's on the bare components, frames checked at
    // this boundary.
    let (gyro_rad_s, accel_m_s2) = (gyro_rad_s.as_nalgebra(), accel_m_s2.as_nalgebra());
    validate_sample(gyro_rad_s, accel_m_s2, dt_s)?;
    prev.validate()?;

    let q_nb0 = prev.q_nb.as_nalgebra();
    let (lat0, h0, v0) = (prev.lat_rad, prev.height_m, prev.v_ned_m_s.to_nalgebra());
    let r_n0 = meridian_radius(lat0) + h0;

    // Predictor-corrector on the mid-interval velocity and position.
    let mut v1 = v0;
    let mut f_n = Vector3::zeros();
    let mut omega_in_n = Vector3::zeros();
    for _pass in 0..2 {
        let v_m = 0.5 * (v0 + v1);
        // Mean velocity over the first half of the interval.
        let v_half = 0.75 * v0 + 0.25 * v1;
        let h_m = h0 - 0.5 * dt_s * v_half.z;
        let lat_m = lat0 + 0.5 * dt_s * v_half.x / r_n0;
        let omega_ie_n = earth_rate_ned(lat_m);
        let omega_en_n = transport_rate_ned(lat_m, h_m, &v_m);
        omega_in_n = omega_ie_n + omega_en_n;
        let q_m = propagate_attitude(q_nb0, gyro_rad_s, &omega_in_n, 0.5 * dt_s);
        f_n = q_m * accel_m_s2;
        let g_n = Vector3::new(0.0, 0.0, normal_gravity(lat_m, h_m));
        let coriolis = (2.0 * omega_ie_n + omega_en_n).cross(&v_m);
        v1 = v0 + (f_n + g_n - coriolis) * dt_s;
    }
    let q1 = propagate_attitude(q_nb0, gyro_rad_s, &omega_in_n, dt_s);

    // Trapezoidal position update, radii at mid-interval.
    let v_avg = 0.5 * (v0 + v1);
    let h1 = h0 - v_avg.z * dt_s;
    let h_m = 0.5 * (h0 + h1);
    let lat_m_pred = lat0 + 0.5 * dt_s * v_avg.x / r_n0;
    let lat1 = lat0 + v_avg.x * dt_s / (meridian_radius(lat_m_pred) + h_m);
    let lat_m = 0.5 * (lat0 + lat1);
    let lon1 = prev.lon_rad + v_avg.y * dt_s / ((transverse_radius(lat_m) + h_m) * lat_m.cos());

    let state = StrapdownState {
        q_nb: Rotation::from_nalgebra(q1),
        v_ned_m_s: Vector::from_nalgebra(v1),
        lat_rad: lat1,
        lon_rad: wrap_pi(lon1),
        height_m: h1,
    };
    state.validate()?;
    Ok(Propagated {
        state,
        specific_force_ned_m_s2: Vector::from_nalgebra(f_n),
    })
}

/// A free (unaided) strapdown inertial navigator: [`propagate`] applied sample by
/// sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Strapdown {
    state: StrapdownState,
    specific_force_ned_m_s2: Vector<Ned>,
    steps: u64,
    rejected: u64,
}

impl Strapdown {
    /// Starts from `state` (e.g. the alignment attitude, a GPS fix and zero
    /// velocity); refused if it does not pass [`StrapdownState::validate`].
    pub fn new(state: StrapdownState) -> Result<Self, StrapdownError> {
        state.validate()?;
        Ok(Self {
            state,
            specific_force_ned_m_s2: Vector::zeros(),
            steps: 0,
            rejected: 0,
        })
    }

    /// Integrates one IMU sample: `gyro_rad_s` and `accel_m_s2` are the averages
    /// over the `dt_s` seconds ending now (`ImuSample`: increment / dt, FRD).
    ///
    /// A refused sample (non-finite, out of range, bad interval, or a step past the
    /// latitude limit) leaves the state unchanged and is counted in
    /// [`Strapdown::rejected_count`].
    pub fn update(
        &mut self,
        gyro_rad_s: &Vector<Frd>,
        accel_m_s2: &Vector<Frd>,
        dt_s: f64,
    ) -> Result<(), StrapdownError> {
        match propagate(&self.state, gyro_rad_s, accel_m_s2, dt_s) {
            Ok(p) => {
                self.state = p.state;
                self.specific_force_ned_m_s2 = p.specific_force_ned_m_s2;
                self.steps += 1;
                Ok(())
            }
            Err(e) => {
                self.rejected += 1;
                Err(e)
            }
        }
    }

    /// The current state.
    pub fn state(&self) -> StrapdownState {
        self.state
    }

    /// Replaces the state (e.g. after an aiding correction); refused, with the
    /// state unchanged, if it does not pass [`StrapdownState::validate`].
    pub fn set_state(&mut self, state: StrapdownState) -> Result<(), StrapdownError> {
        state.validate()?;
        self.state = state;
        Ok(())
    }

    /// The last accepted sample's specific force in NED at mid-interval, m/s²
    /// (zero before the first).
    pub fn specific_force_ned_m_s2(&self) -> Vector<Ned> {
        self.specific_force_ned_m_s2
    }

    /// Samples integrated so far.
    pub fn step_count(&self) -> u64 {
        self.steps
    }

    /// Samples refused so far.
    pub fn rejected_count(&self) -> u64 {
        self.rejected
    }
}
