//! `nauta import ...`: outside data sets as recordings, replayed through the
//! running pipeline (`nauta replay OUT.mcap --fast --record RUN.mcap`) and
//! evaluated (`nauta eval RUN.mcap`).
//!
//! - [`broad`]: BROAD IMU trials with their optical reference (attitude).
//! - [`akit`]: the Snapir AUV's A-KIT trajectories (DVL, reference INS, IMU).
//! - [`csv`]: any vehicle's log, one CSV file per channel, and a `site.toml`.

pub mod akit;
pub mod broad;
pub mod csv;

pub use broad::{ImportBroadArgs, ImportSite, broad, write_broad};
