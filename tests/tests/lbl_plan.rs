//! `nauta lbl plan`: paper 003's sensitivity map and operating box of a
//! transponder layout, through the command line: the PNG, the JSON and its
//! box on the `lbl` scenario's two transponders, and bad layouts refused
//! with a clear error and no map left behind.

use nauta_tests::nauta_cli;
use serde_json::Value;

/// `nauta lbl plan LAYOUT -o MAP [--json]`: (exit code, stdout, stderr).
fn plan(
    layout: &std::path::Path,
    map: &std::path::Path,
    json: bool,
) -> (Option<i32>, String, String) {
    let mut args = vec![
        "lbl".as_ref(),
        "plan".as_ref(),
        layout.as_os_str(),
        "-o".as_ref(),
        map.as_os_str(),
    ];
    if json {
        args.push("--json".as_ref());
    }
    nauta_cli(&args)
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("nauta-lbl-plan-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

#[test]
fn a_two_transponder_layout_gets_its_map_and_box() {
    let dir = temp_dir("two");
    let layout = dir.join("two.csv");
    std::fs::write(
        &layout,
        "# the lbl scenario's transponders\nid,north_m,east_m,depth_m\n1,-50,-150,20\n2,550,-150,20\n",
    )
    .expect("layout");
    let map = dir.join("map.png");
    let (code, out, err) = plan(&layout, &map, true);
    assert_eq!(code, Some(0), "{err}");
    let v: Value = serde_json::from_str(&out).expect("one JSON object");
    assert_eq!(v["baseline_m"], 600.0);
    let corners: Vec<[f64; 2]> = serde_json::from_value(v["box"].clone()).expect("box");
    assert_eq!(
        corners,
        vec![[-50.0, 0.0], [550.0, 0.0], [550.0, 450.0], [-50.0, 450.0]]
    );
    let png = std::fs::read(&map).expect("map written");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // Only the map in the directory: no part file left.
    let names: Vec<_> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
    // The text form prints the same box.
    let (code, out, err) = plan(&layout, &map, false);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.contains("baseline T1-T2: 600.0 m"), "{out}");
    assert!(out.contains("      550.0      450.0"), "{out}");
    // The same transponders in the site.toml of `nauta import csv`.
    let site = dir.join("site.toml");
    std::fs::write(
        &site,
        "latitude_deg = 38.6\nlongitude_deg = -9.3\nmagnetic_declination_deg = 0.0\n\n\
         [[transponders]]\nid = 1\nnorth_m = -50.0\neast_m = -150.0\ndepth_m = 20.0\n\n\
         [[transponders]]\nid = 2\nnorth_m = 550.0\neast_m = -150.0\ndepth_m = 20.0\n",
    )
    .expect("site");
    let (code, out, err) = plan(&site, &map, true);
    assert_eq!(code, Some(0), "{err}");
    let w: Value = serde_json::from_str(&out).expect("one JSON object");
    assert_eq!(w["box"], v["box"]);
    // And the shipped manifest of the lbl scenario (its sensor's
    // `lbl_layout = "Two"` names them), as the interface runs it.
    let manifest = nauta_tests::workspace_root().join("launch/lbl.toml");
    let (code, out, err) = plan(&manifest, &map, true);
    assert_eq!(code, Some(0), "{err}");
    let m: Value = serde_json::from_str(&out).expect("one JSON object");
    assert_eq!(m["baseline_m"], 600.0);
    assert_eq!(m["box"], v["box"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_layouts_are_refused_with_a_clear_error_and_no_map() {
    let dir = temp_dir("bad");
    let cases = [
        (
            "coincident.csv",
            "id,north_m,east_m\n1,10,20\n2,10,20\n",
            "coincident",
        ),
        ("one.csv", "id,north_m,east_m\n1,10,20\n", "at least two"),
        ("nan.csv", "id,north_m,east_m\n1,NaN,20\n2,0,0\n", "north_m"),
        (
            "four.csv",
            "id,north_m,east_m\n1,0,0\n2,600,0\n3,0,700\n4,600,700\n",
            "--pair",
        ),
        ("header.csv", "north,east\n1,2\n", "header"),
    ];
    for (name, text, expected) in cases {
        let layout = dir.join(name);
        std::fs::write(&layout, text).expect("layout");
        let map = dir.join(format!("{name}.png"));
        let (code, out, err) = plan(&layout, &map, false);
        assert_eq!(code, Some(1), "{name}: {out}{err}");
        assert!(
            err.contains(expected) && err.contains(name),
            "{name}: {err}"
        );
        assert!(!map.exists(), "{name}: a map was written");
    }
    let names: Vec<_> = std::fs::read_dir(&dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(names.len(), cases.len(), "only the layouts: {names:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
