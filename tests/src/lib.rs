//! Helpers of nauta's end-to-end tests: locating (and building once) the
//! workspace binaries, running `nauta launch --json`, reading its summary, a
//! watchdog that bounds every test, and the namespace's shared-memory files.
//!
//! The tests themselves are in `tests/e2e.rs`.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Condvar, Mutex, OnceLock};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use nauta_messages::{Role, RunEvent, event_kind, fixed_str};
use nauta_runtime::{Context, Manifest, Namespace, Subscriber, services};

mod kill;
mod kill_swap;
pub mod smoother_fixture;
mod summary;
pub use kill::kill_9_after_draining;
pub use kill_swap::{Follower, KillSwap, kill_9_then_swap, ready_pid};
pub use summary::Summary;

// ---------------------------------------------------------------------------
// Binaries and files of the workspace
// ---------------------------------------------------------------------------

/// The workspace root (parent of this crate).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from(".."))
}

/// `launch/survey.toml`.
pub fn survey_manifest() -> PathBuf {
    workspace_root().join("launch").join("survey.toml")
}

/// `alignment_samples` of the attitude process of `manifest` (its variant's
/// parameters over the common ones, as the process itself reads them).
pub fn alignment_samples(manifest: &Path) -> u64 {
    let m = Manifest::load(manifest)
        .unwrap_or_else(|e| panic!("cannot load {}: {e:#}", manifest.display()));
    let params: serde_json::Value = m
        .params("attitude", None)
        .unwrap_or_else(|e| panic!("{}: attitude parameters: {e:#}", manifest.display()));
    params
        .get("alignment_samples")
        .and_then(serde_json::Value::as_u64)
        .unwrap_or_else(|| {
            panic!(
                "{}: no integer alignment_samples in the attitude parameters: {params}",
                manifest.display()
            )
        })
}

/// The directory holding `nauta`, `nauta-sensor` and `nauta-attitude`, built
/// once per test process (`cargo test` only builds this package's targets).
pub fn bin_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let exe = std::env::current_exe().expect("current_exe");
        // target/<profile>/deps/<test binary>
        let dir = exe
            .parent()
            .and_then(Path::parent)
            .expect("test binary is not in target/<profile>/deps")
            .to_path_buf();
        let profile = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let mut cmd = Command::new(cargo);
        cmd.current_dir(workspace_root())
            .args(["build", "--workspace", "--bins"]);
        match profile.as_str() {
            "debug" => {}
            "release" => {
                cmd.arg("--release");
            }
            other => {
                cmd.args(["--profile", other]);
            }
        }
        let out = cmd
            .stdin(Stdio::null())
            .output()
            .expect("cannot run cargo build");
        assert!(
            out.status.success(),
            "cargo build --workspace --bins failed ({}):\n{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
        for b in ["nauta", "nauta-sensor", "nauta-attitude"] {
            assert!(
                dir.join(b).is_file(),
                "{} missing after the build",
                dir.join(b).display()
            );
        }
        dir
    })
}

/// Path of workspace binary `name`.
pub fn bin(name: &str) -> PathBuf {
    bin_dir().join(name)
}

// ---------------------------------------------------------------------------
// Watchdog
// ---------------------------------------------------------------------------

struct WatchdogShared {
    name: String,
    pids: Mutex<Vec<u32>>,
    fired: AtomicBool,
}

/// Bounds a test: after `bound` it kills the processes it watches (so a test
/// waiting on them wakes up and fails through [`Watchdog::check`]); if the test
/// is still running `GRACE` later (a hang inside the test process itself), it
/// aborts the test process. No test asserts on wall time otherwise.
pub struct Watchdog {
    shared: Arc<WatchdogShared>,
    done: Option<mpsc::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl std::fmt::Debug for Watchdog {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Watchdog")
            .field("name", &self.shared.name)
            .finish()
    }
}

const GRACE: Duration = Duration::from_secs(20);

