//! One-way latency cases. All use the same ping-pong pattern so that every sample
//! is measured unqueued: the peer (sender) stamps a message with CLOCK_MONOTONIC
//! and sends it; the driver (receiver) takes the message, reads the clock and
//! records `now - stamp`, then echoes; the peer sends the next message only after
//! the echo arrived. The first `warmup` samples of every round are discarded.
//!
//! The stamp is taken before the send path starts (before `loan`, before the
//! encoding, before `write`) and the receiver reads the clock after it holds the
//! message (after `receive`, after the decoding and, for 64 KiB, after reading the
//! payload), so every transport is charged for its whole path.

use std::fs::File;
use std::io::{Read, Write};

use anyhow::{Context, bail, ensure};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::update_connections::UpdateConnections as _;
use iceoryx2::prelude::{
    CallbackProgression, PortFactory as _, SignalHandlingMode, WaitSetBuilder, ipc,
};
use iceoryx2::waitset::WaitSetRunResult;
use nauta_messages::ImuSample;

use super::common::{
    Peer, PeerCtx, SPIN_CHECK, STARTUP_TIMEOUT, WAIT_SLICE, Watchdog, driver_node, now_ns,
    peer_node, pipe, since, wait_until,
};
use super::services::{self as svc, LATENCY_BUFFER, Side, name, payload_seq, verify_large};

/// Sample counts of one round.
#[derive(Debug, Clone, Copy)]
pub struct Run {
    /// Samples recorded.
    pub count: u64,
    /// Samples sent first and discarded.
    pub warmup: u64,
}

impl Run {
    pub(super) fn args(&self) -> Vec<(&'static str, String)> {
        vec![
            ("count", self.count.to_string()),
            ("warmup", self.warmup.to_string()),
        ]
    }

    pub(super) fn from_ctx(ctx: &PeerCtx) -> anyhow::Result<Run> {
        Ok(Run {
            count: ctx.num("count")?,
            warmup: ctx.num("warmup")?,
        })
    }
}

/// How the receivers of the 64 KiB cases wait.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wait {
    /// Both sides spin (iceoryx2 `receive()`, non-blocking socket `read()`).
    Busy,
    /// Both sides block (iceoryx2 listener, blocking socket `read()`).
    Blocking,
}

impl Wait {
    pub(super) fn as_arg(self) -> &'static str {
        match self {
            Wait::Busy => "busy",
            Wait::Blocking => "blocking",
        }
    }

    pub(super) fn from_arg(s: &str) -> anyhow::Result<Wait> {
        match s {
            "busy" => Ok(Wait::Busy),
            "blocking" => Ok(Wait::Blocking),
            _ => bail!("unknown wait {s:?}"),
        }
    }
}

/// What the 64 KiB cases do with the payload.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Touch {
    /// The sender writes all 64 KiB of every message (copies a pattern into it) and
    /// the receiver reads all of it (checksum): producing and consuming the data is
    /// charged to both transports alike.
    Full,
    /// Transport only: the sender writes the sequence number and the stamp, the
    /// receiver checks the sequence number; the rest of the payload is what an
    /// earlier message left there. (bincode still copies all 64 KiB when it encodes
    /// and decodes: that is part of the socket's transport.)
    Transport,
}

impl Touch {
    pub(super) fn as_arg(self) -> &'static str {
        match self {
            Touch::Full => "full",
            Touch::Transport => "transport",
        }
    }

    pub(super) fn from_arg(s: &str) -> anyhow::Result<Touch> {
        match s {
            "full" => Ok(Touch::Full),
            "transport" => Ok(Touch::Transport),
            _ => bail!("unknown touch {s:?}"),
        }
    }

    /// The receiver's check of a payload.
    pub(super) fn check(self, bytes: &[u8], seq: u64, pattern_sum: u64) -> anyhow::Result<()> {
        match self {
            Touch::Full => verify_large(bytes, seq, pattern_sum),
            Touch::Transport => {
                let got = payload_seq(bytes);
                ensure!(got == seq, "64 KiB message {got} arrived, expected {seq}");
                Ok(())
            }
        }
    }
}

