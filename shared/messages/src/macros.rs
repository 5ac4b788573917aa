/// Declares a wire message: the `#[repr(C)]` struct with its derives and pinned
/// iceoryx2 type name, its [`crate::Message`] implementation (type name, field schema
/// for self-describing recordings) and a compile-time size assertion.
macro_rules! message {
    (
        $(#[doc = $doc:literal])*
        #[wire(type_name = $tn:literal, size = $size:expr)]
        pub struct $name:ident {
            $(
                $(#[doc = $fdoc:literal])*
                pub $field:ident : $ty:ty
            ),* $(,)?
        }
    ) => {
        $(#[doc = $doc])*
        #[derive(
            Debug, Clone, Copy, PartialEq, Default,
            ZeroCopySend, serde::Serialize, serde::Deserialize,
        )]
        #[type_name($tn)]
        #[repr(C)]
        pub struct $name {
            $(
                $(#[doc = $fdoc])*
                pub $field: $ty,
            )*
        }

        const _: () = assert!(
            core::mem::size_of::<$name>() == $size,
            concat!("wire size of ", stringify!($name), " changed: bump its type-name version")
        );

        impl $crate::registry::Message for $name {
            const TYPE_NAME: &'static str = $tn;
            const FIELDS: &'static [$crate::registry::FieldInfo] = &[
                $(
                    $crate::registry::FieldInfo {
                        name: stringify!($field),
                        ty: stringify!($ty),
                        doc: concat!($($fdoc),*),
                    },
                )*
            ];
            fn header(&self) -> &$crate::Header {
                &self.header
            }
            fn header_mut(&mut self) -> &mut $crate::Header {
                &mut self.header
            }
        }
    };
}
