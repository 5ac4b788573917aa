//! The smoothed track of an LBL forward pass: paper 004's backward pass
//! (eqs. 7-9, [`nauta_estimation::smoother`]) over the filter's recorded
//! steps, one `smoother/lbl/nav` solution per step the filter published.

use std::time::Instant;

use nauta_estimation::lbl::{ForwardPass, ForwardSteps, LblOutput};
use nauta_estimation::readings::LblNav;
use nauta_estimation::smoother::{self, ForwardStep, SmoothError, SmoothedStep};
use nauta_messages::{Header, LblSolution, Role};

/// The topic of the smoothed track.
pub const TOPIC: &str = "smoother/lbl/nav";

/// A smoothed track and the time its backward pass took.
#[derive(Debug, Clone)]
pub struct Track {
    /// One per step of the forward pass that the filter published, in
    /// stamp order; header source [`Role::Smoother`], `seq` from 0.
    pub solutions: Vec<LblSolution>,
    /// Steps smoothed.
    pub steps: usize,
    /// The backward pass's wall time, s.
    pub backward_s: f64,
}

/// The filter's `lbl/nav` at a smoothed step, with the smoothed `x`, `y`,
/// current and the `[x, y, w_x, w_y]` block of `P`; the last range's
/// innovation, transponder and gate verdict are the filter's (the smoother
/// uses the ranges the filter accepted, and computes no innovation).
fn smoothed_nav<const N: usize>(filtered: &LblNav, s: &SmoothedStep<N>) -> LblNav {
    let mut p = [[0.0; 4]; 4];
    for (r, row) in p.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = s.p[(r, c)];
        }
    }
    LblNav {
        stamp_ns: s.stamp_ns,
        x_m: s.x[0],
        y_m: s.x[1],
        current_m_s: [s.x[2], s.x[3]],
        p,
        ..*filtered
    }
}

fn track_of<const N: usize>(
    steps: &[ForwardStep<N>],
    navs: &[LblNav],
) -> Result<Track, SmoothError> {
    const { assert!(N >= 4, "the LBL state starts with [x, y, w_x, w_y]") };
    let start = Instant::now();
    // A restart (a GPS reset, a re-acquisition) is carried back as a fix of
    // the position, x and y.
    let smoothed = smoother::smooth_bridged(steps, 2)?;
    let backward_s = start.elapsed().as_secs_f64();
    // Both in stamp order: walk them together.
    let mut solutions = Vec::with_capacity(navs.len());
    let mut k = 0;
    for nav in navs {
        while k < smoothed.len() && smoothed[k].stamp_ns < nav.stamp_ns {
            k += 1;
        }
        let Some(s) = smoothed.get(k).filter(|s| s.stamp_ns == nav.stamp_ns) else {
            continue;
        };
        let mut m = LblSolution::from(&smoothed_nav(nav, s));
        m.header = Header {
            flags: m.header.flags,
            ..Header::new(s.stamp_ns, solutions.len() as u64, Role::Smoother, 0)
        };
        solutions.push(m);
    }
    Ok(Track {
        solutions,
        steps: steps.len(),
        backward_s,
    })
}

/// The `lbl/nav` solutions the filter published in `pass`.
pub fn navs(pass: &ForwardPass) -> Vec<LblNav> {
    pass.outputs
        .iter()
        .filter_map(|o| match o {
            LblOutput::Nav(n) => Some(*n),
            LblOutput::Ping(_) => None,
        })
        .collect()
}

/// Smooths `pass`: one solution per `lbl/nav` of the pass at a recorded
/// step.
pub fn smoothed_track(pass: &ForwardPass) -> Result<Track, SmoothError> {
    let navs = navs(pass);
    match &pass.steps {
        ForwardSteps::Four(s) => track_of(s, &navs),
        ForwardSteps::Five(s) => track_of(s, &navs),
    }
}
