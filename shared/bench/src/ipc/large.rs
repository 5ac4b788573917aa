//! One-way latency of 64 KiB messages: iceoryx2 zero-copy against a
//! Unix-domain socket, with the same ping-pong pattern as [`super::latency`].

use super::latency::*;
use std::collections::HashSet;
use std::io::{ErrorKind, IoSlice, Read, Write};
use std::mem::MaybeUninit;
use std::os::unix::net::UnixStream;

use anyhow::{Context, bail, ensure};
use iceoryx2::port::update_connections::UpdateConnections as _;
use iceoryx2::prelude::PortFactory as _;

use super::common::{
    Peer, PeerCtx, SPIN_CHECK, STARTUP_TIMEOUT, WAIT_SLICE, Watchdog, driver_node, now_ns,
    peer_node, since, wait_until,
};
use super::services::{
    self as svc, LARGE_PAYLOAD, LATENCY_BUFFER, Large64k, LargeWire, LargeWireOwned, Side,
    WireBytes, bincode_config, checksum, large_pattern, name,
};

/// Driver side of the 64 KiB iceoryx2 case. The receiver checksums the whole
/// payload in place before it reads the clock.
pub fn large_iceoryx2(
    prefix: &str,
    run: Run,
    wait: Wait,
    touch: Touch,
) -> anyhow::Result<Vec<u64>> {
    let pattern_sum = checksum(&large_pattern());
    let mut args = run.args();
    args.push(prefix_arg(prefix));
    args.push(("wait", wait.as_arg().to_string()));
    args.push(("touch", touch.as_arg().to_string()));
    let peer = Peer::spawn("large-iceoryx2", &args, vec![])?;
    driver_node(prefix, peer, |node, peer| {
        let ping = svc::pubsub::<Large64k>(node, name::PING, LATENCY_BUFFER, Side::Create)?;
        let sub = svc::subscriber(&ping, LATENCY_BUFFER)?;

        let take = |seq: u64| -> anyhow::Result<Option<u64>> {
            match sub.receive()? {
                Some(s) => {
                    touch.check(&s.payload, seq, pattern_sum)?;
                    let now = now_ns();
                    Ok(Some(since(s.stamp_ns, now)?))
                }
                None => Ok(None),
            }
        };

        let result = match wait {
            Wait::Busy => {
                let pong = svc::pubsub::<u64>(node, name::PONG, LATENCY_BUFFER, Side::Create)?;
                let echo = svc::publisher(&pong, None)?;
                peer.wait_ready()?;
                wait_until("the peer's ports", STARTUP_TIMEOUT, || {
                    ping.dynamic_config().number_of_publishers() == 1
                        && pong.dynamic_config().number_of_subscribers() == 1
                })?;
                sub.update_connections().context("connect the subscriber")?;
                peer.go()?;
                let wd = Watchdog::driver(peer);
                receive_loop(
                    run,
                    |seq| spin(&wd, || take(seq)),
                    |seq| {
                        echo.send_copy(seq)?;
                        Ok(())
                    },
                )?
            }
            Wait::Blocking => {
                let ping_event = svc::event(node, name::PING_EVENT, Side::Create)?;
                let pong_event = svc::event(node, name::PONG_EVENT, Side::Create)?;
                let listener = svc::listener(&ping_event)?;
                let notifier = svc::notifier(&pong_event)?;
                peer.wait_ready()?;
                wait_until("the peer's ports", STARTUP_TIMEOUT, || {
                    ping.dynamic_config().number_of_publishers() == 1
                        && ping_event.dynamic_config().number_of_notifiers() == 1
                        && pong_event.dynamic_config().number_of_listeners() == 1
                })?;
                sub.update_connections().context("connect the subscriber")?;
                peer.go()?;
                let wd = Watchdog::driver(peer);
                receive_loop(
                    run,
                    |seq| loop {
                        block_listener(&listener, &wd)?;
                        if let Some(latency) = take(seq)? {
                            return Ok(latency);
                        }
                    },
                    |_| {
                        notifier.notify()?;
                        Ok(())
                    },
                )?
            }
        };
        Ok(result)
    })
}

/// Writes the 64 KiB message into a loaned, uninitialised sample: the pattern, the
/// sequence number over its first 8 bytes, then the stamp.
fn write_large(slot: &mut MaybeUninit<Large64k>, stamp_ns: u64, seq: u64, pattern: &[u8]) {
    assert_eq!(pattern.len(), LARGE_PAYLOAD);
    let p = slot.as_mut_ptr();
    // SAFETY: `p` points to writable memory the size of `Large64k`; raw field
    // pointers are taken without creating references to uninitialised data, and every
    // byte is written (`Large64k` is repr(C) u64 + [u8; N], so it has no padding).
    unsafe {
        let payload = (&raw mut (*p).payload).cast::<u8>();
        payload.copy_from_nonoverlapping(pattern.as_ptr(), LARGE_PAYLOAD);
        payload.copy_from_nonoverlapping(seq.to_le_bytes().as_ptr(), 8);
        (&raw mut (*p).stamp_ns).write(stamp_ns);
    }
}

