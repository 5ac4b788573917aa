//! An estimator killed (SIGKILL, restarted warm from its snapshot) and then
//! hot swapped while a test follows its output stream: the stamp and
//! instance of every message, for the "every stamp exactly once" checks of
//! each role (`tests/ains.rs`, `tests/lbl.rs`).

use std::path::Path;
use std::time::{Duration, Instant};

use nauta_messages::{Message, RunEvent, event_kind, fixed_str};
use nauta_runtime::services::ServiceSpec;
use nauta_runtime::{ClockMode, Inbox, Namespace, Subscriber, services};

use crate::{
    EventWatch, Finished, Gate, Running, Watchdog, kill_9_after_draining,
    start_launch_manifest_with, swap_when_accepted,
};

/// Follows one output stream of a run: (stamp, instance) of every message.
pub struct Follower<M: Message> {
    sub: Subscriber<M>,
    _inbox: Inbox,
    /// Every message seen, in order.
    pub seen: Vec<(u64, u32)>,
}

impl<M: Message> std::fmt::Debug for Follower<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Follower")
            .field("type", &M::TYPE_NAME)
            .field("seen", &self.seen.len())
            .finish()
    }
}

impl<M: Message> Follower<M> {
    /// Follows `spec` in `watch`'s namespace.
    pub fn new(watch: &EventWatch, spec: &ServiceSpec<M>) -> Self {
        let (sub, inbox) = watch.ctx.subscriber(spec).expect("the followed service");
        Self {
            sub,
            _inbox: inbox,
            seen: Vec::new(),
        }
    }

    /// Takes what arrived.
    pub fn poll(&mut self) {
        let seen = &mut self.seen;
        self.sub
            .drain(|m| seen.push((m.header().stamp_ns, m.header().instance)))
            .expect("the followed service");
    }

    /// Polls until `instance` has published at or past `t_ns`.
    pub fn until(&mut self, wd: &Watchdog, launch: &mut Running, instance: u32, t_ns: u64) {
        while !self.seen.iter().any(|&(s, i)| i == instance && s >= t_ns) {
            wd.check();
            assert!(
                launch.is_running(),
                "the run ended before instance {instance} published past {t_ns} ns"
            );
            self.poll();
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// The last stamp seen, ns.
    pub fn last_stamp(&self) -> u64 {
        self.seen.last().map_or(0, |s| s.0)
    }
}

/// The pid `process` announced ready with as `instance`, if it has.
pub fn ready_pid(events: &mut Subscriber<RunEvent>, process: &str, instance: u32) -> Option<u32> {
    let mut pid = None;
    events
        .drain(|e| {
            if e.kind == event_kind::READY
                && fixed_str(&e.process) == process
                && e.instance == instance
            {
                pid = Some(e.pid);
            }
        })
        .expect("run/events");
    pid
}

/// What [`kill_9_then_swap`] saw.
#[derive(Debug)]
pub struct KillSwap {
    /// (stamp, instance) of every message of the followed stream: instance
    /// 0, then 1 (the restart), then 2 (the swap).
    pub seen: Vec<(u64, u32)>,
    /// The run.
    pub out: Finished,
}

/// Runs `manifest` with `args` (which set a `wall` clock at `rate`, a
/// duration and no namespace: this adds one) following `spec`: kills
/// `process` with SIGKILL once it has published past 15 s (a few
/// snapshots), waits for its restart to publish 3 s more, swaps it to
/// `variant`, follows the new instance 3 s, and follows the stream to the
/// end of the run (in `wall` clock a subscriber's queue drops its oldest
/// samples when it is not read).
pub fn kill_9_then_swap<M: Message>(
    wd: &Watchdog,
    manifest: &Path,
    rate: f64,
    args: &[&str],
    process: &str,
    spec: &ServiceSpec<M>,
    variant: &str,
) -> KillSwap {
    let ns = Namespace::unique();
    let watch = EventWatch::with_clock(&ns, Duration::from_millis(500), ClockMode::Wall { rate });
    let (mut events, _events_inbox) = watch
        .ctx
        .subscriber(&services::run_events())
        .expect("run/events");
    let mut f = Follower::new(&watch, spec);
    // No other launch of this test process meanwhile: one starting after the
    // kill would reclaim the killed process's shared memory (every launch
    // cleans up dead nodes) before this test has read its last messages.
    let _alone = Gate::close();
    let mut all = args.to_vec();
    all.extend(["--namespace", ns.as_str()]);
    let mut launch = start_launch_manifest_with(wd, manifest, &all, None);
    f.until(wd, &mut launch, 0, 15_000_000_000);
    let pid = loop {
        wd.check();
        if let Some(pid) = ready_pid(&mut events, process, 0) {
            break pid;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    kill_9_after_draining(wd, pid, || f.poll());
    let killed = Instant::now();
    f.until(wd, &mut launch, 1, 0);
    eprintln!(
        "{process} restart to first output: {:.0} ms after kill -9",
        killed.elapsed().as_secs_f64() * 1e3
    );
    let resumed = f.last_stamp();
    f.until(wd, &mut launch, 1, resumed + 3_000_000_000);
    swap_when_accepted(wd, &ns, process, variant);
    let swapped = f.last_stamp();
    f.until(wd, &mut launch, 2, swapped + 3_000_000_000);
    while launch.is_running() {
        wd.check();
        f.poll();
        std::thread::sleep(Duration::from_millis(5));
    }
    let out = launch.wait(wd);
    f.poll();
    watch.finish();
    KillSwap { seen: f.seen, out }
}

impl KillSwap {
    /// Every stamp exactly once, in order, `period_ns` apart, and a message
    /// from each of the three instances.
    pub fn assert_every_stamp_once(&self, topic: &str, period_ns: u64) {
        for w in self.seen.windows(2) {
            assert_eq!(
                w[1].0,
                w[0].0 + period_ns,
                "{topic} went from {:?} to {:?} (stamp, instance): a stamp lost or repeated\n{}",
                w[0],
                w[1],
                self.out.stderr
            );
        }
        for instance in 0..3 {
            assert!(
                self.seen.iter().any(|s| s.1 == instance),
                "{topic}: no message from instance {instance}"
            );
        }
    }
}
