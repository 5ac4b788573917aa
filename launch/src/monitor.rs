//! The launcher's view of a run: a tap on every output service the processes
//! describe (through the message registry, as the logger will do), message counts
//! and rates, and the attitude error against the truth, for the summary line.

use std::any::Any;
use std::time::{Duration, Instant};

use nauta_estimation::AttitudeError;
use nauta_messages::checked::{Attitude, Truth};
use nauta_messages::registry::{MessageVisitor, visit_by_name};
use nauta_messages::*;
use nauta_runtime::ports::Inbox;
use nauta_runtime::{Connect, Context, OrderedMerge, Subscriber, services};

/// A type-erased subscriber.
pub trait Tap {
    /// Service name.
    fn service(&self) -> &str;
    /// Receives everything available, passing each message to `obs`.
    fn drain(&mut self, obs: &mut Observer) -> anyhow::Result<usize>;
    /// Messages received.
    fn count(&self) -> u64;
    /// Sequence gaps seen.
    fn gaps(&self) -> u64;
    /// First and last stamps seen, ns.
    fn span(&self) -> Option<(u64, u64)>;
    /// Wall time from receiving the first message to receiving the last.
    fn wall_span(&self) -> Option<Duration>;
    /// The latest message's stamp and bincode encoding, kept for snapshot
    /// services only (the launcher hands it to a restarted process).
    fn latest(&self) -> Option<&(u64, Vec<u8>)>;
    /// Attaches to the publishers present now; false while there is none.
    fn connect(&self) -> anyhow::Result<bool>;
}

struct TypedTap<M: Message> {
    sub: Subscriber<M>,
    span: Option<(u64, u64)>,
    received: Option<(Instant, Instant)>,
    keep_latest: bool,
    latest: Option<(u64, Vec<u8>)>,
}

impl<M: Message> Tap for TypedTap<M> {
    fn service(&self) -> &str {
        self.sub.service()
    }
    fn drain(&mut self, obs: &mut Observer) -> anyhow::Result<usize> {
        let mut n = 0;
        let now = Instant::now();
        while let Some(m) = self.sub.receive()? {
            self.received = Some(self.received.map_or((now, now), |(a, _)| (a, now)));
            let s = m.header().stamp_ns;
            self.span = Some(self.span.map_or((s, s), |(a, b)| (a.min(s), b.max(s))));
            if self.keep_latest {
                match nauta_messages::codec::encode(&m) {
                    Ok(bytes) => self.latest = Some((s, bytes)),
                    Err(e) => {
                        tracing::warn!(service = %self.sub.service(), error = %e, "snapshot not kept")
                    }
                }
            }
            obs.observe(self.sub.service(), &m);
            n += 1;
        }
        Ok(n)
    }
    fn count(&self) -> u64 {
        self.sub.received()
    }
    fn gaps(&self) -> u64 {
        self.sub.gaps().missing
    }
    fn span(&self) -> Option<(u64, u64)> {
        self.span
    }
    fn wall_span(&self) -> Option<Duration> {
        self.received.map(|(a, b)| b - a)
    }
    fn latest(&self) -> Option<&(u64, Vec<u8>)> {
        self.latest.as_ref()
    }
    fn connect(&self) -> anyhow::Result<bool> {
        Connect::connect(&self.sub)
    }
}

struct MakeTap<'a> {
    ctx: &'a Context,
    service: &'a str,
    out: Option<anyhow::Result<(Box<dyn Tap>, Inbox)>>,
}

impl MessageVisitor for MakeTap<'_> {
    fn visit<M: Message>(&mut self) {
        let made = services::by_name::<M>(self.service).and_then(|spec| {
            let (sub, inbox) = self.ctx.subscriber(&spec)?;
            Ok((
                Box::new(TypedTap {
                    sub,
                    span: None,
                    received: None,
                    keep_latest: self.service.ends_with("/snapshot"),
                    latest: None,
                }) as Box<dyn Tap>,
                inbox,
            ))
        });
        self.out = Some(made);
    }
}

/// Opens a tap on `service` carrying `type_name`.
pub fn tap(ctx: &Context, service: &str, type_name: &str) -> anyhow::Result<(Box<dyn Tap>, Inbox)> {
    let mut v = MakeTap {
        ctx,
        service,
        out: None,
    };
    if !visit_by_name(type_name, &mut v) {
        anyhow::bail!("service {service} has unknown type {type_name}");
    }
    v.out
        .unwrap_or_else(|| anyhow::bail!("no tap made for {service}"))
}

enum Item {
    Truth(Box<Truth>),
    Attitude(Box<Attitude>),
}

