//! nauta's simulator (pure, seeded, no IPC): vehicle, mission, environment and
//! sensor models (DESIGN §10). Every generator takes its own seeded random
//! generator, so a run repeats bit for bit and each sensor can run alone.
//!
//! - [`noise`]: the error processes sensors are built from (white noise, bias
//!   instability, random walks, scale factors, dropouts, spikes, outliers) and
//!   the statistics that check them (Allan deviation).

pub mod noise;
