//! The launcher's supervision of a running pipeline (DESIGN §5): which
//! process runs as which instance, restarts per policy with backoff and a cap,
//! warm starts from the latest snapshot, and the run events that record it.
//!
//! A restart is decided when a child is found exited (the launcher polls every
//! tick). The dead process's shared-memory resources are removed at once, so a
//! back-pressured publisher is not held by its dead subscriber; the new
//! instance (`--instance K+1`) gets the role's latest snapshot as a file
//! (`--snapshot`) and the stamp of the last output the launcher saw from the
//! role (`--resume-after`), so that it initialises from the snapshot, replays
//! what its inputs still hold and publishes only what is new.

use std::collections::{BTreeSet, VecDeque};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use nauta_messages::*;
use nauta_runtime::control::Pending;
use nauta_runtime::{Context, ControlClient, Describe, RestartPolicy};

use crate::children::{self, Launch, Running};
use crate::monitor::{Observer, Tap};

/// Restarts allowed within the window when the manifest gives no cap.
const DEFAULT_MAX: u32 = 10;
/// Window of the cap when the manifest gives none.
const DEFAULT_WINDOW: Duration = Duration::from_secs(60);
/// Backoff when the manifest gives none: first delay, longest delay.
const DEFAULT_BACKOFF: (Duration, Duration) =
    (Duration::from_millis(20), Duration::from_millis(1000));

/// How one process is restarted.
#[derive(Debug, Clone, Copy)]
pub struct Restart {
    /// When.
    pub policy: RestartPolicy,
    /// Most restarts within `window`.
    pub max: u32,
    /// Window of the cap.
    pub window: Duration,
    /// First and longest delay before a restart.
    pub backoff: (Duration, Duration),
}

impl Restart {
    /// From a manifest section (checked by `Manifest::check`).
    pub fn from_section(r: Option<&nauta_runtime::manifest::RestartSection>) -> Self {
        let Some(r) = r else {
            return Self {
                policy: RestartPolicy::Never,
                max: DEFAULT_MAX,
                window: DEFAULT_WINDOW,
                backoff: DEFAULT_BACKOFF,
            };
        };
        Self {
            policy: RestartPolicy::parse(&r.policy).unwrap_or(RestartPolicy::Never),
            max: r.max.unwrap_or(DEFAULT_MAX),
            window: r.window_s.map_or(DEFAULT_WINDOW, Duration::from_secs_f64),
            backoff: r.backoff_ms.map_or(DEFAULT_BACKOFF, |[a, b]| {
                (Duration::from_millis(a), Duration::from_millis(b))
            }),
        }
    }

    /// Delay before the `n`-th restart within the window (1-based):
    /// `first · 2^(n−1)`, at most `longest`.
    pub fn delay(&self, n: u32) -> Duration {
        let (first, longest) = self.backoff;
        let factor = 2u32.saturating_pow(n.saturating_sub(1).min(20));
        first.saturating_mul(factor).min(longest)
    }
}

/// One process of the run.
pub struct Member {
    /// Name in the manifest.
    pub name: String,
    /// Its role.
    pub role: Role,
    bin: PathBuf,
    /// Variant running.
    pub variant: Option<String>,
    args: Vec<String>,
    /// A data source (started in standby, never restarted mid-run).
    pub source: bool,
    /// Data services it publishes (for `--resume-after`).
    outputs: Vec<String>,
    restart: Restart,
    /// Instance running (or last run).
    pub instance: u32,
    /// The child.
    pub child: Running,
    /// When the current instance was started.
    pub started: Instant,
    /// Restarts so far (policy or `nauta restart`).
    pub restarts: u32,
    /// Swaps so far.
    pub swaps: u32,
    recent: VecDeque<Instant>,
    pending: Option<Instant>,
    /// Why the run must stop because of this process, once decided.
    pub failure: Option<String>,
    settled: bool,
    /// Variants its binary implements.
    pub variants: Vec<String>,
    /// `nauta restart`: on the next exit, start again at once, whatever the
    /// policy.
    forced: bool,
    /// `nauta swap`: the variant asked for, until the tick starts the swap.
    swap_request: Option<String>,
    /// A hot swap in progress.
    swap: Option<Swap>,
}

