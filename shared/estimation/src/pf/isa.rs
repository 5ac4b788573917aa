//! The instruction set the per-sample loops run with: on x86-64, AVX-512F
//! when the CPU has it, else AVX2 when it has that, else the target's
//! baseline (SSE2).
//!
//! Each hot loop is written once, as an `#[inline(always)]` body, and
//! [`dispatch!`] makes the function the filter calls. With
//! [`Isa::detect`] it runs the body through a `multiversion` function
//! (compiled for the target, for AVX2 and for AVX-512F, the form chosen by
//! the CPU's features at run time); tests can also ask for AVX2 at most
//! ([`Isa::avx2_at_most`]) or the baseline ([`Isa::baseline`]). Every form
//! gives the same bits: the loops have no data-dependent order, every
//! reduction keeps its own fixed partial sums, and neither Rust nor LLVM
//! fuses a multiply and an add unless told to, so the wider forms compute
//! the same IEEE operations on four (AVX2) or eight (AVX-512) `f64` lanes a
//! register instead of two (test `avx2_and_baseline_give_the_same_bits`).

/// Which compiled form of the loops to run; see the module documentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Isa {
    /// The widest form this CPU runs.
    Detect,
    /// AVX2 if this CPU has it, else the baseline (never AVX-512).
    #[cfg_attr(not(test), allow(dead_code))]
    Avx2AtMost,
    /// The target's baseline form, whatever the CPU has.
    #[cfg_attr(not(test), allow(dead_code))]
    Baseline,
}

impl Isa {
    /// The widest form this CPU runs.
    pub(super) fn detect() -> Self {
        Self::Detect
    }

    /// AVX2 if this CPU has it, else the baseline.
    #[cfg(test)]
    pub(super) fn avx2_at_most() -> Self {
        Self::Avx2AtMost
    }

    /// The target's baseline form.
    #[cfg(test)]
    pub(super) fn baseline() -> Self {
        Self::Baseline
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
            #[multiversion::multiversion(targets("x86_64+avx512f", "x86_64+avx2"))]
            fn widest($($arg: $ty),*) $(-> $ret)? {
                $body($($arg),*)
            }
            #[cfg(test)]
            #[multiversion::multiversion(targets("x86_64+avx2"))]
            fn avx2_at_most($($arg: $ty),*) $(-> $ret)? {
                $body($($arg),*)
            }
            match isa {
                super::isa::Isa::Detect => widest($($arg),*),
                #[cfg(test)]
                super::isa::Isa::Avx2AtMost => avx2_at_most($($arg),*),
                _ => $body($($arg),*),
            }
        }
    };
}
pub(super) use dispatch;
