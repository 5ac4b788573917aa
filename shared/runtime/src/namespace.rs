//! Per-run namespaces (DESIGN §6): every run gets its own iceoryx2 `global.prefix`,
//! so runs and tests never see each other's services, and its own resources can
//! be listed and removed.

use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

use iceoryx2::config::Config;
use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;

use crate::Ipc;

/// Longest namespace accepted (the prefix ends up in file names).
pub const MAX_LEN: usize = 32;

/// A validated run namespace: 1-32 characters of `[A-Za-z0-9-]`.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Namespace(String);

/// The namespace is not acceptable.
#[derive(Debug, thiserror::Error)]
#[error("invalid namespace {0:?}: use 1-{MAX_LEN} characters of A-Z, a-z, 0-9 and '-'")]
pub struct NamespaceError(pub String);

impl Namespace {
    /// Validates `name`.
    pub fn new(name: &str) -> Result<Self, NamespaceError> {
        let ok = !name.is_empty()
            && name.len() <= MAX_LEN
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-');
        if ok {
            Ok(Namespace(name.to_owned()))
        } else {
            Err(NamespaceError(name.to_owned()))
        }
    }

    /// A namespace unique on this machine: pid, time and a per-process counter.
    pub fn unique() -> Self {
        static COUNTER: AtomicU32 = AtomicU32::new(0);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos() as u64)
            .unwrap_or(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        Namespace(format!(
            "r{:x}-{:x}-{:x}",
            std::process::id(),
            nanos & 0xff_ffff_ffff,
            n
        ))
    }

    /// The namespace as given.
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// The iceoryx2 prefix of every resource of this run (`nauta_<ns>_`).
    pub fn prefix(&self) -> String {
        format!("nauta_{}_", self.0)
    }

    /// The iceoryx2 configuration of this run.
    pub fn config(&self) -> anyhow::Result<Config> {
        let mut config = Config::global_config().clone();
        config.global.prefix = FileName::new(self.prefix().as_bytes())
            .map_err(|e| anyhow::anyhow!("namespace prefix {:?}: {e:?}", self.prefix()))?;
        // Dead nodes of this run are removed whenever a node starts or a service opens.
        config.global.node.cleanup_dead_nodes_on_creation = true;
        config.global.service.cleanup_dead_nodes_on_open = true;
        Ok(config)
    }

    /// Removes every resource of this run once its last process has left:
    /// the stale resources of dead nodes, then what iceoryx2 keeps per namespace
    /// on purpose (its persistent global management segment) and anything else
    /// bearing the run's prefix. For a process of the run on its way out
    /// ([`crate::Context::finish`]). Nothing is touched while any node of the run
    /// is alive or in a state that cannot be read (being created). Returns the
    /// number of files removed.
    pub fn remove_if_unused(&self) -> anyhow::Result<usize> {
        let config = self.config()?;
        let report = cleanup_dead_nodes(&config)?;
        if report.alive > 0 || report.unknown > 0 || report.failed > 0 {
            return Ok(0);
        }
        Ok(self.remove_files(&config))
    }

    /// Like [`Namespace::remove_if_unused`], for a namespace this process is not
    /// part of (another run's, found by [`Namespace::on_this_machine`]): it is
    /// removed only on evidence that it was abandoned, i.e. a dead node was found,
    /// or no node exists at all and its newest file is older than `grace`. A run
    /// that is starting right now (its first node not yet readable) is left alone.
    pub fn remove_if_abandoned(&self, grace: Duration) -> anyhow::Result<usize> {
        let config = self.config()?;
        let report = cleanup_dead_nodes(&config)?;
        tracing::debug!(namespace = %self, ?report, "namespace found");
        if report.alive > 0 || report.unknown > 0 || report.failed > 0 {
            return Ok(0);
        }
        let crashed = report.removed > 0;
        if !crashed && self.newest_file_age(&config).is_none_or(|age| age < grace) {
            return Ok(0);
        }
        Ok(self.remove_files(&config))
    }

    fn paths(&self, config: &Config) -> Vec<std::path::PathBuf> {
        let mut paths: Vec<std::path::PathBuf> = self
            .shm_files()
            .into_iter()
            .map(|f| std::path::Path::new("/dev/shm").join(f))
            .collect();
        let mut rest = Vec::new();
        walk(
            std::path::Path::new(&config.global.root_path().to_string()),
            &self.prefix(),
            &mut rest,
        );
        paths.extend(rest.into_iter().map(std::path::PathBuf::from));
        paths
    }

    fn newest_file_age(&self, config: &Config) -> Option<Duration> {
        self.paths(config)
            .iter()
            .filter_map(|p| std::fs::metadata(p).and_then(|m| m.modified()).ok())
            .filter_map(|t| t.elapsed().ok())
            .min()
    }

    fn remove_files(&self, config: &Config) -> usize {
        self.paths(config)
            .iter()
            .filter(|p| std::fs::remove_file(p).is_ok())
            .count()
    }

