//! `nauta bench ipc`: two-process latency and throughput of iceoryx2 against a
//! pipe and a Unix-domain socket (see BENCHMARKS.md, "IPC").
//!
//! The driver (`nauta bench ipc`) re-executes its own binary as
//! `nauta __ipc-peer <case> ...` for every round of every case; the peer is the
//! sender, the driver the receiver that measures. Each iceoryx2 case runs in its own
//! namespace (a unique `global.prefix`) that the peer gets on its command line.
//!
//! The machines are 2-core virtual machines whose wake-up latency and cross-core
//! speed change with the host's state, so comparisons are made under the same
//! conditions: the three wake-up mechanisms take turns message by message in one
//! pair of processes, the other comparisons alternate round by round (which side
//! goes first alternates too). Latencies are pooled over the rounds, throughput is
//! the median of the rounds. A round during which other work ran on the machine is
//! repeated. Nothing is pinned to a CPU.

mod common;
mod large;
mod latency;
mod report;
mod services;
mod throughput;

use anyhow::bail;
use nauta_runtime::Namespace;
use serde_json::json;

use common::{LoadProbe, PeerCtx, Summary, median};
use latency::{Mechanism, Run, Touch, Wait};
use report::{Machine, Report};
use throughput::Writes;

/// Rounds and samples of one latency comparison.
#[derive(Debug, Clone, Copy)]
struct Plan {
    rounds: usize,
    run: Run,
}

const BUSY: Plan = Plan {
    rounds: 3,
    run: Run {
        count: 200_000,
        warmup: 20_000,
    },
};
const WAKEUP: Plan = Plan {
    rounds: 5,
    run: Run {
        count: 2_000,
        warmup: 200,
    },
};
const LARGE_BUSY: Plan = Plan {
    rounds: 3,
    run: Run {
        count: 20_000,
        warmup: 1_000,
    },
};
const LARGE_BLOCKING: Plan = Plan {
    rounds: 3,
    run: Run {
        count: 2_000,
        warmup: 200,
    },
};
/// Messages per iceoryx2 throughput round (and per batched-socket context round).
const THROUGHPUT_MESSAGES: u64 = 2_000_000;
const THROUGHPUT_ROUNDS: usize = 3;
/// Messages per round of the socket baseline, one write() per message: the same
/// work as a publish (each message leaves the sender when it is published). Fewer
/// than iceoryx2's only because the socket is slower; rates are compared.
const UNBUFFERED_MESSAGES: u64 = 500_000;

/// The wait the headline event figure uses (the faster of the two, measured; the
/// other is reported alongside).
const EVENT_WAIT: Mechanism = Mechanism::Listener;

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
    fn add(&mut self, mut round: Vec<u64>) {
        self.round_p50.push(Summary::of(&mut round).p50);
        self.samples.extend_from_slice(&round);
    }

    fn summary(&mut self) -> Summary {
        Summary::of(&mut self.samples)
    }
}

/// The cases' namespace tags.
const CASE_TAGS: [&str; 6] = ["busy", "wake", "tput", "lgb", "lge", "lgt"];

/// The nauta namespace of one case of this run (its rounds run one after the
/// other in it): `bench<pid>-<tag>`.
fn namespace(tag: &str) -> anyhow::Result<Namespace> {
    Ok(Namespace::new(&format!(
        "bench{}-{tag}",
        std::process::id()
    ))?)
}

/// The iceoryx2 prefix of one case's namespace.
fn prefix(tag: &str) -> String {
    namespace(tag).map_or_else(|_| format!("nauta_bench-{tag}_"), |ns| ns.prefix())
}

/// Removes what the cases left once their nodes are gone (iceoryx2 keeps a
/// management file per namespace on purpose; see `Namespace::remove_if_unused`).
fn remove_case_namespaces() {
    for tag in CASE_TAGS {
        if let Ok(ns) = namespace(tag)
            && let Err(e) = ns.remove_if_unused()
        {
            eprintln!("nauta bench ipc: files of namespace {ns} not removed: {e:#}");
        }
    }
}

/// Runs rounds, pools their results and reports progress (with the background load
/// of each round) on stderr. A round during which other work kept more than
/// [`BUSY_MACHINE_CPUS`] busy is repeated (at most [`ROUND_RETRIES`] times): on a
/// 2-core machine such a round measures the other work as much as the IPC.
#[derive(Debug, Default)]
struct RoundLog {
    max_other_cpus: f64,
    repeated: usize,
    contended: usize,
}

/// Background load above which a round is repeated, in CPUs.
const BUSY_MACHINE_CPUS: f64 = 0.2;
/// How often a contended round is repeated before it is kept anyway.
const ROUND_RETRIES: usize = 3;

