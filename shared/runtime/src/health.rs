//! The 1 Hz health message and the counters behind it (DESIGN §4): inputs,
//! outputs, rejected, dropped. A rejection is logged once per kind and input,
//! and counted per kind and input for the process's last log line.

use std::collections::BTreeMap;

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
    /// Rejections per (input service, kind).
    by_kind: BTreeMap<(String, &'static str), u64>,
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
            by_kind: BTreeMap::new(),
        })
    }

    /// Counts a rejected message, logging the first of each kind per service.
    pub fn reject(&mut self, service: &str, error: &ValidationError) {
        if self.count(service, error.kind()) {
            tracing::warn!(service, kind = error.kind(), %error, "rejected input (further ones of this kind are only counted)");
        }
    }

    /// Counts an input the estimator refused (its state kept), logging the
    /// first of each kind per service.
    pub fn refuse(&mut self, service: &str, kind: &'static str, detail: &dyn std::fmt::Display) {
        if self.count(service, kind) {
            tracing::warn!(service, kind, %detail, "input refused by the estimator (further ones of this kind are only counted)");
        }
    }

    /// Counts one rejection; true for the first of its kind and service.
    fn count(&mut self, service: &str, kind: &'static str) -> bool {
        self.rejected += 1;
        let n = self.by_kind.entry((service.to_owned(), kind)).or_insert(0);
        *n += 1;
        *n == 1
    }

    /// The rejections per input and kind, `service kind count` joined by
    /// `, ` (empty when none): `sensor/dvl dvl-spike 12, sensor/gps
    /// gps-gated 3`.
    pub fn rejected_by_kind(&self) -> String {
        self.by_kind
            .iter()
            .map(|((service, kind), n)| format!("{service} {kind} {n}"))
            .collect::<Vec<_>>()
            .join(", ")
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
