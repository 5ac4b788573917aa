//! Lossless throughput of IMU messages from the peer to the driver: iceoryx2 with
//! back-pressure against a Unix stream socket carrying bincode frames.
//!
//! The driver starts its clock just before it tells the peer to go and stops it
//! when the last message is in hand; every message is checked for its sequence
//! number, so a loss or reordering fails the case.

use std::hint::black_box;
use std::io::{BufReader, BufWriter, Read, Write};
use std::os::unix::net::UnixStream;
use std::time::{Duration, Instant};

use anyhow::{Context, ensure};
use iceoryx2::port::update_connections::UpdateConnections as _;
use iceoryx2::prelude::PortFactory as _;
use nauta_messages::{ImuSample, codec};

use super::common::{
    Peer, PeerCtx, SPIN_CHECK, STARTUP_TIMEOUT, Watchdog, driver_node, peer_node, wait_until,
};
use super::services::{self as svc, STREAM_BUFFER, Side, name};

/// Buffer of the socket's user-space reader and writer.
const SOCKET_BUFFER: usize = 64 * 1024;

/// A read that takes longer than this means the sender is stuck.
const READ_TIMEOUT: Duration = Duration::from_secs(10);

/// The stamp of message `seq` (a 100 Hz IMU); both transports send identical messages.
fn stream_sample(seq: u64) -> ImuSample {
    svc::imu(seq, seq * 10_000_000)
}

/// iceoryx2: the driver's subscriber busy-polls `receive()` and copies each sample
/// out; the peer's publisher blocks (retries) when the subscriber's buffer is full.
/// Returns messages per second.
pub fn iceoryx2(prefix: &str, messages: u64) -> anyhow::Result<f64> {
    let peer = Peer::spawn(
        "tput-iceoryx2",
        &[
            ("prefix", prefix.to_string()),
            ("count", messages.to_string()),
        ],
        vec![],
    )?;
    driver_node(prefix, peer, |node, peer| {
        let stream = svc::pubsub::<ImuSample>(node, name::STREAM, STREAM_BUFFER, Side::Create)?;
        let sub = svc::subscriber(&stream, STREAM_BUFFER)?;
        peer.wait_ready()?;
        wait_until("the peer's publisher", STARTUP_TIMEOUT, || {
            stream.dynamic_config().number_of_publishers() == 1
        })?;
        // Connect to the publisher now: a publisher whose buffer is full and whose
        // subscriber has not connected yet drops the sample instead of blocking.
        sub.update_connections().context("connect the subscriber")?;
        // The clock starts before the go message: its delivery is charged.
        let start = Instant::now();
        peer.go()?;
        let elapsed = {
            let wd = Watchdog::driver(peer);
            let mut next = 0u64;
            let mut idle = 0u32;
            while next < messages {
                match sub.receive()? {
                    Some(sample) => {
                        let msg: ImuSample = *sample.payload();
                        ensure!(
                            msg.header.seq == next,
                            "iceoryx2 stream: message {} arrived, expected {next}",
                            msg.header.seq
                        );
                        black_box(msg);
                        next += 1;
                    }
                    None => {
                        idle += 1;
                        if idle == SPIN_CHECK {
                            idle = 0;
                            wd.check()?;
                        }
                    }
                }
            }
            start.elapsed()
        };
        Ok(messages as f64 / elapsed.as_secs_f64())
    })
}

fn iceoryx2_peer(ctx: &mut PeerCtx) -> anyhow::Result<()> {
    let messages = ctx.num("count")?;
    let prefix = ctx.str("prefix")?.to_string();
    peer_node(&prefix, |node| {
        let stream = svc::pubsub::<ImuSample>(node, name::STREAM, STREAM_BUFFER, Side::Open)?;
        let publisher = svc::publisher(&stream, Some(ctx.parent))?;
        wait_until("the driver's subscriber", STARTUP_TIMEOUT, || {
            stream.dynamic_config().number_of_subscribers() == 1
        })?;
        ctx.ready_then_wait_go()?;
        let wd = Watchdog::peer(Some(node), ctx.parent);
        for seq in 0..messages {
            if seq % u64::from(SPIN_CHECK) == 0 {
                wd.check()?;
            }
            let delivered = publisher
                .loan_uninit()?
                .write_payload(stream_sample(seq))
                .send()?;
            ensure!(
                delivered == 1,
                "iceoryx2 stream: message {seq} delivered to {delivered} subscribers"
            );
        }
        ctx.done()
    })
}