impl RoundLog {
    fn measure<T>(
        &mut self,
        what: &str,
        round: usize,
        rounds: usize,
        mut f: impl FnMut() -> anyhow::Result<T>,
        show: impl Fn(&T) -> String,
    ) -> anyhow::Result<T> {
        let mut attempt = 0;
        loop {
            let probe = LoadProbe::start();
            let v = f()?;
            let load = probe.finish();
            let busy = load.other_cpus - load.uncertainty_cpus > BUSY_MACHINE_CPUS;
            let retry = busy && attempt < ROUND_RETRIES;
            eprintln!(
                "[bench ipc] {what} round {}/{rounds}: {} (other load {:.2}±{:.2} CPU{})",
                round + 1,
                show(&v),
                load.other_cpus,
                load.uncertainty_cpus,
                if retry { ", repeating" } else { "" }
            );
            if retry {
                attempt += 1;
                self.repeated += 1;
                continue;
            }
            if busy {
                self.contended += 1;
            }
            self.max_other_cpus = self.max_other_cpus.max(load.other_cpus);
            return Ok(v);
        }
    }

    fn latency(
        &mut self,
        pooled: &mut Pooled,
        what: &str,
        round: usize,
        rounds: usize,
        f: impl FnMut() -> anyhow::Result<Vec<u64>>,
    ) -> anyhow::Result<()> {
        let mut v = self.measure(what, round, rounds, f, |v| {
            let mut c = v.clone();
            let s = Summary::of(&mut c);
            format!("p50 {} ns, p99 {} ns", s.p50, s.p99)
        })?;
        pooled.add(std::mem::take(&mut v));
        Ok(())
    }

    fn rate(
        &mut self,
        rates: &mut Vec<f64>,
        what: &str,
        round: usize,
        rounds: usize,
        f: impl FnMut() -> anyhow::Result<f64>,
    ) -> anyhow::Result<()> {
        let rate = self.measure(what, round, rounds, f, |r| format!("{r:.0} msg/s"))?;
        rates.push(rate);
        Ok(())
    }
}

/// Runs the benchmark and prints the report (a table, or one JSON object with
/// `json`). Progress goes to stderr.
pub fn run(json: bool) -> anyhow::Result<()> {
    if cfg!(debug_assertions) {
        eprintln!("[bench ipc] warning: this is a debug build; use --release for real figures");
    }
    let result = measure(json);
    remove_case_namespaces();
    result
}

