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
use nauta_runtime::process::{ProcessArgs, service_main_checked};
use nauta_runtime::{
    Context, ControlServer, Describe, EventLoop, HealthReporter, LoopExit, Manifest, OrderedMerge,
    PortDescription, Wake, services,
};

mod core;

use crate::core::{AttitudeCore, VARIANTS, VariantParams};
use nauta_estimation::AttitudeStateSnapshot;

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
    service_main_checked(
        Role::Attitude,
        VARIANTS[0],
        &args.process,
        describe,
        |t| {
            core_for(&t.manifest, &t.process, &t.variant)?;
            Ok(())
        },
        serve,
    )
}

/// The core of `variant` with its parameters from the manifest (what
/// `--check` validates).
fn core_for(manifest: &Manifest, process: &str, variant: &str) -> anyhow::Result<AttitudeCore> {
    anyhow::ensure!(
        VARIANTS.contains(&variant),
        "unknown attitude variant {variant:?}; this binary implements {VARIANTS:?}"
    );
    let params = match variant {
        "mekf" => VariantParams::Mekf(manifest.params(process, Some(variant))?),
        "pf" => VariantParams::Pf(manifest.params(process, Some(variant))?),
        _ => VariantParams::Gyro(manifest.params(process, Some(variant))?),
    };
    let site = manifest.site.with_context(|| {
        format!(
            "{}: the manifest has no [site]: the attitude needs the latitude and declination",
            manifest.path.display()
        )
    })?;
    AttitudeCore::new(
        &params,
        site.latitude_deg.to_radians(),
        site.magnetic_declination_deg.to_radians(),
    )
    .with_context(|| format!("{}: process.{process}", manifest.path.display()))
}

