//! The figures of `nauta bench ipc`: the machine they were measured on, the
//! report's table and JSON, and the targets they are judged against.

use super::*;

/// Where the figures were measured.
#[derive(Debug)]
pub(super) struct Machine {
    pub(super) cpus: usize,
    pub(super) model: String,
    pub(super) kernel: String,
}

impl Machine {
    pub(super) fn read() -> Machine {
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
pub(super) struct Report {
    pub(super) busy: Summary,
    pub(super) busy_rounds: Vec<u64>,
    pub(super) event: Summary,
    pub(super) event_rounds: Vec<u64>,
    pub(super) event_other: Summary,
    pub(super) event_other_rounds: Vec<u64>,
    pub(super) pipe: Summary,
    pub(super) pipe_rounds: Vec<u64>,
    pub(super) iox_rate: f64,
    pub(super) uds_rate: f64,
    pub(super) uds_buffered_rate: f64,
    pub(super) iox_rates: Vec<f64>,
    pub(super) uds_rates: Vec<f64>,
    pub(super) uds_buffered_rates: Vec<f64>,
    pub(super) large_iox: Summary,
    pub(super) large_iox_rounds: Vec<u64>,
    pub(super) large_uds: Summary,
    pub(super) large_uds_rounds: Vec<u64>,
    pub(super) large_iox_blocking: Summary,
    pub(super) large_uds_blocking: Summary,
    pub(super) large_iox_full: Summary,
    pub(super) large_uds_full: Summary,
    pub(super) machine: Machine,
    pub(super) max_round_other_cpus: f64,
    pub(super) repeated_rounds: usize,
    pub(super) contended_rounds: usize,
}

fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 { a / b } else { f64::INFINITY }
}

fn wait_name(w: Mechanism) -> &'static str {
    match w {
        Mechanism::Listener => "listener.timed_wait",
        Mechanism::WaitSet => "waitset",
        Mechanism::Pipe => "pipe read",
    }
}

fn other_wait(w: Mechanism) -> Mechanism {
    match w {
        Mechanism::WaitSet => Mechanism::Listener,
        _ => Mechanism::WaitSet,
    }
}

impl Report {
    pub(super) fn event_over_pipe(&self) -> f64 {
        ratio(self.event.p50 as f64, self.pipe.p50 as f64)
    }

    pub(super) fn throughput_ratio(&self) -> f64 {
        ratio(self.iox_rate, self.uds_rate)
    }

    pub(super) fn large_ratio(&self) -> f64 {
        ratio(self.large_uds.p50 as f64, self.large_iox.p50 as f64)
    }

    pub(super) fn large_blocking_ratio(&self) -> f64 {
        ratio(
            self.large_uds_blocking.p50 as f64,
            self.large_iox_blocking.p50 as f64,
        )
    }

    pub(super) fn large_full_ratio(&self) -> f64 {
        ratio(
            self.large_uds_full.p50 as f64,
            self.large_iox_full.p50 as f64,
        )
    }

