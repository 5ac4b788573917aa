//! The message contract: every registered message round-trips through the
//! recording encoding unchanged, and the checks reject bad values clearly.

use nauta_messages::checked::{self, StampOrder, ValidationError};
use nauta_messages::codec::{decode, encode};
use nauta_messages::registry::{MessageVisitor, visit_all};
use nauta_messages::*;
use proptest::prelude::*;

/// Fills every byte of a message from a seed, so that every field of every type
/// gets a distinct, arbitrary bit pattern (including NaN payloads and
/// infinities in float fields: the encoding must carry them unchanged).
fn arbitrary<M: Message>(seed: u64) -> M {
    let mut m = M::default();
    let size = core::mem::size_of::<M>();
    let mut x = seed | 1;
    // SAFETY: every registered message is #[repr(C)] plain data made of integers,
    // floats and arrays of them (the derive of ZeroCopySend checks the fields);
    // every bit pattern is a valid value of those types. Padding: none, the size
    // assertions equal the sum of the field sizes.
    let bytes = unsafe { core::slice::from_raw_parts_mut((&mut m as *mut M).cast::<u8>(), size) };
    for b in bytes.iter_mut() {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        *b = x as u8;
    }
    m
}

fn bits<M: Message>(m: &M) -> Vec<u8> {
    // SAFETY: as above, plain data without padding.
    unsafe { core::slice::from_raw_parts((m as *const M).cast::<u8>(), core::mem::size_of::<M>()) }
        .to_vec()
}

struct RoundTrip(u64);
impl MessageVisitor for RoundTrip {
    fn visit<M: Message>(&mut self) {
        let m: M = arbitrary(self.0);
        let bytes = encode(&m).expect("encodes");
        let back: M = decode(&bytes).expect("decodes");
        assert_eq!(
            bits(&back),
            bits(&m),
            "{} changed in the round trip",
            M::TYPE_NAME
        );
        // Fixed-width encoding: the size never depends on the values.
        let zero = encode(&M::default()).expect("encodes");
        assert_eq!(bytes.len(), zero.len(), "{}", M::TYPE_NAME);
        // Truncated and over-long inputs are errors, not panics.
        assert!(decode::<M>(&bytes[..bytes.len() - 1]).is_err());
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(decode::<M>(&longer).is_err());
    }
}

proptest! {
    #[test]
    fn every_message_round_trips_unchanged(seed in any::<u64>()) {
        visit_all(&mut RoundTrip(seed));
    }
}

struct NoPadding;
impl MessageVisitor for NoPadding {
    fn visit<M: Message>(&mut self) {
        let fields: usize = M::FIELDS.iter().map(|f| field_size(f.ty)).sum();
        assert_eq!(
            fields,
            core::mem::size_of::<M>(),
            "{} has padding or an unknown field type",
            M::TYPE_NAME
        );
    }
}

fn field_size(ty: &str) -> usize {
    let ty = ty.replace(' ', "");
    match ty.as_str() {
        "Header" => 32,
        "u64" | "f64" | "i64" => 8,
        "u32" | "i32" | "f32" => 4,
        "u8" => 1,
        t if t.starts_with('[') => {
            let inner = &t[1..t.len() - 1];
            let (elem, n) = inner.rsplit_once(';').expect("array type");
            field_size(elem) * n.parse::<usize>().expect("array length")
        }
        other => panic!("unknown field type {other}"),
    }
}

#[test]
fn messages_have_no_padding() {
    visit_all(&mut NoPadding);
}

fn imu() -> ImuSample {
    ImuSample {
        header: Header::new(10_000_000, 0, Role::Sensor, 0),
        gyro_rad_s: [0.01, -0.02, 0.1],
        accel_m_s2: [0.1, 0.0, -9.81],
        mag_ut: [20.0, 1.0, 40.0],
        interval_s: 0.01,
    }
}

#[test]
fn valid_imu_converts() {
    let d = checked::Imu::try_from(&imu()).expect("valid");
    assert_eq!(d.stamp_ns, 10_000_000);
    assert!((d.accel_m_s2.z() + 9.81).abs() < 1e-12);
}

