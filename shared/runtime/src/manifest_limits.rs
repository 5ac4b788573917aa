//! The limits a manifest must keep (issue 12): value ranges, the size of
//! the file, process names, and the launcher's flags that `args` may not set.

use std::path::Path;

use anyhow::Context as _;

/// Longest mission a manifest may ask for (`run.duration_s`): 30 days.
pub const MAX_DURATION_S: f64 = 30.0 * 86_400.0;
/// Slowest and fastest `wall` pacing (`run.rate`, `--rate`).
pub const MIN_RATE: f64 = 1e-3;
/// See [`MIN_RATE`].
pub const MAX_RATE: f64 = 1e4;
/// Longest back-pressure deadline (`run.backpressure_deadline_ms`): 10 min.
pub const MAX_DEADLINE_MS: u64 = 600_000;
/// Longest restart window (`restart.window_s`): one day.
pub const MAX_WINDOW_S: f64 = 86_400.0;
/// Longest restart delay (`restart.backoff_ms`): 10 min.
pub const MAX_BACKOFF_MS: u64 = 600_000;
/// Largest manifest file read.
pub const MAX_MANIFEST_BYTES: u64 = 4 << 20;

/// Reads a manifest file: a regular file of at most [`MAX_MANIFEST_BYTES`]
/// (`/dev/zero` or a FIFO is refused, not read forever).
pub(crate) fn read_manifest(path: &Path) -> anyhow::Result<String> {
    use std::io::Read as _;
    let f = std::fs::File::open(path)
        .with_context(|| format!("cannot read manifest {}", path.display()))?;
    let m = f
        .metadata()
        .with_context(|| format!("cannot read manifest {}", path.display()))?;
    anyhow::ensure!(
        m.is_file(),
        "{}: a manifest is a regular file",
        path.display()
    );
    anyhow::ensure!(
        m.len() <= MAX_MANIFEST_BYTES,
        "{}: {} bytes; a manifest has at most {MAX_MANIFEST_BYTES}",
        path.display(),
        m.len()
    );
    let mut text = String::new();
    f.take(MAX_MANIFEST_BYTES + 1)
        .read_to_string(&mut text)
        .with_context(|| format!("cannot read manifest {}", path.display()))?;
    anyhow::ensure!(
        text.len() as u64 <= MAX_MANIFEST_BYTES,
        "{}: a manifest has at most {MAX_MANIFEST_BYTES} bytes",
        path.display()
    );
    Ok(text)
}

/// Longest process name: names travel in the 32-byte fields of run events
/// and pipeline requests.
pub const MAX_PROCESS_NAME: usize = 32;

/// The flags the launcher passes every service binary (DESIGN §5 binary
/// contract): a process's `args` may not repeat or override them.
pub const LAUNCHER_FLAGS: [&str; 9] = [
    "--manifest",
    "--process",
    "--namespace",
    "--instance",
    "--variant",
    "--standby",
    "--snapshot",
    "--resume-after",
    "--absent",
];

/// The launcher flag `arg` sets (`--namespace` or `--namespace=X`), if any.
pub(crate) fn launcher_flag(arg: &str) -> Option<&'static str> {
    let flag = arg.split_once('=').map_or(arg, |(f, _)| f);
    LAUNCHER_FLAGS.iter().copied().find(|f| *f == flag)
}

/// A process name: 1-32 bytes of A-Z, a-z, 0-9, '-' and '_' (it names
/// files, iceoryx2 nodes and fixed-size message fields).
pub(crate) fn check_process_name(name: &str) -> Result<(), String> {
    if name.is_empty() || name.len() > MAX_PROCESS_NAME {
        return Err(format!(
            "a process name has 1-{MAX_PROCESS_NAME} bytes, {name:?} has {}",
            name.len()
        ));
    }
    if !name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        return Err(format!(
            "a process name uses only A-Z, a-z, 0-9, '-' and '_', not {name:?}"
        ));
    }
    Ok(())
}
