use std::collections::BTreeMap;

use nauta_messages::*;

use super::*;
use crate::{LogWriter, WriterOptions};

fn imu(i: u64) -> ImuSample {
    ImuSample {
        header: Header::new(i * 10_000_000, i, Role::Sensor, 0),
        gyro_rad_s: [i as f64 * 1e-3, 0.5, -0.25],
        ..Default::default()
    }
}

/// Writes `n` IMU samples and one depth sample every 10, flushing every
/// `flush_every` messages; returns the file and the flushed sizes.
fn write(dir: &Path, n: u64, flush_every: u64, finish: bool) -> (std::path::PathBuf, Vec<u64>) {
    let path = dir.join("t.mcap");
    let mut w = LogWriter::create(&path, WriterOptions::default()).expect("create");
    let mut meta = BTreeMap::new();
    meta.insert("seed".to_owned(), "7".to_owned());
    w.metadata(crate::META_RUN, meta).expect("meta");
    let mut flushed = Vec::new();
    for i in 0..n {
        w.write_message("sensor/imu", 1_000 + i, &imu(i))
            .expect("write");
        if i % 10 == 0 {
            let d = DepthSample {
                header: Header::new(i * 10_000_000, i / 10, Role::Sensor, 0),
                depth_m: i as f64,
            };
            w.write_message("sensor/depth", 1_000 + i, &d)
                .expect("write");
        }
        if (i + 1) % flush_every == 0 {
            w.flush().expect("flush");
            flushed.push(std::fs::metadata(&path).expect("size").len());
        }
    }
    if finish {
        w.finish().expect("finish");
    } else {
        w.flush().expect("flush");
        flushed.push(std::fs::metadata(&path).expect("size").len());
    }
    (path, flushed)
}

fn imu_samples(path: &Path) -> (Recording, Vec<ImuSample>) {
    let mut out = Vec::new();
    let rec = read(path, |ch, m| {
        if ch.topic == "sensor/imu" {
            assert_eq!(ch.type_name, ImuSample::TYPE_NAME);
            let s: ImuSample = codec::decode(m.data)?;
            assert_eq!(m.publish_time_ns, s.header.stamp_ns);
            out.push(s);
        }
        Ok(())
    })
    .expect("read");
    (rec, out)
}

#[test]
fn a_finished_file_reads_back_exactly() {
    let dir = tempfile::tempdir().expect("tmp");
    let (path, _) = write(dir.path(), 5_000, 1_000, true);
    let (rec, got) = imu_samples(&path);
    assert!(!rec.recovery.truncated, "{:?}", rec.recovery);
    assert_eq!(got, (0..5_000).map(imu).collect::<Vec<_>>());
    assert_eq!(rec.profile, crate::PROFILE);
    assert_eq!(
        rec.metadata(crate::META_RUN)
            .and_then(|m| m.get("seed"))
            .map(String::as_str),
        Some("7")
    );
    let info = crate::info::summarise(&path, |_, _| {}).expect("info");
    let depth = info
        .channels
        .iter()
        .find(|c| c.topic == "sensor/depth")
        .expect("depth");
    assert_eq!((depth.count, depth.gaps), (500, 0));
    let imu_ch = info
        .channels
        .iter()
        .find(|c| c.topic == "sensor/imu")
        .expect("imu");
    assert_eq!((imu_ch.count, imu_ch.gaps), (5_000, 0));
    assert!((imu_ch.rate_hz - 100.0).abs() < 1e-9, "{}", imu_ch.rate_hz);
    assert!(!info.truncated);
}

#[test]
fn a_cut_file_keeps_every_flushed_chunk() {
    let dir = tempfile::tempdir().expect("tmp");
    let (path, mut flushed) = write(dir.path(), 3_000, 500, false);
    flushed.dedup();
    let full = std::fs::read(&path).expect("read");
    // Cut at every flushed size (exactly after a chunk) and at points in
    // between: everything flushed before the cut comes back, nothing else fails.
    let mut cuts: Vec<u64> = flushed.clone();
    for w in flushed.windows(2) {
        cuts.push((w[0] + w[1]) / 2);
        cuts.push(w[0] + 1);
        cuts.push(w[1] - 1);
    }
    cuts.extend([9, 20, 100]);
    for cut in cuts {
        let cut_path = dir.path().join("cut.mcap");
        std::fs::write(&cut_path, &full[..cut as usize]).expect("write");
        let (rec, got) = imu_samples(&cut_path);
        assert!(rec.recovery.truncated, "cut at {cut}");
        assert_eq!(rec.recovery.file_bytes, cut);
        assert!(rec.recovery.reason.is_some());
        let complete_flushes = flushed.iter().filter(|&&f| f <= cut).count() as u64;
        // Everything flushed before the cut; at most the chunk in flight
        // besides (its message indexes may be what the cut lost).
        let n = got.len() as u64;
        assert!(
            n >= complete_flushes * 500 && n <= (complete_flushes + 1) * 500,
            "cut at {cut}: {n}"
        );
        if flushed.contains(&cut) {
            assert_eq!(n, complete_flushes * 500, "cut at {cut}");
        }
        assert_eq!(got, (0..got.len() as u64).map(imu).collect::<Vec<_>>());
        let info = crate::info::summarise(&cut_path, |_, _| {}).expect("info");
        assert!(info.truncated);
        assert_eq!(info.gaps, 0);
    }
}

#[test]
fn a_damaged_chunk_is_skipped_and_counted() {
    let dir = tempfile::tempdir().expect("tmp");
    let (path, flushed) = write(dir.path(), 2_000, 500, true);
    let mut bytes = std::fs::read(&path).expect("read");
    // Overwrite the middle of the second chunk's compressed data.
    let mid = ((flushed[0] + flushed[1]) / 2) as usize;
    for b in &mut bytes[mid..mid + 64] {
        *b ^= 0x5a;
    }
    std::fs::write(&path, &bytes).expect("write");
    let (rec, got) = imu_samples(&path);
    assert_eq!(rec.recovery.damaged_chunks, 1, "{:?}", rec.recovery);
    assert_eq!(got.len(), 1_500);
}

#[test]
fn not_an_mcap_file_is_a_clear_error() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("x.mcap");
    std::fs::write(&path, b"hello, world").expect("write");
    let e = read(&path, |_, _| Ok(())).expect_err("not mcap");
    assert!(e.to_string().contains("not an MCAP file"), "{e}");
    let e = read(&dir.path().join("none.mcap"), |_, _| Ok(())).expect_err("missing");
    assert!(e.to_string().contains("cannot open"), "{e}");
}
