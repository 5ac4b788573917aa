//! `nauta-sensor`: the data source of a run. It runs a scenario of the
//! simulator ([`nauta_sim::scenario`]: survey, lbl, dr, attitude motions) and
//! publishes the truth and every simulated sensor at its own rate (DESIGN §4):
//! in `sim` clock as fast as the pipeline consumes (back-pressured,
//! deterministic), in `wall` clock paced to real time or a multiple of it. It
//! answers LBL interrogations in closed loop ([`lbl_link`]). With `--from
//! FILE` it replays a recording instead ([`replay`]).

use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use clap::Parser;
use nauta_messages::*;
use nauta_runtime::process::{ProcessArgs, service_main_checked};
use nauta_runtime::{Context, ControlServer, Describe, HealthReporter, Lifecycle, Manifest, Pacer};
use nauta_sim::mission::Origin;
use nauta_sim::scenario::Generator;

mod lbl_link;
mod outputs;
mod replay;

use lbl_link::{LblLink, Waited};
use nauta_sim::params::SensorParams;
use outputs::Outputs;

/// Publishes the sensors and the truth of a simulated mission.
#[derive(Debug, Parser)]
#[command(name = "nauta-sensor", version, about)]
struct Args {
    #[command(flatten)]
    process: ProcessArgs,
    /// Replay this recording (MCAP) instead of simulating: its sensor channels
    /// and truth, with their stamps (`nauta replay FILE` sets this up).
    #[arg(long, value_name = "FILE")]
    from: Option<std::path::PathBuf>,
}

/// Steps published between two flushes (one wake-up of the consumers).
pub(crate) const BATCH: u64 = 32;

/// How far the manifest's `[site] magnetic_declination_deg` may be from the
/// World Magnetic Model's before the sensor warns, degrees.
const DECLINATION_TOLERANCE_DEG: f64 = 0.2;

fn describe() -> Describe {
    Describe {
        role: Role::Sensor.name().into(),
        inputs: lbl_link::describe(),
        outputs: outputs::describe(),
        variants: vec!["sim".into()],
        source: true,
    }
}

fn main() -> ExitCode {
    let args = Args::parse();
    let from = args.from.clone();
    service_main_checked(
        Role::Sensor,
        "sim",
        &args.process,
        describe,
        |t| match &from {
            Some(f) => std::fs::metadata(f)
                .map(|_| ())
                .with_context(|| format!("cannot replay {}", f.display())),
            None => setup(&t.manifest, &t.process, &t.variant).map(|_| ()),
        },
        |ctx| match &from {
            Some(f) => replay::serve(ctx, f),
            None => serve(ctx),
        },
    )
}

/// Answers control requests (the shell's [`Lifecycle`] of a source): true if
/// STOP was asked.
pub(crate) fn serve_control(
    control: &mut ControlServer,
    ctx: &Context,
    last_stamp: u64,
) -> anyhow::Result<bool> {
    let mut life = Lifecycle::source(ctx);
    life.standby = false;
    life.serve(ctx, control, last_stamp, Some(last_stamp))?;
    Ok(life.stop)
}

/// Everything the sensor reads from the manifest, checked.
struct Setup {
    params: SensorParams,
    generator: Generator,
    duration_s: f64,
    seed: u64,
}

/// Reads and checks this process's manifest section and builds the scenario
/// (what `--check` validates and `serve` runs).
fn setup(manifest: &Manifest, process: &str, variant: &str) -> anyhow::Result<Setup> {
    let place = format!("{}: process.{process}.params", manifest.path.display());
    let table: toml::Table = manifest.params(process, Some(variant))?;
    let listed = table
        .get("sensors")
        .and_then(|s| s.get("lbl"))
        .and_then(|l| l.get("transponders"))
        .is_some();
    let mut params = SensorParams::from_table(table, &place)?;
    let site = manifest.site.clone().with_context(|| {
        format!(
            "{}: the manifest has no [site] (latitude_deg, longitude_deg)",
            manifest.path.display()
        )
    })?;
    // The simulator's transponders are the site's (what the vehicle is told
    // of its acoustic field is the field it gets).
    if !site.transponders.is_empty() {
        if listed {
            anyhow::bail!(
                "{place}.sensors.lbl.transponders: the site's transponders ([site] or lbl_layout) are the simulator's; give them once"
            );
        }
        params.sensors.lbl.transponders = site.transponders.clone();
    }
    let (duration_s, seed) = (manifest.run.duration_s, manifest.run.seed);
    let origin = Origin::from_degrees(site.latitude_deg, site.longitude_deg);
    let generator = Generator::new(
        &params.scenario,
        origin,
        params.sensors.clone(),
        seed,
        duration_s,
    )
    .with_context(|| format!("{place}: cannot build the scenario"))?;
    let wmm_declination_deg = generator
        .simulator()
        .environment()
        .magnetic
        .declination_rad
        .to_degrees();
    if (wmm_declination_deg - site.magnetic_declination_deg).abs() > DECLINATION_TOLERANCE_DEG {
        tracing::warn!(
            manifest = site.magnetic_declination_deg,
            wmm = wmm_declination_deg,
            "[site] magnetic_declination_deg differs from the World Magnetic Model's value the simulator uses; estimators will see a heading error"
        );
    }
    Ok(Setup {
        params,
        generator,
        duration_s,
        seed,
    })
}

