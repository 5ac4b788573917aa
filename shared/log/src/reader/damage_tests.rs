//! Damaged and hostile recordings (issue 12, point 4): each test is named
//! after a defect of the reader that read them through the `mcap` crate.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use nauta_messages::*;
use rand::{Rng as _, SeedableRng as _};
use rand_chacha::ChaCha8Rng;

use std::path::Path;

use super::records::op;
use super::*;

/// Records the largest single allocation made by each thread, so a test can
/// say "reading this did not allocate what its lengths claim".
struct Largest;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

fn note(size: usize) {
    let _ = LARGEST.try_with(|c| c.set(c.get().max(size)));
}

// SAFETY: every call is forwarded unchanged to the system allocator; the
// thread-local is const-initialised, so noting a size never allocates.
unsafe impl GlobalAlloc for Largest {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: the caller's contract is System's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: as above.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Largest = Largest;

/// The largest single allocation `f` makes on this thread.
fn largest_allocation<T>(f: impl FnOnce() -> T) -> (T, usize) {
    LARGEST.with(|c| c.set(0));
    let out = f();
    (out, LARGEST.with(Cell::get))
}

// ---- a recording built record by record, so any field can be made to lie ----

fn string(s: &str) -> Vec<u8> {
    let mut out = (s.len() as u32).to_le_bytes().to_vec();
    out.extend_from_slice(s.as_bytes());
    out
}

fn record(opcode: u8, body: &[u8]) -> Vec<u8> {
    let mut out = vec![opcode];
    out.extend_from_slice(&(body.len() as u64).to_le_bytes());
    out.extend_from_slice(body);
    out
}

fn imu(i: u64) -> ImuSample {
    ImuSample {
        header: Header::new(i * 10_000_000, i, Role::Sensor, 0),
        gyro_rad_s: [i as f64 * 1e-3, 0.5, -0.25],
        ..Default::default()
    }
}

/// A schema, a channel and `n` IMU messages starting at sample `first`, as
/// a chunk's uncompressed records.
fn imu_records(first: u64, n: u64, announce: bool) -> Vec<u8> {
    let mut out = Vec::new();
    if announce {
        let mut schema = 1u16.to_le_bytes().to_vec();
        schema.extend(string(ImuSample::TYPE_NAME));
        schema.extend(string("none"));
        schema.extend_from_slice(&0u32.to_le_bytes());
        out.extend(record(op::SCHEMA, &schema));
        let mut channel = 1u16.to_le_bytes().to_vec();
        channel.extend_from_slice(&1u16.to_le_bytes());
        channel.extend(string("sensor/imu"));
        channel.extend(string(crate::MESSAGE_ENCODING));
        channel.extend_from_slice(&0u32.to_le_bytes());
        out.extend(record(op::CHANNEL, &channel));
    }
    for i in first..first + n {
        let m = imu(i);
        let mut body = 1u16.to_le_bytes().to_vec();
        body.extend_from_slice(&(i as u32).to_le_bytes());
        body.extend_from_slice(&(1_000 + i).to_le_bytes());
        body.extend_from_slice(&m.header.stamp_ns.to_le_bytes());
        body.extend(codec::encode(&m).expect("encode"));
        out.extend(record(op::MESSAGE, &body));
    }
    out
}

/// A chunk record around `data` (stored as given), declaring
/// `uncompressed_size` and `crc`.
fn chunk(data: &[u8], compression: &str, uncompressed_size: u64, crc: u32) -> Vec<u8> {
    let mut body = Vec::new();
    body.extend_from_slice(&0u64.to_le_bytes());
    body.extend_from_slice(&0u64.to_le_bytes());
    body.extend_from_slice(&uncompressed_size.to_le_bytes());
    body.extend_from_slice(&crc.to_le_bytes());
    body.extend(string(compression));
    body.extend_from_slice(&(data.len() as u64).to_le_bytes());
    body.extend_from_slice(data);
    record(op::CHUNK, &body)
}

/// An uncompressed chunk with its true size and CRC.
fn plain_chunk(records: &[u8]) -> Vec<u8> {
    chunk(records, "", records.len() as u64, crc32fast::hash(records))
}

/// A whole file: magic, header, `records`, data end.
fn file(records: &[Vec<u8>]) -> Vec<u8> {
    let mut out = MAGIC.to_vec();
    let mut header = string(crate::PROFILE);
    header.extend(string("test"));
    out.extend(record(op::HEADER, &header));
    for r in records {
        out.extend_from_slice(r);
    }
    out.extend(record(op::DATA_END, &0u32.to_le_bytes()));
    out
}

/// Reads `bytes` from a file; returns the recovery and the IMU samples
/// delivered.
fn read_file(bytes: &[u8]) -> (Recovery, Vec<ImuSample>) {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("t.mcap");
    std::fs::write(&path, bytes).expect("write");
    let mut got = Vec::new();
    let rec = read(&path, |ch, m| {
        if ch.topic == "sensor/imu" {
            got.push(codec::decode::<ImuSample>(m.data)?);
        }
        Ok(())
    })
    .expect("read");
    (rec.recovery, got)
}

fn samples(range: std::ops::Range<u64>) -> Vec<ImuSample> {
    range.map(imu).collect()
}

#[test]
fn a_chunk_with_a_wrong_crc_is_skipped_not_used() {
    let first = plain_chunk(&imu_records(0, 10, true));
    let mut second_records = imu_records(10, 10, false);
    let crc = crc32fast::hash(&second_records);
    // One bit of the last message's gyro changes after the CRC was taken.
    let at = second_records.len() - 100;
    second_records[at] ^= 0x01;
    let second = chunk(&second_records, "", second_records.len() as u64, crc);
    let third = plain_chunk(&imu_records(20, 10, false));
    let (recovery, got) = read_file(&file(&[first, second, third]));
    assert_eq!(got, [samples(0..10), samples(20..30)].concat());
    assert_eq!(recovery.chunks, 2);
    assert_eq!(recovery.damaged_chunks, 1);
    let d = &recovery.damaged[0];
    assert_eq!(d.chunk, Some(1), "{d}");
    assert!(d.reason.contains("CRC32"), "{d}");
    assert!(!recovery.truncated);
}

#[test]
fn a_chunk_with_a_bad_record_yields_none_of_its_records() {
    // No CRC set (0): the record structure is all that can be checked, and
    // a chunk whose last record is cut delivers none of the records before it.
    let good = imu_records(0, 10, true);
    let mut bad = imu_records(10, 10, false);
    bad.truncate(bad.len() - 3);
    let (recovery, got) = read_file(&file(&[
        chunk(&good, "", good.len() as u64, 0),
        chunk(&bad, "", bad.len() as u64, 0),
    ]));
    assert_eq!(got, samples(0..10));
    assert_eq!(recovery.damaged[0].chunk, Some(1));
    assert!(
        recovery.damaged[0].reason.contains("record 9 "),
        "{:?}",
        recovery.damaged
    );
}

#[test]
fn a_record_length_beyond_its_chunk_does_not_allocate() {
    let mut records = imu_records(0, 3, true);
    // A message record claiming 1 TiB inside a chunk of a few hundred bytes.
    records.extend_from_slice(&[op::MESSAGE]);
    records.extend_from_slice(&(1u64 << 40).to_le_bytes());
    records.extend_from_slice(&[0u8; 64]);
    let bytes = file(&[
        plain_chunk(&records),
        plain_chunk(&imu_records(3, 2, false)),
    ]);
    let ((recovery, got), largest) = largest_allocation(|| read_file(&bytes));
    assert!(largest < 1 << 24, "largest allocation {largest} bytes");
    assert_eq!(recovery.damaged.len(), 1, "{recovery:?}");
    assert!(
        recovery.damaged[0].reason.contains("record body"),
        "{recovery:?}"
    );
    // The next chunk's messages need the lost channel: counted, not used.
    assert!(got.is_empty());
    assert_eq!(recovery.unknown_channel_messages, 2);
}

#[test]
fn a_zstd_bomb_is_refused_at_its_declared_size() {
    let records = imu_records(0, 5, true);
    // 64 MiB of zeros after the records: a few KiB compressed.
    let mut big = records.clone();
    big.resize(64 << 20, 0);
    let bomb = zstd::bulk::compress(&big, 19).expect("compress");
    // Declared as the records' size: decoding stops one byte past it.
    let declared_small = chunk(
        &bomb,
        "zstd",
        records.len() as u64,
        crc32fast::hash(&records),
    );
    // Declared as 1 TiB: refused before anything is allocated.
    let declared_huge = chunk(&bomb, "zstd", 1 << 40, 0);
    // Declared as its true size: more than 32x its compressed size.
    let declared_true = chunk(&bomb, "zstd", big.len() as u64, crc32fast::hash(&big));
    let good = zstd::bulk::compress(&imu_records(5, 5, false), 3).expect("compress");
    let good = chunk(&good, "zstd", imu_records(5, 5, false).len() as u64, 0);
    let bytes = file(&[declared_small, declared_huge, declared_true, good]);
    let ((recovery, got), largest) = largest_allocation(|| read_file(&bytes));
    assert!(largest < 1 << 22, "largest allocation {largest} bytes");
    let reasons: Vec<&str> = recovery.damaged.iter().map(|d| d.reason.as_str()).collect();
    assert_eq!(reasons.len(), 3, "{reasons:?}");
    assert!(reasons[0].contains("decompresses to"), "{reasons:?}");
    assert!(reasons[1].contains("more than the"), "{reasons:?}");
    assert!(reasons[2].contains("decompression bomb"), "{reasons:?}");
    // The channel was in the first (refused) chunk.
    assert!(got.is_empty());
    assert_eq!(recovery.unknown_channel_messages, 5);
}

#[test]
fn a_damaged_chunk_length_resumes_at_the_next_intact_chunk() {
    let chunks = [
        plain_chunk(&imu_records(0, 10, true)),
        plain_chunk(&imu_records(10, 10, false)),
        plain_chunk(&imu_records(20, 10, false)),
    ];
    let mut bytes = file(&chunks);
    let second = MAGIC.len() + 9 + string(crate::PROFILE).len() + 8 + chunks[0].len();
    for (lie, what) in [(u64::MAX, "past the end"), (17, "short")] {
        let mut damaged = bytes.clone();
        damaged[second + 1..second + 9].copy_from_slice(&lie.to_le_bytes());
        let (recovery, got) = read_file(&damaged);
        assert_eq!(got, [samples(0..10), samples(20..30)].concat(), "{what}");
        assert!(!recovery.truncated, "{what}: {recovery:?}");
        assert_eq!(recovery.damaged.len(), 1, "{what}: {recovery:?}");
        assert_eq!(recovery.damaged[0].offset, second as u64, "{what}");
        assert_eq!(recovery.damaged[0].bytes, chunks[1].len() as u64, "{what}");
    }
    // A damaged opcode is skipped the same way.
    bytes[second] = 0x00;
    let (recovery, got) = read_file(&bytes);
    assert_eq!(got, [samples(0..10), samples(20..30)].concat());
    assert!(
        recovery.damaged[0].reason.contains("opcode 0x00"),
        "{recovery:?}"
    );
}

#[test]
fn an_attachment_cut_before_its_crc_does_not_panic() {
    // The mcap crate sliced an attachment's data `..len - 4` before it checked
    // that the 4-byte CRC was there: a complete header with a 2-byte tail
    // panicked. Attachments are skipped unread.
    let mut attachment = Vec::new();
    attachment.extend_from_slice(&0u64.to_le_bytes()); // log time
    attachment.extend_from_slice(&0u64.to_le_bytes()); // create time
    attachment.extend(string("a"));
    attachment.extend(string("text/plain"));
    attachment.extend_from_slice(&0u64.to_le_bytes()); // data length
    attachment.extend_from_slice(&[0, 0]);
    let bytes = file(&[
        record(0x09, &attachment),
        plain_chunk(&imu_records(0, 3, true)),
    ]);
    let (recovery, got) = read_file(&bytes);
    assert_eq!(got, samples(0..3));
    assert!(recovery.damaged.is_empty());
}

/// A finished file of `n` IMU samples in 8 KiB chunks (the first chunk
/// announces the schema and channel; the summary repeats them).
fn finished_recording(dir: &Path, n: u64) -> Vec<u8> {
    let path = dir.join("w.mcap");
    let mut w = crate::LogWriter::create(
        &path,
        crate::WriterOptions {
            chunk_bytes: 8 << 10,
            ..Default::default()
        },
    )
    .expect("create");
    for i in 0..n {
        w.write_message("sensor/imu", 1_000 + i, &imu(i))
            .expect("write");
    }
    w.finish().expect("finish");
    std::fs::read(&path).expect("read")
}

/// (offset, record length) of every top-level chunk record.
fn chunk_records(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut at = MAGIC.len();
    while at + 9 <= bytes.len() && bytes[at] != op::DATA_END {
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().expect("8")) as usize;
        if bytes[at] == op::CHUNK {
            out.push((at, 9 + len));
        }
        at += 9 + len;
    }
    out
}

