//! `nauta bench ipc`: two-process latency and throughput of iceoryx2 against a
//! pipe and a Unix-domain socket (see BENCHMARKS.md, "IPC").
//!
//! The driver (`nauta bench ipc`) re-executes its own binary as
//! `nauta __ipc-peer <case> ...` for every case and round; the peer is the sender,
//! the driver the receiver that measures. Each iceoryx2 case runs in its own
//! namespace (a unique `global.prefix`) that the peer gets on its command line.
//! Cases of a comparison are interleaved round by round so that a slow phase of
//! the (2-core, virtualised) machine hits both sides; latencies are pooled over
//! the rounds, throughput is the median of the rounds.
//!
//! Nothing is pinned to a CPU.

mod common;
mod latency;
mod services;
mod throughput;

use anyhow::bail;
use serde_json::json;

use common::{PeerCtx, Summary, median};
use latency::{EventWait, Run, Wait};

/// Rounds and samples of one latency comparison.
#[derive(Debug, Clone, Copy)]
struct Plan {
    rounds: usize,
    run: Run,
}

const BUSY: Plan = Plan {
    rounds: 3,
    run: Run {
        count: 30_000,
        warmup: 5_000,
    },
};
const WAKEUP: Plan = Plan {
    rounds: 5,
    run: Run {
        count: 4_000,
        warmup: 500,
    },
};
const LARGE_BUSY: Plan = Plan {
    rounds: 3,
    run: Run {
        count: 5_000,
        warmup: 500,
    },
};
const LARGE_BLOCKING: Plan = Plan {
    rounds: 3,
    run: Run {
        count: 2_000,
        warmup: 200,
    },
};
const THROUGHPUT_MESSAGES: u64 = 2_000_000;
const THROUGHPUT_ROUNDS: usize = 3;

/// The wait the headline event figure uses (the faster of the two, measured; the
/// other is reported alongside).
const EVENT_WAIT: EventWait = EventWait::Listener;

const TARGET_BUSY_P50_NS: u64 = 1_000;
const TARGET_EVENT_OVER_PIPE: f64 = 1.5;
const TARGET_THROUGHPUT_RATIO: f64 = 3.0;
const TARGET_LARGE_RATIO: f64 = 20.0;

/// Latencies of one case, pooled over its rounds.
#[derive(Debug, Default)]
struct Pooled {
    samples: Vec<u64>,
    round_p50: Vec<u64>,
}

impl Pooled {
    fn add(&mut self, mut round: Vec<u64>) -> u64 {
        let p50 = Summary::of(&mut round).p50;
        self.round_p50.push(p50);
        self.samples.extend_from_slice(&round);
        p50
    }

    fn summary(&mut self) -> Summary {
        Summary::of(&mut self.samples)
    }
}

fn prefix(tag: &str, round: usize) -> String {
    format!("nautabench{}_{tag}{round}_", std::process::id())
}

fn progress(what: &str, round: usize, rounds: usize, figure: String) {
    eprintln!("[bench ipc] {what} round {}/{rounds}: {figure}", round + 1);
}

