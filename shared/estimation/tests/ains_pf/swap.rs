//! A hot swap from one variant of the aided INS to another in the middle
//! of the survey's dive: the new variant continues from the old one's
//! solution (`nauta_estimation::ains::seed`) at once, instead of waiting
//! for the next GPS fix at the surface.

use super::{position_error, recorded};
use nauta_estimation::Estimator;
use nauta_estimation::Stamped;
use nauta_estimation::ains::dr::DrParams;
use nauta_estimation::ains::ekf::EkfParams;
use nauta_estimation::ains::pf::AinsPfParams;
use nauta_estimation::ains::{AinsCore, AinsParams, VARIANTS, aiding};
use nauta_estimation::readings::Nav;

fn params(variant: &str) -> AinsParams {
    match variant {
        "pf" => AinsParams::Pf(AinsPfParams {
            position_aiding: false,
            seed: 7,
            ..Default::default()
        }),
        "dr" => AinsParams::Dr(DrParams::default()),
        _ => AinsParams::Ekf(EkfParams {
            position_aiding: false,
            ..Default::default()
        }),
    }
}

/// Every pair of variants, swapped 300 s into the survey (submerged since
/// the dive began): the new one publishes from its first triggering input
/// on, near the truth and with the truth inside its σ, for the 120 s
/// after.
#[test]
fn a_swap_to_another_variant_continues_from_its_solution() {
    let (site, inputs) = recorded(7, 420.0);
    let swap_ns = 300_000_000_000u64;
    let cut = inputs.partition_point(|(i, _)| i.stamp_ns() <= swap_ns);
    for from in VARIANTS {
        let mut a = AinsCore::new(&params(from), site).expect("valid");
        let mut out = Vec::new();
        for (i, _) in &inputs[..cut] {
            let _ = a.on_input(i, &mut out);
        }
        let before = *out.last().expect("the first variant ran");
        assert_eq!(
            before.aiding_mode & aiding::GPS,
            0,
            "{from}: submerged at the swap"
        );
        let state = a.snapshot().expect("a snapshot");
        for to in VARIANTS.iter().filter(|v| **v != from) {
            let mut b = AinsCore::new(&params(to), site).expect("valid");
            b.restore(&state, swap_ns)
                .unwrap_or_else(|e| panic!("{from} → {to}: {e}"));
            let mut after: Vec<(Nav, _)> = Vec::new();
            let mut o = Vec::new();
            for (i, t) in &inputs[cut..] {
                o.clear();
                let _ = b.on_input(i, &mut o);
                after.extend(o.iter().map(|n| (*n, *t)));
            }
            let (first, _) = after.first().expect("published after the swap");
            assert!(
                first.stamp_ns - swap_ns <= 200_000_000,
                "{from} → {to}: first solution {} ns after the swap",
                first.stamp_ns - swap_ns
            );
            for (n, t) in after.iter().step_by(100) {
                let e = position_error(n, t);
                let s = n.pos_std_ned_m.to_array();
                let h = e[0].hypot(e[1]);
                assert!(
                    h < 15.0,
                    "{from} → {to} at {:.1} s: horizontal error {h:.2} m",
                    n.stamp_ns as f64 * 1e-9
                );
                for k in 0..2 {
                    assert!(
                        e[k].abs() <= 3.0 * s[k] + 0.5,
                        "{from} → {to} at {:.1} s, axis {k}: error {:.2} m, σ {:.2} m",
                        n.stamp_ns as f64 * 1e-9,
                        e[k],
                        s[k]
                    );
                }
                assert!(e[2].abs() < 0.5, "{from} → {to}: depth error {:.2} m", e[2]);
            }
            let (last, t) = after.last().expect("outputs");
            let e = position_error(last, t);
            eprintln!(
                "{from} → {to}: at the swap σ_h {:.2} m; 120 s later error {:.2} m, σ_h {:.2} m",
                before.predicted_drift_m,
                e[0].hypot(e[1]),
                last.predicted_drift_m
            );
        }
    }
}
