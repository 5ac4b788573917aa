//! Run directories (`nauta_runtime::run_files`): claiming one for a launch
//! (one live run per namespace), and removing what dead runs left in them.

use std::os::fd::AsRawFd as _;
use std::os::unix::fs::{DirBuilderExt as _, OpenOptionsExt as _};
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context as _;
use nauta_runtime::Namespace;
use nauta_runtime::run_files;

/// How old the newest file of a namespace without any node must be before it
/// counts as abandoned (a run being created has fresh files and no readable
/// node yet).
pub const ABANDONED_AFTER: Duration = Duration::from_secs(10);

/// Removes what dead processes of earlier runs left on this machine: the
/// resources of dead nodes of every nauta namespace, and every file of a
/// namespace that was abandoned (see `Namespace::remove_if_abandoned`).
pub fn cleanup_stale_runs() -> usize {
    let removed = Namespace::on_this_machine()
        .into_iter()
        .map(|ns| ns.remove_if_abandoned(ABANDONED_AFTER).unwrap_or(0))
        .sum();
    // Run directories (effective manifests) of runs that left nothing else.
    let runs = run_files::runs_dir_path();
    if run_files::check_private_dir(&runs).is_ok()
        && let Ok(dirs) = std::fs::read_dir(&runs)
    {
        for d in dirs.filter_map(|d| d.ok()) {
            let name = d.file_name().to_string_lossy().into_owned();
            if stale_scratch_file(&name) {
                let _ = std::fs::remove_file(d.path());
                continue;
            }
            // A launcher holds its run directory's lock while it runs.
            let locked = std::fs::OpenOptions::new()
                .read(true)
                .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
                .open(d.path().join("lock"))
                .is_ok_and(|f| !try_lock(&f));
            if !locked
                && is_older(&d.path(), ABANDONED_AFTER)
                && let Ok(ns) = Namespace::new(&name)
                && let Ok(config) = ns.config()
                && ns.all_files(&config).is_empty()
            {
                let _ = std::fs::remove_dir_all(d.path());
            }
        }
    }
    removed
}

/// Where run directories (the effective manifest of each run) live: this
/// user's private directory (see `nauta_runtime::run_files`), created if
/// missing; refused if another user owns it or anyone else may enter it.
pub fn runs_dir() -> anyhow::Result<PathBuf> {
    Ok(run_files::runs_dir()?)
}

/// The run directory of `namespace`, claimed for this launcher: created
/// (mode 0700) with an exclusive lock held on its `lock` file for as long as
/// the returned file is open. A directory whose lock another launcher holds
/// means the namespace is in use: refused, as two runs in one namespace
/// would feed each other. A directory left by a dead launcher is removed
/// first (nothing in it is followed or reused).
pub fn claim_run_dir(namespace: &Namespace) -> anyhow::Result<(PathBuf, std::fs::File)> {
    let dir = runs_dir()?.join(namespace.as_str());
    let lock = dir.join("lock");
    let in_use = || {
        anyhow::anyhow!(
            "namespace {namespace} is in use by a running pipeline (see nauta status --namespace {namespace}); choose another --namespace or stop that run"
        )
    };
    for attempt in 0..2 {
        match std::fs::DirBuilder::new().mode(0o700).create(&dir) {
            Ok(()) => {
                // Created here: exactly 0700 whatever the umask removed (a
                // umask such as 0177 would leave 0600, which the check below
                // refuses).
                std::fs::set_permissions(&dir, std::os::unix::fs::PermissionsExt::from_mode(0o700))
                    .with_context(|| format!("cannot set the mode of {}", dir.display()))?;
                run_files::check_private_dir(&dir)?;
                let file = run_files::create_new(&lock)?;
                if !try_lock(&file) {
                    return Err(in_use());
                }
                return Ok((dir, file));
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && attempt == 0 => {
                run_files::check_private_dir(&dir)?;
                match std::fs::OpenOptions::new()
                    .read(true)
                    .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
                    .open(&lock)
                {
                    Ok(f) if !try_lock(&f) => return Err(in_use()),
                    Ok(_) => {}
                    // Being created by another launcher right now, unless old.
                    Err(_) if !is_older(&dir, ABANDONED_AFTER) => return Err(in_use()),
                    Err(_) => {}
                }
                tracing::info!(dir = %dir.display(), "removing the run directory of a run that ended");
                std::fs::remove_dir_all(&dir)
                    .with_context(|| format!("cannot remove {}", dir.display()))?;
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => return Err(in_use()),
            Err(e) => return Err(e).with_context(|| format!("cannot create {}", dir.display())),
        }
    }
    Err(in_use())
}

/// A `check-PID-….toml` or `replay-PID-….toml` whose process is gone (it
/// was killed before it removed the file).
fn stale_scratch_file(name: &str) -> bool {
    let Some(rest) = name
        .strip_prefix("check-")
        .or_else(|| name.strip_prefix("replay-"))
        .filter(|_| name.ends_with(".toml"))
    else {
        return false;
    };
    let pid: Option<i32> = rest.split('-').next().and_then(|p| p.parse().ok());
    // SAFETY: kill(2) with signal 0 only checks that the process exists.
    pid.is_some_and(|p| p > 0 && unsafe { libc::kill(p, 0) } != 0)
}

/// An exclusive, non-blocking `flock`; false when another process holds it.
fn try_lock(f: &std::fs::File) -> bool {
    // SAFETY: flock(2) on a descriptor we own; released when it is closed.
    unsafe { libc::flock(f.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) == 0 }
}

fn is_older(path: &std::path::Path, age: Duration) -> bool {
    std::fs::symlink_metadata(path)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.elapsed().ok())
        .is_some_and(|a| a > age)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scratch_files_of_dead_processes_are_stale() {
        let me = std::process::id();
        assert!(!stale_scratch_file(&format!("check-{me}-1f-0.toml")));
        assert!(!stale_scratch_file(&format!("replay-{me}-1f-0.toml")));
        // Beyond the kernel's pid limit: no such process.
        assert!(stale_scratch_file("check-2147483646-1f-0.toml"));
        assert!(stale_scratch_file("replay-2147483646-1f-0.toml"));
        assert!(!stale_scratch_file("manifest.toml"));
        assert!(!stale_scratch_file("check-2147483646-1f-0.json"));
        assert!(!stale_scratch_file("check-x-1f-0.toml"));
    }
}
