//! Fuzz target: every message's checked conversion, as a consumer receives
//! one: bytes, bincode-decoded (`nauta_messages::codec`), then `TryFrom`
//! into its checked domain type (`nauta_messages::checked`).
//!
//! Input: one selector byte (which type), then the encoded message. Every
//! registered type is also decoded from the same bytes. Anything may be
//! rejected; nothing may panic.

use nauta_messages::checked::*;
use nauta_messages::*;

/// Decodes `M` and converts it into `C`.
fn checked<M, C>(bytes: &[u8])
where
    M: Message,
    for<'a> C: TryFrom<&'a M>,
{
    if let Ok(m) = codec::decode::<M>(bytes) {
        let _ = C::try_from(&m);
        // What decodes encodes again to the same bytes it was read from.
        let again = codec::encode(&m).expect("a decoded message encodes");
        let twice = codec::decode::<M>(&again)
            .ok()
            .and_then(|d| codec::encode(&d).ok());
        assert_eq!(twice.as_ref(), Some(&again), "{}", M::TYPE_NAME);
    }
}

/// Decodes the bytes as every registered type.
struct DecodeAll<'a>(&'a [u8]);

impl MessageVisitor for DecodeAll<'_> {
    fn visit<M: Message>(&mut self) {
        let _ = codec::decode::<M>(self.0);
    }
}

fn main() {
    afl::fuzz!(|data: &[u8]| {
        let Some((&which, bytes)) = data.split_first() else {
            return;
        };
        match which % 13 {
            0 => checked::<ImuSample, Imu>(bytes),
            1 => checked::<DepthSample, Depth>(bytes),
            2 => checked::<DvlSample, Dvl>(bytes),
            3 => checked::<GpsFix, Gps>(bytes),
            4 => checked::<AhrsSample, Ahrs>(bytes),
            5 => checked::<PropellerSample, Propeller>(bytes),
            6 => checked::<BuoyRange, BuoyRangeReading>(bytes),
            7 => checked::<LblReply, LblReplyReading>(bytes),
            8 => checked::<TruthState, Truth>(bytes),
            9 => checked::<AttitudeEstimate, Attitude>(bytes),
            10 => checked::<NavSolution, Nav>(bytes),
            11 => checked::<PositionFix, Fix>(bytes),
            _ => checked::<LblSolution, LblNav>(bytes),
        }
        registry::visit_all(&mut DecodeAll(bytes));
        for service in SensorMessage::SERVICES {
            let _ = SensorMessage::decode(service, "", bytes);
        }
        let _ = SensorMessage::decode(GPS_SERVICE, GpsFixV1::TYPE_NAME, bytes);
    });
}