fn serve(ctx: &mut Context) -> anyhow::Result<()> {
    let mut core = core_for(ctx.manifest()?, &ctx.process, &ctx.variant)?;

    // A restarted or swapped-in instance continues from the role's latest
    // snapshot (the launcher hands it over) instead of aligning again.
    match ctx.warm_start::<AttitudeSnapshot>() {
        Ok(Some(s)) => {
            let state = AttitudeStateSnapshot {
                q: s.quat_nb,
                gyro_bias: s.gyro_bias_rad_s,
                covariance: s.covariance,
                calibration: s.calibration,
            };
            if let Err(e) = core.warm_start(state, s.header.stamp_ns) {
                tracing::warn!(error = %e, "starting cold");
            }
        }
        Ok(None) => {}
        Err(e) => tracing::warn!(error = %e, "snapshot unreadable; starting cold"),
    }
    // Estimates up to this stamp were published by the previous instance.
    let mut resume_after = ctx.resume_after_ns;
    // Hot swap (DESIGN §5): a standby instance follows its inputs without
    // publishing, keeping its latest estimates, until the launcher activates
    // it at a stamp boundary; the instance it replaces is deactivated first
    // and exits, having published exactly up to that boundary.
    let mut standby = ctx.standby;
    let mut held: std::collections::VecDeque<AttitudeEstimate> = std::collections::VecDeque::new();
    let mut last_published: Option<u64> = None;
    let mut deactivated = false;

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
    health.state = if standby {
        state::STANDBY
    } else {
        state::RUNNING
    };

    // One data input today; the merge is what makes a second one deterministic.
    const IMU: usize = 0;
    let mut merge: OrderedMerge<Imu> = OrderedMerge::new(1);
    let mut order = StampOrder::default();
    let mut last_stamp = 0u64;
    let mut next_snapshot_ns = 0u64;

    let exit = EventLoop::new(Duration::from_secs(1)).run(
        &[&imu_inbox, &progress_inbox, &control_inbox],
        |wake| {
            let mut snapshot_now = false;
            let mut activate_after = None;
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
                    // Publish from the first stamp after the boundary.
                    command::ACTIVATE if standby => {
                        activate_after = Some(req.boundary_stamp_ns);
                        0
                    }
                    // Publish nothing more: the answer carries the last stamp
                    // published, which the launcher hands to the successor.
                    command::DEACTIVATE if !standby => {
                        deactivated = true;
                        0
                    }
                    _ => 2,
                };
                ControlResponse {
                    header: Header::new(last_stamp, 0, Role::Attitude, ctx.instance),
                    status,
                    state: if stop || deactivated {
                        state::DRAINING
                    } else {
                        health.state
                    },
                    last_stamp_ns: if req.command == command::DEACTIVATE {
                        last_published.unwrap_or(0)
                    } else {
                        last_stamp
                    },
                }
            })?;
            if deactivated {
                tracing::info!(last_published = ?last_published, "deactivated; exiting for the successor");
                return Ok(ControlFlow::Break(()));
            }
            if let Some(boundary) = activate_after {
                standby = false;
                health.state = state::RUNNING;
                resume_after = Some(resume_after.map_or(boundary, |r| r.max(boundary)));
                for e in held.drain(..).filter(|e| e.header.stamp_ns > boundary) {
                    last_published = Some(e.header.stamp_ns);
                    estimate_out.publish(e)?;
                    health.outputs += 1;
                }
                estimate_out.flush();
                tracing::info!(boundary, "activated");
            }
            if snapshot_now && !standby {
                publish_snapshot(&core, &mut snapshot_out, last_stamp)?;
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
                let out = core.step(&imu)?;
                // A snapshot at every whole second of the run's clock.
                if stamp >= next_snapshot_ns {
                    next_snapshot_ns = (stamp / SNAPSHOT_PERIOD_NS + 1) * SNAPSHOT_PERIOD_NS;
                    if !standby {
                        publish_snapshot(&core, &mut snapshot_out, stamp)?;
                    }
                }
                if resume_after.is_some_and(|r| stamp <= r) {
                    continue;
                }
                if let Some(out) = out {
                    let mut calibration = if core.is_aligned() {
                        calibration::ALIGNED
                    } else {
                        calibration::NONE
                    };
                    if core.magnetometer_calibrated() {
                        calibration |= calibration::MAGNETOMETER;
                    }
                    let estimate = AttitudeEstimate {
                        header: Header::new(stamp, 0, Role::Attitude, ctx.instance),
                        quat_nb: [out.q_nb.w, out.q_nb.i, out.q_nb.j, out.q_nb.k],
                        std_rad: out.std_rad.into(),
                        gyro_bias_rad_s: out.gyro_bias.into(),
                        calibration,
                        pad: 0,
                    };
                    if standby {
                        held.push_back(estimate);
                        while held.len() > HELD_ESTIMATES {
                            held.pop_front();
                        }
                    } else {
                        estimate_out.publish(estimate)?;
                        last_published = Some(stamp);
                        health.outputs += 1;
                    }
                }
            }
            estimate_out.flush();
            if merge.is_finished() {
                if standby {
                    // Never activated: the active instance ends the stream.
                    return Ok(ControlFlow::Break(()));
                }
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

/// Estimates a standby instance keeps for its activation (5 s at 100 Hz).
const HELD_ESTIMATES: usize = 500;

/// Snapshot period in the run's clock (DESIGN §4: 1 Hz).
const SNAPSHOT_PERIOD_NS: u64 = 1_000_000_000;

/// Publishes the estimator's state after the sample stamped `stamp_ns` (nothing
/// while it aligns).
fn publish_snapshot(
    core: &AttitudeCore,
    out: &mut nauta_runtime::Publisher<AttitudeSnapshot>,
    stamp_ns: u64,
) -> anyhow::Result<()> {
    if let Some(s) = core.snapshot() {
        out.publish_now(AttitudeSnapshot {
            header: Header::new(stamp_ns, 0, Role::Attitude, 0),
            quat_nb: s.q,
            gyro_bias_rad_s: s.gyro_bias,
            covariance: s.covariance,
            calibration: s.calibration,
            pad: 0,
        })?;
    }
    Ok(())
}