/// Runs the benchmark and prints the report (a table, or one JSON object with
/// `json`). Progress goes to stderr.
pub fn run(json: bool) -> anyhow::Result<()> {
    if cfg!(debug_assertions) {
        eprintln!("[bench ipc] warning: this is a debug build; use --release for real figures");
    }

    let only = std::env::var("NAUTA_BENCH_IPC_ONLY").unwrap_or_default();
    let want = |k: &str| only.is_empty() || only.split(',').any(|x| x == k);
    // 1. Busy-poll, IMU.
    let mut busy = Pooled::default();
    for r in 0..BUSY.rounds * usize::from(want("busy")) {
        let p50 = busy.add(latency::busy(&prefix("busy", r), BUSY.run)?);
        progress("busy-poll", r, BUSY.rounds, format!("p50 {p50} ns"));
    }

    // 2./3. Event vs pipe wake-up, interleaved, the order rotating every round.
    let mut event_listener = Pooled::default();
    let mut event_waitset = Pooled::default();
    let mut pipe = Pooled::default();
    for r in 0..WAKEUP.rounds * usize::from(want("wakeup")) {
        for k in 0..3 {
            match (k + r) % 3 {
                0 => {
                    let p50 = event_listener.add(latency::event(
                        &prefix("evl", r),
                        WAKEUP.run,
                        EventWait::Listener,
                    )?);
                    progress("event (listener)", r, WAKEUP.rounds, format!("p50 {p50} ns"));
                }
                1 => {
                    let p50 = event_waitset.add(latency::event(
                        &prefix("evw", r),
                        WAKEUP.run,
                        EventWait::WaitSet,
                    )?);
                    progress("event (waitset)", r, WAKEUP.rounds, format!("p50 {p50} ns"));
                }
                _ => {
                    let p50 = pipe.add(latency::pipe_wakeup(WAKEUP.run)?);
                    progress("pipe", r, WAKEUP.rounds, format!("p50 {p50} ns"));
                }
            }
        }
    }

    // 4. Lossless throughput, alternating which goes first.
    let mut iox_rates = Vec::new();
    let mut uds_rates = Vec::new();
    for r in 0..THROUGHPUT_ROUNDS * usize::from(want("tput")) {
        for k in 0..2 {
            if (k + r) % 2 == 0 {
                let rate = throughput::iceoryx2(&prefix("tput", r), THROUGHPUT_MESSAGES)?;
                progress("throughput iceoryx2", r, THROUGHPUT_ROUNDS, format!("{rate:.0} msg/s"));
                iox_rates.push(rate);
            } else {
                let rate = throughput::uds(THROUGHPUT_MESSAGES)?;
                progress("throughput socket", r, THROUGHPUT_ROUNDS, format!("{rate:.0} msg/s"));
                uds_rates.push(rate);
            }
        }
    }

    // 5. 64 KiB, busy-poll on both sides, then blocking on both sides.
    let mut large_iox = Pooled::default();
    let mut large_uds = Pooled::default();
    for r in 0..LARGE_BUSY.rounds * usize::from(want("large")) {
        for k in 0..2 {
            if (k + r) % 2 == 0 {
                let p50 = large_iox.add(latency::large_iceoryx2(
                    &prefix("lgb", r),
                    LARGE_BUSY.run,
                    Wait::Busy,
                )?);
                progress("64 KiB iceoryx2 busy", r, LARGE_BUSY.rounds, format!("p50 {p50} ns"));
            } else {
                let p50 = large_uds.add(latency::large_uds(LARGE_BUSY.run, Wait::Busy)?);
                progress("64 KiB socket busy", r, LARGE_BUSY.rounds, format!("p50 {p50} ns"));
            }
        }
    }
    let mut large_iox_blocking = Pooled::default();
    let mut large_uds_blocking = Pooled::default();
    for r in 0..LARGE_BLOCKING.rounds * usize::from(want("largeb")) {
        for k in 0..2 {
            if (k + r) % 2 == 0 {
                let p50 = large_iox_blocking.add(latency::large_iceoryx2(
                    &prefix("lge", r),
                    LARGE_BLOCKING.run,
                    Wait::Blocking,
                )?);
                progress("64 KiB iceoryx2 event", r, LARGE_BLOCKING.rounds, format!("p50 {p50} ns"));
            } else {
                let p50 =
                    large_uds_blocking.add(latency::large_uds(LARGE_BLOCKING.run, Wait::Blocking)?);
                progress("64 KiB socket blocking", r, LARGE_BLOCKING.rounds, format!("p50 {p50} ns"));
            }
        }
    }

    let (event, event_other) = match EVENT_WAIT {
        EventWait::Listener => (&mut event_listener, &mut event_waitset),
        EventWait::WaitSet => (&mut event_waitset, &mut event_listener),
    };
    let report = Report {
        busy: busy.summary(),
        busy_rounds: busy.round_p50.clone(),
        event: event.summary(),
        event_rounds: event.round_p50.clone(),
        event_other: event_other.summary(),
        event_other_rounds: event_other.round_p50.clone(),
        pipe: pipe.summary(),
        pipe_rounds: pipe.round_p50.clone(),
        iox_rate: median(iox_rates.clone()),
        uds_rate: median(uds_rates.clone()),
        iox_rates,
        uds_rates,
        large_iox: large_iox.summary(),
        large_iox_rounds: large_iox.round_p50.clone(),
        large_uds: large_uds.summary(),
        large_uds_rounds: large_uds.round_p50.clone(),
        large_iox_blocking: large_iox_blocking.summary(),
        large_uds_blocking: large_uds_blocking.summary(),
        machine: Machine::read(),
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&report.json())?);
    } else {
        report.print_table();
    }
    Ok(())
}

/// The peer side: `nauta __ipc-peer <case> key=value...`.
pub fn peer(args: &[String]) -> anyhow::Result<()> {
    let mut ctx = PeerCtx::from_args(args)?;
    if latency::peer(&mut ctx)? || throughput::peer(&mut ctx)? {
        return Ok(());
    }
    bail!("__ipc-peer: unknown case {:?}", ctx.case)
}

/// Where the figures were measured.
#[derive(Debug)]
struct Machine {
    cpus: usize,
    model: String,
    kernel: String,
}

