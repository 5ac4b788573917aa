//! The summary of a run, as a value: what `nauta launch --json` prints as one
//! JSON object, and the one line it prints without `--json` (the README's
//! "The run summary" lists every key).

use std::collections::BTreeMap;
use std::time::Duration;

use nauta_messages::{ATTITUDE_ESTIMATE_SERVICE, IMU_SERVICE, TRUTH_SERVICE};
use nauta_runtime::{LoopExit, Manifest, Namespace};
use serde::Serialize;

use crate::monitor::{Observer, Tap};
use crate::supervisor::Supervisor;
use nauta_tools::eval::{ErrorSample, Evaluation, Metrics};

/// The summary of a finished run.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// The run's namespace.
    pub namespace: String,
    /// `sim` or `wall`.
    pub clock: String,
    /// Pace of a `wall` run, times real time.
    pub rate: f64,
    /// Seed of every random generator of the run.
    pub seed: u64,
    /// Simulated seconds run: the last stamp of the sensor's stream (the
    /// truth, else the IMU), else the manifest's duration.
    pub mission_s: f64,
    /// Wall seconds from the start of the first process to the end.
    pub wall_s: f64,
    /// Messages received by the launcher on the data services (those of
    /// `streams`).
    pub messages: u64,
    /// Sequence gaps seen by the launcher's taps on the data services (those
    /// of `streams`), and on the progress services in `sim` clock, where
    /// watermarks are lossless. Health and snapshot messages, and watermarks
    /// in `wall`, are states, each superseding the one before: one the
    /// launcher missed while busy is no loss, and is not counted.
    pub gaps: u64,
    /// The services of `gaps`, those with any.
    pub gaps_by_service: BTreeMap<String, u64>,
    /// Messages lost inside the processes: input gaps and deliveries given up
    /// by publishers, as each instance's last health counted them.
    pub lost: u64,
    /// Inputs refused by their checks, as each instance's last health counted them.
    pub rejected: u64,
    /// Per data service (progress, snapshot and health left out): messages and rate.
    pub streams: BTreeMap<String, StreamStats>,
    /// The sensor's stream from its first to its last sample, as the launcher
    /// received it.
    pub sensor_span: Option<SensorSpan>,
    /// Per estimate stream: `nauta eval`'s metrics against the truth.
    pub errors: BTreeMap<String, StreamErrors>,
    /// Per estimate stream: a digest of its outputs (FNV-1a of every
    /// message's encoding, in order), equal for equal outputs.
    pub digests: BTreeMap<String, String>,
    /// Restarts per process (by policy or `nauta restart`), those with any.
    pub restarts: BTreeMap<String, u32>,
    /// Hot swaps per process, those with any.
    pub swaps: BTreeMap<String, u32>,
    /// How the run ended: `end` (by itself: every process finished, or one
    /// failed; see `exit`), `signal`
    /// (SIGINT/SIGTERM to the launcher) or `request` (`nauta stop`).
    pub stopped: Stopped,
    /// `ok`, or `failed` when a process failed beyond its restart policy or
    /// did not exit 0 in the end.
    pub exit: Exit,
    /// The first failure (`failed` only): the process and why.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// Every failure, the first one first.
    pub failures: Vec<String>,
    /// The launcher's exit code: 0, 1 when failed, 130 when stopped by a signal.
    pub exit_code: u8,
}

/// The errors of one estimate stream: `nauta eval`'s keys, and for an
/// attitude the total rotation angle of the same per-sample errors.
#[derive(Debug, Clone, Serialize)]
pub struct StreamErrors {
    /// `nauta eval`'s metrics.
    #[serde(flatten)]
    pub eval: Metrics,
    /// RMS of the total attitude error angle, deg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub total_rms_deg: Option<f64>,
    /// Largest total attitude error angle, deg.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub total_max_deg: Option<f64>,
}

impl StreamErrors {
    fn new(eval: Metrics, series: &[ErrorSample]) -> Self {
        let totals: Vec<f64> = series
            .iter()
            .filter_map(|e| Some(e.attitude?.total_rad.to_degrees()))
            .collect();
        let n = totals.len() as f64;
        StreamErrors {
            eval,
            total_rms_deg: (!totals.is_empty())
                .then(|| (totals.iter().map(|t| t * t).sum::<f64>() / n).sqrt()),
            total_max_deg: totals.iter().copied().reduce(f64::max),
        }
    }
}

