//! Issue 4: malformed manifests are refused before anything starts, each with
//! one error that names the file, the line where it can, and the key.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use nauta_runtime::Namespace;
use nauta_tests::*;

const BOUND: Duration = Duration::from_secs(180);

/// The test library's small manifest with a short alignment.
static GOOD: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    format!(
        "{}variants.gyro = {{ alignment_samples = 100 }}\n",
        nauta_tests::SMALL_MANIFEST
    )
});

/// A describe of `nauta-fake` that subscribes to `sensor/imu` as the wrong type.
const WRONG_TYPE: &str = r#"{"role":"attitude","inputs":[{"service":"sensor/imu","type":"nauta.DvlSample.v1"}],"outputs":[],"variants":["fake"]}"#;

struct Case {
    name: &'static str,
    text: String,
    /// Substrings the error must contain (besides the file name).
    expect: &'static [&'static str],
}

fn cases() -> Vec<Case> {
    let with = |from: &str, to: &str| {
        assert!(GOOD.contains(from), "{from}");
        GOOD.replacen(from, to, 1)
    };
    vec![
        Case {
            name: "unknown key",
            text: with("seed = 3", "seed = 3\ncolour = \"blue\""),
            expect: &["line 5", "colour"],
        },
        Case {
            name: "wrong type",
            text: with("duration_s = 5", "duration_s = \"long\""),
            expect: &["line 3", "duration_s", "invalid type"],
        },
        Case {
            name: "missing binary",
            text: with("bin = \"nauta-attitude\"", "bin = \"nauta-nonexistent\""),
            expect: &[":16:", "process.attitude.bin", "not found"],
        },
        Case {
            name: "duplicate process",
            text: format!("{}\n[process.attitude]\nbin = \"nauta-attitude\"\n", *GOOD),
            expect: &["line 20", "duplicate", "attitude"],
        },
        Case {
            name: "unknown variant",
            text: with(
                "variant = \"gyro\"\nvariants.gyro = { alignment_samples = 100 }",
                "variant = \"kalman\"",
            ),
            expect: &[":17:", "process.attitude.variant", "kalman"],
        },
        Case {
            name: "subscribed service nobody publishes",
            text: with(
                "[process.sensor]\nbin = \"nauta-sensor\"\nparams = { scenario = \"survey\" }\n",
                "",
            ),
            expect: &["process.attitude", "sensor/imu", "no process publishes"],
        },
        Case {
            name: "type mismatch",
            text: format!("{}\n[process.fake]\nbin = \"nauta-fake\"\n", *GOOD),
            expect: &[
                ":21:",
                "process.fake.bin",
                "sensor/imu",
                "nauta.DvlSample.v1",
                "nauta.ImuSample.v1",
            ],
        },
        Case {
            name: "negative rate",
            text: with("seed = 3", "seed = 3\nrate = -2.0"),
            expect: &[":5:", "run.rate", "-2"],
        },
        Case {
            name: "NaN parameter",
            text: with(
                "alignment_samples = 100",
                "alignment_samples = 100, gain = nan",
            ),
            expect: &[":18:", "process.attitude.variants.gyro.gain", "finite"],
        },
        Case {
            name: "cycle in after",
            text: with(
                "params = { scenario = \"survey\" }",
                "params = { scenario = \"survey\" }\nafter = [\"attitude\"]",
            )
            .replacen(
                "variant = \"gyro\"",
                "variant = \"gyro\"\nafter = [\"sensor\"]",
                1,
            ),
            expect: &["cycle in `after`", "attitude -> sensor -> attitude"],
        },
    ]
}

fn write(dir: &Path, i: usize, text: &str) -> PathBuf {
    let p = dir.join(format!("bad-{i}.toml"));
    std::fs::write(&p, text).expect("write manifest");
    p
}

fn nauta(args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(bin("nauta"))
        .args(args)
        .env("NAUTA_FAKE_DESCRIBE", WRONG_TYPE)
        .stdin(Stdio::null())
        .output()
        .expect("run nauta");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn the_shipped_manifests_check() {
    bin_dir();
    for m in ["survey", "lbl", "dr"] {
        let path = workspace_root().join(format!("launch/{m}.toml"));
        let (code, out, err) = nauta(&["check", &path.display().to_string()]);
        assert_eq!(code, Some(0), "{m}: {out}{err}");
        assert!(out.contains(": ok:"), "{m}: {out}");
        // A crashed estimator is restarted, with a cap and a backoff; the
        // source never is (it would start its data over).
        let manifest = nauta_runtime::Manifest::load(&path).expect("loads");
        for (name, p) in &manifest.processes {
            let restart = p.restart.as_ref();
            if p.bin == "nauta-sensor" {
                assert!(restart.is_none_or(|r| r.policy == "never"), "{m}: {name}");
            } else {
                let r = restart.unwrap_or_else(|| panic!("{m}: {name} has no restart policy"));
                assert_eq!(r.policy, "on-failure", "{m}: {name}");
                assert!(
                    r.max.is_some() && r.backoff_ms.is_some(),
                    "{m}: {name}: {r:?}"
                );
            }
        }
    }
}

#[test]
fn ten_malformed_manifests_each_give_one_error_and_start_nothing() {
    bin_dir();
    let wd = Watchdog::new("malformed_manifests", BOUND);
    let ns = Namespace::unique();
    let dir = std::env::temp_dir().join(format!("nauta-test-{}", ns.as_str()));
    std::fs::create_dir_all(&dir).expect("dir");
    let good = write(&dir, 99, &GOOD);
    let (code, out, err) = nauta(&["check", &good.display().to_string()]);
    assert_eq!(code, Some(0), "the good manifest fails: {out}{err}");
    let cases = cases();
    assert_eq!(cases.len(), 10);
    for (i, case) in cases.iter().enumerate() {
        wd.check();
        let path = write(&dir, i, &case.text);
        let file = path.display().to_string();
        let run_ns = Namespace::unique();
        for args in [
            vec!["check", file.as_str()],
            vec!["launch", file.as_str(), "--namespace", run_ns.as_str()],
        ] {
            let (code, out, err) = nauta(&args);
            assert!(
                code.is_some_and(|c| c != 0),
                "{}: `nauta {}` accepted it\n{out}{err}",
                case.name,
                args[0]
            );
            let errors: Vec<&str> = err
                .lines()
                .filter(|l| l.starts_with("nauta: error:"))
                .collect();
            assert_eq!(errors.len(), 1, "{}: not one error\n{err}", case.name);
            assert!(
                err.contains(&file),
                "{}: the error does not name the file\n{err}",
                case.name
            );
            for e in case.expect {
                assert!(
                    err.contains(e),
                    "{}: the error lacks {e:?}\n{err}",
                    case.name
                );
            }
            // Nothing started: no process reported, no file of the run exists.
            assert!(
                !err.contains("nauta: run "),
                "{}: a run started\n{err}",
                case.name
            );
            assert!(
                !err.contains(" ready "),
                "{}: a process started\n{err}",
                case.name
            );
            let config = run_ns.config().expect("config");
            assert!(
                run_ns.all_files(&config).is_empty(),
                "{}: the run left files",
                case.name
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