impl Watchdog {
    /// Starts a watchdog for test `name`.
    pub fn new(name: &str, bound: Duration) -> Self {
        let shared = Arc::new(WatchdogShared {
            name: name.to_owned(),
            pids: Mutex::new(Vec::new()),
            fired: AtomicBool::new(false),
        });
        let (tx, rx) = mpsc::channel::<()>();
        let s = shared.clone();
        let thread = std::thread::spawn(move || {
            if rx.recv_timeout(bound) != Err(mpsc::RecvTimeoutError::Timeout) {
                return;
            }
            s.fired.store(true, Ordering::SeqCst);
            let pids = s.pids.lock().unwrap_or_else(|e| e.into_inner()).clone();
            eprintln!(
                "watchdog: test {} still running after {bound:?}; killing {pids:?}",
                s.name
            );
            for pid in pids {
                // SAFETY: kill(2) on a child this test started and has not reaped.
                unsafe {
                    libc::kill(pid as i32, libc::SIGKILL);
                }
            }
            if rx.recv_timeout(GRACE) == Err(mpsc::RecvTimeoutError::Timeout) {
                eprintln!(
                    "watchdog: test {} still hangs {GRACE:?} after its processes were killed; aborting",
                    s.name
                );
                std::process::abort();
            }
        });
        Watchdog {
            shared,
            done: Some(tx),
            thread: Some(thread),
        }
    }

    /// Kills `pid` if the watchdog fires.
    pub fn watch(&self, pid: u32) {
        self.shared
            .pids
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(pid);
    }

    /// Stops watching `pid` (call before reaping it, so no recycled pid is killed).
    pub fn unwatch(&self, pid: u32) {
        self.shared
            .pids
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .retain(|&p| p != pid);
    }

    /// True once the bound passed.
    pub fn fired(&self) -> bool {
        self.shared.fired.load(Ordering::SeqCst)
    }