/// Errors per estimate stream of an evaluation.
fn errors(eval: Option<Evaluation>) -> BTreeMap<String, StreamErrors> {
    let Some(mut eval) = eval else {
        return BTreeMap::new();
    };
    eval.streams
        .into_iter()
        .map(|(topic, m)| {
            let series = eval.series.remove(&topic).unwrap_or_default();
            let e = StreamErrors::new(m, &series);
            (topic, e)
        })
        .collect()
}

/// Messages of one service.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct StreamStats {
    /// Messages received.
    pub messages: u64,
    /// Mean rate between the first and the last stamp, Hz.
    pub rate_hz: f64,
}

/// The sensor stream's span.
#[derive(Debug, Clone, Serialize)]
pub struct SensorSpan {
    /// The service (`sim/truth`, else `sensor/imu`).
    pub topic: String,
    /// From its first to its last stamp, s.
    pub simulated_s: f64,
    /// From receiving its first message to receiving its last, s.
    pub wall_s: f64,
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Stopped {
    /// By itself: every process finished, or one failed.
    End,
    /// A signal to the launcher.
    Signal,
    /// `nauta stop`.
    Request,
}

/// Whether every process did its job.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Exit {
    /// Every process exited 0 (restarted ones within their policy).
    Ok,
    /// See `failures`.
    Failed,
}

/// What a finished run hands to [`RunSummary::new`].
#[derive(Debug)]
pub struct Report<'a> {
    /// The effective manifest.
    pub manifest: &'a Manifest,
    /// The run's namespace.
    pub ns: &'a Namespace,
    /// Wall time of the run.
    pub wall: Duration,
    /// The launcher's taps, drained.
    pub taps: &'a [Box<dyn Tap>],
    /// The supervisor, every process stopped.
    pub sup: &'a Supervisor,
    /// What went wrong, the first failure first.
    pub failures: Vec<String>,
    /// How the event loop ended.
    pub exit: LoopExit,
    /// `nauta stop` ended the run.
    pub stopped_by_request: bool,
}

/// Services whose messages are bookkeeping, not data.
fn is_data(service: &str) -> bool {
    !(service.ends_with("/progress")
        || service.ends_with("/snapshot")
        || service.ends_with("/health"))
}

fn rate_hz(t: &dyn Tap) -> f64 {
    match t.span() {
        Some((a, b)) if b > a && t.count() > 1 => (t.count() - 1) as f64 / ((b - a) as f64 * 1e-9),
        _ => 0.0,
    }
}

impl RunSummary {
    /// The summary of a run; `obs` evaluates the estimates it received.
    pub fn new(r: Report<'_>, obs: &mut Observer) -> Self {
        let Report {
            manifest,
            ns,
            wall,
            taps,
            sup,
            failures,
            exit,
            stopped_by_request,
        } = r;
        // The sensor's own stream (the truth, else the IMU): what was
        // simulated, and over how much wall time its samples arrived.
        let sensor = [TRUTH_SERVICE, IMU_SERVICE]
            .iter()
            .find_map(|name| taps.iter().find(|t| t.service() == *name && t.count() > 0));
        let mission_s = sensor
            .and_then(|t| t.span())
            .map_or(manifest.run.duration_s, |(_, last)| last as f64 * 1e-9);
        let sensor_span = sensor.and_then(|t| {
            let (a, b) = t.span()?;
            Some(SensorSpan {
                topic: t.service().to_owned(),
                simulated_s: (b - a) as f64 * 1e-9,
                wall_s: t.wall_span()?.as_secs_f64(),
            })
        });
        let streams: BTreeMap<String, StreamStats> = taps
            .iter()
            .filter(|t| is_data(t.service()))
            .map(|t| {
                let stats = StreamStats {
                    messages: t.count(),
                    rate_hz: rate_hz(t.as_ref()),
                };
                (t.service().to_owned(), stats)
            })
            .collect();
        let lossless = manifest.clock().is_lossless();
        let counts_gaps =
            |service: &str| is_data(service) || (lossless && service.ends_with("/progress"));
        let (lost, rejected) = obs.process_losses();
        let per_member = |n: fn(&crate::supervisor::Member) -> u32| {
            sup.members
                .iter()
                .filter(|m| n(m) > 0)
                .map(|m| (m.name.clone(), n(m)))
                .collect()
        };
        let stopped = if exit == LoopExit::Signal {
            Stopped::Signal
        } else if stopped_by_request {
            Stopped::Request
        } else {
            Stopped::End
        };
        RunSummary {
            namespace: ns.as_str().to_owned(),
            clock: manifest.clock().name().to_owned(),
            rate: manifest.run.rate,
            seed: manifest.run.seed,
            mission_s,
            wall_s: wall.as_secs_f64(),
            messages: streams.values().map(|s| s.messages).sum(),
            gaps: taps
                .iter()
                .filter(|t| counts_gaps(t.service()))
                .map(|t| t.gaps())
                .sum(),
            gaps_by_service: taps
                .iter()
                .filter(|t| counts_gaps(t.service()) && t.gaps() > 0)
                .map(|t| (t.service().to_owned(), t.gaps()))
                .collect(),
            lost,
            rejected,
            streams,
            sensor_span,
            errors: errors(obs.evaluate(manifest)),
            digests: obs.digests(),
            restarts: per_member(|m| m.restarts),
            swaps: per_member(|m| m.swaps),
            stopped,
            exit: if failures.is_empty() {
                Exit::Ok
            } else {
                Exit::Failed
            },
            failure: failures.first().cloned(),
            exit_code: if stopped == Stopped::Signal {
                130
            } else if failures.is_empty() {
                0
            } else {
                1
            },
            failures,
        }
    }