#[test]
fn a_damaged_first_chunk_loses_no_channel_of_a_finished_file() {
    let dir = tempfile::tempdir().expect("tmp");
    let original = finished_recording(dir.path(), 2_000);
    let chunks = chunk_records(&original);
    assert!(chunks.len() > 3, "{chunks:?}");
    let (first, len) = chunks[0];
    let mut bytes = original.clone();
    bytes[first + len - 50] ^= 0x04;
    // The channel comes from the summary (its CRC checked): every message
    // of the other chunks is read, none of the damaged one.
    let (recovery, got) = read_file(&bytes);
    assert_eq!(recovery.damaged.len(), 1, "{recovery:?}");
    assert_eq!(recovery.damaged[0].chunk, Some(0));
    assert_eq!(recovery.unknown_channel_messages, 0);
    let lost = 2_000 - got.len() as u64;
    assert!(
        lost > 0 && got == samples(lost..2_000),
        "{} read",
        got.len()
    );
    // A damaged summary is not used: the messages are counted, not guessed.
    let summary_byte = original.len() - 8 - 29 - 20;
    bytes[summary_byte] ^= 0x01;
    let (recovery, got) = read_file(&bytes);
    assert!(got.is_empty());
    assert_eq!(recovery.unknown_channel_messages, 2_000 - lost);
}