fn measure(json: bool) -> anyhow::Result<()> {
    let mut log = RoundLog::default();

    // 1. Busy-poll, IMU.
    let mut busy = Pooled::default();
    for r in 0..BUSY.rounds {
        log.latency(&mut busy, "busy-poll", r, BUSY.rounds, || {
            latency::busy(&prefix("busy"), BUSY.run)
        })?;
    }

    // 2./3. Event vs pipe wake-up, interleaved message by message.
    let mut event_listener = Pooled::default();
    let mut event_waitset = Pooled::default();
    let mut pipe = Pooled::default();
    for r in 0..WAKEUP.rounds {
        let [l, w, p] = log.measure(
            "wake-up",
            r,
            WAKEUP.rounds,
            || latency::wakeup(&prefix("wake"), WAKEUP.run),
            |v| {
                let p50 = |x: &Vec<u64>| Summary::of(&mut x.clone()).p50;
                format!(
                    "p50 listener {} ns, waitset {} ns, pipe {} ns",
                    p50(&v[0]),
                    p50(&v[1]),
                    p50(&v[2])
                )
            },
        )?;
        event_listener.add(l);
        event_waitset.add(w);
        pipe.add(p);
    }

    // 4. Lossless throughput, alternating which goes first.
    let mut iox_rates = Vec::new();
    let mut uds_rates = Vec::new();
    for r in 0..THROUGHPUT_ROUNDS {
        for k in 0..2 {
            if (k + r) % 2 == 0 {
                log.rate(
                    &mut iox_rates,
                    "throughput iceoryx2",
                    r,
                    THROUGHPUT_ROUNDS,
                    || throughput::iceoryx2(&prefix("tput"), THROUGHPUT_MESSAGES),
                )?;
            } else {
                log.rate(
                    &mut uds_rates,
                    "throughput socket",
                    r,
                    THROUGHPUT_ROUNDS,
                    || throughput::uds(UNBUFFERED_MESSAGES, Writes::PerMessage),
                )?;
            }
        }
    }

    // For context: the socket batching ~560 messages per write() through a
    // BufWriter. A batch is delivered only when the buffer fills, so this is not
    // the same work as publishing each message at once; iceoryx2 could batch
    // too (slices), which is not measured here.
    let mut uds_buffered_rates = Vec::new();
    for r in 0..THROUGHPUT_ROUNDS {
        log.rate(
            &mut uds_buffered_rates,
            "throughput socket, buffered (batched) writes",
            r,
            THROUGHPUT_ROUNDS,
            || throughput::uds(THROUGHPUT_MESSAGES, Writes::Buffered),
        )?;
    }

    // 5. 64 KiB, busy-poll on both sides, then blocking on both sides.
    let mut large_iox = Pooled::default();
    let mut large_uds = Pooled::default();
    for r in 0..LARGE_BUSY.rounds {
        for k in 0..2 {
            if (k + r) % 2 == 0 {
                log.latency(
                    &mut large_iox,
                    "64 KiB iceoryx2 busy",
                    r,
                    LARGE_BUSY.rounds,
                    || {
                        large::large_iceoryx2(
                            &prefix("lgb"),
                            LARGE_BUSY.run,
                            Wait::Busy,
                            Touch::Transport,
                        )
                    },
                )?;
            } else {
                log.latency(
                    &mut large_uds,
                    "64 KiB socket busy",
                    r,
                    LARGE_BUSY.rounds,
                    || large::large_uds(LARGE_BUSY.run, Wait::Busy, Touch::Transport),
                )?;
            }
        }
    }
    let mut large_iox_blocking = Pooled::default();
    let mut large_uds_blocking = Pooled::default();
    for r in 0..LARGE_BLOCKING.rounds {
        for k in 0..2 {
            if (k + r) % 2 == 0 {
                log.latency(
                    &mut large_iox_blocking,
                    "64 KiB iceoryx2 event",
                    r,
                    LARGE_BLOCKING.rounds,
                    || {
                        large::large_iceoryx2(
                            &prefix("lge"),
                            LARGE_BLOCKING.run,
                            Wait::Blocking,
                            Touch::Full,
                        )
                    },
                )?;
            } else {
                log.latency(
                    &mut large_uds_blocking,
                    "64 KiB socket blocking",
                    r,
                    LARGE_BLOCKING.rounds,
                    || large::large_uds(LARGE_BLOCKING.run, Wait::Blocking, Touch::Full),
                )?;
            }
        }
    }
    let mut large_iox_full = Pooled::default();
    let mut large_uds_full = Pooled::default();
    for r in 0..LARGE_BUSY.rounds {
        for k in 0..2 {
            if (k + r) % 2 == 0 {
                log.latency(
                    &mut large_iox_full,
                    "64 KiB iceoryx2 busy, fill + checksum timed",
                    r,
                    LARGE_BUSY.rounds,
                    || {
                        large::large_iceoryx2(
                            &prefix("lgt"),
                            LARGE_BUSY.run,
                            Wait::Busy,
                            Touch::Full,
                        )
                    },
                )?;
            } else {
                log.latency(
                    &mut large_uds_full,
                    "64 KiB socket busy, fill + checksum timed",
                    r,
                    LARGE_BUSY.rounds,
                    || large::large_uds(LARGE_BUSY.run, Wait::Busy, Touch::Full),
                )?;
            }
        }
    }
    if log.contended > 0 {
        eprintln!(
            "[bench ipc] warning: {} rounds ran while other work kept up to {:.2} CPUs busy; \
             on a 2-core machine that distorts the figures: rerun on a quiet machine",
            log.contended, log.max_other_cpus
        );
    }

    let (event, event_other) = match EVENT_WAIT {
        Mechanism::WaitSet => (&mut event_waitset, &mut event_listener),
        _ => (&mut event_listener, &mut event_waitset),
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
        uds_buffered_rate: median(uds_buffered_rates.clone()),
        iox_rates,
        uds_rates,
        uds_buffered_rates,
        large_iox: large_iox.summary(),
        large_iox_rounds: large_iox.round_p50.clone(),
        large_uds: large_uds.summary(),
        large_uds_rounds: large_uds.round_p50.clone(),
        large_iox_blocking: large_iox_blocking.summary(),
        large_uds_blocking: large_uds_blocking.summary(),
        large_iox_full: large_iox_full.summary(),
        large_uds_full: large_uds_full.summary(),
        machine: Machine::read(),
        max_round_other_cpus: log.max_other_cpus,
        repeated_rounds: log.repeated,
        contended_rounds: log.contended,
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
    if latency_peer(&mut ctx)? || throughput::peer(&mut ctx)? {
        return Ok(());
    }
    bail!("__ipc-peer: unknown case {:?}", ctx.case)
}

/// Runs the peer side of a latency case (small messages in `latency`, 64 KiB
/// in `large`, which builds on it); `Ok(false)` if `case` is not one.
fn latency_peer(ctx: &mut common::PeerCtx) -> anyhow::Result<bool> {
    match ctx.case.as_str() {
        "busy" => latency::busy_peer(ctx)?,
        "wakeup" => latency::wakeup_peer(ctx)?,
        "large-iceoryx2" => large::large_iceoryx2_peer(ctx)?,
        "large-uds" => large::large_uds_peer(ctx)?,
        _ => return Ok(false),
    }
    Ok(true)
}
