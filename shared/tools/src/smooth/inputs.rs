//! The LBL filter's inputs as a recording logged them, read through the
//! one offline reader (`nauta_log::streams`), checked as the service checks
//! them, in the order the service's input merge takes them: by stamp, ties
//! in its declared input order (AHRS, depth, propeller, DVL, replies, GPS),
//! then in file order.

use std::collections::BTreeMap;
use std::path::Path;

use nauta_estimation::lbl::LblInput;
use nauta_log::checked::Value;
use nauta_log::reader::Recording;
use nauta_messages::{
    AHRS_SERVICE, DEPTH_SERVICE, DVL_SERVICE, GPS_SERVICE, LBL_REPLY_SERVICE, PROPELLER_SERVICE,
};

/// The topics the LBL role reads, in its declared order.
pub const TOPICS: [&str; 6] = [
    AHRS_SERVICE,
    DEPTH_SERVICE,
    PROPELLER_SERVICE,
    DVL_SERVICE,
    LBL_REPLY_SERVICE,
    GPS_SERVICE,
];

/// What the first read of a recording gives.
#[derive(Debug)]
pub struct LoggedInputs {
    /// The inputs in the merge's order.
    pub inputs: Vec<LblInput>,
    /// Per topic, the messages refused by their checks (they are skipped,
    /// as the service refuses them).
    pub rejected: BTreeMap<String, usize>,
    /// The file's channels, metadata and recovery.
    pub recording: Recording,
}

fn input_of(v: &Value) -> Option<LblInput> {
    Some(match *v {
        Value::Ahrs(m) => LblInput::Ahrs(m),
        Value::Depth(m) => LblInput::Depth(m),
        Value::Propeller(m) => LblInput::Propeller(m),
        Value::Dvl(m) => LblInput::Dvl(m),
        Value::LblReply(m) => LblInput::Reply(m),
        Value::Gps(m) => LblInput::Gps(m),
        _ => return None,
    })
}

/// Reads the LBL inputs of `path` (all of them, as the service subscribes
/// to all: the filter itself ignores the DVL unless it is its velocity
/// source); `on_progress(bytes read, file bytes)`.
pub fn read(path: &Path, on_progress: impl FnMut(u64, u64)) -> anyhow::Result<LoggedInputs> {
    let wanted = |topic: &str| TOPICS.contains(&topic);
    // (stamp, declared order, file order, input)
    let mut keyed: Vec<(u64, usize, usize, LblInput)> = Vec::new();
    let mut rejected: BTreeMap<String, usize> = BTreeMap::new();
    let recording = nauta_log::streams::visit(
        path,
        on_progress,
        |ch| wanted(&ch.topic),
        |m| {
            let Some(checked) = m.checked else {
                return Ok(());
            };
            let order = TOPICS
                .iter()
                .position(|t| *t == m.channel.topic)
                .unwrap_or(TOPICS.len());
            match checked {
                Ok(c) => {
                    if let Some(input) = input_of(&c.value) {
                        let stamp = c.value.stamp_ns();
                        keyed.push((stamp, order, keyed.len(), input));
                    }
                }
                Err(_) => *rejected.entry(m.channel.topic.clone()).or_default() += 1,
            }
            Ok(())
        },
    )?;
    keyed.sort_unstable_by_key(|(stamp, order, index, _)| (*stamp, *order, *index));
    Ok(LoggedInputs {
        inputs: keyed.into_iter().map(|k| k.3).collect(),
        rejected,
        recording,
    })
}
