// Integration tests of the aided INS's `ekf` variant (it needs the simulator,
// which depends on this crate).
//! The error-state EKF against the simulator's survey.

mod harness;

use harness::*;
use nauta_estimation::ains::ekf::EkfParams;
use nauta_estimation::attitude_core::{MekfVariantParams, PfVariantParams, VariantParams};

fn no_fix() -> EkfParams {
    EkfParams {
        position_aiding: false,
        ..Default::default()
    }
}

#[test]
fn explore() {
    let dur: f64 = std::env::var("EKF_DUR").ok().and_then(|s| s.parse().ok()).unwrap_or(3000.0);
    let seed: u64 = std::env::var("EKF_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(7);
    let h = match std::env::var("EKF_HEADING").as_deref() {
        Ok("pf") => Heading::Attitude(VariantParams::Pf(PfVariantParams { alignment_samples: 400, ..Default::default() })),
        Ok("mekf") => Heading::Attitude(VariantParams::Mekf(MekfVariantParams { alignment_samples: 400, ..Default::default() })),
        Ok("pfcal") => attitude_pf(),
        Ok("mekfcal") => attitude_mekf(),
        _ => Heading::Ahrs,
    };
    let t = std::time::Instant::now();
    let mut p = no_fix();
    if std::env::var("EKF_NOHEADING").is_ok() {
        p.ahrs_heading_std_rad = 1.0;
        p.heading_bias_std_rad = 0.0;
    }
    if let Ok(v) = std::env::var("EKF_BH") {
        p.heading_bias_std_rad = v.parse().expect("number");
    }
    let mut sensors = nauta_sim::suite::SuiteConfig::survey();
    if std::env::var("EKF_CLEAN").is_ok() {
        sensors = sensors.noise_free();
    }
    if std::env::var("EKF_CLEAN_AHRS").is_ok() {
        sensors.ahrs.heading_bias_sigma_rad = 0.0;
    }
    let f = run_with(seed, dur, &p, h, sensors);
    report("explore", &f);
    eprintln!("wall {:?}", t.elapsed());
}
