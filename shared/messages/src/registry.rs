//! The registry of known message types, used by the logger to subscribe to every
//! service it discovers and to write self-describing schemas (DESIGN §6, §8).

use core::fmt::Debug;

use iceoryx2::prelude::ZeroCopySend;
use serde::{Serialize, de::DeserializeOwned};

use crate::Header;

/// One field of a message, for the recording's schema.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldInfo {
    /// Field name, with its unit (`depth_m`).
    pub name: &'static str,
    /// Rust type as written (`[f64; 3]`).
    pub ty: &'static str,
    /// Documentation of the field.
    pub doc: &'static str,
}

/// What every wire message provides.
pub trait Message:
    ZeroCopySend + Copy + Debug + Default + PartialEq + Serialize + DeserializeOwned + 'static
{
    /// Pinned, versioned type name (`nauta.ImuSample.v1`), also iceoryx2's type name.
    const TYPE_NAME: &'static str;
    /// Fields in declaration order.
    const FIELDS: &'static [FieldInfo];
    /// The common header.
    fn header(&self) -> &Header;
    /// The common header, mutable.
    fn header_mut(&mut self) -> &mut Header;
}

/// Static description of a registered type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TypeInfo {
    /// Pinned type name.
    pub type_name: &'static str,
    /// `size_of` on the wire (shared memory), bytes.
    pub size: usize,
    /// Fields in declaration order.
    pub fields: &'static [FieldInfo],
}

impl TypeInfo {
    /// The description of `M`.
    pub fn of<M: Message>() -> Self {
        TypeInfo {
            type_name: M::TYPE_NAME,
            size: core::mem::size_of::<M>(),
            fields: M::FIELDS,
        }
    }
}

/// Something generic over message types, called with each registered type.
pub trait MessageVisitor {
    /// Called with the concrete type `M`.
    fn visit<M: Message>(&mut self);
}

macro_rules! registry {
    ($($ty:ty),* $(,)?) => {
        /// Calls `visitor.visit::<M>()` for every registered type.
        pub fn visit_all<V: MessageVisitor>(visitor: &mut V) {
            $( visitor.visit::<$ty>(); )*
        }

        /// Calls `visitor.visit::<M>()` for the type named `type_name`; false when
        /// the name is not registered.
        pub fn visit_by_name<V: MessageVisitor>(type_name: &str, visitor: &mut V) -> bool {
            $(
                if type_name == <$ty as Message>::TYPE_NAME {
                    visitor.visit::<$ty>();
                    return true;
                }
            )*
            false
        }
    };
}

use crate::*;

registry!(
    ImuSample,
    DvlSample,
    DepthSample,
    GpsFix,
    GpsFixV1,
    AhrsSample,
    PropellerSample,
    BuoyRange,
    LblReply,
    LblInterrogation,
    TruthState,
    AttitudeEstimate,
    NavSolution,
    PositionFix,
    LblSolution,
    AttitudeSnapshot,
    AinsSnapshot,
    PositioningSnapshot,
    LblSnapshot,
    Health,
    Progress,
    RunEvent,
    ControlRequest,
    ControlResponse,
    PipelineRequest,
    PipelineResponse,
);

/// Descriptions of every registered type.
pub fn all_types() -> Vec<TypeInfo> {
    struct Collect(Vec<TypeInfo>);
    impl MessageVisitor for Collect {
        fn visit<M: Message>(&mut self) {
            self.0.push(TypeInfo::of::<M>());
        }
    }
    let mut c = Collect(Vec::new());
    visit_all(&mut c);
    c.0
}

/// The description of the type named `type_name`, if registered.
pub fn type_info(type_name: &str) -> Option<TypeInfo> {
    all_types().into_iter().find(|t| t.type_name == type_name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_versioned_and_match_iceoryx() {
        let types = all_types();
        let mut names: Vec<_> = types.iter().map(|t| t.type_name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), types.len(), "duplicate type name");
        for t in &types {
            assert!(t.type_name.starts_with("nauta."), "{}", t.type_name);
            assert!(t.type_name.contains(".v"), "{}", t.type_name);
            assert_eq!(
                t.fields[0].name, "header",
                "{} must start with the header",
                t.type_name
            );
        }
        // The iceoryx2 type name is the pinned one, not the Rust path.
        assert_eq!(
            unsafe { <ImuSample as ZeroCopySend>::type_name() },
            "nauta.ImuSample.v1"
        );
    }

    #[test]
    fn lookup_by_name() {
        assert_eq!(type_info("nauta.DepthSample.v1").map(|t| t.size), Some(40));
        assert!(type_info("nauta.Nope.v1").is_none());
    }
}
