//! The closed LBL loop: interrogations in from `lbl/interrogate`, replies out
//! on `sensor/lbl` after the acoustic travel both ways (the physics is in
//! [`nauta_sim::suite`]).
//!
//! # Determinism in `sim` clock
//!
//! The sensor runs ahead of its consumers as fast as they drain, so without a
//! rule an interrogation would reach it after a timing-dependent number of
//! further steps. The rule: at every synchronisation point (every
//! `1 / lbl_sync_hz` s of simulated time, 10 Hz by default) the sensor
//! publishes a watermark `W` on `sensor/progress` (the stamp of that step,
//! floored to the LBL clock tick) and generates nothing further until the
//! interrogator's own watermark on `lbl/progress` reaches `W`. The
//! interrogator processes its inputs up to `W`, publishes any interrogation
//! stamped `W` or later (its "now"), then its watermark. Interrogations are
//! thus registered at the same simulated instant in every run. One stamped
//! before the last generated step (a contract violation) is still registered,
//! with the vehicle at that step, and counted as late.
//!
//! The wait ends early when the interrogator ends its stream or has gone (no
//! publisher left), on STOP or a termination signal, and after the run's
//! back-pressure deadline (counted, logged once): a dead interrogator cannot
//! stall the run.
//!
//! In `wall` clock nothing waits: interrogations are registered as they come.

use std::time::{Duration, Instant};

use nauta_messages::checked::ValidationError;
use nauta_messages::*;
use nauta_runtime::ports::Inbox;
use nauta_runtime::{Connect, Context, HealthReporter, PortDescription, Subscriber, services};
use nauta_sim::scenario::Generator;
use nauta_sim::suite::SuiteError;

/// The inputs, for `--describe` (both optional: most runs have no interrogator).
pub fn describe() -> Vec<PortDescription> {
    vec![
        PortDescription::optional(&services::lbl_interrogate()),
        PortDescription::optional(&services::progress(Role::Lbl)),
    ]
}

/// How a wait for the interrogator ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Waited {
    /// Its watermark reached ours, it ended, or it is not there.
    Done,
    /// The back-pressure deadline passed.
    TimedOut,
    /// A termination signal arrived.
    Terminated,
}

/// The interrogation input and the synchronisation with the interrogator.
pub struct LblLink {
    requests: Subscriber<LblInterrogation>,
    requests_inbox: Inbox,
    progress: Subscriber<Progress>,
    progress_inbox: Inbox,
    watermark_ns: Option<u64>,
    ended: bool,
    sync_every_ns: u64,
    next_sync_ns: u64,
    tick_ns: u64,
    deadline: Duration,
    /// Interrogations registered.
    pub accepted: u64,
    /// Interrogations stamped before the last generated step (sim clock).
    pub late: u64,
    /// Waits that hit the deadline.
    pub timed_out: u64,
    late_logged: bool,
    lockstep: bool,
}

impl LblLink {
    /// Opens the inputs; `sync_hz` is the synchronisation rate, `tick_ns` the
    /// LBL clock resolution, `lockstep` whether the sensor waits for the
    /// interrogator (`sim` clock), where a late ping is a contract violation
    /// worth a warning (in `wall` clock every ping arrives a little late).
    pub fn open(ctx: &Context, sync_hz: f64, tick_ns: u64, lockstep: bool) -> anyhow::Result<Self> {
        let (requests, requests_inbox) = ctx.subscriber(&services::lbl_interrogate())?;
        let (progress, progress_inbox) = ctx.subscriber(&services::progress(Role::Lbl))?;
        let sync_every_ns = ((1e9 / sync_hz).round() as u64).max(1);
        Ok(Self {
            requests,
            requests_inbox,
            progress,
            progress_inbox,
            watermark_ns: None,
            ended: false,
            sync_every_ns,
            next_sync_ns: sync_every_ns,
            tick_ns: tick_ns.max(1),
            deadline: ctx.deadline,
            accepted: 0,
            late: 0,
            timed_out: 0,
            late_logged: false,
            lockstep,
        })
    }

    /// Attaches the inputs to the interrogator, if there is one. Called once
    /// the launcher has activated the sensor (every process is ready then).
    pub fn connect(&self) -> anyhow::Result<bool> {
        Ok(self.requests.connect()? & self.progress.connect()?)
    }

