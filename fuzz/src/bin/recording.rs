//! Fuzz target: a whole recording through every command's read path that is
//! a library: the reader (`nauta_log::reader`), the summary of
//! `nauta log info` (`nauta_log::info`), the replay's decoding of sensor
//! messages (`nauta-sensor --from`: `SensorMessage::decode`), and
//! `nauta export` to every format (`nauta_log::export`, track building and
//! writers). `nauta eval`'s loading lives in the `nauta` binary and is
//! covered by tests/tests/corrupt.rs instead.
//!
//! Nothing may panic, hang or allocate without bound; an export that fails
//! leaves no file.

use nauta_log::export::{self, ExportOptions, Format};

const FORMATS: [Format; 5] = [
    Format::Kml,
    Format::GeoJson,
    Format::Csv,
    Format::Gpx,
    Format::Foxglove,
];

fn main() {
    let dir = std::env::temp_dir().join(format!("nauta-fuzz-recording-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let input = dir.join("in.mcap");
    afl::fuzz!(|data: &[u8]| {
        let read = nauta_log::reader::read_bytes(
            data,
            |_, _| {},
            |ch, m| {
                let _ = nauta_messages::SensorMessage::decode(&ch.topic, &ch.type_name, m.data);
                let _ = nauta_log::header_of(m.data);
                Ok(())
            },
        );
        if let Ok(rec) = read {
            let _ = rec.recovery.damage_notes();
        }
        let _ = nauta_log::info::summarise_bytes("fuzz", data);
        if std::fs::write(&input, data).is_err() {
            return;
        }
        for format in FORMATS {
            let output = dir.join(format!("out.{}", format.name()));
            let _ = std::fs::remove_file(&output);
            let result = export::export(&input, &output, &ExportOptions::new(format), |_, _| {});
            assert_eq!(
                result.is_ok(),
                output.exists(),
                "{format}: an output exactly when the export succeeds ({result:?})"
            );
        }
    });
}
