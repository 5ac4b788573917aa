//! Controlling a running pipeline from another shell (DESIGN §9):
//! `nauta status`, `nauta stop`, `nauta restart P`, `nauta swap P V`.
//!
//! Every `nauta launch` registers its run in its run directory
//! (`<run directory>/<namespace>/status.json`, in this user's private
//! run directory, see `nauta_runtime::run_files`; rewritten every second and after
//! every change): the launcher's pid and each process's pid, variant, state,
//! uptime, restarts and swaps (counted apart), rates and losses (from the
//! processes' health). `status`
//! reads it; the commands go to the launcher over iceoryx2 request-response
//! (`launcher/control/0` in the run's namespace).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::{Context as _, bail};
use nauta_messages::*;
use nauta_runtime::control::pipeline_control_name;
use nauta_runtime::run_files;
use nauta_runtime::{Context, Namespace, PipelineClient};
use serde::{Deserialize, Serialize};

use crate::monitor::Observer;
use crate::supervisor::Supervisor;

/// One process in `status.json` (and `nauta status --json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ProcessStatus {
    /// Name in the manifest.
    pub name: String,
    /// Role.
    pub role: String,
    /// Pid of the running instance (0 once exited).
    pub pid: u32,
    /// Instance number (restarts and swaps increment it).
    pub instance: u32,
    /// Variant running.
    pub variant: String,
    /// `starting`, `ready`, `running`, `standby`, `draining`, `stopped`, `exited`, `restarting`.
    pub state: String,
    /// Seconds since the running instance started.
    pub uptime_s: f64,
    /// Restarts so far (policy or `nauta restart`).
    pub restarts: u32,
    /// Swaps so far.
    pub swaps: u32,
    /// Messages accepted per second (last health interval).
    pub inputs_per_s: f64,
    /// Messages published per second (last health interval).
    pub outputs_per_s: f64,
    /// Messages rejected so far (this instance).
    pub rejected: u64,
    /// Messages lost so far (this instance).
    pub dropped: u64,
}

/// `status.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunStatus {
    /// The run's namespace.
    pub namespace: String,
    /// The manifest it runs.
    pub manifest: String,
    /// `sim` or `wall`.
    pub clock: String,
    /// Pid of `nauta launch`.
    pub launcher_pid: u32,
    /// When the run started, Unix seconds.
    pub started_unix_s: f64,
    /// The processes, in start order.
    pub processes: Vec<ProcessStatus>,
}

fn state_name(s: u32) -> &'static str {
    match s {
        state::STARTING => "starting",
        state::READY => "ready",
        state::RUNNING => "running",
        state::STANDBY => "standby",
        state::DRAINING => "draining",
        state::STOPPED => "stopped",
        _ => "unknown",
    }
}

/// Writes a run's `status.json`.
#[derive(Debug)]
pub struct StatusWriter {
    path: PathBuf,
    namespace: String,
    manifest: String,
    clock: String,
    started_unix_s: f64,
    last: Option<Instant>,
}

