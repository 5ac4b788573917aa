//! Errors of each estimate stream against the reference, sample by sample,
//! and the metrics of `nauta eval` over them.
//!
//! - Against the truth: each estimate is compared with the truth at its own
//!   stamp, interpolated between the two neighbouring truth samples (linear in
//!   position, depth, velocity and distance; slerp for the attitude).
//! - Against GPS: each fix is compared with the estimate at the fix's stamp,
//!   interpolated between the stream's two neighbouring samples. Only the
//!   horizontal position is compared (a surface GPS fix says nothing of the
//!   depth under water, the velocity or the attitude).

use nalgebra::{Matrix2, UnitQuaternion, Vector2, Vector3};
use nauta_estimation::AttitudeError;
use nauta_estimation::attitude::{rotation_vector, wrap_pi};
use nauta_estimation::earth::{meridian_radius, transverse_radius};
use nauta_log::run::GeoOrigin;
use nauta_messages::checked::Gps;
use serde::Serialize;

use super::data::{Data, EstimateSample, Horizontal, Stream, TruthSample};

/// 95% quantile of the chi-square distribution with 2 degrees of freedom
/// (`-2 ln 0.05`): a horizontal error `e` lies inside the 95% ellipse of its
/// covariance `C` when `eᵀ C⁻¹ e ≤` this.
pub const CHI2_2DOF_95: f64 = 5.991_464_547_107_979;
/// 95% quantile of the chi-square distribution with 3 degrees of freedom.
pub const CHI2_3DOF_95: f64 = 7.814_727_903_251_178;

/// Two neighbouring samples further apart than this are not interpolated
/// between (the reference has a hole there), s. Above 1 s: a 1 Hz reference
/// is interpolated between its samples (A-KIT's are 1.0025 s apart, and an
/// IMU-rate estimate falls between them).
pub const MAX_INTERPOLATION_GAP_S: f64 = 1.5;

/// What the estimates are compared with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Reference {
    /// `sim/truth`.
    Truth,
    /// `sensor/gps` surface fixes.
    Gps,
}

/// The error of one matched sample (estimate minus reference).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorSample {
    /// Stamp, ns (the estimate's against the truth, the fix's against GPS).
    pub stamp_ns: u64,
    /// North and east error, m.
    pub ne_m: Option<[f64; 2]>,
    /// Down error, m (estimated depth minus true depth).
    pub down_m: Option<f64>,
    /// Velocity error NED, m/s.
    pub vel_m_s: Option<[f64; 3]>,
    /// Attitude error (roll, pitch, yaw wrapped to ±180°).
    pub attitude: Option<AttitudeError>,
    /// Whether the error lies inside the 95% region of the published
    /// covariance (`None`: no covariance for this sample).
    pub inside_95: Option<bool>,
    /// Distance travelled at this sample, m (truth: its `distance_m`; GPS:
    /// along the estimated track from the first matched fix).
    pub distance_m: f64,
}

/// `nauta eval`'s metrics of one stream (JSON; keys that do not apply to the
/// stream are left out).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Metrics {
    /// Matched samples (estimates with a reference at their stamp, or GPS
    /// fixes with an estimate at theirs).
    pub samples: u64,
    /// Estimates (or fixes) without a reference (outside its span or across a
    /// hole).
    pub unmatched: u64,
    /// Messages of the stream that did not decode or failed their checks.
    pub rejected: u64,
    /// RMS north error, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub north_rms_m: Option<f64>,
    /// RMS east error, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub east_rms_m: Option<f64>,
    /// RMS down error, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub down_rms_m: Option<f64>,
    /// RMS horizontal error `√(mean(eN² + eE²))`, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub horizontal_rms_m: Option<f64>,
    /// Largest horizontal error, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub horizontal_max_m: Option<f64>,
    /// RMS north velocity error, m/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vel_north_rms_m_s: Option<f64>,
    /// RMS east velocity error, m/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vel_east_rms_m_s: Option<f64>,
    /// RMS down velocity error, m/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vel_down_rms_m_s: Option<f64>,
    /// RMS roll error, deg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub roll_rms_deg: Option<f64>,
    /// RMS pitch error, deg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch_rms_deg: Option<f64>,
    /// RMS yaw error (wrapped to ±180°), deg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub yaw_rms_deg: Option<f64>,
    /// Horizontal error of the last matched sample, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub final_error_m: Option<f64>,
    /// `final_error_m` in % of `distance_m` (paper 002's relative error).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub final_error_pct: Option<f64>,
    /// `final_error_m` per km of `distance_m`, m/km.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drift_m_per_km: Option<f64>,
    /// Distance travelled between the first and the last matched sample, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub distance_m: Option<f64>,
    /// Samples whose error lies inside the 95% region of the published
    /// covariance, % of `covariance_samples`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inside_95_pct: Option<f64>,
    /// Matched samples that carried a usable covariance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub covariance_samples: Option<u64>,
    /// Paper 002's dives (against the truth, between surface GPS fixes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dives: Option<Vec<super::dives::Dive>>,
    /// Mean over the dives of `error_pct`, %.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dive_error_pct: Option<f64>,
    /// Mean over the dives of the error per km travelled submerged, m/km.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dive_drift_m_per_km: Option<f64>,
    /// Paper 000's per-axis drift: slope of the north, east and down error
    /// against the distance travelled submerged, m/km.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drift_slope_m_per_km: Option<[f64; 3]>,
}

