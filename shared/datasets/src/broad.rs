//! BROAD trials (Laidig et al. 2021, doi:10.3390/data6070072; CC BY 4.0) as
//! converted in `shared/data/broad/`: one gzip-compressed (or plain) CSV per
//! trial, one row per sample at 285.714 Hz (`1 / 0.0035 s`), columns
//!
//! ```text
//! t_s, gyr_x_rad_s, gyr_y_rad_s, gyr_z_rad_s, acc_x_m_s2, acc_y_m_s2, acc_z_m_s2,
//! mag_x_uT, mag_y_uT, mag_z_uT, ref_qw, ref_qx, ref_qy, ref_qz, moving
//! ```
//!
//! The IMU data are in the IMU's own frame; the reference is the optical
//! (OMC) orientation of the IMU frame with respect to an ENU Earth frame
//! (x east, y north, z up), NaN while the markers were occluded; `moving` marks
//! the samples the published metric uses.
//!
//! # nauta's NED attitude in BROAD's ENU convention
//!
//! nauta's estimators give `q_nb`, body → NED. Fed BROAD's IMU samples as
//! they are, their "body" is the IMU frame (any right-handed frame will do:
//! the estimators never assume which way a body axis points), and the
//! specific force and field keep their meaning (at rest the accelerometer
//! reads +g along the axis that points up, as nauta's specific force does).
//! Only the Earth frame differs. A vector's NED coordinates `(n, e, d)` are
//! ENU coordinates `(e, n, −d)`:
//!
//! ```text
//! v_enu = M v_ned,   M = [0 1 0; 1 0 0; 0 0 −1]   (det M = +1)
//! ```
//!
//! `M = 2 a aᵀ − I` with `a = (1, 1, 0)/√2`: the rotation of 180° about the
//! horizontal axis halfway between north and east, quaternion
//! `q_enu_ned = [0, 1/√2, 1/√2, 0]`. So the estimate in BROAD's convention is
//!
//! ```text
//! q_enu_imu = q_enu_ned ⊗ q_ned_imu                                      (B1)
//! ```
//!
//! ([`enu_from_ned`]), and the reference in nauta's is
//! `q_ned_imu = q_enu_ned⁻¹ ⊗ q_enu_imu` ([`ned_from_enu`]; the rotation is its
//! own inverse). A heading error (about NED down) becomes one of the same size
//! about ENU up, so BROAD's heading and inclination errors are the same
//! computed in either frame (tested below).
//!
//! "North" is whatever north the reference's Earth frame uses: see
//! `shared/bench/src/attitude.rs` for how the benchmark sets the declination.

use nauta_estimation::frames::{Frd, Ned, Rotation};
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use thiserror::Error;

/// BROAD's sampling period, s (285.714 Hz).
pub const SAMPLE_PERIOD_S: f64 = 0.0035;

/// The header every trial file starts with.
pub const HEADER: [&str; 15] = [
    "t_s",
    "gyr_x_rad_s",
    "gyr_y_rad_s",
    "gyr_z_rad_s",
    "acc_x_m_s2",
    "acc_y_m_s2",
    "acc_z_m_s2",
    "mag_x_uT",
    "mag_y_uT",
    "mag_z_uT",
    "ref_qw",
    "ref_qx",
    "ref_qy",
    "ref_qz",
    "moving",
];

/// `q_enu_ned`: NED → ENU, 180° about `(1, 1, 0)/√2` (module docs, (B1)).
pub fn q_enu_ned() -> UnitQuaternion<f64> {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    UnitQuaternion::new_unchecked(Quaternion::new(0.0, h, h, 0.0))
}

/// (B1): an attitude body → NED as body → ENU, `q_enu_ned ⊗ q_ned_b`.
pub fn enu_from_ned(q_ned_b: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    q_enu_ned() * q_ned_b
}

/// The inverse of (B1): body → ENU as body → NED, `q_enu_ned⁻¹ ⊗ q_enu_b`.
pub fn ned_from_enu(q_enu_b: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
    q_enu_ned().inverse() * q_enu_b
}

/// One sample of a trial.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BroadSample {
    /// Time since the first sample, s.
    pub t_s: f64,
    /// Angular rate, IMU frame, rad/s.
    pub gyro_rad_s: Vector3<f64>,
    /// Specific force, IMU frame, m/s².
    pub accel_m_s2: Vector3<f64>,
    /// Magnetic field, IMU frame, µT.
    pub mag_ut: Vector3<f64>,
    /// Reference orientation IMU → ENU, or `None` while the markers were
    /// occluded (NaN in the file).
    pub reference_enu: Option<UnitQuaternion<f64>>,
    /// Part of the movement phase (the samples the BROAD metric uses).
    pub moving: bool,
}

/// A trial: its name (the file name up to its first dot) and samples.
#[derive(Debug, Clone, PartialEq)]
pub struct BroadTrial {
    /// E.g. `01_undisturbed_slow_rotation_A`.
    pub name: String,
    /// The samples in file order.
    pub samples: Vec<BroadSample>,
}