impl StatusWriter {
    /// For the run in `run_dir`.
    pub fn new(run_dir: &Path, namespace: &str, manifest: &Path, clock: &str) -> Self {
        Self {
            path: run_dir.join("status.json"),
            namespace: namespace.to_owned(),
            manifest: manifest.display().to_string(),
            clock: clock.to_owned(),
            started_unix_s: SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64()),
            last: None,
        }
    }

    /// Rewrites the file if a second has passed (or `now` is set).
    pub fn update(&mut self, sup: &mut Supervisor, obs: &Observer, force: bool) {
        if !force
            && self
                .last
                .is_some_and(|t| t.elapsed() < Duration::from_secs(1))
        {
            return;
        }
        self.last = Some(Instant::now());
        let status = self.status(sup, obs);
        // A new file created exclusively and renamed over: a symlink planted
        // at the path is replaced, never followed.
        let written = serde_json::to_vec_pretty(&status)
            .map_err(anyhow::Error::from)
            .and_then(|b| Ok(run_files::replace_file(&self.path, &b)?));
        if let Err(e) = written {
            tracing::warn!(error = %e, path = %self.path.display(), "status not written");
        }
    }

    fn status(&self, sup: &mut Supervisor, obs: &Observer) -> RunStatus {
        let processes = sup
            .members
            .iter_mut()
            .map(|m| {
                let exited = m.child.poll();
                let health = obs
                    .latest_health
                    .get(&health_service(m.role.name()))
                    .filter(|(_, (_, h))| h.header.instance == m.instance);
                let (rates, state, rejected, dropped) = match health {
                    Some((prev, (t1, h1))) => {
                        let rates = prev
                            .filter(|(_, h0)| h0.header.instance == h1.header.instance)
                            .map(|(t0, h0)| {
                                let dt = t1.duration_since(t0).as_secs_f64().max(1e-3);
                                (
                                    h1.inputs.saturating_sub(h0.inputs) as f64 / dt,
                                    h1.outputs.saturating_sub(h0.outputs) as f64 / dt,
                                )
                            })
                            .unwrap_or((0.0, 0.0));
                        (rates, state_name(h1.state), h1.rejected, h1.dropped)
                    }
                    None => ((0.0, 0.0), "starting", 0, 0),
                };
                let state = if m.restarting() {
                    "restarting"
                } else if exited {
                    "exited"
                } else {
                    state
                };
                ProcessStatus {
                    name: m.name.clone(),
                    role: m.role.name().to_owned(),
                    pid: if exited { 0 } else { m.child.child.id() },
                    instance: m.instance,
                    variant: m.variant.clone().unwrap_or_default(),
                    state: state.to_owned(),
                    uptime_s: m.started.elapsed().as_secs_f64(),
                    restarts: m.restarts,
                    swaps: m.swaps,
                    inputs_per_s: rates.0,
                    outputs_per_s: rates.1,
                    rejected,
                    dropped,
                }
            })
            .collect();
        RunStatus {
            namespace: self.namespace.clone(),
            manifest: self.manifest.clone(),
            clock: self.clock.clone(),
            launcher_pid: std::process::id(),
            started_unix_s: self.started_unix_s,
            processes,
        }
    }
}

fn alive(pid: u32) -> bool {
    // SAFETY: kill(2) with signal 0 only checks that the process exists.
    pid > 0 && unsafe { libc::kill(pid as i32, 0) } == 0
}

/// Largest `status.json` read.
const MAX_STATUS_BYTES: u64 = 4 << 20;

/// The runs this user's launchers registered on this machine whose launcher
/// is alive. Only this user's private run directory and the directories and
/// files in it that this user owns are trusted (anything else is skipped
/// with a warning); a run directory that is not private is an error.
fn running_pipelines() -> anyhow::Result<Vec<RunStatus>> {
    let mut out = Vec::new();
    let runs = run_files::runs_dir_path();
    if std::fs::symlink_metadata(&runs).is_err() {
        return Ok(out);
    }
    run_files::check_private_dir(&runs)?;
    let dirs =
        std::fs::read_dir(&runs).with_context(|| format!("cannot read {}", runs.display()))?;
    for d in dirs.filter_map(|d| d.ok()) {
        let path = d.path();
        if Namespace::new(&d.file_name().to_string_lossy()).is_err() {
            continue;
        }
        let read = run_files::check_private_dir(&path)
            .and_then(|()| run_files::read_owned(&path.join("status.json"), MAX_STATUS_BYTES));
        let bytes = match read {
            Ok(b) => b,
            Err(run_files::RunFileError::Io { source, .. })
                if source.kind() == std::io::ErrorKind::NotFound =>
            {
                continue;
            }
            Err(e) => {
                tracing::warn!("{e}; skipped");
                continue;
            }
        };
        if let Ok(s) = serde_json::from_slice::<RunStatus>(&bytes)
            && alive(s.launcher_pid)
        {
            out.push(s);
        }
    }
    out.sort_by(|a, b| a.started_unix_s.total_cmp(&b.started_unix_s));
    Ok(out)
}

