//! Development loop for the positioning (issue 14): the error budget and
//! the tuning of `BENCHMARKS.md`, "Acoustic positioning: error budget".
//!
//! Records per survey seed the aided INS's solutions without fixes and the
//! positioning's sensor inputs per modem case, then replays positioning
//! configurations over them in process (a fraction of a second each, where
//! the complete system's bench takes minutes). The aided INS here takes no
//! fix: its solution at a stamp is approximated by the last buoy fix plus
//! the INS's own drift since (the ains resets to each fix, `fix_reset`,
//! and the fixes do not change its velocity); the EKF's figures agree with
//! `nauta bench nav --complete --seeds 7-9` to a few centimetres, the PF's
//! only in the mean over particle seeds (its random stream differs).
//!
//! ```sh
//! cargo run --release -p nauta-bench --example posdev -- SEEDS CASES VARIANT[:JSON] ...
//! cargo run --release -p nauta-bench --example posdev -- 7,8,9 clean,jitteronly,nominal ekf 'pf:{"seed":1}'
//! ```
//!
//! `SEEDS` a list (development: 7,8,9), `CASES` a list of modem cases (see
//! `tweak`: `nominal`, the robustness cases `loss`, `sound`, `buoy5`,
//! `multipath`, `all`, and for the budget `clean` (no modem error),
//! `jitteronly`, `soundonly`, `buoyonly`, `nojitter`, `halfjitter` (0.5
//! ms), `nosound`, `nobuoygps`), each `VARIANT` `pf` or `ekf` with its parameters as JSON.
//! Per seed and the mean: the buoy fixes' N/E RMS and truth inside their
//! 95 % region, the approximated `ains/nav` N/E and horizontal RMS, the
//! first and last third of the dive. `TRACE=1` prints every fix, `VEL=1`
//! the INS's velocity error per 10 s instead.

use anyhow::Context as _;
use nauta_bench::nav::complete::positioning_inputs;
use nauta_bench::nav::{StepInputs, site, survey_attitude, variant_cores};
use nauta_estimation::Estimator;
use nauta_estimation::local::flat;
use nauta_estimation::positioning::{
    Positioning, PositioningEkfParams, PositioningInput, PositioningPfParams, source,
};
use nauta_estimation::readings::{Fix, Nav};
use nauta_messages::NavSolution;
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioParams};
use nauta_sim::suite::SuiteConfig;

struct Base {
    /// Per step: truth lat, lon; unaided nav error n, e (NaN before a nav).
    truth: Vec<[f64; 2]>,
    nav_err: Vec<[f64; 2]>,
    nav_vel_err: Vec<[f64; 2]>,
    nav: Vec<Option<Nav>>,
    stamps: Vec<u64>,
}

struct CaseRec {
    /// Per step: early and late inputs.
    early: Vec<Vec<PositioningInput>>,
    late: Vec<Vec<PositioningInput>>,
    /// Per step with a modem message: true range excess (outlier).
    outlier: Vec<bool>,
}

fn tweak(case: &str, s: &mut SuiteConfig) -> anyhow::Result<()> {
    match case {
        "nominal" => {}
        "loss" => s.modem.noise.loss_probability = 0.3,
        "sound" => s.modem.noise.sound_speed_error = 0.01,
        "buoy5" => s.modem.buoy_gps_sigma_m = 5.0,
        "multipath" => s.modem.noise.multipath_probability = 0.02,
        "all" => {
            s.modem.noise.loss_probability = 0.3;
            s.modem.noise.sound_speed_error = 0.01;
            s.modem.buoy_gps_sigma_m = 5.0;
            s.modem.noise.multipath_probability = 0.02;
        }
        "clean" => {
            s.modem.buoy_gps_sigma_m = 0.0;
            s.modem.noise.clock_jitter_sigma = 0.0;
            s.modem.noise.sound_speed_error = 0.0;
        }
        "jitteronly" => {
            s.modem.buoy_gps_sigma_m = 0.0;
            s.modem.noise.sound_speed_error = 0.0;
        }
        "soundonly" => {
            s.modem.buoy_gps_sigma_m = 0.0;
            s.modem.noise.clock_jitter_sigma = 0.0;
        }
        "buoyonly" => {
            s.modem.noise.clock_jitter_sigma = 0.0;
            s.modem.noise.sound_speed_error = 0.0;
        }
        "nobuoygps" => s.modem.buoy_gps_sigma_m = 0.0,
        "nojitter" => s.modem.noise.clock_jitter_sigma = 0.0,
        "halfjitter" => s.modem.noise.clock_jitter_sigma = 0.5e-3,
        "nosound" => s.modem.noise.sound_speed_error = 0.0,
        _ => return Err(anyhow::anyhow!("unknown case {case}")),
    }
    Ok(())
}

