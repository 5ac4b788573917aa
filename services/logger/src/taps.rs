//! A type-erased subscriber that writes what it receives to the recording.

use nauta_log::LogWriter;
use nauta_log::writer::ChannelId;
use nauta_messages::registry::{MessageVisitor, visit_by_name};
use nauta_messages::{GapCounter, Message, TypeInfo, codec};
use nauta_runtime::ports::Inbox;
use nauta_runtime::{Connect, Context, Subscriber, services};

/// One recorded service.
pub trait RecordingTap {
    /// Service name without namespace.
    fn topic(&self) -> &str;
    /// Writes every message available now; returns how many.
    fn drain(&mut self, writer: &mut LogWriter, log_time_ns: u64) -> anyhow::Result<usize>;
    /// Attaches to the publishers present now.
    fn connect(&self) -> anyhow::Result<bool>;
    /// Messages received.
    fn received(&self) -> u64;
    /// Sequence gaps, per (source, instance).
    fn gaps(&self) -> &GapCounter;
    /// Latest stamp received, ns.
    fn last_stamp_ns(&self) -> u64;
}

struct Typed<M: Message> {
    sub: Subscriber<M>,
    channel: ChannelId,
    last_stamp_ns: u64,
    encode_failures: u64,
}

impl<M: Message> RecordingTap for Typed<M> {
    fn topic(&self) -> &str {
        self.sub.service()
    }

    fn drain(&mut self, writer: &mut LogWriter, log_time_ns: u64) -> anyhow::Result<usize> {
        let mut n = 0;
        while let Some(m) = self.sub.receive()? {
            self.last_stamp_ns = self.last_stamp_ns.max(m.header().stamp_ns);
            match codec::encode(&m) {
                Ok(bytes) => writer.write(self.channel, log_time_ns, &bytes)?,
                Err(e) => {
                    // Cannot happen for fixed-size plain data; counted, never fatal.
                    self.encode_failures += 1;
                    if self.encode_failures == 1 {
                        tracing::warn!(service = %self.sub.service(), error = %e, "message not recorded");
                    }
                }
            }
            n += 1;
        }
        Ok(n)
    }

    fn connect(&self) -> anyhow::Result<bool> {
        Connect::connect(&self.sub)
    }

    fn received(&self) -> u64 {
        self.sub.received()
    }

    fn gaps(&self) -> &GapCounter {
        self.sub.gaps()
    }

    fn last_stamp_ns(&self) -> u64 {
        self.last_stamp_ns
    }
}

struct Open<'a> {
    ctx: &'a Context,
    writer: &'a mut LogWriter,
    service: &'a str,
    out: Option<anyhow::Result<(Box<dyn RecordingTap>, Inbox)>>,
}

impl MessageVisitor for Open<'_> {
    fn visit<M: Message>(&mut self) {
        let made = services::by_name::<M>(self.service).and_then(|spec| {
            let channel = self.writer.channel(self.service, &TypeInfo::of::<M>())?;
            let (sub, inbox) = self.ctx.subscriber(&spec)?;
            Ok((
                Box::new(Typed {
                    sub,
                    channel,
                    last_stamp_ns: 0,
                    encode_failures: 0,
                }) as Box<dyn RecordingTap>,
                inbox,
            ))
        });
        self.out = Some(made);
    }
}

/// Subscribes to `service` (carrying `type_name`) and adds its channel.
pub fn open(
    ctx: &Context,
    writer: &mut LogWriter,
    service: &str,
    type_name: &str,
) -> anyhow::Result<(Box<dyn RecordingTap>, Inbox)> {
    let mut v = Open {
        ctx,
        writer,
        service,
        out: None,
    };
    if !visit_by_name(type_name, &mut v) {
        anyhow::bail!("service {service} has unknown type {type_name}");
    }
    v.out
        .unwrap_or_else(|| anyhow::bail!("no subscriber made for {service}"))
}