/// The driver's loop: receive (returns the latency), record after warm-up, echo.
pub(super) fn receive_loop(
    run: Run,
    mut receive: impl FnMut(u64) -> anyhow::Result<u64>,
    mut echo: impl FnMut(u64) -> anyhow::Result<()>,
) -> anyhow::Result<Vec<u64>> {
    let mut out = Vec::with_capacity(run.count as usize);
    for seq in 0..run.warmup + run.count {
        let latency = receive(seq)?;
        if seq >= run.warmup {
            out.push(latency);
        }
        echo(seq)?;
    }
    Ok(out)
}

/// The peer's loop: send, wait for the echo.
pub(super) fn send_loop(
    run: Run,
    mut send: impl FnMut(u64) -> anyhow::Result<()>,
    mut wait_echo: impl FnMut(u64) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    for seq in 0..run.warmup + run.count {
        send(seq)?;
        wait_echo(seq)?;
    }
    Ok(())
}

/// Polls until `poll` yields, checking the watchdog every [`SPIN_CHECK`] empty polls.
#[inline]
pub(super) fn spin<T>(
    wd: &Watchdog<'_>,
    mut poll: impl FnMut() -> anyhow::Result<Option<T>>,
) -> anyhow::Result<T> {
    let mut idle = 0u32;
    loop {
        if let Some(v) = poll()? {
            return Ok(v);
        }
        idle += 1;
        if idle == SPIN_CHECK {
            idle = 0;
            wd.check()?;
        }
    }
}

/// Blocks on the listener until at least one notification arrived (no spinning
/// before blocking: this measures the wake-up).
pub(super) fn block_listener(
    listener: &Listener<ipc::Service>,
    wd: &Watchdog<'_>,
) -> anyhow::Result<()> {
    loop {
        let mut notified = false;
        listener
            .timed_wait(|_| notified = true, WAIT_SLICE)
            .context("listener wait")?;
        if notified {
            return Ok(());
        }
        wd.check()?;
    }
}

pub(super) fn prefix_arg(prefix: &str) -> (&'static str, String) {
    ("prefix", prefix.to_string())
}

// ---------------------------------------------------------------------------
// 1. Busy-poll, IMU, iceoryx2.
// ---------------------------------------------------------------------------

/// Driver side of the busy-poll case.
pub fn busy(prefix: &str, run: Run) -> anyhow::Result<Vec<u64>> {
    let mut args = run.args();
    args.push(prefix_arg(prefix));
    let peer = Peer::spawn("busy", &args, vec![])?;
    driver_node(prefix, peer, |node, peer| {
        let ping = svc::pubsub::<ImuSample>(node, name::PING, LATENCY_BUFFER, Side::Create)?;
        let pong = svc::pubsub::<u64>(node, name::PONG, LATENCY_BUFFER, Side::Create)?;
        let sub = svc::subscriber(&ping, LATENCY_BUFFER)?;
        let echo = svc::publisher(&pong, None)?;
        peer.wait_ready()?;
        wait_until("the peer's ports", STARTUP_TIMEOUT, || {
            ping.dynamic_config().number_of_publishers() == 1
                && pong.dynamic_config().number_of_subscribers() == 1
        })?;
        sub.update_connections().context("connect the subscriber")?;
        peer.go()?;
        let latencies = {
            let wd = Watchdog::driver(peer);
            receive_loop(
                run,
                |seq| {
                    let (latency, got) = spin(&wd, || {
                        Ok(match sub.receive()? {
                            Some(s) => {
                                let now = now_ns();
                                Some((since(s.header.stamp_ns, now)?, s.header.seq))
                            }
                            None => None,
                        })
                    })?;
                    ensure!(got == seq, "busy: message {got} arrived, expected {seq}");
                    Ok(latency)
                },
                |seq| {
                    echo.send_copy(seq)?;
                    Ok(())
                },
            )?
        };
        Ok(latencies)
    })
}

