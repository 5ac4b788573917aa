//! Tests of the manifest: schema, values, overrides and where errors point.

use super::*;

const GOOD: &str = r#"
[run]
clock = "sim"
duration_s = 60
seed = 7

[site]
latitude_deg = 38.7
longitude_deg = -9.1

[process.attitude]
bin = "nauta-attitude"
variant = "gyro"
variants.gyro = { gain = 1.5 }
params = { publish = true }
"#;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct P {
    gain: f64,
    publish: bool,
}

#[test]
fn parses_and_merges_params() {
    let m = Manifest::parse(Path::new("m.toml"), GOOD).expect("parses");
    assert_eq!(m.run.seed, 7);
    let p: P = m.params("attitude", None).expect("params");
    assert!((p.gain - 1.5).abs() < 1e-12);
    assert!(p.publish);
}

#[test]
fn unknown_key_names_file_line_and_key() {
    let bad = GOOD.replace("seed = 7", "seed = 7\nsped = 3");
    let e = Manifest::parse(Path::new("m.toml"), &bad)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("m.toml") && e.contains("sped") && e.contains("line 6"),
        "{e}"
    );
}

#[test]
fn bad_values_are_refused_with_place() {
    let bad = GOOD.replace("duration_s = 60", "duration_s = -1");
    let e = Manifest::parse(Path::new("m.toml"), &bad)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("m.toml:4") && e.contains("run.duration_s"),
        "{e}"
    );
    let bad = GOOD.replace("gain = 1.5", "gain = nan");
    let e = Manifest::parse(Path::new("m.toml"), &bad)
        .unwrap_err()
        .to_string();
    assert!(e.contains("variants.gyro.gain"), "{e}");
    let bad = GOOD.replace("variant = \"gyro\"", "variant = \"pf\"");
    let e = Manifest::parse(Path::new("m.toml"), &bad)
        .unwrap_err()
        .to_string();
    assert!(e.contains("unknown variant"), "{e}");
}

