//! What a test of the shell runs: a source, role threads, a collector,
//! the launcher's handover, and the in-process references.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};

use nauta_estimation::Estimator;
use nauta_estimation::readings::{Depth, Imu, LblNav, Nav};
use nauta_messages::*;
use nauta_runtime::context::ContextSettings;
use nauta_runtime::{Connect, Context, ControlClient, Namespace, Shell, services};

use super::roles::*;

// ---- the pieces of a run -----------------------------------------------------

/// One source message, in publication order.
#[derive(Debug, Clone, Copy)]
pub enum Out {
    Imu(ImuSample),
    Depth(DepthSample),
}

/// The source's samples: 100 Hz velocity, 5 Hz position, seeded noise.
pub fn samples(seconds: u64, seed: u64) -> Vec<Out> {
    let mut noise = Noise(seed);
    let mut v = Vec::new();
    for k in 1..=seconds * 100 {
        let stamp = k * IMU_DT_NS;
        let t = stamp as f64 * 1e-9;
        // The average velocity over the interval (what an integrating sensor gives).
        let dt = IMU_DT_NS as f64 * 1e-9;
        let mean_v = (truth_x(t) - truth_x(t - dt)) / dt;
        v.push(Out::Imu(ImuSample {
            header: Header::new(stamp, 0, Role::Sensor, 0),
            accel_m_s2: [mean_v + SIGMA_V * noise.gauss(), 0.0, 0.0],
            interval_s: dt,
            ..Default::default()
        }));
        if k % DEPTH_EVERY == 0 {
            v.push(Out::Depth(DepthSample {
                header: Header::new(stamp, 0, Role::Sensor, 0),
                depth_m: truth_x(t) + SIGMA_X * noise.gauss(),
            }));
        }
    }
    v
}

pub fn stamp_of(o: &Out) -> u64 {
    match o {
        Out::Imu(m) => m.header.stamp_ns,
        Out::Depth(m) => m.header.stamp_ns,
    }
}

/// A thread that panics the test process if the test outlives `bound`.
pub struct Watchdog(Arc<AtomicBool>);
impl Watchdog {
    pub fn new(name: &'static str, bound: Duration) -> Self {
        let done = Arc::new(AtomicBool::new(false));
        let d = done.clone();
        std::thread::spawn(move || {
            let t0 = Instant::now();
            while !d.load(Ordering::Relaxed) {
                if t0.elapsed() > bound {
                    eprintln!("watchdog: {name} still running after {bound:?}");
                    std::process::exit(101);
                }
                std::thread::sleep(Duration::from_millis(50));
            }
        });
        Watchdog(done)
    }
}
impl Drop for Watchdog {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
    }
}

pub fn settings(role: Role, process: &str, instance: u32) -> ContextSettings {
    ContextSettings {
        process: process.into(),
        instance,
        variant: "kf".into(),
        ..Context::settings(role)
    }
}

/// How the source interleaves its two channels.
#[derive(Debug, Clone, Copy)]
pub enum Arrival {
    /// In stamp order, a watermark and a flush every 32 messages.
    InOrder,
    /// Each batch publishes every position sample before the velocity
    /// samples (and flushes in between), seeded batch lengths.
    SlowFirst(u64),
}

/// Where the source stops until it is told to go on: before each stamp of
/// `at`, in turn, it says `paused` and waits for `go`.
pub struct Pauses {
    pub at: Vec<u64>,
    pub go: mpsc::Receiver<()>,
    pub paused: mpsc::Sender<()>,
}

