use super::*;
use crate::noise::mean_std;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn rel(measured: f64, spec: f64) -> f64 {
    measured / spec - 1.0
}

/// A rate check: within 10 % of spec, and a spec 15 % off would have failed.
fn check_rate(what: &str, events: usize, trials: usize, p: f64) {
    assert!(events >= 10_000, "{what}: only {events} events");
    let r = events as f64 / trials as f64;
    eprintln!(
        "{what}: spec {p:.5}, measured {r:.5} ({events} / {trials}, {:+.2} %)",
        100.0 * rel(r, p)
    );
    assert!(rel(r, p).abs() < 0.10, "{what}: {r} vs {p}");
    assert!(rel(r, p * 1.15).abs() > 0.10);
}

#[test]
fn dvl_noise_spikes_and_dropouts() {
    let spec = DvlSpec::default();
    let mut r = rng(5);
    let mut dvl = DvlNoise::new(spec, &mut r).expect("spec");
    let mut spikes_rng = rng(55);
    let v = Vector3::new(1.5, -0.1, 0.05);
    let expected = v * (1.0 + dvl.scale_factor_error());
    let n = 2_200_000;
    let (mut valid, mut spikes, mut drops, mut surge) = (0usize, 0usize, 0usize, 0usize);
    let mut resid_x = Vec::new();
    for _ in 0..n {
        match dvl.next(&mut r, &mut spikes_rng, v) {
            DvlOutcome::Valid(m) => {
                valid += 1;
                if resid_x.len() < 200_000 {
                    resid_x.push(m.x - expected.x);
                }
            }
            DvlOutcome::Dropout => drops += 1,
            DvlOutcome::Spike { velocity, axis } => {
                spikes += 1;
                if axis == 0 {
                    surge += 1;
                }
                let a = (velocity[axis] - expected[axis]).abs();
                assert!(a > 0.5 - 0.06 && a < 3.0 + 0.06, "spike size {a}");
            }
        }
    }
    let (mean, std) = mean_std(&resid_x);
    eprintln!(
        "dvl noise: spec σ {}, measured {std:.5} ({:+.2} %), mean {mean:.2e}",
        spec.noise_sigma,
        100.0 * rel(std, spec.noise_sigma)
    );
    assert!(rel(std, spec.noise_sigma).abs() < 0.10);
    assert!(rel(std, spec.noise_sigma * 1.15).abs() > 0.10);
    check_rate(
        "dvl spike rate (per non-dropped sample)",
        spikes,
        valid + spikes,
        spec.spike_probability,
    );
    check_rate("dvl dropout fraction", drops, n, spec.dropout_fraction());
    let f = surge as f64 / spikes as f64;
    assert!(
        rel(f, spec.spike_surge_fraction).abs() < 0.10,
        "surge share {f}"
    );
}

/// Paper 002 Fig. 5's comparison needs runs that differ by their spikes
/// only: with spikes switched off, every other sample is the same, bit for
/// bit, and the spiked ones differ on one axis.
#[test]
fn a_spike_free_dvl_differs_only_by_its_spikes() {
    let run = |spike_probability: f64| {
        let spec = DvlSpec {
            spike_probability,
            ..DvlSpec::default()
        };
        let mut r = rng(9);
        let mut s = rng(99);
        let mut d = DvlNoise::new(spec, &mut r).expect("spec");
        (0..200_000)
            .map(|k| {
                d.next(
                    &mut r,
                    &mut s,
                    Vector3::new(1.5, 0.1 * (k as f64).sin(), 0.0),
                )
            })
            .collect::<Vec<_>>()
    };
    let (spiky, clean) = (run(0.01), run(0.0));
    let mut spikes = 0;
    for (a, b) in spiky.iter().zip(&clean) {
        match (a, b) {
            (DvlOutcome::Spike { velocity, axis }, DvlOutcome::Valid(v)) => {
                spikes += 1;
                for i in 0..3 {
                    if i == *axis {
                        assert!((velocity[i] - v[i]).abs() >= 0.5, "spike too small");
                    } else {
                        assert_eq!(velocity[i], v[i]);
                    }
                }
            }
            (a, b) => assert_eq!(a, b, "a sample without a spike differs"),
        }
    }
    assert!(spikes > 1000, "{spikes} spikes");
}

