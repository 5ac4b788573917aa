//! The estimator shell (STYLE item 4, DESIGN §3): everything a role's
//! estimator process does besides estimating, written once. A role declares
//! its inputs (service and checked type), outputs, snapshot and variants; the
//! shell gives it `--describe` and `--check`, subscribes, reports ready once
//! its inputs are connected, merges the inputs by stamp with their publishers'
//! watermarks, refuses and counts bad input, runs standby / activation /
//! deactivation at a stamp boundary and resume-after, publishes a snapshot at
//! every whole second of the run's clock and warm-starts from one, publishes
//! health, its own watermark and end of stream, and answers control. The
//! estimator itself is a pure [`Estimator`] from `nauta-estimation`.
//!
//! ```text
//! Shell::<AttitudeCore>::new(Role::Attitude, &VARIANTS)
//!     .input(services::imu(), Role::Sensor, std::convert::identity)
//!     .output(services::attitude_estimate(), |r| Some(AttitudeEstimate::from(r)))
//!     .snapshot(services::snapshot(Role::Attitude), AttitudeSnapshot::of_state, AttitudeSnapshot::state)
//!     .main(&args.process, make_core)
//! ```
//!
//! **Watermarks and cycles.** After each wake-up the role publishes on
//! `<role>/progress` the earliest stamp it could still publish: the smallest
//! next stamp of the inputs that trigger outputs (see [`Shell::aiding`]). A
//! role whose outputs come only from a sparse input (positioning: one fix per
//! buoy message) thus advances its watermark with that input's publisher, and
//! a consumer of its outputs never waits on it sample by sample; in a wiring
//! cycle (ains ↔ positioning) each side's watermark moves with the sensor's,
//! so both run in `sim` clock, deterministically, without a round trip per
//! sample.

mod inputs;
pub mod lifecycle;
mod outputs;

use std::ops::ControlFlow;
use std::process::ExitCode;
use std::time::Duration;

use nauta_estimation::{Estimator, Stamped};
use nauta_messages::checked::ValidationError;
use nauta_messages::{Message, Progress, Role, state};

use crate::context::Context;
use crate::control::ControlServer;
use crate::describe::{Describe, PortDescription};
use crate::event_loop::{EventLoop, LoopExit, Wake};
use crate::health::HealthReporter;
use crate::manifest::Manifest;
use crate::merge::OrderedMerge;
use crate::ports::{Connect, Inbox, Publisher};
use crate::process::{ProcessArgs, service_main_checked};
use crate::services::{self, ServiceSpec};

use inputs::{InputDecl, Watermarks};
pub use lifecycle::{Lifecycle, Requests};
use outputs::{OutputDecl, OutputPort, SnapshotDecl, SnapshotPort};

/// Snapshot period in the run's clock (DESIGN §4: 1 Hz).
pub const SNAPSHOT_PERIOD_NS: u64 = 1_000_000_000;

/// Builds the role's estimator from the manifest (parameters, site) for its
/// process and variant: what `--check` validates and the service runs.
pub type MakeEstimator<E> = fn(&Manifest, &str, &str) -> anyhow::Result<E>;

/// A role's declaration: inputs, outputs, snapshot, variants.
pub struct Shell<E: Estimator> {
    role: Role,
    variants: Vec<String>,
    inputs: Vec<InputDecl<E::Input>>,
    outputs: Vec<OutputDecl<E::Output>>,
    snapshot: Option<SnapshotDecl<E::Snapshot>>,
    advisories: Vec<Advisory<E::Output>>,
}

/// A declared advisory: a run event of `kind` whenever `raised` becomes
/// true of a published output.
struct Advisory<O> {
    kind: u32,
    name: &'static str,
    raised: fn(&O) -> bool,
}

impl<E: Estimator> std::fmt::Debug for Shell<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Shell")
            .field("role", &self.role)
            .field("variants", &self.variants)
            .field(
                "inputs",
                &self
                    .inputs
                    .iter()
                    .map(|i| &i.port.service)
                    .collect::<Vec<_>>(),
            )
            .finish()
    }
}

