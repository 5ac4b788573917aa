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
        _ => Heading::Ahrs,
    };
    let t = std::time::Instant::now();
    let f = run(seed, dur, &no_fix(), h);
    report("explore", &f);
    eprintln!("wall {:?}", t.elapsed());
}
