//! The aided INS role's estimator as the shell runs it: one of its variants
//! behind one [`Estimator`], and the state one instance hands another.
//!
//! Variants so far: `dr` (paper 002, [`DeadReckoning`]). Paper 000's `pf`
//! and the error-state `ekf` join this enum as they are built.

use crate::ains::AinsInput;
use crate::ains::dr::{DeadReckoning, DrParams, DrSnapshot, Site};
use crate::readings::Nav;
use crate::role::{Estimator, EstimatorError};

/// The variants of the aided INS role; the first is the default.
pub const VARIANTS: [&str; 1] = ["dr"];

/// A variant's parameters, as the manifest gives them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AinsParams {
    /// `dr`: paper 002's dead reckoning.
    Dr(DrParams),
}

/// One running variant.
#[derive(Debug, Clone)]
pub enum AinsCore {
    /// `dr`.
    Dr(Box<DeadReckoning>),
}

/// The state of an aided INS instance, for a warm restart or a hot swap:
/// the exact state of its variant (another instance of the same variant
/// continues bit for bit).
#[derive(Debug, Clone, PartialEq)]
pub enum AinsState {
    /// A `dr` instance's state.
    Dr(Box<DrSnapshot>),
    /// A snapshot message that did not decode into any variant's state (its
    /// variant, and why); refused on restore.
    Unreadable {
        /// The variant the message names.
        variant: String,
        /// Why it could not be read.
        reason: String,
    },
}

impl AinsState {
    /// The variant this state belongs to.
    pub fn variant(&self) -> &str {
        match self {
            AinsState::Dr(_) => "dr",
            AinsState::Unreadable { variant, .. } => variant,
        }
    }
}

impl AinsCore {
    /// The variant of `params` at `site`.
    pub fn new(params: &AinsParams, site: Site) -> anyhow::Result<Self> {
        Ok(match params {
            AinsParams::Dr(p) => AinsCore::Dr(Box::new(DeadReckoning::new(p, site)?)),
        })
    }

    /// This instance's variant.
    pub fn variant(&self) -> &'static str {
        match self {
            AinsCore::Dr(_) => "dr",
        }
    }

    /// Whether the variant's error prediction says it is time to surface
    /// (paper 002's embedded use).
    pub fn surfacing_advised(&self) -> bool {
        match self {
            AinsCore::Dr(d) => d.surfacing_advised(),
        }
    }
}

impl Estimator for AinsCore {
    type Input = AinsInput;
    type Output = Nav;
    type Snapshot = AinsState;

    fn on_input(&mut self, input: &AinsInput, out: &mut Vec<Nav>) -> Result<(), EstimatorError> {
        match self {
            AinsCore::Dr(d) => d.on_input(input, out),
        }
    }

    fn snapshot(&self) -> Option<AinsState> {
        match self {
            AinsCore::Dr(d) => d.snapshot().map(|s| AinsState::Dr(Box::new(s))),
        }
    }

    fn restore(&mut self, state: &AinsState, stamp_ns: u64) -> Result<(), EstimatorError> {
        if let AinsState::Unreadable { variant, reason } = state {
            return Err(EstimatorError::new(
                "snapshot-unreadable",
                format!("the {variant} snapshot cannot be read: {reason}"),
            ));
        }
        let own = self.variant();
        let mismatch = || {
            EstimatorError::new(
                "snapshot-variant",
                format!(
                    "a {own} instance continues only from a {own} snapshot, not from a {} one",
                    state.variant(),
                ),
            )
        };
        if own != state.variant() {
            return Err(mismatch());
        }
        match (&mut *self, state) {
            (AinsCore::Dr(d), AinsState::Dr(s)) => d.restore(s, stamp_ns),
            _ => Err(mismatch()),
        }
    }
}