impl<E> Shell<E>
where
    E: Estimator + 'static,
    E::Input: 'static,
    E::Output: 'static,
    E::Snapshot: 'static,
{
    /// A role with these variants (the first is the default).
    pub fn new(role: Role, variants: &[&str]) -> Self {
        Shell {
            role,
            variants: variants.iter().map(|v| v.to_string()).collect(),
            inputs: Vec::new(),
            outputs: Vec::new(),
            snapshot: None,
            advisories: Vec::new(),
        }
    }

    /// An input: messages of `spec`, published by `publisher` (whose
    /// `progress` service carries the watermarks), checked into `D` and
    /// handed to the estimator as `into(d)`. Inputs are merged by stamp; a
    /// tie goes to the input declared first.
    pub fn input<M, D>(
        mut self,
        spec: ServiceSpec<M>,
        publisher: Role,
        into: fn(D) -> E::Input,
    ) -> Self
    where
        M: Message,
        D: for<'a> TryFrom<&'a M, Error = ValidationError> + 'static,
    {
        self.inputs.push(InputDecl::new(spec, publisher, into));
        self
    }

    /// An aiding input: as [`Shell::input`], but its messages never make the
    /// estimator publish (it only corrects the state), so the role's
    /// watermark does not wait for it.
    pub fn aiding<M, D>(
        self,
        spec: ServiceSpec<M>,
        publisher: Role,
        into: fn(D) -> E::Input,
    ) -> Self
    where
        M: Message,
        D: for<'a> TryFrom<&'a M, Error = ValidationError> + 'static,
    {
        let mut s = self.input(spec, publisher, into);
        if let Some(last) = s.inputs.last_mut() {
            last.triggers = false;
        }
        s
    }

    /// An optional aiding input: as [`Shell::aiding`], for an input the role
    /// can run without (`positioning/fix` when no positioning runs). Its
    /// `--describe` marks it optional; the launcher passes `--absent SERVICE`
    /// when no process of the run publishes it, and the shell then neither
    /// subscribes to it nor waits for its publisher's watermark.
    pub fn optional_aiding<M, D>(
        self,
        spec: ServiceSpec<M>,
        publisher: Role,
        into: fn(D) -> E::Input,
    ) -> Self
    where
        M: Message,
        D: for<'a> TryFrom<&'a M, Error = ValidationError> + 'static,
    {
        let mut s = self.aiding(spec, publisher, into);
        if let Some(last) = s.inputs.last_mut() {
            last.port.optional = true;
        }
        s
    }

    /// An output: the message `make` builds from an estimator output (`None`
    /// when that output is not for this service).
    pub fn output<M: Message>(
        mut self,
        spec: ServiceSpec<M>,
        make: fn(&E::Output) -> Option<M>,
    ) -> Self {
        self.outputs.push(OutputDecl::new(spec, make));
        self
    }

    /// An advisory: whenever `raised` becomes true of a published output
    /// (at the first, or after outputs of which it was false), the shell
    /// logs a warning naming it and publishes a run event of `kind`
    /// (`event_kind::SURFACING_ADVISED`, ...) at that output's stamp. The
    /// output itself carries the flag; the event is for the run's log and
    /// whoever follows `run/events`. A standby instance announces nothing.
    pub fn advisory(
        mut self,
        kind: u32,
        name: &'static str,
        raised: fn(&E::Output) -> bool,
    ) -> Self {
        self.advisories.push(Advisory { kind, name, raised });
        self
    }

    /// The snapshot service and the conversions of the estimator's snapshot
    /// to and from its message (stamped with the last input processed).
    pub fn snapshot<M: Message>(
        mut self,
        spec: ServiceSpec<M>,
        to_wire: fn(&E::Snapshot, u64) -> M,
        from_wire: fn(&M) -> E::Snapshot,
    ) -> Self {
        self.snapshot = Some(SnapshotDecl::new(spec, to_wire, from_wire));
        self
    }

    /// What `--describe` prints.
    pub fn describe(&self) -> Describe {
        let mut inputs: Vec<PortDescription> = self.inputs.iter().map(|i| i.port.clone()).collect();
        for i in &self.inputs {
            // A publisher's watermarks are optional when every input it
            // qualifies is.
            let optional = self
                .inputs
                .iter()
                .filter(|j| j.publisher == i.publisher)
                .all(|j| j.port.optional);
            let p = if optional {
                PortDescription::optional(&services::progress(i.publisher))
            } else {
                PortDescription::of(&services::progress(i.publisher))
            };
            if !inputs.iter().any(|q| q.service == p.service) {
                inputs.push(p);
            }
        }
        let mut outputs: Vec<PortDescription> =
            self.outputs.iter().map(|o| o.port.clone()).collect();
        outputs.extend(self.snapshot.iter().map(|s| s.port.clone()));
        outputs.push(PortDescription::of(&services::progress(self.role)));
        Describe {
            role: self.role.name().into(),
            inputs,
            outputs,
            variants: self.variants.clone(),
            source: false,
        }
    }

    /// The whole `main` of the role's binary: `--describe`, `--check` (the
    /// estimator built from the manifest), or the service.
    pub fn main(self, args: &ProcessArgs, make: MakeEstimator<E>) -> ExitCode {
        let default_variant = self.variants.first().cloned().unwrap_or_default();
        let variants = self.variants.clone();
        let check_variant = |v: &str| -> anyhow::Result<()> {
            anyhow::ensure!(
                variants.iter().any(|x| x == v),
                "unknown {} variant {v:?}; this binary implements {variants:?}",
                self.role.name()
            );
            Ok(())
        };
        service_main_checked(
            self.role,
            &default_variant,
            args,
            || self.describe(),
            |t| {
                check_variant(&t.variant)?;
                make(&t.manifest, &t.process, &t.variant).map(|_| ())
            },
            |ctx| {
                check_variant(&ctx.variant)?;
                let core = make(ctx.manifest()?, &ctx.process, &ctx.variant)?;
                self.serve(ctx, core)
            },
        )
    }

    /// Runs `core` as this role in `ctx` until its inputs end, a stop
    /// request, a deactivation or a termination signal.
    pub fn serve(&self, ctx: &mut Context, mut core: E) -> anyhow::Result<()> {
        // A restarted or swapped-in instance continues from the role's
        // latest snapshot (the launcher hands it over).
        let mut warm_from = None;
        if let Some(s) = &self.snapshot {
            match (s.warm_start)(ctx) {
                Ok(Some((state, stamp))) => {
                    if let Err(e) = core.restore(&state, stamp) {
                        tracing::warn!(error = %e, "starting cold");
                    } else {
                        warm_from = Some(stamp);
                    }
                }
                Ok(None) => {}
                Err(e) => tracing::warn!(error = %e, "snapshot unreadable; starting cold"),
            }
        }
        // The inputs of this run: an optional one nobody publishes is left out.
        let decls: Vec<&InputDecl<E::Input>> = self
            .inputs
            .iter()
            .filter(|d| {
                let absent = d.port.optional && ctx.absent.contains(&d.port.service);
                if absent {
                    tracing::info!(service = %d.port.service, "optional input absent from this run");
                }
                !absent
            })
            .collect();
        let mut ports = Vec::with_capacity(decls.len());
        let mut inboxes = Vec::new();
        for d in &decls {
            let (p, inbox) = (d.open)(ctx)?;
            ports.push(p);
            inboxes.push(inbox);
        }
        let (mut marks, mark_inboxes) = Watermarks::open(ctx, &decls)?;
        inboxes.extend(mark_inboxes);
        let mut outs = self
            .outputs
            .iter()
            .map(|o| (o.open)(ctx))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let mut snapshot_out = self.snapshot.as_ref().map(|s| (s.open)(ctx)).transpose()?;
        let mut progress_out = ctx.publisher(&services::progress(self.role))?;
        let mut health = HealthReporter::new(ctx)?;
        let (mut control, control_inbox) = ControlServer::open(ctx)?;
        inboxes.push(control_inbox);

        let span = role_span(self.role, &ctx.process, &ctx.variant);
        let _e = span.enter();
        {
            let mut connectors: Vec<&dyn Connect> = ports.iter().map(|p| p.connector()).collect();
            connectors.extend(marks.iter().map(|m| &m.sub as &dyn Connect));
            if !ctx.connect_and_ready(&connectors)? {
                tracing::info!("stopped by a signal before the inputs appeared");
                return Ok(());
            }
        }
        let mut run = Run {
            life: Lifecycle::estimator(ctx),
            merge: OrderedMerge::strictly_increasing(ports.len()),
            triggers: decls.iter().map(|d| d.triggers).collect(),
            last_stamp: 0,
            last_published: None,
            next_snapshot_ns: 0,
            progress_ns: None,
            ended_stream: false,
            produced: Vec::new(),
            raised: vec![false; self.advisories.len()],
            announced: Vec::new(),
        };
        health.state = run.life.state();

        let inbox_refs: Vec<&Inbox> = inboxes.iter().collect();
        let exit = EventLoop::new(Duration::from_secs(1)).run(&inbox_refs, |wake| {
            let asked = run
                .life
                .serve(ctx, &mut control, run.last_stamp, run.last_published)?;
            if run.life.deactivated {
                tracing::info!(last_published = ?run.last_published, "deactivated; exiting for the successor");
                return Ok(ControlFlow::Break(()));
            }
            if let Some(boundary) = asked.activated_after {
                for o in outs.iter_mut() {
                    let (n, last) = o.release(boundary)?;
                    health.outputs += n;
                    if let Some(s) = last {
                        run.last_published = Some(run.last_published.map_or(s, |l| l.max(s)));
                    }
                }
                tracing::info!(boundary, "activated");
            }
            health.state = run.life.state();
            if asked.snapshot_now && !run.life.standby {
                run.publish_snapshot(&core, &mut snapshot_out)?;
            }
            if wake == Wake::Tick {
                health.dropped = ports.iter().map(|p| p.gaps()).sum::<u64>()
                    + outs.iter().map(|o| o.given_up()).sum::<u64>();
                health.publish(ctx);
                ctx.cleanup_dead_nodes();
                if !run.life.stop {
                    return Ok(ControlFlow::Continue(()));
                }
            }
            // Watermarks first: one seen here was published after every
            // message it covers, so those are queued by the drain below.
            let mut taken = Vec::with_capacity(marks.len());
            for m in marks.iter_mut() {
                taken.push(m.take()?);
            }
            for (i, p) in ports.iter_mut().enumerate() {
                let before = p.first();
                p.drain(i, &mut run.merge, &mut health)?;
                // A warm start replays its inputs from the snapshot out of
                // the services' history; a history that begins after it
                // (the instance subscribed too late: see
                // `services::history_for`) leaves a hole in the replay.
                if let (None, Some((stamp, seq)), Some(snap)) = (before, p.first(), warm_from)
                    && stamp > snap
                    && seq > 0
                {
                    tracing::warn!(
                        service = %decls[i].port.service,
                        first_stamp_ns = stamp,
                        snapshot_stamp_ns = snap,
                        "the input's history begins after the snapshot: what it held in between is lost to this instance"
                    );
                }
            }
            for (m, (mark, ended)) in marks.iter().zip(taken) {
                for &i in &m.inputs {
                    if let Some(w) = mark {
                        run.merge.advance(i, w);
                    }
                    if ended || run.life.stop {
                        run.merge.end(i);
                    }
                }
                if ended {
                    tracing::debug!(publisher = m.publisher.name(), "input ended");
                }
            }
            run.process(&mut core, &mut outs, &mut snapshot_out, &mut health, &decls, &self.advisories)?;
            for (i, stamp) in run.announced.drain(..) {
                let a = &self.advisories[i];
                tracing::warn!(advisory = a.name, stamp_ns = stamp, "advisory raised");
                ctx.announce(a.kind, stamp, 0);
            }
            for o in outs.iter_mut() {
                o.flush();
            }
            // A role with nothing to publish still hands its history to the
            // consumers that restarted meanwhile (`Publisher::flush`).
            progress_out.flush();
            if let Some(s) = snapshot_out.as_mut() {
                s.flush();
            }
            // Once no triggering input can deliver anything, the role will
            // publish nothing more: it says so at once, even if an aiding
            // input is still open (in a cycle, that input's publisher may be
            // waiting for this very end of stream). A standby instance that
            // was never activated ends quietly: the active one ends the
            // stream.
            let finished = run.merge.is_finished();
            if !run.ended_stream && !run.life.standby && (finished || run.watermark() == Some(u64::MAX)) {
                let published = outs.iter().map(|o| o.published()).sum();
                progress_out.publish_now(Progress::end_of_stream(run.last_stamp, self.role, published))?;
                run.ended_stream = true;
            }
            if finished {
                return Ok(ControlFlow::Break(()));
            }
            run.publish_watermark(&mut progress_out, self.role, &outs)?;
            Ok(ControlFlow::Continue(()))
        })?;
        health.state = state::STOPPED;
        health.dropped = ports.iter().map(|p| p.gaps()).sum::<u64>()
            + outs.iter().map(|o| o.given_up()).sum::<u64>();
        health.publish(ctx);
        tracing::info!(
            inputs = health.inputs,
            outputs = health.outputs,
            rejected = health.rejected,
            rejected_by_kind = %health.rejected_by_kind(),
            gaps = ports.iter().map(|p| p.gaps()).sum::<u64>(),
            by_signal = exit == LoopExit::Signal,
            "done"
        );
        Ok(())
    }
}

