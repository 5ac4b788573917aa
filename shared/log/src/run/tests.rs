use super::*;

fn meta(pairs: &[(&str, &str)]) -> BTreeMap<String, String> {
    pairs
        .iter()
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect()
}

fn read(m: Option<&BTreeMap<String, String>>) -> RunInfo {
    RunInfo::read(m, &Overrides::default(), None)
}

#[test]
fn origin_from_keys_then_from_the_manifest() {
    let m = meta(&[("origin_lat_deg", "38.6"), ("origin_lon_deg", "-9.3")]);
    let o = read(Some(&m)).origin.expect("origin");
    assert!((o.value.lat_rad.to_degrees() - 38.6).abs() < 1e-12);
    assert!(o.source.contains("origin_lat_deg"), "{}", o.source);
    let m = meta(&[(
        "manifest",
        "[run]\nseed = 7\n[site]\nlatitude_deg = -12.5\nlongitude_deg = 170.25\n",
    )]);
    let o = read(Some(&m)).origin.expect("origin from the manifest");
    assert!((o.value.lon_rad.to_degrees() - 170.25).abs() < 1e-12);
    assert!(o.source.contains("manifest"), "{}", o.source);
    assert!(read(None).origin.is_none());
    assert!(
        read(Some(&meta(&[("manifest", "not = [toml")])))
            .origin
            .is_none()
    );
    let bad = read(Some(&meta(&[
        ("origin_lat_deg", "95"),
        ("origin_lon_deg", "0"),
    ])));
    assert!(bad.origin.is_none());
    assert!(
        bad.notes.iter().any(|n| n.contains("±90")),
        "{:?}",
        bad.notes
    );
}

#[test]
fn an_override_wins_over_the_recording() {
    let m = meta(&[("origin_lat_deg", "38.6"), ("origin_lon_deg", "-9.3")]);
    let given = GeoOrigin::from_degrees(10.0, 20.0).expect("origin");
    let overrides = Overrides {
        origin: Some(given),
        utc_start: None,
    };
    let o = RunInfo::read(Some(&m), &overrides, None)
        .origin
        .expect("origin");
    assert_eq!(o.value, given);
    assert_eq!(o.source, "--origin");
}

#[test]
fn explicit_transponders_are_found_at_any_depth() {
    let m = meta(&[(
        "sensor_config.sensor",
        "[params.sensors.lbl]\nenabled = true\ntransponders = [\
         { id = 1, north_m = -50.0, east_m = -150.0, depth_m = 20.0 },\
         { id = 2, north_m = 550.0, east_m = -150.0, turnaround_s = 0.02 },\
         { id = 2, north_m = 1.0, east_m = 1.0 }]\n",
    )]);
    let r = read(Some(&m));
    assert_eq!(r.transponders.len(), 2, "the repeated id 2 is dropped");
    assert_eq!(r.transponders[1].id, 2);
    assert!(r.transponders[1].depth_m.is_nan());
    assert_eq!(r.transponders[1].turnaround_s, Some(0.02));
    assert_eq!(r.transponders[0].east_m, -150.0);
}

#[test]
fn acoustics_from_keys_then_documents_then_presets() {
    let cfg = r#"{"lbl": {"enabled": true, "transponders": [{"id": 7, "north_m": 1.0, "east_m": 2.0, "depth_m": 3.0}], "noise": {"turnaround": 0.02}}, "sound_speed_m_s": 1490.0}"#;
    let r = read(Some(&meta(&[("sensors", cfg)])));
    assert_eq!(r.transponders.len(), 1);
    assert_eq!(r.transponders[0].id, 7);
    assert_eq!(r.sound_speed_m_s, Some(1490.0));
    assert_eq!(r.turnaround_s, Some(0.02));
    let r = read(Some(&meta(&[
        ("sensors", cfg),
        ("sound_speed_m_s", "1500"),
    ])));
    assert_eq!(r.sound_speed_m_s, Some(1500.0), "a plain key first");

    fn presets(_: &BTreeMap<String, String>, origin: Option<&GeoOrigin>) -> Presets {
        Presets {
            transponders: vec![Transponder {
                id: 9,
                north_m: 0.0,
                east_m: 0.0,
                depth_m: 10.0,
                turnaround_s: None,
            }],
            sound_speed_m_s: origin.map(|_| 1507.5),
            turnaround_s: Some(0.0125),
        }
    }
    let m = meta(&[("origin_lat_deg", "38.6"), ("origin_lon_deg", "-9.3")]);
    let r = RunInfo::read(Some(&m), &Overrides::default(), Some(presets));
    assert_eq!(r.transponders[0].id, 9);
    assert_eq!(r.sound_speed_m_s, Some(1507.5));
    assert_eq!(r.turnaround_s, Some(0.0125));
    let r = RunInfo::read(
        Some(&meta(&[("sensors", cfg)])),
        &Overrides::default(),
        Some(presets),
    );
    assert_eq!(
        r.transponders[0].id, 9,
        "the presets' layout is the sensor's"
    );
    assert_eq!(r.sound_speed_m_s, Some(1490.0), "the recorded value first");
}

#[test]
fn utc_start_is_read_or_noted() {
    let r = read(Some(&meta(&[("utc_start", "2026-06-21T09:30:00Z")])));
    assert!(r.utc_start.is_some());
    let r = read(Some(&meta(&[("utc_start", "yesterday")])));
    assert!(r.utc_start.is_none());
    assert!(
        r.notes.iter().any(|n| n.contains("utc_start")),
        "{:?}",
        r.notes
    );
}

#[test]
fn local_and_geodetic_round_trip() {
    let o = GeoOrigin::from_degrees(38.6, -9.3).expect("origin");
    let (lat, lon) = o.to_geodetic(550.0, -150.0);
    let (n, e) = o.to_local(lat, lon);
    assert!((n - 550.0).abs() < 1e-6 && (e + 150.0).abs() < 1e-6);
    // 550 m north is about 0.00495°.
    assert!(((lat - o.lat_rad).to_degrees() - 0.00495).abs() < 1e-4);
}
