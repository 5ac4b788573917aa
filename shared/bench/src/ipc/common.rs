//! Plumbing of `nauta bench ipc`: the shared clock, statistics, iceoryx2
//! namespaces, the peer process and its control channel, watchdogs.

use std::collections::HashMap;
use std::io::{ErrorKind, Read, Write};
use std::os::fd::{AsFd, AsRawFd, FromRawFd, OwnedFd, RawFd};
use std::os::unix::net::UnixStream;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use anyhow::{Context, anyhow, bail, ensure};
use iceoryx2::config::Config;
use iceoryx2::node::{Node, NodeBuilder};
use iceoryx2::prelude::{FileName, SemanticString, SignalHandlingMode, ipc};

/// How long a peer may take to start and report ready.
pub const STARTUP_TIMEOUT: Duration = Duration::from_secs(20);
/// How long one case (one peer process) may run before it is killed.
pub const CASE_TIMEOUT: Duration = Duration::from_secs(180);
/// How long a peer may take to exit once it has finished.
const EXIT_TIMEOUT: Duration = Duration::from_secs(10);
/// Blocking iceoryx2 waits wake up at least this often to check the watchdog.
pub const WAIT_SLICE: Duration = Duration::from_secs(1);
/// Busy loops check the watchdog every this many empty polls.
pub const SPIN_CHECK: u32 = 1 << 16;

/// CLOCK_MONOTONIC in ns. It is system-wide, so stamps taken in one process can be
/// subtracted from readings in another (vDSO, no system call with the TSC clock
/// source).
#[inline]
pub fn now_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec and CLOCK_MONOTONIC always exists.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

/// One-way latency from a stamp taken in the other process, in ns.
#[inline]
pub fn since(stamp_ns: u64, now: u64) -> anyhow::Result<u64> {
    now.checked_sub(stamp_ns)
        .ok_or_else(|| anyhow!("stamp {stamp_ns} is in the future (now {now}): clocks differ"))
}

/// Percentiles of a set of latencies.
#[derive(Debug, Clone, Copy, Default)]
pub struct Summary {
    /// Number of samples.
    pub n: usize,
    /// Median, ns.
    pub p50: u64,
    /// 99th percentile, ns.
    pub p99: u64,
}

impl Summary {
    /// Nearest-rank percentiles (sorts `v`).
    pub fn of(v: &mut [u64]) -> Summary {
        if v.is_empty() {
            return Summary::default();
        }
        v.sort_unstable();
        let rank = |p: f64| {
            let r = (p / 100.0 * v.len() as f64).ceil() as usize;
            v[r.clamp(1, v.len()) - 1]
        };
        Summary {
            n: v.len(),
            p50: rank(50.0),
            p99: rank(99.0),
        }
    }
}

/// The median of a few numbers (the upper one for an even count).
pub fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// An iceoryx2 node in its own namespace: a copy of the global config with
/// `global.prefix` set, so this case sees no other run's services and vice versa.
fn create_node(prefix: &str, signals: SignalHandlingMode) -> anyhow::Result<Node<ipc::Service>> {
    let mut config = Config::global_config().clone();
    config.global.prefix = FileName::new(prefix.as_bytes())
        .map_err(|e| anyhow!("invalid iceoryx2 prefix {prefix:?}: {e:?}"))?;
    NodeBuilder::new()
        .config(&config)
        .signal_handling_mode(signals)
        .create::<ipc::Service>()
        .context("create iceoryx2 node")
}