/// The frame a `lbl/nav`-like (local) stream is compared in.
#[derive(Debug, Clone, Copy)]
pub struct LocalFrame(pub GeoOrigin);

// ---------------------------------------------------------------------------
// Geometry
// ---------------------------------------------------------------------------

/// North and east offset of `(lat, lon)` from `(lat_r, lon_r)` at height `h`,
/// m: paper 002 eq. 2, `dN = (R_N + h) dL`, `dE = (R_E + h) cos L dλ`, with
/// the standard radii of curvature (meridian `R_N` with latitude, transverse
/// `R_E` with longitude; see `nauta_estimation::earth` for the paper's
/// swapped names), evaluated at the reference point. Exact to second order
/// in the offset, i.e. to well below a millimetre for errors of metres.
pub fn ne_offset(lat_rad: f64, lon_rad: f64, lat_r: f64, lon_r: f64, h_m: f64) -> [f64; 2] {
    [
        (lat_rad - lat_r) * (meridian_radius(lat_r) + h_m),
        wrap_pi(lon_rad - lon_r) * (transverse_radius(lat_r) + h_m) * lat_r.cos(),
    ]
}

/// Horizontal error of `est` against the reference point, m. A local (LBL)
/// position is compared in its own frame: the reference is mapped into it.
fn horizontal_error(
    est: Horizontal,
    lat_r: f64,
    lon_r: f64,
    h_r: f64,
    frame: Option<LocalFrame>,
) -> Option<[f64; 2]> {
    match est {
        Horizontal::Geodetic { lat_rad, lon_rad } => {
            Some(ne_offset(lat_rad, lon_rad, lat_r, lon_r, h_r))
        }
        Horizontal::Local { north_m, east_m } => {
            let (n, e) = frame?.0.to_local(lat_r, lon_r);
            Some([north_m - n, east_m - e])
        }
    }
}

/// Whether `e` lies inside the 95% ellipse of `cov` (chi-square, 2 dof).
pub fn inside_95_2d(e: [f64; 2], cov: &Matrix2<f64>) -> Option<bool> {
    let inv = cov.try_inverse()?;
    let v = Vector2::from(e);
    let d2 = (v.transpose() * inv * v)[(0, 0)];
    d2.is_finite().then_some(d2 <= CHI2_2DOF_95)
}

/// The 1σ semi-axes (major, minor) of the uncertainty ellipse of `cov`, m:
/// the square roots of the eigenvalues of `P_xy` (paper 003 §V-A; paper 004,
/// the axes of Figs. 6-8).
pub fn ellipse_axes(cov: &Matrix2<f64>) -> (f64, f64) {
    let (a, b, d) = (cov[(0, 0)], 0.5 * (cov[(0, 1)] + cov[(1, 0)]), cov[(1, 1)]);
    let mean = 0.5 * (a + d);
    let r = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    ((mean + r).max(0.0).sqrt(), (mean - r).max(0.0).sqrt())
}

/// The orientation of the major axis of `cov`'s ellipse, rad from north
/// towards east.
pub fn ellipse_orientation(cov: &Matrix2<f64>) -> f64 {
    let (a, b, d) = (cov[(0, 0)], 0.5 * (cov[(0, 1)] + cov[(1, 0)]), cov[(1, 1)]);
    0.5 * (2.0 * b).atan2(a - d)
}

// ---------------------------------------------------------------------------
// Interpolation
// ---------------------------------------------------------------------------

