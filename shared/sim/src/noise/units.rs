//! Conversions from datasheet units to the SI units used inside the models.
//!
//! Gyro white noise is quoted either as a rate noise density in °/s/√Hz or
//! as an angle random walk in °/√h; both are the same coefficient N
//! (IEEE Std 952-1997: N in °/√h = 60 × N in °/s/√Hz, because
//! 1 °/s/√Hz = 1 °/√s = 60 °/√h). Inside, N is in rad/√s (= rad/s/√Hz).

use std::f64::consts::PI;

/// Standard gravity g₀ = 9.80665 m/s² (used to convert µg).
pub const STANDARD_GRAVITY: f64 = 9.806_65;

/// Degrees to radians.
pub fn deg_to_rad(deg: f64) -> f64 {
    deg * PI / 180.0
}

/// °/s/√Hz (rate noise density) → rad/s/√Hz (= rad/√s).
pub fn deg_per_s_per_rt_hz_to_si(x: f64) -> f64 {
    deg_to_rad(x)
}

/// °/√h (angle random walk) → rad/√s.
pub fn deg_per_rt_h_to_si(x: f64) -> f64 {
    deg_to_rad(x) / 60.0
}

/// rad/√s → °/√h.
pub fn si_to_deg_per_rt_h(x: f64) -> f64 {
    x.to_degrees() * 60.0
}

/// °/h → rad/s (bias instability, turn-on bias).
pub fn deg_per_h_to_si(x: f64) -> f64 {
    deg_to_rad(x) / 3600.0
}

/// rad/s → °/h.
pub fn si_to_deg_per_h(x: f64) -> f64 {
    x.to_degrees() * 3600.0
}

/// °/s → rad/s.
pub fn deg_per_s_to_si(x: f64) -> f64 {
    deg_to_rad(x)
}

/// °/h/√h (rate random walk) → rad/s/√s.
pub fn deg_per_h_per_rt_h_to_si(x: f64) -> f64 {
    deg_to_rad(x) / 3600.0 / 60.0
}

/// µg → m/s².
pub fn micro_g_to_si(x: f64) -> f64 {
    x * 1e-6 * STANDARD_GRAVITY
}

/// m/s² → µg.
pub fn si_to_micro_g(x: f64) -> f64 {
    x / (1e-6 * STANDARD_GRAVITY)
}

/// µg/√Hz → m/s²/√Hz.
pub fn micro_g_per_rt_hz_to_si(x: f64) -> f64 {
    micro_g_to_si(x)
}

/// ppm → fraction.
pub fn ppm_to_fraction(x: f64) -> f64 {
    x * 1e-6
}

/// milligauss → tesla (1 G = 1e-4 T, so 1 mG = 1e-7 T = 0.1 µT).
pub fn milligauss_to_tesla(x: f64) -> f64 {
    x * 1e-7
}

/// microtesla → tesla.
pub fn microtesla_to_tesla(x: f64) -> f64 {
    x * 1e-6
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_agree() {
        // 0.03 °/s/√Hz is 1.8 °/√h.
        let n = deg_per_s_per_rt_hz_to_si(0.03);
        assert!((si_to_deg_per_rt_h(n) - 1.8).abs() < 1e-12);
        assert!((deg_per_rt_h_to_si(1.8) - n).abs() < 1e-15);
        assert!((si_to_deg_per_h(deg_per_h_to_si(18.0)) - 18.0).abs() < 1e-12);
        assert!((si_to_micro_g(micro_g_to_si(40.0)) - 40.0).abs() < 1e-9);
        assert!((milligauss_to_tesla(0.5) - 0.05e-6).abs() < 1e-20);
    }
}
