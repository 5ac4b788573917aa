//! The common header every message starts with (DESIGN §4).

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};

/// The first 32 bytes of every message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
pub struct Header {
    /// Time of validity of the content, in the run's clock (DESIGN §7). A derived
    /// message keeps the stamp of the input it was computed from.
    pub stamp_ns: u64,
    /// Per-publisher sequence number: 0, 1, 2, ... so that a gap is visible.
    pub seq: u64,
    /// The producing role, a [`Role`] as `u32`.
    pub source: u32,
    /// How many times the launcher has started this role in this run; `seq`
    /// restarts at 0 with every instance.
    pub instance: u32,
    /// [`Flags`] bits.
    pub flags: u32,
    /// Zero; keeps the header at 32 bytes.
    pub reserved: u32,
}

const _: () = assert!(core::mem::size_of::<Header>() == 32);

impl Header {
    /// A header for `source`/`instance` with the valid flag set.
    pub fn new(stamp_ns: u64, seq: u64, source: Role, instance: u32) -> Self {
        Self {
            stamp_ns,
            seq,
            source: source as u32,
            instance,
            flags: Flags::VALID.0,
            reserved: 0,
        }
    }

    /// The flag bits.
    pub fn flags(&self) -> Flags {
        Flags(self.flags)
    }

    /// True when the publisher marked this as its last message.
    pub fn is_end_of_stream(&self) -> bool {
        self.flags().contains(Flags::END_OF_STREAM)
    }
}

/// Header flag bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Flags(pub u32);

impl Flags {
    /// The content is valid.
    pub const VALID: Flags = Flags(1);
    /// The content is valid but of reduced quality (e.g. aiding missing).
    pub const DEGRADED: Flags = Flags(1 << 1);
    /// The publisher will send nothing after this message.
    pub const END_OF_STREAM: Flags = Flags(1 << 2);
    /// Sent by an estimator that is initialising (not yet converged/aligned).
    pub const INITIALISING: Flags = Flags(1 << 3);

    /// True when every bit of `other` is set.
    pub fn contains(self, other: Flags) -> bool {
        self.0 & other.0 == other.0
    }
}

impl core::ops::BitOr for Flags {
    type Output = Flags;
    fn bitor(self, rhs: Flags) -> Flags {
        Flags(self.0 | rhs.0)
    }
}

/// The producing role of a message (`Header::source`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u32)]
pub enum Role {
    /// Unknown or not set.
    Unknown = 0,
    /// The sensor process (simulator, replay or import).
    Sensor = 1,
    /// The attitude estimator.
    Attitude = 2,
    /// The aided INS.
    Ains = 3,
    /// Buoy time-of-flight positioning.
    Positioning = 4,
    /// LBL navigation.
    Lbl = 5,
    /// The logger.
    Logger = 6,
    /// The launcher (`nauta`).
    Launcher = 7,
    /// The post-mission smoother.
    Smoother = 8,
    /// A recording being replayed.
    Replay = 9,
    /// Test and benchmark peers.
    Test = 100,
}

impl Role {
    /// Every role, in numeric order.
    pub const ALL: [Role; 11] = [
        Role::Unknown,
        Role::Sensor,
        Role::Attitude,
        Role::Ains,
        Role::Positioning,
        Role::Lbl,
        Role::Logger,
        Role::Launcher,
        Role::Smoother,
        Role::Replay,
        Role::Test,
    ];

    /// The role with this wire value, if any.
    pub fn from_u32(v: u32) -> Option<Role> {
        Role::ALL.into_iter().find(|r| *r as u32 == v)
    }

    /// The role's name as used in service names (`attitude/health`).
    pub fn name(self) -> &'static str {
        match self {
            Role::Unknown => "unknown",
            Role::Sensor => "sensor",
            Role::Attitude => "attitude",
            Role::Ains => "ains",
            Role::Positioning => "positioning",
            Role::Lbl => "lbl",
            Role::Logger => "logger",
            Role::Launcher => "launcher",
            Role::Smoother => "smoother",
            Role::Replay => "replay",
            Role::Test => "test",
        }
    }

    /// The role with this name, if any.
    pub fn from_name(name: &str) -> Option<Role> {
        Role::ALL.into_iter().find(|r| r.name() == name)
    }
}

/// Sequence-gap bookkeeping for one input, per (source, instance).
#[derive(Debug, Clone, Default)]
pub struct GapCounter {
    last: Vec<(u32, u32, u64)>,
    /// Messages missing between consecutive sequence numbers.
    pub missing: u64,
    /// Messages whose sequence number did not increase (duplicates, reordering).
    pub out_of_order: u64,
}

impl GapCounter {
    /// Records one received header.
    pub fn record(&mut self, source: u32, instance: u32, seq: u64) {
        match self
            .last
            .iter_mut()
            .find(|(s, i, _)| *s == source && *i == instance)
        {
            Some((_, _, last)) => {
                if seq > *last {
                    self.missing += seq - *last - 1;
                    *last = seq;
                } else {
                    self.out_of_order += 1;
                }
            }
            None => {
                // First message of this (source, instance): a late join or a
                // restart; messages before it were not ours to see.
                self.last.push((source, instance, seq));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_are_per_source_and_instance() {
        let mut g = GapCounter::default();
        for seq in 0..10 {
            g.record(1, 0, seq);
        }
        g.record(1, 0, 12); // 10, 11 missing
        g.record(1, 1, 0); // a restart: new instance, no gap
        g.record(1, 1, 1);
        g.record(2, 0, 5); // a late join: no gap
        g.record(1, 0, 12); // duplicate
        assert_eq!(g.missing, 2);
        assert_eq!(g.out_of_order, 1);
    }
}
