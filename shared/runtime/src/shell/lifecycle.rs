//! The launcher's commands to one process (DESIGN §5), answered in one place
//! for every role: standby, activation at a stamp boundary, deactivation,
//! snapshot-now and stop. The estimator shell and the sensor (a source) both
//! keep their lifecycle here.

use std::time::{Duration, Instant};

use nauta_messages::{ControlResponse, Header, command, state};

use crate::context::Context;
use crate::control::ControlServer;
use crate::health::HealthReporter;

/// Where a process is in its life, as the launcher's commands move it.
#[derive(Debug, Clone)]
pub struct Lifecycle {
    /// Following inputs without publishing (hot-swap standby, or a source
    /// waiting to be activated).
    pub standby: bool,
    /// STOP was asked: drain and exit.
    pub stop: bool,
    /// DEACTIVATE was answered: publish nothing more and exit (a successor
    /// takes over at the last published stamp).
    pub deactivated: bool,
    /// Publish nothing stamped at or before this (a previous instance did).
    pub resume_after: Option<u64>,
    /// Whether DEACTIVATE is accepted (estimators; a source is never swapped).
    deactivatable: bool,
}

/// What a round of control requests asked for, beyond the flags of
/// [`Lifecycle`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Requests {
    /// ACTIVATE with this boundary: publish from the first stamp after it.
    pub activated_after: Option<u64>,
    /// SNAPSHOT_NOW.
    pub snapshot_now: bool,
}

impl Lifecycle {
    /// The lifecycle of an estimator started as `ctx` says (`--standby`,
    /// `--resume-after`).
    pub fn estimator(ctx: &Context) -> Self {
        Lifecycle {
            standby: ctx.standby,
            stop: false,
            deactivated: false,
            resume_after: ctx.resume_after_ns,
            deactivatable: true,
        }
    }

    /// The lifecycle of a source: standby until activated, never deactivated.
    pub fn source(ctx: &Context) -> Self {
        Lifecycle {
            deactivatable: false,
            resume_after: None,
            ..Self::estimator(ctx)
        }
    }

    /// The health state this lifecycle shows.
    pub fn state(&self) -> u32 {
        if self.stop || self.deactivated {
            state::DRAINING
        } else if self.standby {
            state::STANDBY
        } else {
            state::RUNNING
        }
    }

    /// Answers every pending request. `last_stamp_ns` is the last input
    /// processed, `last_published_ns` the last output published (what a
    /// DEACTIVATE answers, for the successor's boundary). An ACTIVATE ends
    /// standby and moves `resume_after` to its boundary.
    pub fn serve(
        &mut self,
        ctx: &Context,
        control: &mut ControlServer,
        last_stamp_ns: u64,
        last_published_ns: Option<u64>,
    ) -> anyhow::Result<Requests> {
        let mut asked = Requests::default();
        control.serve(|req| {
            let status = match req.command {
                command::SNAPSHOT_NOW => {
                    asked.snapshot_now = true;
                    0
                }
                command::STOP => {
                    self.stop = true;
                    0
                }
                command::ACTIVATE if self.standby => {
                    self.standby = false;
                    let b = req.boundary_stamp_ns;
                    self.resume_after = Some(self.resume_after.map_or(b, |r| r.max(b)));
                    asked.activated_after = Some(b);
                    0
                }
                command::DEACTIVATE if self.deactivatable && !self.standby => {
                    self.deactivated = true;
                    0
                }
                _ => 2,
            };
            ControlResponse {
                header: Header::new(last_stamp_ns, 0, ctx.role, ctx.instance),
                status,
                state: self.state(),
                last_stamp_ns: if req.command == command::DEACTIVATE {
                    last_published_ns.unwrap_or(0)
                } else {
                    last_stamp_ns
                },
            }
        })?;
        Ok(asked)
    }

    /// True when an output stamped `stamp_ns` may be published (not at or
    /// before the resume point).
    pub fn publishes(&self, stamp_ns: u64) -> bool {
        self.resume_after.is_none_or(|r| stamp_ns > r)
    }

    /// A source started with `--standby` waits here for the launcher's
    /// ACTIVATE, sent once every consumer is connected, so that nothing is
    /// published before anyone listens (DESIGN §5). Health is published every
    /// second meanwhile. False on STOP or a termination signal.
    pub fn hold_until_activated(
        &mut self,
        ctx: &Context,
        control: &mut ControlServer,
        health: &mut HealthReporter,
    ) -> anyhow::Result<bool> {
        let mut last_health = Instant::now();
        while self.standby {
            health.state = self.state();
            self.serve(ctx, control, 0, None)?;
            if self.stop {
                return Ok(false);
            }
            if last_health.elapsed() >= Duration::from_secs(1) {
                last_health = Instant::now();
                health.publish(ctx);
            }
            if self.standby && !ctx.sleep(Duration::from_millis(1)) {
                return Ok(false);
            }
        }
        health.state = self.state();
        Ok(true)
    }
}
