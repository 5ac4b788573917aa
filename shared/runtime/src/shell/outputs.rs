//! A role's outputs: each a service whose message is made from the
//! estimator's output (or not, when the output is not for it), published, or
//! held while the process is in standby; and its snapshot service.

use std::collections::VecDeque;

use nauta_messages::Message;

use crate::context::Context;
use crate::describe::PortDescription;
use crate::ports::Publisher;
use crate::services::ServiceSpec;

/// How much of its outputs a standby instance keeps for its activation, in
/// the run's clock: the launcher activates it at its predecessor's last
/// published stamp, which lies at most a few wake-ups behind (5 s is 500
/// estimates at 100 Hz).
const HELD_NS: u64 = 5_000_000_000;

/// Opens a declared port in a process.
type Open<P> = Box<dyn Fn(&Context) -> anyhow::Result<Box<P>>>;
/// Reads the warm-start snapshot handed over, with its stamp.
type WarmStart<S> = Box<dyn Fn(&Context) -> anyhow::Result<Option<(S, u64)>>>;

/// One declared output, not yet opened.
pub(super) struct OutputDecl<O> {
    pub port: PortDescription,
    pub open: Open<dyn OutputPort<O>>,
}

/// An opened output, its message type erased.
pub(super) trait OutputPort<O> {
    /// Publishes the message made from `o`, or keeps it when `hold`;
    /// returns the stamp published.
    fn offer(&mut self, o: &O, stamp_ns: u64, hold: bool) -> anyhow::Result<Option<u64>>;
    /// Publishes what was held with a stamp after `boundary_ns`; returns how
    /// many and the last stamp published.
    fn release(&mut self, boundary_ns: u64) -> anyhow::Result<(u64, Option<u64>)>;
    fn flush(&mut self);
    fn published(&self) -> u64;
    fn given_up(&self) -> u64;
}

struct TypedOutput<M: Message, O> {
    publisher: Publisher<M>,
    make: fn(&O) -> Option<M>,
    held: VecDeque<M>,
}

impl<M: Message, O> OutputPort<O> for TypedOutput<M, O> {
    fn offer(&mut self, o: &O, stamp_ns: u64, hold: bool) -> anyhow::Result<Option<u64>> {
        let Some(msg) = (self.make)(o) else {
            return Ok(None);
        };
        if hold {
            self.held.push_back(msg);
            while self
                .held
                .front()
                .is_some_and(|m| m.header().stamp_ns.saturating_add(HELD_NS) < stamp_ns)
            {
                self.held.pop_front();
            }
            return Ok(None);
        }
        self.publisher.publish(msg)?;
        Ok(Some(stamp_ns))
    }

    fn release(&mut self, boundary_ns: u64) -> anyhow::Result<(u64, Option<u64>)> {
        let (mut n, mut last) = (0, None);
        for m in self.held.drain(..) {
            let s = m.header().stamp_ns;
            if s > boundary_ns {
                self.publisher.publish(m)?;
                n += 1;
                last = Some(s);
            }
        }
        self.publisher.flush();
        Ok((n, last))
    }

    fn flush(&mut self) {
        self.publisher.flush();
    }

    fn published(&self) -> u64 {
        self.publisher.published()
    }

    fn given_up(&self) -> u64 {
        self.publisher.given_up()
    }
}

impl<O: 'static> OutputDecl<O> {
    pub fn new<M: Message>(spec: ServiceSpec<M>, make: fn(&O) -> Option<M>) -> Self {
        OutputDecl {
            port: PortDescription::of(&spec),
            open: Box::new(move |ctx: &Context| {
                let port: Box<dyn OutputPort<O>> = Box::new(TypedOutput {
                    publisher: ctx.publisher(&spec)?,
                    make,
                    held: VecDeque::new(),
                });
                Ok(port)
            }),
        }
    }
}

/// The role's snapshot service (`<role>/snapshot`), declared.
pub(super) struct SnapshotDecl<S> {
    pub port: PortDescription,
    pub open: Open<dyn SnapshotPort<S>>,
    /// The snapshot the launcher handed over (`--snapshot`), with its stamp.
    pub warm_start: WarmStart<S>,
}

/// An opened snapshot publisher.
pub(super) trait SnapshotPort<S> {
    fn publish(&mut self, state: &S, stamp_ns: u64) -> anyhow::Result<()>;
    /// Hands the latest snapshot to subscribers that joined since.
    fn flush(&mut self);
}

struct TypedSnapshot<M: Message, S> {
    publisher: Publisher<M>,
    to_wire: fn(&S, u64) -> M,
}

impl<M: Message, S> SnapshotPort<S> for TypedSnapshot<M, S> {
    fn publish(&mut self, state: &S, stamp_ns: u64) -> anyhow::Result<()> {
        self.publisher
            .publish_now((self.to_wire)(state, stamp_ns))
            .map_err(Into::into)
    }

    fn flush(&mut self) {
        self.publisher.flush();
    }
}

impl<S: 'static> SnapshotDecl<S> {
    pub fn new<M: Message>(
        spec: ServiceSpec<M>,
        to_wire: fn(&S, u64) -> M,
        from_wire: fn(&M) -> S,
    ) -> Self {
        SnapshotDecl {
            port: PortDescription::of(&spec),
            open: Box::new(move |ctx: &Context| {
                let port: Box<dyn SnapshotPort<S>> = Box::new(TypedSnapshot {
                    publisher: ctx.publisher(&spec)?,
                    to_wire,
                });
                Ok(port)
            }),
            warm_start: Box::new(move |ctx: &Context| {
                Ok(ctx
                    .warm_start::<M>()?
                    .map(|m| (from_wire(&m), m.header().stamp_ns)))
            }),
        }
    }
}