    /// Tightens what iceoryx2 allows in this run's shared memory: every
    /// segment it creates is 0600 except its per-prefix management segment
    /// (`…global_mgmt`), which it makes 0666 on purpose (no configuration
    /// changes that); nauta's runs are one user's, so it is made 0600 too.
    /// A segment of this run that another user owns means that user's run
    /// has this namespace: refused. For a process that has just created its
    /// node ([`crate::Context::new`]).
    pub fn secure_shared_memory(&self) -> anyhow::Result<()> {
        use std::os::unix::fs::{MetadataExt as _, OpenOptionsExt as _, PermissionsExt as _};
        for name in self.shm_files() {
            let path = std::path::Path::new("/dev/shm").join(&name);
            let Ok(f) = std::fs::OpenOptions::new()
                .read(true)
                .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC | libc::O_NONBLOCK)
                .open(&path)
            else {
                continue; // removed meanwhile, or not ours to open (checked below)
            };
            let m = f.metadata()?;
            anyhow::ensure!(
                m.uid() == crate::run_files::uid(),
                "{} belongs to uid {}: another user's run uses namespace {self}; choose another --namespace",
                path.display(),
                m.uid()
            );
            // Only a segment in its final, world-accessible state: one being
            // initialised signals readiness through its permissions.
            if name.ends_with(".global_mgmt") && m.mode() & 0o777 == 0o666 {
                f.set_permissions(std::fs::Permissions::from_mode(0o600))?;
            }
        }
        Ok(())
    }

    /// Files of this run in /dev/shm (shared memory segments), by name.
    pub fn shm_files(&self) -> Vec<String> {
        files_with_prefix("/dev/shm", &self.prefix())
    }

    /// The namespaces that have files on this machine (in /dev/shm or under
    /// iceoryx2's root directory), from their prefixes.
    pub fn on_this_machine() -> Vec<Namespace> {
        let mut names = std::collections::BTreeSet::new();
        let mut files = files_with_prefix("/dev/shm", "nauta_");
        let root = Config::global_config().global.root_path().to_string();
        walk(std::path::Path::new(&root), "nauta_", &mut files);
        for f in files {
            let name = f.rsplit('/').next().unwrap_or(&f);
            if let Some((ns, _)) = name.strip_prefix("nauta_").and_then(|r| r.split_once('_'))
                && let Ok(ns) = Namespace::new(ns)
            {
                names.insert(ns.0);
            }
        }
        names.into_iter().map(Namespace).collect()
    }

    /// Every file of this run in /dev/shm and under iceoryx2's root directory.
    pub fn all_files(&self, config: &Config) -> Vec<String> {
        let mut files = self.shm_files();
        let root = config.global.root_path().to_string();
        walk(std::path::Path::new(&root), &self.prefix(), &mut files);
        files
    }
}

impl std::fmt::Display for Namespace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

fn files_with_prefix(dir: &str, prefix: &str) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut out: Vec<String> = entries
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(prefix))
        .collect();
    out.sort();
    out
}

fn walk(dir: &std::path::Path, prefix: &str, out: &mut Vec<String>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.filter_map(|e| e.ok()) {
        let path = e.path();
        if path.is_dir() {
            walk(&path, prefix, out);
        } else if e.file_name().to_string_lossy().starts_with(prefix) {
            out.push(path.to_string_lossy().into_owned());
        }
    }
}

/// What a cleanup pass found.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CleanupReport {
    /// Dead nodes whose resources were removed.
    pub removed: u64,
    /// Dead nodes that could not be removed (permissions, or another process is at it).
    pub failed: u64,
    /// Nodes still alive.
    pub alive: u64,
    /// Nodes whose state could not be read (being created, or no permission).
    pub unknown: u64,
}

/// Removes the stale resources of every dead node under `config` (processes that
/// died without cleaning up, e.g. by `kill -9`). Safe to call at any time.
pub fn cleanup_dead_nodes(config: &Config) -> anyhow::Result<CleanupReport> {
    let mut report = CleanupReport::default();
    let mut dead = Vec::new();
    Node::<Ipc>::list(config, |state| {
        match state {
            NodeState::Alive(_) => report.alive += 1,
            NodeState::Dead(view) => dead.push(view),
            NodeState::Inaccessible(_) | NodeState::Undefined(_) => report.unknown += 1,
        }
        CallbackProgression::Continue
    })
    .map_err(|e| anyhow::anyhow!("cannot list the nodes of this run: {e:?}"))?;
    for view in dead {
        let id = *view.id();
        match view.try_remove_stale_resources() {
            // Already cleaned by someone else (another process of the run
            // cleaning at the same moment, or a cleaner that was stopped half
            // way): the node is dead either way, and its files are the
            // namespace's to remove.
            Ok(()) | Err(iceoryx2::node::NodeCleanupFailure::ResourcesAlreadyCleanedUp) => {
                report.removed += 1
            }
            Err(e) => {
                tracing::debug!(node = ?id, error = ?e, "dead node not removed");
                report.failed += 1;
            }
        }
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation() {
        assert!(Namespace::new("run-1").is_ok());
        assert!(Namespace::new("").is_err());
        assert!(Namespace::new("a/b").is_err());
        assert!(Namespace::new("x".repeat(MAX_LEN + 1).as_str()).is_err());
        let a = Namespace::unique();
        let b = Namespace::unique();
        assert_ne!(a, b);
        assert!(Namespace::new(a.as_str()).is_ok(), "{a}");
    }
}
