//! The services and messages of `nauta bench ipc`.
//!
//! Every service is defined here once and used by both processes: iceoryx2 treats
//! the QoS a creator set as requirements for everyone who opens the service, so
//! the driver creates and the peer opens with exactly the same settings
//! (DESIGN §6).

use std::fmt::Debug;
use std::time::{Duration, Instant};

use anyhow::Context;
use iceoryx2::node::Node;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::{BackpressureAction, BackpressureInfo};
use iceoryx2::prelude::{BackpressureStrategy, ServiceName, ZeroCopySend, ipc};
use iceoryx2::service::builder::event::EventOpenError;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use nauta_messages::{Header, ImuSample, Role};
use serde::{Deserialize, Serialize};

/// Bytes in the payload of [`Large64k`].
pub const LARGE_PAYLOAD: usize = 64 * 1024;

/// A 64 KiB message (plus its stamp) for the large-message latency case.
#[derive(Debug, ZeroCopySend)]
#[type_name("nauta.bench.Large64k.v1")]
#[repr(C)]
pub struct Large64k {
    /// Send time, CLOCK_MONOTONIC ns.
    pub stamp_ns: u64,
    /// Payload; bytes 0..8 hold the sequence number, the rest a fixed pattern.
    pub payload: [u8; LARGE_PAYLOAD],
}

const _: () = assert!(core::mem::size_of::<Large64k>() == 8 + LARGE_PAYLOAD);

/// Which process makes the service: the driver creates, the peer opens.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// Create the service (the driver, before it starts the peer).
    Create,
    /// Open the existing service (the peer).
    Open,
}

/// Service names; each case has its own namespace, so names repeat across cases.
pub mod name {
    /// Sender -> receiver (IMU or 64 KiB) in the latency cases.
    pub const PING: &str = "nauta/bench/ping";
    /// Receiver -> sender echo in the latency cases.
    pub const PONG: &str = "nauta/bench/pong";
    /// Event service the receiver waits on.
    pub const PING_EVENT: &str = "nauta/bench/ping_event";
    /// Event service the sender waits on for the echo.
    pub const PONG_EVENT: &str = "nauta/bench/pong_event";
    /// Like [`PING_EVENT`], for the receiver that waits in a WaitSet.
    pub const PING_EVENT_WAITSET: &str = "nauta/bench/ping_event_waitset";
    /// Like [`PONG_EVENT`], for the sender that waits in a WaitSet.
    pub const PONG_EVENT_WAITSET: &str = "nauta/bench/pong_event_waitset";
    /// The throughput stream.
    pub const STREAM: &str = "nauta/bench/stream";
}

/// Subscriber buffer of the ping-pong services: at most one sample is ever in flight.
pub const LATENCY_BUFFER: usize = 2;

/// Subscriber buffer of the throughput service. Measured on the 2-core machines:
/// 4 to 4096 give the same rate (within 3 %); 256 is a middle value.
pub const STREAM_BUFFER: usize = 256;

/// How long the peer waits for the driver to create a service.
pub const OPEN_TIMEOUT: Duration = Duration::from_secs(20);

/// A publisher blocked by back-pressure gives up after this long (DESIGN §6), so a
/// dead or stuck receiver cannot hang the benchmark.
pub const BACKPRESSURE_LIMIT: Duration = Duration::from_secs(10);

/// Opens or creates a publish-subscribe service with the benchmark's explicit QoS:
/// one publisher, one subscriber, two nodes, no history, no overflow (lossless,
/// back-pressure).
pub fn pubsub<T: Debug + ZeroCopySend>(
    node: &Node<ipc::Service>,
    name: &str,
    buffer: usize,
    side: Side,
) -> anyhow::Result<PubSubFactory<ipc::Service, T, ()>> {
    let service_name =
        ServiceName::new(name).map_err(|e| anyhow::anyhow!("service name {name:?}: {e:?}"))?;
    let builder = || {
        node.service_builder(&service_name)
            .publish_subscribe::<T>()
            .subscriber_max_buffer_size(buffer)
            .subscriber_max_borrowed_samples(1)
            .history_size(0)
            .max_publishers(1)
            .max_subscribers(1)
            .max_nodes(2)
            .enable_safe_overflow(false)
    };
    match side {
        Side::Create => builder()
            .create()
            .with_context(|| format!("create service {name}")),
        Side::Open => retry_open(name, || match builder().open() {
            Err(PublishSubscribeOpenError::DoesNotExist) => Ok(None),
            other => other.map(Some),
        }),
    }
}

