//! nauta's navigation math: pure functions and estimator cores with no IPC
//! (DESIGN §3). Services wrap these in ports, a clock and configuration; tests use
//! them in-process.
//!
//! Frames and conventions (DESIGN §4): navigation frame NED, body frame FRD,
//! attitude `q_nb` (Hamilton, `[w, x, y, z]`) rotating body vectors into NED,
//! geodetic latitude/longitude in radians on WGS84, heights positive up.
//!
//! - [`earth`]: WGS84 constants, radii of curvature, gravity, Earth and transport
//!   rates, geodetic ↔ ECEF.
//! - [`ains`]: the aided INS role's inputs and the aiding-mode bits of its
//!   output (`ains/nav`), the depth gauge's surface tare, and the `dr`
//!   variant (paper 002's dead reckoning with its DVL spike filter).
//! - [`attitude`]: quaternion and Euler conventions, rotation vectors, the exact
//!   attitude update and its sensor-side inverse, attitude error metrics.
//! - [`attitude_core`]: the attitude role's estimator (alignment, then the
//!   `pf`, `mekf` or `gyro` variant, magnetometer calibration applied first).
//! - [`role`]: the [`Estimator`] trait every role's estimator implements for
//!   the runtime's estimator shell.
//! - [`alignment`]: static coarse alignment from accelerometer and magnetometer.
//! - [`calibration`]: static gyro/accelerometer offsets and magnetometer hard-
//!   and soft-iron calibration (least-squares ellipsoid, particle swarm).
//! - [`frames`]: frames in types: `Vector<Frd>`, `Vector<Ned>`, `Rotation<Frd, Ned>`,
//!   and the one conversion between the wire's `[w, x, y, z]` and the quaternion.
//! - [`estimator`]: the [`AttitudeEstimator`] role trait and its snapshot.
//! - [`lbl`]: the LBL role's estimator (paper 003 §V's EKF of position and
//!   current from transponder ranges and propeller dead reckoning, its
//!   interrogation schedule, and the forward pass paper 004's smoother
//!   runs over).
//! - [`local`]: north/east/down about an origin: the exact local tangent plane
//!   (through ECEF) every tool uses, and paper 002 eq. 4's flat form.
//! - [`gyro`]: pure gyro integration, paper 000's baseline.
//! - [`mekf`]: multiplicative extended Kalman filter for attitude and gyro bias,
//!   aided by gravity and magnetic heading.
//! - [`pf`]: paper 000's attitude particle filter, with gyro bias estimation,
//!   disturbance rejection and initialisation from the first samples.
//! - [`positioning`]: the positioning role's estimator (paper 000 §III-B-2's
//!   buoy time-of-flight particle filter, and a range-only EKF).
//! - [`predictor`]: paper 002's error predictor (eqs. 14-17) as the
//!   covariance of the sensors' errors along the track: `predicted_drift_m`
//!   and the surfacing advisory.
//! - [`readings`]: the checked domain values sensors and estimators report
//!   (built from wire messages by `nauta_messages::checked`).
//! - [`smoother`]: paper 004's fixed-interval RTS smoother (eqs. 7-9) over
//!   the steps of a forward Kalman pass ([`smoother::ForwardStep`]).
//! - [`strapdown`]: free strapdown inertial navigation on the WGS84 ellipsoid.
//!
//! Equations name the paper (`../shared/papers/`, by number) or the textbook
//! (Titterton & Weston 2004; Groves 2013; Farrell 2008) they implement.

#![forbid(unsafe_code)]

pub mod ains;
pub mod alignment;
pub mod attitude;
pub mod attitude_core;
pub mod calibration;
pub mod earth;
pub mod estimator;
pub mod frames;
pub mod gyro;
pub mod lbl;
pub mod local;
pub mod magnetic;
pub mod mekf;
pub mod params;
pub mod pf;
pub mod positioning;
pub mod predictor;
pub mod readings;
pub mod role;
pub mod smoother;
pub mod strapdown;

pub use alignment::Alignment;
pub use attitude::{AttitudeError, HeadingInclinationError};
pub use estimator::{AttitudeEstimator, AttitudeOutput, AttitudeStateSnapshot};
pub use frames::{Frd, Ned, Rotation, Vector};
pub use gyro::{GyroIntegrator, GyroState};
pub use mekf::{MagneticReference, Mekf, MekfConfig, MekfParams};
pub use pf::{ParticleFilter, PfConfig, PfParams};
pub use role::{Estimator, EstimatorError, Stamped};
pub use strapdown::{Strapdown, StrapdownError, StrapdownState};
