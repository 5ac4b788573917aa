//! A recording as typed, checked streams: one [`Stream`] per channel of a
//! type [`crate::checked`] knows, its values in file order with the times the
//! logger saw, and each message it rejected with the reason. The one
//! reader offline tools use ([`visit`] message by message, for tools that
//! keep little, such as the map exports; [`Streams::read`] to hold them).

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Context as _;

use crate::checked::{self, Checked, Rejection, Value};
use crate::reader::{self, Channel, RecordedMessage, Recording};
use crate::run::{Resolver, RunInfo};
use nauta_messages::Message as _;
use nauta_messages::checked as checked_types;

/// A checked value with the times of its message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Logged<T> {
    /// The value.
    pub value: T,
    /// When the logger received it, ns since the Unix epoch.
    pub log_time_ns: u64,
    /// The publisher's sequence number.
    pub seq: u64,
}

/// A message of a known type that gave no value.
#[derive(Debug, Clone, PartialEq)]
pub struct Rejected {
    /// When the logger received it, ns since the Unix epoch.
    pub log_time_ns: u64,
    /// The MCAP publish time (the stamp the logger filed it under), ns.
    pub publish_time_ns: u64,
    /// Why.
    pub rejection: Rejection,
}

/// The checked values of one channel, in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct Stream<T> {
    /// Channel topic (`ains/nav`).
    pub topic: String,
    /// Values that passed their checks.
    pub samples: Vec<Logged<T>>,
    /// Messages that did not decode or failed their checks.
    pub rejected: Vec<Rejected>,
}

impl<T> Stream<T> {
    fn new(topic: &str) -> Self {
        Stream {
            topic: topic.to_owned(),
            samples: Vec::new(),
            rejected: Vec::new(),
        }
    }

    /// The values alone.
    pub fn values(&self) -> impl Iterator<Item = &T> {
        self.samples.iter().map(|s| &s.value)
    }
}

/// A stream of any of the known types (the variants of [`Value`]).
#[derive(Debug, Clone, PartialEq)]
pub enum AnyStream {
    /// `nauta.ImuSample.v1`.
    Imu(Stream<checked_types::Imu>),
    /// `nauta.DepthSample.v1`.
    Depth(Stream<checked_types::Depth>),
    /// `nauta.DvlSample.v1`.
    Dvl(Stream<checked_types::Dvl>),
    /// `nauta.GpsFix.v1`.
    Gps(Stream<checked_types::Gps>),
    /// `nauta.AhrsSample.v1`.
    Ahrs(Stream<checked_types::Ahrs>),
    /// `nauta.PropellerSample.v1`.
    Propeller(Stream<checked_types::Propeller>),
    /// `nauta.BuoyRange.v1`.
    Buoy(Stream<checked_types::BuoyRangeReading>),
    /// `nauta.LblReply.v1`.
    LblReply(Stream<checked_types::LblReplyReading>),
    /// `nauta.TruthState.v1`.
    Truth(Stream<checked_types::Truth>),
    /// `nauta.AttitudeEstimate.v1`.
    Attitude(Stream<checked_types::Attitude>),
    /// `nauta.NavSolution.v1`.
    Nav(Stream<checked_types::Nav>),
    /// `nauta.PositionFix.v1`.
    Fix(Stream<checked_types::Fix>),
    /// `nauta.LblSolution.v1`.
    Lbl(Stream<checked_types::LblNav>),
}

/// A checked type a stream can hold.
pub trait Kind: Sized {
    /// Its stream, if `s` is one of this type.
    fn of(s: &AnyStream) -> Option<&Stream<Self>>;
}

macro_rules! kinds {
    ($($variant:ident => $ty:ident, $wire:ident),* $(,)?) => {
        $(impl Kind for checked_types::$ty {
            fn of(s: &AnyStream) -> Option<&Stream<Self>> {
                match s {
                    AnyStream::$variant(s) => Some(s),
                    _ => None,
                }
            }
        })*

        impl AnyStream {
            /// An empty stream for a channel of `type_name`, if it is known.
            fn for_type(type_name: &str, topic: &str) -> Option<Self> {
                match type_name {
                    $(nauta_messages::$wire::TYPE_NAME => Some(AnyStream::$variant(Stream::new(topic))),)*
                    // Fixes of recordings made before v2: the same stream.
                    nauta_messages::GpsFixV1::TYPE_NAME => Some(AnyStream::Gps(Stream::new(topic))),
                    _ => None,
                }
            }

            /// Appends `v` if it is of this stream's type (else counts it as
            /// rejected: a channel's type is pinned).
            fn push(&mut self, v: Value, log_time_ns: u64, seq: u64) {
                match (self, v) {
                    $((AnyStream::$variant(s), Value::$variant(value)) => {
                        s.samples.push(Logged { value, log_time_ns, seq })
                    })*
                    (s, v) => s.reject(Rejected {
                        log_time_ns,
                        publish_time_ns: v.stamp_ns(),
                        rejection: Rejection::Undecodable("a value of another type".into()),
                    }),
                }
            }

            fn reject(&mut self, r: Rejected) {
                match self {
                    $(AnyStream::$variant(s) => s.rejected.push(r),)*
                }
            }

            /// The channel's topic.
            pub fn topic(&self) -> &str {
                match self {
                    $(AnyStream::$variant(s) => &s.topic,)*
                }
            }

            /// Values that passed their checks.
            pub fn len(&self) -> usize {
                match self {
                    $(AnyStream::$variant(s) => s.samples.len(),)*
                }
            }

            /// True when no value passed its checks.
            pub fn is_empty(&self) -> bool {
                self.len() == 0
            }

            /// Messages that did not decode or failed their checks.
            pub fn rejected(&self) -> &[Rejected] {
                match self {
                    $(AnyStream::$variant(s) => &s.rejected,)*
                }
            }
        }
    };
}

