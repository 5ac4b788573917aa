//! The one reader of recordings for offline tools: typed, checked streams.

use nauta_log::checked::Rejection;
use nauta_log::streams::{Select, Streams};
use nauta_log::{LogWriter, WriterOptions};
use nauta_messages::checked::{Depth, Nav};
use nauta_messages::*;

fn nav(i: u64, lat: f64) -> NavSolution {
    NavSolution {
        header: Header::new(i * 1_000_000, i, Role::Ains, 0),
        lat_rad: lat,
        lon_rad: -0.16,
        depth_m: 5.0,
        quat_nb: [1.0, 0.0, 0.0, 0.0],
        ..Default::default()
    }
}

#[test]
fn a_recording_reads_as_typed_checked_streams() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("run.mcap");
    let mut w = LogWriter::create(&path, WriterOptions::default()).expect("create");
    let mut meta = std::collections::BTreeMap::new();
    meta.insert("origin_lat_deg".to_owned(), "38.6".to_owned());
    meta.insert("origin_lon_deg".to_owned(), "-9.3".to_owned());
    w.metadata(nauta_log::META_RUN, meta).expect("metadata");
    for i in 0..10u64 {
        let lat = if i == 4 { f64::NAN } else { 0.67 };
        w.write_message("ains/nav", 1_000 + i, &nav(i, lat))
            .expect("write");
        let d = DepthSample {
            header: Header::new(i * 1_000_000, i, Role::Sensor, 0),
            depth_m: i as f64,
        };
        w.write_message("sensor/depth", 1_000 + i, &d)
            .expect("write");
        w.write_message("attitude/health", 1_000 + i, &Health::default())
            .expect("write");
    }
    let ch = w
        .channel("ains/nav", &TypeInfo::of::<NavSolution>())
        .expect("channel");
    w.write(ch, 99, &[0u8; 40]).expect("short payload");
    w.finish().expect("finish");

    let s = Streams::read(&path, &Select::All, None, |_, _| {}).expect("read");
    let navs = s.get::<Nav>("ains/nav").expect("ains/nav is a Nav stream");
    assert_eq!(navs.samples.len(), 9);
    assert!(navs.samples.iter().all(|n| n.value.lat_rad == 0.67));
    assert_eq!(
        navs.samples[4].seq, 5,
        "the invalid one (seq 4) is not a sample"
    );
    assert_eq!(navs.rejected.len(), 2);
    assert!(matches!(
        navs.rejected[0].rejection,
        Rejection::Invalid { seq: 4, .. }
    ));
    assert!(matches!(
        navs.rejected[1].rejection,
        Rejection::Undecodable(_)
    ));
    assert!(
        s.get::<Depth>("ains/nav").is_none(),
        "a stream has one type"
    );
    let depths: Vec<f64> = s
        .get::<Depth>("sensor/depth")
        .expect("depth")
        .values()
        .map(|d| d.depth_m)
        .collect();
    assert_eq!(depths, (0..10).map(|i| i as f64).collect::<Vec<_>>());
    assert_eq!(s.of_type::<Nav>().count(), 1);
    assert!(
        !s.by_topic.contains_key("attitude/health"),
        "types offline tools do not read are not streams"
    );
    let o = s.run.origin.expect("origin").value;
    assert!((o.lat_rad.to_degrees() - 38.6).abs() < 1e-12);
    assert_eq!(s.first_stamp_ns, 0, "the short payload's header stamp");

    let only = Select::Types(vec![DepthSample::TYPE_NAME]);
    let s = Streams::read(&path, &only, None, |_, _| {}).expect("read");
    assert_eq!(s.by_topic.len(), 1);
    assert!(s.get::<Depth>("sensor/depth").is_some());
}

/// `nauta.GpsFix.v2` added the receiver's velocity: a recording made before
/// it (v1 fixes on `sensor/gps`) still reads, for the offline tools and for
/// a replay, as fixes without a velocity; a v2 fix keeps its velocity.
#[test]
fn gps_fixes_of_v1_recordings_read_as_fixes_without_a_velocity() {
    use nauta_messages::checked::Gps;
    let dir = tempfile::tempdir().expect("tmp");
    let old_path = dir.path().join("old.mcap");
    let mut w = LogWriter::create(&old_path, WriterOptions::default()).expect("create");
    for i in 0..3u64 {
        let old = GpsFixV1 {
            header: Header::new(i * 1_000_000_000, i, Role::Sensor, 0),
            lat_rad: 0.67,
            lon_rad: -0.16,
            horizontal_std_m: 2.5,
            quality: 1,
            satellites: 8,
            ..Default::default()
        };
        w.write_message(GPS_SERVICE, 1_000 + i, &old)
            .expect("write");
    }
    w.finish().expect("finish");
    let new_path = dir.path().join("new.mcap");
    let mut w = LogWriter::create(&new_path, WriterOptions::default()).expect("create");
    let new = GpsFix {
        header: Header::new(9_000_000_000, 0, Role::Sensor, 0),
        lat_rad: 0.67,
        lon_rad: -0.16,
        horizontal_std_m: 2.5,
        quality: 1,
        vel_ned_m_s: [1.0, -0.5, 0.0],
        vel_std_m_s: 0.05,
        velocity_valid: 1,
        ..Default::default()
    };
    w.write_message(GPS_SERVICE, 2_000, &new).expect("write");
    w.finish().expect("finish");

    let s = Streams::read(&old_path, &Select::All, None, |_, _| {}).expect("read");
    let fixes = s
        .get::<Gps>(GPS_SERVICE)
        .expect("sensor/gps is a Gps stream");
    assert_eq!(fixes.samples.len(), 3, "{:?}", fixes.rejected);
    assert!(fixes.samples.iter().all(|f| f.value.velocity.is_none()
        && f.value.lat_rad == 0.67
        && f.value.horizontal_std_m == 2.5));
    let s = Streams::read(&new_path, &Select::All, None, |_, _| {}).expect("read");
    let fixes = s
        .get::<Gps>(GPS_SERVICE)
        .expect("sensor/gps is a Gps stream");
    let (v, std) = fixes.samples[0].value.velocity.expect("the v2 velocity");
    assert_eq!((v.to_array(), std), ([1.0, -0.5, 0.0], 0.05));

    // What `nauta-sensor --from` replays: v2 fixes on the wire.
    let mut replayed = Vec::new();
    nauta_log::read(&old_path, |ch, m| {
        if let Some(msg) = SensorMessage::decode(&ch.topic, &ch.type_name, m.data) {
            replayed.push(msg?);
        }
        Ok(())
    })
    .expect("read");
    assert_eq!(replayed.len(), 3);
    match replayed[0] {
        SensorMessage::Gps(g) => {
            assert_eq!((g.velocity_valid, g.lat_rad, g.satellites), (0, 0.67, 8))
        }
        other => panic!("not a fix: {other:?}"),
    }
}
