//! Typed ports: a [`Publisher`] fills in the header's sequence, source and instance,
//! applies the run's back-pressure rules and wakes subscribers once per batch; a
//! [`Subscriber`] copies samples out and counts sequence gaps per (source,
//! instance), so a restart is not a gap (DESIGN §4).

use std::cell::Cell;
use std::rc::Rc;
use std::time::Duration;

use iceoryx2::config::Config;
use iceoryx2::port::SendError;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::service::port_factory::PortFactory as _;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;
use nauta_messages::{Flags, Message, Role};

use crate::Ipc;
use crate::namespace::cleanup_dead_nodes;

/// Default time a `sim`-mode publisher waits for a full subscriber before it gives
/// that delivery up (the subscriber is dead or stuck) and cleans up dead nodes.
pub const DEFAULT_BACKPRESSURE_DEADLINE: Duration = Duration::from_secs(2);

/// A typed publisher with its companion event notifier.
pub struct Publisher<M: Message> {
    pub(crate) service: PortFactory<Ipc, M, ()>,
    pub(crate) inner: iceoryx2::port::publisher::Publisher<Ipc, M, ()>,
    pub(crate) notifier: Notifier<Ipc>,
    pub(crate) name: String,
    pub(crate) role: Role,
    pub(crate) instance: u32,
    pub(crate) config: Config,
    pub(crate) seq: u64,
    pub(crate) pending: bool,
    /// Messages published since the last notification.
    pub(crate) unnotified: usize,
    /// Notify at the latest after this many: half a subscriber's queue.
    pub(crate) notify_every: usize,
    pub(crate) published: u64,
    pub(crate) given_up: u64,
    pub(crate) gave_up_flag: Rc<Cell<bool>>,
    /// Subscribers seen at the last `connect_late_joiners`.
    pub(crate) subscribers_seen: usize,
}

impl<M: Message> std::fmt::Debug for Publisher<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Publisher")
            .field("service", &self.name)
            .field("type", &M::TYPE_NAME)
            .field("seq", &self.seq)
            .finish()
    }
}

/// Publishing failed for a reason other than back-pressure.
#[derive(Debug, thiserror::Error)]
#[error("cannot publish on {service}: {source}")]
pub struct PublishError {
    /// Service name.
    pub service: String,
    /// iceoryx2's error.
    #[source]
    pub source: SendError,
}

impl<M: Message> Publisher<M> {
    /// Publishes `msg`. The caller sets `stamp_ns` and any flags beyond `VALID`;
    /// `seq`, `source` and `instance` are filled in here. Subscribers are woken on
    /// the next [`Publisher::flush`], so a batch costs one wake-up.
    ///
    /// In `sim` mode this blocks while a subscriber's queue is full, up to the
    /// back-pressure deadline; a delivery given up is counted (see
    /// [`Publisher::given_up`]) and dead nodes are cleaned up.
    pub fn publish(&mut self, mut msg: M) -> Result<(), PublishError> {
        let h = msg.header_mut();
        h.seq = self.seq;
        h.source = self.role as u32;
        h.instance = self.instance;
        h.flags |= Flags::VALID.0;
        h.reserved = 0;
        // A long batch wakes its subscribers before their queues can fill:
        // in `sim` a publisher blocked on a full queue would otherwise wait
        // for a subscriber that was never told to drain it, until the
        // deadline gives the delivery up. (Before this message is counted,
        // so that it stays pending for the batch's own flush.)
        if self.unnotified >= self.notify_every {
            self.flush();
        }
        self.seq += 1;
        self.published += 1;
        self.pending = true;
        self.unnotified += 1;
        match self.inner.send_copy(msg) {
            Ok(_) => Ok(()),
            Err(SendError::UnableToDeliver) => {
                self.given_up += 1;
                self.gave_up_flag.set(true);
                tracing::warn!(
                    service = %self.name,
                    "a subscriber did not drain within the back-pressure deadline; delivery given up, cleaning up dead nodes"
                );
                if let Err(e) = cleanup_dead_nodes(&self.config) {
                    tracing::warn!(error = %e, "dead-node cleanup failed");
                }
                Ok(())
            }
            Err(source) => Err(PublishError {
                service: self.name.clone(),
                source,
            }),
        }
    }

    /// Wakes the subscribers if anything was published since the last flush.
    /// With nothing to send, attaches the subscribers that joined since the
    /// last send and hands them the history (`connect_late_joiners`).
    pub fn flush(&mut self) {
        if self.pending {
            self.pending = false;
            self.unnotified = 0;
            self.notify();
        } else {
            self.connect_late_joiners();
        }
    }

    /// Attaches subscribers that joined since the last send and delivers the
    /// service's history to them, waking them when their number changed.
    ///
    /// iceoryx2 does this only inside a send (or an explicit
    /// `update_connections`): a publisher with nothing new to say would never
    /// give a restarted subscriber the history it warm-starts from. In the
    /// ains ↔ positioning cycle that was a deadlock: a killed positioning came
    /// back subscribed to an ains that was waiting for the positioning's
    /// watermark and so published nothing, neither `ains/nav` nor its own
    /// watermark (docs/design-notes.md, "Acoustic positioning").
    fn connect_late_joiners(&mut self) {
        use iceoryx2::port::update_connections::UpdateConnections;
        if let Err(e) = self.inner.update_connections() {
            tracing::debug!(service = %self.name, error = ?e, "connecting new subscribers failed");
        }
        let n = self.subscriber_count();
        if n != self.subscribers_seen {
            self.subscribers_seen = n;
            self.notify();
        }
    }