/// `q_a` towards `q_b` by `f` in [0, 1], the shorter way round: slerp
/// (Shoemake, SIGGRAPH 1985), or normalised linear interpolation where slerp
/// is ill-conditioned.
pub fn interpolate_attitude(
    a: &UnitQuaternion<f64>,
    b: &UnitQuaternion<f64>,
    f: f64,
) -> UnitQuaternion<f64> {
    let b = if a.coords.dot(&b.coords) < 0.0 {
        UnitQuaternion::new_unchecked(-b.into_inner())
    } else {
        *b
    };
    a.try_slerp(&b, f, 1e-12)
        .unwrap_or_else(|| UnitQuaternion::new_normalize(a.lerp(&b, f)))
}

/// Where `t` falls in `stamps`: `Exact(i)`, `Between(i, f)` (between `i` and
/// `i + 1`, fraction `f`), or `None` outside the span or across a gap longer
/// than [`MAX_INTERPOLATION_GAP_S`].
#[derive(Debug, Clone, Copy, PartialEq)]
enum Bracket {
    Exact(usize),
    Between(usize, f64),
}

fn bracket<T>(items: &[T], stamp: impl Fn(&T) -> u64, t: u64) -> Option<Bracket> {
    let i = items.partition_point(|x| stamp(x) < t);
    if i < items.len() && stamp(&items[i]) == t {
        return Some(Bracket::Exact(i));
    }
    if i == 0 || i == items.len() {
        return None;
    }
    let (t0, t1) = (stamp(&items[i - 1]), stamp(&items[i]));
    let gap = (t1 - t0) as f64 * 1e-9;
    (gap <= MAX_INTERPOLATION_GAP_S)
        .then(|| Bracket::Between(i - 1, (t - t0) as f64 / (t1 - t0) as f64))
}

fn lerp(a: f64, b: f64, f: f64) -> f64 {
    a + (b - a) * f
}

/// The truth at `t`.
pub fn truth_at(truth: &[TruthSample], t: u64) -> Option<TruthSample> {
    match bracket(truth, |s| s.stamp_ns, t)? {
        Bracket::Exact(i) => Some(truth[i]),
        Bracket::Between(i, f) => {
            let (a, b) = (&truth[i], &truth[i + 1]);
            Some(TruthSample {
                stamp_ns: t,
                lat_rad: lerp(a.lat_rad, b.lat_rad, f),
                lon_rad: wrap_pi(a.lon_rad + wrap_pi(b.lon_rad - a.lon_rad) * f),
                depth_m: lerp(a.depth_m, b.depth_m, f),
                vel_ned_m_s: a.vel_ned_m_s.lerp(&b.vel_ned_m_s, f),
                attitude: interpolate_attitude(&a.attitude, &b.attitude, f),
                distance_m: lerp(a.distance_m, b.distance_m, f),
            })
        }
    }
}

fn lerp_horizontal(a: Horizontal, b: Horizontal, f: f64) -> Option<Horizontal> {
    match (a, b) {
        (
            Horizontal::Geodetic { lat_rad, lon_rad },
            Horizontal::Geodetic {
                lat_rad: lat_b,
                lon_rad: lon_b,
            },
        ) => Some(Horizontal::Geodetic {
            lat_rad: lerp(lat_rad, lat_b, f),
            lon_rad: wrap_pi(lon_rad + wrap_pi(lon_b - lon_rad) * f),
        }),
        (
            Horizontal::Local { north_m, east_m },
            Horizontal::Local {
                north_m: n_b,
                east_m: e_b,
            },
        ) => Some(Horizontal::Local {
            north_m: lerp(north_m, n_b, f),
            east_m: lerp(east_m, e_b, f),
        }),
        _ => None,
    }
}

/// A stream's estimate at `t` (for the comparison with a GPS fix). A field is
/// interpolated when both neighbours have it.
pub fn estimate_at(samples: &[EstimateSample], t: u64) -> Option<EstimateSample> {
    match bracket(samples, |s| s.stamp_ns, t)? {
        Bracket::Exact(i) => Some(samples[i]),
        Bracket::Between(i, f) => {
            let (a, b) = (&samples[i], &samples[i + 1]);
            Some(EstimateSample {
                stamp_ns: t,
                pos: a.pos.zip(b.pos).and_then(|(x, y)| lerp_horizontal(x, y, f)),
                depth_m: a.depth_m.zip(b.depth_m).map(|(x, y)| lerp(x, y, f)),
                vel_ned_m_s: a.vel_ned_m_s.zip(b.vel_ned_m_s).map(|(x, y)| x.lerp(&y, f)),
                attitude: a
                    .attitude
                    .zip(b.attitude)
                    .map(|(x, y)| interpolate_attitude(&x, &y, f)),
                cov_ne_m2: a.cov_ne_m2.zip(b.cov_ne_m2).map(|(x, y)| x + (y - x) * f),
                att_std_rad: a.att_std_rad.zip(b.att_std_rad).map(|(x, y)| x.lerp(&y, f)),
                innovation: a.innovation,
                predicted_drift_m: a
                    .predicted_drift_m
                    .zip(b.predicted_drift_m)
                    .map(|(x, y)| lerp(x, y, f)),
            })
        }
    }
}