/// Runs one case in the driver on a node in namespace `prefix`, with its peer
/// already started: the driver never holds a node without a live peer, which cleans
/// up after the driver if the driver dies (SIGTERM by `PR_SET_PDEATHSIG`). The peer
/// is reaped after the driver's node is gone. If the case fails, the peer is killed
/// and reaped, then iceoryx2's own cleanup removes what it left in the namespace.
/// Nothing is removed by hand.
///
/// The driver does not take over SIGINT/SIGTERM: stopped, it dies at once, and its
/// peer cleans up after it.
pub fn driver_node<T>(
    prefix: &str,
    mut peer: Peer,
    body: impl FnOnce(&Node<ipc::Service>, &mut Peer) -> anyhow::Result<T>,
) -> anyhow::Result<T> {
    let node = create_node(prefix, SignalHandlingMode::Disabled)?;
    match body(&node, &mut peer) {
        Ok(value) => {
            drop(node);
            peer.finish()?;
            Ok(value)
        }
        Err(e) => {
            drop(peer);
            let _ = node.try_cleanup_dead_nodes();
            Err(e)
        }
    }
}

/// Runs the peer's side of a case on a node in namespace `prefix`. iceoryx2's
/// SIGINT/SIGTERM handling is installed before anything else, the watchdog turns a
/// signal into an error, and on any error iceoryx2's cleanup removes what a dead
/// driver left in the namespace.
pub fn peer_node<T>(
    prefix: &str,
    body: impl FnOnce(&Node<ipc::Service>) -> anyhow::Result<T>,
) -> anyhow::Result<T> {
    let node = create_node(prefix, SignalHandlingMode::HandleTerminationRequests)?;
    // iceoryx2 installs its signal handlers on the first check for a termination
    // request; do it now rather than on the first slow path.
    let result = node
        .wait(Duration::ZERO)
        .map_err(|e| anyhow!("stopped by a signal ({e:?})"))
        .and_then(|()| body(&node));
    if result.is_err() {
        let _ = node.try_cleanup_dead_nodes();
    }
    result
}

/// Polls `cond` (1 ms apart) until it holds or `timeout` passes.
pub fn wait_until(
    what: &str,
    timeout: Duration,
    mut cond: impl FnMut() -> bool,
) -> anyhow::Result<()> {
    let end = Instant::now() + timeout;
    while !cond() {
        if Instant::now() > end {
            bail!("timed out waiting for {what}");
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    Ok(())
}

/// Sets or clears FD_CLOEXEC.
fn set_cloexec(fd: RawFd, on: bool) -> anyhow::Result<()> {
    // SAFETY: fcntl on a descriptor we own; bad descriptors only return an error.
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFD) };
    ensure!(
        flags >= 0,
        "fcntl(F_GETFD): {}",
        std::io::Error::last_os_error()
    );
    let flags = if on {
        flags | libc::FD_CLOEXEC
    } else {
        flags & !libc::FD_CLOEXEC
    };
    // SAFETY: as above.
    let rc = unsafe { libc::fcntl(fd, libc::F_SETFD, flags) };
    ensure!(
        rc == 0,
        "fcntl(F_SETFD): {}",
        std::io::Error::last_os_error()
    );
    Ok(())
}

/// A pipe (read end, write end), both close-on-exec.
pub fn pipe() -> anyhow::Result<(OwnedFd, OwnedFd)> {
    let mut fds = [0 as RawFd; 2];
    // SAFETY: `fds` has room for the two descriptors pipe2 writes.
    let rc = unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) };
    ensure!(rc == 0, "pipe2: {}", std::io::Error::last_os_error());
    // SAFETY: pipe2 succeeded, so both descriptors are open and owned by nobody else.
    Ok(unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) })
}

/// A line-based control channel between the driver and the peer (a Unix socket
/// pair; not part of any measurement).
#[derive(Debug)]
pub struct Ctl(UnixStream);

impl Ctl {
    /// Sends one word.
    pub fn send(&mut self, word: &str) -> anyhow::Result<()> {
        self.0
            .write_all(format!("{word}\n").as_bytes())
            .context("control channel: send")
    }

