//! Fuzz target: a manifest, parsed and checked as `nauta check` and
//! `nauta launch` read one (`Manifest::load_with`), with `--set` overrides.
//!
//! Input: manifest text; lines `#set KEY=VALUE` at its end (TOML comments,
//! so the text stays a manifest) are also applied as `--set` overrides.
//! Anything may be refused with an error; nothing may panic, hang or
//! allocate without bound.

use std::io::Write as _;

fn main() {
    let dir = std::env::temp_dir().join(format!("nauta-fuzz-manifest-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("fuzz.toml");
    afl::fuzz!(|data: &[u8]| {
        let Ok(text) = std::str::from_utf8(data) else {
            return;
        };
        let overrides: Vec<String> = text
            .lines()
            .filter_map(|l| l.strip_prefix("#set "))
            .map(str::to_owned)
            .collect();
        // From text, as generated manifests are read.
        if let Ok(m) = nauta_runtime::Manifest::parse(&path, text) {
            exercise(&m);
        }
        // From a file, with the overrides, as the commands read one.
        let written = std::fs::File::create(&path).and_then(|mut f| f.write_all(data));
        if written.is_ok()
            && let Ok(m) = nauta_runtime::Manifest::load_with(&path, &overrides)
        {
            exercise(&m);
        }
    });
}

/// What the launcher does with a checked manifest before it starts anything.
fn exercise(m: &nauta_runtime::Manifest) {
    let _ = m.start_order(|_| 0);
    let _ = m.to_toml();
    let _ = m.clock();
    for name in m.processes.keys() {
        let _ = m.process(name);
        let _ = m.params::<serde_json::Value>(name, None);
    }
}
