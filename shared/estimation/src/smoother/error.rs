//! Why the smoother refused a forward pass.

use std::fmt;

/// Which value of a step an error names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepField {
    /// [`super::ForwardStep::phi`].
    Phi,
    /// [`super::ForwardStep::x_prior`].
    XPrior,
    /// [`super::ForwardStep::p_prior`].
    PPrior,
    /// [`super::ForwardStep::x_post`].
    XPost,
    /// [`super::ForwardStep::p_post`].
    PPost,
    /// The smoothed state the backward pass computed (eq. 7).
    XSmoothed,
    /// The smoothed covariance the backward pass computed (eq. 9).
    PSmoothed,
}

impl fmt::Display for StepField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Phi => "the transition matrix φ",
            Self::XPrior => "the prior state",
            Self::PPrior => "the prior covariance",
            Self::XPost => "the filtered state",
            Self::PPost => "the filtered covariance",
            Self::XSmoothed => "the smoothed state",
            Self::PSmoothed => "the smoothed covariance",
        })
    }
}

/// A forward pass the smoother cannot smooth. Nothing is returned with it:
/// the caller keeps the forward pass and may report the step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SmoothError {
    /// A value of the step is NaN or infinite.
    #[error("step {step} (stamp {stamp_ns} ns): {field} is not finite")]
    NonFinite {
        /// Index of the step in the forward pass.
        step: usize,
        /// Its stamp.
        stamp_ns: u64,
        /// The value.
        field: StepField,
    },
    /// A covariance of the step is not positive definite (its Cholesky
    /// factorisation failed).
    #[error("step {step} (stamp {stamp_ns} ns): {field} is not positive definite")]
    NotPositiveDefinite {
        /// Index of the step in the forward pass.
        step: usize,
        /// Its stamp.
        stamp_ns: u64,
        /// The covariance.
        field: StepField,
    },
    /// The step's stamp is earlier than the previous step's.
    #[error("step {step}: stamp {stamp_ns} ns is before the previous step's {previous_ns} ns")]
    StampBackwards {
        /// Index of the step in the forward pass.
        step: usize,
        /// Its stamp.
        stamp_ns: u64,
        /// The previous step's stamp.
        previous_ns: u64,
    },
}
