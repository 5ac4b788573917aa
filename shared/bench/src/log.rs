//! `nauta bench log`: how fast a 45-minute survey is written to a recording
//! and read back (issue 5 target: both together under 10 s). The messages are
//! what the pipeline records: the simulator's truth and every sensor of the
//! survey scenario, plus one attitude estimate per IMU sample (the truth's
//! attitude, as an estimator would publish), generated in memory first so
//! that only the recording is timed. Writing encodes every message (bincode),
//! compresses (zstd) and writes to a file; reading walks the file, decompresses
//! and decodes every message into its type. See BENCHMARKS.md, "Recording".

use std::time::Instant;

use anyhow::Context as _;
use nauta_log::{LogWriter, WriterOptions};
use nauta_messages::*;
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
use serde_json::json;

/// Rounds; the median is reported.
const ROUNDS: usize = 3;
/// The survey ends after ~2603 s; the cap is far beyond.
const CAP_S: f64 = 3600.0;

/// One recorded message: service, log time, payload type and content.
enum Item {
    Sensor(SensorMessage),
    Estimate(AttitudeEstimate),
}

fn generate() -> anyhow::Result<(Vec<Item>, f64)> {
    let params = ScenarioParams {
        scenario: ScenarioKind::Survey,
        ..ScenarioParams::default()
    };
    let mut g = Generator::new(&params, Origin::lisbon(), params.sensors_preset(), 7, CAP_S)?;
    let mut items = Vec::new();
    let mut scratch = Vec::new();
    let mut seq = [0u64; 9];
    let mut est_seq = 0;
    while let Some(m) = g.step() {
        let m = m.context("the sensor suite failed")?;
        scratch.clear();
        nauta_sim::wire::to_wire(&m, &mut scratch);
        for mut msg in scratch.drain(..) {
            let k = msg.order();
            msg.header_mut().seq = seq[k];
            seq[k] += 1;
            if let SensorMessage::Imu(imu) = &msg {
                let mut header = Header::new(imu.header.stamp_ns, est_seq, Role::Attitude, 0);
                header.flags |= Flags::VALID.0;
                est_seq += 1;
                items.push(Item::Sensor(msg));
                items.push(Item::Estimate(AttitudeEstimate {
                    header,
                    quat_nb: m.truth.quat_nb,
                    std_rad: [1e-3, 1e-3, 5e-3],
                    gyro_bias_rad_s: [0.0; 3],
                    calibration: calibration::ALIGNED,
                    pad: 0,
                }));
            } else {
                items.push(Item::Sensor(msg));
            }
        }
    }
    Ok((items, g.t_s()))
}

/// Writes every item; returns (seconds, file bytes).
fn write(items: &[Item], path: &std::path::Path) -> anyhow::Result<(f64, u64)> {
    let t0 = Instant::now();
    let mut w = LogWriter::create(path, WriterOptions::default())?;
    let mut channels = std::collections::HashMap::new();
    let est = w.channel(
        ATTITUDE_ESTIMATE_SERVICE,
        &TypeInfo::of::<AttitudeEstimate>(),
    )?;
    let mut last_flush = Instant::now();
    for (i, item) in items.iter().enumerate() {
        // The logger stamps the receive time; here a steady 10 µs per message.
        let log_time = 1_700_000_000_000_000_000 + i as u64 * 10_000;
        match item {
            Item::Sensor(m) => {
                let ch = match channels.get(&m.order()) {
                    Some(ch) => *ch,
                    None => {
                        let ch = w.channel(m.service(), &m.type_info())?;
                        channels.insert(m.order(), ch);
                        ch
                    }
                };
                w.write(ch, log_time, &m.encode()?)?;
            }
            Item::Estimate(e) => w.write(est, log_time, &codec::encode(e)?)?,
        }
        // As the logger does: a flush (chunk closed) at least once per second.
        if last_flush.elapsed().as_secs_f64() >= 1.0 {
            w.flush()?;
            last_flush = Instant::now();
        }
    }
    w.finish()?;
    let bytes = std::fs::metadata(path)?.len();
    Ok((t0.elapsed().as_secs_f64(), bytes))
}

/// Reads and decodes every message; returns (seconds, messages).
fn read(path: &std::path::Path) -> anyhow::Result<(f64, u64)> {
    let t0 = Instant::now();
    let mut n = 0u64;
    let rec = nauta_log::read(path, |ch, m| {
        if ch.topic == ATTITUDE_ESTIMATE_SERVICE {
            codec::decode::<AttitudeEstimate>(m.data)?;
        } else {
            SensorMessage::decode(&ch.topic, &ch.type_name, m.data)
                .with_context(|| format!("unexpected channel {}", ch.topic))??;
        }
        n += 1;
        Ok(())
    })?;
    anyhow::ensure!(
        !rec.recovery.truncated,
        "the benchmark file reads as truncated"
    );
    Ok((t0.elapsed().as_secs_f64(), n))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs the benchmark.
pub fn run(json_out: bool) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let (items, mission_s) = generate()?;
    let generate_s = t0.elapsed().as_secs_f64();
    let dir = std::env::temp_dir().join(format!("nauta-bench-log-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = dir.join("survey.mcap");
    let (mut writes, mut reads) = (Vec::new(), Vec::new());
    let (mut bytes, mut read_n) = (0, 0);
    for _ in 0..ROUNDS {
        let (w, b) = write(&items, &path)?;
        let (r, n) = read(&path)?;
        writes.push(w);
        reads.push(r);
        bytes = b;
        read_n = n;
    }
    let _ = std::fs::remove_dir_all(&dir);
    anyhow::ensure!(
        read_n == items.len() as u64,
        "read {read_n} messages back, wrote {}",
        items.len()
    );
    let raw: u64 = items
        .iter()
        .map(|i| match i {
            Item::Sensor(m) => m.type_info().size as u64,
            Item::Estimate(_) => core::mem::size_of::<AttitudeEstimate>() as u64,
        })
        .sum();
    let (write_s, read_s) = (median(writes), median(reads));
    let out = json!({
        "mission_s": mission_s,
        "messages": items.len(),
        "raw_bytes": raw,
        "file_bytes": bytes,
        "compression_ratio": raw as f64 / bytes as f64,
        "write_s": write_s,
        "read_s": read_s,
        "total_s": write_s + read_s,
        "write_msgs_per_s": items.len() as f64 / write_s,
        "read_msgs_per_s": items.len() as f64 / read_s,
        "generate_s": generate_s,
        "rounds": ROUNDS,
    });
    if json_out {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        println!(
            "recording of the {:.0}-s survey: {} messages, {:.1} MB raw, {:.1} MB on disk ({:.1}x)",
            mission_s,
            items.len(),
            raw as f64 / 1e6,
            bytes as f64 / 1e6,
            raw as f64 / bytes as f64
        );
        println!(
            "  write {write_s:.3} s ({:.0} msg/s), read {read_s:.3} s ({:.0} msg/s), total {:.3} s (target < 10 s); median of {ROUNDS}",
            items.len() as f64 / write_s,
            items.len() as f64 / read_s,
            write_s + read_s
        );
    }
    Ok(())
}