#[test]
fn dvl_scale_factor_spread() {
    // 2000 instances: the drawn scale factors have σ_s within 10 %.
    let spec = DvlSpec::default();
    let mut r = rng(8);
    let s: Vec<f64> = (0..2000)
        .map(|_| {
            DvlNoise::new(spec, &mut r)
                .expect("spec")
                .scale_factor_error()
        })
        .collect();
    let (_, std) = mean_std(&s);
    assert!(rel(std, spec.scale_factor_sigma).abs() < 0.10, "σ_s {std}");
}

#[test]
fn modem_loss_rate_jitter_and_sound_speed() {
    let spec = ModemSpec::default();
    let mut modem = ModemNoise::new(spec).expect("spec");
    let mut r = rng(9);
    let mut mp = rng(90);
    let range = 800.0;
    let n = 120_000;
    let mut lost = 0;
    let mut tof_err = Vec::new();
    let mut range_ratio = Vec::new();
    for _ in 0..n {
        match modem.next(&mut r, &mut mp, range) {
            ModemOutcome::Lost => lost += 1,
            ModemOutcome::Multipath(_) => panic!("no multipath by default"),
            ModemOutcome::Received(m) => {
                tof_err.push(m.time_of_flight - range / spec.sound_speed);
                range_ratio.push(m.range / range);
            }
        }
    }
    check_rate("modem loss rate", lost, n, spec.loss_probability);
    let (_, std) = mean_std(&tof_err);
    eprintln!(
        "modem jitter: spec σ {} s, measured {std:.6} s ({:+.2} %)",
        spec.clock_jitter_sigma,
        100.0 * rel(std, spec.clock_jitter_sigma)
    );
    assert!(rel(std, spec.clock_jitter_sigma).abs() < 0.10);
    // Mean range scales by 1 + e_c (jitter averages out: 1.5 m / √108000).
    let (ratio, _) = mean_std(&range_ratio);
    assert!(
        (ratio - 1.0 - spec.sound_speed_error).abs() < 2e-4,
        "ratio {ratio}"
    );
}

#[test]
fn lbl_multipath_rate_quantisation_and_detection() {
    // The clock alone (no detection jitter), so a direct reply is exact to a tick.
    let spec = LblSpec {
        timing_jitter_sigma: 0.0,
        ..LblSpec::default()
    };
    let mut lbl = LblNoise::new(spec).expect("spec");
    let mut r = rng(10);
    let range = 700.0;
    let ta = 12.5e-3;
    let true_rt = 2.0 * range / spec.sound_speed + ta;
    let n = 220_000;
    let (mut direct, mut multi, mut none) = (0usize, 0usize, 0usize);
    for _ in 0..n {
        let out = lbl.next(&mut r, range, ta);
        if let Some(reply) = out.reply() {
            // Every round trip is a whole number of 100 µs ticks.
            assert_eq!(reply.round_trip, reply.ticks as f64 * 100e-6);
            let ticks = reply.round_trip / 100e-6;
            assert!((ticks - ticks.round()).abs() < 1e-9);
        }
        match out {
            LblOutcome::Direct(reply) => {
                direct += 1;
                assert!(reply.round_trip <= true_rt && reply.round_trip > true_rt - 100e-6);
            }
            LblOutcome::Multipath(reply) => {
                multi += 1;
                let extra = reply.round_trip - true_rt;
                assert!(extra > 1e-3 - 100e-6 && extra <= 20e-3, "extra {extra}");
            }
            LblOutcome::NoReply => none += 1,
        }
    }
    check_rate(
        "lbl multipath rate (per detected reply)",
        multi,
        direct + multi,
        spec.multipath_probability,
    );
    // At 700 m, p = 1/(1+e^-13) ≈ 1: almost no misses.
    assert!(none < 5, "misses {none}");
    // Range from a direct reply is within c Δ / 2 = 7.5 cm of the truth.
    let rt = (true_rt / 100e-6).floor() * 100e-6;
    assert!((spec.range_from_round_trip(rt, ta) - range).abs() <= 0.075 + 1e-9);

    // Detection probability: ½ at r₅₀, falling with range.
    let trials = 20_000;
    let detected = (0..trials)
        .filter(|_| {
            lbl.next(&mut r, spec.detection_range_50, ta)
                .reply()
                .is_some()
        })
        .count();
    let p = detected as f64 / trials as f64;
    assert!(rel(p, 0.5).abs() < 0.10, "p(r50) {p}");
    assert!(spec.detection_probability(0.0) > 0.999_999);
    assert!(spec.detection_probability(2500.0) < 0.01);
}

