//! The aided INS role's estimator as the shell runs it: one of its variants
//! behind one [`Estimator`], and the state one instance hands another.
//!
//! Variants: `pf` (paper 000 §III-A, [`ParticleAins`], the default), `dr`
//! (paper 002, [`DeadReckoning`]) and `ekf` (an error-state Kalman filter,
//! [`Ekf`]).

use crate::ains::AinsInput;
use crate::ains::dr::{DeadReckoning, DrParams, DrSnapshot, Site};
use crate::ains::ekf::{Ekf, EkfParams, EkfSnapshot};
use crate::ains::pf::{AinsPfParams, AinsPfSnapshot, ParticleAins};
use crate::ains::seed::NavSeed;
use crate::readings::Nav;
use crate::role::{Estimator, EstimatorError};

/// The variants of the aided INS role; the first is the default.
pub const VARIANTS: [&str; 3] = ["pf", "dr", "ekf"];

/// A variant's parameters, as the manifest gives them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AinsParams {
    /// `pf`: paper 000's velocity and position particle filters.
    Pf(AinsPfParams),
    /// `dr`: paper 002's dead reckoning.
    Dr(DrParams),
    /// `ekf`: the error-state Kalman filter.
    Ekf(EkfParams),
}

/// One running variant.
#[derive(Debug, Clone)]
pub enum AinsCore {
    /// `pf`.
    Pf(Box<ParticleAins>),
    /// `dr`.
    Dr(Box<DeadReckoning>),
    /// `ekf`.
    Ekf(Box<Ekf>),
}

/// The state of an aided INS instance, for a warm restart or a hot swap.
/// `dr` and `ekf` continue bit for bit; `pf` from its filters' moments (its
/// particles do not fit a snapshot: the cloud is redrawn). Another
/// variant continues from the solution the state holds ([`NavSeed`]).
#[derive(Debug, Clone, PartialEq)]
pub enum AinsState {
    /// A `pf` instance's state.
    Pf(Box<AinsPfSnapshot>),
    /// A `dr` instance's state.
    Dr(Box<DrSnapshot>),
    /// An `ekf` instance's state.
    Ekf(Box<EkfSnapshot>),
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
    /// The solution this state holds, for another variant to continue from
    /// (`None` for a state that fails its checks, an `ekf` not yet
    /// initialised, or an unreadable one).
    pub fn seed(&self) -> Option<NavSeed> {
        match self {
            AinsState::Pf(s) => NavSeed::from_pf(s),
            AinsState::Dr(s) => NavSeed::from_dr(s),
            AinsState::Ekf(s) => NavSeed::from_ekf(s),
            AinsState::Unreadable { .. } => None,
        }
    }

    /// The variant this state belongs to.
    pub fn variant(&self) -> &str {
        match self {
            AinsState::Pf(_) => "pf",
            AinsState::Dr(_) => "dr",
            AinsState::Ekf(_) => "ekf",
            AinsState::Unreadable { variant, .. } => variant,
        }
    }
}

impl AinsCore {
    /// The variant of `params` at `site`.
    pub fn new(params: &AinsParams, site: Site) -> anyhow::Result<Self> {
        Ok(match params {
            AinsParams::Pf(p) => AinsCore::Pf(Box::new(ParticleAins::new(p, site)?)),
            AinsParams::Dr(p) => AinsCore::Dr(Box::new(DeadReckoning::new(p, site)?)),
            AinsParams::Ekf(p) => AinsCore::Ekf(Box::new(Ekf::new(p, site)?)),
        })
    }

    /// This instance's variant.
    pub fn variant(&self) -> &'static str {
        match self {
            AinsCore::Pf(_) => "pf",
            AinsCore::Dr(_) => "dr",
            AinsCore::Ekf(_) => "ekf",
        }
    }
}

impl Estimator for AinsCore {
    type Input = AinsInput;
    type Output = Nav;
    type Snapshot = AinsState;

    fn on_input(&mut self, input: &AinsInput, out: &mut Vec<Nav>) -> Result<(), EstimatorError> {
        match self {
            AinsCore::Pf(p) => p.on_input(input, out),
            AinsCore::Dr(d) => d.on_input(input, out),
            AinsCore::Ekf(e) => e.on_input(input, out),
        }
    }

    fn snapshot(&self) -> Option<AinsState> {
        match self {
            AinsCore::Pf(p) => p.snapshot().map(|s| AinsState::Pf(Box::new(s))),
            AinsCore::Dr(d) => d.snapshot().map(|s| AinsState::Dr(Box::new(s))),
            AinsCore::Ekf(e) => e.snapshot().map(|s| AinsState::Ekf(Box::new(s))),
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
                    "a {own} instance cannot continue from the {} snapshot: it holds no valid solution yet",
                    state.variant(),
                ),
            )
        };
        match (&mut *self, state) {
            (AinsCore::Pf(p), AinsState::Pf(s)) => return p.restore(s, stamp_ns),
            (AinsCore::Dr(d), AinsState::Dr(s)) => return d.restore(s, stamp_ns),
            (AinsCore::Ekf(e), AinsState::Ekf(s)) => return e.restore(s, stamp_ns),
            _ => {}
        }
        // Another variant's state: continue from its solution.
        let seed = state.seed().ok_or_else(mismatch)?;
        tracing::info!(
            from = state.variant(),
            to = own,
            "continuing from the other variant's solution (position, velocity, attitude and their σ)"
        );
        match self {
            AinsCore::Pf(p) => p.start_from(&seed, stamp_ns),
            AinsCore::Dr(d) => d.start_from(&seed, stamp_ns),
            AinsCore::Ekf(e) => e.start_from(&seed, stamp_ns),
        }
    }
}