/// A hot swap in progress (DESIGN §5): the new variant runs in standby beside
/// the old one until the old one is deactivated and the new one activated at
/// the old one's last published stamp.
enum Swap {
    /// The new instance starts in standby from the latest snapshot.
    Starting {
        new: Running,
        instance: u32,
        variant: String,
        since: Instant,
    },
    /// DEACTIVATE sent to the old instance; its answer names its last stamp.
    Deactivating {
        new: Running,
        instance: u32,
        variant: String,
        since: Instant,
        _client: ControlClient,
        pending: Pending<ControlRequest, ControlResponse>,
    },
    /// ACTIVATE sent to the new instance with that boundary.
    Activating {
        new: Running,
        instance: u32,
        variant: String,
        since: Instant,
        _client: ControlClient,
        pending: Pending<ControlRequest, ControlResponse>,
    },
}

/// How long a swap phase may take before the swap is abandoned.
const SWAP_PHASE_TIMEOUT: Duration = Duration::from_secs(15);

impl Member {
    /// Whether a restart is scheduled or asked for.
    pub fn restarting(&self) -> bool {
        self.pending.is_some() || self.forced || self.swap.is_some() || self.swap_request.is_some()
    }
}

/// What a tick found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    /// The run goes on.
    Running,
    /// Every process has exited and none will be restarted.
    Finished,
    /// A process failed beyond its policy: the run stops.
    Failed(String),
}

/// The processes of a run and their supervision.
pub struct Supervisor {
    /// The members, in start order.
    pub members: Vec<Member>,
    /// Instances replaced by a swap, until they have exited: (child, since).
    retiring: Vec<(Running, Instant)>,
    manifest_file: PathBuf,
    /// The effective manifest, to restore it if the run directory is removed.
    manifest_text: Vec<u8>,
    run_dir: PathBuf,
    namespace: String,
}

impl Supervisor {
    /// An empty supervisor for a run.
    pub fn new(manifest_file: &Path, run_dir: &Path, namespace: &str) -> Self {
        Self {
            members: Vec::new(),
            retiring: Vec::new(),
            manifest_file: manifest_file.to_owned(),
            manifest_text: nauta_runtime::run_files::read_owned(manifest_file, 64 << 20)
                .unwrap_or_default(),
            run_dir: run_dir.to_owned(),
            namespace: namespace.to_owned(),
        }
    }

    /// Starts instance 0 of a process (sources in standby).
    #[allow(clippy::too_many_arguments)]
    pub fn start(
        &mut self,
        name: &str,
        bin: &Path,
        describe: &Describe,
        variant: Option<&str>,
        args: &[String],
        restart: Restart,
    ) -> anyhow::Result<()> {
        let source = describe.is_source();
        let child = children::spawn(&Launch {
            bin,
            name,
            manifest: &self.manifest_file,
            namespace: &self.namespace,
            instance: 0,
            variant,
            standby: source,
            args,
            warm: None,
        })?;
        let outputs = describe
            .outputs
            .iter()
            .map(|o| o.service.clone())
            .filter(|s| {
                !(s.ends_with("/progress") || s.ends_with("/health") || s.ends_with("/snapshot"))
            })
            .collect();
        self.members.push(Member {
            name: name.to_owned(),
            role: Role::from_name(&describe.role).unwrap_or(Role::Unknown),
            bin: bin.to_owned(),
            variant: variant
                .map(str::to_owned)
                .or_else(|| describe.variants.first().cloned()),
            args: args.to_vec(),
            source,
            outputs,
            restart,
            instance: 0,
            child,
            started: Instant::now(),
            restarts: 0,
            swaps: 0,
            recent: VecDeque::new(),
            pending: None,
            failure: None,
            settled: false,
            variants: describe.variants.clone(),
            forced: false,
            swap_request: None,
            swap: None,
        });
        Ok(())
    }

