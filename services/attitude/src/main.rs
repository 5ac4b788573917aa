//! `nauta-attitude`: the attitude role. A thin shell around [`core::AttitudeCore`]:
//! subscribe to the IMU, validate every sample, feed the estimator in stamp
//! order, publish `attitude/estimate`, its snapshot, health and progress.

use std::ops::ControlFlow;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use clap::Parser;
use nauta_messages::checked::{Imu, StampOrder};
use nauta_messages::*;
use nauta_runtime::process::{ProcessArgs, service_main};
use nauta_runtime::{
    Context, ControlServer, Describe, EventLoop, HealthReporter, LoopExit, OrderedMerge,
    PortDescription, Wake, services,
};

mod core;

use crate::core::{AttitudeCore, VARIANTS, VariantParams};

/// Estimates the vehicle's attitude from the IMU.
#[derive(Debug, Parser)]
#[command(name = "nauta-attitude", version, about)]
struct Args {
    #[command(flatten)]
    process: ProcessArgs,
}

fn describe() -> Describe {
    Describe {
        role: Role::Attitude.name().into(),
        inputs: vec![
            PortDescription::of(&services::imu()),
            PortDescription::of(&services::progress(Role::Sensor)),
        ],
        outputs: vec![
            PortDescription::of(&services::attitude_estimate()),
            PortDescription::of(&services::snapshot::<AttitudeSnapshot>(Role::Attitude)),
            PortDescription::of(&services::progress(Role::Attitude)),
        ],
        variants: VARIANTS.iter().map(|v| v.to_string()).collect(),
        source: false,
    }
}

fn main() -> ExitCode {
    let args = Args::parse();
    service_main(Role::Attitude, VARIANTS[0], &args.process, describe, serve)
}