/// The process's span, named after its role (`attitude: done ...`): span
/// names are static, so one arm per role.
fn role_span(role: Role, process: &str, variant: &str) -> tracing::Span {
    macro_rules! span {
        ($name:literal) => {
            tracing::info_span!($name, process = %process, variant = %variant)
        };
    }
    match role {
        Role::Attitude => span!("attitude"),
        Role::Ains => span!("ains"),
        Role::Positioning => span!("positioning"),
        Role::Lbl => span!("lbl"),
        Role::Smoother => span!("smoother"),
        Role::Sensor => span!("sensor"),
        Role::Logger => span!("logger"),
        Role::Launcher => span!("launcher"),
        Role::Replay => span!("replay"),
        Role::Test => span!("test"),
        Role::Unknown => span!("unknown"),
    }
}

/// The state of one run of the shell's loop.
struct Run<E: Estimator> {
    life: Lifecycle,
    merge: OrderedMerge<E::Input>,
    triggers: Vec<bool>,
    last_stamp: u64,
    last_published: Option<u64>,
    next_snapshot_ns: u64,
    /// The last watermark published on `<role>/progress`.
    progress_ns: Option<u64>,
    /// End of stream published.
    ended_stream: bool,
    produced: Vec<E::Output>,
    /// Per declared advisory: raised by the last published output.
    raised: Vec<bool>,
    /// Advisories raised in this wake-up (index, stamp), to announce.
    announced: Vec<(usize, u64)>,
}