/// Attitude error against the truth, matched by stamp, and a digest of every
/// attitude output (equal digests: bit-identical outputs).
pub struct Observer {
    merge: OrderedMerge<Item>,
    last_truth: Option<Truth>,
    /// Estimates compared with a truth of the same stamp.
    pub compared: u64,
    sum_sq: [f64; 4],
    max_total: f64,
    digest: u64,
    health: std::collections::BTreeMap<String, (u64, u64)>,
    /// Per health service: the previous and the latest message, with the
    /// time each arrived (rates for `nauta status`).
    pub latest_health: std::collections::BTreeMap<String, HealthPair>,
    /// The progress services whose end of stream was seen.
    pub end_of_stream: std::collections::BTreeSet<String>,
}

/// A health message and when it arrived.
pub type TimedHealth = (Instant, Health);
/// The previous (if any) and the latest health message of a process.
pub type HealthPair = (Option<TimedHealth>, TimedHealth);

const TRUTH: usize = 0;
const ATTITUDE: usize = 1;

impl Default for Observer {
    fn default() -> Self {
        Observer {
            merge: OrderedMerge::new(2),
            last_truth: None,
            compared: 0,
            sum_sq: [0.0; 4],
            max_total: 0.0,
            digest: 0xcbf2_9ce4_8422_2325,
            health: Default::default(),
            latest_health: Default::default(),
            end_of_stream: Default::default(),
        }
    }
}

impl Observer {
    fn observe(&mut self, service: &str, msg: &dyn Any) {
        if let Some(t) = msg.downcast_ref::<TruthState>()
            && let Ok(t) = Truth::try_from(t)
        {
            let _ = self.merge.push(TRUTH, t.stamp_ns, Item::Truth(Box::new(t)));
        } else if let Some(a) = msg.downcast_ref::<AttitudeEstimate>() {
            if let Ok(bytes) = codec::encode(a) {
                for b in bytes {
                    // FNV-1a, 64 bit.
                    self.digest = (self.digest ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
                }
            }
            if let Ok(checked) = Attitude::try_from(a) {
                let _ = self.merge.push(
                    ATTITUDE,
                    checked.stamp_ns,
                    Item::Attitude(Box::new(checked)),
                );
            }
        } else if let Some(h) = msg.downcast_ref::<Health>() {
            self.health
                .insert(service.to_owned(), (h.dropped, h.rejected));
            let now = Instant::now();
            let prev = self.latest_health.remove(service).map(|(_, last)| last);
            self.latest_health
                .insert(service.to_owned(), (prev, (now, *h)));
        } else if let Some(p) = msg.downcast_ref::<Progress>()
            && p.header.is_end_of_stream()
        {
            self.end_of_stream.insert(service.to_owned());
            if service == progress_service(Role::Sensor.name()) {
                self.merge.end(TRUTH);
            } else if service == progress_service(Role::Attitude.name()) {
                self.merge.end(ATTITUDE);
            }
        }
        self.settle();
    }

    fn settle(&mut self) {
        while let Some((_, stamp, item)) = self.merge.pop() {
            match item {
                Item::Truth(t) => self.last_truth = Some(*t),
                Item::Attitude(a) => {
                    if let Some(t) = self.last_truth.as_ref().filter(|t| t.stamp_ns == stamp) {
                        let e = AttitudeError::between(&a.attitude, &t.attitude);
                        for (s, v) in self.sum_sq.iter_mut().zip([
                            e.roll_rad,
                            e.pitch_rad,
                            e.yaw_rad,
                            e.total_rad,
                        ]) {
                            *s += v * v;
                        }
                        self.max_total = self.max_total.max(e.total_rad);
                        self.compared += 1;
                    }
                }
            }
        }
    }

    /// RMS roll, pitch, yaw and total attitude error, degrees.
    pub fn rms_deg(&self) -> Option<[f64; 4]> {
        (self.compared > 0).then(|| {
            self.sum_sq
                .map(|s| (s / self.compared as f64).sqrt().to_degrees())
        })
    }

    /// Largest total attitude error, degrees.
    pub fn max_total_deg(&self) -> f64 {
        self.max_total.to_degrees()
    }

    /// Messages lost and rejected inside the processes, from their last health.
    pub fn process_losses(&self) -> (u64, u64) {
        self.health
            .values()
            .fold((0, 0), |(l, r), (dl, dr)| (l + dl, r + dr))
    }

    /// FNV-1a digest of every attitude estimate's encoding, in order.
    pub fn digest(&self) -> u64 {
        self.digest
    }
}