/// Writes only the sequence number and the stamp into a sample whose payload an
/// earlier [`write_large`] initialised completely.
///
/// # Safety
///
/// Every byte of `*slot` must have been written before (by `write_large`).
unsafe fn write_large_header(slot: &mut MaybeUninit<Large64k>, stamp_ns: u64, seq: u64) {
    let p = slot.as_mut_ptr();
    // SAFETY: raw field pointers into the writable slot; no references are created.
    unsafe {
        let payload = (&raw mut (*p).payload).cast::<u8>();
        payload.copy_from_nonoverlapping(seq.to_le_bytes().as_ptr(), 8);
        (&raw mut (*p).stamp_ns).write(stamp_ns);
    }
}

pub(super) fn large_iceoryx2_peer(ctx: &mut PeerCtx) -> anyhow::Result<()> {
    let run = Run::from_ctx(ctx)?;
    let wait = Wait::from_arg(ctx.str("wait")?)?;
    let touch = Touch::from_arg(ctx.str("touch")?)?;
    let pattern = large_pattern();
    let prefix = ctx.str("prefix")?.to_string();
    peer_node(&prefix, |node| {
        let ping = svc::pubsub::<Large64k>(node, name::PING, LATENCY_BUFFER, Side::Open)?;
        let publisher = svc::publisher(&ping, Some(ctx.parent))?;
        // Samples (by address in the shared segment) whose payload was fully written.
        let mut written: HashSet<usize> = HashSet::new();
        let mut send = |seq: u64| -> anyhow::Result<()> {
            let t0 = now_ns();
            let mut sample = publisher.loan_uninit()?;
            let slot = sample.payload_mut();
            if touch == Touch::Full || written.insert(slot.as_ptr() as usize) {
                write_large(slot, t0, seq, &pattern);
            } else {
                // SAFETY: this sample's memory was fully written when it was first loaned
                // (the set holds its address) and the receiver only reads it.
                unsafe { write_large_header(slot, t0, seq) };
            }
            // SAFETY: every byte of the payload is initialised (just now or earlier).
            let sample = unsafe { sample.assume_init() };
            ensure!(
                sample.send()? == 1,
                "64 KiB: the driver's subscriber is gone"
            );
            Ok(())
        };
        match wait {
            Wait::Busy => {
                let pong = svc::pubsub::<u64>(node, name::PONG, LATENCY_BUFFER, Side::Open)?;
                let echo = svc::subscriber(&pong, LATENCY_BUFFER)?;
                wait_until("the driver's ports", STARTUP_TIMEOUT, || {
                    ping.dynamic_config().number_of_subscribers() == 1
                        && pong.dynamic_config().number_of_publishers() == 1
                })?;
                echo.update_connections()
                    .context("connect the subscriber")?;
                ctx.ready_then_wait_go()?;
                let wd = Watchdog::peer(Some(node), ctx.parent);
                send_loop(run, send, |seq| {
                    let got = spin(&wd, || Ok(echo.receive()?.map(|s| *s.payload())))?;
                    ensure!(got == seq, "64 KiB: echo {got}, expected {seq}");
                    Ok(())
                })?;
            }
            Wait::Blocking => {
                let ping_event = svc::event(node, name::PING_EVENT, Side::Open)?;
                let pong_event = svc::event(node, name::PONG_EVENT, Side::Open)?;
                let notifier = svc::notifier(&ping_event)?;
                let listener = svc::listener(&pong_event)?;
                wait_until("the driver's ports", STARTUP_TIMEOUT, || {
                    ping.dynamic_config().number_of_subscribers() == 1
                        && ping_event.dynamic_config().number_of_listeners() == 1
                })?;
                ctx.ready_then_wait_go()?;
                let wd = Watchdog::peer(Some(node), ctx.parent);
                send_loop(
                    run,
                    |seq| {
                        send(seq)?;
                        notifier.notify()?;
                        Ok(())
                    },
                    |_| block_listener(&listener, &wd),
                )?;
            }
        }
        ctx.done()
    })
}

/// Reads one length-prefixed frame (u32 little-endian length, then the body) from
/// a Unix stream. With ping-pong nothing follows a frame, so the buffer is empty
/// again once one was returned.
#[derive(Debug)]
struct FrameReader {
    buf: Vec<u8>,
    filled: usize,
}

impl FrameReader {
    fn new() -> Self {
        FrameReader {
            buf: vec![0u8; 4 + 16 + LARGE_PAYLOAD],
            filled: 0,
        }
    }

    fn read<'a>(
        &'a mut self,
        stream: &mut UnixStream,
        wait: Wait,
        wd: &Watchdog<'_>,
    ) -> anyhow::Result<&'a [u8]> {
        let mut idle = 0u32;
        loop {
            if self.filled >= 4 {
                let len = u32::from_le_bytes([self.buf[0], self.buf[1], self.buf[2], self.buf[3]])
                    as usize;
                if self.filled >= 4 + len {
                    ensure!(
                        self.filled == 4 + len,
                        "socket: unexpected bytes after a frame"
                    );
                    self.filled = 0;
                    return Ok(&self.buf[4..4 + len]);
                }
                if self.buf.len() < 4 + len {
                    self.buf.resize(4 + len, 0);
                }
            }
            match stream.read(&mut self.buf[self.filled..]) {
                Ok(0) => bail!("socket closed"),
                Ok(n) => self.filled += n,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                    idle += 1;
                    if wait == Wait::Blocking || idle == SPIN_CHECK {
                        idle = 0;
                        wd.check()?;
                    }
                }
                Err(e) => return Err(e).context("socket read"),
            }
        }
    }
}

