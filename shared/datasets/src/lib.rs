//! Readers for recorded datasets that nauta's estimators are measured on. The
//! estimators themselves stay pure (`nauta-estimation` does no I/O); this crate
//! reads the files and turns them into checked values.
//!
//! - [`broad`]: the BROAD benchmark of inertial orientation estimation (Laidig,
//!   Caruso, Cereatti, Seel, "BROAD - A Benchmark for Robust Inertial
//!   Orientation Estimation", Data 6(7):72, 2021, doi:10.3390/data6070072; data
//!   CC BY 4.0), in the gzip-compressed CSV form of `shared/data/broad/`, and
//!   the conversion of nauta's NED attitude to BROAD's ENU convention.

#![forbid(unsafe_code)]

pub mod broad;
