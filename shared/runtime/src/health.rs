//! The 1 Hz health message and the counters behind it (DESIGN §4): inputs,
//! outputs, rejected, dropped. A rejection is logged once per kind and input.

use std::collections::BTreeSet;

use nauta_messages::checked::ValidationError;
use nauta_messages::{Header, Health, to_fixed_str};

use crate::context::Context;
use crate::ports::Publisher;
use crate::services;

/// Counts and publishes a process's health.
#[derive(Debug)]
pub struct HealthReporter {
    publisher: Publisher<Health>,
    /// Messages accepted.
    pub inputs: u64,
    /// Messages published.
    pub outputs: u64,
    /// Messages rejected by validation.
    pub rejected: u64,
    /// Messages lost (input gaps, outputs given up).
    pub dropped: u64,
    /// Last input stamp processed.
    pub last_stamp_ns: u64,
    /// `state::*` value.
    pub state: u32,
    logged: BTreeSet<(String, &'static str)>,
}

impl HealthReporter {
    /// Opens `<role>/health`.
    pub fn new(ctx: &Context) -> anyhow::Result<Self> {
        Ok(HealthReporter {
            publisher: ctx.publisher(&services::health(ctx.role))?,
            inputs: 0,
            outputs: 0,
            rejected: 0,
            dropped: 0,
            last_stamp_ns: 0,
            state: nauta_messages::state::STARTING,
            logged: BTreeSet::new(),
        })
    }

    /// Counts a rejected message, logging the first of each kind per service.
    pub fn reject(&mut self, service: &str, error: &ValidationError) {
        self.rejected += 1;
        if self.logged.insert((service.to_owned(), error.kind())) {
            tracing::warn!(service, kind = error.kind(), %error, "rejected input (further ones of this kind are only counted)");
        }
    }

    /// Counts an input the estimator refused (its state kept), logging the
    /// first of each kind per service.
    pub fn refuse(&mut self, service: &str, kind: &'static str, detail: &dyn std::fmt::Display) {
        self.rejected += 1;
        if self.logged.insert((service.to_owned(), kind)) {
            tracing::warn!(service, kind, %detail, "input refused by the estimator (further ones of this kind are only counted)");
        }
    }

    /// Publishes the health message now.
    pub fn publish(&mut self, ctx: &Context) {
        let msg = Health {
            header: Header::new(self.last_stamp_ns, 0, ctx.role, ctx.instance),
            inputs: self.inputs,
            outputs: self.outputs,
            rejected: self.rejected,
            dropped: self.dropped,
            uptime_ns: ctx.uptime().as_nanos() as u64,
            pid: std::process::id(),
            state: self.state,
            variant: to_fixed_str(&ctx.variant),
        };
        if let Err(e) = self.publisher.publish_now(msg) {
            tracing::debug!(error = %e, "health not published");
        }
    }
}