/// The default detection jitter (0.4 ms) on top of the clock: the direct
/// replies' round trips scatter by √(σ² + Δ²/12) about the truth less half
/// a tick (the clock floors).
#[test]
fn lbl_timing_jitter_has_its_sigma() {
    let spec = LblSpec {
        multipath_probability: 0.0,
        ..LblSpec::default()
    };
    assert_eq!(spec.timing_jitter_sigma, 0.4e-3);
    let mut lbl = LblNoise::new(spec).expect("spec");
    let mut r = rng(11);
    let (range, ta) = (500.0, 12.5e-3);
    let true_rt = 2.0 * range / spec.sound_speed + ta;
    let err: Vec<f64> = (0..50_000)
        .filter_map(|_| {
            let eps = lbl.jitter(&mut r);
            lbl.next(&mut r, range, ta + eps).reply()
        })
        .map(|reply| reply.round_trip - true_rt)
        .collect();
    let (mean, std) = mean_std(&err);
    let want = (spec.timing_jitter_sigma.powi(2) + spec.clock_resolution.powi(2) / 12.0).sqrt();
    assert!(rel(std, want).abs() < 0.02, "σ {std} against {want}");
    assert!(
        (mean + 0.5 * spec.clock_resolution).abs() < 1e-5,
        "mean {mean}"
    );
}

#[test]
fn depth_and_magnetometer_noise() {
    let spec = DepthSpec::default();
    let mut depth = DepthNoise::new(spec).expect("spec");
    let mut r = rng(12);
    let e: Vec<f64> = (0..100_000)
        .map(|_| depth.next(&mut r, 15.0) - 15.0)
        .collect();
    let (mean, std) = mean_std(&e);
    eprintln!(
        "depth: spec σ {} m offset {} m, measured σ {std:.5} ({:+.2} %) offset {mean:.5}",
        spec.noise_sigma,
        spec.offset,
        100.0 * rel(std, spec.noise_sigma)
    );
    assert!(rel(std, spec.noise_sigma).abs() < 0.10);
    assert!(rel(std, spec.noise_sigma * 1.15).abs() > 0.10);
    assert!((mean - spec.offset).abs() < 1e-3);

    let spec = MagnetometerSpec::default();
    let mut mag = MagnetometerNoise::new(spec).expect("spec");
    let m = Vector3::new(20e-6, -3e-6, 40e-6);
    let clean = spec.soft_iron_matrix() * m + spec.hard_iron_vector();
    for axis in 0..3 {
        let e: Vec<f64> = (0..100_000)
            .map(|_| mag.next(&mut r, m)[axis] - clean[axis])
            .collect();
        let (mean, std) = mean_std(&e);
        eprintln!(
            "mag axis {axis}: spec σ {:.3e} T, measured {std:.3e} ({:+.2} %)",
            spec.noise_sigma,
            100.0 * rel(std, spec.noise_sigma)
        );
        assert!(rel(std, spec.noise_sigma).abs() < 0.10);
        assert!(mean.abs() < 1e-9);
    }
}

