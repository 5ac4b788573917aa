//! Starting and stopping the processes of a run (DESIGN §5 binary contract).

use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};

use anyhow::Context as _;
use nauta_messages::Role;
use nauta_runtime::Describe;

/// Finds a manifest's `bin`: a path (with a `/`) as given, a name next to the
/// running `nauta` executable, then on PATH. Like `cargo` running a build
/// script, `nauta check` and `nauta launch` run the binaries a user's
/// manifest names (`--describe`, `--check`, then the run). An empty `bin`
/// or a directory is refused.
pub fn find_binary(bin: &str) -> anyhow::Result<PathBuf> {
    anyhow::ensure!(
        !bin.is_empty(),
        "bin is empty: name a service binary (nauta-<role>) or a path to one"
    );
    let usable = |p: &Path| -> anyhow::Result<bool> {
        match std::fs::metadata(p) {
            Ok(m) if m.is_dir() => anyhow::bail!("{} is a directory, not a binary", p.display()),
            Ok(m) => Ok(m.is_file()),
            Err(_) => Ok(false),
        }
    };
    if bin.contains('/') {
        let p = PathBuf::from(bin);
        if usable(&p)? {
            return Ok(p);
        }
        anyhow::bail!("binary {bin:?} not found");
    }
    if let Some(dir) = own_dir() {
        let p = dir.join(bin);
        if usable(&p)? {
            return Ok(p);
        }
    }
    if let Some(path) = std::env::var_os("PATH") {
        for dir in std::env::split_paths(&path) {
            let p = dir.join(bin);
            if usable(&p)? {
                return Ok(p);
            }
        }
    }
    anyhow::bail!(
        "binary {bin:?} not found next to nauta or on PATH (build the workspace: cargo build --release)"
    )
}

/// The directory of the running `nauta` executable.
fn own_dir() -> Option<PathBuf> {
    std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(Path::to_path_buf))
}

/// Whether nauta ships a service binary (`nauta-<role>`) for `role`: every
/// role but the launcher itself, replays (`nauta replay`), tests and unknown.
fn is_service_role(role: Role) -> bool {
    !matches!(
        role,
        Role::Unknown | Role::Launcher | Role::Replay | Role::Test
    )
}

/// Finds one of nauta's own service binaries: `bin` must be `nauta-<role>`
/// for a role nauta ships, and is taken only from beside the running
/// `nauta` (never a path, never from PATH). What a recording's manifest may
/// start.
pub fn find_service_binary(bin: &str) -> anyhow::Result<PathBuf> {
    let known: Vec<String> = Role::ALL
        .into_iter()
        .filter(|r| is_service_role(*r))
        .map(|r| format!("nauta-{}", r.name()))
        .collect();
    anyhow::ensure!(
        known.iter().any(|k| k == bin),
        "{bin:?} is not one of nauta's service binaries ({})",
        known.join(", ")
    );
    let p = own_dir()
        .map(|d| d.join(bin))
        .context("cannot locate the nauta executable")?;
    anyhow::ensure!(
        p.is_file(),
        "{} not found beside nauta (build the workspace: cargo build --release)",
        p.display()
    );
    Ok(p)
}

/// Runs `bin --describe` and parses its answer.
pub fn describe(bin: &Path) -> anyhow::Result<Describe> {
    let out = Command::new(bin)
        .arg("--describe")
        .stderr(Stdio::inherit())
        .output()
        .with_context(|| format!("cannot run {} --describe", bin.display()))?;
    anyhow::ensure!(
        out.status.success(),
        "{} --describe failed: {}",
        bin.display(),
        out.status
    );
    serde_json::from_slice(&out.stdout)
        .with_context(|| format!("{} --describe printed invalid JSON", bin.display()))
}

/// Runs `bin --manifest FILE --process NAME --check [--variant V]`: the
/// binary validates its own parameters. The error is the binary's message.
pub fn check(
    bin: &Path,
    manifest: &Path,
    process: &str,
    variant: Option<&str>,
) -> anyhow::Result<()> {
    let mut cmd = Command::new(bin);
    cmd.arg("--manifest")
        .arg(manifest)
        .args(["--process", process, "--check"]);
    if let Some(v) = variant {
        cmd.args(["--variant", v]);
    }
    let out = cmd
        .env("NAUTA_LOG", "error")
        .stdin(Stdio::null())
        .output()
        .with_context(|| format!("cannot run {} --check", bin.display()))?;
    if out.status.success() {
        return Ok(());
    }
    let msg = String::from_utf8_lossy(&out.stderr);
    let msg = msg.trim();
    anyhow::bail!(
        "{}",
        if msg.is_empty() {
            format!("{} --check failed: {}", bin.display(), out.status)
        } else {
            msg.to_owned()
        }
    )
}