/// Opens or creates an event service: one notifier, one listener, no
/// created/dropped/dead notifications, no deadline.
pub fn event(
    node: &Node<ipc::Service>,
    name: &str,
    side: Side,
) -> anyhow::Result<EventFactory<ipc::Service>> {
    let service_name =
        ServiceName::new(name).map_err(|e| anyhow::anyhow!("service name {name:?}: {e:?}"))?;
    let builder = || {
        node.service_builder(&service_name)
            .event()
            .max_notifiers(1)
            .max_listeners(1)
            .max_nodes(2)
            .event_id_max_value(1)
            .disable_notifier_created_event()
            .disable_notifier_dropped_event()
            .disable_notifier_dead_event()
            .disable_deadline()
    };
    match side {
        Side::Create => builder()
            .create()
            .with_context(|| format!("create event service {name}")),
        Side::Open => retry_open(name, || match builder().open() {
            Err(EventOpenError::DoesNotExist) => Ok(None),
            other => other.map(Some),
        }),
    }
}

/// The peer starts before the driver has created its services: opens, retrying
/// while the service does not exist yet, for at most [`OPEN_TIMEOUT`].
fn retry_open<F, E: std::error::Error + Send + Sync + 'static>(
    name: &str,
    mut open: impl FnMut() -> Result<Option<F>, E>,
) -> anyhow::Result<F> {
    let end = Instant::now() + OPEN_TIMEOUT;
    loop {
        if let Some(f) = open().with_context(|| format!("open service {name}"))? {
            return Ok(f);
        }
        anyhow::ensure!(
            Instant::now() < end,
            "open service {name}: it does not exist after {OPEN_TIMEOUT:?}"
        );
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// A publisher with back-pressure: it retries until the sample is delivered, for at
/// most [`BACKPRESSURE_LIMIT`], and (in the peer, `parent` set) gives up at once
/// when the driver has died.
pub fn publisher<T: Debug + ZeroCopySend>(
    service: &PubSubFactory<ipc::Service, T, ()>,
    parent: Option<u32>,
) -> anyhow::Result<Publisher<ipc::Service, T, ()>> {
    service
        .publisher_builder()
        .max_loaned_samples(1)
        .backpressure_strategy(BackpressureStrategy::RetryUntilDelivered)
        .set_backpressure_handler(move |info: &BackpressureInfo| {
            // SAFETY: getppid has no preconditions.
            let orphaned = parent.is_some_and(|p| unsafe { libc::getppid() } as u32 != p);
            if info.elapsed_time < BACKPRESSURE_LIMIT && !orphaned {
                BackpressureAction::Retry
            } else {
                BackpressureAction::DiscardDataAndFail
            }
        })
        .create()
        .context("create publisher")
}

/// A subscriber with the service's buffer size.
pub fn subscriber<T: Debug + ZeroCopySend>(
    service: &PubSubFactory<ipc::Service, T, ()>,
    buffer: usize,
) -> anyhow::Result<Subscriber<ipc::Service, T, ()>> {
    service
        .subscriber_builder()
        .buffer_size(buffer)
        .create()
        .context("create subscriber")
}

/// The listener of an event service.
pub fn listener(service: &EventFactory<ipc::Service>) -> anyhow::Result<Listener<ipc::Service>> {
    service
        .listener_builder()
        .create()
        .context("create listener")
}

/// The notifier of an event service.
pub fn notifier(service: &EventFactory<ipc::Service>) -> anyhow::Result<Notifier<ipc::Service>> {
    service
        .notifier_builder()
        .create()
        .context("create notifier")
}

/// The IMU sample sent in the IMU cases: a realistic, fully populated message.
pub fn imu(seq: u64, stamp_ns: u64) -> ImuSample {
    let x = seq as f64 * 1e-3;
    ImuSample {
        header: Header::new(stamp_ns, seq, Role::Test, 0),
        gyro_rad_s: [0.01 + x, -0.02, 0.003],
        accel_m_s2: [0.1, -0.2, -9.81 + x],
        mag_ut: [20.0, 1.5, 43.0],
        interval_s: 0.01,
    }
}

/// The fixed pattern of the 64 KiB payload (bytes 0..8 are overwritten by the sequence
/// number). Both transports copy this into their message, so both do the same work
/// to produce the payload.
pub fn large_pattern() -> Vec<u8> {
    let mut v: Vec<u8> = (0..LARGE_PAYLOAD)
        .map(|i| (i.wrapping_mul(31).wrapping_add(7)) as u8)
        .collect();
    v[..8].fill(0);
    v
}

/// Sum of the payload as little-endian u64 words (wrapping). Both receivers compute
/// it over the whole payload, so both actually read the 64 KiB they received.
pub fn checksum(bytes: &[u8]) -> u64 {
    bytes.chunks_exact(8).fold(0u64, |acc, c| {
        let mut w = [0u8; 8];
        w.copy_from_slice(c);
        acc.wrapping_add(u64::from_le_bytes(w))
    })
}

/// Reads the sequence number from bytes 0..8 of a payload.
pub fn payload_seq(bytes: &[u8]) -> u64 {
    let mut w = [0u8; 8];
    w.copy_from_slice(&bytes[..8]);
    u64::from_le_bytes(w)
}

/// Checks a received 64 KiB payload: right sequence number and right content.
pub fn verify_large(bytes: &[u8], seq: u64, pattern_sum: u64) -> anyhow::Result<()> {
    anyhow::ensure!(
        bytes.len() == LARGE_PAYLOAD,
        "64 KiB payload has {} bytes",
        bytes.len()
    );
    let got = payload_seq(bytes);
    anyhow::ensure!(got == seq, "64 KiB message {got} arrived, expected {seq}");
    let sum = checksum(bytes);
    anyhow::ensure!(
        sum == pattern_sum.wrapping_add(seq),
        "64 KiB message {seq} has a corrupt payload"
    );
    Ok(())
}

/// The bincode (serde) form of the 64 KiB message for the Unix socket, borrowed for
/// encoding.
///
/// serde implements `Serialize` for arrays only up to 32 elements, so
/// `[u8; 65536]` cannot go through `nauta_messages::codec` as it is. The payload is
/// therefore serialized as a byte string (`serialize_bytes`, what `serde_bytes`
/// does): bincode writes a u64 length and copies the bytes, which is the same work
/// bincode does for a fixed array of bytes (a copy) plus 8 bytes of length. Same
/// configuration as the codec: fixed-width integers, little endian.
#[derive(Debug, Serialize)]
pub struct LargeWire<'a> {
    /// Send time, CLOCK_MONOTONIC ns.
    pub stamp_ns: u64,
    /// The 64 KiB payload.
    pub payload: WireBytes<'a>,
}

/// The decoded (owned) form of [`LargeWire`].
#[derive(Debug, Deserialize)]
pub struct LargeWireOwned {
    /// Send time, CLOCK_MONOTONIC ns.
    pub stamp_ns: u64,
    /// The 64 KiB payload.
    pub payload: OwnedBytes,
}

/// Borrowed bytes serialized as a serde byte string.
#[derive(Debug)]
pub struct WireBytes<'a>(pub &'a [u8]);