/// The source: waits until `ready` processes reported ready, then publishes
/// `data` as `arrival` says, a watermark after each batch, the end of stream
/// last, stopping at `pauses`. Returns once the source listens for the
/// READY events: start the processes it waits for after it.
pub fn source(
    ns: Namespace,
    data: Vec<Out>,
    arrival: Arrival,
    ready: Vec<&'static str>,
    pauses: Option<Pauses>,
) -> std::thread::JoinHandle<anyhow::Result<()>> {
    let (listening_tx, listening_rx) = mpsc::channel();
    let h = std::thread::spawn(move || {
        let ctx = Context::new(&ns, settings(Role::Sensor, "source", 0))?;
        // Listening for READY before anyone can be ready: events keep no
        // history. (A role is ready only once the publishers below exist,
        // but the collector is ready once the role's output exists, which
        // can be before this thread ran at all: its READY was lost and the
        // source waited for it forever, the hang of 2026-12-03.)
        let (mut events, _inbox) = ctx.subscriber(&services::run_events())?;
        listening_tx.send(()).ok();
        let mut imu = ctx.publisher(&services::imu())?;
        let mut depth = ctx.publisher(&services::depth())?;
        let mut progress = ctx.publisher(&services::progress(Role::Sensor))?;
        let mut seen = std::collections::BTreeSet::new();
        while !ready.iter().all(|r| seen.contains(*r)) {
            events.drain(|e| {
                if e.kind == event_kind::READY {
                    seen.insert(fixed_str(&e.process));
                }
            })?;
            std::thread::sleep(Duration::from_millis(1));
        }
        let mut noise = Noise(match arrival {
            Arrival::SlowFirst(seed) => seed,
            Arrival::InOrder => 0,
        });
        let mut i = 0;
        let mut pause = pauses;
        while i < data.len() {
            let len = match arrival {
                Arrival::InOrder => 32,
                Arrival::SlowFirst(_) => 1 + (noise.next_u64() % 200) as usize,
            };
            let mut batch: Vec<Out> = data[i..(i + len).min(data.len())].to_vec();
            if let Some(p) = pause.as_mut()
                && let Some(&at) = p.at.first()
                && batch.iter().any(|o| stamp_of(o) >= at)
            {
                batch.retain(|o| stamp_of(o) < at);
                if batch.is_empty() {
                    p.paused.send(()).ok();
                    p.go.recv()?;
                    p.at.remove(0);
                    continue;
                }
            }
            i += batch.len();
            if let Arrival::SlowFirst(_) = arrival {
                batch.sort_by_key(|o| matches!(o, Out::Imu(_)));
            }
            let last = batch.iter().map(stamp_of).max().unwrap_or(0);
            for (k, o) in batch.iter().enumerate() {
                match o {
                    Out::Imu(m) => imu.publish(*m)?,
                    Out::Depth(m) => depth.publish(*m)?,
                }
                if k % 7 == 3 {
                    imu.flush();
                    depth.flush();
                }
            }
            imu.flush();
            depth.flush();
            // Nothing earlier than the next message's stamp will come (a
            // batch may end between two channels of one instant).
            let next = data.get(i).map_or(last + 1, stamp_of);
            progress.publish_now(Progress::at(next, Role::Sensor, 0))?;
        }
        let last = data.last().map_or(0, stamp_of);
        progress.publish_now(Progress::end_of_stream(last, Role::Sensor, 0))?;
        drop((imu, depth, progress, events));
        ctx.finish();
        Ok(())
    });
    // (A source that failed before it listened says why when joined.)
    let _ = listening_rx.recv();
    h
}

/// Runs `shell` with a fresh `core` as `process` instance `instance`;
/// `prepare` sets the context's standby, snapshot and resume-after.
pub fn role<E>(
    ns: &Namespace,
    shell: fn() -> Shell<E>,
    core: E,
    role: Role,
    process: &'static str,
    instance: u32,
    prepare: impl FnOnce(&mut Context) + Send + 'static,
) -> std::thread::JoinHandle<anyhow::Result<()>>
where
    E: Estimator + Send + 'static,
    E::Input: 'static,
    E::Output: 'static,
    E::Snapshot: 'static,
{
    let ns = ns.clone();
    std::thread::spawn(move || {
        let mut ctx = Context::new(&ns, settings(role, process, instance))?;
        prepare(&mut ctx);
        let result = shell().serve(&mut ctx, core);
        ctx.finish();
        result
    })
}

/// The tracker as instance `instance` of process `tracker`, cold; `prepare`
/// as in [`role`].
pub fn tracker(
    ns: &Namespace,
    instance: u32,
    prepare: impl FnOnce(&mut Context) + Send + 'static,
) -> std::thread::JoinHandle<anyhow::Result<()>> {
    role(
        ns,
        tracker_shell,
        Tracker::cold(),
        Role::Ains,
        "tracker",
        instance,
        prepare,
    )
}

/// Collects `ains/nav` until the end of stream of instance `final_instance`
/// on `ains/progress`; also the
/// latest snapshot and the last health of the tracker.
pub struct Collected {
    pub nav: Vec<NavSolution>,
    pub health: Option<Health>,
}