fn below(rng: &mut ChaCha8Rng, n: usize) -> usize {
    rng.random_range(0..n.max(1))
}

#[test]
fn damaged_copies_of_a_real_recording_never_deliver_a_changed_message() {
    let dir = tempfile::tempdir().expect("tmp");
    let original = finished_recording(dir.path(), 2_000);
    let all = samples(0..2_000);
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for case in 0..200 {
        let mut bytes = original.clone();
        let what = match case % 4 {
            0 => {
                for _ in 0..1 + below(&mut rng, 8) {
                    let at = below(&mut rng, bytes.len());
                    bytes[at] ^= 1 << below(&mut rng, 8);
                }
                "byte flips"
            }
            1 => {
                bytes.truncate(below(&mut rng, bytes.len()));
                "truncation"
            }
            2 => {
                let at = below(&mut rng, bytes.len().saturating_sub(8));
                let lie = match below(&mut rng, 3) {
                    0 => u64::MAX - rng.random::<u64>() % 1_000,
                    1 => rng.random::<u64>() % (1 << 20),
                    _ => rng.random::<u64>(),
                };
                bytes[at..at + 8].copy_from_slice(&lie.to_le_bytes());
                "length overwrite"
            }
            _ => {
                let at = below(&mut rng, bytes.len());
                let n = below(&mut rng, 4_096).min(bytes.len() - at);
                bytes.drain(at..at + n);
                "bytes removed"
            }
        };
        let ((outcome, got), largest) = largest_allocation(|| {
            let mut got = Vec::new();
            let r = read_bytes(
                &bytes,
                |_, _| {},
                |ch, m| {
                    if ch.topic == "sensor/imu" {
                        got.push(codec::decode::<ImuSample>(m.data)?);
                    }
                    Ok(())
                },
            );
            (r, got)
        });
        assert!(
            largest <= (1 << 21) + bytes.len(),
            "case {case} ({what}): {largest}"
        );
        // Every message used is one that was written, in order; the file
        // either reads (perhaps with damage named) or is not an MCAP file.
        let mut last = None;
        for s in &got {
            let i = s.header.seq;
            assert!(
                i < 2_000 && *s == all[i as usize],
                "case {case} ({what}): {s:?}"
            );
            assert!(last < Some(i), "case {case} ({what}): {i} after {last:?}");
            last = Some(i);
        }
        match outcome {
            Ok(rec) => {
                let r = &rec.recovery;
                assert!(r.read_bytes <= r.file_bytes, "case {case} ({what}): {r:?}");
                assert_eq!(r.damaged_chunks, r.damaged.len() as u64);
            }
            Err(e) => assert!(
                e.to_string().contains("not an MCAP file"),
                "case {case} ({what}): {e:#}"
            ),
        }
    }
}