impl Machine {
    fn read() -> Machine {
        let cpus = std::thread::available_parallelism().map_or(0, |n| n.get());
        let model = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        let kernel = std::fs::read_to_string("/proc/sys/kernel/osrelease")
            .map(|s| s.trim().to_string())
            .unwrap_or_else(|_| "unknown".into());
        Machine {
            cpus,
            model,
            kernel,
        }
    }
}

#[derive(Debug)]
struct Report {
    busy: Summary,
    busy_rounds: Vec<u64>,
    event: Summary,
    event_rounds: Vec<u64>,
    event_other: Summary,
    event_other_rounds: Vec<u64>,
    pipe: Summary,
    pipe_rounds: Vec<u64>,
    iox_rate: f64,
    uds_rate: f64,
    iox_rates: Vec<f64>,
    uds_rates: Vec<f64>,
    large_iox: Summary,
    large_iox_rounds: Vec<u64>,
    large_uds: Summary,
    large_uds_rounds: Vec<u64>,
    large_iox_blocking: Summary,
    large_uds_blocking: Summary,
    machine: Machine,
}

fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 { a / b } else { f64::INFINITY }
}

fn wait_name(w: EventWait) -> &'static str {
    match w {
        EventWait::Listener => "listener.timed_wait",
        EventWait::WaitSet => "waitset",
    }
}

fn other_wait(w: EventWait) -> EventWait {
    match w {
        EventWait::Listener => EventWait::WaitSet,
        EventWait::WaitSet => EventWait::Listener,
    }
}

impl Report {
    fn event_over_pipe(&self) -> f64 {
        ratio(self.event.p50 as f64, self.pipe.p50 as f64)
    }

    fn throughput_ratio(&self) -> f64 {
        ratio(self.iox_rate, self.uds_rate)
    }

    fn large_ratio(&self) -> f64 {
        ratio(self.large_uds.p50 as f64, self.large_iox.p50 as f64)
    }

    fn large_blocking_ratio(&self) -> f64 {
        ratio(
            self.large_uds_blocking.p50 as f64,
            self.large_iox_blocking.p50 as f64,
        )
    }

    fn json(&self) -> serde_json::Value {
        // Built key by key: one json! literal this size exceeds the macro recursion limit.
        let mut o = serde_json::Map::new();
        let mut put = |k: &str, v: serde_json::Value| {
            o.insert(k.to_string(), v);
        };
        put("busy_poll_p50_ns", json!(self.busy.p50));
        put("busy_poll_p99_ns", json!(self.busy.p99));
        put("busy_poll_samples", json!(self.busy.n));
        put("busy_poll_target_p50_max_ns", json!(TARGET_BUSY_P50_NS));
        put("busy_poll_target_met", json!(self.busy.p50 <= TARGET_BUSY_P50_NS));
        put("event_p50_ns", json!(self.event.p50));
        put("event_p99_ns", json!(self.event.p99));
        put("event_samples", json!(self.event.n));
        put("event_wait", json!(wait_name(EVENT_WAIT)));
        put("event_alt_wait", json!(wait_name(other_wait(EVENT_WAIT))));
        put("event_alt_p50_ns", json!(self.event_other.p50));
        put("event_alt_p99_ns", json!(self.event_other.p99));
        put("pipe_wakeup_p50_ns", json!(self.pipe.p50));
        put("pipe_wakeup_p99_ns", json!(self.pipe.p99));
        put("pipe_wakeup_samples", json!(self.pipe.n));
        put("event_over_pipe_p50_ratio", json!(self.event_over_pipe()));
        put("event_over_pipe_target_max", json!(TARGET_EVENT_OVER_PIPE));
        put("event_over_pipe_target_met", json!(self.event_over_pipe() <= TARGET_EVENT_OVER_PIPE));
        put("iceoryx2_msgs_per_s", json!(self.iox_rate));
        put("uds_msgs_per_s", json!(self.uds_rate));
        put("throughput_messages", json!(THROUGHPUT_MESSAGES));
        put("throughput_rounds", json!(THROUGHPUT_ROUNDS));
        put("iceoryx2_over_uds_throughput_ratio", json!(self.throughput_ratio()));
        put("throughput_target_min_ratio", json!(TARGET_THROUGHPUT_RATIO));
        put("throughput_target_met", json!(self.throughput_ratio() >= TARGET_THROUGHPUT_RATIO));
        put("large_wait", json!("busy-poll (both)"));
        put("large_iceoryx2_p50_ns", json!(self.large_iox.p50));
        put("large_iceoryx2_p99_ns", json!(self.large_iox.p99));
        put("large_uds_p50_ns", json!(self.large_uds.p50));
        put("large_uds_p99_ns", json!(self.large_uds.p99));
        put("large_samples", json!(self.large_iox.n));
        put("large_uds_over_iceoryx2_p50_ratio", json!(self.large_ratio()));
        put("large_target_min_ratio", json!(TARGET_LARGE_RATIO));
        put("large_target_met", json!(self.large_ratio() >= TARGET_LARGE_RATIO));
        put("large_blocking_iceoryx2_p50_ns", json!(self.large_iox_blocking.p50));
        put("large_blocking_iceoryx2_p99_ns", json!(self.large_iox_blocking.p99));
        put("large_blocking_uds_p50_ns", json!(self.large_uds_blocking.p50));
        put("large_blocking_uds_p99_ns", json!(self.large_uds_blocking.p99));
        put("large_blocking_samples", json!(self.large_iox_blocking.n));
        put("large_blocking_uds_over_iceoryx2_p50_ratio", json!(self.large_blocking_ratio()));
        put(
            "rounds",
            json!({
                "busy_poll_p50_ns": self.busy_rounds,
                "event_p50_ns": self.event_rounds,
                "event_alt_p50_ns": self.event_other_rounds,
                "pipe_wakeup_p50_ns": self.pipe_rounds,
                "iceoryx2_msgs_per_s": self.iox_rates,
                "uds_msgs_per_s": self.uds_rates,
                "large_iceoryx2_p50_ns": self.large_iox_rounds,
                "large_uds_p50_ns": self.large_uds_rounds,
            }),
        );
        put(
            "machine",
            json!({
                "cpus": self.machine.cpus,
                "model": self.machine.model,
                "kernel": self.machine.kernel,
            }),
        );
        serde_json::Value::Object(o)
    }