/// A started process.
#[derive(Debug)]
pub struct Running {
    /// Name in the manifest.
    pub name: String,
    /// The child.
    pub child: Child,
    /// Exit status, once reaped.
    pub status: Option<ExitStatus>,
}

/// What to start.
#[derive(Debug, Clone)]
pub struct Launch<'a> {
    /// Binary path.
    pub bin: &'a Path,
    /// Process name.
    pub name: &'a str,
    /// Effective manifest file.
    pub manifest: &'a Path,
    /// Namespace.
    pub namespace: &'a str,
    /// Instance.
    pub instance: u32,
    /// Variant, if any.
    pub variant: Option<&'a str>,
    /// Start in standby (a source waits for ACTIVATE).
    pub standby: bool,
    /// Extra arguments from the manifest.
    pub args: &'a [String],
    /// Warm start of a restarted or swapped-in process.
    pub warm: Option<Warm<'a>>,
}

/// What a process restarted mid-run is handed (`--snapshot`, `--resume-after`).
#[derive(Debug, Clone, Copy)]
pub struct Warm<'a> {
    /// The role's latest snapshot message, encoded, in a file.
    pub snapshot: Option<&'a Path>,
    /// The last output stamp seen from the role.
    pub resume_after_ns: Option<u64>,
}

/// Starts a process in its own process group, set to receive SIGTERM if the
/// launcher dies (so no orphans are left, even after `kill -9` of the launcher).
pub fn spawn(l: &Launch<'_>) -> anyhow::Result<Running> {
    let mut cmd = Command::new(l.bin);
    cmd.arg("--manifest")
        .arg(l.manifest)
        .args(["--process", l.name, "--namespace", l.namespace])
        .args(["--instance", &l.instance.to_string()]);
    if let Some(v) = l.variant {
        cmd.args(["--variant", v]);
    }
    if l.standby {
        cmd.arg("--standby");
    }
    if let Some(w) = &l.warm {
        if let Some(f) = w.snapshot {
            cmd.arg("--snapshot").arg(f);
        }
        if let Some(t) = w.resume_after_ns {
            cmd.args(["--resume-after", &t.to_string()]);
        }
    }
    // The launcher's command line, for the logger's metadata.
    let command_line: Vec<String> = std::env::args().collect();
    cmd.args(l.args)
        .env("NAUTA_COMMAND_LINE", command_line.join(" "))
        .stdin(Stdio::null())
        .process_group(0);
    // SAFETY: prctl is async-signal-safe and touches only the calling (child) process.
    unsafe {
        cmd.pre_exec(|| {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let child = cmd
        .spawn()
        .with_context(|| format!("cannot start {} ({})", l.name, l.bin.display()))?;
    Ok(Running {
        name: l.name.to_owned(),
        child,
        status: None,
    })
}

impl Running {
    /// Reaps the child if it has exited; true when it has.
    pub fn poll(&mut self) -> bool {
        if self.status.is_some() {
            return true;
        }
        match self.child.try_wait() {
            Ok(Some(s)) => {
                self.status = Some(s);
                true
            }
            Ok(None) => false,
            Err(_) => false,
        }
    }

    /// Sends SIGTERM (no effect once exited).
    pub fn terminate(&self) {
        if self.status.is_none() {
            // SAFETY: plain kill(2) on our own child's pid.
            unsafe {
                libc::kill(self.child.id() as i32, libc::SIGTERM);
            }
        }
    }

    /// Sends SIGKILL.
    pub fn kill(&mut self) {
        if self.status.is_none() {
            let _ = self.child.kill();
        }
    }

    /// Exit code, or minus the signal that ended it.
    pub fn code(&self) -> Option<i32> {
        self.status
            .map(|s| s.code().unwrap_or_else(|| -s.signal().unwrap_or(0)))
    }
}
