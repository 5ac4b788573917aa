//! Static coarse alignment: initial attitude from averaged accelerometer and
//! magnetometer samples taken while the vehicle is still.
//!
//! Roll and pitch level the averaged specific force, heading comes from the
//! tilt-compensated averaged magnetic field plus the local declination. This is
//! the aiding attitude of paper 000 (eqs. 30-41: pitch and roll from the
//! normalised accelerometer components, yaw from the magnetometer compensated for
//! pitch and roll, eq. 40, composed as `q_ψ ⊗ q_θ ⊗ q_φ`), written with `atan2`
//! instead of the paper's half-angle square roots, which lose accuracy and sign
//! near ±90° (leveling: Groves 2013 §5.6, Titterton & Weston 2004 ch. 10;
//! magnetic heading: Groves 2013 §6.1). Averaging many samples is paper 000
//! §IV-A's static calibration (400 samples).

use nalgebra::{UnitQuaternion, Vector3};
use thiserror::Error;

use crate::attitude::{from_euler, wrap_pi};

/// Number of samples averaged by paper 000's static calibration (§IV-A).
pub const PAPER_000_STATIC_SAMPLES: usize = 400;

/// Accumulates still accelerometer and magnetometer samples and turns their means
/// into an initial `q_nb`.
#[derive(Debug, Clone, PartialEq)]
pub struct Alignment {
    declination_rad: f64,
    min_samples: usize,
    count: usize,
    sum_f_b: Vector3<f64>,
    sum_m_b: Vector3<f64>,
}

/// Why a sample was not accepted by [`Alignment::push`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum AlignmentPushError {
    /// A component of the accelerometer or magnetometer sample is NaN or infinite;
    /// the sample was dropped and the running means are unchanged.
    #[error("accelerometer or magnetometer sample is not finite")]
    NonFinite,
}

/// Why [`Alignment::finish`] gave no attitude.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum AlignmentFinishError {
    /// Fewer samples than the configured minimum.
    #[error("only {got} samples, need at least {need}")]
    TooFewSamples {
        /// Samples accumulated.
        got: usize,
        /// Samples required.
        need: usize,
    },
    /// The declination or a mean is not finite.
    #[error("declination or mean sample is not finite")]
    NonFinite,
    /// The mean specific force is too small to define the vertical
    /// (below [`Alignment::MIN_SPECIFIC_FORCE_M_S2`]): free fall or no accelerometer.
    #[error("mean specific force {0} m/s^2 is too small to level")]
    NoGravity(f64),
    /// The tilt-compensated magnetic field has no horizontal component (a zero
    /// field, or a field along the vertical), so heading is undefined.
    #[error("magnetic field has no horizontal component")]
    ZeroHorizontalField,
}

/// Why an [`Alignment`] could not be configured.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum AlignmentNewError {
    /// The declination is not finite.
    #[error("declination is not finite")]
    NonFiniteDeclination,
    /// `min_samples` is zero.
    #[error("min_samples must be at least 1")]
    ZeroMinSamples,
}

impl Alignment {
    /// A mean specific force below this cannot define the vertical, m/s² (a tenth
    /// of gravity: far from anything a still vehicle measures).
    pub const MIN_SPECIFIC_FORCE_M_S2: f64 = 1.0;

    /// A new accumulator. `declination_rad` is the local magnetic declination, east
    /// positive (true heading = magnetic heading + declination); `min_samples` the
    /// number of samples [`finish`](Self::finish) requires.
    pub fn new(declination_rad: f64, min_samples: usize) -> Result<Self, AlignmentNewError> {
        if !declination_rad.is_finite() {
            return Err(AlignmentNewError::NonFiniteDeclination);
        }
        if min_samples == 0 {
            return Err(AlignmentNewError::ZeroMinSamples);
        }
        Ok(Self {
            declination_rad,
            min_samples,
            count: 0,
            sum_f_b: Vector3::zeros(),
            sum_m_b: Vector3::zeros(),
        })
    }

    /// Adds one still sample: specific force `f^b` (m/s², FRD; ≈ `[0, 0, -g]` when
    /// level) and magnetic field `m^b` (µT, FRD, calibrated). A non-finite sample is
    /// dropped.
    pub fn push(
        &mut self,
        accel_m_s2: &Vector3<f64>,
        mag_ut: &Vector3<f64>,
    ) -> Result<(), AlignmentPushError> {
        if !(accel_m_s2.iter().all(|v| v.is_finite()) && mag_ut.iter().all(|v| v.is_finite())) {
            return Err(AlignmentPushError::NonFinite);
        }
        self.count += 1;
        self.sum_f_b += accel_m_s2;
        self.sum_m_b += mag_ut;
        Ok(())
    }

    /// Samples accumulated so far.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Mean specific force of the samples so far (m/s², FRD), `None` before the
    /// first sample.
    pub fn mean_specific_force(&self) -> Option<Vector3<f64>> {
        (self.count > 0).then(|| self.sum_f_b / self.count as f64)
    }