// ---------------------------------------------------------------------------
// Errors
// ---------------------------------------------------------------------------

/// The errors of `stream` against the truth, and how many estimates had none.
pub fn errors_against_truth(
    stream: &Stream,
    truth: &[TruthSample],
    frame: Option<LocalFrame>,
) -> (Vec<ErrorSample>, u64) {
    let mut out = Vec::with_capacity(stream.samples.len());
    let mut unmatched = 0;
    for s in &stream.samples {
        let Some(t) = truth_at(truth, s.stamp_ns) else {
            unmatched += 1;
            continue;
        };
        let ne = s
            .pos
            .and_then(|p| horizontal_error(p, t.lat_rad, t.lon_rad, -t.depth_m, frame));
        if s.pos.is_some() && ne.is_none() {
            unmatched += 1;
            continue;
        }
        let attitude = s.attitude.map(|q| AttitudeError::between(&q, &t.attitude));
        let inside_95 = match (s.kind_of_check(), ne) {
            (Check::Position(cov), Some(e)) => inside_95_2d(e, &cov),
            (Check::Attitude(std), _) => s.attitude.and_then(|q| {
                // The error rotation in the navigation frame, q_est ⊗ q_truth⁻¹,
                // as a rotation vector about N, E, D: the axes of std_rad.
                let theta = rotation_vector(&(q * t.attitude.inverse()));
                let d2 = theta.component_div(&std).norm_squared();
                d2.is_finite().then_some(d2 <= CHI2_3DOF_95)
            }),
            _ => None,
        };
        out.push(ErrorSample {
            stamp_ns: s.stamp_ns,
            ne_m: ne,
            down_m: s.depth_m.map(|d| d - t.depth_m),
            vel_m_s: s.vel_ned_m_s.map(|v| (v - t.vel_ned_m_s).into()),
            attitude,
            inside_95,
            distance_m: t.distance_m,
        });
    }
    (out, unmatched)
}

/// The errors of `stream` against the GPS fixes (horizontal only), and how
/// many fixes had no estimate at their stamp.
pub fn errors_against_gps(
    stream: &Stream,
    gps: &[Gps],
    frame: Option<LocalFrame>,
) -> (Vec<ErrorSample>, u64) {
    let mut out: Vec<ErrorSample> = Vec::new();
    let mut unmatched = 0;
    let mut last_pos: Option<(usize, Horizontal)> = None;
    let mut distance_m = 0.0;
    for g in gps {
        let Some(s) = estimate_at(&stream.samples, g.stamp_ns) else {
            unmatched += 1;
            continue;
        };
        let Some(pos) = s.pos else {
            unmatched += 1;
            continue;
        };
        let Some(ne) = horizontal_error(pos, g.lat_rad, g.lon_rad, g.height_m, frame) else {
            unmatched += 1;
            continue;
        };
        // Distance along the estimated track since the first matched fix.
        let i = stream.samples.partition_point(|x| x.stamp_ns <= g.stamp_ns);
        if let Some((j, from)) = last_pos {
            distance_m += track_length(from, &stream.samples[j..i], pos);
        }
        last_pos = Some((i, pos));
        // The comparison is with a noisy fix: the error's covariance is the
        // estimate's plus the fix's (independent errors).
        let gps_var = g.horizontal_std_m * g.horizontal_std_m;
        let inside_95 = s
            .cov_ne_m2
            .and_then(|c| inside_95_2d(ne, &(c + Matrix2::identity() * gps_var)));
        out.push(ErrorSample {
            stamp_ns: g.stamp_ns,
            ne_m: Some(ne),
            down_m: None,
            vel_m_s: None,
            attitude: None,
            inside_95,
            distance_m,
        });
    }
    (out, unmatched)
}

/// Horizontal length of the polyline `from`, `between...`, `to`, m.
fn track_length(from: Horizontal, between: &[EstimateSample], to: Horizontal) -> f64 {
    let mut prev = from;
    let mut sum = 0.0;
    for p in between.iter().filter_map(|s| s.pos).chain([to]) {
        sum += step_m(prev, p);
        prev = p;
    }
    sum
}