    pub(super) fn json(&self) -> serde_json::Value {
        // Built key by key: one json! literal this size exceeds the macro recursion limit.
        let mut o = serde_json::Map::new();
        let mut put = |k: &str, v: serde_json::Value| {
            o.insert(k.to_string(), v);
        };
        put("busy_poll_p50_ns", json!(self.busy.p50));
        put("busy_poll_p99_ns", json!(self.busy.p99));
        put("busy_poll_samples", json!(self.busy.n));
        put("busy_poll_target_p50_max_ns", json!(TARGET_BUSY_P50_NS));
        put(
            "busy_poll_target_met",
            json!(self.busy.p50 <= TARGET_BUSY_P50_NS),
        );
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
        put(
            "event_over_pipe_target_met",
            json!(self.event_over_pipe() <= TARGET_EVENT_OVER_PIPE),
        );
        put("iceoryx2_msgs_per_s", json!(self.iox_rate));
        put("uds_msgs_per_s", json!(self.uds_rate));
        put("uds_writes", json!("one write() per message"));
        put("throughput_messages", json!(THROUGHPUT_MESSAGES));
        put("uds_messages", json!(UNBUFFERED_MESSAGES));
        put("throughput_rounds", json!(THROUGHPUT_ROUNDS));
        put(
            "iceoryx2_over_uds_throughput_ratio",
            json!(self.throughput_ratio()),
        );
        put(
            "throughput_target_min_ratio",
            json!(TARGET_THROUGHPUT_RATIO),
        );
        put(
            "throughput_target_met",
            json!(self.throughput_ratio() >= TARGET_THROUGHPUT_RATIO),
        );
        put("large_wait", json!("busy-poll (both)"));
        put(
            "large_measures",
            json!(
                "stamp taken when the filled message is handed to the transport, read when the receiver holds it"
            ),
        );
        put("large_iceoryx2_p50_ns", json!(self.large_iox.p50));
        put("large_iceoryx2_p99_ns", json!(self.large_iox.p99));
        put("large_uds_p50_ns", json!(self.large_uds.p50));
        put("large_uds_p99_ns", json!(self.large_uds.p99));
        put("large_samples", json!(self.large_iox.n));
        put(
            "large_uds_over_iceoryx2_p50_ratio",
            json!(self.large_ratio()),
        );
        put("large_target_min_ratio", json!(TARGET_LARGE_RATIO));
        put(
            "large_target_met",
            json!(self.large_ratio() >= TARGET_LARGE_RATIO),
        );
        put(
            "large_blocking_iceoryx2_p50_ns",
            json!(self.large_iox_blocking.p50),
        );
        put(
            "large_blocking_iceoryx2_p99_ns",
            json!(self.large_iox_blocking.p99),
        );
        put(
            "large_blocking_uds_p50_ns",
            json!(self.large_uds_blocking.p50),
        );
        put(
            "large_blocking_uds_p99_ns",
            json!(self.large_uds_blocking.p99),
        );
        put("large_blocking_samples", json!(self.large_iox_blocking.n));
        put(
            "large_blocking_uds_over_iceoryx2_p50_ratio",
            json!(self.large_blocking_ratio()),
        );
        put(
            "rounds",
            json!({
                "busy_poll_p50_ns": self.busy_rounds,
                "event_p50_ns": self.event_rounds,
                "event_alt_p50_ns": self.event_other_rounds,
                "pipe_wakeup_p50_ns": self.pipe_rounds,
                "iceoryx2_msgs_per_s": self.iox_rates,
                "uds_msgs_per_s": self.uds_rates,
                "uds_buffered_msgs_per_s": self.uds_buffered_rates,
                "large_iceoryx2_p50_ns": self.large_iox_rounds,
                "large_uds_p50_ns": self.large_uds_rounds,
            }),
        );
        put(
            "large_full_path_iceoryx2_p50_ns",
            json!(self.large_iox_full.p50),
        );
        put(
            "large_full_path_iceoryx2_p99_ns",
            json!(self.large_iox_full.p99),
        );
        put("large_full_path_uds_p50_ns", json!(self.large_uds_full.p50));
        put("large_full_path_uds_p99_ns", json!(self.large_uds_full.p99));
        put(
            "large_full_path_uds_over_iceoryx2_p50_ratio",
            json!(self.large_full_ratio()),
        );
        put("uds_buffered_msgs_per_s", json!(self.uds_buffered_rate));
        put("uds_buffered_messages", json!(THROUGHPUT_MESSAGES));
        put(
            "iceoryx2_over_uds_buffered_throughput_ratio",
            json!(ratio(self.iox_rate, self.uds_buffered_rate)),
        );
        put(
            "background_load_max_round_cpus",
            json!(self.max_round_other_cpus),
        );
        put("repeated_rounds", json!(self.repeated_rounds));
        put("contended_rounds", json!(self.contended_rounds));
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

    pub(super) fn print_table(&self) {
        let met = |ok: bool| if ok { "met" } else { "NOT met" };
        let m = &self.machine;
        println!(
            "nauta bench ipc: {} CPUs, {}, kernel {}",
            m.cpus, m.model, m.kernel
        );
        println!();
        println!("One-way latency, ping-pong (the next message goes after the echo)");
        println!(
            "  {:<52}{:>13}{:>13}{:>10}",
            "case", "p50", "p99", "samples"
        );
        let row = |name: &str, s: &Summary| {
            println!(
                "  {name:<52}{:>10} ns{:>10} ns{:>10}",
                group(s.p50),
                group(s.p99),
                group(s.n as u64)
            );
        };
        row("busy-poll, IMU, iceoryx2", &self.busy);
        row(
            &format!("event wake-up, IMU, iceoryx2, {}", wait_name(EVENT_WAIT)),
            &self.event,
        );
        row(
            &format!(
                "event wake-up, IMU, iceoryx2, {}",
                wait_name(other_wait(EVENT_WAIT))
            ),
            &self.event_other,
        );
        row("pipe wake-up, 8-byte stamp (kernel floor)", &self.pipe);
        row("64 KiB, iceoryx2, busy-poll", &self.large_iox);
        row("64 KiB, socket + bincode, busy-poll", &self.large_uds);
        row(
            "64 KiB, iceoryx2, busy, fill + checksum inside",
            &self.large_iox_full,
        );
        row(
            "64 KiB, socket + bincode, busy, fill + checksum inside",
            &self.large_uds_full,
        );
        row("64 KiB, iceoryx2, event", &self.large_iox_blocking);
        row(
            "64 KiB, socket + bincode, blocking read",
            &self.large_uds_blocking,
        );
        println!();
        println!(
            "Lossless throughput, IMU messages (median of {} rounds)",
            THROUGHPUT_ROUNDS
        );
        let rate = |name: &str, r: f64, n: u64| {
            println!(
                "  {name:<52}{:>13} msg/s  ({} messages)",
                group(r as u64),
                group(n)
            );
        };
        rate(
            "iceoryx2, back-pressure",
            self.iox_rate,
            THROUGHPUT_MESSAGES,
        );
        rate(
            "socket + bincode, one write per message",
            self.uds_rate,
            UNBUFFERED_MESSAGES,
        );
        rate(
            "socket + bincode, batched writes (context)",
            self.uds_buffered_rate,
            THROUGHPUT_MESSAGES,
        );
        println!();
        println!("Targets");
        let target = |name: &str, value: String, ok: bool| {
            println!("  {name:<52}{value:>13}  {}", met(ok));
        };
        target(
            &format!("busy-poll p50 <= {TARGET_BUSY_P50_NS} ns"),
            format!("{} ns", group(self.busy.p50)),
            self.busy.p50 <= TARGET_BUSY_P50_NS,
        );
        target(
            &format!("event p50 <= {TARGET_EVENT_OVER_PIPE} x pipe p50"),
            format!("{:.2} x", self.event_over_pipe()),
            self.event_over_pipe() <= TARGET_EVENT_OVER_PIPE,
        );
        target(
            &format!("iceoryx2 >= {TARGET_THROUGHPUT_RATIO} x socket throughput"),
            format!("{:.2} x", self.throughput_ratio()),
            self.throughput_ratio() >= TARGET_THROUGHPUT_RATIO,
        );
        target(
            &format!("64 KiB socket p50 >= {TARGET_LARGE_RATIO} x iceoryx2 p50"),
            format!("{:.1} x", self.large_ratio()),
            self.large_ratio() >= TARGET_LARGE_RATIO,
        );
        println!(
            "    (64 KiB with payload fill and checksum timed: {:.1} x; both blocking: {:.2} x)",
            self.large_full_ratio(),
            self.large_blocking_ratio()
        );
        if self.contended_rounds > 0 {
            println!();
            println!(
                "Warning: {} rounds ran while other work kept up to {:.2} CPUs busy.",
                self.contended_rounds, self.max_round_other_cpus
            );
        }
    }
}

/// 1234567 -> "1,234,567".
fn group(v: u64) -> String {
    let s = v.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}
