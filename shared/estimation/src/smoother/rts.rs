//! The backward pass of the fixed-interval Rauch-Tung-Striebel smoother,
//! paper 004 eqs. 7-9 (Gelb, *Applied Optimal Estimation*, ch. 5, the paper's ref. 6, for the
//! linear case; the nonlinear
//! form linearises about the forward pass's estimates, as the paper does).
//!
//! With the forward pass's `E_i, P_i` (posterior at `t_i`) and
//! `E⁻_{i+1} = φ_i E_i + b_i`, `P⁻_{i+1} = φ_i P_i φ_iᵀ + Q_i` (prior at
//! `t_{i+1}`, [`ForwardStep`]), from `E_{N|N} = E_N`, `P_{N|N} = P_N`
//! backwards:
//!
//! - eq. 8: `K_i = P_i φ_iᵀ (P⁻_{i+1})⁻¹`, computed as the solution of
//!   `P⁻_{i+1} K_iᵀ = φ_i P_i` by Cholesky (both covariances symmetric), so
//!   nothing is inverted and a prior that is not positive definite is
//!   found, not divided by;
//! - eq. 7: `E_{i|N} = E_i + K_i (E_{i+1|N} − E⁻_{i+1})`;
//! - eq. 9: `P_{i|N} = P_i + K_i (P_{i+1|N} − P⁻_{i+1}) K_iᵀ`, made
//!   symmetric and checked positive definite.
//!
//! The prior is taken from the forward pass as it was computed (the paper
//! writes eq. 7's `φ_i E_i + b_i` and eq. 9's `φ_i P_i φ_iᵀ + Q_i`, which
//! is what the forward pass predicted), so a filter that integrates eqs.
//! 3-4 more finely than `φ_i` is smoothed about its own prediction.
//!
//! **Restarts.** Eqs. 7-9 assume that each posterior is the prior corrected
//! by measurements (eqs. 5-6), so that `P_i ≤ P⁻_i`. A filter may instead
//! discard its prior: reset the position to a GPS fix at the surface, or
//! widen `P` to re-acquire after a blackout. Such a step knows less than
//! its prior in some direction (`P_i − P⁻_i` has a positive eigenvalue), and
//! carrying its jump back through eq. 7 would move the whole track before
//! it (with `K_i ≈ I` between two corrections) and inflate `P_{i|N}` above
//! `P_i`. [`smooth`] therefore restarts there, as at the end of the
//! mission: the step before it keeps its filtered estimate
//! (`E_{i|N} = E_i`, `P_{i|N} = P_i`), and each stretch between restarts is
//! smoothed on its own ([`is_restart`]).
//!
//! [`smooth_bridged`] instead carries the restart's information back as
//! what it is, a fix of the states the restart set (the first `m`: the
//! position): the smoothed estimate there, `E_{i+1|N}`'s first `m`
//! components with `P_{i+1|N}`'s `m × m` block as their covariance (the
//! stretch after the restart, which discarded the prior there), corrects
//! the prior `E⁻_{i+1}, P⁻_{i+1}` as a measurement would (eqs. 5-6, Joseph
//! form), and eqs. 7-9 go on from that corrected prior. The stretch before
//! is then smoothed towards where the vehicle was found after it (a
//! blackout is bridged), and `P̃_{i+1} ≤ P⁻_{i+1}` keeps `P_{i|N} ≤ P_i`.
//! The other states' information after the restart is left out (it holds
//! the prior's, which would count twice).
//!
//! The cost is a few 4×4 products and one Cholesky per step, with no
//! allocation but the output's.

use nalgebra::{SMatrix, SVector};

use crate::smoother::error::{SmoothError, StepField};
use crate::smoother::step::{ForwardStep, SmoothedStep};

/// Smooths a forward pass: one [`SmoothedStep`] per [`ForwardStep`], in
/// the same order, restarting at each restart (module docs). An empty pass
/// gives an empty result.
pub fn smooth<const N: usize>(
    steps: &[ForwardStep<N>],
) -> Result<Vec<SmoothedStep<N>>, SmoothError> {
    let mut out = Vec::new();
    smooth_into(steps, &mut out)?;
    Ok(out)
}

