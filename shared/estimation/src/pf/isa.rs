//! The instruction set the per-sample loops run with: AVX2 when the CPU has
//! it (x86-64), the target's baseline (SSE2 on x86-64) otherwise.
//!
//! Each hot loop is written once, as an `#[inline(always)]` body, and
//! [`dispatch!`] makes the function the filter calls. With
//! [`Isa::detect`] it runs the body through a `multiversion` function
//! (compiled once for the target and once with AVX2, the form chosen by the
//! CPU's features at run time); with [`Isa::baseline`], as compiled for the
//! target. Both give the same bits: the loops have no data-dependent order,
//! every reduction keeps its own fixed partial sums, and neither Rust nor
//! LLVM fuses a multiply and an add unless told to, so the AVX2 form
//! computes the same IEEE operations, four `f64` (eight `u32`) lanes a
//! register instead of two (four) (test `avx2_and_baseline_give_the_same_bits`).

/// Which compiled form of the loops to run; see the module documentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Isa {
    dispatch: bool,
}

impl Isa {
    /// The best form for this CPU (AVX2 if it has it).
    pub(super) fn detect() -> Self {
        Self { dispatch: true }
    }

    /// The target's baseline form, whatever the CPU has.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) fn baseline() -> Self {
        Self { dispatch: false }
    }

    /// Whether the form is chosen by the CPU's features.
    pub(super) fn dispatches(self) -> bool {
        self.dispatch
    }
}

/// `fn name(isa: Isa, args...) -> R`, which runs `body(args...)` in the
/// form `isa` says. `body` must be `#[inline(always)]`, so that it is
/// compiled into each form.
macro_rules! dispatch {
    ($(#[$attr:meta])* $vis:vis fn $name:ident
        ($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? = $body:path;) => {
        $(#[$attr])*
        $vis fn $name(isa: super::isa::Isa, $($arg: $ty),*) $(-> $ret)? {
            #[multiversion::multiversion(targets("x86_64+avx2"))]
            fn dispatched($($arg: $ty),*) $(-> $ret)? {
                $body($($arg),*)
            }
            if isa.dispatches() {
                dispatched($($arg),*)
            } else {
                $body($($arg),*)
            }
        }
    };
}
pub(super) use dispatch;