kinds! {
    Imu => Imu, ImuSample,
    Depth => Depth, DepthSample,
    Dvl => Dvl, DvlSample,
    Gps => Gps, GpsFix,
    Ahrs => Ahrs, AhrsSample,
    Propeller => Propeller, PropellerSample,
    Buoy => BuoyRangeReading, BuoyRange,
    LblReply => LblReplyReading, LblReply,
    Truth => Truth, TruthState,
    Attitude => Attitude, AttitudeEstimate,
    Nav => Nav, NavSolution,
    Fix => Fix, PositionFix,
    Lbl => LblNav, LblSolution,
}

/// One message of a recording as [`visit`] gives it.
#[derive(Debug, Clone, Copy)]
pub struct Message<'a> {
    /// Its channel.
    pub channel: &'a Channel,
    /// The recorded message (times and payload).
    pub recorded: &'a RecordedMessage<'a>,
    /// The checked value, or why there is none; `None` for a type offline
    /// tools do not read (or a channel not in nauta's encoding).
    pub checked: Option<&'a Result<Checked, Rejection>>,
}

/// Reads `path` message by message, each checked ([`checked::decode`]) when
/// `wanted(channel)` says so; `on_progress(bytes read, file bytes)`. Errors
/// as [`reader::read`] does, or with `on_message`'s error.
pub fn visit(
    path: &Path,
    on_progress: impl FnMut(u64, u64),
    wanted: impl Fn(&Channel) -> bool,
    mut on_message: impl FnMut(Message<'_>) -> anyhow::Result<()>,
) -> anyhow::Result<Recording> {
    reader::read_with_progress(path, on_progress, |ch, m| {
        let checked = (ch.message_encoding == crate::MESSAGE_ENCODING && wanted(ch))
            .then(|| checked::decode(&ch.type_name, m.data))
            .flatten();
        on_message(Message {
            channel: ch,
            recorded: m,
            checked: checked.as_ref(),
        })
    })
}

/// Which channels [`Streams::read`] keeps.
#[derive(Debug, Clone, Default)]
pub enum Select {
    /// Every channel of a known type.
    #[default]
    All,
    /// The channels of these type names.
    Types(Vec<&'static str>),
}

impl Select {
    fn wants(&self, ch: &Channel) -> bool {
        match self {
            Select::All => true,
            Select::Types(t) => t.contains(&ch.type_name.as_str()),
        }
    }
}

/// A recording read into typed, checked streams, with its run metadata.
#[derive(Debug, Clone, Default)]
pub struct Streams {
    /// Streams by topic.
    pub by_topic: BTreeMap<String, AnyStream>,
    /// Earliest publish time of any message in the file, ns (0 when empty).
    pub first_stamp_ns: u64,
    /// The run's frame, site and acoustics from the `nauta.run` metadata.
    pub run: RunInfo,
    /// The file's channels, metadata and recovery (cut or damaged files).
    pub recording: Recording,
}

impl Streams {
    /// Reads the channels `select` names from `path`; `presets` knows the
    /// simulator's scenarios (see [`RunInfo::read`]).
    pub fn read(
        path: &Path,
        select: &Select,
        presets: Option<Resolver>,
        on_progress: impl FnMut(u64, u64),
    ) -> anyhow::Result<Self> {
        let mut by_topic: BTreeMap<String, AnyStream> = BTreeMap::new();
        let mut first = u64::MAX;
        let recording = visit(
            path,
            on_progress,
            |ch| select.wants(ch),
            |m| {
                first = first.min(m.recorded.publish_time_ns);
                if let Some(checked) = m.checked {
                    Self::take(&mut by_topic, m.channel, checked, m.recorded);
                }
                Ok(())
            },
        )
        .with_context(|| format!("cannot read the recording {}", path.display()))?;
        let run = RunInfo::read(
            recording.metadata(crate::META_RUN),
            &Default::default(),
            presets,
        );
        Ok(Streams {
            by_topic,
            first_stamp_ns: if first == u64::MAX { 0 } else { first },
            run,
            recording,
        })
    }

    fn take(
        by_topic: &mut BTreeMap<String, AnyStream>,
        ch: &Channel,
        checked: &Result<Checked, Rejection>,
        m: &RecordedMessage<'_>,
    ) {
        if !by_topic.contains_key(&ch.topic) {
            let Some(s) = AnyStream::for_type(&ch.type_name, &ch.topic) else {
                return;
            };
            by_topic.insert(ch.topic.clone(), s);
        }
        let Some(s) = by_topic.get_mut(&ch.topic) else {
            return;
        };
        match checked {
            Ok(c) => s.push(c.value, m.log_time_ns, c.seq),
            Err(rejection) => s.reject(Rejected {
                log_time_ns: m.log_time_ns,
                publish_time_ns: m.publish_time_ns,
                rejection: rejection.clone(),
            }),
        }
    }

    /// The stream of `topic`, if it is of type `T`.
    pub fn get<T: Kind>(&self, topic: &str) -> Option<&Stream<T>> {
        self.by_topic.get(topic).and_then(T::of)
    }

    /// Every stream of type `T`, by topic.
    pub fn of_type<'a, T: Kind + 'a>(&'a self) -> impl Iterator<Item = &'a Stream<T>> {
        self.by_topic.values().filter_map(T::of)
    }
}