impl Serialize for WireBytes<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(self.0)
    }
}

/// Owned bytes deserialized from a serde byte string.
#[derive(Debug)]
pub struct OwnedBytes(pub Vec<u8>);

impl<'de> Deserialize<'de> for OwnedBytes {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = OwnedBytes;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a byte string")
            }
            fn visit_byte_buf<E: serde::de::Error>(self, v: Vec<u8>) -> Result<OwnedBytes, E> {
                Ok(OwnedBytes(v))
            }
            fn visit_bytes<E: serde::de::Error>(self, v: &[u8]) -> Result<OwnedBytes, E> {
                Ok(OwnedBytes(v.to_vec()))
            }
        }
        d.deserialize_byte_buf(V)
    }
}

/// The bincode configuration of `nauta_messages::codec` (fixed-width integers,
/// little endian), repeated here for the hand-encoded 64 KiB message.
pub fn bincode_config() -> impl bincode::config::Config {
    bincode::config::standard()
        .with_fixed_int_encoding()
        .with_little_endian()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_message_round_trips_through_bincode() {
        let mut payload = large_pattern();
        payload[..8].copy_from_slice(&7u64.to_le_bytes());
        let bytes = bincode::serde::encode_to_vec(
            LargeWire {
                stamp_ns: 42,
                payload: WireBytes(&payload),
            },
            bincode_config(),
        )
        .unwrap();
        // stamp (8) + byte-string length (8) + payload: a copy, no per-byte encoding.
        assert_eq!(bytes.len(), 16 + LARGE_PAYLOAD);
        let (back, used): (LargeWireOwned, usize) =
            bincode::serde::decode_from_slice(&bytes, bincode_config()).unwrap();
        assert_eq!(used, bytes.len());
        assert_eq!(back.stamp_ns, 42);
        verify_large(&back.payload.0, 7, checksum(&large_pattern())).unwrap();
    }

    #[test]
    fn verify_large_catches_a_wrong_sequence_or_a_corrupt_byte() {
        let sum = checksum(&large_pattern());
        let mut payload = large_pattern();
        payload[..8].copy_from_slice(&3u64.to_le_bytes());
        verify_large(&payload, 3, sum).unwrap();
        assert!(verify_large(&payload, 4, sum).is_err());
        payload[1000] ^= 1;
        assert!(verify_large(&payload, 3, sum).is_err());
    }

    #[test]
    fn imu_sample_goes_through_the_project_codec() {
        let msg = imu(5, 123);
        let bytes = nauta_messages::codec::encode(&msg).unwrap();
        let back: ImuSample = nauta_messages::codec::decode(&bytes).unwrap();
        assert_eq!(back, msg);
    }
}