    /// `nauta restart P` (`variant` None) or `nauta swap P V`: stops the
    /// process (SIGTERM) and starts it again at once, warm, whatever its
    /// policy. Err explains a refusal.
    pub fn request_restart(
        &mut self,
        name: &str,
        variant: Option<&str>,
    ) -> Result<(), (u32, String)> {
        let m = self.members.iter_mut().find(|m| m.name == name).ok_or((
            pipeline_status::UNKNOWN_PROCESS,
            format!("no process {name}"),
        ))?;
        if let Some(v) = variant
            && !m.variants.iter().any(|x| x == v)
        {
            return Err((pipeline_status::UNKNOWN_VARIANT, format!("no variant {v}")));
        }
        if m.source {
            return Err((pipeline_status::REFUSED, format!("{name} is a source")));
        }
        if m.settled || m.restarting() || m.child.poll() {
            return Err((
                pipeline_status::REFUSED,
                format!("{name} is not running or busy"),
            ));
        }
        match variant {
            // A swap starts the new variant beside the old one (next tick).
            Some(v) => m.swap_request = Some(v.to_owned()),
            None => {
                m.forced = true;
                m.child.terminate();
            }
        }
        Ok(())
    }

    /// The children, for start-up waits and shutdown.
    pub fn children_mut(&mut self) -> impl Iterator<Item = &mut Running> {
        self.members.iter_mut().map(|m| &mut m.child)
    }

    /// Checks every child: reports exits, schedules and performs restarts.
    /// `taps` (drained just before) give the latest snapshots and stamps.
    pub fn tick(
        &mut self,
        ctx: &mut Context,
        taps: &mut [Box<dyn Tap>],
        obs: &mut Observer,
        ready: &BTreeSet<(String, u32)>,
    ) -> anyhow::Result<Outcome> {
        self.advance_swaps(ctx, taps, ready)?;
        // Once a source has ended its stream, the run is draining: nothing
        // more is restarted.
        let draining = self
            .members
            .iter_mut()
            .any(|m| m.source && m.child.poll() && m.child.code() == Some(0));
        let sources: Vec<String> = self
            .members
            .iter()
            .filter(|m| m.source)
            .map(|m| progress_service(m.role.name()))
            .collect();
        let now = Instant::now();
        for i in 0..self.members.len() {
            let m = &mut self.members[i];
            // During a swap the old instance exits on purpose.
            if m.settled || m.pending.is_some() || m.swap.is_some() || !m.child.poll() {
                continue;
            }
            let code = m.child.code().unwrap_or(-1);
            publish(ctx, event_kind::EXITED, m, code);
            // What it published before it died is taken first (a removed
            // publisher's unread messages are lost to its subscribers, and
            // `--resume-after` is the last stamp the taps saw); then its
            // shared memory goes, not at a publisher's deadline.
            for t in taps.iter_mut() {
                t.drain(obs)?;
            }
            let report = ctx.cleanup_dead_nodes();
            tracing::debug!(?report, process = %m.name, "cleaned up after exit");
            if std::mem::take(&mut m.forced) {
                m.pending = Some(now);
                continue;
            }
            // A consumer ends by itself only once its inputs ended (a
            // source's end of stream, which it saw before it exited: take
            // what the taps hold before deciding). Exit 0 before that is a
            // failure, not the end of the run.
            let early = code == 0 && !m.source && !inputs_ended(&sources, obs) && {
                for t in taps.iter_mut() {
                    t.drain(obs)?;
                }
                !inputs_ended(&sources, obs)
            };
            let m = &mut self.members[i];
            if early {
                tracing::error!(process = %m.name, "exited 0 before its inputs ended (no end of stream seen)");
            }
            let failed = code != 0 || early;
            let wants = match m.restart.policy {
                RestartPolicy::Never => false,
                RestartPolicy::OnFailure => failed,
                RestartPolicy::Always => true,
            };
            let why = if early {
                format!("{} exited 0 before its inputs ended", m.name)
            } else {
                format!("{} exited {code}", m.name)
            };
            if !wants || draining || m.source {
                m.settled = true;
                if failed {
                    m.failure = Some(why);
                }
                continue;
            }
            while m
                .recent
                .front()
                .is_some_and(|t| now.duration_since(*t) > m.restart.window)
            {
                m.recent.pop_front();
            }
            if m.recent.len() as u32 >= m.restart.max {
                m.settled = true;
                m.failure = Some(format!(
                    "{why} and was restarted {} times within {:?}",
                    m.restart.max, m.restart.window
                ));
                continue;
            }
            m.recent.push_back(now);
            let delay = m.restart.delay(m.recent.len() as u32);
            tracing::warn!(process = %m.name, code, ?delay, "process exited; restarting");
            m.pending = Some(now + delay);
        }
        if self
            .members
            .iter()
            .any(|m| m.pending.is_some_and(|t| t <= now))
        {
            // The dead process published its last messages before it died:
            // take them all, so that `--resume-after` is its true last stamp.
            for t in taps.iter_mut() {
                t.drain(obs)?;
            }
        }
        for i in 0..self.members.len() {
            if self.members[i].pending.is_some_and(|t| t <= now) {
                self.restart(ctx, i, taps)?;
            }
        }
        if let Some(f) = self.members.iter().find_map(|m| m.failure.clone()) {
            return Ok(Outcome::Failed(f));
        }
        // The logger runs until it is stopped, after everyone else.
        let done = self.retiring.is_empty()
            && self.members.iter_mut().all(|m| {
                m.role == Role::Logger
                    || (m.pending.is_none() && m.swap.is_none() && m.child.poll())
            });
        Ok(if done {
            Outcome::Finished
        } else {
            Outcome::Running
        })
    }

