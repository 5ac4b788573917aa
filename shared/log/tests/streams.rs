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