/// Horizontal distance between two positions of one stream, m (0 between
/// positions of different frames, which one stream never mixes).
fn step_m(a: Horizontal, b: Horizontal) -> f64 {
    match (a, b) {
        (
            Horizontal::Geodetic { lat_rad, lon_rad },
            Horizontal::Geodetic {
                lat_rad: lb,
                lon_rad: ob,
            },
        ) => {
            let [n, e] = ne_offset(lb, ob, lat_rad, lon_rad, 0.0);
            n.hypot(e)
        }
        (
            Horizontal::Local { north_m, east_m },
            Horizontal::Local {
                north_m: nb,
                east_m: eb,
            },
        ) => (nb - north_m).hypot(eb - east_m),
        _ => 0.0,
    }
}

enum Check {
    Position(Matrix2<f64>),
    Attitude(Vector3<f64>),
    None,
}

impl EstimateSample {
    fn kind_of_check(&self) -> Check {
        if let Some(c) = self.cov_ne_m2 {
            Check::Position(c)
        } else if let Some(s) = self.att_std_rad {
            Check::Attitude(s)
        } else {
            Check::None
        }
    }
}

// ---------------------------------------------------------------------------
// Metrics
// ---------------------------------------------------------------------------

fn rms(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (mut n, mut sum) = (0u64, 0.0);
    for v in values {
        n += 1;
        sum += v * v;
    }
    (n > 0).then(|| (sum / n as f64).sqrt())
}

/// The metrics over `errors`.
pub fn metrics(errors: &[ErrorSample], unmatched: u64, rejected: u64) -> Metrics {
    let mut m = Metrics {
        samples: errors.len() as u64,
        unmatched,
        rejected,
        ..Default::default()
    };
    let ne: Vec<[f64; 2]> = errors.iter().filter_map(|e| e.ne_m).collect();
    m.north_rms_m = rms(ne.iter().map(|e| e[0]));
    m.east_rms_m = rms(ne.iter().map(|e| e[1]));
    m.horizontal_rms_m = rms(ne.iter().map(|e| e[0].hypot(e[1])));
    m.horizontal_max_m = ne.iter().map(|e| e[0].hypot(e[1])).reduce(f64::max);
    m.down_rms_m = rms(errors.iter().filter_map(|e| e.down_m));
    let vel = |k: usize| rms(errors.iter().filter_map(|e| e.vel_m_s.map(|v| v[k])));
    m.vel_north_rms_m_s = vel(0);
    m.vel_east_rms_m_s = vel(1);
    m.vel_down_rms_m_s = vel(2);
    let att = |f: fn(&AttitudeError) -> f64| {
        rms(errors.iter().filter_map(|e| e.attitude.as_ref().map(f))).map(f64::to_degrees)
    };
    m.roll_rms_deg = att(|a| a.roll_rad);
    m.pitch_rms_deg = att(|a| a.pitch_rad);
    m.yaw_rms_deg = att(|a| a.yaw_rad);

    let positioned: Vec<&ErrorSample> = errors.iter().filter(|e| e.ne_m.is_some()).collect();
    if let (Some(first), Some(last)) = (positioned.first(), positioned.last()) {
        let final_m = last.ne_m.map(|e| e[0].hypot(e[1])).unwrap_or_default();
        let distance = last.distance_m - first.distance_m;
        m.final_error_m = Some(final_m);
        m.distance_m = Some(distance);
        // Paper 002 §2 and Table 2: relative error = final position error /
        // distance travelled (defined in the text, without an equation number).
        if distance > 0.0 {
            m.final_error_pct = Some(100.0 * final_m / distance);
            m.drift_m_per_km = Some(final_m / (distance / 1000.0));
        }
    }
    let checked: Vec<bool> = errors.iter().filter_map(|e| e.inside_95).collect();
    if !checked.is_empty() {
        let inside = checked.iter().filter(|b| **b).count();
        m.inside_95_pct = Some(100.0 * inside as f64 / checked.len() as f64);
        m.covariance_samples = Some(checked.len() as u64);
    }
    m
}

/// The local frame a local (LBL) stream is evaluated in, and a note when
/// there is none.
pub fn local_frame(data: &Data) -> Result<LocalFrame, String> {
    if let Some(o) = &data.run.origin {
        return Ok(LocalFrame(o.value));
    }
    // The simulator's missions start at rest at their origin (shared/sim
    // mission.rs): a truth that starts with no distance travelled is there.
    match data.truth.first() {
        Some(t) if t.distance_m == 0.0 => Ok(LocalFrame(GeoOrigin {
            lat_rad: t.lat_rad,
            lon_rad: t.lon_rad,
        })),
        Some(_) => Err(
            "the recording has no origin in its nauta.run metadata and its truth starts after the mission start"
                .to_owned(),
        ),
        None => Err("the recording has no origin in its nauta.run metadata".to_owned()),
    }
}