/// The running pipeline named `namespace`, or the only one.
pub fn find(namespace: Option<&str>) -> anyhow::Result<RunStatus> {
    let runs = running_pipelines()?;
    match namespace {
        Some(ns) => runs
            .into_iter()
            .find(|r| r.namespace == ns)
            .with_context(|| format!("no pipeline running in namespace {ns:?} on this machine")),
        None => match runs.len() {
            0 => bail!("no pipeline is running on this machine (start one with nauta launch)"),
            1 => Ok(runs.into_iter().next().context("one run")?),
            _ => bail!(
                "{} pipelines are running; choose one with --namespace: {}",
                runs.len(),
                runs.iter()
                    .map(|r| format!("{} ({})", r.namespace, r.manifest))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        },
    }
}

/// `nauta status`.
pub fn status(json: bool, namespace: Option<&str>) -> anyhow::Result<()> {
    let run = find(namespace)?;
    if json {
        println!("{}", serde_json::to_string(&run)?);
        return Ok(());
    }
    let age = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
        - run.started_unix_s;
    println!(
        "run {} ({}, {} clock), launcher pid {}, up {:.0} s",
        run.namespace, run.manifest, run.clock, run.launcher_pid, age
    );
    println!(
        "{:<12} {:>8} {:>4} {:<10} {:<10} {:>9} {:>8} {:>5} {:>9} {:>9} {:>8} {:>8}",
        "process",
        "pid",
        "inst",
        "variant",
        "state",
        "uptime s",
        "restarts",
        "swaps",
        "in/s",
        "out/s",
        "rejected",
        "dropped"
    );
    for p in &run.processes {
        println!(
            "{:<12} {:>8} {:>4} {:<10} {:<10} {:>9.1} {:>8} {:>5} {:>9.1} {:>9.1} {:>8} {:>8}",
            p.name,
            p.pid,
            p.instance,
            p.variant,
            p.state,
            p.uptime_s,
            p.restarts,
            p.swaps,
            p.inputs_per_s,
            p.outputs_per_s,
            p.rejected,
            p.dropped
        );
    }
    Ok(())
}

/// Sends one command to the launcher of the chosen run.
pub fn command(
    namespace: Option<&str>,
    command: u32,
    process: &str,
    variant: &str,
) -> anyhow::Result<()> {
    // Names travel in 32-byte fields: a longer one would be cut to another
    // process's or variant's name.
    for (what, name) in [("process", process), ("variant", variant)] {
        anyhow::ensure!(
            name.len() <= nauta_runtime::manifest::MAX_PROCESS_NAME,
            "no {what} {name:?} can exist: names have at most {} bytes",
            nauta_runtime::manifest::MAX_PROCESS_NAME
        );
    }
    let run = find(namespace)?;
    let ns = Namespace::new(&run.namespace)?;
    let mut settings = Context::settings(Role::Test);
    settings.process = format!("nauta-cli-{}", std::process::id());
    let ctx = Context::new(&ns, settings)?;
    let result = (|| {
        let client = PipelineClient::open_named(&ctx, &pipeline_control_name())?;
        let response = client.request(
            &ctx,
            PipelineRequest {
                header: Header::new(0, 0, Role::Test, 0),
                command,
                pad: 0,
                process: to_fixed_str(process),
                variant: to_fixed_str(variant),
            },
            Duration::from_secs(10),
        )?;
        if response.status != pipeline_status::OK {
            bail!("the launcher refused: {}", fixed_str(&response.detail));
        }
        Ok(())
    })();
    ctx.finish();
    result
}