/// [`smooth`], carrying each restart back as a fix of the first `m` states
/// (module docs, "Restarts"; `m = 0` is [`smooth`], `m` is at most `N`).
pub fn smooth_bridged<const N: usize>(
    steps: &[ForwardStep<N>],
    m: usize,
) -> Result<Vec<SmoothedStep<N>>, SmoothError> {
    let mut out = Vec::new();
    let result = backward(steps, &mut out, m.min(N));
    if result.is_err() {
        out.clear();
    }
    result.map(|()| out)
}

/// [`smooth`] into `out` (cleared first), reusing its allocation. On an
/// error `out` is left empty.
pub fn smooth_into<const N: usize>(
    steps: &[ForwardStep<N>],
    out: &mut Vec<SmoothedStep<N>>,
) -> Result<(), SmoothError> {
    out.clear();
    let result = backward(steps, out, 0);
    if result.is_err() {
        out.clear();
    }
    result
}

fn backward<const N: usize>(
    steps: &[ForwardStep<N>],
    out: &mut Vec<SmoothedStep<N>>,
    bridge: usize,
) -> Result<(), SmoothError> {
    let Some(last) = steps.last() else {
        return Ok(());
    };
    check_stamps(steps)?;
    let n = steps.len() - 1;
    check_posterior(last, n)?;
    out.resize(
        steps.len(),
        SmoothedStep {
            stamp_ns: 0,
            x: SVector::zeros(),
            p: SMatrix::zeros(),
        },
    );
    // E_{N|N} = E_N, P_{N|N} = P_N.
    out[n] = SmoothedStep {
        stamp_ns: last.stamp_ns,
        x: last.x_post,
        p: last.p_post,
    };
    let mut x_next = last.x_post;
    let mut p_next = last.p_post;
    for i in (0..n).rev() {
        let step = &steps[i];
        let next = &steps[i + 1];
        check_posterior(step, i)?;
        check_transition(next, i + 1)?;
        let Some(chol) = next.p_prior.cholesky() else {
            return Err(SmoothError::NotPositiveDefinite {
                step: i + 1,
                stamp_ns: next.stamp_ns,
                field: StepField::PPrior,
            });
        };
        // What eqs. 7 and 9 pull the prior towards: the smoothed estimate at
        // `i + 1`, or at a bridged restart the prior fixed by it.
        let (x_target, p_target) = if is_restart(next) {
            match fix_prior(next, &x_next, &p_next, bridge) {
                Some(fixed) => fixed,
                None => {
                    out[i] = SmoothedStep {
                        stamp_ns: step.stamp_ns,
                        x: step.x_post,
                        p: step.p_post,
                    };
                    x_next = step.x_post;
                    p_next = step.p_post;
                    continue;
                }
            }
        } else {
            (x_next, p_next)
        };
        // Eq. 8: P⁻_{i+1} K_iᵀ = φ_i P_i.
        let gain = chol.solve(&(next.phi * step.p_post)).transpose();
        // Eq. 7.
        let x = step.x_post + gain * (x_target - next.x_prior);
        // Eq. 9.
        let p = step.p_post + gain * (p_target - next.p_prior) * gain.transpose();
        let p = (p + p.transpose()) * 0.5;
        let fail = |field| {
            Err(SmoothError::NonFinite {
                step: i,
                stamp_ns: step.stamp_ns,
                field,
            })
        };
        if !x.iter().all(|v| v.is_finite()) {
            // Only an overflow gets here: every input was finite.
            return fail(StepField::XSmoothed);
        }
        if !p.iter().all(|v| v.is_finite()) {
            return fail(StepField::PSmoothed);
        }
        if p.cholesky().is_none() {
            return Err(SmoothError::NotPositiveDefinite {
                step: i,
                stamp_ns: step.stamp_ns,
                field: StepField::PSmoothed,
            });
        }
        out[i] = SmoothedStep {
            stamp_ns: step.stamp_ns,
            x,
            p,
        };
        x_next = x;
        p_next = p;
    }
    Ok(())
}