    /// Receives one word, waiting at most `timeout`.
    pub fn recv(&mut self, timeout: Duration) -> anyhow::Result<String> {
        self.0.set_read_timeout(Some(timeout))?;
        let mut line = Vec::new();
        let mut byte = [0u8; 1];
        loop {
            match self.0.read(&mut byte) {
                Ok(0) => bail!("control channel closed"),
                Ok(_) if byte[0] == b'\n' => break,
                Ok(_) => line.push(byte[0]),
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                    bail!("control channel: nothing received within {timeout:?}")
                }
                Err(e) => return Err(e).context("control channel: receive"),
            }
        }
        Ok(String::from_utf8_lossy(&line).into_owned())
    }

    /// Receives `word` or fails.
    pub fn expect(&mut self, word: &str, timeout: Duration) -> anyhow::Result<()> {
        let got = self.recv(timeout)?;
        ensure!(
            got == word,
            "control channel: expected {word:?}, got {got:?}"
        );
        Ok(())
    }
}

/// The peer process of one case, seen from the driver. It is killed if the case
/// fails or outlives [`CASE_TIMEOUT`] and it is always reaped: no orphans.
#[derive(Debug)]
pub struct Peer {
    child: Option<Child>,
    ctl: Ctl,
    deadman: Option<(mpsc::Sender<()>, JoinHandle<()>)>,
    label: String,
}

impl Peer {
    /// Re-executes this binary as `nauta __ipc-peer <case> key=value...` and hands it
    /// `fds` (their numbers go on its command line as `key=<fd>`).
    pub fn spawn(
        case: &str,
        args: &[(&str, String)],
        fds: Vec<(&str, OwnedFd)>,
    ) -> anyhow::Result<Peer> {
        let exe = std::env::current_exe().context("find own executable")?;
        let (ctl_here, ctl_there) = UnixStream::pair().context("control socket pair")?;
        let mut cmd = Command::new(exe);
        cmd.arg("__ipc-peer")
            .arg(case)
            .arg(format!("parent={}", std::process::id()));
        for (k, v) in args {
            cmd.arg(format!("{k}={v}"));
        }
        // The peer inherits exactly these descriptors (everything else the driver
        // has is close-on-exec); the driver closes its copies right after the spawn
        // so that end-of-file works when either side dies.
        set_cloexec(ctl_there.as_raw_fd(), false)?;
        cmd.arg(format!("ctl={}", ctl_there.as_raw_fd()));
        for (k, fd) in &fds {
            set_cloexec(fd.as_raw_fd(), false)?;
            cmd.arg(format!("{k}={}", fd.as_raw_fd()));
        }
        // stdout is reserved for the driver's report: the peer's goes to stderr.
        let stderr_copy = std::io::stderr().as_fd().try_clone_to_owned()?;
        cmd.stdin(Stdio::null())
            .stdout(Stdio::from(stderr_copy))
            .stderr(Stdio::inherit());
        let child = cmd.spawn().context("start peer process")?;
        drop(ctl_there);
        drop(fds);

        let pid = child.id() as libc::pid_t;
        let (tx, rx) = mpsc::channel::<()>();
        let deadman = std::thread::spawn(move || {
            if let Err(mpsc::RecvTimeoutError::Timeout) = rx.recv_timeout(CASE_TIMEOUT) {
                // SAFETY: the child is not reaped before this thread is joined, so
                // `pid` still names it.
                unsafe { libc::kill(pid, libc::SIGKILL) };
            }
        });
        Ok(Peer {
            child: Some(child),
            ctl: Ctl(ctl_here),
            deadman: Some((tx, deadman)),
            label: case.to_string(),
        })
    }

    /// Waits until the peer reports that its ports exist.
    pub fn wait_ready(&mut self) -> anyhow::Result<()> {
        let label = self.label.clone();
        self.ctl
            .expect("ready", STARTUP_TIMEOUT)
            .with_context(|| format!("peer {label} did not start"))
    }

    /// Tells the peer to start.
    pub fn go(&mut self) -> anyhow::Result<()> {
        self.ctl.send("go")
    }