fn err_of(truth: [f64; 2], lat: f64, lon: f64) -> [f64; 2] {
    let (n, e) = flat::to_local(truth[0], truth[1], lat, lon);
    [n, e]
}

fn base(seed: u64) -> anyhow::Result<Base> {
    let survey = ScenarioParams::default();
    let sensors = survey.sensors_preset();
    let site = site(&survey, sensors.clone(), seed)?;
    let mut ains = variant_cores(site, false)?.swap_remove(0);
    let mut attitude = survey_attitude()?;
    let mut g = Generator::new(&survey, Origin::lisbon(), sensors, seed, 1e6)?;
    let mut si = StepInputs::default();
    let mut wire = Vec::new();
    let mut b = Base {
        truth: vec![],
        nav_err: vec![],
        nav_vel_err: vec![],
        nav: vec![],
        stamps: vec![],
    };
    let mut out = Vec::new();
    while let Some(step) = g.step() {
        let step = step?;
        wire.clear();
        nauta_sim::wire::to_wire(&step, &mut wire);
        si.collect(&wire, Some(&mut attitude), |_| Ok(()))?;
        out.clear();
        for i in si.inputs() {
            let _ = ains.on_input(i, &mut out);
        }
        let t = [step.truth.lat_rad, step.truth.lon_rad];
        b.truth.push(t);
        b.stamps.push(step.stamp_ns);
        let n = out
            .last()
            .and_then(|n| Nav::try_from(&NavSolution::from(n)).ok());
        anyhow::ensure!(out.len() <= 1, "more than one nav per step");
        match n {
            Some(n) => {
                b.nav_err.push(err_of(t, n.lat_rad, n.lon_rad));
                let v = n.vel_ned_m_s.to_array();
                b.nav_vel_err.push([
                    v[0] - step.truth.vel_ned_m_s[0],
                    v[1] - step.truth.vel_ned_m_s[1],
                ]);
            }
            None => {
                b.nav_err.push([f64::NAN; 2]);
                b.nav_vel_err.push([f64::NAN; 2]);
            }
        }
        b.nav.push(n);
    }
    Ok(b)
}

fn case(seed: u64, name: &str) -> anyhow::Result<CaseRec> {
    let survey = ScenarioParams::default();
    let mut sensors = survey.sensors_preset();
    tweak(name, &mut sensors)?;
    let mut g = Generator::new(&survey, Origin::lisbon(), sensors, seed, 1e6)?;
    let mut wire = Vec::new();
    let mut r = CaseRec {
        early: vec![],
        late: vec![],
        outlier: vec![],
    };
    while let Some(step) = g.step() {
        let step = step?;
        wire.clear();
        nauta_sim::wire::to_wire(&step, &mut wire);
        let (early, late) = positioning_inputs(&wire, step.stamp_ns);
        r.outlier.push(
            step.modem
                .as_ref()
                .is_some_and(|m| m.time_of_flight_s * m.sound_speed_m_s > m.true_range_m + 15.0),
        );
        r.early.push(early);
        r.late.push(late);
    }
    Ok(r)
}

#[derive(Default, Debug, Clone)]
struct Score {
    fix_sq: [f64; 2],
    fix_n: f64,
    fix_in: f64,
    fix_all_n: f64,
    fix_all_in: f64,
    nav_sq: [f64; 2],
    nav_n: f64,
    thirds: [f64; 2],
    outliers: u64,
    refused: u64,
    nees: f64,
}

fn inside(e: [f64; 2], f: &Fix) -> (bool, f64) {
    let (a, b, r) = (f.std_north_m, f.std_east_m, f.corr_ne);
    let (x, y) = (e[0] / a, e[1] / b);
    let m = (x * x - 2.0 * r * x * y + y * y) / (1.0 - r * r);
    (m <= 5.991, m)
}