    /// Mean magnetic field of the samples so far (µT, FRD), `None` before the
    /// first sample.
    pub fn mean_magnetic_field(&self) -> Option<Vector3<f64>> {
        (self.count > 0).then(|| self.sum_m_b / self.count as f64)
    }

    /// Forgets every sample (keeps the declination and the minimum).
    pub fn reset(&mut self) {
        self.count = 0;
        self.sum_f_b = Vector3::zeros();
        self.sum_m_b = Vector3::zeros();
    }

    /// The initial attitude `q_nb` from the means (the accumulator is kept, so more
    /// samples can be pushed and `finish` called again).
    pub fn finish(&self) -> Result<UnitQuaternion<f64>, AlignmentFinishError> {
        if self.count < self.min_samples {
            return Err(AlignmentFinishError::TooFewSamples {
                got: self.count,
                need: self.min_samples,
            });
        }
        let n = self.count as f64;
        let euler = level_and_heading(
            &(self.sum_f_b / n),
            &(self.sum_m_b / n),
            self.declination_rad,
        )?;
        Ok(from_euler(euler.0, euler.1, euler.2))
    }
}

/// Roll, pitch and true heading (rad) from one specific-force vector `f^b` (m/s²)
/// and one magnetic-field vector `m^b` (any unit), FRD, with declination `δ`
/// (east positive).
///
/// With `f^b = C_n^b [0, 0, -g]` for a still vehicle (paper 000 eqs. 31-36; Groves
/// 2013 §5.6):
/// `φ = atan2(-f_y, -f_z)`, `θ = atan2(f_x, √(f_y² + f_z²))`.
/// The field is rotated into the level frame that shares the body's heading
/// (paper 000 eq. 40, `m^E = C(q_θ ⊗ q_φ) m^b`):
/// `m_x^E = m_x cos θ + (m_y sin φ + m_z cos φ) sin θ`, `m_y^E = m_y cos φ - m_z sin φ`,
/// magnetic heading `ψ_m = atan2(-m_y^E, m_x^E)` (paper 000 eqs. 37-39; Groves 2013
/// §6.1), true heading `ψ = ψ_m + δ` wrapped to [-π, π).
pub fn level_and_heading(
    f_b: &Vector3<f64>,
    m_b: &Vector3<f64>,
    declination_rad: f64,
) -> Result<(f64, f64, f64), AlignmentFinishError> {
    if !(f_b.iter().all(|v| v.is_finite())
        && m_b.iter().all(|v| v.is_finite())
        && declination_rad.is_finite())
    {
        return Err(AlignmentFinishError::NonFinite);
    }
    let g = f_b.norm();
    if g.is_nan() || g < Alignment::MIN_SPECIFIC_FORCE_M_S2 {
        return Err(AlignmentFinishError::NoGravity(g));
    }
    let roll = (-f_b.y).atan2(-f_b.z);
    let pitch = f_b.x.atan2(f_b.y.hypot(f_b.z));
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let mx = m_b.x * cp + (m_b.y * sr + m_b.z * cr) * sp;
    let my = m_b.y * cr - m_b.z * sr;
    let horizontal = mx.hypot(my);
    // Zero field, or a field within 1e-9 rad of the vertical: heading undefined.
    if horizontal.is_nan() || horizontal <= 1e-9 * m_b.norm() {
        return Err(AlignmentFinishError::ZeroHorizontalField);
    }
    let heading_mag = (-my).atan2(mx);
    Ok((roll, pitch, wrap_pi(heading_mag + declination_rad)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::{AttitudeError, to_euler};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    const G: f64 = 9.80;

    /// Field in NED for a given declination: 20 µT horizontal toward magnetic
    /// north (azimuth δ from true north), 40 µT down (northern hemisphere).
    fn field_ned(declination: f64) -> Vector3<f64> {
        Vector3::new(20.0 * declination.cos(), 20.0 * declination.sin(), 40.0)
    }

    fn synth(q: &UnitQuaternion<f64>, declination: f64) -> (Vector3<f64>, Vector3<f64>) {
        let f = q.inverse_transform_vector(&Vector3::new(0.0, 0.0, -G));
        let m = q.inverse_transform_vector(&field_ned(declination));
        (f, m)
    }

    #[test]
    fn level_north_is_identity() {
        let (r, p, y) =
            level_and_heading(&Vector3::new(0.0, 0.0, -G), &field_ned(0.0), 0.0).expect("ok");
        assert!(r.abs() < 1e-15 && p.abs() < 1e-15 && y.abs() < 1e-15);
    }

    #[test]
    fn recovers_known_attitudes_with_declination() {
        let declination = (-21.5f64).to_radians(); // São Paulo (paper 002 §1.2: about -20°)
        for (r, p, y) in [
            (0.0, 0.0, 0.0),
            (0.1, -0.2, 1.0),
            (-0.5, 0.4, -2.5),
            (0.3, 1.2, 3.0),
            (2.5, -0.3, -0.7), // upside down-ish: atan2 keeps the quadrant
        ] {
            let truth = from_euler(r, p, y);
            let (f, m) = synth(&truth, declination);
            let mut a = Alignment::new(declination, 3).expect("valid");
            for _ in 0..3 {
                a.push(&f, &m).expect("finite");
            }
            let q = a.finish().expect("aligned");
            let e = AttitudeError::between(&q, &truth);
            assert!(e.total_rad < 1e-12, "({r}, {p}, {y}): {e:?}");
            let (r2, p2, y2) = to_euler(&q);
            assert!((r2 - r).abs() < 1e-12 && (p2 - p).abs() < 1e-12 && (y2 - y).abs() < 1e-12);
        }
    }

    #[test]
    fn declination_sign_true_is_magnetic_plus_declination() {
        // Vehicle pointing at true north, declination +10° (magnetic north is 10°
        // east of true): the compass reads -10°, and alignment must give 0°.
        let declination = 10f64.to_radians();
        let (f, m) = synth(&UnitQuaternion::identity(), declination);
        let (_, _, mag_heading) = level_and_heading(&f, &m, 0.0).expect("ok");
        assert!((mag_heading + declination).abs() < 1e-14);
        let (_, _, true_heading) = level_and_heading(&f, &m, declination).expect("ok");
        assert!(true_heading.abs() < 1e-14);
    }

    #[test]
    fn averaging_noisy_samples_converges() {
        let declination = 0.05;
        let truth = from_euler(0.05, -0.03, 2.0);
        let (f, m) = synth(&truth, declination);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let acc_noise = Normal::new(0.0, 0.05).expect("valid");
        let mag_noise = Normal::new(0.0, 0.5).expect("valid");
        let mut a = Alignment::new(declination, PAPER_000_STATIC_SAMPLES).expect("valid");
        for _ in 0..4000 {
            let fn_ = f + Vector3::from_fn(|_, _| acc_noise.sample(&mut rng));
            let mn = m + Vector3::from_fn(|_, _| mag_noise.sample(&mut rng));
            a.push(&fn_, &mn).expect("finite");
        }
        let e = AttitudeError::between(&a.finish().expect("aligned"), &truth);
        // σ/√N: 0.05/9.8/63 ≈ 1e-4 rad tilt, 0.5/20/63 ≈ 4e-4 rad heading.
        assert!(e.total_rad < 2e-3, "{e:?}");
    }

    #[test]
    fn errors() {
        assert_eq!(
            Alignment::new(f64::NAN, 1),
            Err(AlignmentNewError::NonFiniteDeclination)
        );
        assert_eq!(
            Alignment::new(0.0, 0),
            Err(AlignmentNewError::ZeroMinSamples)
        );
        let mut a = Alignment::new(0.0, 2).expect("valid");
        let f = Vector3::new(0.0, 0.0, -G);
        let m = field_ned(0.0);
        a.push(&f, &m).expect("finite");
        assert_eq!(
            a.finish(),
            Err(AlignmentFinishError::TooFewSamples { got: 1, need: 2 })
        );
        assert_eq!(
            a.push(&Vector3::new(f64::NAN, 0.0, 0.0), &m),
            Err(AlignmentPushError::NonFinite)
        );
        assert_eq!(
            a.push(&f, &Vector3::new(0.0, f64::INFINITY, 0.0)),
            Err(AlignmentPushError::NonFinite)
        );
        assert_eq!(a.count(), 1);
        assert_eq!(a.mean_specific_force(), Some(f));
        assert_eq!(a.mean_magnetic_field(), Some(m));
        a.push(&f, &m).expect("finite");
        assert!(a.finish().is_ok());
        a.reset();
        assert_eq!(a.count(), 0);
        assert_eq!(a.mean_magnetic_field(), None);

        // No horizontal field: zero, or straight down.
        let mut a = Alignment::new(0.0, 1).expect("valid");
        a.push(&f, &Vector3::zeros()).expect("finite");
        assert_eq!(a.finish(), Err(AlignmentFinishError::ZeroHorizontalField));
        let mut a = Alignment::new(0.0, 1).expect("valid");
        a.push(&f, &Vector3::new(0.0, 0.0, 45.0)).expect("finite");
        assert_eq!(a.finish(), Err(AlignmentFinishError::ZeroHorizontalField));
        // No gravity.
        let mut a = Alignment::new(0.0, 1).expect("valid");
        a.push(&Vector3::new(0.0, 0.0, -0.1), &m).expect("finite");
        assert!(matches!(
            a.finish(),
            Err(AlignmentFinishError::NoGravity(_))
        ));
        // Overflowing sums are caught at finish.
        let mut a = Alignment::new(0.0, 2).expect("valid");
        a.push(&Vector3::new(0.0, 0.0, -f64::MAX), &m)
            .expect("finite");
        a.push(&Vector3::new(0.0, 0.0, -f64::MAX), &m)
            .expect("finite");
        assert_eq!(a.finish(), Err(AlignmentFinishError::NonFinite));
    }
}
