//! nauta's simulator (pure, seeded, no IPC): vehicle, mission, environment and
//! sensor models (DESIGN §10). Every generator takes its own seeded random
//! generator, so a run repeats bit for bit and each sensor can run alone.
//!
//! - [`noise`]: the error processes sensors are built from (white noise, bias
//!   instability, random walks, scale factors, dropouts, spikes, outliers) and
//!   the statistics that check them (Allan deviation).
//! - [`environment`]: WGS84 gravity and Earth rate, the WMM magnetic field,
//!   sound speed (Mackenzie 1981) and the water current.
//! - [`vehicle`]: a REMUS-100 class AUV with first-order surge, yaw and pitch
//!   dynamics, buoyancy and propeller speed.
//! - [`mission`]: waypoint routes and attitude scripts, and the `survey`, `lbl`,
//!   `dr` and attitude scenario builders.
//! - [`guidance`]: line-of-sight path following with heading and depth control.
//! - [`trajectory`]: the truth generator and its exact noise-free IMU.
//! - [`scenario`]: scenario parameters (survey, lbl, dr, attitude motions) and
//!   the generator that steps the truth and the sensors together.
//! - [`suite`]: the seeded sensor suite that turns each truth step into the
//!   measurements due (IMU, AHRS, DVL, depth, GPS, propeller, buoy modem, LBL).
//! - [`ains_inputs`], [`lbl_inputs`]: a step's readings as an estimator's
//!   inputs, for running one in process (the LBL one in lock step with the
//!   transponders, as the sensor process keeps it).

pub mod ains_inputs;
pub mod environment;
pub mod guidance;
pub mod lbl_inputs;
pub mod manoeuvre;
pub mod mission;
pub mod noise;
pub mod params;
pub mod scenario;
pub mod suite;
pub mod trajectory;
pub mod vehicle;
pub mod wire;