fn replay(b: &Base, c: &CaseRec, pos: &mut Positioning, trace: bool) -> Score {
    let mut s = Score::default();
    let mut out = Vec::new();
    // Last buoy fix: (step, error)
    let mut last: Option<(usize, [f64; 2])> = None;
    let mut surfaced_after = false;
    let mut nav_e: Vec<(f64, [f64; 2])> = Vec::new();
    let mut dive: Option<(f64, f64)> = None;
    for i in 0..b.truth.len() {
        let mut feed = |inp: &PositioningInput, s: &mut Score, out: &mut Vec<Fix>| {
            out.clear();
            let refused = pos.on_input(inp, out).is_err();
            if matches!(inp, PositioningInput::Modem(_)) && c.outlier[i] {
                s.outliers += 1;
                s.refused += u64::from(refused);
            }
            for f in out.iter() {
                let e = err_of(b.truth[i], f.lat_rad, f.lon_rad);
                let (ins, m) = inside(e, f);
                s.fix_all_n += 1.0;
                s.fix_all_in += f64::from(u8::from(ins));
                if f.source == source::BUOY {
                    s.fix_sq[0] += e[0] * e[0];
                    s.fix_sq[1] += e[1] * e[1];
                    s.fix_n += 1.0;
                    s.fix_in += f64::from(u8::from(ins));
                    s.nees += m;
                    last = Some((i, e));
                    let t = f.stamp_ns as f64 * 1e-9;
                    dive = Some((dive.map_or(t, |d| d.0), t));
                    if trace {
                        eprintln!(
                            "{t:7.1} fix err {:6.2} {:6.2} std {:5.2} {:5.2} corr {:5.2} m2 {:5.2}",
                            e[0], e[1], f.std_north_m, f.std_east_m, f.corr_ne, m
                        );
                    }
                } else if f.source == source::GPS && last.is_some() {
                    surfaced_after = true;
                    last = Some((i, e));
                }
            }
        };
        for inp in &c.early[i] {
            feed(inp, &mut s, &mut out);
        }
        if let Some(n) = &b.nav[i] {
            feed(&PositioningInput::Nav(*n), &mut s, &mut out);
        }
        for inp in &c.late[i] {
            feed(inp, &mut s, &mut out);
        }
        let u = b.nav_err[i];
        if u[0].is_nan() {
            continue;
        }
        let e = match last {
            Some((_, f)) if surfaced_after => f,
            Some((k, f)) => {
                let uk = b.nav_err[k];
                [f[0] + u[0] - uk[0], f[1] + u[1] - uk[1]]
            }
            _ => u,
        };
        s.nav_sq[0] += e[0] * e[0];
        s.nav_sq[1] += e[1] * e[1];
        s.nav_n += 1.0;
        nav_e.push((b.stamps[i] as f64 * 1e-9, e));
    }
    if let Some((from, to)) = dive {
        let third = (to - from) / 3.0;
        let rms = |a: f64, z: f64| {
            let v: Vec<f64> = nav_e
                .iter()
                .filter(|x| x.0 >= a && x.0 < z)
                .map(|x| x.1[0].powi(2) + x.1[1].powi(2))
                .collect();
            (v.iter().sum::<f64>() / v.len().max(1) as f64).sqrt()
        };
        s.thirds = [rms(from, from + third), rms(to - third, to + 1e-9)];
    }
    s
}