impl<E: Estimator> Run<E> {
    /// Feeds the estimator every input the merge releases and publishes (or,
    /// in standby, holds) its outputs.
    fn process(
        &mut self,
        core: &mut E,
        outs: &mut [Box<dyn OutputPort<E::Output>>],
        snapshot_out: &mut Option<Box<dyn SnapshotPort<E::Snapshot>>>,
        health: &mut HealthReporter,
        decls: &[&InputDecl<E::Input>],
        advisories: &[Advisory<E::Output>],
    ) -> anyhow::Result<()> {
        while let Some((idx, stamp, input)) = self.merge.pop() {
            self.last_stamp = stamp;
            health.last_stamp_ns = stamp;
            self.produced.clear();
            if let Err(e) = core.on_input(&input, &mut self.produced) {
                health.refuse(&decls[idx].port.service, e.kind, &e.detail);
            }
            // A snapshot at every whole second of the run's clock.
            if stamp >= self.next_snapshot_ns {
                self.next_snapshot_ns = (stamp / SNAPSHOT_PERIOD_NS + 1) * SNAPSHOT_PERIOD_NS;
                if !self.life.standby {
                    self.publish_snapshot(core, snapshot_out)?;
                }
            }
            for o in &self.produced {
                let s = o.stamp_ns();
                if !self.life.publishes(s) {
                    continue;
                }
                if !self.life.standby {
                    for (i, a) in advisories.iter().enumerate() {
                        let up = (a.raised)(o);
                        if up && !self.raised[i] {
                            self.announced.push((i, s));
                        }
                        self.raised[i] = up;
                    }
                }
                for port in outs.iter_mut() {
                    if port.offer(o, s, self.life.standby)?.is_some() {
                        self.last_published = Some(self.last_published.map_or(s, |l| l.max(s)));
                        health.outputs += 1;
                    }
                }
            }
        }
        Ok(())
    }