    /// Fails if the peer has exited (without reaping it).
    pub fn check_running(&self) -> anyhow::Result<()> {
        let Some(child) = &self.child else {
            bail!("peer {} is gone", self.label)
        };
        // SAFETY: zeroed siginfo_t is a valid out-parameter for waitid.
        let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
        // SAFETY: WNOWAIT leaves the child waitable; `info` is writable.
        let rc = unsafe {
            libc::waitid(
                libc::P_PID,
                child.id() as libc::id_t,
                &mut info,
                libc::WEXITED | libc::WNOHANG | libc::WNOWAIT,
            )
        };
        // SAFETY: waitid filled `info` (or left it zeroed, pid 0 = still running).
        if rc == 0 && unsafe { info.si_pid() } != 0 {
            bail!("peer {} exited early", self.label);
        }
        Ok(())
    }

    /// Waits for the peer's "done" and its successful exit.
    pub fn finish(mut self) -> anyhow::Result<()> {
        self.ctl
            .expect("done", CASE_TIMEOUT)
            .with_context(|| format!("peer {} did not finish", self.label))?;
        let status = self.reap(EXIT_TIMEOUT)?;
        ensure!(status.success(), "peer {} exited with {status}", self.label);
        Ok(())
    }

    /// Stops the dead-man timer, then waits for the child (killing it after
    /// `timeout`).
    fn reap(&mut self, timeout: Duration) -> anyhow::Result<std::process::ExitStatus> {
        if let Some((tx, handle)) = self.deadman.take() {
            drop(tx);
            let _ = handle.join();
        }
        let Some(mut child) = self.child.take() else {
            bail!("peer {} already reaped", self.label)
        };
        let end = Instant::now() + timeout;
        loop {
            if let Some(status) = child.try_wait()? {
                return Ok(status);
            }
            if Instant::now() > end {
                let _ = child.kill();
                let status = child.wait()?;
                bail!("peer {} did not exit; killed ({status})", self.label);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

impl Drop for Peer {
    /// Only reached with the child unreaped when the case failed: kill and reap it.
    fn drop(&mut self) {
        if self.child.is_some() {
            if self.check_running().is_err() {
                eprintln!("[bench ipc] the peer of case {} had exited", self.label);
            }
            if let Some(child) = &mut self.child {
                let _ = child.kill();
            }
            let _ = self.reap(EXIT_TIMEOUT);
        }
    }
}

/// Catches a stuck case: a deadline, the peer's (or, in the peer, the driver's)
/// liveness and iceoryx2's SIGINT/SIGTERM flag. Only called on slow paths (after a
/// blocking wait slice or every [`SPIN_CHECK`] empty polls).
#[derive(Debug)]
pub struct Watchdog<'a> {
    deadline: Instant,
    node: Option<&'a Node<ipc::Service>>,
    peer: Option<&'a Peer>,
    parent: Option<u32>,
}

impl<'a> Watchdog<'a> {
    /// The driver's watchdog for one case.
    pub fn driver(peer: &'a Peer) -> Self {
        Watchdog {
            deadline: Instant::now() + CASE_TIMEOUT,
            node: None,
            peer: Some(peer),
            parent: None,
        }
    }

    /// The peer's watchdog.
    pub fn peer(node: Option<&'a Node<ipc::Service>>, parent: u32) -> Self {
        Watchdog {
            deadline: Instant::now() + CASE_TIMEOUT,
            node,
            peer: None,
            parent: Some(parent),
        }
    }

    /// Fails when the case must stop.
    pub fn check(&self) -> anyhow::Result<()> {
        if Instant::now() > self.deadline {
            bail!("timed out after {CASE_TIMEOUT:?}");
        }
        if let Some(node) = self.node {
            node.wait(Duration::ZERO)
                .map_err(|e| anyhow!("stopped by a signal ({e:?})"))?;
        }
        if let Some(peer) = self.peer {
            peer.check_running()?;
        }
        if let Some(parent) = self.parent {
            // SAFETY: getppid has no preconditions.
            let ppid = unsafe { libc::getppid() } as u32;
            ensure!(ppid == parent, "the benchmark driver is gone");
        }
        Ok(())
    }
}

/// What the peer learns from its command line and its side of the control channel.
#[derive(Debug)]
pub struct PeerCtx {
    /// The case to run.
    pub case: String,
    /// The driver's process id.
    pub parent: u32,
    args: HashMap<String, String>,
    ctl: Ctl,
}

impl PeerCtx {
    /// Parses `<case> key=value...`, arranges to die with the driver and takes the
    /// control channel.
    pub fn from_args(args: &[String]) -> anyhow::Result<PeerCtx> {
        let (case, rest) = args
            .split_first()
            .ok_or_else(|| anyhow!("__ipc-peer: missing case"))?;
        let mut map = HashMap::new();
        for a in rest {
            let (k, v) = a
                .split_once('=')
                .ok_or_else(|| anyhow!("__ipc-peer: bad argument {a:?}"))?;
            map.insert(k.to_string(), v.to_string());
        }
        let parent: u32 = map
            .get("parent")
            .ok_or_else(|| anyhow!("__ipc-peer: missing parent"))?
            .parse()?;
        // Stop when the driver dies, even by SIGKILL: SIGTERM, which iceoryx2 turns into
        // a termination request, so the peer leaves through its error path, drops its
        // node and cleans up after the dead driver (peers without a node just die).
        // Then check the driver did not die before this took effect.
        // SAFETY: prctl(PR_SET_PDEATHSIG) only changes this process's own attribute.
        unsafe { libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM as libc::c_ulong) };
        // SAFETY: getppid has no preconditions.
        if unsafe { libc::getppid() } as u32 != parent {
            // Leave the namespace clean: the driver may have created services.
            if let Some(prefix) = map.get("prefix") {
                let _ = create_node(prefix, SignalHandlingMode::Disabled)
                    .map(|node| node.try_cleanup_dead_nodes());
            }
            bail!("the benchmark driver is gone");
        }
        let ctl = Ctl(UnixStream::from(take_fd(&mut map, "ctl")?));
        Ok(PeerCtx {
            case: case.clone(),
            parent,
            args: map,
            ctl,
        })
    }

    /// A string argument.
    pub fn str(&self, key: &str) -> anyhow::Result<&str> {
        self.args
            .get(key)
            .map(String::as_str)
            .ok_or_else(|| anyhow!("__ipc-peer: missing {key}"))
    }

    /// A numeric argument.
    pub fn num(&self, key: &str) -> anyhow::Result<u64> {
        self.str(key)?
            .parse()
            .with_context(|| format!("__ipc-peer: bad {key}"))
    }

    /// Takes ownership of an inherited descriptor named on the command line.
    pub fn fd(&mut self, key: &str) -> anyhow::Result<OwnedFd> {
        take_fd(&mut self.args, key)
    }

    /// Reports ready, then waits for the driver's go.
    pub fn ready_then_wait_go(&mut self) -> anyhow::Result<()> {
        self.ctl.send("ready")?;
        self.ctl.expect("go", STARTUP_TIMEOUT)
    }

    /// Reports that the peer is done.
    pub fn done(&mut self) -> anyhow::Result<()> {
        self.ctl.send("done")
    }
}

/// Takes ownership of the inherited descriptor whose number is `args[key]`.
fn take_fd(args: &mut HashMap<String, String>, key: &str) -> anyhow::Result<OwnedFd> {
    let raw: RawFd = args
        .remove(key)
        .ok_or_else(|| anyhow!("__ipc-peer: missing {key}"))?
        .parse()?;
    // Make sure it is open before taking ownership.
    // SAFETY: F_GETFD only inspects the descriptor table.
    ensure!(
        unsafe { libc::fcntl(raw, libc::F_GETFD) } >= 0,
        "__ipc-peer: descriptor {key}={raw} is not open"
    );
    // SAFETY: the driver opened this descriptor for this process and left it open
    // across exec; it is taken once (removed from the map), so nothing else owns it.
    let fd = unsafe { OwnedFd::from_raw_fd(raw) };
    set_cloexec(fd.as_raw_fd(), true)?;
    Ok(fd)
}

/// CPU time the rest of the machine used while a part of the benchmark ran: the
/// time the CPUs were not idle (from the idle time in `/proc/stat`) minus this
/// process's and its reaped peers' CPU time. On a 2-core machine anything else
/// running (a build, tests) distorts the figures, so rounds that saw other work are
/// repeated and the report says how much there was.
#[derive(Debug, Clone, Copy)]
pub struct LoadProbe {
    wall: Instant,
    idle_s: f64,
    own_s: f64,
}

/// What a [`LoadProbe`] saw.
#[derive(Debug, Clone, Copy, Default)]
pub struct Load {
    /// Average number of CPUs busy with other work (including time the hypervisor
    /// took away).
    pub other_cpus: f64,
    /// How far off `other_cpus` can be: `/proc/stat` counts in 10 ms steps.
    pub uncertainty_cpus: f64,
}

impl LoadProbe {
    /// Starts measuring.
    pub fn start() -> LoadProbe {
        LoadProbe {
            wall: Instant::now(),
            idle_s: machine_idle_s().0,
            own_s: own_cpu_s(),
        }
    }

    /// The load since `start`.
    pub fn finish(&self) -> Load {
        let wall = self.wall.elapsed().as_secs_f64().max(1e-3);
        let (idle_s, tick_s) = machine_idle_s();
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
        let own = own_cpu_s() - self.own_s;
        let busy = cpus * wall - (idle_s - self.idle_s);
        Load {
            other_cpus: ((busy - own) / wall).max(0.0),
            uncertainty_cpus: 2.0 * cpus * tick_s / wall,
        }
    }
}

/// (idle + iowait CPU-seconds of the whole machine since boot, length of one
/// `/proc/stat` unit in seconds).
fn machine_idle_s() -> (f64, f64) {
    // SAFETY: sysconf has no preconditions.
    let tick = 1.0 / unsafe { libc::sysconf(libc::_SC_CLK_TCK) }.max(1) as f64;
    let Ok(stat) = std::fs::read_to_string("/proc/stat") else {
        return (0.0, tick);
    };
    let Some(line) = stat.lines().find(|l| l.starts_with("cpu ")) else {
        return (0.0, tick);
    };
    let v: Vec<f64> = line
        .split_whitespace()
        .skip(1)
        .filter_map(|x| x.parse().ok())
        .collect();
    // user nice system idle iowait ...
    let idle = v.get(3).copied().unwrap_or(0.0) + v.get(4).copied().unwrap_or(0.0);
    (idle * tick, tick)
}

/// CPU-seconds used by this process and its reaped children.
fn own_cpu_s() -> f64 {
    let usage = |who: libc::c_int| {
        // SAFETY: zeroed rusage is a valid out-parameter.
        let mut r: libc::rusage = unsafe { std::mem::zeroed() };
        // SAFETY: `r` is writable; RUSAGE_SELF/CHILDREN are valid selectors.
        unsafe { libc::getrusage(who, &mut r) };
        let tv = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
        tv(r.ru_utime) + tv(r.ru_stime)
    };
    usage(libc::RUSAGE_SELF) + usage(libc::RUSAGE_CHILDREN)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_percentiles() {
        let mut v: Vec<u64> = (1..=100).rev().collect();
        let s = Summary::of(&mut v);
        assert_eq!((s.n, s.p50, s.p99), (100, 50, 99));
        let mut one = vec![7];
        let s = Summary::of(&mut one);
        assert_eq!((s.p50, s.p99), (7, 7));
        assert_eq!(Summary::of(&mut []).n, 0);
    }

    #[test]
    fn median_of_rates() {
        assert!((median(vec![3.0, 1.0, 2.0]) - 2.0).abs() < 1e-12);
        assert!((median(vec![4.0, 1.0]) - 4.0).abs() < 1e-12);
    }

    #[test]
    fn clock_is_monotonic() {
        let a = now_ns();
        let b = now_ns();
        assert!(b >= a);
        assert!(since(b + 1, b).is_err());
    }
}