fn serve(ctx: &mut Context) -> anyhow::Result<()> {
    anyhow::ensure!(
        VARIANTS.contains(&ctx.variant.as_str()),
        "unknown attitude variant {:?}; this binary implements {VARIANTS:?}",
        ctx.variant
    );
    let params = match ctx.variant.as_str() {
        "mekf" => VariantParams::Mekf(ctx.params()?),
        _ => VariantParams::Gyro(ctx.params()?),
    };
    let site = ctx
        .manifest()?
        .site
        .context("the manifest has no [site]: the attitude needs the latitude and declination")?;
    let mut core = AttitudeCore::new(
        &params,
        site.latitude_deg.to_radians(),
        site.magnetic_declination_deg.to_radians(),
    )?;

    let (mut imu_in, imu_inbox) = ctx.subscriber(&services::imu())?;
    let (mut sensor_progress, progress_inbox) =
        ctx.subscriber(&services::progress(Role::Sensor))?;
    let mut estimate_out = ctx.publisher(&services::attitude_estimate())?;
    let mut snapshot_out =
        ctx.publisher(&services::snapshot::<AttitudeSnapshot>(Role::Attitude))?;
    let mut progress_out = ctx.publisher(&services::progress(Role::Attitude))?;
    let mut health = HealthReporter::new(ctx)?;
    let (mut control, control_inbox) = ControlServer::open(ctx)?;
    let mut stop = false;
    let span = tracing::info_span!("attitude", process = %ctx.process, variant = %ctx.variant);
    let _e = span.enter();
    if !ctx.connect_and_ready(&[&imu_in, &sensor_progress])? {
        tracing::info!("stopped by a signal before the inputs appeared");
        return Ok(());
    }
    health.state = state::RUNNING;

    // One data input today; the merge is what makes a second one deterministic.
    const IMU: usize = 0;
    let mut merge: OrderedMerge<Imu> = OrderedMerge::new(1);
    let mut order = StampOrder::default();
    let mut last_stamp = 0u64;

    let exit = EventLoop::new(Duration::from_secs(1)).run(
        &[&imu_inbox, &progress_inbox, &control_inbox],
        |wake| {
            let mut snapshot_now = wake == Wake::Tick;
            control.serve(|req| {
                let status = match req.command {
                    command::SNAPSHOT_NOW => {
                        snapshot_now = true;
                        0
                    }
                    command::STOP => {
                        stop = true;
                        0
                    }
                    // Standby and switching arrive with the launcher's hot swap.
                    _ => 2,
                };
                ControlResponse {
                    header: Header::new(last_stamp, 0, Role::Attitude, ctx.instance),
                    status,
                    state: if stop { state::DRAINING } else { health.state },
                    last_stamp_ns: last_stamp,
                }
            })?;
            if snapshot_now && let Some(s) = core.snapshot() {
                snapshot_out.publish_now(AttitudeSnapshot {
                    header: Header::new(last_stamp, 0, Role::Attitude, ctx.instance),
                    quat_nb: s.q,
                    gyro_bias_rad_s: s.gyro_bias,
                    covariance: s.covariance,
                    calibration: s.calibration,
                    pad: 0,
                })?;
            }
            if wake == Wake::Tick {
                health.dropped = imu_in.gaps().missing + estimate_out.given_up();
                health.publish(ctx);
                ctx.cleanup_dead_nodes();
                if !stop {
                    return Ok(ControlFlow::Continue(()));
                }
            }
            // Progress first: a watermark or end-of-stream seen here means every
            // IMU sample sent before it is already in the IMU queue, drained just
            // below; the watermark applies after that drain.
            let mut ended = false;
            let mut watermark = None;
            sensor_progress.drain(|p| {
                if p.header.is_end_of_stream() {
                    ended = true;
                } else {
                    watermark = Some(p.header.stamp_ns);
                }
            })?;
            let imu_service = IMU_SERVICE;
            imu_in.drain(|m| {
                let checked = order
                    .check(m.header.stamp_ns)
                    .and_then(|()| Imu::try_from(&m));
                match checked {
                    Ok(imu) => {
                        health.inputs += 1;
                        if let Err(e) = merge.push(IMU, imu.stamp_ns, imu) {
                            tracing::warn!(%e, "out-of-order input dropped");
                        }
                    }
                    Err(e) => health.reject(imu_service, &e),
                }
            })?;
            if let Some(w) = watermark {
                merge.advance(IMU, w);
            }
            if ended || stop {
                merge.end(IMU);
            }
            while let Some((_, stamp, imu)) = merge.pop() {
                last_stamp = stamp;
                health.last_stamp_ns = stamp;
                if let Some(out) = core.step(&imu)? {
                    let calibration = if core.is_aligned() {
                        calibration::ALIGNED
                    } else {
                        calibration::NONE
                    };
                    estimate_out.publish(AttitudeEstimate {
                        header: Header::new(stamp, 0, Role::Attitude, ctx.instance),
                        quat_nb: [out.q_nb.w, out.q_nb.i, out.q_nb.j, out.q_nb.k],
                        std_rad: out.std_rad.into(),
                        gyro_bias_rad_s: out.gyro_bias.into(),
                        calibration,
                        pad: 0,
                    })?;
                    health.outputs += 1;
                }
            }
            estimate_out.flush();
            if merge.is_finished() {
                progress_out.publish_now(Progress::end_of_stream(
                    last_stamp,
                    Role::Attitude,
                    estimate_out.published(),
                ))?;
                return Ok(ControlFlow::Break(()));
            }
            Ok(ControlFlow::Continue(()))
        },
    )?;
    health.state = state::STOPPED;
    health.dropped = imu_in.gaps().missing + estimate_out.given_up();
    health.publish(ctx);
    tracing::info!(
        inputs = health.inputs,
        outputs = health.outputs,
        rejected = health.rejected,
        gaps = imu_in.gaps().missing,
        by_signal = exit == LoopExit::Signal,
        "done"
    );
    Ok(())
}