    fn publish_snapshot(
        &self,
        core: &E,
        out: &mut Option<Box<dyn SnapshotPort<E::Snapshot>>>,
    ) -> anyhow::Result<()> {
        if let (Some(out), Some(s)) = (out.as_mut(), core.snapshot()) {
            out.publish(&s, self.last_stamp)?;
        }
        Ok(())
    }

    /// The earliest stamp the role could still publish: the smallest next
    /// stamp of its triggering inputs (`None` while one has no watermark).
    fn watermark(&self) -> Option<u64> {
        let mut w = u64::MAX;
        for (i, _) in self.triggers.iter().enumerate().filter(|(_, t)| **t) {
            w = w.min(self.merge.next_bound(i)?);
        }
        Some(w)
    }

    /// Publishes the role's watermark when it moved (never in standby: the
    /// active instance speaks for the role).
    fn publish_watermark(
        &mut self,
        out: &mut Publisher<Progress>,
        role: Role,
        outs: &[Box<dyn OutputPort<E::Output>>],
    ) -> anyhow::Result<()> {
        if self.life.standby || self.ended_stream {
            return Ok(());
        }
        let Some(w) = self.watermark().filter(|w| *w != u64::MAX) else {
            return Ok(());
        };
        if self.progress_ns.is_some_and(|p| w <= p) {
            return Ok(());
        }
        self.progress_ns = Some(w);
        let published = outs.iter().map(|o| o.published()).sum();
        out.publish_now(Progress::at(w, role, published))?;
        Ok(())
    }
}