    /// Moves every hot swap one step on, without blocking (the launcher keeps
    /// draining its taps meanwhile, so no publisher waits on it).
    fn advance_swaps(
        &mut self,
        ctx: &mut Context,
        taps: &[Box<dyn Tap>],
        ready: &BTreeSet<(String, u32)>,
    ) -> anyhow::Result<()> {
        let now = Instant::now();
        for i in 0..self.members.len() {
            if let Some(variant) = self.members[i].swap_request.take() {
                self.restore_run_files();
                let m = &self.members[i];
                let snapshot = latest_snapshot(&self.run_dir, m, taps)?;
                let instance = m.instance + 1;
                let new = children::spawn(&Launch {
                    bin: &m.bin,
                    name: &m.name,
                    manifest: &self.manifest_file,
                    namespace: &self.namespace,
                    instance,
                    variant: Some(&variant),
                    standby: true,
                    args: &m.args,
                    warm: Some(children::Warm {
                        snapshot: snapshot.as_deref(),
                        resume_after_ns: None,
                    }),
                })?;
                tracing::info!(process = %m.name, %variant, instance, "swap: the new variant starts in standby");
                self.members[i].swap = Some(Swap::Starting {
                    new,
                    instance,
                    variant,
                    since: now,
                });
            }
            let Some(swap) = self.members[i].swap.take() else {
                continue;
            };
            let m = &mut self.members[i];
            let next = match swap {
                Swap::Starting {
                    mut new,
                    instance,
                    variant,
                    since,
                } => {
                    if new.poll() || now.duration_since(since) > SWAP_PHASE_TIMEOUT {
                        tracing::error!(process = %m.name, %variant, "swap abandoned: the new variant did not become ready");
                        new.kill();
                        self.retiring.push((new, now));
                        None
                    } else if ready.contains(&(m.name.clone(), instance)) {
                        let client = ControlClient::open(ctx, m.role, m.instance)?;
                        let pending = client.send(control(command::DEACTIVATE, 0))?;
                        Some(Swap::Deactivating {
                            new,
                            instance,
                            variant,
                            since: now,
                            _client: client,
                            pending,
                        })
                    } else {
                        Some(Swap::Starting {
                            new,
                            instance,
                            variant,
                            since,
                        })
                    }
                }
                Swap::Deactivating {
                    mut new,
                    instance,
                    variant,
                    since,
                    _client,
                    pending,
                } => match pending.poll()? {
                    Some(r) if r.status == 0 => {
                        let boundary = r.last_stamp_ns;
                        let client = ControlClient::open(ctx, m.role, instance)?;
                        let pending = client.send(control(command::ACTIVATE, boundary))?;
                        tracing::info!(process = %m.name, boundary, "swap: the old variant is deactivated");
                        Some(Swap::Activating {
                            new,
                            instance,
                            variant,
                            since: now,
                            _client: client,
                            pending,
                        })
                    }
                    answer => {
                        if answer.is_some() || now.duration_since(since) > SWAP_PHASE_TIMEOUT {
                            tracing::error!(process = %m.name, %variant, "swap abandoned: the old variant did not deactivate");
                            new.kill();
                            self.retiring.push((new, now));
                            None
                        } else {
                            Some(Swap::Deactivating {
                                new,
                                instance,
                                variant,
                                since,
                                _client,
                                pending,
                            })
                        }
                    }
                },
                Swap::Activating {
                    new,
                    instance,
                    variant,
                    since,
                    _client,
                    pending,
                } => {
                    let answer = pending.poll()?;
                    if answer.is_none() && now.duration_since(since) <= SWAP_PHASE_TIMEOUT {
                        Some(Swap::Activating {
                            new,
                            instance,
                            variant,
                            since,
                            _client,
                            pending,
                        })
                    } else {
                        if answer.is_none_or(|r| r.status != 0) {
                            tracing::error!(process = %m.name, "the new variant did not confirm its activation; it runs anyway");
                        }
                        let old = std::mem::replace(&mut m.child, new);
                        self.retiring.push((old, now));
                        m.instance = instance;
                        m.variant = Some(variant);
                        m.started = now;
                        m.swaps += 1;
                        publish(ctx, event_kind::SWAPPED, m, 0);
                        tracing::info!(process = %m.name, instance, "swap done");
                        None
                    }
                }
            };
            self.members[i].swap = next;
        }
        // Replaced instances exit by themselves once deactivated.
        self.retiring.retain_mut(|(child, since)| {
            if child.poll() {
                return false;
            }
            if now.duration_since(*since) > SWAP_PHASE_TIMEOUT {
                child.kill();
            }
            true
        });
        Ok(())
    }

