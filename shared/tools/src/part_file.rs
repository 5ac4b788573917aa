//! No partial output: a command writes its file to a hidden part file
//! beside it (`nauta_log::export::part_path`) and renames it into place when
//! complete; an error removes it, and so do SIGINT (Ctrl-C), SIGTERM and
//! SIGHUP, which end the process (exit 128 + signal).

use std::path::Path;

use anyhow::Context as _;

/// The part file being written, for the signal handler (set once, before
/// the handler is installed).
static PART_FILE: std::sync::OnceLock<std::ffi::CString> = std::sync::OnceLock::new();

extern "C" fn remove_part_and_exit(signal: libc::c_int) {
    // Only async-signal-safe calls: unlink and _exit.
    if let Some(path) = PART_FILE.get() {
        // SAFETY: `path` is a NUL-terminated string that lives for the program.
        unsafe { libc::unlink(path.as_ptr()) };
    }
    // SAFETY: _exit ends the process at once; 128 + signal as a shell reports it.
    unsafe { libc::_exit(128 + signal) };
}

/// SIGINT (Ctrl-C), SIGTERM or SIGHUP from now on remove the part file of
/// `output` and end the process (exit 128 + signal): an interrupted command
/// leaves nothing behind. One output per process.
pub fn remove_part_file_on_signal(output: &Path) -> anyhow::Result<()> {
    use std::os::unix::ffi::OsStrExt as _;
    let part = nauta_log::export::part_path(output)
        .with_context(|| format!("the output path {} names no file", output.display()))?;
    let c = std::ffi::CString::new(part.as_os_str().as_bytes())
        .with_context(|| format!("the output path {} holds a NUL byte", output.display()))?;
    let _ = PART_FILE.set(c);
    for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
        // SAFETY: the handler only calls async-signal-safe functions and
        // reads a OnceLock that was set before it was installed.
        let previous = unsafe {
            libc::signal(
                signal,
                remove_part_and_exit as extern "C" fn(libc::c_int) as libc::sighandler_t,
            )
        };
        anyhow::ensure!(
            previous != libc::SIG_ERR,
            "cannot handle signal {signal}: {}",
            std::io::Error::last_os_error()
        );
    }
    Ok(())
}

/// Writes `output` through its part file: `write` gets the part file's
/// path; when it succeeds the part file is renamed to `output`, when it
/// fails (or a signal comes) the part file is removed and `output` is left
/// as it was.
pub fn write_via_part(
    output: &Path,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    anyhow::ensure!(
        !output.is_dir(),
        "cannot write {}: it is a directory",
        output.display()
    );
    let part = nauta_log::export::part_path(output)
        .with_context(|| format!("the output path {} names no file", output.display()))?;
    remove_part_file_on_signal(output)?;
    let result = write(&part).and_then(|()| {
        std::fs::rename(&part, output).with_context(|| format!("cannot write {}", output.display()))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&part);
    }
    result
}
