//! The forward pass as the smoother needs it (paper 004 §IV): at every
//! step, the transition matrix from the previous step's posterior, the
//! prior (which already holds `b_i` and `Q_i`, eqs. 7-9) and the posterior;
//! and the offline entry point that runs the filter over a recording's
//! checked inputs in stamp order (what `nauta smooth` feeds it).

use crate::lbl::core::Lbl;
use crate::lbl::{LblInput, LblOutput};
use crate::role::{Estimator, EstimatorError};
pub use crate::smoother::ForwardStep;

/// The steps of a forward pass, of the filter's dimension.
#[derive(Debug, Clone, PartialEq)]
pub enum ForwardSteps {
    /// `[x, y, w_x, w_y]`.
    Four(Vec<ForwardStep<4>>),
    /// `[x, y, w_x, w_y, k]`.
    Five(Vec<ForwardStep<5>>),
}

impl ForwardSteps {
    /// How many steps.
    pub fn len(&self) -> usize {
        match self {
            Self::Four(v) => v.len(),
            Self::Five(v) => v.len(),
        }
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// What a forward pass over a recording gave.
#[derive(Debug, Clone)]
pub struct ForwardPass {
    /// The steps, for the smoother.
    pub steps: ForwardSteps,
    /// Every output, as the service would have published it (`lbl/nav` and
    /// the interrogations it would have sent).
    pub outputs: Vec<LblOutput>,
    /// Every input refused, with its error (the service's health counts).
    pub refused: Vec<(u64, EstimatorError)>,
}

/// Runs `filter` over `inputs` in stamp order (ties in the service's input
/// order: AHRS, depth, propeller, DVL, replies, GPS) and returns the
/// steps, outputs and refusals. The filter's own interrogations are outputs
/// only: a recording's replies answer the pings the vehicle sent then.
pub fn forward_pass<'a>(
    mut filter: Lbl,
    inputs: impl IntoIterator<Item = &'a LblInput>,
) -> ForwardPass {
    filter.record_steps(true);
    // A recording's replies answer the recorded pings, not ours.
    filter.replay_replies(true);
    let mut outputs = Vec::new();
    let mut refused = Vec::new();
    for i in inputs {
        if let Err(e) = filter.on_input(i, &mut outputs) {
            refused.push((crate::role::Stamped::stamp_ns(i), e));
        }
    }
    ForwardPass {
        steps: filter.take_steps(),
        outputs,
        refused,
    }
}
