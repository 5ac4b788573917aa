//! The estimator of a role as the runtime's estimator shell runs it (STYLE item
//! 4, copper-rs's task inside a runtime-owned lifecycle): a plain struct that
//! takes checked inputs in stamp order and returns stamped outputs, and that
//! can hand its state over to another instance. Standby, activation at a stamp
//! boundary, resume, snapshots, health and control are the shell's
//! (`nauta_runtime::shell`), written once; the same object runs in a service, in
//! a benchmark and in an in-process pipeline.
//!
//! Time comes only from the inputs' stamps (DESIGN §7): an estimator never
//! reads a clock, so the same inputs give the same outputs, bit for bit.

use thiserror::Error;

/// Something valid at one stamp of the run's clock, ns.
pub trait Stamped {
    /// The time of validity, ns.
    fn stamp_ns(&self) -> u64;
}

/// Why an estimator could not use an input or a snapshot (the shell counts
/// the input as rejected, logs the first of each kind and goes on). A
/// malformed input or snapshot leaves the state as it was; a measurement
/// refused on its merits (a gated fix, a DVL spike) may still have moved the
/// state on to its stamp, and the outputs pushed before the error are
/// published.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{kind}: {detail}")]
pub struct EstimatorError {
    /// A short, stable name of the kind of failure (for counting and log-once).
    pub kind: &'static str,
    /// What happened.
    pub detail: String,
}

impl EstimatorError {
    /// An error of `kind` described by `detail`.
    pub fn new(kind: &'static str, detail: impl std::fmt::Display) -> Self {
        Self {
            kind,
            detail: detail.to_string(),
        }
    }
}

/// A role's estimator (attitude, aided INS, positioning, LBL, ...).
pub trait Estimator {
    /// One checked input from any of the role's input services (an enum when
    /// the role has several).
    type Input;
    /// One output, published on one of the role's output services; it keeps
    /// the stamp of the input it was computed from.
    type Output: Stamped;
    /// The state another instance continues from (warm restart, hot swap).
    type Snapshot;

    /// Processes one input (inputs come in stamp order, ties in the order the
    /// role declared its inputs) and appends its outputs to `out`.
    fn on_input(
        &mut self,
        input: &Self::Input,
        out: &mut Vec<Self::Output>,
    ) -> Result<(), EstimatorError>;

    /// The state after the last input, once there is one (nothing while the
    /// estimator initialises).
    fn snapshot(&self) -> Option<Self::Snapshot>;

    /// Continues from `snapshot`, the state of another instance after its
    /// input stamped `stamp_ns`: inputs up to that stamp are then skipped. A
    /// snapshot that fails its checks is refused and the state kept.
    fn restore(&mut self, snapshot: &Self::Snapshot, stamp_ns: u64) -> Result<(), EstimatorError>;
}