pub(super) fn busy_peer(ctx: &mut PeerCtx) -> anyhow::Result<()> {
    let run = Run::from_ctx(ctx)?;
    let prefix = ctx.str("prefix")?.to_string();
    peer_node(&prefix, |node| {
        let ping = svc::pubsub::<ImuSample>(node, name::PING, LATENCY_BUFFER, Side::Open)?;
        let pong = svc::pubsub::<u64>(node, name::PONG, LATENCY_BUFFER, Side::Open)?;
        let publisher = svc::publisher(&ping, Some(ctx.parent))?;
        let echo = svc::subscriber(&pong, LATENCY_BUFFER)?;
        wait_until("the driver's subscriber", STARTUP_TIMEOUT, || {
            ping.dynamic_config().number_of_subscribers() == 1
                && pong.dynamic_config().number_of_publishers() == 1
        })?;
        echo.update_connections()
            .context("connect the subscriber")?;
        ctx.ready_then_wait_go()?;
        let wd = Watchdog::peer(Some(node), ctx.parent);
        send_loop(
            run,
            |seq| {
                let t0 = now_ns();
                let delivered = publisher
                    .loan_uninit()?
                    .write_payload(svc::imu(seq, t0))
                    .send()?;
                ensure!(delivered == 1, "busy: the driver's subscriber is gone");
                Ok(())
            },
            |seq| {
                let got = spin(&wd, || Ok(echo.receive()?.map(|s| *s.payload())))?;
                ensure!(got == seq, "busy: echo {got}, expected {seq}");
                Ok(())
            },
        )?;
        ctx.done()
    })
}

// ---------------------------------------------------------------------------
// 2./3. Wake-up: iceoryx2 event (two ways of waiting) and a pipe, interleaved.
// ---------------------------------------------------------------------------

/// The three blocking mechanisms of the wake-up case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mechanism {
    /// iceoryx2 sample + notification; the receiver blocks in `Listener::timed_wait`
    /// (one blocking `recvfrom` on the listener's socket).
    Listener,
    /// iceoryx2 sample + notification; the receiver blocks in a `WaitSet` with the
    /// listener attached (`epoll_wait`, then `Listener::try_wait`).
    WaitSet,
    /// An 8-byte stamp through a pipe; the receiver blocks in `read()`.
    Pipe,
}

impl Mechanism {
    /// All three, in the order of their latency vectors.
    pub const ALL: [Mechanism; 3] = [Mechanism::Listener, Mechanism::WaitSet, Mechanism::Pipe];

    /// The mechanism of message `seq`. Messages rotate through the three, in an order
    /// that changes every triple (all six permutations in turn), so that each
    /// mechanism follows each other equally often. Driver and peer both use this.
    fn of(seq: u64) -> Mechanism {
        const ORDERS: [[usize; 3]; 6] = [
            [0, 1, 2],
            [1, 2, 0],
            [2, 0, 1],
            [0, 2, 1],
            [2, 1, 0],
            [1, 0, 2],
        ];
        let triple = (seq / 3) % 6;
        Mechanism::ALL[ORDERS[triple as usize][(seq % 3) as usize]]
    }
}