    /// Whether an interrogator is connected and has not ended its stream.
    pub fn interrogator_present(&self) -> bool {
        !self.ended && self.requests.publisher_count() > 0
    }

    /// If the step stamped `stamp_ns` is a synchronisation point, the
    /// watermark to publish after it.
    pub fn sync_point(&mut self, stamp_ns: u64) -> Option<u64> {
        if stamp_ns < self.next_sync_ns {
            return None;
        }
        while self.next_sync_ns <= stamp_ns {
            self.next_sync_ns += self.sync_every_ns;
        }
        Some(stamp_ns - stamp_ns % self.tick_ns)
    }

    fn take_progress(&mut self) -> anyhow::Result<()> {
        let (mut w, mut ended) = (self.watermark_ns, self.ended);
        self.progress.drain(|p| {
            if p.header.is_end_of_stream() {
                ended = true;
            }
            w = Some(w.map_or(p.header.stamp_ns, |x: u64| x.max(p.header.stamp_ns)));
        })?;
        self.watermark_ns = w;
        self.ended = ended;
        Ok(())
    }

    /// Waits until the interrogator's watermark reaches `watermark_ns` (see
    /// the module docs); `poll` runs every few milliseconds meanwhile (control
    /// requests) and may end the wait by returning false.
    pub fn wait_for(
        &mut self,
        ctx: &Context,
        watermark_ns: u64,
        mut poll: impl FnMut() -> anyhow::Result<bool>,
    ) -> anyhow::Result<Waited> {
        let t0 = Instant::now();
        loop {
            self.take_progress()?;
            if self.watermark_ns.is_some_and(|w| w >= watermark_ns) || !self.interrogator_present()
            {
                return Ok(Waited::Done);
            }
            if ctx.termination_requested() || !poll()? {
                return Ok(Waited::Terminated);
            }
            if t0.elapsed() > self.deadline {
                self.timed_out += 1;
                if self.timed_out == 1 {
                    tracing::warn!(
                        watermark_ns,
                        interrogator_watermark_ns = ?self.watermark_ns,
                        deadline = ?self.deadline,
                        "the LBL interrogator did not advance within the deadline; going on without it (further ones are only counted)"
                    );
                }
                return Ok(Waited::TimedOut);
            }
            self.progress_inbox.wait(Duration::from_millis(5));
        }
    }

    /// Registers every interrogation received; `last_step_ns` is the stamp of
    /// the last generated step.
    pub fn drain(
        &mut self,
        generator: &mut Generator,
        last_step_ns: u64,
        lbl_enabled: bool,
        health: &mut HealthReporter,
    ) -> anyhow::Result<()> {
        self.requests_inbox.clear();
        let mut pending = Vec::new();
        self.requests.drain(|r| pending.push(r))?;
        for r in pending {
            let id = r.transponder_id;
            match generator.interrogate(id, r.header.stamp_ns) {
                Ok(()) => {
                    health.inputs += 1;
                    self.accepted += 1;
                    if r.header.stamp_ns < last_step_ns {
                        self.late += 1;
                        if self.lockstep && !self.late_logged {
                            self.late_logged = true;
                            tracing::warn!(
                                stamp_ns = r.header.stamp_ns,
                                last_step_ns,
                                "LBL interrogation stamped before the last generated step; \
                                 registered at that step (further ones are only counted)"
                            );
                        }
                    }
                }
                Err(SuiteError::UnknownTransponder(_)) | Err(SuiteError::LblDisabled) => {
                    let ids = generator.suite().config().lbl.ids();
                    let (min, max) = match (lbl_enabled, ids.iter().min(), ids.iter().max()) {
                        (true, Some(a), Some(b)) => (f64::from(*a), f64::from(*b)),
                        // Nothing is accepted: an empty range.
                        _ => (1.0, 0.0),
                    };
                    health.reject(
                        LBL_INTERROGATE_SERVICE,
                        &ValidationError::OutOfRange {
                            type_name: LblInterrogation::TYPE_NAME,
                            field: "transponder_id",
                            value: f64::from(id),
                            min,
                            max,
                        },
                    );
                }
                Err(e) => return Err(e.into()),
            }
        }
        Ok(())
    }
}