    /// The one line `nauta launch` prints without `--json`.
    pub fn line(&self) -> String {
        let mut parts = vec![format!(
            "nauta: run {} {} {:.1} s mission in {:.2} s wall ({:.1}x)",
            self.namespace,
            self.clock,
            self.mission_s,
            self.wall_s,
            self.mission_s / self.wall_s.max(1e-9)
        )];
        for (s, st) in &self.streams {
            parts.push(format!("{s} {} msgs {:.1} Hz", st.messages, st.rate_hz));
        }
        if let Some(s) = &self.sensor_span {
            parts.push(format!(
                "{} span {:.3} s simulated in {:.3} s wall",
                s.topic, s.simulated_s, s.wall_s
            ));
        }
        parts.push(format!("gaps {}", self.gaps));
        for (s, n) in &self.gaps_by_service {
            parts.push(format!("{s} gaps {n}"));
        }
        parts.push(format!(
            "lost in processes {}, rejected {}",
            self.lost, self.rejected
        ));
        for topic in self.digests.keys() {
            // `attitude/estimate` keeps its short name of the earlier line.
            let name = if topic == ATTITUDE_ESTIMATE_SERVICE {
                "attitude"
            } else {
                topic.as_str()
            };
            parts.push(match self.errors.get(topic) {
                Some(m) => error_part(name, m),
                None => format!("{name} error: no estimate matched a truth sample"),
            });
            parts.push(format!("{name} digest {}", self.digests[topic]));
        }
        let list = |m: &BTreeMap<String, u32>| {
            m.iter()
                .map(|(p, n)| format!("{p} {n}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        if !self.restarts.is_empty() {
            parts.push(format!("restarts {}", list(&self.restarts)));
        }
        if !self.swaps.is_empty() {
            parts.push(format!("swaps {}", list(&self.swaps)));
        }
        match self.stopped {
            Stopped::Signal => parts.push("stopped by signal".into()),
            Stopped::Request => parts.push("stopped by request".into()),
            Stopped::End => {}
        }
        if self.failures.is_empty() {
            parts.push("all processes exited 0".into());
        } else {
            parts.push(format!("FAILED: {}", self.failures.join(", ")));
        }
        parts.join(" | ")
    }
}

/// `NAME error rms ...` of one stream: what it has of attitude, horizontal
/// position and depth.
fn error_part(name: &str, e: &StreamErrors) -> String {
    let m = &e.eval;
    let mut what = Vec::new();
    if let (Some(r), Some(p), Some(y)) = (m.roll_rms_deg, m.pitch_rms_deg, m.yaw_rms_deg) {
        what.push(format!("roll {r:.3}° pitch {p:.3}° yaw {y:.3}°"));
    }
    if let (Some(t), Some(max)) = (e.total_rms_deg, e.total_max_deg) {
        what.push(format!("total {t:.3}° max {max:.3}°"));
    }
    if let Some(h) = m.horizontal_rms_m {
        what.push(format!("horizontal {h:.3} m"));
    }
    if let Some(d) = m.down_rms_m {
        what.push(format!("down {d:.3} m"));
    }
    format!(
        "{name} error rms {} over {} samples",
        what.join(" "),
        m.samples
    )
}