/// The prior of the restart `next` corrected by the smoothed estimate
/// there, `x_s`, `p_s`, as a fix of its first `m` states (module docs,
/// "Restarts"); `None` when `m` is 0 or the correction fails (the pass then
/// restarts).
fn fix_prior<const N: usize>(
    next: &ForwardStep<N>,
    x_s: &SVector<f64, N>,
    p_s: &SMatrix<f64, N, N>,
    m: usize,
) -> Option<(SVector<f64, N>, SMatrix<f64, N, N>)> {
    if m == 0 {
        return None;
    }
    let prior = nalgebra::DMatrix::from_column_slice(N, N, next.p_prior.as_slice());
    let h = nalgebra::DMatrix::<f64>::identity(m, N);
    let r = p_s.view((0, 0), (m, m)).clone_owned();
    let r = nalgebra::DMatrix::from_column_slice(m, m, r.as_slice());
    // Eqs. 5-6 with z = x_s[..m], H = [I 0], R = p_s[..m, ..m].
    let s = &h * &prior * h.transpose() + &r;
    let gain = s.cholesky()?.solve(&(&h * &prior)).transpose();
    let innovation = nalgebra::DVector::from_iterator(m, (0..m).map(|k| x_s[k] - next.x_prior[k]));
    let dx = &gain * innovation;
    let i_kh = nalgebra::DMatrix::<f64>::identity(N, N) - &gain * &h;
    let p = &i_kh * &prior * i_kh.transpose() + &gain * &r * gain.transpose();
    let x = next.x_prior + SVector::<f64, N>::from_iterator(dx.iter().copied());
    let p = SMatrix::<f64, N, N>::from_iterator(p.iter().copied());
    let p = (p + p.transpose()) * 0.5;
    (x.iter().chain(p.iter()).all(|v| v.is_finite()) && p.cholesky().is_some()).then_some((x, p))
}

/// Relative size of a positive eigenvalue of `P_i − P⁻_i` that makes a
/// restart (rounding in a correction stays far below).
const RESTART_TOLERANCE: f64 = 1e-9;

/// Whether `step`'s posterior discards its prior (module docs, "Restarts"):
/// `P⁻_i − P_i` is not positive semi-definite, to
/// [`RESTART_TOLERANCE`] of `trace P⁻_i`. A step without a correction
/// (posterior equal to the prior) is none.
pub fn is_restart<const N: usize>(step: &ForwardStep<N>) -> bool {
    if step.p_post == step.p_prior {
        return false;
    }
    let slack = RESTART_TOLERANCE * step.p_prior.trace().abs();
    let d = step.p_prior - step.p_post + SMatrix::<f64, N, N>::identity() * slack;
    d.cholesky().is_none()
}

fn check_stamps<const N: usize>(steps: &[ForwardStep<N>]) -> Result<(), SmoothError> {
    for (i, pair) in steps.windows(2).enumerate() {
        if pair[1].stamp_ns < pair[0].stamp_ns {
            return Err(SmoothError::StampBackwards {
                step: i + 1,
                stamp_ns: pair[1].stamp_ns,
                previous_ns: pair[0].stamp_ns,
            });
        }
    }
    Ok(())
}

/// The filtered state and covariance of step `i`: finite, `P_i` positive
/// definite.
fn check_posterior<const N: usize>(step: &ForwardStep<N>, i: usize) -> Result<(), SmoothError> {
    finite(step, i, step.x_post.as_slice(), StepField::XPost)?;
    finite(step, i, step.p_post.as_slice(), StepField::PPost)?;
    if step.p_post.cholesky().is_none() {
        return Err(SmoothError::NotPositiveDefinite {
            step: i,
            stamp_ns: step.stamp_ns,
            field: StepField::PPost,
        });
    }
    Ok(())
}

/// The transition into step `i` (`φ`, the prior): finite. The prior's
/// positivity is checked by the Cholesky eq. 8 needs.
fn check_transition<const N: usize>(step: &ForwardStep<N>, i: usize) -> Result<(), SmoothError> {
    finite(step, i, step.phi.as_slice(), StepField::Phi)?;
    finite(step, i, step.x_prior.as_slice(), StepField::XPrior)?;
    finite(step, i, step.p_prior.as_slice(), StepField::PPrior)
}

fn finite<const N: usize>(
    step: &ForwardStep<N>,
    i: usize,
    values: &[f64],
    field: StepField,
) -> Result<(), SmoothError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(SmoothError::NonFinite {
            step: i,
            stamp_ns: step.stamp_ns,
            field,
        })
    }
}