fn serve(ctx: &mut Context) -> anyhow::Result<()> {
    let Setup {
        params,
        mut generator,
        duration_s,
        seed,
    } = setup(ctx.manifest()?, &ctx.process, &ctx.variant)?;
    let lbl_enabled = params.sensors.lbl.enabled;
    let tick_ns = nauta_sim::suite::stamp_ns(params.sensors.lbl.noise.clock_resolution);

    let mut out = Outputs::open(ctx)?;
    let lockstep = ctx.clock.is_lossless() && lbl_enabled;
    let mut link = LblLink::open(ctx, params.lbl_sync_hz, tick_ns, lockstep)?;
    let mut health = HealthReporter::new(ctx)?;
    let mut pacer = Pacer::new(ctx.clock);
    // Requests are polled once per batch (a source never blocks on inputs).
    let (mut control, control_inbox) = ControlServer::open(ctx)?;
    drop(control_inbox);
    ctx.ready();
    if ctx.standby && !hold_until_activated(ctx, &mut control, &mut health)? {
        return Ok(());
    }
    // Every process is ready now: an interrogator's publishers exist.
    link.connect()?;
    health.state = state::RUNNING;
    let span = tracing::info_span!("sensor", process = %ctx.process, clock = ctx.clock.name());
    let _e = span.enter();
    tracing::info!(
        scenario = params.scenario.scenario.name(),
        duration_s,
        seed,
        interrogator = link.interrogator_present(),
        "publishing"
    );

    let mut last_health = Instant::now();
    let mut last_stamp = 0;
    let mut stopped = false;
    let mut steps = 0u64;
    while let Some(m) = generator.step() {
        let m = m?;
        last_stamp = m.stamp_ns;
        let wait = pacer.delay_for(m.stamp_ns);
        if !wait.is_zero() {
            out.flush();
            if !ctx.sleep(wait) {
                stopped = true;
                break;
            }
        }
        out.publish(&m)?;
        steps += 1;
        if lbl_enabled && let Some(w) = link.sync_point(m.stamp_ns) {
            let published = out.published();
            out.progress
                .publish(Progress::at(w, Role::Sensor, published))?;
            if lockstep && link.interrogator_present() {
                out.flush();
                let waited = link.wait_for(ctx, w, || {
                    serve_control(&mut control, ctx, last_stamp).map(|stop| !stop)
                })?;
                if waited == Waited::Terminated {
                    stopped = true;
                    break;
                }
                link.drain(&mut generator, m.stamp_ns, lbl_enabled, &mut health)?;
            }
        }
        // Wall clock: pings are registered as they come, at the next step (a
        // receive on an empty input is a shared-memory read). Without LBL they
        // are only counted as rejected, once per batch.
        if !lockstep && (lbl_enabled || steps.is_multiple_of(BATCH)) {
            link.drain(&mut generator, m.stamp_ns, lbl_enabled, &mut health)?;
        }
        if steps.is_multiple_of(BATCH) {
            // Without the LBL lockstep (whose sync points are the
            // watermarks), a watermark per batch: every channel of this step
            // is published, so nothing at or before it will come. A consumer
            // of a sparse channel (GPS at the surface, the buoy every 30 s)
            // then processes its other inputs without waiting for it.
            if !lbl_enabled {
                let published = out.published();
                out.progress
                    .publish(Progress::at(last_stamp + 1, Role::Sensor, published))?;
            }
            out.flush();
            if serve_control(&mut control, ctx, last_stamp)? || ctx.termination_requested() {
                stopped = true;
                break;
            }
            if last_health.elapsed() >= Duration::from_secs(1) {
                last_health = Instant::now();
                health.outputs = out.published();
                health.dropped = out.given_up() + link.timed_out;
                health.last_stamp_ns = last_stamp;
                health.publish(ctx);
                ctx.cleanup_dead_nodes();
            }
        }
    }
    out.flush();
    // End of stream: nothing more will come from this source.
    let published = out.published();
    out.progress
        .publish_now(Progress::end_of_stream(last_stamp, Role::Sensor, published))?;
    health.state = state::STOPPED;
    health.outputs = out.published();
    health.dropped = out.given_up() + link.timed_out;
    health.last_stamp_ns = last_stamp;
    health.publish(ctx);
    let stats = generator.suite().stats();
    tracing::info!(
        counts = ?out.counts(),
        simulated_s = generator.t_s(),
        interrogations = link.accepted,
        late_interrogations = link.late,
        interrogator_timeouts = link.timed_out,
        lbl_no_reply = stats.lbl_no_reply,
        lbl_multipath = stats.lbl_multipath,
        given_up = out.given_up(),
        stopped_by_signal = stopped,
        "done"
    );
    Ok(())
}

/// Started with `--standby`, a source waits for the launcher's ACTIVATE
/// (the shell's [`Lifecycle::hold_until_activated`]). False on STOP or a
/// termination signal.
pub(crate) fn hold_until_activated(
    ctx: &Context,
    control: &mut ControlServer,
    health: &mut HealthReporter,
) -> anyhow::Result<bool> {
    Lifecycle::source(ctx).hold_until_activated(ctx, control, health)
}