    fn notify(&self) {
        if let Err(e) = self.notifier.notify() {
            tracing::debug!(service = %self.name, error = ?e, "notify failed");
        }
    }

    /// Publishes and wakes subscribers at once (for single, rare messages).
    pub fn publish_now(&mut self, msg: M) -> Result<(), PublishError> {
        self.publish(msg)?;
        self.flush();
        Ok(())
    }

    /// Messages published so far.
    pub fn published(&self) -> u64 {
        self.published
    }

    /// Deliveries given up at the back-pressure deadline.
    pub fn given_up(&self) -> u64 {
        self.given_up
    }

    /// The next sequence number.
    pub fn next_seq(&self) -> u64 {
        self.seq
    }

    /// Service name without namespace.
    pub fn service(&self) -> &str {
        &self.name
    }

    /// Number of subscribers of the service now.
    pub fn subscriber_count(&self) -> usize {
        self.service.dynamic_config().number_of_subscribers()
    }
}

/// The wake-up side of an input: an event listener that a [`crate::EventLoop`]
/// waits on.
pub struct Inbox {
    pub(crate) listener: Listener<Ipc>,
    pub(crate) name: String,
}

impl std::fmt::Debug for Inbox {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Inbox")
            .field("service", &self.name)
            .finish()
    }
}

impl Inbox {
    /// Consumes every pending notification (never blocks).
    pub fn clear(&self) {
        let _ = self.listener.try_wait(|_| {});
    }

    /// Waits up to `timeout` for a notification and consumes every pending
    /// one; true if there was any. For a process that must wait on one input
    /// outside its [`crate::EventLoop`] (bounded: check for termination between
    /// calls).
    pub fn wait(&self, timeout: Duration) -> bool {
        let mut any = false;
        let _ = self.listener.timed_wait(|_| any = true, timeout);
        if any {
            self.clear();
        }
        any
    }
}

pub use nauta_messages::GapCounter;

/// A typed subscriber.
pub struct Subscriber<M: Message> {
    pub(crate) service: PortFactory<Ipc, M, ()>,
    pub(crate) inner: iceoryx2::port::subscriber::Subscriber<Ipc, M, ()>,
    pub(crate) name: String,
    pub(crate) received: u64,
    pub(crate) gaps: GapCounter,
}

impl<M: Message> std::fmt::Debug for Subscriber<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Subscriber")
            .field("service", &self.name)
            .field("type", &M::TYPE_NAME)
            .field("received", &self.received)
            .finish()
    }
}

impl<M: Message> Subscriber<M> {
    /// The next sample, copied out, or `None` when the queue is empty.
    pub fn receive(&mut self) -> anyhow::Result<Option<M>> {
        match self.inner.receive() {
            Ok(Some(sample)) => {
                let msg = *sample.payload();
                drop(sample);
                let h = msg.header();
                self.gaps.record(h.source, h.instance, h.seq);
                self.received += 1;
                Ok(Some(msg))
            }
            Ok(None) => Ok(None),
            Err(e) => anyhow::bail!("cannot receive on {}: {e}", self.name),
        }
    }

    /// Calls `f` for every sample available now; returns how many.
    pub fn drain(&mut self, mut f: impl FnMut(M)) -> anyhow::Result<usize> {
        let mut n = 0;
        while let Some(m) = self.receive()? {
            f(m);
            n += 1;
        }
        Ok(n)
    }

    /// Samples received so far.
    pub fn received(&self) -> u64 {
        self.received
    }

    /// Sequence-gap counts.
    pub fn gaps(&self) -> &GapCounter {
        &self.gaps
    }

    /// Service name without namespace.
    pub fn service(&self) -> &str {
        &self.name
    }

    /// Number of publishers of the service now.
    pub fn publisher_count(&self) -> usize {
        self.service.dynamic_config().number_of_publishers()
    }
}

/// An input that can attach itself to the publishers that exist now.
///
/// iceoryx2 links a subscriber to a publisher lazily: until the subscriber side
/// has attached (`update_connections`, done implicitly by `receive`), a sender
/// treats the link as unconnected and, once the queue is full, drops samples
/// for it without back-pressure. A consumer therefore connects every input to
/// its publishers before it reports ready, and a source publishes only after
/// every consumer is ready (DESIGN §5).
pub trait Connect {
    /// Service name.
    fn service(&self) -> &str;
    /// Attaches to every publisher present now; false while there is none.
    fn connect(&self) -> anyhow::Result<bool>;
}

impl<M: Message> Connect for Subscriber<M> {
    fn service(&self) -> &str {
        &self.name
    }

    fn connect(&self) -> anyhow::Result<bool> {
        use iceoryx2::port::update_connections::UpdateConnections;
        if self.publisher_count() == 0 {
            return Ok(false);
        }
        self.inner.update_connections().map_err(|e| {
            anyhow::anyhow!("cannot connect {} to its publishers: {e:?}", self.name)
        })?;
        Ok(true)
    }
}
