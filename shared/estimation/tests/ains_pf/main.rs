// Integration tests of the aided INS's `pf` variant (it needs the simulator,
// which depends on this crate).
//! Paper 000 §III-A's velocity and position particle filters against the
//! simulator's truth on the survey (paper 000's parallel transects, GPS
//! only at the surface), without position aiding.

mod harness;

use harness::*;
use nauta_estimation::ains::pf::AinsPfParams;

fn report(name: &str, s: &Score) {
    let v = s.vel_rms();
    eprintln!(
        "{name}: {} outputs, vel RMS N/E/D {:.4} {:.4} {:.4} m/s, pos 95% coverage {:.3}, vel 95% coverage {:.3}, {:.2} µs per IMU sample",
        s.outputs,
        v[0],
        v[1],
        v[2],
        s.coverage(),
        s.vel_coverage(),
        s.us_per_imu()
    );
    for (k, d) in s.dives.iter().enumerate() {
        let f = d.final_m_per_km();
        let sl = d.slope_m_per_km();
        eprintln!(
            "  dive {k}: {:.0} m submerged, final error N/E/D {:.2} {:.2} {:.2} m = {:.2} {:.2} {:.2} m/km, slope {:.2} {:.2} {:.2} m/km",
            d.distance_m,
            d.final_error_m[0],
            d.final_error_m[1],
            d.final_error_m[2],
            f[0],
            f[1],
            f[2],
            sl[0],
            sl[1],
            sl[2]
        );
    }
    if let Some(n) = s.last {
        eprintln!(
            "  last: pos σ {:?} vel σ {:?} mode {:#b}",
            n.pos_std_ned_m, n.vel_std_ned_m_s, n.aiding_mode
        );
    }
    eprintln!("  stats {:?}", s.stats);
}

fn seed_from_env(default: u64) -> u64 {
    std::env::var("NAUTA_PF_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

#[test]
fn survey_dev() {
    let p = AinsPfParams {
        position_aiding: false,
        seed: 7,
        ..Default::default()
    };
    let dur = std::env::var("NAUTA_PF_DURATION_S")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1e6);
    let s = run_survey(seed_from_env(7), dur, &[p]);
    report("survey", &s[0]);
}
