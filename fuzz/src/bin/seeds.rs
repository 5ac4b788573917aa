//! Writes the seed corpora that are derived from the committed real
//! recordings (`fuzz/corpus/recording/*.mcap`, made by `nauta launch
//! --record`): `messages/` gets one input per checked message type (its
//! selector byte and a recorded payload of that type), `recording/` a
//! multi-chunk recording of the same IMU samples (512-byte chunks, so the
//! fuzzer starts from a file whose chunks can be damaged one by one).
//!
//! Usage: `seeds CORPUS_IN OUT_DIR` (fuzz/run calls it).

use std::collections::BTreeMap;
use std::path::Path;

use nauta_messages::*;

/// The selector byte of each type in the `messages` target.
const TYPES: [&str; 13] = [
    ImuSample::TYPE_NAME,
    DepthSample::TYPE_NAME,
    DvlSample::TYPE_NAME,
    GpsFix::TYPE_NAME,
    AhrsSample::TYPE_NAME,
    PropellerSample::TYPE_NAME,
    BuoyRange::TYPE_NAME,
    LblReply::TYPE_NAME,
    TruthState::TYPE_NAME,
    AttitudeEstimate::TYPE_NAME,
    NavSolution::TYPE_NAME,
    PositionFix::TYPE_NAME,
    LblSolution::TYPE_NAME,
];

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    anyhow::ensure!(args.len() == 3, "usage: seeds CORPUS_IN OUT_DIR");
    let (input, out) = (Path::new(&args[1]), Path::new(&args[2]));
    std::fs::create_dir_all(out.join("messages"))?;
    std::fs::create_dir_all(out.join("recording"))?;
    let mut first: BTreeMap<usize, Vec<u8>> = BTreeMap::new();
    let mut imu: Vec<ImuSample> = Vec::new();
    for entry in std::fs::read_dir(input.join("recording"))? {
        let path = entry?.path();
        nauta_log::read(&path, |ch, m| {
            if let Some(i) = TYPES.iter().position(|t| *t == ch.type_name) {
                first.entry(i).or_insert_with(|| m.data.to_vec());
            }
            if ch.type_name == ImuSample::TYPE_NAME
                && imu.len() < 60
                && let Ok(s) = codec::decode::<ImuSample>(m.data)
            {
                imu.push(s);
            }
            Ok(())
        })?;
    }
    for (i, data) in &first {
        let mut seed = vec![*i as u8];
        seed.extend_from_slice(data);
        std::fs::write(out.join("messages").join(format!("type{i}")), seed)?;
    }
    let mut w = nauta_log::LogWriter::create(
        &out.join("recording").join("imu-multichunk.mcap"),
        nauta_log::WriterOptions {
            chunk_bytes: 512,
            ..Default::default()
        },
    )?;
    for s in &imu {
        w.write_message("sensor/imu", 1_000 + s.header.stamp_ns, s)?;
    }
    w.finish()?;
    eprintln!(
        "seeds: {} message types, {} IMU samples in the multi-chunk recording",
        first.len(),
        imu.len()
    );
    Ok(())
}
