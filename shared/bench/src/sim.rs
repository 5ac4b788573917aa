//! `nauta bench sim`: how fast the simulator generates a scenario in-process
//! (truth and every sensor, no IPC), on one core. Issue target: the 45-minute
//! survey in under 2 s. See BENCHMARKS.md, "Simulator".

use std::time::Instant;

use anyhow::Context as _;
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
use serde_json::json;

/// Rounds per scenario; the median is reported.
const ROUNDS: usize = 3;
/// A cap far beyond every shipped mission's end, s.
const CAP_S: f64 = 4.0 * 3600.0;

/// Message counts of one generation.
#[derive(Debug, Default, Clone, Copy)]
struct Counts {
    steps: u64,
    imu: u64,
    ahrs: u64,
    dvl: u64,
    depth: u64,
    gps: u64,
    propeller: u64,
    modem: u64,
    lbl: u64,
}

impl Counts {
    fn total(&self) -> u64 {
        // The truth is one message per step.
        self.steps
            + self.imu
            + self.ahrs
            + self.dvl
            + self.depth
            + self.gps
            + self.propeller
            + self.modem
            + self.lbl
    }
}

/// One generation of `params` to the end of its mission: (wall s, simulated s, counts).
fn generate(params: &ScenarioParams, seed: u64) -> anyhow::Result<(f64, f64, Counts)> {
    let t0 = Instant::now();
    let mut g = Generator::new(
        params,
        Origin::lisbon(),
        params.sensors_preset(),
        seed,
        CAP_S,
    )?;
    // The LBL scenario needs pings to answer: one every 2 s, alternating
    // transponders (what a navigator would ask), registered at the step.
    let ids = g.suite().config().lbl.ids();
    let lbl_on = g.suite().config().lbl.enabled && !ids.is_empty();
    let mut c = Counts::default();
    while let Some(m) = g.step() {
        let m = m.context("the sensor suite failed")?;
        c.steps += 1;
        c.imu += u64::from(m.imu.is_some());
        c.ahrs += u64::from(m.ahrs.is_some());
        c.dvl += u64::from(m.dvl.is_some());
        c.depth += u64::from(m.depth.is_some());
        c.gps += u64::from(m.gps.is_some());
        c.propeller += u64::from(m.propeller.is_some());
        c.modem += u64::from(m.modem.is_some());
        c.lbl += m.lbl.len() as u64;
        if lbl_on && c.steps % 200 == 0 {
            let id = ids[(c.steps / 200) as usize % ids.len()];
            g.interrogate(id, m.stamp_ns)?;
        }
    }
    Ok((t0.elapsed().as_secs_f64(), g.t_s(), c))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs the benchmark and prints a table, or one JSON object with `--json`.
pub fn run(json: bool) -> anyhow::Result<()> {
    let scenarios = [
        ("survey", ScenarioKind::Survey, 1),
        ("lbl", ScenarioKind::Lbl, 1),
        ("dr1", ScenarioKind::Dr, 1),
        ("dr2", ScenarioKind::Dr, 2),
    ];
    let mut rows = Vec::new();
    for (name, kind, manoeuvre) in scenarios {
        let params = ScenarioParams {
            scenario: kind,
            dr_manoeuvre: manoeuvre,
            ..ScenarioParams::default()
        };
        let mut walls = Vec::new();
        let mut last = None;
        for round in 0..ROUNDS {
            if !json {
                eprint!("\rnauta bench sim: {name} round {}/{ROUNDS}   ", round + 1);
            }
            let (wall, sim_s, counts) = generate(&params, 7)?;
            walls.push(wall);
            last = Some((sim_s, counts));
        }
        let (sim_s, counts) = last.context("no round ran")?;
        rows.push((name, median(walls), sim_s, counts));
    }
    if !json {
        eprintln!();
    }
    let survey = rows[0];
    if json {
        let per: serde_json::Map<String, serde_json::Value> = rows
            .iter()
            .map(|(name, wall, sim_s, c)| {
                (
                    name.to_string(),
                    json!({
                        "generate_s": wall,
                        "sim_duration_s": sim_s,
                        "steps": c.steps,
                        "messages": c.total(),
                        "realtime_factor": sim_s / wall,
                        "counts": {
                            "imu": c.imu, "ahrs": c.ahrs, "dvl": c.dvl, "depth": c.depth,
                            "gps": c.gps, "propeller": c.propeller, "modem": c.modem,
                            "lbl": c.lbl, "truth": c.steps,
                        },
                    }),
                )
            })
            .collect();
        println!(
            "{}",
            json!({
                "survey_generate_s": survey.1,
                "survey_sim_duration_s": survey.2,
                "target_generate_s": 2.0,
                "rounds": ROUNDS,
                "scenarios": per,
            })
        );
    } else {
        println!(
            "scenario   simulated    generate   x real time   steps     messages   (median of {ROUNDS}, one core)"
        );
        for (name, wall, sim_s, c) in &rows {
            println!(
                "{name:<9} {:>8.1} s {:>9.3} s {:>12.0} {:>8} {:>11}",
                sim_s,
                wall,
                sim_s / wall,
                c.steps,
                c.total()
            );
        }
        println!(
            "survey: {:.1} min generated in {:.3} s (target < 2 s): {}",
            survey.2 / 60.0,
            survey.1,
            if survey.1 < 2.0 { "met" } else { "NOT met" }
        );
    }
    Ok(())
}