/// Driver side of the wake-up case. The three mechanisms take turns message by
/// message within one pair of processes, so that all three see the same state of the
/// (virtualised) machine; the receiver blocks without spinning first in every case,
/// as this measures the wake-up. Returns the latencies of [`Mechanism::ALL`], `run`
/// counting per mechanism.
pub fn wakeup(prefix: &str, run: Run) -> anyhow::Result<[Vec<u64>; 3]> {
    let (ping_r, ping_w_fd) = pipe()?;
    let (echo_r, echo_w) = pipe()?;
    let mut args = run.args();
    args.push(prefix_arg(prefix));
    let peer = Peer::spawn("wakeup", &args, vec![("ping", ping_w_fd), ("echo", echo_r)])?;
    let mut ping_r = File::from(ping_r);
    let mut echo_w = File::from(echo_w);
    driver_node(prefix, peer, |node, peer| {
        let ping = svc::pubsub::<ImuSample>(node, name::PING, LATENCY_BUFFER, Side::Create)?;
        let ping_l = svc::event(node, name::PING_EVENT, Side::Create)?;
        let pong_l = svc::event(node, name::PONG_EVENT, Side::Create)?;
        let ping_w = svc::event(node, name::PING_EVENT_WAITSET, Side::Create)?;
        let pong_w = svc::event(node, name::PONG_EVENT_WAITSET, Side::Create)?;
        let sub = svc::subscriber(&ping, LATENCY_BUFFER)?;
        let listener_l = svc::listener(&ping_l)?;
        let listener_w = svc::listener(&ping_w)?;
        let notifier_l = svc::notifier(&pong_l)?;
        let notifier_w = svc::notifier(&pong_w)?;
        let waitset = WaitSetBuilder::new()
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<ipc::Service>()
            .context("create waitset")?;
        let _guard = waitset
            .attach_notification(&listener_w)
            .context("attach listener")?;
        peer.wait_ready()?;
        wait_until("the peer's ports", STARTUP_TIMEOUT, || {
            ping.dynamic_config().number_of_publishers() == 1
                && ping_l.dynamic_config().number_of_notifiers() == 1
                && ping_w.dynamic_config().number_of_notifiers() == 1
                && pong_l.dynamic_config().number_of_listeners() == 1
                && pong_w.dynamic_config().number_of_listeners() == 1
        })?;
        sub.update_connections().context("connect the subscriber")?;
        peer.go()?;

        let mut out: [Vec<u64>; 3] = Default::default();
        {
            let wd = Watchdog::driver(peer);
            let take = |seq: u64| -> anyhow::Result<Option<u64>> {
                match sub.receive()? {
                    Some(s) => {
                        let now = now_ns();
                        ensure!(
                            s.header.seq == seq,
                            "wake-up: message {} arrived, expected {seq}",
                            s.header.seq
                        );
                        Ok(Some(since(s.header.stamp_ns, now)?))
                    }
                    None => Ok(None),
                }
            };
            for seq in 0..3 * (run.warmup + run.count) {
                let mechanism = Mechanism::of(seq);
                let latency = match mechanism {
                    Mechanism::Listener => loop {
                        block_listener(&listener_l, &wd)?;
                        if let Some(latency) = take(seq)? {
                            break latency;
                        }
                    },
                    Mechanism::WaitSet => loop {
                        block_waitset(&waitset, &listener_w, &wd)?;
                        if let Some(latency) = take(seq)? {
                            break latency;
                        }
                    },
                    Mechanism::Pipe => {
                        // No timeout: if the peer dies the pipe reports end-of-file, and
                        // the peer's dead-man timer bounds the case.
                        let mut stamp = [0u8; 8];
                        ping_r.read_exact(&mut stamp).context("pipe read")?;
                        let now = now_ns();
                        since(u64::from_ne_bytes(stamp), now)?
                    }
                };
                if seq >= 3 * run.warmup {
                    out[mechanism as usize].push(latency);
                }
                match mechanism {
                    Mechanism::Listener => {
                        notifier_l.notify()?;
                    }
                    Mechanism::WaitSet => {
                        notifier_w.notify()?;
                    }
                    Mechanism::Pipe => echo_w.write_all(&[1]).context("pipe echo")?,
                }
            }
        }
        Ok(out)
    })
}

/// Blocks in the WaitSet (at most [`WAIT_SLICE`] per wait) until the listener was
/// notified, then drains the listener.
fn block_waitset(
    waitset: &iceoryx2::waitset::WaitSet<ipc::Service>,
    listener: &Listener<ipc::Service>,
    wd: &Watchdog<'_>,
) -> anyhow::Result<()> {
    loop {
        let result = waitset
            .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, WAIT_SLICE)
            .context("waitset wait")?;
        if matches!(
            result,
            WaitSetRunResult::Interrupt | WaitSetRunResult::TerminationRequest
        ) {
            bail!("stopped by a signal");
        }
        let mut notified = false;
        listener
            .try_wait(|_| notified = true)
            .context("listener drain")?;
        if notified {
            return Ok(());
        }
        wd.check()?;
    }
}