#[test]
fn names_launcher_flags_and_empty_manifests_are_refused() {
    let parse = |text: &str| {
        Manifest::parse(Path::new("m.toml"), text)
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    let at = |n: usize| {
        GOOD.replace(
            "[process.attitude]",
            &format!("[process.{}]", "a".repeat(n)),
        )
    };
    parse(&at(MAX_PROCESS_NAME)).expect("32 bytes");
    let e = parse(&at(MAX_PROCESS_NAME + 1)).expect_err("33 bytes");
    assert!(e.contains("1-32 bytes"), "{e}");
    let e = parse(&GOOD.replace("[process.attitude]", "[process.\"a/b\"]")).expect_err("a slash");
    assert!(e.contains("only A-Z"), "{e}");
    for arg in LAUNCHER_FLAGS {
        for given in [arg.to_owned(), format!("{arg}=1")] {
            let text = GOOD.replace(
                "variant = \"gyro\"",
                &format!("variant = \"gyro\"\nargs = [\"{given}\"]"),
            );
            let e = parse(&text).expect_err(&given);
            assert!(
                e.contains("process.attitude.args") && e.contains(arg),
                "{given}: {e}"
            );
        }
    }
    let text = GOOD.replace(
        "variant = \"gyro\"",
        "variant = \"gyro\"\nargs = [\"--namespaces\"]",
    );
    parse(&text).expect("not a launcher flag");
    let run_only = GOOD.split("[site]").next().unwrap_or(GOOD);
    let e = parse(run_only).expect_err("no process");
    assert!(e.contains("no process"), "{e}");
}

#[test]
fn errors_keep_their_place_with_overrides() {
    let dir = std::env::temp_dir().join(format!("nauta-manifest-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let file = dir.join("m.toml");
    let load = |text: &str, overrides: &[&str]| {
        std::fs::write(&file, text).expect("write");
        let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        Manifest::load_with(&file, &o)
            .map(|_| ())
            .expect_err("refused")
            .to_string()
    };
    let fast = ["run.clock=\"sim\""];
    // A key of the file: its line, with overrides too.
    let e = load(&GOOD.replace("seed = 7", "seed = 7\nsped = 3"), &fast);
    assert!(e.contains("line 6") && e.contains("sped"), "{e}");
    let e = load(&GOOD.replace("seed = 7", "seed = -1"), &fast);
    assert!(e.contains("line 5") && e.contains("-1"), "{e}");
    // A key an override brings: the override.
    let e = load(GOOD, &["run.seed=-1"]);
    assert!(e.contains("on the command line (run.seed=-1)"), "{e}");
    let e = load(GOOD, &["attitude.colour=1"]);
    assert!(
        e.contains("attitude.colour=1") && e.contains("colour"),
        "{e}"
    );
    // A value an override set out of range: the override, not a line.
    let e = load(GOOD, &["run.rate=0.0"]);
    assert!(
        e.starts_with(&format!(
            "{}: run.rate (set on the command line: run.rate)",
            file.display()
        )),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn parameter_errors_name_their_line_and_key() {
    let text = GOOD.replace("gain = 1.5", "gain = 1.5, colour = 1");
    let m = Manifest::parse(Path::new("m.toml"), &text).expect("parses");
    let e = m
        .params::<P>("attitude", None)
        .expect_err("unknown field")
        .to_string();
    assert!(
        e.starts_with("m.toml:14: process.attitude.variants.gyro.colour: unknown field"),
        "{e}"
    );
    let text = GOOD.replace("publish = true", "publish = 3");
    let m = Manifest::parse(Path::new("m.toml"), &text).expect("parses");
    let e = m
        .params::<P>("attitude", None)
        .expect_err("wrong type")
        .to_string();
    assert!(
        e.starts_with("m.toml:15: process.attitude.params.publish: invalid type"),
        "{e}"
    );
}

#[test]
fn restart_policies_are_checked() {
    let with = |restart: &str| {
        let text = format!("{GOOD}restart = {restart}\n");
        Manifest::parse(Path::new("m.toml"), &text).map_err(|e| e.to_string())
    };
    with(r#"{ policy = "on-failure", max = 5, window_s = 60, backoff_ms = [20, 1000] }"#)
        .expect("valid");
    for (restart, key) in [
        (r#"{ policy = "sometimes" }"#, "restart.policy"),
        (r#"{ policy = "always", max = 0 }"#, "restart.max"),
        (
            r#"{ policy = "always", window_s = -1.0 }"#,
            "restart.window_s",
        ),
        (
            r#"{ policy = "always", backoff_ms = [500, 20] }"#,
            "restart.backoff_ms",
        ),
        (r#"{ policy = "always", tries = 3 }"#, "tries"),
    ] {
        let e = with(restart).expect_err(restart);
        assert!(e.contains("m.toml") && e.contains(key), "{restart}: {e}");
    }
}

#[test]
fn after_orders_the_start_and_refuses_cycles() {
    let three = |a: &str, b: &str, c: &str| {
        format!(
            "[run]\nduration_s = 1\n[process.a]\nbin = \"x\"\nafter = {a}\n\
             [process.b]\nbin = \"x\"\nafter = {b}\n[process.c]\nbin = \"x\"\nafter = {c}\n"
        )
    };
    let m =
        Manifest::parse(Path::new("m.toml"), &three("[\"c\"]", "[]", "[\"b\"]")).expect("valid");
    assert_eq!(m.start_order(|_| 0), ["b", "c", "a"]);
    // Rank decides among the free ones; `after` still wins.
    assert_eq!(m.start_order(|n| u8::from(n != "a")), ["b", "c", "a"]);
    let e = Manifest::parse(Path::new("m.toml"), &three("[\"c\"]", "[\"a\"]", "[\"b\"]"))
        .expect_err("cycle")
        .to_string();
    assert!(
        e.contains("cycle in `after`") && e.contains("m.toml:5"),
        "{e}"
    );
    assert!(e.contains("a -> c -> b -> a"), "{e}");
    let e = Manifest::parse(Path::new("m.toml"), &three("[\"a\"]", "[]", "[]"))
        .expect_err("self")
        .to_string();
    assert!(e.contains("a -> a"), "{e}");
}

#[test]
fn effective_manifest_names_the_users_file() {
    let m = Manifest::parse(Path::new("launch/survey.toml"), GOOD).expect("parses");
    let effective = m.to_toml().expect("serialises");
    let bad = effective.replace("gain = 1.5", "gain = \"high\"");
    let m2 = Manifest::parse(Path::new("/tmp/nauta/x/manifest.toml"), &effective).expect("parses");
    assert_eq!(m2.path, Path::new("launch/survey.toml"));
    let m3 = Manifest::parse(Path::new("/tmp/nauta/x/manifest.toml"), &bad).expect("parses");
    let e = m3.params::<P>("attitude", None).unwrap_err().to_string();
    assert!(e.starts_with("launch/survey.toml"), "{e}");
}

#[test]
fn overrides() {
    let mut t: toml::Table = toml::from_str(GOOD).expect("toml");
    apply_override(&mut t, "run.duration_s=5").expect("run");
    apply_override(&mut t, "attitude.variants.gyro.gain=2").expect("proc");
    apply_override(&mut t, "run.clock=wall").expect("string");
    assert!(apply_override(&mut t, "nobody.x=1").is_err());
    let m = Manifest::from_table(Path::new("m.toml"), t, String::new(), &[]).expect("valid");
    assert!((m.run.duration_s - 5.0).abs() < 1e-12);
    assert_eq!(m.run.clock, "wall");
    let p: P = m.params("attitude", None).expect("params");
    assert!((p.gain - 2.0).abs() < 1e-12);
}

/// Issue 13: "the site's declination, from the manifest, else the WMM". A
/// site without `magnetic_declination_deg` takes the World Magnetic Model's
/// at the site today (Lisbon: about −1°, westerly); a written one is kept,
/// and a non-finite one is refused, not replaced.
#[test]
fn a_site_without_declination_takes_the_world_magnetic_models() {
    let m = Manifest::parse(Path::new("m.toml"), GOOD).expect("parses");
    let site = m.site.expect("a site");
    assert!(
        matches!(site.declination_from, DeclinationSource::Wmm { .. }),
        "{site:?}"
    );
    assert!(
        (-2.5..0.5).contains(&site.magnetic_declination_deg),
        "{site:?}"
    );
    let given = GOOD.replace(
        "longitude_deg = -9.1",
        "longitude_deg = -9.1\nmagnetic_declination_deg = 3.25",
    );
    let site = Manifest::parse(Path::new("m.toml"), &given)
        .expect("parses")
        .site
        .expect("a site");
    assert_eq!(site.declination_from, DeclinationSource::Manifest);
    assert_eq!(site.magnetic_declination_deg, 3.25);
    let nan = GOOD.replace(
        "longitude_deg = -9.1",
        "longitude_deg = -9.1\nmagnetic_declination_deg = nan",
    );
    let e = Manifest::parse(Path::new("m.toml"), &nan)
        .unwrap_err()
        .to_string();
    assert!(e.contains("magnetic_declination_deg"), "{e}");
}

/// Issue 15: `[site]` holds the transponders and the sound speed the
/// vehicle assumes; a process's `lbl_layout` names them when `[site]` lists
/// none (`--set sensor.params.lbl_layout=Four` gives four everywhere); both
/// at once, an unknown layout, coincident transponders and an impossible
/// sound speed are refused with the key.
#[test]
fn the_site_holds_the_transponders() {
    let with = |site: &str, params: &str| {
        GOOD.replace(
            "longitude_deg = -9.1\n",
            &format!("longitude_deg = -9.1\nmagnetic_declination_deg = 0.0\n{site}"),
        )
        .replace("params = { publish = true }", params)
    };
    let listed = with(
        "sound_speed_m_s = 1507.5\ntransponders = [\n  { id = 1, north_m = 0.0, east_m = 0.0, depth_m = 20.0 },\n  { id = 2, north_m = 600.0, east_m = 0.0, depth_m = 20.0, turnaround_s = 0.02 },\n]\n",
        "params = { publish = true }",
    );
    let s = Manifest::parse(Path::new("m.toml"), &listed)
        .expect("parses")
        .site
        .expect("a site");
    assert_eq!(s.sound_speed_m_s, Some(1507.5));
    assert_eq!(s.transponders.len(), 2);
    assert_eq!(s.transponders[1].turnaround_s, 0.02);
    assert_eq!(s.transponders[0].turnaround_s, 0.0125);
    assert_eq!(s.transponders_from, TranspondersSource::Manifest);
    assert!(s.layout().is_some());

    let named = with("", "params = { publish = true, lbl_layout = \"Two\" }");
    let path = std::env::temp_dir().join(format!("nauta-site-{}.toml", std::process::id()));
    std::fs::write(&path, &named).expect("write");
    let m =
        Manifest::load_with(&path, &["attitude.params.lbl_layout=Four".into()]).expect("parses");
    let s = m.site.expect("a site");
    assert_eq!(s.transponders.len(), 4, "--set names four");
    assert_eq!(
        s.transponders_from,
        TranspondersSource::Layout {
            process: "attitude".into(),
            name: "Four".into()
        }
    );
    let _ = std::fs::remove_file(&path);

    let err = |text: &str| {
        Manifest::parse(Path::new("m.toml"), text)
            .expect_err("refused")
            .to_string()
    };
    let both = listed.replace(
        "params = { publish = true }",
        "params = { lbl_layout = \"Two\" }",
    );
    let e = err(&both);
    assert!(
        e.contains("process.attitude.params.lbl_layout") && e.contains("keep one"),
        "{e}"
    );
    let e = err(&named.replace("\"Two\"", "\"Three\""));
    assert!(e.contains("unknown layout \"Three\""), "{e}");
    let e = err(&listed.replace("north_m = 600.0", "north_m = 0.2"));
    assert!(
        e.contains("site.transponders") && e.contains("cannot tell a position apart"),
        "{e}"
    );
    let e = err(&listed.replace("id = 2", "id = 1"));
    assert!(e.contains("id 1 is given twice"), "{e}");
    let e = err(&listed.replace("1507.5", "150.0"));
    assert!(
        e.contains("m.toml:") && e.contains("site.sound_speed_m_s"),
        "{e}"
    );
    let e = err(&listed.replace("depth_m = 20.0 }", "depth = 20.0 }"));
    assert!(e.contains("depth"), "{e}");
}