    fn print_table(&self) {
        let met = |ok: bool| if ok { "met" } else { "NOT met" };
        let m = &self.machine;
        println!(
            "nauta bench ipc: {} CPUs, {}, kernel {}",
            m.cpus, m.model, m.kernel
        );
        println!();
        println!(
            "One-way latency (ping-pong, unqueued)      {:>10} {:>10} {:>9}",
            "p50", "p99", "samples"
        );
        let row = |name: &str, s: &Summary| {
            println!(
                "  {name:<41}{:>7} ns {:>7} ns {:>9}",
                group(s.p50),
                group(s.p99),
                group(s.n as u64)
            );
        };
        row("busy-poll, IMU, iceoryx2", &self.busy);
        row(
            &format!("event wake-up, IMU, iceoryx2 ({})", wait_name(EVENT_WAIT)),
            &self.event,
        );
        row(
            &format!("  (same with {})", wait_name(other_wait(EVENT_WAIT))),
            &self.event_other,
        );
        row("pipe wake-up, 8-byte stamp", &self.pipe);
        row("64 KiB, iceoryx2, busy-poll", &self.large_iox);
        row("64 KiB, socket + bincode, busy-poll", &self.large_uds);
        row("64 KiB, iceoryx2, event", &self.large_iox_blocking);
        row("64 KiB, socket + bincode, blocking read", &self.large_uds_blocking);
        println!();
        println!(
            "Lossless throughput, IMU, {} messages, median of {} rounds",
            group(THROUGHPUT_MESSAGES),
            THROUGHPUT_ROUNDS
        );
        println!(
            "  iceoryx2 (back-pressure)                 {:>12} msg/s",
            group(self.iox_rate as u64)
        );
        println!(
            "  Unix socket + bincode                    {:>12} msg/s",
            group(self.uds_rate as u64)
        );
        println!();
        println!("Targets");
        println!(
            "  busy-poll p50 <= {} ns                   {:>9} ns   {}",
            TARGET_BUSY_P50_NS,
            group(self.busy.p50),
            met(self.busy.p50 <= TARGET_BUSY_P50_NS)
        );
        println!(
            "  event p50 <= {:.1} x pipe p50              {:>9.2} x    {}",
            TARGET_EVENT_OVER_PIPE,
            self.event_over_pipe(),
            met(self.event_over_pipe() <= TARGET_EVENT_OVER_PIPE)
        );
        println!(
            "  iceoryx2 >= {:.0} x socket throughput        {:>9.2} x    {}",
            TARGET_THROUGHPUT_RATIO,
            self.throughput_ratio(),
            met(self.throughput_ratio() >= TARGET_THROUGHPUT_RATIO)
        );
        println!(
            "  64 KiB socket p50 >= {:.0} x iceoryx2 p50   {:>9.2} x    {} (busy-poll; blocking: {:.2} x)",
            TARGET_LARGE_RATIO,
            self.large_ratio(),
            met(self.large_ratio() >= TARGET_LARGE_RATIO),
            self.large_blocking_ratio()
        );
    }
}

/// 1234567 -> "1,234,567".
fn group(v: u64) -> String {
    let s = v.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}
