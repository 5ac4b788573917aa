//! Calibration manoeuvres, simulated: what a sensor reads while the vehicle
//! is turned by hand on deck through many attitudes (paper 000 §IV-A's
//! magnetometer calibration needs such samples). Used by `nauta calibrate
//! magnetometer --sim` and the attitude benchmark.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::noise::{MagnetometerNoise, MagnetometerSpec};

/// Attitudes of a magnetometer manoeuvre.
pub const MAGNETOMETER_MANOEUVRE_SAMPLES: usize = 2000;

/// A uniformly distributed attitude (Shoemake 1992, from three uniforms).
fn random_attitude(rng: &mut ChaCha8Rng) -> UnitQuaternion<f64> {
    let (u1, u2, u3): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    UnitQuaternion::new_normalize(Quaternion::new(
        a * (tau * u2).sin(),
        a * (tau * u2).cos(),
        b * (tau * u3).sin(),
        b * (tau * u3).cos(),
    ))
}

/// A calibration manoeuvre on deck, simulated: the magnetometer `spec` (its
/// hard and soft iron and noise) turned through [`MAGNETOMETER_MANOEUVRE_SAMPLES`] random attitudes in the
/// field `field_ned_t` (T); the readings, µT.
pub fn magnetometer_manoeuvre(
    spec: MagnetometerSpec,
    field_ned_t: &Vector3<f64>,
    seed: u64,
) -> anyhow::Result<Vec<Vector3<f64>>> {
    let mut noise = MagnetometerNoise::new(spec)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    Ok((0..MAGNETOMETER_MANOEUVRE_SAMPLES)
        .map(|_| {
            let q = random_attitude(&mut rng);
            noise.next(&mut rng, q.inverse_transform_vector(field_ned_t)) * 1e6
        })
        .collect())
}