/// How the socket's sender writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Writes {
    /// Through a 64 KiB `BufWriter`: one `write` per ~560 frames.
    Buffered,
    /// One `write` per frame.
    PerMessage,
}

/// Unix stream socket: every message is encoded with `nauta_messages::codec::encode`
/// and written as a length-prefixed frame (through a 64 KiB `BufWriter` or one
/// `write` per frame); the driver reads through a 64 KiB `BufReader` and decodes
/// every frame with `codec::decode`. Returns messages per second.
pub fn uds(messages: u64, writes: Writes) -> anyhow::Result<f64> {
    let (here, there) = UnixStream::pair().context("socket pair")?;
    here.set_read_timeout(Some(READ_TIMEOUT))?;
    let buffered = match writes {
        Writes::Buffered => "1",
        Writes::PerMessage => "0",
    };
    let mut peer = Peer::spawn(
        "tput-uds",
        &[
            ("count", messages.to_string()),
            ("buffered", buffered.to_string()),
        ],
        vec![("data", there.into())],
    )?;
    peer.wait_ready()?;
    let mut reader = BufReader::with_capacity(SOCKET_BUFFER, here);
    let mut body = vec![0u8; 1024];
    let start = Instant::now();
    peer.go()?;
    for next in 0..messages {
        let mut len = [0u8; 4];
        reader.read_exact(&mut len).context("socket read")?;
        let len = u32::from_le_bytes(len) as usize;
        ensure!(len <= body.len(), "socket: frame of {len} bytes");
        reader.read_exact(&mut body[..len]).context("socket read")?;
        let msg: ImuSample = codec::decode(&body[..len])?;
        ensure!(
            msg.header.seq == next,
            "socket stream: message {} arrived, expected {next}",
            msg.header.seq
        );
        black_box(msg);
    }
    let elapsed = start.elapsed();
    peer.finish()?;
    Ok(messages as f64 / elapsed.as_secs_f64())
}

fn uds_peer(ctx: &mut PeerCtx) -> anyhow::Result<()> {
    let messages = ctx.num("count")?;
    let buffered = ctx.num("buffered")? != 0;
    let mut stream = UnixStream::from(ctx.fd("data")?);
    ctx.ready_then_wait_go()?;
    if buffered {
        let mut writer = BufWriter::with_capacity(SOCKET_BUFFER, stream);
        for seq in 0..messages {
            let bytes = codec::encode(&stream_sample(seq))?;
            writer.write_all(&u32::try_from(bytes.len())?.to_le_bytes())?;
            writer.write_all(&bytes)?;
        }
        writer.flush()?;
    } else {
        let mut frame = Vec::with_capacity(256);
        for seq in 0..messages {
            let bytes = codec::encode(&stream_sample(seq))?;
            frame.clear();
            frame.extend_from_slice(&u32::try_from(bytes.len())?.to_le_bytes());
            frame.extend_from_slice(&bytes);
            stream.write_all(&frame)?;
        }
    }
    ctx.done()
}

/// Runs the peer side of a throughput case; `Ok(false)` if `case` is not one.
pub fn peer(ctx: &mut PeerCtx) -> anyhow::Result<bool> {
    match ctx.case.as_str() {
        "tput-iceoryx2" => iceoryx2_peer(ctx)?,
        "tput-uds" => uds_peer(ctx)?,
        _ => return Ok(false),
    }
    Ok(true)
}