    /// Panics if the bound passed.
    pub fn check(&self) {
        assert!(
            !self.fired(),
            "watchdog: test {} exceeded its bound",
            self.shared.name
        );
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        if let Some(tx) = self.done.take() {
            let _ = tx.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Polls `cond` every 20 ms until it holds (true) or `timeout` passes (false);
/// panics if the watchdog fires meanwhile.
pub fn wait_until(wd: &Watchdog, timeout: Duration, mut cond: impl FnMut() -> bool) -> bool {
    let t0 = Instant::now();
    loop {
        if cond() {
            return true;
        }
        wd.check();
        if t0.elapsed() >= timeout {
            return false;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

// ---------------------------------------------------------------------------
// Launch gate
// ---------------------------------------------------------------------------

/// Every `nauta launch` removes the stale resources of every dead node on the
/// machine when it starts. Tests that need a dead node's leftovers to stay until
/// they say so (kill -9 tests) close this gate: no launch of this test process
/// runs meanwhile. Launches share the gate (a count, so one test may hold it
/// several times); a closer waits until no launch runs.
#[derive(Debug, Default)]
pub struct Gate {
    state: Mutex<(usize, bool)>,
    cv: Condvar,
}

/// A launch's share of the [`Gate`].
#[derive(Debug)]
pub struct Shared(&'static Gate);

/// The [`Gate`] closed.
#[derive(Debug)]
pub struct Closed(&'static Gate);

impl Gate {
    fn get() -> &'static Gate {
        static GATE: OnceLock<Gate> = OnceLock::new();
        GATE.get_or_init(Gate::default)
    }

    /// Enters the gate to launch (waits while it is closed).
    pub fn share() -> Shared {
        let g = Self::get();
        let mut s = g.state.lock().unwrap_or_else(|e| e.into_inner());
        while s.1 {
            s = g.cv.wait(s).unwrap_or_else(|e| e.into_inner());
        }
        s.0 += 1;
        Shared(g)
    }

    /// Closes the gate once no launch runs.
    pub fn close() -> Closed {
        let g = Self::get();
        let mut s = g.state.lock().unwrap_or_else(|e| e.into_inner());
        while s.1 || s.0 > 0 {
            s = g.cv.wait(s).unwrap_or_else(|e| e.into_inner());
        }
        s.1 = true;
        Closed(g)
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        let mut s = self.0.state.lock().unwrap_or_else(|e| e.into_inner());
        s.0 -= 1;
        self.0.cv.notify_all();
    }
}

impl Drop for Closed {
    fn drop(&mut self) {
        let mut s = self.0.state.lock().unwrap_or_else(|e| e.into_inner());
        s.1 = false;
        self.0.cv.notify_all();
    }
}

// ---------------------------------------------------------------------------
// Child processes
// ---------------------------------------------------------------------------

/// What a finished process printed.
#[derive(Debug)]
pub struct Finished {
    /// The command line, for messages.
    pub command: String,
    /// Exit status.
    pub status: ExitStatus,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
}

impl Finished {
    /// A `key=value` field of the sensor's final log line (`sensor: done
    /// ...`) on stderr.
    pub fn sensor_done_field(&self, key: &str) -> Option<u64> {
        self.stderr
            .lines()
            .filter(|l| l.contains("sensor") && l.contains(" done "))
            .find_map(|l| {
                l.split_whitespace()
                    .find_map(|w| w.strip_prefix(key)?.strip_prefix('=')?.parse().ok())
            })
    }

    /// The sensor and its LBL interrogator stayed in lock step (`sim`
    /// clock): every interrogation registered at the instant it was
    /// stamped, and the sensor never gave up waiting for the interrogator.
    pub fn assert_lbl_lock_step(&self) {
        for key in ["late_interrogations", "interrogator_timeouts"] {
            assert_eq!(self.sensor_done_field(key), Some(0), "{key}\n{self}");
        }
    }

    /// Exit code (None when ended by a signal).
    pub fn code(&self) -> Option<i32> {
        self.status.code()
    }

    /// The run summary of `nauta launch --json` (every launch helper here
    /// passes `--json`).
    pub fn summary(&self) -> Summary {
        Summary::parse(&self.stdout).unwrap_or_else(|e| panic!("{e}\n{self}"))
    }
}

impl std::fmt::Display for Finished {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "command: {}", self.command)?;
        writeln!(f, "status: {}", self.status)?;
        writeln!(f, "--- stdout ---\n{}", self.stdout)?;
        write!(f, "--- stderr ---\n{}", self.stderr)
    }
}

/// A running child whose output is collected by threads (so it never blocks on
/// a full pipe); killed on drop unless it was waited for.
pub struct Running {
    /// The command line, for messages.
    pub command: String,
    child: Option<Child>,
    stdout: Option<JoinHandle<String>>,
    stderr: Option<JoinHandle<String>>,
    _gate: Option<Shared>,
}

impl std::fmt::Debug for Running {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Running")
            .field("command", &self.command)
            .field("pid", &self.child.as_ref().map(Child::id))
            .finish()
    }
}

fn collect(mut r: impl Read + Send + 'static) -> JoinHandle<String> {
    std::thread::spawn(move || {
        let mut buf = Vec::new();
        let _ = r.read_to_end(&mut buf);
        String::from_utf8_lossy(&buf).into_owned()
    })
}

impl Running {
    /// Starts `program args` with collected output, watched by `wd`.
    pub fn spawn<S: AsRef<std::ffi::OsStr>>(
        wd: &Watchdog,
        program: &Path,
        args: &[S],
        gate: Option<Shared>,
    ) -> Self {
        let command = std::iter::once(program.display().to_string())
            .chain(
                args.iter()
                    .map(|a| a.as_ref().to_string_lossy().into_owned()),
            )
            .collect::<Vec<_>>()
            .join(" ");
        let mut child = Command::new(program)
            .args(args)
            .current_dir(workspace_root())
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {command}: {e}"));
        wd.watch(child.id());
        let stdout = child.stdout.take().map(collect);
        let stderr = child.stderr.take().map(collect);
        Running {
            command,
            child: Some(child),
            stdout,
            stderr,
            _gate: gate,
        }
    }

    /// The child's pid.
    pub fn pid(&self) -> u32 {
        self.child.as_ref().map_or(0, Child::id)
    }

    /// True while the child has not exited (does not reap it).
    pub fn is_running(&mut self) -> bool {
        let pid = self.pid() as libc::pid_t;
        let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
        // SAFETY: waitid on our own unreaped child, WNOWAIT leaves it waitable.
        let r = unsafe {
            libc::waitid(
                libc::P_PID,
                pid as libc::id_t,
                &mut info,
                libc::WEXITED | libc::WNOHANG | libc::WNOWAIT,
            )
        };
        // SAFETY: si_pid is valid to read after waitid filled `info` (0 if none).
        r == 0 && unsafe { info.si_pid() } == 0
    }

    /// Sends `signal` to the child.
    pub fn signal(&self, signal: i32) {
        if let Some(c) = &self.child {
            // SAFETY: kill(2) on our own unreaped child.
            unsafe {
                libc::kill(c.id() as i32, signal);
            }
        }
    }

    /// Waits for the child to exit and collects its output.
    pub fn wait(mut self, wd: &Watchdog) -> Finished {
        let mut child = self.child.take().expect("child");
        let status = child.wait().expect("wait for child");
        wd.unwatch(child.id());
        let stdout = self
            .stdout
            .take()
            .and_then(|t| t.join().ok())
            .unwrap_or_default();
        let stderr = self
            .stderr
            .take()
            .and_then(|t| t.join().ok())
            .unwrap_or_default();
        let f = Finished {
            command: self.command.clone(),
            status,
            stdout,
            stderr,
        };
        assert!(!wd.fired(), "watchdog fired while waiting for\n{f}");
        f
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        if let Some(mut c) = self.child.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// `launch MANIFEST --json ARGS`: the arguments of every launch the tests run.
fn launch_args(manifest: &Path, args: &[&str]) -> Vec<String> {
    [
        "launch".to_owned(),
        manifest.display().to_string(),
        "--json".to_owned(),
    ]
    .into_iter()
    .chain(args.iter().map(|s| s.to_string()))
    .collect()
}

/// Starts `nauta launch <survey.toml> --json <args>`, sharing the launch gate.
pub fn start_launch(wd: &Watchdog, args: &[&str]) -> Running {
    start_launch_with(wd, args, Some(Gate::share()))
}

/// Starts `nauta launch <survey.toml> --json <args>` with an explicit gate
/// share (`None` for a test that holds the gate closed).
pub fn start_launch_with(wd: &Watchdog, args: &[&str], gate: Option<Shared>) -> Running {
    Running::spawn(
        wd,
        &bin("nauta"),
        &launch_args(&survey_manifest(), args),
        gate,
    )
}

/// Runs `nauta launch <survey.toml> --json <args>` to its end.
pub fn launch(wd: &Watchdog, args: &[&str]) -> Finished {
    start_launch(wd, args).wait(wd)
}

/// Starts `nauta launch <manifest> --json <args>`, sharing the launch gate.
pub fn start_launch_manifest(wd: &Watchdog, manifest: &Path, args: &[&str]) -> Running {
    start_launch_manifest_with(wd, manifest, args, Some(Gate::share()))
}

/// [`start_launch_manifest`] with an explicit gate share (`None` for a test
/// that holds the gate closed: a kill -9 test, whose killed publisher's
/// shared memory another launch starting meanwhile would reclaim before this
/// run's consumers have read it).
pub fn start_launch_manifest_with(
    wd: &Watchdog,
    manifest: &Path,
    args: &[&str],
    gate: Option<Shared>,
) -> Running {
    Running::spawn(wd, &bin("nauta"), &launch_args(manifest, args), gate)
}

/// Runs `nauta launch <manifest> --json <args>` to its end, sharing the launch gate.
pub fn launch_manifest(wd: &Watchdog, manifest: &Path, args: &[&str]) -> Finished {
    start_launch_manifest(wd, manifest, args).wait(wd)
}

// ---------------------------------------------------------------------------
// Joining a run
// ---------------------------------------------------------------------------

/// A test participant in namespace `ns` that watches `run/events`.
pub struct EventWatch {
    /// The test's context (its node is alive while this exists).
    pub ctx: Context,
    events: Subscriber<RunEvent>,
    ready: Vec<String>,
}

impl std::fmt::Debug for EventWatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EventWatch")
            .field("ctx", &self.ctx)
            .field("ready", &self.ready)
            .finish()
    }
}

impl EventWatch {
    /// Joins `ns` as a test process and subscribes to its run events (before
    /// starting the processes to watch: the service keeps only the last event).
    pub fn new(ns: &Namespace, deadline: Duration) -> Self {
        Self::with_clock(ns, deadline, nauta_runtime::ClockMode::Sim)
    }

    /// [`EventWatch::new`] for a run on `clock` (a service's overflow setting
    /// follows the clock, and every participant must agree on it).
    pub fn with_clock(ns: &Namespace, deadline: Duration, clock: nauta_runtime::ClockMode) -> Self {
        let mut s = Context::settings(Role::Test);
        s.deadline = deadline;
        s.clock = clock;
        let ctx = Context::new(ns, s).unwrap_or_else(|e| panic!("test context in {ns}: {e:#}"));
        let (events, _inbox) = ctx
            .subscriber(&services::run_events())
            .unwrap_or_else(|e| panic!("run/events in {ns}: {e:#}"));
        EventWatch {
            ctx,
            events,
            ready: Vec::new(),
        }
    }

    /// Leaves the run like a nauta process does ([`Context::finish`]): if this
    /// was the run's last node, nothing of the run is left behind.
    pub fn finish(self) {
        drop(self.events);
        self.ctx.finish();
    }

    /// Waits until process `name` announced READY; false if `child` exited first.
    pub fn wait_ready(&mut self, wd: &Watchdog, name: &str, child: &mut Running) -> bool {
        loop {
            let ready = &mut self.ready;
            self.events
                .drain(|e| {
                    if e.kind == event_kind::READY {
                        ready.push(fixed_str(&e.process));
                    }
                })
                .unwrap_or_else(|e| panic!("run/events: {e:#}"));
            if self.ready.iter().any(|r| r == name) {
                return true;
            }
            if !child.is_running() {
                return false;
            }
            wd.check();
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}

// ---------------------------------------------------------------------------
// Python: independent readers of nauta's files
// ---------------------------------------------------------------------------

/// The Python interpreter of a virtual environment holding
/// `tests/py/requirements.txt` (the PyPI `mcap` reader, `geojson`,
/// `jsonschema`), created once under the target directory; concurrent tests
/// wait for the one that creates it (an exclusive `flock`).
pub fn python() -> PathBuf {
    static PY: OnceLock<PathBuf> = OnceLock::new();
    PY.get_or_init(|| {
        let target = bin_dir()
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| workspace_root().join("target"));
        let venv = target.join("nauta-pyvenv");
        let requirements = workspace_root().join("tests/py/requirements.txt");
        let lock_path = target.join("nauta-pyvenv.lock");
        let lock = std::fs::File::create(&lock_path)
            .unwrap_or_else(|e| panic!("cannot create {}: {e}", lock_path.display()));
        // SAFETY: flock on a file descriptor we own; released when `lock` drops.
        let rc = unsafe { libc::flock(std::os::fd::AsRawFd::as_raw_fd(&lock), libc::LOCK_EX) };
        assert_eq!(rc, 0, "cannot lock {}", lock_path.display());
        let py = venv.join("bin").join("python");
        let stamp = venv.join("requirements.installed");
        let wanted = std::fs::read_to_string(&requirements)
            .unwrap_or_else(|e| panic!("cannot read {}: {e}", requirements.display()));
        if std::fs::read_to_string(&stamp).ok().as_deref() != Some(wanted.as_str()) {
            let run = |cmd: &mut Command| {
                let out = cmd
                    .stdin(Stdio::null())
                    .output()
                    .unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
                assert!(
                    out.status.success(),
                    "{cmd:?} failed ({}):\n{}{}",
                    out.status,
                    String::from_utf8_lossy(&out.stdout),
                    String::from_utf8_lossy(&out.stderr)
                );
            };
            run(Command::new("python3").arg("-m").arg("venv").arg(&venv));
            run(Command::new(&py)
                .args([
                    "-m",
                    "pip",
                    "install",
                    "-q",
                    "--disable-pip-version-check",
                    "-r",
                ])
                .arg(&requirements));
            std::fs::write(&stamp, &wanted)
                .unwrap_or_else(|e| panic!("cannot write {}: {e}", stamp.display()));
        }
        drop(lock);
        py
    })
    .clone()
}

/// Runs `tests/py/<script>` with [`python`] and `args`; returns its stdout,
/// panicking with its output when it fails.
pub fn run_python(script: &str, args: &[&std::ffi::OsStr]) -> String {
    let path = workspace_root().join("tests/py").join(script);
    let out = Command::new(python())
        .arg(&path)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap_or_else(|e| panic!("cannot run {}: {e}", path.display()));
    assert!(
        out.status.success(),
        "{} failed ({}):\n{}{}",
        path.display(),
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Runs `nauta ARGS` from the workspace root to its end: (exit code, stdout,
/// stderr).
pub fn nauta_cli<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> (Option<i32>, String, String) {
    let out = Command::new(bin("nauta"))
        .args(args.iter().map(AsRef::as_ref))
        .current_dir(workspace_root())
        .stdin(Stdio::null())
        .output()
        .expect("run nauta");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

// ---------------------------------------------------------------------------
// A running pipeline, through the command line
// ---------------------------------------------------------------------------

/// `nauta status --json --namespace NS`, once the run answers.
pub fn status_json(ns: &str) -> Option<serde_json::Value> {
    let (code, out, _) = nauta_cli(&["status", "--json", "--namespace", ns]);
    (code == Some(0)).then(|| serde_json::from_str(&out).ok())?
}

/// Pid of process `name` of the run in `ns` while `nauta status` shows it
/// running.
pub fn running_pid(ns: &str, name: &str) -> Option<u32> {
    status_json(ns)?["processes"]
        .as_array()?
        .iter()
        .find(|p| p["name"] == name && p["state"] == "running")?["pid"]
        .as_u64()
        .map(|p| p as u32)
        .filter(|p| *p > 0)
}

/// A small valid manifest: 5 s of the survey in `sim` clock, the sensor
/// and the attitude process (`gyro`).
pub const SMALL_MANIFEST: &str = r#"[run]
clock = "sim"
duration_s = 5
seed = 3

[site]
latitude_deg = 38.6
longitude_deg = -9.3
magnetic_declination_deg = -0.98

[process.sensor]
bin = "nauta-sensor"
params = { scenario = "survey" }

[process.attitude]
bin = "nauta-attitude"
variant = "gyro"
"#;

/// Waits (up to a minute) until `nauta status` shows process `name` of the
/// run in `ns` running; its pid. Panics if it never does.
pub fn wait_running_pid(wd: &Watchdog, ns: &str, name: &str) -> u32 {
    let mut pid = None;
    assert!(
        wait_until(wd, Duration::from_secs(60), || {
            pid = running_pid(ns, name);
            pid.is_some()
        }),
        "process {name} of run {ns} never ran"
    );
    pid.unwrap_or_else(|| panic!("process {name} of run {ns}: no pid"))
}

/// True when process `pid` has exited: no `/proc` entry, or a zombie
/// waiting for its parent to reap it (it runs nothing).
pub fn process_gone(pid: u32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Err(_) => true,
        // A zombie waiting for its new parent to reap it runs nothing.
        Ok(stat) => stat
            .rsplit_once(") ")
            .is_some_and(|(_, rest)| rest.starts_with('Z')),
    }
}

/// `nauta swap PROCESS VARIANT`, asked again while it is refused (a
/// previous swap or a restart still starting, no snapshot yet).
pub fn swap_when_accepted(wd: &Watchdog, ns: &Namespace, process: &str, variant: &str) {
    let mut tries = 0;
    loop {
        let (code, _, err) = nauta_cli(&["swap", process, variant, "--namespace", ns.as_str()]);
        if code == Some(0) {
            return;
        }
        tries += 1;
        assert!(tries < 200, "swap to {variant} refused: {err}");
        wd.check();
        std::thread::sleep(Duration::from_millis(50));
    }
}
