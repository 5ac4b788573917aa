//! `nauta-sensor --from FILE`: republishes a recording's sensor channels (and
//! its truth, when it has one) with their recorded stamps (DESIGN §8), in the
//! order the simulator published them: by stamp, and within a stamp the truth
//! first, then the IMU, AHRS, DVL, depth, GPS, propeller, modem and LBL. In
//! `sim` clock as fast as the pipeline consumes; in `wall` clock at the
//! recorded speed or a multiple of it (`run.rate`).

use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use nauta_messages::*;
use nauta_runtime::{Context, ControlServer, HealthReporter, Pacer};

use crate::outputs::Outputs;

/// What a replay holds, in publishing order.
#[derive(Debug, Default)]
pub struct Replay {
    /// Messages in publishing order.
    pub messages: Vec<SensorMessage>,
    /// Recorded messages that could not be decoded (skipped).
    pub undecodable: u64,
}

/// Reads the sensor channels of `path`.
pub fn load(path: &Path) -> anyhow::Result<Replay> {
    let mut tagged: Vec<(u64, usize, SensorMessage)> = Vec::new();
    let mut bad = 0u64;
    let rec = nauta_log::read(path, |ch, m| {
        match SensorMessage::decode(&ch.topic, &ch.type_name, m.data) {
            Some(Ok(msg)) => tagged.push((msg.header().stamp_ns, msg.order(), msg)),
            Some(Err(e)) => {
                bad += 1;
                if bad == 1 {
                    tracing::warn!(error = %e, "undecodable message skipped (further ones are only counted)");
                }
            }
            None => {}
        }
        Ok(())
    })
    .with_context(|| format!("cannot replay {}", path.display()))?;
    if rec.recovery.truncated {
        tracing::warn!(
            file = %path.display(),
            lost_bytes = rec.recovery.lost_bytes(),
            "the recording was cut short; replaying its complete part"
        );
    }
    for note in rec.recovery.damage_notes() {
        tracing::warn!(file = %path.display(), "{note}");
    }
    anyhow::ensure!(
        !tagged.is_empty(),
        "{} holds no sensor channel to replay",
        path.display()
    );
    // Stable: each channel keeps its recorded order.
    tagged.sort_by_key(|(stamp, rank, _)| (*stamp, *rank));
    Ok(Replay {
        messages: tagged.into_iter().map(|(_, _, r)| r).collect(),
        undecodable: bad,
    })
}

/// Publishes the replay; returns after the end of stream or on STOP/signal.
pub fn serve(ctx: &mut Context, path: &Path) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let replay = load(path)?;
    tracing::info!(
        file = %path.display(),
        messages = replay.messages.len(),
        undecodable = replay.undecodable,
        load_s = t0.elapsed().as_secs_f64(),
        "replay loaded"
    );
    let mut out = Outputs::open(ctx)?;
    let mut health = HealthReporter::new(ctx)?;
    health.rejected = replay.undecodable;
    let mut pacer = Pacer::new(ctx.clock);
    let (mut control, control_inbox) = ControlServer::open(ctx)?;
    drop(control_inbox);
    ctx.ready();
    if ctx.standby && !crate::hold_until_activated(ctx, &mut control, &mut health)? {
        return Ok(());
    }
    health.state = state::RUNNING;
    tracing::info!(file = %path.display(), clock = ctx.clock.name(), "replaying");
    let mut last_health = Instant::now();
    let mut last_stamp = 0;
    let mut stopped = false;
    for (i, r) in replay.messages.iter().enumerate() {
        let stamp = r.header().stamp_ns;
        last_stamp = stamp;
        let wait = pacer.delay_for(stamp);
        if !wait.is_zero() {
            out.flush();
            if !ctx.sleep(wait) {
                stopped = true;
                break;
            }
        }
        out.publish_message(r)?;
        if (i as u64 + 1).is_multiple_of(crate::BATCH) {
            // A watermark per batch, as the simulator publishes: the
            // recording is in stamp order, so nothing earlier than the next
            // message's stamp is still to come, and a consumer of a sparse
            // channel does not wait for that channel's next message.
            match replay.messages.get(i + 1) {
                Some(next) => {
                    let published = out.published();
                    out.publish_watermark(Progress::at(
                        next.header().stamp_ns,
                        Role::Sensor,
                        published,
                    ))?;
                }
                None => out.flush(),
            }
            if crate::serve_control(&mut control, ctx, last_stamp)? || ctx.termination_requested() {
                stopped = true;
                break;
            }
            if last_health.elapsed() >= Duration::from_secs(1) {
                last_health = Instant::now();
                health.outputs = out.published();
                health.dropped = out.given_up();
                health.last_stamp_ns = last_stamp;
                health.publish(ctx);
                ctx.cleanup_dead_nodes();
            }
        }
    }
    let published = out.published();
    out.publish_watermark(Progress::end_of_stream(last_stamp, Role::Sensor, published))?;
    health.state = state::STOPPED;
    health.outputs = published;
    health.dropped = out.given_up();
    health.last_stamp_ns = last_stamp;
    health.publish(ctx);
    tracing::info!(
        counts = ?out.counts(),
        given_up = out.given_up(),
        stopped_by_signal = stopped,
        "done"
    );
    Ok(())
}