/// Why a trial could not be read.
#[derive(Debug, Error)]
pub enum BroadReadError {
    /// The file could not be opened or read (or its gzip stream is corrupt).
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The first line is not [`HEADER`].
    #[error("{path}: header is not the BROAD CSV header: {found:?}")]
    Header {
        /// The file.
        path: PathBuf,
        /// The first line as found.
        found: String,
    },
    /// A row is malformed.
    #[error("{path}:{line}: {message}")]
    Row {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The file has a header but no samples.
    #[error("{path}: no samples")]
    Empty {
        /// The file.
        path: PathBuf,
    },
}

/// The trial name of a file: its file name up to the first dot
/// (`01_undisturbed_slow_rotation_A.csv.gz` → `01_undisturbed_slow_rotation_A`).
pub fn trial_name(path: &Path) -> String {
    let file = path
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    match file.split_once('.') {
        Some((stem, _)) => stem.to_string(),
        None => file,
    }
}

/// True for a file name that ends in `.csv` or `.csv.gz`.
pub fn is_trial_file(path: &Path) -> bool {
    let name = path
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    name.ends_with(".csv") || name.ends_with(".csv.gz")
}

/// Every `.csv` and `.csv.gz` file directly in `dir`, sorted by name.
pub fn list_trials(dir: &Path) -> Result<Vec<PathBuf>, BroadReadError> {
    let io = |source| BroadReadError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        if path.is_file() && is_trial_file(&path) {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// Reads one trial file, gzip-decoded when its name ends in `.gz`.
pub fn read_trial(path: &Path) -> Result<BroadTrial, BroadReadError> {
    let file = File::open(path).map_err(|source| BroadReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let reader: Box<dyn Read> = if path.extension().is_some_and(|e| e == "gz") {
        Box::new(flate2::read::GzDecoder::new(file))
    } else {
        Box::new(file)
    };
    parse_trial(path, &trial_name(path), BufReader::new(reader))
}

/// Parses a trial from `reader` (the CSV text); `path` only names it in errors.
pub fn parse_trial<R: BufRead>(
    path: &Path,
    name: &str,
    reader: R,
) -> Result<BroadTrial, BroadReadError> {
    let mut lines = reader.lines();
    let io = |source| BroadReadError::Io {
        path: path.to_path_buf(),
        source,
    };
    let header = match lines.next() {
        Some(line) => line.map_err(io)?,
        None => String::new(),
    };
    let columns: Vec<&str> = header.trim_end().split(',').map(str::trim).collect();
    if columns != HEADER {
        return Err(BroadReadError::Header {
            path: path.to_path_buf(),
            found: header,
        });
    }
    let mut samples = Vec::new();
    for (index, line) in lines.enumerate() {
        let line = line.map_err(io)?;
        let line_no = index + 2;
        if line.trim().is_empty() {
            continue;
        }
        let sample = parse_row(&line).map_err(|message| BroadReadError::Row {
            path: path.to_path_buf(),
            line: line_no,
            message,
        })?;
        samples.push(sample);
    }
    if samples.is_empty() {
        return Err(BroadReadError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(BroadTrial {
        name: name.to_string(),
        samples,
    })
}

/// One data row: 15 numbers; the IMU values must be finite, the reference is
/// four finite numbers of norm within 1e-3 of 1 or all NaN, `moving` is 0 or 1.
fn parse_row(line: &str) -> Result<BroadSample, String> {
    let mut v = [0.0f64; 15];
    let mut n = 0;
    for field in line.trim_end().split(',') {
        if n == v.len() {
            return Err(format!("more than {} columns", v.len()));
        }
        let field = field.trim();
        v[n] = field
            .parse::<f64>()
            .map_err(|e| format!("column {} ({field:?}): {e}", HEADER[n]))?;
        n += 1;
    }
    if n != v.len() {
        return Err(format!("{n} columns, expected {}", v.len()));
    }
    if let Some(i) = v[..10].iter().position(|x| !x.is_finite()) {
        return Err(format!("{} is not finite", HEADER[i]));
    }
    let q = [v[10], v[11], v[12], v[13]];
    let reference_enu = if q.iter().all(|x| x.is_nan()) {
        None
    } else if q.iter().all(|x| x.is_finite()) {
        // The order only: the reference is body → ENU, not a frame of `frames`.
        let q4 = Rotation::<Frd, Ned>::quaternion_from_wxyz(q);
        let norm = q4.norm();
        if !((norm - 1.0).abs() <= 1e-3) {
            return Err(format!("reference quaternion has norm {norm}"));
        }
        Some(UnitQuaternion::new_normalize(q4))
    } else {
        return Err("reference quaternion is partly NaN".into());
    };
    let moving = if v[14] == 0.0 {
        false
    } else if v[14] == 1.0 {
        true
    } else {
        return Err(format!("moving is {}, not 0 or 1", v[14]));
    };
    Ok(BroadSample {
        t_s: v[0],
        gyro_rad_s: Vector3::new(v[1], v[2], v[3]),
        accel_m_s2: Vector3::new(v[4], v[5], v[6]),
        mag_ut: Vector3::new(v[7], v[8], v[9]),
        reference_enu,
        moving,
    })
}

#[cfg(test)]
mod tests;