#[test]
fn non_finite_values_are_rejected_with_the_field() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut m = imu();
        m.gyro_rad_s[1] = bad;
        let e = checked::Imu::try_from(&m).unwrap_err();
        assert!(
            matches!(
                e,
                ValidationError::NonFinite {
                    field: "gyro_rad_s",
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("ImuSample.gyro_rad_s"), "{e}");
        let mut d = DepthSample {
            header: Header::default(),
            depth_m: bad,
        };
        assert!(checked::Depth::try_from(&d).is_err());
        d.depth_m = 10.0;
        assert!(checked::Depth::try_from(&d).is_ok());
    }
}

#[test]
fn out_of_range_values_are_rejected() {
    let mut m = imu();
    m.accel_m_s2[2] = -1.0e4;
    let e = checked::Imu::try_from(&m).unwrap_err();
    assert_eq!(e.kind(), "out-of-range");
    assert!(e.to_string().contains("accel_m_s2"), "{e}");

    let d = DepthSample {
        header: Header::default(),
        depth_m: -50.0,
    };
    assert!(matches!(
        checked::Depth::try_from(&d),
        Err(ValidationError::OutOfRange {
            field: "depth_m",
            ..
        })
    ));
    // A little above the surface (waves, sensor offset) is fine.
    let d = DepthSample {
        header: Header::default(),
        depth_m: -0.5,
    };
    assert!(checked::Depth::try_from(&d).is_ok());

    let g = GpsFix {
        lat_rad: 2.0,
        ..Default::default()
    };
    assert!(checked::Gps::try_from(&g).is_err());
    let b = BuoyRange {
        time_of_flight_s: -0.1,
        sound_speed_m_s: 1500.0,
        ..Default::default()
    };
    assert!(checked::BuoyRangeReading::try_from(&b).is_err());
    let b = BuoyRange {
        time_of_flight_s: 1.0,
        sound_speed_m_s: 340.0,
        ..Default::default()
    };
    assert!(
        checked::BuoyRangeReading::try_from(&b).is_err(),
        "speed of sound in air"
    );
    let mut l = LblReply {
        interrogation_stamp_ns: 100,
        reply_stamp_ns: 50,
        round_trip_s: 1.0,
        ..Default::default()
    };
    assert_eq!(
        checked::LblReplyReading::try_from(&l).unwrap_err().kind(),
        "stamp-backwards"
    );
    l.reply_stamp_ns = 200;
    assert!(checked::LblReplyReading::try_from(&l).is_ok());
}

#[test]
fn quaternions_must_be_unit() {
    let mut a = AttitudeEstimate {
        quat_nb: [1.0, 0.0, 0.0, 0.0],
        ..Default::default()
    };
    assert!(checked::Attitude::try_from(&a).is_ok());
    a.quat_nb = [1.0005, 0.0, 0.0, 0.0]; // rounding: accepted and renormalised
    let q = checked::Attitude::try_from(&a).expect("near unit").attitude;
    assert!((q.as_nalgebra().into_inner().norm() - 1.0).abs() < 1e-15);
    a.quat_nb = [0.9, 0.1, 0.0, 0.0];
    let e = checked::Attitude::try_from(&a).unwrap_err();
    assert_eq!(e.kind(), "non-unit-quaternion");
    assert!(e.to_string().contains("norm"), "{e}");
    a.quat_nb = [0.0; 4];
    assert!(checked::Attitude::try_from(&a).is_err());
    a.quat_nb = [f64::NAN, 0.0, 0.0, 0.0];
    assert_eq!(
        checked::Attitude::try_from(&a).unwrap_err().kind(),
        "non-finite"
    );
}

#[test]
fn backwards_stamps_are_rejected() {
    let mut order = StampOrder::default();
    order.check(100).expect("first");
    order.check(100).expect("equal stamps are allowed");
    order.check(200).expect("forward");
    let e = order.check(150).unwrap_err();
    assert_eq!(
        e,
        ValidationError::StampBackwards {
            stamp_ns: 150,
            previous_ns: 200
        }
    );
    assert!(e.to_string().contains("backwards"), "{e}");
    // The rejected stamp does not move the reference.
    order.check(200).expect("still at 200");
}

#[test]
fn fixed_strings() {
    let s: [u8; 8] = to_fixed_str("attitude-mekf");
    assert_eq!(fixed_str(&s), "attitude");
    let s: [u8; 4] = to_fixed_str("aé"); // é is two bytes: fits
    assert_eq!(fixed_str(&s), "aé");
    let s: [u8; 2] = to_fixed_str("aé"); // would split é: truncated before it
    assert_eq!(fixed_str(&s), "a");
}