pub(super) fn wakeup_peer(ctx: &mut PeerCtx) -> anyhow::Result<()> {
    let run = Run::from_ctx(ctx)?;
    let prefix = ctx.str("prefix")?.to_string();
    peer_node(&prefix, |node| {
        let ping = svc::pubsub::<ImuSample>(node, name::PING, LATENCY_BUFFER, Side::Open)?;
        let ping_l = svc::event(node, name::PING_EVENT, Side::Open)?;
        let pong_l = svc::event(node, name::PONG_EVENT, Side::Open)?;
        let ping_w = svc::event(node, name::PING_EVENT_WAITSET, Side::Open)?;
        let pong_w = svc::event(node, name::PONG_EVENT_WAITSET, Side::Open)?;
        let publisher = svc::publisher(&ping, Some(ctx.parent))?;
        let notifier_l = svc::notifier(&ping_l)?;
        let notifier_w = svc::notifier(&ping_w)?;
        let listener_l = svc::listener(&pong_l)?;
        let listener_w = svc::listener(&pong_w)?;
        let waitset = WaitSetBuilder::new()
            .create::<ipc::Service>()
            .context("create waitset")?;
        let _guard = waitset
            .attach_notification(&listener_w)
            .context("attach listener")?;
        let mut ping_w_fd = File::from(ctx.fd("ping")?);
        let mut echo_r = File::from(ctx.fd("echo")?);
        wait_until("the driver's ports", STARTUP_TIMEOUT, || {
            ping.dynamic_config().number_of_subscribers() == 1
                && ping_l.dynamic_config().number_of_listeners() == 1
                && ping_w.dynamic_config().number_of_listeners() == 1
        })?;
        ctx.ready_then_wait_go()?;
        let wd = Watchdog::peer(Some(node), ctx.parent);
        for seq in 0..3 * (run.warmup + run.count) {
            match Mechanism::of(seq) {
                Mechanism::Listener | Mechanism::WaitSet => {
                    let t0 = now_ns();
                    let delivered = publisher
                        .loan_uninit()?
                        .write_payload(svc::imu(seq, t0))
                        .send()?;
                    ensure!(delivered == 1, "wake-up: the driver's subscriber is gone");
                    if Mechanism::of(seq) == Mechanism::Listener {
                        ensure!(
                            notifier_l.notify()? == 1,
                            "wake-up: the driver's listener is gone"
                        );
                        block_listener(&listener_l, &wd)?;
                    } else {
                        ensure!(
                            notifier_w.notify()? == 1,
                            "wake-up: the driver's listener is gone"
                        );
                        block_waitset(&waitset, &listener_w, &wd)?;
                    }
                }
                Mechanism::Pipe => {
                    let t0 = now_ns();
                    ping_w_fd
                        .write_all(&t0.to_ne_bytes())
                        .context("pipe write")?;
                    let mut b = [0u8; 1];
                    echo_r.read_exact(&mut b).context("pipe echo read")?;
                }
            }
        }
        ctx.done()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mechanisms_take_equal_turns_and_follow_each_other_equally_often() {
        let mut count = [0usize; 3];
        let mut follows = [[0usize; 3]; 3];
        let n = 3 * 6 * 100;
        for seq in 0..n {
            let m = Mechanism::of(seq) as usize;
            count[m] += 1;
            if seq > 0 {
                follows[Mechanism::of(seq - 1) as usize][m] += 1;
            }
        }
        assert_eq!(count, [600, 600, 600]);
        for (a, row) in follows.iter().enumerate() {
            for (b, &k) in row.iter().enumerate() {
                if a != b {
                    assert!((250..=350).contains(&k), "{a} -> {b}: {k}");
                }
            }
        }
        // Each triple holds each mechanism once.
        for t in 0..100 {
            let mut seen = [false; 3];
            for k in 0..3 {
                seen[Mechanism::of(3 * t + k) as usize] = true;
            }
            assert_eq!(seen, [true; 3]);
        }
    }
}