    /// Ends swaps in progress and waits for replaced instances (shutdown).
    pub fn end_swaps(&mut self) {
        for m in self.members.iter_mut() {
            if let Some(
                Swap::Starting { new, .. }
                | Swap::Deactivating { new, .. }
                | Swap::Activating { new, .. },
            ) = m.swap.take()
            {
                new.terminate();
                self.retiring.push((new, Instant::now()));
            }
        }
        let t0 = Instant::now();
        while !self.retiring.is_empty() && t0.elapsed() < Duration::from_secs(5) {
            self.retiring.retain_mut(|(c, _)| !c.poll());
            std::thread::sleep(Duration::from_millis(5));
        }
        for (c, _) in self.retiring.iter_mut() {
            c.kill();
            let _ = c.child.wait();
        }
        self.retiring.clear();
    }

    fn restart(
        &mut self,
        ctx: &mut Context,
        i: usize,
        taps: &[Box<dyn Tap>],
    ) -> anyhow::Result<()> {
        self.restore_run_files();
        let m = &mut self.members[i];
        m.pending = None;
        let file = latest_snapshot(&self.run_dir, m, taps)?;
        let resume_after = taps
            .iter()
            .filter(|t| m.outputs.iter().any(|o| o == t.service()))
            .filter_map(|t| t.span().map(|(_, last)| last))
            .max();
        let instance = m.instance + 1;
        m.child = children::spawn(&Launch {
            bin: &m.bin,
            name: &m.name,
            manifest: &self.manifest_file,
            namespace: &self.namespace,
            instance,
            variant: m.variant.as_deref(),
            standby: false,
            args: &m.args,
            warm: Some(children::Warm {
                snapshot: file.as_deref(),
                resume_after_ns: resume_after,
            }),
        })?;
        m.instance = instance;
        m.started = Instant::now();
        m.restarts += 1;
        publish(ctx, event_kind::RESTARTED, m, 0);
        Ok(())
    }
}