pub fn collector(
    ns: &Namespace,
    final_instance: u32,
    attached: &Arc<AtomicUsize>,
) -> (
    std::thread::JoinHandle<anyhow::Result<Collected>>,
    mpsc::Receiver<()>,
) {
    let ns = ns.clone();
    let (ready_tx, ready_rx) = mpsc::channel();
    let attached = attached.clone();
    let h = std::thread::spawn(move || {
        let mut ctx = Context::new(&ns, settings(Role::Test, "collector", 0))?;
        let (mut nav, _a) = ctx.subscriber(&services::nav_solution())?;
        let (mut progress, _b) = ctx.subscriber(&services::progress(Role::Ains))?;
        let (mut health, _c) = ctx.subscriber(&services::health(Role::Ains))?;
        ready_tx.send(()).ok();
        // Attached to the tracker's publisher before the source starts (it
        // waits for this READY): until a subscriber attaches, iceoryx2 drops
        // what overflows its queue without back-pressure (docs/design-notes.md,
        // start-up order).
        while !Connect::connect(&nav)? {
            std::thread::sleep(Duration::from_millis(1));
        }
        ctx.ready();
        let mut out = Collected {
            nav: Vec::new(),
            health: None,
        };
        let mut ended = false;
        loop {
            // A stopped instance ends its stream too; the run ends with the
            // last instance's.
            progress.drain(|p| {
                ended |= p.header.is_end_of_stream() && p.header.instance == final_instance
            })?;
            let publishers = nav.publisher_count();
            nav.drain(|m| out.nav.push(m))?;
            attached.store(publishers, Ordering::SeqCst);
            health.drain(|h| out.health = Some(h))?;
            if ended {
                break;
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        // The final health comes right after the end of stream.
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(2)
            && out.health.is_none_or(|h| h.state != state::STOPPED)
        {
            health.drain(|h| out.health = Some(h))?;
            std::thread::sleep(Duration::from_millis(1));
        }
        drop((nav, progress, health));
        ctx.finish();
        Ok(out)
    });
    (h, ready_rx)
}

/// The same estimator in-process, on the inputs in (stamp, declared input)
/// order: what every run through the shell must reproduce.
pub fn reference(data: &[Out]) -> Vec<TrackOut> {
    let mut merged: Vec<(u64, usize, TrackIn)> = data
        .iter()
        .filter_map(|o| match o {
            Out::Imu(m) => Imu::try_from(m)
                .ok()
                .map(|i| (i.stamp_ns, 0, TrackIn::Velocity(i))),
            Out::Depth(m) => Depth::try_from(m)
                .ok()
                .map(|d| (d.stamp_ns, 1, TrackIn::Position(d))),
        })
        .collect();
    merged.sort_by_key(|(s, i, _)| (*s, *i));
    let mut t = Tracker::cold();
    let mut out = Vec::new();
    for (_, _, i) in merged {
        t.on_input(&i, &mut out).expect("valid input");
    }
    out
}

/// Equal output sequences, or the first difference.
pub fn assert_same(a: &[TrackOut], b: &[TrackOut], what: &str) {
    if let Some(k) = (0..a.len().min(b.len())).find(|&k| a[k] != b[k]) {
        panic!("{what}: output {k} differs: {:?} against {:?}", a[k], b[k]);
    }
    assert_eq!(a.len(), b.len(), "{what}: output counts");
}

pub fn outputs(nav: &[NavSolution]) -> Vec<TrackOut> {
    nav.iter()
        .map(|m| TrackOut {
            stamp_ns: m.header.stamp_ns,
            x: m.depth_m,
            std: m.pos_std_ned_m[2],
        })
        .collect()
}

pub fn join<T>(h: std::thread::JoinHandle<anyhow::Result<T>>, what: &str) -> T {
    h.join()
        .unwrap_or_else(|_| panic!("{what} panicked"))
        .unwrap_or_else(|e| panic!("{what}: {e:#}"))
}

/// One run of the tracker over `data` arriving as `arrival`.
pub fn run_tracker(data: Vec<Out>, arrival: Arrival) -> Collected {
    let ns = Namespace::unique();
    let (col, col_ready) = collector(&ns, 0, &Arc::default());
    col_ready.recv().expect("collector started");
    let src = source(
        ns.clone(),
        data,
        arrival,
        vec!["tracker", "collector"],
        None,
    );
    let trk = tracker(&ns, 0, |_| {});
    join(src, "source");
    join(trk, "tracker");
    join(col, "collector")
}

/// Snapshot message of the role's latest state, as the launcher keeps it.
pub fn latest_snapshot(sub: &mut nauta_runtime::Subscriber<AinsSnapshot>) -> Option<AinsSnapshot> {
    let mut last = None;
    sub.drain(|s| last = Some(s)).expect("snapshots");
    last
}

pub fn snapshot_file(s: &AinsSnapshot) -> std::path::PathBuf {
    let path = std::env::temp_dir().join(format!(
        "nauta-shell-test-{}-{}.snapshot",
        std::process::id(),
        s.header.stamp_ns
    ));
    std::fs::write(&path, codec::encode(s).expect("encode")).expect("write snapshot");
    path
}

/// How instance 1 takes over from instance 0 in [`run_handover`].
#[derive(Debug, Clone, Copy)]
pub enum Handover {
    /// A hot swap: instance 1 in standby, activated at instance 0's last
    /// output.
    Swap,
    /// Instance 0 stops; instance 1 starts warm from the latest snapshot once
    /// the source has gone on alone for `lag_ns` (how far a killed instance
    /// lagged behind its inputs, plus the restart, in the run's clock).
    Restart { lag_ns: u64 },
}

/// What the launcher does for a swap or a restart: pause the source at
/// `at_ns`, take the latest snapshot, start instance 1 from it (in standby
/// for a swap), hand over, resume the source.
pub fn run_handover(how: Handover, at_ns: u64) -> (Collected, u64, Vec<TrackOut>) {
    let ns = Namespace::unique();
    let data = samples(30, 3);
    let expected = reference(&data);
    let attached = Arc::new(AtomicUsize::new(0));
    let (col, col_ready) = collector(&ns, 1, &attached);
    col_ready.recv().expect("collector started");
    let launcher =
        Context::new(&ns, settings(Role::Launcher, "launcher", 0)).expect("launcher node");
    let (mut snaps, _i) = launcher
        .subscriber(&services::snapshot::<AinsSnapshot>(Role::Ains))
        .expect("snapshot tap");
    // Run events keep no history: listening before instance 1 starts.
    let (mut events, _e) = launcher
        .subscriber(&services::run_events())
        .expect("run events");
    let (go_tx, go_rx) = mpsc::channel();
    let (paused_tx, paused_rx) = mpsc::channel();
    let mut at = vec![at_ns];
    if let Handover::Restart { lag_ns } = how
        && lag_ns > 0
    {
        at.push(at_ns + lag_ns);
    }
    let src = source(
        ns.clone(),
        data,
        Arrival::InOrder,
        vec!["tracker", "collector"],
        Some(Pauses {
            at,
            go: go_rx,
            paused: paused_tx,
        }),
    );
    let first = tracker(&ns, 0, |_| {});
    paused_rx.recv().expect("source paused");
    // Let the tracker drain what the source published before the pause.
    let t0 = Instant::now();
    let mut snapshot = None;
    while t0.elapsed() < Duration::from_secs(30) {
        if let Some(s) = latest_snapshot(&mut snaps) {
            snapshot = Some(s);
            if s.header.stamp_ns >= at_ns - 2 * SNAPSHOT_NS {
                break;
            }
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let snapshot = snapshot.expect("a snapshot of instance 0");
    let file = snapshot_file(&snapshot);
    let old = ControlClient::open(&launcher, Role::Ains, 0).expect("control of instance 0");
    let request = |command, boundary| ControlRequest {
        header: Header::new(0, 0, Role::Launcher, 0),
        command,
        pad: 0,
        boundary_stamp_ns: boundary,
    };
    let timeout = Duration::from_secs(30);
    let (second, boundary);
    match how {
        Handover::Swap => {
            let f = file.clone();
            second = tracker(&ns, 1, move |c| {
                c.standby = true;
                c.snapshot_file = Some(f);
            });
            // Wait until the collector is attached to the new instance's
            // publisher and the standby instance has had time to catch up.
            wait_attached(&attached, 2);
            std::thread::sleep(Duration::from_millis(300));
            let answer = old
                .request(&launcher, request(command::DEACTIVATE, 0), timeout)
                .expect("deactivate");
            assert_eq!(answer.status, 0, "instance 0 deactivated");
            boundary = answer.last_stamp_ns;
            join(first, "instance 0");
            let new = ControlClient::open(&launcher, Role::Ains, 1).expect("control of instance 1");
            let t0 = Instant::now();
            loop {
                let a = new.request(&launcher, request(command::ACTIVATE, boundary), timeout);
                if matches!(a, Ok(ref r) if r.status == 0) {
                    break;
                }
                assert!(t0.elapsed() < timeout, "instance 1 never activated: {a:?}");
                std::thread::sleep(Duration::from_millis(10));
            }
        }
        Handover::Restart { lag_ns } => {
            let answer = old
                .request(&launcher, request(command::STOP, 0), timeout)
                .expect("stop");
            assert_eq!(answer.status, 0);
            join(first, "instance 0");
            // Instance 0 drained its inputs on STOP: its last output is the
            // last velocity sample before the pause (what the launcher saw
            // last).
            boundary = (at_ns - 1) / IMU_DT_NS * IMU_DT_NS;
            if lag_ns > 0 {
                // Nobody follows the source meanwhile: what it publishes now
                // reaches instance 1 only through the services' history.
                go_tx.send(()).expect("resume the source");
                paused_rx.recv().expect("source paused again");
            }
            let f = file.clone();
            second = tracker(&ns, 1, move |c| {
                c.snapshot_file = Some(f);
                c.resume_after_ns = Some(boundary);
            });
            // The source goes on once instance 1 has subscribed to it (its
            // READY), as it would be running meanwhile in a real run. (Not
            // the collector's count of publishers: a count taken before
            // instance 0 left can be stored after it left, and the source
            // then ended before instance 1 subscribed, which waited for the
            // source's publishers forever: the hang of 2026-12-03.)
            wait_ready(&mut events, "tracker", 1);
        }
    }
    go_tx.send(()).expect("resume the source");
    join(src, "source");
    join(second, "instance 1");
    let _ = std::fs::remove_file(&file);
    drop((old, snaps, events));
    launcher.finish();
    (join(col, "collector"), boundary, expected)
}

/// Waits for the READY event of `process` instance `instance`.
pub fn wait_ready(events: &mut nauta_runtime::Subscriber<RunEvent>, process: &str, instance: u32) {
    let t0 = Instant::now();
    let mut ready = false;
    while !ready {
        events
            .drain(|e| {
                ready |= e.kind == event_kind::READY
                    && e.instance == instance
                    && fixed_str(&e.process) == process;
            })
            .expect("run events");
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "{process} instance {instance} never reported ready"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}

pub const SNAPSHOT_NS: u64 = 1_000_000_000;

/// Waits until the collector has received with `n` publishers present
/// (attached to each: iceoryx2 attaches on receive).
pub fn wait_attached(attached: &AtomicUsize, n: usize) {
    let t0 = Instant::now();
    while attached.load(Ordering::SeqCst) < n {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "collector never attached to {n} publishers"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}
/// The σ a cold tracker starts with, m.
pub const COLD_STD_M: f64 = 10.0;

pub fn assert_every_stamp_once(nav: &[NavSolution], what: &str) {
    let mut count: BTreeMap<u64, u32> = BTreeMap::new();
    for m in nav {
        *count.entry(m.header.stamp_ns).or_default() += 1;
    }
    let expected: Vec<u64> = (1..=3000).map(|k| k * IMU_DT_NS).collect();
    let repeated: Vec<_> = count.iter().filter(|(_, n)| **n > 1).collect();
    assert!(
        repeated.is_empty(),
        "{what}: stamps published twice {repeated:?}"
    );
    let missing: Vec<_> = expected.iter().filter(|s| !count.contains_key(s)).collect();
    assert!(
        missing.is_empty(),
        "{what}: {} stamps missing, first {:?}",
        missing.len(),
        missing.first()
    );
    assert_eq!(count.len(), expected.len(), "{what}: unexpected stamps");
}

/// Both estimators in one thread, in the order the two merges define. At
/// each stamp t: the tracker's velocity input (its output nav(t)); the
/// relay's position input of t, if any (it sorts before nav(t), the relay's
/// second input; its output fix(t)); the relay's nav(t); the tracker's
/// fix(t) (after its velocity input of t, its first input, and before the
/// next one).
pub fn cycle_reference(data: &[Out]) -> Vec<TrackOut> {
    let (mut tracker, mut relay) = (Tracker::cold(), Relay::default());
    let (mut nav, mut fix) = (Vec::new(), Vec::new());
    let mut k = 0;
    while k < data.len() {
        let Out::Imu(m) = &data[k] else {
            panic!("a stamp starts with its velocity sample")
        };
        let before = nav.len();
        let imu = Imu::try_from(m).expect("valid");
        tracker
            .on_input(&TrackIn::Velocity(imu), &mut nav)
            .expect("valid");
        fix.clear();
        if let Some(Out::Depth(d)) = data.get(k + 1) {
            let d = Depth::try_from(d).expect("valid");
            relay
                .on_input(&RelayIn::Position(d), &mut fix)
                .expect("valid");
            k += 1;
        }
        for n in &nav[before..] {
            let seen = Nav::try_from(&nav_of(n).expect("nav")).expect("valid");
            relay
                .on_input(&RelayIn::Tracked(seen), &mut Vec::new())
                .expect("valid");
        }
        for f in &fix {
            let seen = LblNav::try_from(&lbl_of(f).expect("lbl")).expect("valid");
            tracker
                .on_input(&TrackIn::Relayed(seen), &mut Vec::new())
                .expect("valid");
        }
        k += 1;
    }
    nav
}