/// Reads exactly one byte (the echo), spinning or blocking.
fn read_echo(stream: &mut UnixStream, wait: Wait, wd: &Watchdog<'_>) -> anyhow::Result<()> {
    let mut b = [0u8; 1];
    let mut idle = 0u32;
    loop {
        match stream.read(&mut b) {
            Ok(0) => bail!("socket closed"),
            Ok(_) => return Ok(()),
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                idle += 1;
                if wait == Wait::Blocking || idle == SPIN_CHECK {
                    idle = 0;
                    wd.check()?;
                }
            }
            Err(e) => return Err(e).context("socket read"),
        }
    }
}

/// Writes all of `bufs` with as few `writev` calls as the socket allows.
fn write_all_vectored(
    stream: &mut UnixStream,
    mut bufs: &mut [IoSlice<'_>],
    wd: &Watchdog<'_>,
) -> anyhow::Result<()> {
    let mut idle = 0u32;
    while !bufs.is_empty() {
        match stream.write_vectored(bufs) {
            Ok(0) => bail!("socket closed"),
            Ok(n) => IoSlice::advance_slices(&mut bufs, n),
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                idle += 1;
                if idle == SPIN_CHECK {
                    idle = 0;
                    wd.check()?;
                }
            }
            Err(e) => return Err(e).context("socket write"),
        }
    }
    Ok(())
}

fn configure_stream(stream: &UnixStream, wait: Wait) -> anyhow::Result<()> {
    match wait {
        Wait::Busy => stream.set_nonblocking(true)?,
        Wait::Blocking => {
            stream.set_nonblocking(false)?;
            stream.set_read_timeout(Some(WAIT_SLICE))?;
        }
    }
    Ok(())
}

/// Driver side of the 64 KiB Unix-socket case: read the frame, bincode-decode it
/// (a copy into an owned buffer), checksum the payload, read the clock.
pub fn large_uds(run: Run, wait: Wait, touch: Touch) -> anyhow::Result<Vec<u64>> {
    let pattern_sum = checksum(&large_pattern());
    let (mut here, there) = UnixStream::pair().context("socket pair")?;
    configure_stream(&here, wait)?;
    let mut args = run.args();
    args.push(("wait", wait.as_arg().to_string()));
    args.push(("touch", touch.as_arg().to_string()));
    let mut peer = Peer::spawn("large-uds", &args, vec![("data", there.into())])?;
    peer.wait_ready()?;
    peer.go()?;
    let latencies = {
        let wd = Watchdog::driver(&peer);
        let mut reader = FrameReader::new();
        let mut stream = here.try_clone()?;
        receive_loop(
            run,
            |seq| {
                let body = reader.read(&mut stream, wait, &wd)?;
                let (msg, used): (LargeWireOwned, usize) =
                    bincode::serde::decode_from_slice(body, bincode_config())
                        .context("decode 64 KiB message")?;
                ensure!(used == body.len(), "64 KiB: trailing bytes in a frame");
                touch.check(&msg.payload.0, seq, pattern_sum)?;
                let now = now_ns();
                since(msg.stamp_ns, now)
            },
            |_| here.write_all(&[1]).context("socket echo"),
        )?
    };
    peer.finish()?;
    Ok(latencies)
}

pub(super) fn large_uds_peer(ctx: &mut PeerCtx) -> anyhow::Result<()> {
    let run = Run::from_ctx(ctx)?;
    let wait = Wait::from_arg(ctx.str("wait")?)?;
    let touch = Touch::from_arg(ctx.str("touch")?)?;
    let pattern = large_pattern();
    let mut stream = UnixStream::from(ctx.fd("data")?);
    configure_stream(&stream, wait)?;
    let mut reader = stream.try_clone()?;
    // The sender's own copy of the message (what it would hold before encoding).
    let mut msg = pattern.clone();
    ctx.ready_then_wait_go()?;
    let wd = Watchdog::peer(None, ctx.parent);
    send_loop(
        run,
        |seq| {
            let t0 = now_ns();
            if touch == Touch::Full {
                msg.copy_from_slice(&pattern);
            }
            msg[..8].copy_from_slice(&seq.to_le_bytes());
            let body = bincode::serde::encode_to_vec(
                LargeWire {
                    stamp_ns: t0,
                    payload: WireBytes(&msg),
                },
                bincode_config(),
            )
            .context("encode 64 KiB message")?;
            let len = u32::try_from(body.len())?.to_le_bytes();
            write_all_vectored(
                &mut stream,
                &mut [IoSlice::new(&len), IoSlice::new(&body)],
                &wd,
            )
        },
        |_| read_echo(&mut reader, wait, &wd),
    )?;
    ctx.done()
}
