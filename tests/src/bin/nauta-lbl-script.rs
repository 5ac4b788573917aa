//! `nauta-lbl-script`: a scripted LBL interrogator for the tests, standing in
//! for the LBL navigator until it exists. It follows the binary contract
//! (DESIGN §5) as the `lbl` role: at every sensor watermark at or after its
//! next ping time it pings the next transponder in turn, stamped with that
//! watermark, then publishes its own watermark (the synchronisation rule of
//! services/sensor/src/lbl_link.rs). At the end of the sensor's stream it
//! writes a JSON report of its pings, the replies and the true vehicle
//! positions at the ping and reply instants, for the test to check.
//!
//! Parameters (`[process.NAME.params]`): `report` (path, required),
//! `ping_every_s` (default 2), `transponders` (ids to ping in turn, default [1, 2]).

use std::collections::VecDeque;
use std::ops::ControlFlow;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use clap::Parser;
use nauta_messages::*;
use nauta_runtime::process::{ProcessArgs, service_main};
use nauta_runtime::{Context, Describe, EventLoop, HealthReporter, PortDescription, services};
use serde::{Deserialize, Serialize};

#[derive(Debug, Parser)]
#[command(name = "nauta-lbl-script", about = "Scripted LBL interrogator (tests)")]
struct Args {
    #[command(flatten)]
    process: ProcessArgs,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Params {
    report: String,
    #[serde(default = "default_every")]
    ping_every_s: f64,
    #[serde(default = "default_ids")]
    transponders: Vec<u32>,
}

fn default_every() -> f64 {
    2.0
}

fn default_ids() -> Vec<u32> {
    vec![1, 2]
}

/// A true position: stamp, latitude, longitude (rad), depth (m).
type Fix = (u64, f64, f64, f64);

/// What the test reads.
#[derive(Debug, Default, Serialize)]
struct Report {
    /// (transponder id, stamp) of every ping sent.
    pings: Vec<(u32, u64)>,
    /// Every reply: (id, interrogation stamp, reply stamp, round trip s).
    replies: Vec<(u32, u64, u64, f64)>,
    /// The truth at each ping stamp (exact step).
    ping_truth: Vec<Fix>,
    /// The truth at each reply stamp, interpolated between the two steps around it.
    reply_truth: Vec<Fix>,
    /// Sensor watermarks seen.
    watermarks: u64,
}

fn describe() -> Describe {
    Describe {
        role: Role::Lbl.name().into(),
        inputs: vec![
            PortDescription::of(&services::progress(Role::Sensor)),
            PortDescription::of(&services::lbl_reply()),
            PortDescription::of(&services::truth()),
        ],
        outputs: vec![
            PortDescription::of(&services::lbl_interrogate()),
            PortDescription::of(&services::progress(Role::Lbl)),
        ],
        variants: vec!["script".into()],
        source: false,
    }
}

fn main() -> ExitCode {
    let args = Args::parse();
    service_main(Role::Lbl, "script", &args.process, describe, serve)
}

fn at(truth: &VecDeque<TruthState>, stamp: u64) -> Option<Fix> {
    let i = truth.iter().position(|t| t.header.stamp_ns >= stamp)?;
    let b = &truth[i];
    if b.header.stamp_ns == stamp || i == 0 {
        return Some((stamp, b.lat_rad, b.lon_rad, b.depth_m));
    }
    let a = &truth[i - 1];
    let f = (stamp - a.header.stamp_ns) as f64 / (b.header.stamp_ns - a.header.stamp_ns) as f64;
    let lerp = |x: f64, y: f64| x + (y - x) * f;
    Some((
        stamp,
        lerp(a.lat_rad, b.lat_rad),
        lerp(a.lon_rad, b.lon_rad),
        lerp(a.depth_m, b.depth_m),
    ))
}

fn serve(ctx: &mut Context) -> anyhow::Result<()> {
    let params: Params = ctx.params()?;
    anyhow::ensure!(!params.transponders.is_empty(), "no transponders to ping");
    let every_ns = (params.ping_every_s * 1e9) as u64;
    let (mut progress_in, progress_inbox) = ctx.subscriber(&services::progress(Role::Sensor))?;
    let (mut replies_in, replies_inbox) = ctx.subscriber(&services::lbl_reply())?;
    let (mut truth_in, truth_inbox) = ctx.subscriber(&services::truth())?;
    let mut ping_out = ctx.publisher(&services::lbl_interrogate())?;
    let mut progress_out = ctx.publisher(&services::progress(Role::Lbl))?;
    let mut health = HealthReporter::new(ctx)?;
    if !ctx.connect_and_ready(&[&progress_in, &replies_in, &truth_in])? {
        return Ok(());
    }
    let mut report = Report::default();
    let mut truth: VecDeque<TruthState> = VecDeque::new();
    let mut waiting: Vec<(u32, u64, u64, f64)> = Vec::new();
    let mut next_ping = every_ns;
    let mut turn = 0usize;
    EventLoop::new(Duration::from_secs(1)).run(
        &[&progress_inbox, &replies_inbox, &truth_inbox],
        |wake| {
            if wake == nauta_runtime::Wake::Tick {
                health.outputs = ping_out.published();
                health.publish(ctx);
            }
            // Watermarks first: whatever the sensor published before one is
            // already queued on the other inputs.
            let mut marks = Vec::new();
            let mut ended = false;
            progress_in.drain(|p| {
                if p.header.is_end_of_stream() {
                    ended = true;
                } else {
                    marks.push(p.header.stamp_ns);
                }
            })?;
            truth_in.drain(|t| truth.push_back(t))?;
            replies_in.drain(|r| {
                report.replies.push((
                    r.transponder_id,
                    r.interrogation_stamp_ns,
                    r.header.stamp_ns,
                    r.round_trip_s,
                ));
                waiting.push((
                    r.transponder_id,
                    r.interrogation_stamp_ns,
                    r.header.stamp_ns,
                    r.round_trip_s,
                ));
            })?;
            // Truth around the replies (a reply stamp lies at most one step
            // before the latest truth).
            let newest = truth.back().map_or(0, |t| t.header.stamp_ns);
            waiting.retain(|r| {
                if r.2 <= newest {
                    if let Some(f) = at(&truth, r.2) {
                        report.reply_truth.push(f);
                    }
                    false
                } else {
                    true
                }
            });
            for w in marks {
                report.watermarks += 1;
                if w >= next_ping {
                    let id = params.transponders[turn % params.transponders.len()];
                    turn += 1;
                    next_ping = w + every_ns;
                    ping_out.publish(LblInterrogation {
                        header: Header::new(w, 0, Role::Lbl, 0),
                        transponder_id: id,
                        pad: 0,
                    })?;
                    report.pings.push((id, w));
                    if let Some(f) = at(&truth, w) {
                        report.ping_truth.push(f);
                    }
                }
                ping_out.flush();
                progress_out.publish_now(Progress::at(w, Role::Lbl, ping_out.published()))?;
            }
            while truth.len() > 4000 {
                truth.pop_front();
            }
            if ended {
                progress_out.publish_now(Progress::end_of_stream(
                    newest,
                    Role::Lbl,
                    ping_out.published(),
                ))?;
                return Ok(ControlFlow::Break(()));
            }
            Ok(ControlFlow::Continue(()))
        },
    )?;
    health.state = state::STOPPED;
    health.publish(ctx);
    std::fs::write(&params.report, serde_json::to_string(&report)?)
        .with_context(|| format!("cannot write {}", params.report))?;
    Ok(())
}
