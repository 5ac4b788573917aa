//! A role's inputs: each a service of a checked type, received, checked
//! (finite, in range, stamps strictly increasing), counted, and queued into
//! the ordered merge; and the watermarks of their publishers
//! (`<publisher>/progress`) that let the merge release a message once no input
//! can still send anything earlier.

use std::collections::BTreeMap;

use nauta_messages::checked::ValidationError;
use nauta_messages::{Message, Progress, Role};

use crate::context::Context;
use crate::describe::PortDescription;
use crate::health::HealthReporter;
use crate::merge::OrderedMerge;
use crate::ports::{Connect, Inbox, Subscriber};
use crate::services::{self, ServiceSpec};

/// Opens a declared input in a process: the port and the inbox that wakes
/// on its messages.
type OpenInput<I> = Box<dyn Fn(&Context) -> anyhow::Result<(Box<dyn InputPort<I>>, Inbox)>>;

/// One declared input, not yet opened.
pub(super) struct InputDecl<I> {
    pub port: PortDescription,
    /// The role whose `progress` service qualifies this input.
    pub publisher: Role,
    /// Whether messages of this input can make the role publish (see
    /// [`super::Shell::aiding`]).
    pub triggers: bool,
    pub open: OpenInput<I>,
}

/// An opened input, its message type erased.
pub(super) trait InputPort<I> {
    fn connector(&self) -> &dyn Connect;
    /// Receives everything available: each message is checked and queued as
    /// input `index` of `merge`; what fails is counted in `health`.
    fn drain(
        &mut self,
        index: usize,
        merge: &mut OrderedMerge<I>,
        health: &mut HealthReporter,
    ) -> anyhow::Result<()>;
    /// Messages missing between sequence numbers.
    fn gaps(&self) -> u64;
    /// The first message received: its stamp and sequence number.
    fn first(&self) -> Option<(u64, u64)>;
}

struct TypedInput<M: Message, D, I> {
    sub: Subscriber<M>,
    last_stamp: Option<u64>,
    first: Option<(u64, u64)>,
    into: fn(D) -> I,
}

impl<M, D, I> InputPort<I> for TypedInput<M, D, I>
where
    M: Message,
    D: for<'a> TryFrom<&'a M, Error = ValidationError>,
{
    fn connector(&self) -> &dyn Connect {
        &self.sub
    }

    fn drain(
        &mut self,
        index: usize,
        merge: &mut OrderedMerge<I>,
        health: &mut HealthReporter,
    ) -> anyhow::Result<()> {
        let Self {
            sub,
            last_stamp,
            first,
            into,
        } = self;
        let service = sub.service().to_owned();
        sub.drain(|m| {
            let stamp_ns = m.header().stamp_ns;
            first.get_or_insert((stamp_ns, m.header().seq));
            // A repeated stamp is as wrong as one that goes backwards: one
            // input carries one message per instant.
            let checked = match *last_stamp {
                Some(previous_ns) if stamp_ns <= previous_ns => {
                    Err(ValidationError::StampBackwards {
                        stamp_ns,
                        previous_ns,
                    })
                }
                _ => D::try_from(&m),
            };
            match checked {
                Ok(d) => match merge.push(index, stamp_ns, into(d)) {
                    Ok(()) => {
                        *last_stamp = Some(stamp_ns);
                        health.inputs += 1;
                    }
                    // Earlier than its publisher's own watermark: the
                    // publisher broke its promise (or handed the history
                    // of this service over after a watermark; see
                    // `Outputs::publish_watermark` in the sensor); refused.
                    Err(e) => health.refuse(&service, "before-watermark", &e),
                },
                Err(e) => health.reject(&service, &e),
            }
        })?;
        Ok(())
    }

    fn gaps(&self) -> u64 {
        self.sub.gaps().missing
    }

    fn first(&self) -> Option<(u64, u64)> {
        self.first
    }
}

impl<I: 'static> InputDecl<I> {
    pub fn new<M, D>(spec: ServiceSpec<M>, publisher: Role, into: fn(D) -> I) -> Self
    where
        M: Message,
        D: for<'a> TryFrom<&'a M, Error = ValidationError> + 'static,
    {
        InputDecl {
            port: PortDescription::of(&spec),
            publisher,
            triggers: true,
            open: Box::new(move |ctx: &Context| {
                let (sub, inbox) = ctx.subscriber(&spec)?;
                let port: Box<dyn InputPort<I>> = Box::new(TypedInput {
                    sub,
                    last_stamp: None,
                    first: None,
                    into,
                });
                Ok((port, inbox))
            }),
        }
    }
}

/// The watermark service of one publisher role, and what it said last.
pub(super) struct Watermarks {
    pub publisher: Role,
    pub sub: Subscriber<Progress>,
    /// Inputs (merge indices) this publisher's watermark applies to.
    pub inputs: Vec<usize>,
}

impl Watermarks {
    /// One per distinct publisher of `decls`, in order of first appearance.
    pub fn open<I>(
        ctx: &Context,
        decls: &[&InputDecl<I>],
    ) -> anyhow::Result<(Vec<Watermarks>, Vec<Inbox>)> {
        let mut by_role: BTreeMap<u32, usize> = BTreeMap::new();
        let (mut out, mut inboxes) = (Vec::<Watermarks>::new(), Vec::new());
        for (i, d) in decls.iter().enumerate() {
            if let Some(&k) = by_role.get(&(d.publisher as u32)) {
                out[k].inputs.push(i);
                continue;
            }
            let (sub, inbox) = ctx.subscriber(&services::progress(d.publisher))?;
            by_role.insert(d.publisher as u32, out.len());
            out.push(Watermarks {
                publisher: d.publisher,
                sub,
                inputs: vec![i],
            });
            inboxes.push(inbox);
        }
        Ok((out, inboxes))
    }

    /// Drains the watermark service: the newest watermark and whether the
    /// publisher ended its stream. Call before draining the data inputs: a
    /// watermark seen here was published after every message it covers, which
    /// is therefore already queued on the data inputs.
    pub fn take(&mut self) -> anyhow::Result<(Option<u64>, bool)> {
        let (mut mark, mut ended) = (None, false);
        self.sub.drain(|p| {
            if p.header.is_end_of_stream() {
                ended = true;
            } else {
                let s = p.header.stamp_ns;
                mark = Some(mark.map_or(s, |m: u64| m.max(s)));
            }
        })?;
        Ok((mark, ended))
    }
}