fn make(spec: &str) -> anyhow::Result<Positioning> {
    let (v, j) = spec.split_once(':').unwrap_or((spec, "{}"));
    match v {
        "pf" => Positioning::pf(&serde_json::from_str::<PositioningPfParams>(j)?),
        "ekf" => Positioning::ekf(&serde_json::from_str::<PositioningEkfParams>(j)?),
        _ => anyhow::bail!("variant {v}"),
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    anyhow::ensure!(
        args.len() >= 3,
        "usage: posdev SEEDS CASES VARIANT[:JSON] ..."
    );
    let seeds: Vec<u64> = args[0]
        .split(',')
        .map(|x| x.parse().with_context(|| format!("seed {x:?}")))
        .collect::<anyhow::Result<_>>()?;
    let cases: Vec<String> = args[1].split(',').map(String::from).collect();
    let specs = &args[2..];
    let trace = std::env::var("TRACE").is_ok();
    let velocity = std::env::var("VEL").is_ok();
    let jobs: Vec<u64> = seeds.clone();
    let bases: Vec<Base> = std::thread::scope(|sc| {
        let hs: Vec<_> = jobs.iter().map(|&s| sc.spawn(move || base(s))).collect();
        hs.into_iter()
            .map(|h| h.join().expect("a replay thread panicked"))
            .collect::<anyhow::Result<_>>()
    })?;
    if velocity {
        for (seed, b) in seeds.iter().zip(&bases) {
            // per 10 s: mean velocity error, nav velocity
            let mut k = 0;
            while k + 1000 <= b.truth.len() {
                let (mut m, mut v, mut n) = ([0.0; 2], [0.0; 2], 0.0);
                for i in k..k + 1000 {
                    if let Some(nv) = &b.nav[i] {
                        let e = b.nav_vel_err[i];
                        m[0] += e[0];
                        m[1] += e[1];
                        let vv = nv.vel_ned_m_s.to_array();
                        v[0] += vv[0];
                        v[1] += vv[1];
                        n += 1.0;
                    }
                }
                if n > 0.0 {
                    println!(
                        "{seed} {:.0} {:.5} {:.5} {:.3} {:.3}",
                        b.stamps[k] as f64 * 1e-9,
                        m[0] / n,
                        m[1] / n,
                        v[0] / n,
                        v[1] / n
                    );
                }
                k += 1000;
            }
        }
        return Ok(());
    }
    for case_name in &cases {
        let recs: Vec<CaseRec> = std::thread::scope(|sc| {
            let hs: Vec<_> = seeds
                .iter()
                .map(|&s| sc.spawn(move || case(s, case_name)))
                .collect();
            hs.into_iter()
                .map(|h| h.join().expect("a replay thread panicked"))
                .collect::<anyhow::Result<_>>()
        })?;
        for spec in specs {
            let mut tot = [0.0; 8];
            for (k, (b, c)) in bases.iter().zip(&recs).enumerate() {
                let mut p = make(spec).context("spec")?;
                let t0 = std::time::Instant::now();
                let s = replay(b, c, &mut p, trace);
                let el = t0.elapsed().as_secs_f64();
                let f = [
                    (s.fix_sq[0] / s.fix_n).sqrt(),
                    (s.fix_sq[1] / s.fix_n).sqrt(),
                ];
                let nv = [
                    (s.nav_sq[0] / s.nav_n).sqrt(),
                    (s.nav_sq[1] / s.nav_n).sqrt(),
                ];
                println!(
                    "{case_name:9} seed {:3} {spec:40} fix {:.2}/{:.2} in95 {:.0}% (all {:.0}%) nees {:.2} | nav {:.2}/{:.2} h {:.2} thirds {:.2}->{:.2} | outl {}/{} | {:.2}s",
                    seeds[k],
                    f[0],
                    f[1],
                    100.0 * s.fix_in / s.fix_n,
                    100.0 * s.fix_all_in / s.fix_all_n,
                    s.nees / s.fix_n,
                    nv[0],
                    nv[1],
                    nv[0].hypot(nv[1]),
                    s.thirds[0],
                    s.thirds[1],
                    s.refused,
                    s.outliers,
                    el
                );
                for (t, v) in tot.iter_mut().zip([
                    f[0],
                    f[1],
                    100.0 * s.fix_in / s.fix_n,
                    nv[0],
                    nv[1],
                    nv[0].hypot(nv[1]),
                    s.thirds[1] / s.thirds[0],
                    100.0 * s.fix_all_in / s.fix_all_n,
                ]) {
                    *t += v / seeds.len() as f64;
                }
            }
            println!(
                "{case_name:9} MEAN     {spec:40} fix {:.2}/{:.2} in95 {:.0}% (all {:.0}%) | nav {:.2}/{:.2} h {:.2} | thirds ratio {:.2}",
                tot[0], tot[1], tot[2], tot[7], tot[3], tot[4], tot[5], tot[6]
            );
        }
    }
    Ok(())
}
