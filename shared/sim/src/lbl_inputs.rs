//! A simulator step's readings as the LBL role's inputs
//! (`nauta_estimation::lbl::LblInput`), and the closed loop of the sensor
//! and its interrogator in process, for tests and benchmarks that run the
//! LBL estimator on the simulator.
//!
//! The order is the service's (`services/lbl`): by stamp, ties in the order
//! it declares its inputs (AHRS, depth, propeller, DVL, replies, GPS). A
//! step's replies carry their own stamps, at or after the previous step's.
//! Interrogations are registered as the sensor registers them in `sim`
//! clock (`services/sensor/src/lbl_link.rs`): at every synchronisation
//! point (`lbl_sync_hz`, 10 Hz), after the interrogator has taken every
//! input up to it.

use nauta_estimation::Estimator;
use nauta_estimation::frames::Vector;
use nauta_estimation::lbl::{Lbl, LblInput, LblOutput};
use nauta_estimation::readings::{Ahrs, Depth, Dvl, Gps, LblReplyReading as Reply, Propeller};
use nauta_estimation::role::EstimatorError;

use crate::scenario::Generator;
use crate::suite::{LblReplyReading, Measurements};

/// The step's readings as the role's inputs, in the service's order,
/// appended to `out` with their simulator reply (for the annotations:
/// multipath, true round trip).
pub fn inputs(m: &Measurements, out: &mut Vec<(LblInput, Option<LblReplyReading>)>) {
    let start = out.len();
    if let Some(r) = &m.ahrs {
        out.push((
            LblInput::Ahrs(Ahrs {
                stamp_ns: r.stamp_ns,
                roll_rad: r.roll_rad,
                pitch_rad: r.pitch_rad,
                heading_mag_rad: r.heading_mag_rad,
            }),
            None,
        ));
    }
    if let Some(r) = &m.depth {
        out.push((
            LblInput::Depth(Depth {
                stamp_ns: r.stamp_ns,
                depth_m: r.depth_m,
            }),
            None,
        ));
    }
    if let Some(r) = &m.propeller {
        out.push((
            LblInput::Propeller(Propeller {
                stamp_ns: r.stamp_ns,
                shaft_speed_rad_s: r.shaft_speed_rad_s,
            }),
            None,
        ));
    }
    if let Some(r) = &m.dvl {
        out.push((
            LblInput::Dvl(Dvl {
                stamp_ns: r.stamp_ns,
                velocity_body_m_s: Vector::from_array(r.velocity_body_m_s),
                altitude_m: r.altitude_m,
                beams_valid: r.beams_valid as u8,
                bottom_lock: r.bottom_lock != 0,
            }),
            None,
        ));
    }
    for r in &m.lbl {
        out.push((
            LblInput::Reply(Reply {
                stamp_ns: r.stamp_ns,
                transponder_id: r.transponder_id,
                interrogation_stamp_ns: r.interrogation_stamp_ns,
                round_trip_s: r.round_trip_s,
            }),
            Some(*r),
        ));
    }
    if let Some(r) = &m.gps {
        out.push((
            LblInput::Gps(Gps {
                stamp_ns: r.stamp_ns,
                lat_rad: r.lat_rad,
                lon_rad: r.lon_rad,
                height_m: r.height_m,
                horizontal_std_m: r.horizontal_std_m,
                quality: r.quality,
                velocity: None,
            }),
            None,
        ));
    }
    // By stamp, ties in the order above (a stable sort keeps it).
    out[start..].sort_by_key(|(i, _)| nauta_estimation::Stamped::stamp_ns(i));
}

/// What one step of the loop gave.
#[derive(Debug, Default)]
pub struct LoopStep {
    /// The estimator's outputs.
    pub outputs: Vec<LblOutput>,
    /// Every reply taken, with whether the estimator refused it (and why).
    pub replies: Vec<(LblReplyReading, Result<(), EstimatorError>)>,
    /// Every other input refused.
    pub refused: Vec<EstimatorError>,
}

/// The sensor and the LBL estimator in lock step (module docs).
#[derive(Debug)]
pub struct LblLoop {
    sync_every_ns: u64,
    next_sync_ns: u64,
    pings: Vec<(u32, u64)>,
    buf: Vec<(LblInput, Option<LblReplyReading>)>,
}

impl LblLoop {
    /// A loop synchronised at `sync_hz` (the sensor's `lbl_sync_hz`).
    pub fn new(sync_hz: f64) -> Self {
        let every = ((1e9 / sync_hz).round() as u64).max(1);
        Self {
            sync_every_ns: every,
            next_sync_ns: every,
            pings: Vec::new(),
            buf: Vec::new(),
        }
    }

    /// Feeds one step of `g` to `est`; `None` once the run is over.
    pub fn step(&mut self, g: &mut Generator, est: &mut Lbl) -> Option<(Measurements, LoopStep)> {
        self.step_with(g, est, |_, _, _| {})
    }

    /// [`LblLoop::step`], with `before` called first with the estimator, the
    /// step's stamp and whether the step holds a reply (a test may replace
    /// the estimator there: a restart between two steps).
    pub fn step_with(
        &mut self,
        g: &mut Generator,
        est: &mut Lbl,
        mut before: impl FnMut(&mut Lbl, u64, bool),
    ) -> Option<(Measurements, LoopStep)> {
        let m = g.step()?.expect("a simulator step");
        before(est, m.stamp_ns, !m.lbl.is_empty());
        let mut step = LoopStep::default();
        self.buf.clear();
        inputs(&m, &mut self.buf);
        for (input, sim) in &self.buf {
            let r = est.on_input(input, &mut step.outputs);
            match sim {
                Some(reply) => step.replies.push((*reply, r)),
                None => {
                    if let Err(e) = r {
                        step.refused.push(e);
                    }
                }
            }
        }
        for o in &step.outputs {
            if let LblOutput::Ping(p) = o {
                self.pings.push((p.transponder_id, p.stamp_ns));
            }
        }
        if m.stamp_ns >= self.next_sync_ns {
            while self.next_sync_ns <= m.stamp_ns {
                self.next_sync_ns += self.sync_every_ns;
            }
            for (id, stamp) in self.pings.drain(..) {
                // The sensor refuses (and counts) a transponder it does not have.
                let _ = g.interrogate(id, stamp);
            }
        }
        Some((m, step))
    }
}
