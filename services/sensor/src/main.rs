//! `nauta-sensor`: the data source of a run. For now it publishes the scripted
//! mission of [`scripted`] (IMU, depth and truth); the full simulator, replay and
//! import come with their own issues.

use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use clap::Parser;
use nauta_messages::*;
use nauta_runtime::process::{ProcessArgs, service_main};
use nauta_runtime::{
    Context, ControlServer, Describe, HealthReporter, Pacer, PortDescription, services,
};

mod scripted;

use scripted::{Script, ScriptParams};

/// Publishes the sensors and the truth of a simulated mission.
#[derive(Debug, Parser)]
#[command(name = "nauta-sensor", version, about)]
struct Args {
    #[command(flatten)]
    process: ProcessArgs,
}

/// Samples published between two flushes (one wake-up of the consumers).
const BATCH: u64 = 32;

fn describe() -> Describe {
    Describe {
        role: Role::Sensor.name().into(),
        inputs: vec![],
        outputs: vec![
            PortDescription::of(&services::imu()),
            PortDescription::of(&services::depth()),
            PortDescription::of(&services::truth()),
            PortDescription::of(&services::progress(Role::Sensor)),
        ],
        variants: vec!["scripted".into()],
    }
}

fn main() -> ExitCode {
    let args = Args::parse();
    service_main(Role::Sensor, "scripted", &args.process, describe, serve)
}

fn serve(ctx: &mut Context) -> anyhow::Result<()> {
    let params: ScriptParams = ctx.params()?;
    let manifest = ctx.manifest()?;
    let site = manifest
        .site
        .context("the manifest has no [site] (latitude_deg, longitude_deg)")?;
    let duration_s = manifest.run.duration_s;
    let seed = manifest.run.seed;
    let mut script = Script::new(
        params,
        site.latitude_deg.to_radians(),
        site.longitude_deg.to_radians(),
        seed,
    )?;
    let steps = (duration_s / script.dt_s()).round() as u64;
    let depth_every = script.depth_every();

    let mut imu = ctx.publisher(&services::imu())?;
    let mut depth = ctx.publisher(&services::depth())?;
    let mut truth = ctx.publisher(&services::truth())?;
    let mut progress = ctx.publisher(&services::progress(Role::Sensor))?;
    let mut health = HealthReporter::new(ctx)?;
    let mut pacer = Pacer::new(ctx.clock);
    // Requests are polled once per batch (a source never blocks on inputs).
    let (mut control, control_inbox) = ControlServer::open(ctx)?;
    drop(control_inbox);
    ctx.ready();
    if ctx.standby && !hold_until_activated(ctx, &mut control, &mut health)? {
        return Ok(());
    }
    health.state = state::RUNNING;
    let span = tracing::info_span!("sensor", process = %ctx.process, clock = ctx.clock.name());
    let _e = span.enter();
    tracing::info!(steps, duration_s, "publishing");

    let mut last_health = Instant::now();
    let mut last_stamp = 0;
    let mut stopped = false;
    for k in 1..=steps {
        let s = script.step();
        last_stamp = s.stamp_ns;
        let wait = pacer.delay_for(s.stamp_ns);
        if !wait.is_zero() {
            imu.flush();
            depth.flush();
            truth.flush();
            if !ctx.sleep(wait) {
                stopped = true;
                break;
            }
        }
        let header = Header::new(s.stamp_ns, 0, Role::Sensor, 0);
        truth.publish(TruthState {
            header,
            lat_rad: s.lat_rad,
            lon_rad: s.lon_rad,
            depth_m: s.depth_m,
            vel_ned_m_s: s.vel_ned.into(),
            quat_nb: quat(&s.q_nb),
            rate_nb_body_rad_s: s.rate_nb_body.into(),
            current_ned_m_s: [0.0; 3],
            distance_m: s.distance_m,
        })?;
        imu.publish(ImuSample {
            header,
            gyro_rad_s: s.gyro.into(),
            accel_m_s2: s.accel.into(),
            mag_ut: s.mag.into(),
            interval_s: s.dt_s,
        })?;
        if k % depth_every == 0 {
            depth.publish(DepthSample {
                header,
                depth_m: s.depth_measured_m,
            })?;
        }
        if k % BATCH == 0 {
            truth.flush();
            imu.flush();
            depth.flush();
            let mut stop_requested = false;
            control.serve(|req| {
                let status = match req.command {
                    command::STOP => {
                        stop_requested = true;
                        0
                    }
                    _ => 2,
                };
                ControlResponse {
                    header: Header::new(last_stamp, 0, Role::Sensor, 0),
                    status,
                    state: state::RUNNING,
                    last_stamp_ns: last_stamp,
                }
            })?;
            if stop_requested || ctx.termination_requested() {
                stopped = true;
                break;
            }
            if last_health.elapsed() >= Duration::from_secs(1) {
                last_health = Instant::now();
                health.outputs = truth.published() + imu.published() + depth.published();
                health.dropped = truth.given_up() + imu.given_up() + depth.given_up();
                health.last_stamp_ns = last_stamp;
                health.publish(ctx);
                ctx.cleanup_dead_nodes();
            }
        }
    }
    truth.flush();
    imu.flush();
    depth.flush();
    // End of stream: nothing more will come from this source.
    let mut eos = Progress {
        header: Header::new(last_stamp, 0, Role::Sensor, 0),
        published: imu.published() + depth.published() + truth.published(),
    };
    eos.header.flags |= Flags::END_OF_STREAM.0;
    progress.publish_now(eos)?;
    health.state = state::STOPPED;
    health.outputs = truth.published() + imu.published() + depth.published();
    health.dropped = truth.given_up() + imu.given_up() + depth.given_up();
    health.last_stamp_ns = last_stamp;
    health.publish(ctx);
    tracing::info!(
        imu = imu.published(),
        depth = depth.published(),
        truth = truth.published(),
        given_up = health.dropped,
        stopped_by_signal = stopped,
        "done"
    );
    Ok(())
}

/// Started with `--standby`, a source opens its ports, reports ready and waits
/// for the launcher's ACTIVATE, sent once every consumer has connected, so that
/// nothing is published before anyone listens (DESIGN §5). False on STOP or a
/// termination signal.
fn hold_until_activated(
    ctx: &Context,
    control: &mut ControlServer,
    health: &mut HealthReporter,
) -> anyhow::Result<bool> {
    health.state = state::STANDBY;
    let mut last_health = Instant::now();
    loop {
        let mut decision = None;
        control.serve(|req| {
            let status = match req.command {
                command::ACTIVATE => {
                    decision = Some(true);
                    0
                }
                command::STOP => {
                    decision = Some(false);
                    0
                }
                command::SNAPSHOT_NOW => 0,
                _ => 2,
            };
            ControlResponse {
                header: Header::new(0, 0, Role::Sensor, ctx.instance),
                status,
                state: if decision == Some(true) {
                    state::RUNNING
                } else {
                    state::STANDBY
                },
                last_stamp_ns: 0,
            }
        })?;
        if let Some(d) = decision {
            return Ok(d);
        }
        if last_health.elapsed() >= Duration::from_secs(1) {
            last_health = Instant::now();
            health.publish(ctx);
        }
        if !ctx.sleep(Duration::from_millis(1)) {
            return Ok(false);
        }
    }
}

fn quat(q: &nalgebra::UnitQuaternion<f64>) -> [f64; 4] {
    [q.w, q.i, q.j, q.k]
}