#[test]
fn same_seed_same_series_other_seed_differs() {
    fn dvl(seed: u64) -> Vec<Option<Vector3<f64>>> {
        let mut r = rng(seed);
        let mut d = DvlNoise::new(DvlSpec::default(), &mut r).expect("spec");
        let mut s = rng(seed + 1000);
        (0..5000)
            .map(|_| {
                d.next(&mut r, &mut s, Vector3::new(1.0, 0.0, 0.0))
                    .velocity()
            })
            .collect()
    }
    fn lbl(seed: u64) -> Vec<LblOutcome> {
        let mut r = rng(seed);
        let mut l = LblNoise::new(LblSpec {
            timing_jitter_sigma: 50e-6,
            ..LblSpec::default()
        })
        .expect("spec");
        (0..5000).map(|_| l.next(&mut r, 1900.0, 12.5e-3)).collect()
    }
    fn modem(seed: u64) -> Vec<ModemOutcome> {
        let mut r = rng(seed);
        let mut mp = rng(seed + 1000);
        let mut m = ModemNoise::new(ModemSpec::default()).expect("spec");
        (0..2000).map(|_| m.next(&mut r, &mut mp, 500.0)).collect()
    }
    fn depth_mag(seed: u64) -> Vec<f64> {
        let mut r = rng(seed);
        let mut d = DepthNoise::new(DepthSpec::default()).expect("spec");
        let mut m = MagnetometerNoise::new(MagnetometerSpec::default()).expect("spec");
        (0..2000)
            .map(|_| d.next(&mut r, 3.0) + m.next(&mut r, Vector3::new(2e-5, 0.0, 4e-5)).x)
            .collect()
    }
    assert_eq!(dvl(1), dvl(1));
    assert_ne!(dvl(1), dvl(2));
    assert_eq!(lbl(1), lbl(1));
    assert_ne!(lbl(1), lbl(2));
    assert_eq!(modem(1), modem(1));
    assert_ne!(modem(1), modem(2));
    let (a, b, c) = (depth_mag(1), depth_mag(1), depth_mag(2));
    assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
    assert_ne!(a, c);
}

#[test]
fn invalid_configurations_are_rejected() {
    let mut r = rng(0);
    let bad_dvl = [
        DvlSpec {
            noise_sigma: -0.1,
            ..DvlSpec::default()
        },
        DvlSpec {
            spike_probability: 1.5,
            ..DvlSpec::default()
        },
        DvlSpec {
            dropout_probability: f64::NAN,
            ..DvlSpec::default()
        },
        DvlSpec {
            spike_magnitude: [3.0, 0.5],
            ..DvlSpec::default()
        },
        DvlSpec {
            mean_dropout_length: 0.5,
            ..DvlSpec::default()
        },
    ];
    for s in bad_dvl {
        assert!(DvlNoise::new(s, &mut r).is_err(), "{s:?}");
    }
    assert!(matches!(
        DvlNoise::new(
            DvlSpec {
                noise_sigma: -0.1,
                ..DvlSpec::default()
            },
            &mut r
        ),
        Err(NoiseError::Negative { .. })
    ));
    assert!(matches!(
        ModemNoise::new(ModemSpec {
            loss_probability: -0.01,
            ..ModemSpec::default()
        }),
        Err(NoiseError::NotAProbability { .. })
    ));
    assert!(matches!(
        ModemNoise::new(ModemSpec {
            clock_jitter_sigma: f64::INFINITY,
            ..ModemSpec::default()
        }),
        Err(NoiseError::NotFinite { .. })
    ));
    assert!(
        ModemNoise::new(ModemSpec {
            sound_speed_error: -1.0,
            ..ModemSpec::default()
        })
        .is_err()
    );
    assert!(matches!(
        LblNoise::new(LblSpec {
            multipath_probability: f64::NAN,
            ..LblSpec::default()
        }),
        Err(NoiseError::NotAProbability { .. })
    ));
    assert!(matches!(
        LblNoise::new(LblSpec {
            clock_resolution: 0.0,
            ..LblSpec::default()
        }),
        Err(NoiseError::NotPositive { .. })
    ));
    assert!(matches!(
        LblNoise::new(LblSpec {
            multipath_delay: [0.02, 0.001],
            ..LblSpec::default()
        }),
        Err(NoiseError::EmptyInterval { .. })
    ));
    assert!(matches!(
        DepthNoise::new(DepthSpec {
            noise_sigma: -0.02,
            ..DepthSpec::default()
        }),
        Err(NoiseError::Negative { .. })
    ));
    assert!(
        DepthNoise::new(DepthSpec {
            offset: f64::NAN,
            ..DepthSpec::default()
        })
        .is_err()
    );
    assert!(matches!(
        MagnetometerNoise::new(MagnetometerSpec {
            soft_iron: [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
            ..MagnetometerSpec::default()
        }),
        Err(NoiseError::Singular { .. })
    ));
    assert!(
        MagnetometerNoise::new(MagnetometerSpec {
            hard_iron: [f64::NAN, 0.0, 0.0],
            ..MagnetometerSpec::default()
        })
        .is_err()
    );
}