impl Supervisor {
    /// The run directory and the effective manifest a new instance reads,
    /// recreated if something removed them (a temp cleaner): logged, and the
    /// run goes on.
    fn restore_run_files(&self) {
        if std::fs::symlink_metadata(&self.manifest_file).is_ok() {
            return;
        }
        let restored = nauta_runtime::run_files::runs_dir()
            .and_then(|_| nauta_runtime::run_files::private_dir(&self.run_dir))
            .and_then(|()| {
                nauta_runtime::run_files::create_file(&self.manifest_file, &self.manifest_text)
            });
        match restored {
            Ok(()) => {
                tracing::warn!(dir = %self.run_dir.display(), "the run directory was removed; recreated it")
            }
            Err(e) => {
                tracing::error!(error = %e, "the run directory was removed and cannot be recreated")
            }
        }
    }
}

/// Writes the role's latest snapshot (as the launcher's tap kept it) to a
/// file in the run directory for a new instance; None if there is none yet.
fn latest_snapshot(
    run_dir: &Path,
    m: &Member,
    taps: &[Box<dyn Tap>],
) -> anyhow::Result<Option<PathBuf>> {
    let service = snapshot_service(m.role.name());
    let Some((stamp, bytes)) = taps
        .iter()
        .find(|t| t.service() == service)
        .and_then(|t| t.latest())
    else {
        return Ok(None);
    };
    let path = run_dir.join(format!("snapshot-{}-{}.bin", m.name, m.instance + 1));
    // Exclusively created and renamed over (mode 0600): a file or symlink
    // already at the path is replaced, never followed.
    if let Err(e) = nauta_runtime::run_files::replace_file(&path, bytes) {
        // A temp cleaner may have removed the run directory: the run goes on,
        // the new instance starts cold.
        tracing::error!(process = %m.name, error = %e, "snapshot not written; the new instance starts without it");
        return Ok(None);
    }
    tracing::info!(process = %m.name, snapshot_stamp_ns = stamp, "warm start from the latest snapshot");
    Ok(Some(path))
}

/// Whether a source of the run has ended its stream (its end-of-stream
/// progress reached the launcher's tap).
fn inputs_ended(source_progress: &[String], obs: &Observer) -> bool {
    source_progress
        .iter()
        .any(|s| obs.end_of_stream.contains(s))
}

fn control(command: u32, boundary_stamp_ns: u64) -> ControlRequest {
    ControlRequest {
        header: Header::new(0, 0, Role::Launcher, 0),
        command,
        pad: 0,
        boundary_stamp_ns,
    }
}

impl Supervisor {
    /// Publishes a STARTED event for every process running now: a logger that
    /// joined after them records who runs (their own READY events went out
    /// before it listened).
    pub fn announce_running(&mut self, ctx: &mut Context) {
        for m in self.members.iter_mut() {
            if !m.child.poll() {
                publish(ctx, event_kind::STARTED, m, 0);
            }
        }
    }
}

fn publish(ctx: &mut Context, kind: u32, m: &Member, exit_code: i32) {
    ctx.publish_event(RunEvent {
        header: Header::new(0, 0, Role::Launcher, 0),
        kind,
        role: m.role as u32,
        instance: m.instance,
        pid: m.child.child.id(),
        exit_code,
        pad: 0,
        process: to_fixed_str(&m.name),
        variant: to_fixed_str(m.variant.as_deref().unwrap_or("")),
    });
}

// By hand: a member holds iceoryx2 ports and children, which print nothing useful.
impl std::fmt::Debug for Member {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Member")
            .field("name", &self.name)
            .field("role", &self.role)
            .finish_non_exhaustive()
    }
}

impl std::fmt::Debug for Supervisor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Supervisor")
            .field("members", &self.members)
            .finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backoff_doubles_up_to_the_longest() {
        let r = Restart {
            policy: RestartPolicy::OnFailure,
            max: 10,
            window: DEFAULT_WINDOW,
            backoff: (Duration::from_millis(20), Duration::from_millis(1000)),
        };
        let d: Vec<u128> = (1..=8).map(|n| r.delay(n).as_millis()).collect();
        assert_eq!(d, [20, 40, 80, 160, 320, 640, 1000, 1000]);
        assert_eq!(r.delay(1000), Duration::from_millis(1000));
    }
}
