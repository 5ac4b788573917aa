//! One recorded message as a checked domain value (DESIGN §4: a value that
//! fails its check is counted, never trusted): the payload decoded with the
//! channel's pinned type and converted by `nauta_messages::checked`, the only
//! place that turns wire arrays into domain values. Every offline tool (eval,
//! report, export, the smoother) reads a recording through this and
//! [`crate::streams`].

use nauta_messages::checked::{
    Ahrs, Attitude, BuoyRangeReading, Depth, Dvl, Fix, Gps, Imu, LblNav, LblReplyReading, Nav,
    Propeller, Truth,
};
use nauta_messages::{
    AhrsSample, AttitudeEstimate, BuoyRange, DepthSample, DvlSample, GpsFix, GpsFixV1, ImuSample,
    LblReply, LblSolution, Message, NavSolution, PositionFix, PropellerSample, TruthState, codec,
};

/// A checked value of one of the message types offline tools read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// `nauta.ImuSample.v1`.
    Imu(Imu),
    /// `nauta.DepthSample.v1`.
    Depth(Depth),
    /// `nauta.DvlSample.v1`.
    Dvl(Dvl),
    /// `nauta.GpsFix.v1`.
    Gps(Gps),
    /// `nauta.AhrsSample.v1`.
    Ahrs(Ahrs),
    /// `nauta.PropellerSample.v1`.
    Propeller(Propeller),
    /// `nauta.BuoyRange.v1` (`sensor/modem`).
    Buoy(BuoyRangeReading),
    /// `nauta.LblReply.v1` (`sensor/lbl`).
    LblReply(LblReplyReading),
    /// `nauta.TruthState.v1` (`sim/truth`).
    Truth(Truth),
    /// `nauta.AttitudeEstimate.v1`.
    Attitude(Attitude),
    /// `nauta.NavSolution.v1` (`ains/nav`, or a smoothed track).
    Nav(Nav),
    /// `nauta.PositionFix.v1` (`positioning/fix`).
    Fix(Fix),
    /// `nauta.LblSolution.v1` (`lbl/nav`, or a smoothed LBL track).
    Lbl(LblNav),
}

/// Why a message of a known type gave no value.
#[derive(Debug, Clone, PartialEq)]
pub enum Rejection {
    /// The payload is not an encoding of its type (a short or damaged
    /// payload): it has no stamp either.
    Undecodable(String),
    /// It decoded, but a field failed its check; its header is kept.
    Invalid {
        /// The message's stamp, ns.
        stamp_ns: u64,
        /// Its sequence number.
        seq: u64,
        /// Which check failed.
        reason: String,
    },
}

impl std::fmt::Display for Rejection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Rejection::Undecodable(e) => write!(f, "did not decode: {e}"),
            Rejection::Invalid { reason, .. } => write!(f, "failed its check: {reason}"),
        }
    }
}

/// A checked value with the sequence number of the message it came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Checked {
    /// The value.
    pub value: Value,
    /// The publisher's sequence number.
    pub seq: u64,
}

/// Decodes and checks `data` as a message of `type_name`; `None` for a type
/// offline tools do not read (health, progress, snapshots, ...).
pub fn decode(type_name: &str, data: &[u8]) -> Option<Result<Checked, Rejection>> {
    Some(match type_name {
        ImuSample::TYPE_NAME => check::<ImuSample, Imu>(data, Value::Imu),
        DepthSample::TYPE_NAME => check::<DepthSample, Depth>(data, Value::Depth),
        DvlSample::TYPE_NAME => check::<DvlSample, Dvl>(data, Value::Dvl),
        GpsFix::TYPE_NAME => check::<GpsFix, Gps>(data, Value::Gps),
        GpsFixV1::TYPE_NAME => check::<GpsFixV1, Gps>(data, Value::Gps),
        AhrsSample::TYPE_NAME => check::<AhrsSample, Ahrs>(data, Value::Ahrs),
        PropellerSample::TYPE_NAME => check::<PropellerSample, Propeller>(data, Value::Propeller),
        BuoyRange::TYPE_NAME => check::<BuoyRange, BuoyRangeReading>(data, Value::Buoy),
        LblReply::TYPE_NAME => check::<LblReply, LblReplyReading>(data, Value::LblReply),
        TruthState::TYPE_NAME => check::<TruthState, Truth>(data, Value::Truth),
        AttitudeEstimate::TYPE_NAME => check::<AttitudeEstimate, Attitude>(data, Value::Attitude),
        NavSolution::TYPE_NAME => check::<NavSolution, Nav>(data, Value::Nav),
        PositionFix::TYPE_NAME => check::<PositionFix, Fix>(data, Value::Fix),
        LblSolution::TYPE_NAME => check::<LblSolution, LblNav>(data, Value::Lbl),
        _ => return None,
    })
}

fn check<M, C>(data: &[u8], wrap: fn(C) -> Value) -> Result<Checked, Rejection>
where
    M: Message,
    C: for<'a> TryFrom<&'a M>,
    for<'a> <C as TryFrom<&'a M>>::Error: std::fmt::Display,
{
    let m: M = codec::decode(data).map_err(|e| Rejection::Undecodable(e.to_string()))?;
    let header = m.header();
    match C::try_from(&m) {
        Ok(c) => Ok(Checked {
            value: wrap(c),
            seq: header.seq,
        }),
        Err(e) => Err(Rejection::Invalid {
            stamp_ns: header.stamp_ns,
            seq: header.seq,
            reason: e.to_string(),
        }),
    }
}

impl Value {
    /// The value's stamp, ns.
    pub fn stamp_ns(&self) -> u64 {
        match self {
            Value::Imu(v) => v.stamp_ns,
            Value::Depth(v) => v.stamp_ns,
            Value::Dvl(v) => v.stamp_ns,
            Value::Gps(v) => v.stamp_ns,
            Value::Ahrs(v) => v.stamp_ns,
            Value::Propeller(v) => v.stamp_ns,
            Value::Buoy(v) => v.stamp_ns,
            Value::LblReply(v) => v.stamp_ns,
            Value::Truth(v) => v.stamp_ns,
            Value::Attitude(v) => v.stamp_ns,
            Value::Nav(v) => v.stamp_ns,
            Value::Fix(v) => v.stamp_ns,
            Value::Lbl(v) => v.stamp_ns,
        }
    }
}
